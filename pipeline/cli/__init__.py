"""The command line: ``main`` (``g2tom`` and its subcommands), ``predict`` (``g2tom predict``'s
input and output) and ``roughness`` (``g2tom roughness``'s output)."""
