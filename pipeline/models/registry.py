"""The contact models by name (:data:`~g2tom.models.registry.CONTACT_MODELS`), the one place ``contact.model`` is read
(:func:`contact_model`), and the checks across parameters that follow from a model's capabilities."""

from __future__ import annotations

from typing import Any, Callable

from g2tom.config import ConfigError, Scenario
from g2tom.models.base import ContactModel
from g2tom.models.discrete import Discrete
from g2tom.models.greenwood_tripp import GreenwoodTripp

__all__ = ["CONTACT_MODELS", "contact_model", "models_that", "check_contact_model", "step_target_conflicts"]

#: Every contact model by its ``contact.model`` name.
CONTACT_MODELS: dict[str, type[ContactModel]] = {model.name: model for model in (GreenwoodTripp, Discrete)}


def contact_model(scenario: Scenario) -> ContactModel:
    """The contact model ``scenario`` selects (``contact.model``)."""
    try:
        return CONTACT_MODELS[scenario.contact.model]()
    except KeyError:
        raise ConfigError(f"contact.model = {scenario.contact.model!r} is not a contact model: must be one of "
                          f"{', '.join(repr(name) for name in CONTACT_MODELS)}") from None


def models_that(can: Callable[[type[ContactModel]], bool]) -> str:
    """The names of the models for which ``can`` holds, as a message says them (``'discrete'``)."""
    return " or ".join(repr(name) for name, model in CONTACT_MODELS.items() if can(model))


def check_contact_model(s: Scenario) -> None:
    """The model's spot rules and its own checks (:meth:`g2tom.models.ContactModel.check`).

    Raises
    ------
    ConfigError
        Naming the parameter, its value and what is allowed.
    """
    model = contact_model(s)
    if s.oxide.spot_rule not in model.spot_rules:
        raise ConfigError(
            f"oxide.spot_rule = {s.oxide.spot_rule!r} is not allowed with contact.model = {s.contact.model!r}: "
            f"must be {' or '.join(repr(r) for r in model.spot_rules)} ({model.spot_rule_reason}; the "
            f"{s.oxide.spot_rule} rule needs contact.model = {models_that(lambda m: s.oxide.spot_rule in m.spot_rules)})")
    model.check(s)


def step_target_conflicts(s: Scenario) -> list[tuple[str, Any, str, str]]:
    """The settings that keep a per-step ensemble target (``oxide.step_half_width``) from applying:
    (parameter, its value, the value it needs, why) each; empty where one applies."""
    needs = [("oxide.ensemble", s.oxide.ensemble, "adaptive", "a fixed ensemble has no target")]
    if not contact_model(s).computes_steps_alone:
        able = next(name for name, model in CONTACT_MODELS.items() if model.computes_steps_alone)
        needs.append(("contact.model", s.contact.model, able, "only discrete spots compute a field at some steps alone"))
    needs.append(("fits.reduction", s.fits.reduction, "geometric_mean", "the target is the geometric mean's"))
    return [need for need in needs if need[1] != need[2]]
