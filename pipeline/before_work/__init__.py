"""Everything that runs before work: ``scenario_checks`` (settings that rule each other out, run as
a scenario is loaded), ``window_checks`` (the window, the radial domain and the oxide band once they
are numbers), ``domains`` (the auto domains and the cell count), ``plan`` (each stage's memory and
run time against the machine), ``preflight`` (the data directory, the inputs and the cluster) and
``surrogate_grid`` (the surrogate's limits on the oxide grid). The range of each single parameter
is checked from its declaration, as it is loaded (:mod:`g2tom.config.validation`).

:func:`load_scenario` is the loader every command uses: the scenario read and every check run."""

from g2tom.before_work.scenario_checks import load_scenario

__all__ = ["load_scenario"]
