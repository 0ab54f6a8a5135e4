"""A linear damped oscillator under a record, integrated exactly.

The response q(t) of q̈ + 2ζω q̇ + ω² q = −ü_g(t) to a record, whose acceleration is
linear between samples, is exact at every step from the state-transition matrix of the
oscillator augmented with its linear forcing (one matrix exponential per distinct step;
the Nigam–Jennings scheme). :func:`response` samples it at least ``samples_per_period``
times per period of the oscillator and follows its free vibration after the record until
it has decayed to :data:`DECAY`. The floor motion of a building mode
(:mod:`rockbench.scenarios.floor`) and the spectral acceleration Sa(T, ζ)
(:mod:`rockbench.scenarios.intensity`) read it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

from rockbench import checks
from rockbench.scenarios.excitation import MIN_RECORD_STEP, Record

__all__ = ["Oscillator", "Response", "response", "DECAY"]

#: The free vibration after the record is followed until exp(−ζωt) falls to this.
DECAY = 1e-4


@dataclass(frozen=True)
class Oscillator:
    """A single-degree-of-freedom linear oscillator.

    Parameters
    ----------
    period : float
        Natural period T (s).
    damping : float
        Damping ratio ζ (default 0.05), in (0, 0.99].

    Raises
    ------
    ScenarioError
        A period that is not positive or a damping ratio out of range.
    """

    period: float
    damping: float = 0.05

    def __post_init__(self) -> None:
        checks.number(self.period, "oscillator period", low=0.0, unit="s")
        checks.number(self.damping, "oscillator damping ratio", low=0.0, high=0.99)

    @property
    def omega(self) -> float:
        """Circular frequency ω = 2π/T (rad/s)."""
        return 2.0 * math.pi / self.period


@dataclass(frozen=True)
class Response:
    """The oscillator's response on its time grid.

    Attributes
    ----------
    t : ndarray
        Times (s): the record's samples, each step cut to at most T / samples per
        period, then the free vibration.
    q, q_dot : ndarray
        Relative displacement (m) and velocity (m/s).
    ground : ndarray
        The ground acceleration (m/s², scale applied; 0 after the record).
    """

    t: np.ndarray
    q: np.ndarray
    q_dot: np.ndarray
    ground: np.ndarray


def _transition(osc: Oscillator, h: float) -> np.ndarray:
    """Exact one-step map of (q, q̇) under a forcing linear over the step, shape (2, 4).

    The columns act on (q, q̇, f_k, (f_{k+1} − f_k)/h), f = −ü_g.
    """
    w, z = osc.omega, osc.damping
    m = np.zeros((4, 4))
    m[0, 1] = 1.0
    m[1, 0], m[1, 1], m[1, 2] = -w * w, -2.0 * z * w, 1.0
    m[2, 3] = 1.0
    return expm(m * h)[:2]


def response(record: Record, osc: Oscillator, *, samples_per_period: int = 50) -> Response:
    """The oscillator's exact response to ``record``, from rest until it has decayed.

    Parameters
    ----------
    record : Record
        The ground acceleration (its scale applied).
    osc : Oscillator
        The oscillator.
    samples_per_period : int
        Fewest samples per period of the oscillator.

    Returns
    -------
    Response
        The time grid, q, q̇ and the ground acceleration on it. The sample after the
        record's last is 2 :data:`~rockbench.scenarios.excitation.MIN_RECORD_STEP` later,
        where the record's acceleration has dropped to 0 (a record may end on a constant
        of its baseline correction).
    """
    t_in = np.asarray(record.times, float)
    w, z = osc.omega, osc.damping
    h_max = osc.period / int(checks.integer(samples_per_period, "samples per period"))
    tail = math.log(1.0 / DECAY) / (z * w)
    # each record step cut into equal sub-steps no longer than h_max: the ground
    # acceleration stays linear on them
    cuts = np.maximum(1, np.ceil(np.diff(t_in) / h_max - 1e-9).astype(int))
    t = np.concatenate([np.concatenate([np.linspace(a, b, n, endpoint=False)
                                        for a, b, n in zip(t_in[:-1], t_in[1:], cuts,
                                                           strict=True)]),
                        [t_in[-1]],
                        t_in[-1] + 2.0 * MIN_RECORD_STEP
                        + h_max * np.arange(int(math.ceil(tail / h_max)) + 1)])
    ag = np.asarray(record.acceleration(t), float)
    ag[t > t_in[-1]] = 0.0
    # −ü_g at the start and end of each step; after the last sample it is 0
    f0 = np.where(t[:-1] >= t_in[-1], 0.0, -ag[:-1])
    f1 = -ag[1:]
    x = np.zeros((t.size, 2))
    maps: dict[float, np.ndarray] = {}
    for k, h in enumerate(np.diff(t)):
        key = round(float(h), 12)
        if key not in maps:
            maps[key] = _transition(osc, float(h))
        x[k + 1] = maps[key] @ (x[k, 0], x[k, 1], f0[k], (f1[k] - f0[k]) / h)
    return Response(t, x[:, 0], x[:, 1], ag)
