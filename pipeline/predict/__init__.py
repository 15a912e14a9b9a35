"""The predictor (Eq. 27) from a written surrogate: ``predictor`` (R_el and its band), ``queries``
(the grid of queries and their ranges), ``domain`` (which surface a query is on),
``surrogate_file`` (surrogate.json) and ``atlas`` (the shipped atlas surrogate over mu and Pi)."""
