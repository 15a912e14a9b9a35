"""Contact models: the strategy ``contact.model`` chooses, once, from a registry.

:class:`~g2tom.models.base.ContactModel` says what a model owns (its checks, its share of the contact
stage, the cube's spots and unit of work, the clean surface, its costs and its words);
:class:`GreenwoodTripp` (the asperities' mean on the lattice of cells, :mod:`g2tom.models.lattice_cube`)
and :class:`Discrete` (each surface's own coupled caps, :mod:`g2tom.models.discrete_pool`,
:mod:`g2tom.models.discrete_cube`, :mod:`g2tom.models.discrete_cost`) are the two;
:func:`contact_model` picks one (:data:`~g2tom.models.registry.CONTACT_MODELS`). A new model is one subclass and one registry
line (:mod:`g2tom.models.registry`).
"""

from g2tom.models.base import ContactModel, PlanWork, TypicalEnsemble
from g2tom.models.discrete import Discrete
from g2tom.models.greenwood_tripp import GreenwoodTripp
from g2tom.models.registry import CONTACT_MODELS, check_contact_model, contact_model, models_that, step_target_conflicts

__all__ = ["ContactModel", "PlanWork", "TypicalEnsemble", "GreenwoodTripp", "Discrete", "CONTACT_MODELS",
           "contact_model", "models_that", "check_contact_model", "step_target_conflicts"]
