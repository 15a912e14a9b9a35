"""Named contact materials: elastic constants, resistivity and hardness of common connector metals.

A scenario names its two bodies (``material.bodies = ["hard_gold", "copper"]``) and the pair's
effective modulus ``E* = 1 / ((1 - nu1^2)/E1 + (1 - nu2^2)/E2)``, effective resistivity
``rho* = (rho1 + rho2) / 2`` and the hardness of the softer body follow
(:func:`pair_properties`); a value the scenario gives itself wins over the table's.

Values are for the bulk metal at room temperature, rounded to the precision the handbooks agree on:
Young's modulus and Poisson's ratio of the polycrystal and the resistivity at 20 degC from the CRC
Handbook of Chemistry and Physics (resistivity of the elements; elastic constants of polycrystals)
and ASM Handbook vol. 2 (copper alloys); the hardness ``H`` (Vickers, HV x 9.807 MPa) of the temper
or deposit a connector uses, from Slade (ed.), *Electrical Contacts: Principles and Applications*,
2nd ed. (2014) and the plating specifications it cites (ASTM B488 for gold: Grade C, 130-200 HK, for
hard gold). Hardness depends on temper and deposition more than any other entry here: measure yours
and set ``material.hardness`` where it matters.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

__all__ = ["NamedMaterial", "MATERIALS", "pair_properties"]


@dataclass(frozen=True)
class NamedMaterial:
    """One body's properties.

    Attributes
    ----------
    E
        Young's modulus, Pa.
    nu
        Poisson's ratio.
    rho
        Electrical resistivity at 20 degC, ohm m.
    hardness
        Indentation hardness of the temper or deposit named, Pa.
    note
        What the entry stands for (temper, deposit).
    """

    E: float
    nu: float
    rho: float
    hardness: float
    note: str


#: The table, by the name a scenario uses.
MATERIALS: dict[str, NamedMaterial] = {
    "gold": NamedMaterial(79e9, 0.42, 2.2e-8, 0.8e9, "soft (pure) gold electroplate, ASTM B488 Type III, ~80 HV"),
    "hard_gold": NamedMaterial(79e9, 0.42, 2.2e-8, 1.5e9, "cobalt-hardened gold electroplate, ASTM B488 Grade C, "
                               "~150 HV; resistivity of pure gold (the hardener raises it: measure yours)"),
    "silver": NamedMaterial(83e9, 0.37, 1.6e-8, 0.9e9, "silver electroplate, ~90 HV"),
    "copper": NamedMaterial(128e9, 0.34, 1.7e-8, 1.0e9, "half-hard copper (C11000 H02), ~100 HV"),
    "tin": NamedMaterial(50e9, 0.36, 1.15e-7, 0.1e9, "matte tin electroplate, ~10 HV"),
    "nickel": NamedMaterial(200e9, 0.31, 6.9e-8, 2.2e9, "nickel electroplate (Watts bath), ~220 HV"),
    "palladium": NamedMaterial(121e9, 0.39, 1.05e-7, 2.5e9, "palladium electroplate, ~250 HV"),
    "brass": NamedMaterial(110e9, 0.35, 6.2e-8, 1.3e9, "cartridge brass C26000, half hard, ~130 HV"),
    "steel": NamedMaterial(210e9, 0.30, 7.2e-7, 2.0e9, "the paper's steel (Table 1: E, nu and rho of a stainless "
                           "steel) with an annealed austenitic stainless steel's ~200 HV"),
}


def pair_properties(bodies: Sequence[str]) -> tuple[float, float, float]:
    """``(E*, rho*, H)`` of the pair named by ``bodies`` (one name: two bodies of it), Pa, ohm m, Pa.

    ``H`` is the softer body's hardness: the asperities of the softer body yield first.

    Raises
    ------
    KeyError
        On a name not in :data:`MATERIALS`.
    """
    pair = [MATERIALS[name] for name in bodies] * (2 // len(bodies))
    compliance = sum((1.0 - m.nu**2) / m.E for m in pair)
    return 1.0 / compliance, sum(m.rho for m in pair) / 2.0, min(m.hardness for m in pair)
