"""The command line: ``main`` (the ``g2tom`` entry point: one BLAS thread, the scenario, the checks
before work, the exit status), ``arguments`` (every subcommand and its options), ``commands`` (each
subcommand's work), ``predict`` (``g2tom predict``'s input and output) and ``roughness``
(``g2tom roughness``'s output)."""
