"""The atlas over the dimensionless groups (mu, Pi): ``design`` (its scenes), ``run`` (the chain on
every scene, resumable) and ``fit`` (the atlas surrogate written from the scenes' fits)."""
