"""Overturning of a single rocking block under one-sine and one-cosine acceleration pulses.

The classic overturning spectra (Housner 1963; Makris & Roussos 2000; Zhang &
Makris 2001; Dimitrakopoulos & DeJong 2012) give, for each pulse frequency, the
pulse accelerations that overturn a block. In normalised form a pulse is
described by ``a_p/(g λ)`` and ``ω_p/p``; in the linearised model (sin x ≈ x,
cos x ≈ 1, uplift at g λ) the response θ/λ depends on these two numbers and η
only, so one map serves every slender block.

How a cell is decided
---------------------
The pulse ü_g = a_p sin(ω_p t) or a_p cos(ω_p t), 0 ≤ t ≤ 2π/ω_p, is solved with
:func:`rockbench.analytic.housner.solve_single` up to its end only. After the
pulse the motion is free and its fate follows from energy alone
(:func:`free_motion_fate`, ``two-block-model.md`` §4): between impacts the
energy is conserved, each impact multiplies θ̇ by η, so the block either
overturns before its next impact, or after exactly one more impact, or never.
No duration has to be chosen and cells next to a boundary (where the block
lingers near the saddle for an arbitrarily long time) are decided exactly.

Outcome codes (:attr:`Outcome.code`): ``-1`` no uplift, ``0`` rocks but
survives, ``1`` overturns without impact (mode 1), ``n + 1`` overturns after
``n`` impacts (``2`` is Zhang & Makris' mode 2).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from rockbench.analytic.housner import scalar_acceleration, solve_single
from rockbench.geometry import RockingProperties
from rockbench.scenarios import CosinePulse, Motion, SinePulse

__all__ = [
    "PULSES", "NO_UPLIFT", "SAFE", "Outcome", "Boundary", "ColumnResult",
    "pulse_excitation", "free_motion_fate", "pulse_outcome", "normalised_outcome",
    "scan_column", "minimum_overturning_acceleration", "housner_eta", "outcome_label",
]

#: Pulse shapes: ü_g = a_p sin(ω_p t) ("sine") or a_p cos(ω_p t) ("cosine") over one period.
PULSES = ("sine", "cosine")
#: Outcome code of a block that never leaves rest.
NO_UPLIFT = -1
#: Outcome code of a block that rocks and survives.
SAFE = 0
#: At most this many boundaries are refined between two neighbouring grid cells.
_MAX_CHANGES = 8


def housner_eta(lam: float) -> float:
    """Housner's velocity ratio at impact of a rectangular block, ``1 − 1.5 sin² λ``.

    Parameters
    ----------
    lam : float
        Critical angle λ (rad).

    Returns
    -------
    float
        η (θ̇⁺ = η θ̇⁻), clipped at 0 past λ ≈ 54.7° where the formula goes negative
        (a squat block stops at its first impact).
    """
    return max(0.0, 1.0 - 1.5 * math.sin(lam) ** 2)


def outcome_label(code: int) -> str:
    """Human-readable name of an outcome code."""
    if code == NO_UPLIFT:
        return "safe (no uplift)"
    if code == SAFE:
        return "safe (rocks)"
    if code == 1:
        return "overturns without impact (mode 1)"
    n = code - 1
    return f"overturns after {n} impact{'s' if n > 1 else ''}"


@dataclass(frozen=True)
class Outcome:
    """Fate of a block under one pulse.

    Attributes
    ----------
    overturned : bool
        True if the block overturns (during the pulse or in the free motion after it).
    impacts : int
        Impacts before overturning (if overturned) or during the pulse (if safe).
    uplift : bool
        True if the block left rest at all.
    overturn_time : float or None
        Time when |θ| reached π/2 if that happened during the pulse; None if the
        block survived or its overturning was decided from the free motion after
        the pulse.
    message : str
        The solver's message (e.g. ``"incomplete"`` chattering).
    """

    overturned: bool
    impacts: int
    uplift: bool
    overturn_time: float | None = None
    message: str = ""

    @property
    def code(self) -> int:
        """``-1`` no uplift, ``0`` safe, ``1`` mode 1 (no impact), ``n + 1`` after n impacts."""
        if not self.uplift:
            return NO_UPLIFT
        return self.impacts + 1 if self.overturned else SAFE

    @property
    def label(self) -> str:
        """Human-readable outcome (:func:`outcome_label`)."""
        return outcome_label(self.code)


def pulse_excitation(kind: str, a_p: float, omega_p: float) -> SinePulse | CosinePulse:
    """The one-cycle pulse ü_g = a_p sin(ω_p t) or a_p cos(ω_p t) on [0, 2π/ω_p].

    Parameters
    ----------
    kind : {"sine", "cosine"}
        Pulse shape.
    a_p : float
        Acceleration amplitude (m/s², signed).
    omega_p : float
        Circular frequency (rad/s).

    Returns
    -------
    SinePulse or CosinePulse

    Raises
    ------
    ValueError
        Unknown pulse kind.
    """
    if kind == "sine":
        return SinePulse.from_acceleration(a_p, omega_p)
    if kind == "cosine":
        return CosinePulse.from_acceleration(a_p, omega_p)
    raise ValueError(f"unknown pulse {kind!r}; choose one of {', '.join(PULSES)}")


def _potential(theta: float, s: float, lam: float, p: float, linear: bool) -> float:
    """Potential per unit I_O relative to the saddle (CG above the pivot on side s)."""
    if linear:
        return -0.5 * p * p * (theta - s * lam) ** 2
    # cos(sλ − θ) − 1 = −2 sin²((sλ − θ)/2), accurate near the saddle
    return -2.0 * p * p * math.sin(0.5 * (s * lam - theta)) ** 2


def free_motion_fate(theta: float, omega: float, *, lam: float, p: float, eta: float,
                     linear: bool = False) -> tuple[bool, int]:
    """Decide overturning of free rocking (no base motion) from one state.

    Between impacts the energy e = ½θ̇² + V(θ) is conserved; the saddle (centre
    of gravity above the pivot) has e = 0 here. On side s = sgn θ:

    * |θ| < λ moving outward (s θ̇ > 0) with e > 0: overturns before any impact;
    * |θ| ≥ λ: overturns unless it moves back (s θ̇ < 0) with e > 0;
    * otherwise it returns to θ = 0, the impact keeps η θ̇ and it overturns on the
      other side iff the reduced energy is still above the saddle. Later impacts
      only lose energy, so the block is then safe for good.

    Parameters
    ----------
    theta, omega : float
        Rotation (rad) and rate (rad/s).
    lam, p : float
        Critical angle (rad) and frequency parameter (rad/s).
    eta : float
        Velocity ratio at impact.
    linear : bool
        Linearised potential −½p²(θ − sλ)² instead of p²(cos(sλ − θ) − 1).

    Returns
    -------
    overturns : bool
    impacts : int
        Impacts before overturning (0 or 1); 0 when it does not overturn.
    """
    if theta == 0.0 and omega == 0.0:
        return False, 0
    s = math.copysign(1.0, theta if theta != 0.0 else omega)
    e = 0.5 * omega * omega + _potential(theta, s, lam, p, linear)
    outward = s * omega > 0.0
    if s * theta >= lam:
        if outward or e <= 0.0:
            return True, 0
    elif outward and e > 0.0:
        return True, 0
    # back to θ = 0, impact, then the other side
    v0 = _potential(0.0, s, lam, p, linear)
    w2 = 2.0 * (e - v0)
    e_after = 0.5 * eta * eta * w2 + v0
    return (True, 1) if e_after > 0.0 else (False, 0)


def pulse_outcome(rock: RockingProperties, excitation: Motion, *, g: float,
                  eta: float | None = None, linear: bool = False, rtol: float = 1e-9,
                  atol: float = 1e-12) -> Outcome:
    """Fate of a block at rest under a base motion that ends (a pulse or any finite motion).

    Parameters
    ----------
    rock : RockingProperties
        Block constants (λ, p, η).
    excitation : Motion
        Base motion with a finite ``end_time``.
    g : float
        Gravity (m/s²).
    eta : float, optional
        Velocity ratio at impact; default ``rock.eta`` (Housner's formula).
    linear : bool
        Linearised model.
    rtol, atol : float
        Tolerances of the forced phases.

    Returns
    -------
    Outcome

    Raises
    ------
    ValueError
        The excitation never ends.
    """
    t_end = float(excitation.end_time)
    if not math.isfinite(t_end):
        raise ValueError("pulse_outcome needs an excitation with a finite end_time")
    eta = float(rock.eta if eta is None else eta)
    if t_end <= 0.0:
        return Outcome(False, 0, False)
    sol = solve_single(rock, g=g, accel=excitation.acceleration,
                       accel_scalar=scalar_acceleration(excitation),
                       breakpoints=excitation.breakpoints, end_time=t_end,
                       t_out=np.array([0.0, t_end]), eta=eta, linear=linear,
                       rtol=rtol, atol=atol)
    uplift = sol.uplift_times.size > 0
    n_imp = int(sol.impacts.size)
    if sol.status == "overturned":
        return Outcome(True, n_imp, True, sol.overturn_time, sol.message)
    if sol.status != "ok":  # chattering guard hit: report as survived, with the reason
        return Outcome(False, n_imp, uplift, None, sol.message)
    over, extra = free_motion_fate(float(sol.theta[-1]), float(sol.theta_dot[-1]),
                                   lam=rock.lam, p=rock.p, eta=eta, linear=linear)
    return Outcome(over, n_imp + extra, uplift, None, sol.message)


def normalised_outcome(rock: RockingProperties, kind: str, a_ratio: float, w_ratio: float, *,
                       g: float, eta: float | None = None, linear: bool = False,
                       rtol: float = 1e-9) -> Outcome:
    """:func:`pulse_outcome` of a pulse given as ``a_p/(g λ)`` and ``ω_p/p``.

    Parameters
    ----------
    rock : RockingProperties
        Block constants.
    kind : {"sine", "cosine"}
        Pulse shape.
    a_ratio : float
        a_p/(g λ) (signed: negative reverses the pulse).
    w_ratio : float
        ω_p/p (> 0).
    g : float
        Gravity (m/s²).
    eta : float, optional
        Velocity ratio at impact (default Housner's).
    linear : bool
        Linearised model.
    rtol : float
        Relative tolerance of the forced phases.
    """
    if a_ratio == 0.0:
        return Outcome(False, 0, False)
    exc = pulse_excitation(kind, a_ratio * g * rock.lam, w_ratio * rock.p)
    return pulse_outcome(rock, exc, g=g, eta=eta, linear=linear, rtol=rtol)


@dataclass(frozen=True)
class Boundary:
    """A refined change of outcome along a_p at fixed ω_p.

    Attributes
    ----------
    w_ratio : float
        ω_p/p of the column.
    a_ratio : float
        a_p/(g λ) of the boundary (midpoint of the final bisection bracket).
    below, above : int
        Outcome codes just below and just above it.
    width : float
        Width of the final bracket in a_p/(g λ).
    """

    w_ratio: float
    a_ratio: float
    below: int
    above: int
    width: float

    @property
    def kind(self) -> str:
        """``"onset"`` (safe below, overturns above), ``"island"`` (overturns below, safe
        above) or ``"mode"`` (both overturn, with different numbers of impacts)."""
        lo, hi = self.below > SAFE, self.above > SAFE
        if lo and hi:
            return "mode"
        return "onset" if hi else "island"


@dataclass(frozen=True)
class ColumnResult:
    """Outcomes of one ω_p/p column of an overturning map.

    Attributes
    ----------
    w_ratio : float
        ω_p/p.
    a_ratios : ndarray
        a_p/(g λ) of the grid cells (increasing).
    codes : ndarray of int
        Outcome code of each cell.
    boundaries : list of Boundary
        Refined changes between neighbouring cells (only those involving overturning).
    n_solves : int
        Number of pulse solutions computed.
    """

    w_ratio: float
    a_ratios: np.ndarray
    codes: np.ndarray
    boundaries: list[Boundary] = field(default_factory=list)
    n_solves: int = 0

    @property
    def minimum_overturning(self) -> float:
        """Smallest overturning a_p/(g λ) found (the first onset), NaN if none."""
        onsets = [b.a_ratio for b in self.boundaries if b.kind == "onset"]
        if onsets:
            return min(onsets)
        over = np.flatnonzero(self.codes > SAFE)
        return float(self.a_ratios[over[0]]) if over.size else math.nan


def _bisect(f: Callable[[float], int], lo: float, hi: float, c_lo: int, c_hi: int,
            tol: float, differs: Callable[[int, int], bool]) -> tuple[float, float, int, int, int]:
    """Shrink [lo, hi] around a change: keep ``differs(c_lo, code) `` true at ``hi``."""
    n = 0
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        c = f(mid)
        n += 1
        if differs(c_lo, c):
            hi, c_hi = mid, c
        else:
            lo, c_lo = mid, c
    return lo, hi, c_lo, c_hi, n


def scan_column(rock: RockingProperties, kind: str, w_ratio: float,
                a_ratios: Sequence[float] | np.ndarray, *, g: float, eta: float | None = None,
                linear: bool = False, tol: float | None = 1e-3, rtol: float = 1e-9,
                modes: bool = True) -> ColumnResult:
    """Outcomes along a_p/(g λ) at one ω_p/p, with the boundaries refined by bisection.

    Every change between neighbouring grid cells where at least one side
    overturns is bisected down to ``tol``: the safe/overturn boundaries
    (``onset`` and ``island``) and, with ``modes``, the changes of the number of
    impacts. After each bisection the search goes on above the change found,
    up to the next grid cell, so that several changes between two cells (a
    narrow island between two overturning modes) are all refined. The
    overturning set is not monotone in a_p (safe islands above the first
    boundary): an island lying entirely between two cells with the same code is
    missed; refine the grid to find it.

    Parameters
    ----------
    rock : RockingProperties
        Block constants.
    kind : {"sine", "cosine"}
        Pulse shape.
    w_ratio : float
        ω_p/p.
    a_ratios : array_like
        Increasing a_p/(g λ) values of the grid (≥ 0).
    g : float
        Gravity (m/s²).
    eta : float, optional
        Velocity ratio at impact (default Housner's).
    linear : bool
        Linearised model.
    tol : float or None
        Bisection tolerance in a_p/(g λ); None skips the refinement.
    rtol : float
        Relative tolerance of the forced phases.
    modes : bool
        Also refine changes between overturning modes.

    Returns
    -------
    ColumnResult
    """
    a = np.asarray(a_ratios, dtype=float)
    if a.ndim != 1 or np.any(np.diff(a) <= 0):
        raise ValueError("a_ratios must be a strictly increasing 1-D sequence")

    def code(x: float) -> int:
        return normalised_outcome(rock, kind, x, w_ratio, g=g, eta=eta, linear=linear,
                                  rtol=rtol).code

    codes = np.array([code(float(x)) for x in a], dtype=int)
    n = a.size

    def key(c: int) -> int:
        if c <= SAFE:
            return SAFE
        return c if modes else 1

    def differs(c0: int, c1: int) -> bool:
        return key(c0) != key(c1)

    bounds: list[Boundary] = []
    if tol is not None:
        for i in range(a.size - 1):
            lo, c_lo = float(a[i]), int(codes[i])
            top, c_top = float(a[i + 1]), int(codes[i + 1])
            # each pass finds the lowest change above lo; more may hide before the next cell
            for _ in range(_MAX_CHANGES):
                if not differs(c_lo, c_top) or top - lo <= tol:
                    break
                lo, hi, c_lo, c_hi, k = _bisect(code, lo, top, c_lo, c_top, tol, differs)
                n += k
                if c_lo > SAFE or c_hi > SAFE:
                    bounds.append(Boundary(w_ratio, 0.5 * (lo + hi), c_lo, c_hi, hi - lo))
                lo, c_lo = hi, c_hi
    return ColumnResult(w_ratio, a, codes, bounds, n)


def minimum_overturning_acceleration(rock: RockingProperties, kind: str, omega_p: float, *,
                                     g: float, eta: float | None = None, linear: bool = False,
                                     a_max: float = 20.0, n_scan: int = 200,
                                     tol: float = 1e-6) -> tuple[float, int]:
    """Smallest a_p (m/s²) of a pulse of frequency ω_p that overturns the block.

    A scan of ``n_scan`` accelerations from the uplift threshold to
    ``a_max · g λ`` finds the first overturning cell, then bisection refines the
    boundary. The overturning set is not monotone in a_p; an overturning sliver
    narrower than the scan step below the first one found would be missed.

    Parameters
    ----------
    rock : RockingProperties
        Block constants.
    kind : {"sine", "cosine"}
        Pulse shape.
    omega_p : float
        Circular frequency (rad/s).
    g : float
        Gravity (m/s²).
    eta : float, optional
        Velocity ratio at impact (default Housner's).
    linear : bool
        Linearised model.
    a_max : float
        Upper end of the scan in units of g λ.
    n_scan : int
        Number of scan points.
    tol : float
        Bisection tolerance in units of g λ.

    Returns
    -------
    a_p : float
        Minimum overturning acceleration (m/s²), NaN if none up to ``a_max``.
    code : int
        Outcome code just above it (1: mode 1, 2: after one impact, ...).
    """
    w_ratio = omega_p / rock.p
    thr = 1.0 if linear else math.tan(rock.lam) / rock.lam
    a = np.linspace(thr, a_max, n_scan)
    col = scan_column(rock, kind, w_ratio, [0.0, *a.tolist()], g=g, eta=eta, linear=linear,
                      tol=None)
    over = np.flatnonzero(col.codes > SAFE)
    if not over.size:
        return math.nan, SAFE
    i = int(over[0])

    def code(x: float) -> int:
        return normalised_outcome(rock, kind, x, w_ratio, g=g, eta=eta, linear=linear).code

    lo, hi, _, c_hi, _ = _bisect(code, float(col.a_ratios[i - 1]), float(col.a_ratios[i]),
                                 int(col.codes[i - 1]), int(col.codes[i]), tol,
                                 lambda c_lo, c: c > SAFE)
    return 0.5 * (lo + hi) * g * rock.lam, c_hi
