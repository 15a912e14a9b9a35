"""Analysis: the figures (``figures_*``, one module per family, in the shared ``style``) and the report
(``report``: its assembly; ``report_results``, ``report_physics``, ``report_appendix``: its sections;
``report_blocks`` and ``report_render``: its elements and their Markdown and HTML), built from the
stage outputs (the reductions over realizations are :mod:`g2tom.reductions`, applied by the fits
stage)."""
