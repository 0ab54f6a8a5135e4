"""Overturning spectra: which one-sine / one-cosine pulses overturn a block, per method.

A map covers a grid of pulse frequencies ω_p/p × accelerations a_p/(g λ) (λ and
p of the block as modelled, so every method shares the axes). Each cell gets an
outcome code (:mod:`rockbench.analytic.overturning`): ``-1`` no uplift, ``0``
rocks and survives, ``1`` overturns without impact (mode 1), ``n + 1`` after
``n`` impacts; engines add ``-2`` for a failed run (crash, instability,
timeout). Changes along a_p are refined by bisection: all of them for the
analytic model, the first overturning boundary (the minimum overturning
acceleration) for engines, whose cells are full simulations.

* Analytic cells are exact (:func:`rockbench.analytic.overturning.pulse_outcome`
  decides the free motion after the pulse from energy) and are computed per
  ω_p column through the one dispatcher (:func:`rockbench.runner.map_tasks`:
  local processes or a Dask cluster).
* Engine cells are :class:`rockbench.runner.Job` runs through
  :func:`rockbench.runner.run_jobs`, lasting the pulse plus ``settle / p``; a
  run is *overturned* if the engine reports it, or if at its end the block is
  beyond its critical angle and still moving outward. Its impacts are
  :func:`rockbench.evaluation.rocking_impacts` (the one definition); a run whose
  |θ| stays below 2 % λ did not uplift.

Figures and CSV/JSON files of the maps: :mod:`rockbench.report.spectrum_figures`.
"""

from __future__ import annotations

import math
import re
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rockbench.analytic.overturning import (
    NO_UPLIFT,
    SAFE,
    Boundary,
    ColumnResult,
    pulse_excitation,
    scan_column,
)
from rockbench.errors import RockbenchError, ScenarioError
from rockbench.evaluation import rocking_impacts
from rockbench.geometry import RockingProperties
from rockbench.runner import ExecutionOptions, Job, TaskFault, map_tasks, run_jobs
from rockbench.scenarios import Block, Contact, Scenario, get_scenario, single
from rockbench.trajectory import Status, Trajectory

__all__ = [
    "FAILED", "SpectrumMap", "BlockSpec", "parse_block", "parse_grid", "grid_axes",
    "analytic_map", "engine_map", "classify_trajectory", "UPLIFT_FRACTION",
]

#: Outcome code of an engine run that failed (crashed, unstable, timeout, unsupported).
FAILED = -2
#: Default density of a block given as WIDTHxHEIGHT (granite, kg/m³).
DEFAULT_DENSITY = 2670.0
#: |θ| below this fraction of λ counts as resting (engine contact noise).
UPLIFT_FRACTION = 0.02


@dataclass(frozen=True)
class BlockSpec:
    """The block of a spectrum: geometry, contact and gravity.

    Attributes
    ----------
    name : str
        Where it came from (catalog name, file or ``WIDTHxHEIGHT``).
    block : Block
        The block (its first block when read from a scenario).
    contact : Contact
        Contact of the engines' runs; ``contact.eta`` (if set) is the analytic η.
    g : float
        Gravity (m/s²).
    """

    name: str
    block: Block
    contact: Contact
    g: float

    @property
    def rock(self) -> RockingProperties:
        """λ, p, η of the block on a rigid base."""
        return self.block.rocking(self.g)


_SIZE = re.compile(r"^\s*([0-9.eE+-]+)\s*[xX×]\s*([0-9.eE+-]+)\s*$")


def parse_block(spec: str) -> BlockSpec:
    """A block from a catalog scenario name, a scenario TOML file or ``WIDTHxHEIGHT`` (m).

    A scenario contributes its first block, its contact and its gravity. A size
    gives a block of that width (rocking direction) and height, depth equal to
    the width, density 2670 kg/m³, friction 1 and no restitution, g = 9.81.

    Raises
    ------
    ScenarioError, UnknownScenario
        Neither a valid size nor a known scenario, or a scenario whose first body
        is not a rectangular block.
    """
    m = _SIZE.match(spec)
    if m:
        try:
            w, h = float(m.group(1)), float(m.group(2))
        except ValueError:
            raise ScenarioError(f"--block {spec!r}: expected WIDTHxHEIGHT in m") from None
        block = Block(width=w, depth=w, height=h, density=DEFAULT_DENSITY)
        return BlockSpec(f"{w:g}x{h:g}", block, Contact(friction=1.0), 9.81)
    sc = get_scenario(spec)
    first = sc.blocks[0]
    if not isinstance(first, Block):
        raise ScenarioError(f"--block {spec!r}: the scenario's first body is a "
                            f"{type(first).__name__}, not a rectangular block")
    return BlockSpec(sc.name, first, sc.contact, sc.g)


def parse_grid(spec: str) -> tuple[int, int]:
    """``NxM`` → (N frequencies, M accelerations), each ≥ 2.

    Raises
    ------
    RockbenchError
        Malformed value.
    """
    m = re.match(r"^\s*(\d+)\s*[xX×]\s*(\d+)\s*$", spec)
    if not m or int(m.group(1)) < 2 or int(m.group(2)) < 2:
        raise RockbenchError(f"grid must be NxM with N, M >= 2 (e.g. 40x60), got {spec!r}")
    return int(m.group(1)), int(m.group(2))


def grid_axes(n_w: int, n_a: int, w_range: tuple[float, float],
              a_range: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Grid values: ω_p/p evenly spaced in ``w_range``, a_p/(g λ) in ``a_range``.

    Raises
    ------
    RockbenchError
        Empty or invalid ranges (ω_p/p must be > 0, a_p/(g λ) ≥ 0).
    """
    (w0, w1), (a0, a1) = w_range, a_range
    if not (0 < w0 < w1 and math.isfinite(w1)):
        raise RockbenchError(f"frequency range must satisfy 0 < low < high, got {w0}:{w1}")
    if not (0 <= a0 < a1 and math.isfinite(a1)):
        raise RockbenchError(f"acceleration range must satisfy 0 <= low < high, got {a0}:{a1}")
    return np.linspace(w0, w1, n_w), np.linspace(a0, a1, n_a)


@dataclass
class SpectrumMap:
    """An overturning map of one method.

    Attributes
    ----------
    method : str
        ``"analytic"``, ``"analytic (linear)"`` or an engine name.
    w_ratios : ndarray, shape (n_w,)
        ω_p/p of the columns.
    a_ratios : ndarray, shape (n_a,)
        a_p/(g λ) of the rows.
    codes : ndarray of int, shape (n_w, n_a)
        Outcome code of each cell.
    boundaries : list of Boundary
        Refined boundaries.
    wall_time : float
        Wall-clock time of the whole map (s).
    n_runs : int
        Number of solutions or simulations computed (grid plus bisection).
    notes : list of str
        Failure messages (engines).
    """

    method: str
    w_ratios: np.ndarray
    a_ratios: np.ndarray
    codes: np.ndarray
    boundaries: list[Boundary] = field(default_factory=list)
    wall_time: float = 0.0
    n_runs: int = 0
    notes: list[str] = field(default_factory=list)

    def first_boundary(self) -> np.ndarray:
        """Minimum overturning a_p/(g λ) per column (NaN where nothing overturns)."""
        out = np.full(self.w_ratios.size, np.nan)
        for j, w in enumerate(self.w_ratios):
            onsets = [b.a_ratio for b in self.boundaries
                      if b.kind == "onset" and b.w_ratio == w]
            if onsets:
                out[j] = min(onsets)
        return out


# ---------------------------------------------------------------------- analytic map
def _column_task(args: tuple[Any, ...]) -> ColumnResult:
    rock, kind, w, a, g, eta, linear, tol = args
    return scan_column(rock, kind, w, a, g=g, eta=eta, linear=linear, tol=tol)


def analytic_map(spec: BlockSpec, kind: str, w_ratios: Sequence[float] | np.ndarray,
                 a_ratios: Sequence[float] | np.ndarray, *, linear: bool = False,
                 eta: float | None = None, tol: float | None = 1e-3,
                 execution: ExecutionOptions | None = None,
                 on_column: Callable[[ColumnResult], None] | None = None) -> SpectrumMap:
    """The analytic overturning map, one ω_p/p column per task.

    Parameters
    ----------
    spec : BlockSpec
        The block.
    kind : {"sine", "cosine"}
        Pulse shape.
    w_ratios, a_ratios : array_like
        Grid of ω_p/p and of a_p/(g λ) (increasing).
    linear : bool
        Linearised Housner model.
    eta : float, optional
        Velocity ratio at impact; default ``spec.contact.eta`` or Housner's formula.
    tol : float or None
        Bisection tolerance in a_p/(g λ); None: no refinement.
    execution : ExecutionOptions, optional
        Workers (one column per task), time limit per column, executor.
    on_column : callable, optional
        Called with each finished column (progress).

    Returns
    -------
    SpectrumMap
    """
    start = time.perf_counter()
    w = np.asarray(w_ratios, dtype=float)
    a = np.asarray(a_ratios, dtype=float)
    eta = spec.contact.eta if eta is None else eta
    items = [(spec.rock, kind, float(x), a, spec.g, eta, linear, tol) for x in w]

    def done(i: int, col: ColumnResult) -> None:
        if on_column is not None:
            on_column(col)

    def fault(i: int, f: TaskFault) -> ColumnResult:
        raise RockbenchError(f"analytic spectrum column ω_p/p = {w[i]:.4g}: {f.message}")

    cols = map_tasks(_column_task, items, execution, on_done=done, on_fault=fault)
    ready = [c for c in cols if c is not None]
    codes = np.array([c.codes for c in ready], dtype=int).reshape(w.size, a.size)
    return SpectrumMap("analytic (linear)" if linear else "analytic", w, a, codes,
                       [b for c in ready for b in c.boundaries],
                       time.perf_counter() - start, sum(c.n_solves for c in ready))


# ---------------------------------------------------------------------- engines
def classify_trajectory(traj: Trajectory, lam: float) -> int:
    """Outcome code of an engine run of a pulse.

    Overturned if the engine says so, or if the last sample is beyond λ and
    still moving outward (it will fall); its impacts are
    :func:`rockbench.evaluation.rocking_impacts`. A run whose |θ| stays below
    :data:`UPLIFT_FRACTION` λ did not uplift. ``-2`` for a failed run.

    Parameters
    ----------
    traj : Trajectory
        One-block trajectory.
    lam : float
        Critical angle of the block (rad).
    """
    if traj.status not in (Status.OK, Status.OVERTURNED):
        return FAILED
    th = traj.theta[:, 0] if traj.theta.size else np.zeros(0)
    if not np.any(np.abs(th) >= UPLIFT_FRACTION * lam) and traj.status == Status.OK:
        return NO_UPLIFT
    impacts = int(rocking_impacts(traj, lam).size)
    over = traj.status == Status.OVERTURNED
    if not over and th.size >= 2:
        last, prev = th[-1], th[-2]
        over = abs(last) > lam and (last - prev) * math.copysign(1.0, last) > 0
    return impacts + 1 if over else SAFE


def _engine_scenario(spec: BlockSpec, kind: str, w: float, a: float, settle: float,
                     rate: float) -> Scenario:
    rock = spec.rock
    exc = pulse_excitation(kind, a * spec.g * rock.lam, w * rock.p)
    return Scenario(name=f"spectrum-{kind}-w{w:.4g}-a{a:.4g}", geometry=single(spec.block),
                    contact=spec.contact, excitation=exc,
                    duration=exc.end_time + settle / rock.p, output_rate=rate, g=spec.g)


def engine_map(engine: str, spec: BlockSpec, kind: str, w_ratios: Sequence[float] | np.ndarray,
               a_ratios: Sequence[float] | np.ndarray, *,
               settings: dict[str, Any] | None = None, refine: int = 3,
               settle: float = 4.0, output_rate: float = 250.0,
               execution: ExecutionOptions | None = None,
               on_result: Callable[[Job, Trajectory], None] | None = None) -> SpectrumMap:
    """An engine's overturning map; every cell is a full simulation.

    Parameters
    ----------
    engine : str
        Engine name.
    spec : BlockSpec
        The block.
    kind : {"sine", "cosine"}
        Pulse shape.
    w_ratios, a_ratios : array_like
        Grid (keep it coarse: e.g. 12 × 16).
    settings : dict, optional
        Engine settings (``{"preset": ...}`` and knobs).
    refine : int
        Bisection steps on the first overturning boundary of each column (each
        step is one simulation per column, all columns in parallel). A bracket
        reaching below the static uplift threshold a_p = g tan λ starts there.
    settle : float
        Simulated time after the pulse in units of 1/p.
    output_rate : float
        Samples per second of the runs (only used to classify them).
    execution : ExecutionOptions, optional
        Workers, time limit per run, executor.
    on_result : callable, optional
        Called with each finished job (progress).

    Returns
    -------
    SpectrumMap
    """
    start = time.perf_counter()
    w = np.asarray(w_ratios, dtype=float)
    a = np.asarray(a_ratios, dtype=float)
    lam = spec.rock.lam
    settings = dict(settings or {})
    notes: list[str] = []
    if execution is None or execution.executor == "process":
        # import the engine's library here once: the forked workers inherit it
        from rockbench.engines import get_engine

        get_engine(engine)

    def run(cells: list[tuple[float, float]]) -> list[int]:
        jobs = [Job(_engine_scenario(spec, kind, x, y, settle, output_rate), engine, settings)
                for x, y in cells]
        trajs = run_jobs(jobs, execution, on_result=on_result)
        out = []
        for (x, y), tr in zip(cells, trajs, strict=True):
            c = classify_trajectory(tr, lam)
            if c == FAILED:
                notes.append(f"w={x:.4g} a={y:.4g}: {tr.status}: {tr.message}")
            out.append(c)
        return out

    # a = 0 needs no simulation
    cells = [(float(x), float(y)) for x in w for y in a if y > 0]
    got = iter(run(cells))
    codes = np.array([[next(got) if y > 0 else NO_UPLIFT for y in a] for _ in w], dtype=int)
    n_runs = len(cells)
    # brackets of the first onset per column; nothing overturns below the static uplift
    # threshold g tan λ, so a bracket starting below it starts at it instead
    thr = math.tan(lam) / lam
    brackets: dict[int, list[Any]] = {}
    for j in range(w.size):
        for i in range(1, a.size):
            if codes[j, i] > SAFE and codes[j, i - 1] in (NO_UPLIFT, SAFE):
                lo = float(a[i - 1])
                c_lo = int(codes[j, i - 1])
                if lo < thr < a[i]:
                    lo, c_lo = thr, NO_UPLIFT
                brackets[j] = [lo, float(a[i]), c_lo, int(codes[j, i])]
                break
            if codes[j, i] > SAFE or codes[j, i] == FAILED:
                break
    for _ in range(max(0, refine)):
        if not brackets:
            break
        order = sorted(brackets)
        mids = [0.5 * (brackets[j][0] + brackets[j][1]) for j in order]
        res = run([(float(w[j]), m) for j, m in zip(order, mids, strict=True)])
        n_runs += len(order)
        for j, m, c in zip(order, mids, res, strict=True):
            if c == FAILED:
                continue
            if c > SAFE:
                brackets[j][1], brackets[j][3] = m, c
            else:
                brackets[j][0], brackets[j][2] = m, c
    bounds = [Boundary(float(w[j]), 0.5 * (lo + hi), c_lo, c_hi, hi - lo)
              for j, (lo, hi, c_lo, c_hi) in sorted(brackets.items())]
    return SpectrumMap(engine, w, a, codes, bounds, time.perf_counter() - start, n_runs, notes)
