"""Analysis: reductions, figures and the report built from the stage outputs."""
