"""Eurocode 8's seismic coefficient of a non-structural element (EN 1998-1 §4.3.5.2).

A parapet, an ornament, a chimney on a building is checked in EN 1998-1 with a horizontal
force F_a = S_a W_a γ_a / q_a at its centre of mass [4.24], where

    S_a = α S [3 (1 + z/H) / (1 + (1 − T_a/T_1)²) − 0.5],   S_a ≥ α S        [4.25]

α = a_g/g on type A ground, S the soil factor, z the height of the element's base above
the foundation of a building of height H and fundamental period T_1, T_a the element's
period, γ_a its importance factor and q_a its behaviour factor (Tab. 4.4: 1.0 for
cantilevering parapets and ornamentations, 2.0 for walls and partitions). A rigid block
has no elastic period (T_a = 0): S_a = α S (1.5 (1 + z/H) − 0.5), α S on the ground and
2.5 α S on the roof. The soil factors are those of the type 1 spectrum (Tab. 3.2).
"""

from __future__ import annotations

from rockbench import checks
from rockbench.errors import ScenarioError

__all__ = ["SOIL_FACTORS", "soil_factor", "element_coefficient"]

#: S of the type 1 elastic spectrum (EN 1998-1 Tab. 3.2), by ground type.
SOIL_FACTORS = {"A": 1.0, "B": 1.2, "C": 1.15, "D": 1.35, "E": 1.4}


def soil_factor(ground: str) -> float:
    """S of ground type A–E (type 1 spectrum).

    Raises
    ------
    ScenarioError
        An unknown ground type.
    """
    if ground not in SOIL_FACTORS:
        raise ScenarioError(f"ground type must be one of {', '.join(SOIL_FACTORS)}, got "
                            f"{checks.describe(ground)}")
    return SOIL_FACTORS[ground]


def element_coefficient(alpha: float, soil: float, z: float = 0.0, height: float = 1.0,
                        element_period: float = 0.0, building_period: float = 1.0) -> float:
    """S_a of [4.25], in g: the element's design acceleration before γ_a / q_a.

    Parameters
    ----------
    alpha : float
        a_g / g on type A ground.
    soil : float
        The soil factor S.
    z, height : float
        Height of the element's base and of the building (m); z = 0 on the ground.
    element_period, building_period : float
        T_a and T_1 (s).

    Raises
    ------
    ScenarioError
        Negative values, z above the building, or periods that are not positive (T_a may
        be 0).
    """
    checks.number(alpha, "ag", low=0.0, strict=False)
    checks.number(soil, "soil factor S", low=0.0)
    checks.number(height, "building height", low=0.0)
    checks.number(z, "element height", low=0.0, strict=False, high=height)
    checks.number(element_period, "element period", low=0.0, strict=False)
    checks.number(building_period, "building period", low=0.0)
    r = 1.0 - element_period / building_period
    sa = alpha * soil * (3.0 * (1.0 + z / height) / (1.0 + r * r) - 0.5)
    return max(sa, alpha * soil)
