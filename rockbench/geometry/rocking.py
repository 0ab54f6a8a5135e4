"""Housner's rocking constants of a rigid body about a corner pivot."""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["RockingProperties", "rocking_about"]


@dataclass(frozen=True)
class RockingProperties:
    """Rocking constants of a rigid body about a corner pivot.

    Attributes
    ----------
    lam : float
        Critical (slenderness) angle λ = atan(b/h) in rad, b the pivot
        half-width and h the height of the centre of gravity above the pivots.
    R : float
        Distance pivot–centre of gravity (m).
    p : float
        Frequency parameter sqrt(m g R / I_O) (rad/s).
    eta : float
        Housner's angular-velocity ratio at impact, 1 − 2 m b² / I_O.
    I_O : float
        Moment of inertia about the pivot (kg m²).
    """

    lam: float
    R: float
    p: float
    eta: float
    I_O: float

    @property
    def uplift_acceleration(self) -> float:
        """Static uplift threshold g tan λ divided by g (i.e. tan λ)."""
        return math.tan(self.lam)


def rocking_about(m: float, b: float, h: float, i_c: float, g: float) -> RockingProperties:
    """The constants of a body of mass ``m`` and centroidal inertia ``i_c`` (about y).

    Parameters
    ----------
    m : float
        Mass (kg).
    b, h : float
        Horizontal and vertical distances from the pivot to the centre of gravity (m).
    i_c : float
        Centroidal moment of inertia about y (kg m²).
    g : float
        Gravity (m/s²).
    """
    r = math.hypot(b, h)
    i_o = float(i_c) + m * r * r
    return RockingProperties(
        lam=math.atan2(b, h), R=r, p=math.sqrt(m * g * r / i_o),
        eta=1.0 - 2.0 * m * b * b / i_o, I_O=i_o,
    )
