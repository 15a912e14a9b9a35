"""Analysis: the figures and the report, built from the stage outputs (the reductions over
realizations are :mod:`pipeline.reductions`, applied by the fits stage)."""
