"""Statistics, pure numpy/scipy like :mod:`g2tom.physics` and below the stages: the surrogate
over (xi, lambda), the curve model and the power law fitted per cell, the adaptive ensemble's
stopping rule and the atlas surrogate over (xi, lambda, mu, Pi)."""
