"""Everything that runs before work: ``domains`` (the auto domains and the cell count),
``plan`` (each stage's memory and run time against the machine) and ``preflight`` (the data
directory, the inputs and the cluster)."""
