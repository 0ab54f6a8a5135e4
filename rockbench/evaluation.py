"""One typed result per run: :class:`RunMetrics`, computed by :func:`evaluate_run` only.

Every study, table, figure, CSV/JSON file, JUnit file, tolerance check and the
results store read a run's numbers from a :class:`RunMetrics`; no metric is
computed anywhere else. Definitions (angles normalised by the scenario's λ):

* ``peaks``: max |θ_i|/λ per block (bottom first).
* ``max_error``: max |θ − θ_ref|/λ over all blocks and common samples; when the
  reference overturns, only until the reference passes λ (beyond it the fall is
  no rocking comparison). ``max_error_early``: the same up to the reference's
  third impact.
* impacts (:func:`rocking_impacts`, one definition for engines and references):
  the zero crossings of the bottom block's θ, linearly interpolated between
  samples, counted only once |θ| reached :data:`IMPACT_THRESHOLD` λ since the
  previous counted crossing (contact jitter before uplift is not an impact).
  ``impact_time_errors``: relative errors of the first :data:`N_IMPACTS`
  reference impacts (None where the run lacks one, counted in
  ``impacts_missing``).
* ``peak_errors``: signed (p_i − r_i) / max(r_i, :data:`PEAK_FLOOR`) per block
  against a reference that ends ``ok``: the floor keeps a reference that barely
  lifts (a few thousandths of λ) from turning noise into huge relative errors.
  ``peak_error``: the largest magnitude.
* ``time_to_rest``: first time after which every |θ| stays below 0.01 λ.
* ``realtime_factor``: simulated seconds per wall second of the run (the
  samples the run produced, not the duration requested).
* ``slide``: the bottom block's largest departure from rigid rocking
  kinematics (sliding or contact drift, m); ``max_wobble``: largest out-of-plane
  rotation (rad); ``max_roll`` and ``max_twist``: largest |rotation about +x| and about the
  block's own vertical axis (rad; 0 for planar methods).
* ``interface_slip``, ``interface_gap``: the largest departure of the upper
  blocks from rigid no-slip rocking on the block below (:func:`interface_motion`,
  m; None for a single block): tangential (slip along the lower block's top
  face) and normal (gap, or penetration, at the active interface pivot).
* ``horizon``: the predictability horizon t* the comparison stopped at
  (:mod:`rockbench.campaign.predictability`; None: not measured, the whole run
  is compared). With a horizon shorter than the run, ``max_error``,
  ``max_error_early``, the impact errors and the peak errors (peaks of θ up to
  t*) stop at t*: beyond it the reference itself is not predictable, so peaks
  and impacts there are not compared one-to-one (``error_note`` says so).
"""

from __future__ import annotations

import math
import typing
from collections.abc import Mapping
from dataclasses import MISSING, asdict, dataclass, fields
from typing import Any

import numpy as np

from rockbench import metrics
from rockbench.analytic import critical_angle
from rockbench.method import Method
from rockbench.scenarios import Scenario
from rockbench.trajectory import Status, Trajectory

__all__ = ["RunMetrics", "RunResult", "evaluate_run", "rocking_impacts", "sliding",
           "interface_motion", "finite_or_none",
           "IMPACT_THRESHOLD", "PEAK_FLOOR", "N_IMPACTS", "NUMERIC_METRICS"]

#: A zero crossing of θ is an impact only after |θ| reached this fraction of λ.
IMPACT_THRESHOLD = 0.01
#: Floor (fraction of λ) under the reference peak in relative peak errors.
PEAK_FLOOR = 0.02
#: Number of first impacts whose times are compared.
N_IMPACTS = 3


def finite_or_none(x: Any) -> float | None:
    """``x`` as a finite float, or None (the one convention for undefined numbers)."""
    try:
        v = float(x)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def rocking_impacts(traj: Trajectory, lam: float, block: int = 0,
                    threshold: float = IMPACT_THRESHOLD) -> np.ndarray:
    """Impact times of a block: zero crossings of θ after it rocked beyond ``threshold`` λ."""
    if traj.t.size < 2:
        return np.zeros(0)
    return metrics.zero_crossings(traj.t, traj.theta[:, block], threshold * lam)


def sliding(traj: Trajectory, scenario: Scenario) -> float | None:
    """Largest sliding of the bottom block on the base (m), None if positions are unknown.

    A block that rocks without sliding has its centroid where the rigid
    rotation about its active pivot puts it: ``x = u_g + s b' − s b' cos θ +
    h sin θ`` (``s = sgn θ``, ``b'`` the pivot half-width, ``h`` the half-height,
    ``u_g`` the base displacement). The largest departure from it measures
    sliding or drift of the contact. Only samples where the block is within its
    critical angle count (an overturning block slides when it lands).
    """
    col = scenario.geometry.column
    if col is None or traj.t.size == 0 or not np.all(np.isfinite(traj.x[:, 0])):
        return None  # (other geometries' blocks have no single base pivot to slide on)
    b = col.blocks[0]
    th = traj.theta[:, 0]
    sgn = np.sign(th)
    u = np.asarray(scenario.motion.x.displacement(traj.t), float)
    x_kin = (u + col.offsets[0] + sgn * b.pivot_half_width
             - sgn * b.pivot_half_width * np.cos(th) + b.h * np.sin(th))
    keep = np.abs(th) <= b.rocking(scenario.g).lam  # not falling over
    return float(np.max(np.abs(traj.x[keep, 0] - x_kin[keep]))) if keep.any() else None


def interface_motion(traj: Trajectory,
                     scenario: Scenario) -> tuple[float | None, float | None]:
    """Largest slip and gap (m) of each upper block on the block below, from the poses.

    Without slip or separation, the active interface pivot (the corner of the
    contact face on the side of the relative rotation φ = θ_up − θ_lo) is one
    point of both blocks: ``X_lo + R(θ_lo) (x_p − o_lo, h_lo)`` and
    ``X_up + R(θ_up) (x_p − o_up, −h_up)`` (X the centroid, o the block's offset,
    x_p the pivot's x in the stack's upright frame, R the rotation about +y).
    Their difference, resolved along the lower block's top face, is the slip;
    normal to it, the gap (separation or penetration). Both are the largest
    magnitudes over the interfaces and over the samples where every block is within its
    critical angle on its support (a falling block slides when it lands).

    Returns
    -------
    (max_slip, max_gap) : tuple of float or None
        None for a single block or a trajectory without finite positions.
    """
    nb = scenario.n_blocks
    col = scenario.geometry.column
    if nb < 2 or traj.t.size == 0 or col is None:
        return None, None
    if not (np.all(np.isfinite(traj.x)) and np.all(np.isfinite(traj.z))):
        return None, None
    # not falling: the bottom block within its λ, each upper one within its interface's
    keep = np.abs(traj.theta[:, 0]) <= col.blocks[0].rocking(scenario.g).lam
    for i in range(1, nb):
        keep &= (np.abs(traj.theta[:, i] - traj.theta[:, i - 1])
                 <= col.interface(i, scenario.g).lam)
    if not keep.any():
        return None, None
    th, x, z = traj.theta[keep], traj.x[keep], traj.z[keep]
    offs = col.offsets
    slip = gap = 0.0
    for i in range(1, nb):
        lo, up = col.blocks[i - 1], col.blocks[i]
        o_lo, o_up = offs[i - 1], offs[i]
        left, right = col.overlap(i)
        phi = th[:, i] - th[:, i - 1]
        # at φ = 0 (face contact) every point of the face is shared: take its middle
        xp = np.where(phi > 0, right, np.where(phi < 0, left, 0.5 * (left + right)))
        pts = []
        for k, (o, hz) in enumerate(((o_lo, lo.h), (o_up, -up.h))):
            j = i - 1 + k
            vx, c, s = xp - o, np.cos(th[:, j]), np.sin(th[:, j])
            # R(θ)(v_x, v_z) = (v_x cos θ + v_z sin θ, −v_x sin θ + v_z cos θ)
            pts.append((x[:, j] + vx * c + hz * s, z[:, j] - vx * s + hz * c))
        dx, dz = pts[1][0] - pts[0][0], pts[1][1] - pts[0][1]
        c, s = np.cos(th[:, i - 1]), np.sin(th[:, i - 1])
        # lower block's top face: tangent R(θ)(1, 0) = (c, −s), normal R(θ)(0, 1) = (s, c)
        slip = max(slip, float(np.max(np.abs(dx * c - dz * s))))
        gap = max(gap, float(np.max(np.abs(dx * s + dz * c))))
    return slip, gap


def _floats(values: Any) -> tuple[float | None, ...]:
    return tuple(finite_or_none(v) for v in values)


@dataclass(frozen=True)
class RunMetrics:
    """Everything measured of one run (see the module docstring for the definitions).

    Undefined numbers are None (no reference, no samples, a reference that
    overturned where a peak error is asked for, ...); ``error_note`` says why the
    errors are missing when they are.
    """

    status: Status
    message: str
    n_blocks: int
    critical_angle: float
    duration: float
    peaks: tuple[float | None, ...]
    simulated_time: float
    n_samples: int
    wall_time: float
    cpu_time: float | None
    realtime_factor: float | None
    time_to_rest: float | None
    max_wobble: float | None
    slide: float | None
    engine_version: str = ""
    settings_hash: str = ""
    scenario_hash: str = ""
    reference_status: Status | None = None
    reference_time_to_rest: float | None = None
    max_error: float | None = None
    max_error_early: float | None = None
    peak_errors: tuple[float | None, ...] = ()
    peak_error: float | None = None
    max_roll: float | None = None
    max_twist: float | None = None
    impact_time_errors: tuple[float | None, ...] = ()
    impact_time_error: float | None = None
    impacts_missing: int | None = None
    error_note: str = ""
    interface_slip: float | None = None
    interface_gap: float | None = None
    horizon: float | None = None

    @property
    def completed(self) -> bool:
        """The run ended ``ok`` or ``overturned``."""
        return self.status.completed

    @property
    def time_per_simulated_second(self) -> float | None:
        """Wall seconds per simulated second (the inverse of the real-time factor)."""
        return (self.wall_time / self.simulated_time
                if self.simulated_time > 0 and self.wall_time > 0 else None)

    @property
    def cpu_per_simulated_second(self) -> float | None:
        """CPU seconds per simulated second (None where CPU time was not measured)."""
        return (self.cpu_time / self.simulated_time
                if self.cpu_time and self.simulated_time > 0 else None)

    def value(self, name: str) -> float | None:
        """A scalar metric by name (tolerance and baseline files name them).

        Raises
        ------
        KeyError
            ``name`` is not one of :data:`NUMERIC_METRICS`.
        """
        if name not in NUMERIC_METRICS:
            raise KeyError(name)
        return finite_or_none(getattr(self, name))

    def to_json(self) -> dict[str, Any]:
        """Plain JSON-able form (the store's and baselines' format)."""
        out = asdict(self)
        out["status"] = self.status.value
        out["reference_status"] = (None if self.reference_status is None
                                   else self.reference_status.value)
        for k in ("peaks", "peak_errors", "impact_time_errors"):
            out[k] = list(out[k])
        return out

    @classmethod
    def from_json(cls, data: Any, *, where: str = "metrics") -> RunMetrics:
        """Inverse of :meth:`to_json`, with every field's type checked (no coercion).

        Unknown keys are ignored and fields with defaults may be missing.

        Raises
        ------
        ValueError
            Not a table, a missing required field, or a value of the wrong type;
            the message names ``where`` and the field.
        """
        if not isinstance(data, Mapping):
            raise ValueError(f"{where} must be a table of run metrics")
        missing = sorted(_REQUIRED - set(data))
        if missing:
            raise ValueError(f"{where}.{missing[0]} is missing")
        kw = {}
        for name, hint in _HINTS.items():
            if name in data:
                kw[name] = _checked(data[name], hint, f"{where}.{name}")
        return cls(**kw)


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _checked(value: Any, hint: Any, where: str) -> Any:
    """One JSON value as a :class:`RunMetrics` field of type ``hint`` (no coercion)."""
    args = typing.get_args(hint)
    optional = type(None) in args
    if value is None:
        if optional:
            return None
        raise ValueError(f"{where} must not be null")
    base = next((a for a in args if a is not type(None)), hint) if optional else hint
    if typing.get_origin(base) is tuple:
        if not isinstance(value, list):
            raise ValueError(f"{where} must be a list of numbers or nulls, got {value!r}")
        for i, v in enumerate(value):
            if v is not None and not _is_number(v):
                raise ValueError(f"{where}[{i}] must be a number or null, got {v!r}")
        return _floats(value)
    if base is Status:
        try:
            return Status(value)
        except ValueError:
            raise ValueError(f"{where} must be one of {', '.join(s.value for s in Status)}, "
                             f"got {value!r}") from None
    if base is str:
        if not isinstance(value, str):
            raise ValueError(f"{where} must be a string, got {value!r}")
        return value
    if base is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValueError(f"{where} must be an integer, got {value!r}")
        return value
    if not _is_number(value):
        raise ValueError(f"{where} must be a number{' or null' if optional else ''}, "
                         f"got {value!r}")
    return float(value)


_HINTS = typing.get_type_hints(RunMetrics)
_REQUIRED = {f.name for f in fields(RunMetrics)
             if f.default is MISSING and f.default_factory is MISSING}


#: Scalar metrics that tolerance and baseline files may name.
NUMERIC_METRICS = frozenset({
    "max_error", "max_error_early", "peak_error", "impact_time_error", "impacts_missing",
    "time_to_rest", "reference_time_to_rest", "wall_time", "cpu_time", "realtime_factor",
    "slide", "max_wobble", "max_roll", "max_twist", "simulated_time", "interface_slip",
    "interface_gap",
})


def evaluate_run(scenario: Scenario, traj: Trajectory, reference: Trajectory | None, *,
                 is_reference: bool = False, settings_hash: str = "", scenario_hash: str = "",
                 engine_version: str = "", reference_note: str = "",
                 horizon: float | None = None) -> RunMetrics:
    """The metrics of one run against the analytic reference (the only metric function).

    Parameters
    ----------
    scenario : Scenario
        What was simulated.
    traj : Trajectory
        The run's result.
    reference : Trajectory or None
        The analytic reference of the scenario (None if there is none).
    is_reference : bool
        ``traj`` is the reference itself: no errors are computed.
    settings_hash, scenario_hash, engine_version : str
        Identity of the run, stored with it.
    reference_note : str
        Why there is no usable reference (kept as ``error_note``).
    horizon : float, optional
        Predictability horizon t* (s) of the scenario: errors are measured up
        to it (see the module docstring); recorded as ``horizon``.
    """
    lam = critical_angle(scenario.geometry)
    n = traj.t.size
    simulated = float(traj.t[-1]) if n else 0.0
    wall = float(traj.wall_time)
    slip, gap = interface_motion(traj, scenario)
    base: dict[str, Any] = dict(
        status=traj.status, message=traj.message, n_blocks=scenario.n_blocks,
        critical_angle=lam, duration=scenario.duration,
        peaks=_floats(metrics.peak_ratio(traj, lam)) if n else (None,) * scenario.n_blocks,
        simulated_time=simulated, n_samples=int(n), wall_time=wall,
        cpu_time=finite_or_none(traj.cpu_time) if traj.cpu_time else None,
        realtime_factor=simulated / wall if wall > 0 and simulated > 0 else None,
        time_to_rest=finite_or_none(metrics.time_to_rest(traj, lam)) if n else None,
        max_wobble=finite_or_none(np.max(np.abs(traj.wobble))) if n else None,
        max_roll=finite_or_none(np.max(np.abs(traj.roll))) if n else None,
        max_twist=finite_or_none(np.max(np.abs(traj.twist))) if n else None,
        slide=sliding(traj, scenario),
        interface_slip=slip, interface_gap=gap,
        engine_version=engine_version or traj.engine_version, settings_hash=settings_hash,
        scenario_hash=scenario_hash, horizon=finite_or_none(horizon),
    )
    # a horizon inside the run: the comparison stops there
    cut = (float(horizon) if horizon is not None and horizon < scenario.duration else None)
    if is_reference:
        return RunMetrics(**base, error_note="reference")
    if reference is None or not reference.t.size or not reference.status.completed:
        note = reference_note or (f"no analytic reference ({reference.status}: "
                                  f"{reference.message})" if reference is not None
                                  else "no analytic reference")
        return RunMetrics(**base, reference_status=None if reference is None
                          else reference.status, error_note=note)
    base["reference_status"] = reference.status
    base["reference_time_to_rest"] = finite_or_none(metrics.time_to_rest(reference, lam))
    if not n or not traj.status.completed:
        return RunMetrics(**base, error_note=f"{traj.status}: {traj.message}")
    t_end: float | None = None
    if reference.status is Status.OVERTURNED:
        past = np.nonzero(np.max(np.abs(reference.theta), axis=1) > lam)[0]
        t_end = float(reference.t[past[0]]) if past.size else None
    # the reference still rocks at t*: its fall (if any) lies in the unpredictable part
    rocking_at_cut = cut is not None and (t_end is None or t_end > cut)
    if cut is not None:
        t_end = cut if t_end is None else min(t_end, cut)
    try:
        max_error = metrics.max_error(traj, reference, lam, t_end)
    except ValueError as exc:  # sampled at other times
        return RunMetrics(**base, error_note=str(exc))
    ref_imp = rocking_impacts(reference, lam)
    if t_end is not None:
        ref_imp = ref_imp[ref_imp <= t_end]
    early = float(ref_imp[N_IMPACTS - 1]) if ref_imp.size >= N_IMPACTS else t_end
    if early is not None and t_end is not None:
        early = min(early, t_end)
    k = min(N_IMPACTS, ref_imp.size)
    imp_errors: tuple[float | None, ...] = ()
    missing: int | None = None
    if k:
        eng_imp = rocking_impacts(traj, lam)[:k]
        errs = np.full(k, np.nan)
        errs[:eng_imp.size] = np.abs(eng_imp - ref_imp[:eng_imp.size]) / ref_imp[:eng_imp.size]
        imp_errors = _floats(errs)
        missing = int(np.sum(~np.isfinite(errs)))
    peak_errors: tuple[float | None, ...] = ()
    note = ""
    if reference.status is Status.OK or rocking_at_cut:
        p = _peaks_until(traj, lam, cut)
        r = _peaks_until(reference, lam, cut)
        peak_errors = _floats((p - r) / np.maximum(r, PEAK_FLOOR))
    else:
        note = f"reference {reference.status}: {reference.message}"
    if cut is not None:
        note = (f"chaotic after t* = {cut:.2f} s: errors up to t*, beyond it see the "
                f"distributions" + (f"; {note}" if note else ""))
    defined = [abs(e) for e in peak_errors if e is not None]
    imp_defined = [e for e in imp_errors if e is not None]
    return RunMetrics(
        **base, max_error=finite_or_none(max_error),
        max_error_early=finite_or_none(metrics.max_error(traj, reference, lam, early)),
        peak_errors=peak_errors, peak_error=max(defined) if defined else None,
        impact_time_errors=imp_errors,
        impact_time_error=max(imp_defined) if imp_defined else None,
        impacts_missing=missing, error_note=note,
    )


def _peaks_until(traj: Trajectory, lam: float, t_end: float | None) -> np.ndarray:
    """max |θ_i|/λ per block over the samples up to ``t_end`` (all of them if None)."""
    if t_end is None:
        return metrics.peak_ratio(traj, lam)
    n = int(np.searchsorted(traj.t, t_end, side="right"))
    if n == 0:
        return np.full(traj.n_blocks, np.nan)
    return np.max(np.abs(traj.theta[:n]), axis=0) / lam


@dataclass(frozen=True)
class RunResult:
    """A run of a study: what was simulated, by which method, and its metrics.

    Attributes
    ----------
    scenario : Scenario
        What was simulated.
    method : Method
        Engine and settings.
    metrics : RunMetrics
        From :func:`evaluate_run`.
    trajectory : str
        The file holding its time history, if the study keeps one.
    reused : bool
        Taken from the results store rather than run now.
    """

    scenario: Scenario
    method: Method
    metrics: RunMetrics
    trajectory: str = ""
    reused: bool = False

    @property
    def status(self) -> Status:
        """How the run ended."""
        return self.metrics.status

    @property
    def key(self) -> tuple[str, str]:
        """(scenario name, method label)."""
        return (self.scenario.name, self.method.label)
