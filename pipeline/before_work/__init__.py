"""Everything that runs before work: ``domains`` (the auto domains and the cell count),
``plan`` (each stage's memory and run time against the machine), ``preflight`` (the data
directory, the inputs and the cluster) and ``surrogate_grid`` (the surrogate's limits on the
oxide grid). The checks of a scenario's own parameters run as it is loaded (:mod:`pipeline.config`)."""
