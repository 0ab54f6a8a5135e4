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
  ω_p column in a process pool or on a Dask cluster.
* Engine cells are :class:`rockbench.runner.Job` runs through
  :func:`rockbench.runner.run_jobs` (isolated processes or Dask), lasting the
  pulse plus ``settle / p``; a run is *overturned* if the engine reports it, or
  if at its end the block is beyond its critical angle and still moving
  outward. Impacts are counted as sign changes of θ (ignoring |θ| < 2 % λ).
"""

from __future__ import annotations

import csv
import json
import math
import multiprocessing
import re
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rockbench.analytic.overturning import (
    NO_UPLIFT,
    SAFE,
    Boundary,
    ColumnResult,
    outcome_label,
    pulse_excitation,
    scan_column,
)
from rockbench.errors import RockbenchError, ScenarioError
from rockbench.runner import Job, dask_client, default_jobs, run_jobs
from rockbench.scenarios import Block, Contact, RockingProperties, Scenario, Stack, get_scenario
from rockbench.trajectory import Status, Trajectory

__all__ = [
    "FAILED", "SpectrumMap", "BlockSpec", "parse_block", "parse_grid", "grid_axes",
    "analytic_map", "engine_map", "classify_trajectory", "write_boundary_csv",
    "write_cells_csv", "spectrum_figure",
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
        Neither a valid size nor a known scenario.
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
    return BlockSpec(sc.name, sc.blocks[0], sc.contact, sc.g)


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


# ---------------------------------------------------------------------- parallel map
def _column_task(args: tuple[Any, ...]) -> ColumnResult:
    rock, kind, w, a, g, eta, linear, tol = args
    return scan_column(rock, kind, w, a, g=g, eta=eta, linear=linear, tol=tol)


def _context() -> multiprocessing.context.BaseContext:
    methods = multiprocessing.get_all_start_methods()
    return multiprocessing.get_context("fork" if "fork" in methods else "spawn")


def _parallel_map(fn: Callable[[Any], Any], items: Sequence[Any], *, n_jobs: int | None,
                  executor: str, scheduler: Any,
                  on_done: Callable[[int, Any], None]) -> None:
    """Apply ``fn`` to each item in worker processes (or Dask), reporting as they finish."""
    if executor == "dask":
        with dask_client(n_jobs, scheduler) as client:
            from distributed import as_completed as dask_completed

            futures = {client.submit(fn, item, pure=False): i for i, item in enumerate(items)}
            for fut in dask_completed(futures):
                on_done(futures[fut], fut.result())
        return
    if executor != "process":
        raise RockbenchError(f"unknown executor {executor!r}; choose one of process, dask")
    workers = min(n_jobs or default_jobs(), len(items))
    if workers <= 1:
        for i, item in enumerate(items):
            on_done(i, fn(item))
        return
    with ProcessPoolExecutor(max_workers=workers, mp_context=_context()) as pool:
        futs = {pool.submit(fn, item): i for i, item in enumerate(items)}
        try:
            for fut in as_completed(futs):
                on_done(futs[fut], fut.result())
        except BaseException:
            for f in futs:
                f.cancel()
            raise


def analytic_map(spec: BlockSpec, kind: str, w_ratios: Sequence[float] | np.ndarray,
                 a_ratios: Sequence[float] | np.ndarray, *, linear: bool = False,
                 eta: float | None = None, tol: float | None = 1e-3,
                 n_jobs: int | None = None, executor: str = "process", scheduler: Any = None,
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
    n_jobs : int, optional
        Worker processes (default: the machine's cores; 1 runs here).
    executor : {"process", "dask"}
        Local process pool or a Dask cluster.
    scheduler : str or distributed.Client, optional
        Dask scheduler (None: a local cluster of ``n_jobs`` workers).
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
    cols: list[ColumnResult | None] = [None] * w.size

    def done(i: int, col: ColumnResult) -> None:
        cols[i] = col
        if on_column is not None:
            on_column(col)

    _parallel_map(_column_task, items, n_jobs=n_jobs, executor=executor, scheduler=scheduler,
                  on_done=done)
    ready = [c for c in cols if c is not None]
    codes = np.array([c.codes for c in ready], dtype=int).reshape(w.size, a.size)
    return SpectrumMap("analytic (linear)" if linear else "analytic", w, a, codes,
                       [b for c in ready for b in c.boundaries],
                       time.perf_counter() - start, sum(c.n_solves for c in ready))


# ---------------------------------------------------------------------- engines
def classify_trajectory(traj: Trajectory, lam: float) -> int:
    """Outcome code of an engine run of a pulse.

    Overturned if the engine says so, or if the last sample is beyond λ and
    still moving outward (it will fall); impacts are sign changes of θ among
    samples with |θ| ≥ 2 % λ before that. ``-2`` for a failed run.

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
    big = np.abs(th) >= UPLIFT_FRACTION * lam
    if not big.any() and traj.status == Status.OK:
        return NO_UPLIFT
    signs = np.sign(th[big])
    impacts = int(np.count_nonzero(signs[1:] != signs[:-1]))
    over = traj.status == Status.OVERTURNED
    if not over and th.size >= 2:
        last, prev = th[-1], th[-2]
        over = abs(last) > lam and (last - prev) * math.copysign(1.0, last) > 0
    return impacts + 1 if over else SAFE


def _engine_scenario(spec: BlockSpec, kind: str, w: float, a: float, settle: float,
                     rate: float) -> Scenario:
    rock = spec.rock
    exc = pulse_excitation(kind, a * spec.g * rock.lam, w * rock.p)
    return Scenario(name=f"spectrum-{kind}-w{w:.4g}-a{a:.4g}", stack=Stack((spec.block,)),
                    contact=spec.contact, excitation=exc,
                    duration=exc.end_time + settle / rock.p, output_rate=rate, g=spec.g)


def engine_map(engine: str, spec: BlockSpec, kind: str, w_ratios: Sequence[float] | np.ndarray,
               a_ratios: Sequence[float] | np.ndarray, *,
               settings: dict[str, Any] | None = None, refine: int = 3,
               settle: float = 4.0, output_rate: float = 250.0, n_jobs: int | None = None,
               timeout: float | None = 300.0, executor: str = "process",
               scheduler: Any = None,
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
    n_jobs, timeout, executor, scheduler
        As in :func:`rockbench.runner.run_jobs`.
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
    if executor == "process":
        # import the engine's library here once: the forked workers inherit it
        from rockbench.engines import get_engine

        get_engine(engine)

    def run(cells: list[tuple[float, float]]) -> list[int]:
        jobs = [Job(_engine_scenario(spec, kind, x, y, settle, output_rate), engine, settings)
                for x, y in cells]
        trajs = run_jobs(jobs, n_jobs=n_jobs, timeout=timeout, on_result=on_result,
                         executor=executor, scheduler=scheduler)
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


# ---------------------------------------------------------------------- output
def write_boundary_csv(path: str | Path, maps: Sequence[SpectrumMap], spec: BlockSpec,
                       kind: str) -> Path:
    """Boundary points of every map as CSV.

    Columns: method, pulse, omega_ratio (ω_p/p), omega_p (rad/s), accel_ratio
    (a_p/(g λ)), a_p (m/s²), kind (onset / island / mode), first (1 for the
    minimum overturning acceleration of its column), below/above (outcome
    codes and labels), bracket (final bisection width in a_p/(g λ)).
    """
    path = Path(path)
    rock = spec.rock
    with path.open("w", newline="") as fh:
        wr = csv.writer(fh)
        wr.writerow(["method", "pulse", "omega_ratio", "omega_p", "accel_ratio", "a_p", "kind",
                     "first", "below", "above", "below_label", "above_label", "bracket"])
        for mp in maps:
            first = mp.first_boundary()
            for b in sorted(mp.boundaries, key=lambda b: (b.w_ratio, b.a_ratio)):
                j = int(np.argmin(np.abs(mp.w_ratios - b.w_ratio)))
                is_first = b.kind == "onset" and b.a_ratio == first[j]
                wr.writerow([mp.method, kind, f"{b.w_ratio:.6g}", f"{b.w_ratio * rock.p:.6g}",
                             f"{b.a_ratio:.6g}", f"{b.a_ratio * spec.g * rock.lam:.6g}",
                             b.kind, int(is_first), b.below, b.above, outcome_label(b.below),
                             outcome_label(b.above), f"{b.width:.3g}"])
    return path


def write_cells_csv(path: str | Path, maps: Sequence[SpectrumMap]) -> Path:
    """Every grid cell of every map: method, omega_ratio, accel_ratio, code, label."""
    path = Path(path)
    with path.open("w", newline="") as fh:
        wr = csv.writer(fh)
        wr.writerow(["method", "omega_ratio", "accel_ratio", "code", "label"])
        for mp in maps:
            for j, w in enumerate(mp.w_ratios):
                for i, a in enumerate(mp.a_ratios):
                    c = int(mp.codes[j, i])
                    wr.writerow([mp.method, f"{w:.6g}", f"{a:.6g}", c,
                                 "failed" if c == FAILED else outcome_label(c)])
    return path


def write_summary_json(path: str | Path, maps: Sequence[SpectrumMap], spec: BlockSpec,
                       kind: str, extra: dict[str, Any] | None = None) -> Path:
    """Block constants, grid, timings and notes of the maps as JSON."""
    rock = spec.rock
    data = {
        "block": spec.name, "width": spec.block.width, "height": spec.block.height,
        "depth": spec.block.depth, "chamfer": spec.block.chamfer, "g": spec.g,
        "lambda": rock.lam, "p": rock.p, "eta_housner": rock.eta,
        "eta": spec.contact.eta, "pulse": kind,
        "maps": [{"method": m.method, "grid": list(m.codes.shape), "wall_time": m.wall_time,
                  "runs": m.n_runs, "notes": m.notes,
                  "first_boundary": [None if not np.isfinite(x) else float(x)
                                     for x in m.first_boundary()]} for m in maps],
    } | dict(extra or {})
    path = Path(path)
    path.write_text(json.dumps(data, indent=2))
    return path


# ---------------------------------------------------------------------- figure
#: Display classes: (codes, label, colour).
_CLASSES = [
    ((FAILED,), "run failed", "#4d4d4d"),
    ((NO_UPLIFT,), "safe: no uplift", "#ffffff"),
    ((SAFE,), "safe: rocks", "#cfe8cf"),
    ((1,), "overturns without impact (mode 1)", "#b2182b"),
    ((2,), "overturns after 1 impact (mode 2)", "#ef8a62"),
    ((3,), "overturns after 2 impacts", "#fddb7a"),
    (None, "overturns after ≥ 3 impacts", "#9e7cc1"),
]
_ENGINE_COLOURS = ["#1f77b4", "#2ca02c", "#9467bd", "#e377c2", "#17becf", "#8c564b"]


_ENGINE_MARKERS = ["o", "s", "^", "D", "v", "P"]
_ENGINE_DASHES = ["--", "-.", ":", (0, (5, 1)), (0, (3, 1, 1, 1, 1, 1)), "--"]


def _engine_style(k: int) -> dict[str, Any]:
    return {"c": _ENGINE_COLOURS[k % len(_ENGINE_COLOURS)], "lw": 2.0,
            "ls": _ENGINE_DASHES[k % len(_ENGINE_DASHES)],
            "marker": _ENGINE_MARKERS[k % len(_ENGINE_MARKERS)], "ms": 6,
            "mfc": "white", "mew": 1.5}


def _class_index(codes: np.ndarray) -> np.ndarray:
    idx = np.full(codes.shape, len(_CLASSES) - 1, dtype=int)
    for k, (cs, _, _) in enumerate(_CLASSES[:-1]):
        for c in cs:  # type: ignore[union-attr]
            idx[codes == c] = k
    return idx


def _edges(v: np.ndarray) -> np.ndarray:
    if v.size == 1:
        return np.array([v[0] - 0.5, v[0] + 0.5])
    mid = 0.5 * (v[1:] + v[:-1])
    return np.concatenate([[v[0] - (mid[0] - v[0])], mid, [v[-1] + (v[-1] - mid[-1])]])


def _draw_map(ax: Any, mp: SpectrumMap) -> None:
    from matplotlib.colors import BoundaryNorm, ListedColormap

    cmap = ListedColormap([c for _, _, c in _CLASSES])
    norm = BoundaryNorm(np.arange(len(_CLASSES) + 1) - 0.5, cmap.N)
    ax.pcolormesh(_edges(mp.w_ratios), _edges(mp.a_ratios), _class_index(mp.codes).T,
                  cmap=cmap, norm=norm, shading="flat", rasterized=True)


def _draw_first(ax: Any, mp: SpectrumMap, **style: Any) -> Any:
    first = mp.first_boundary()
    ok = np.isfinite(first)
    (line,) = ax.plot(mp.w_ratios[ok], first[ok], **style)
    return line


def spectrum_figure(path: str | Path, ref: SpectrumMap, engines: Sequence[SpectrumMap],
                    spec: BlockSpec, kind: str) -> Path:
    """Draw the analytic map with every engine's first boundary, plus one panel per engine.

    Parameters
    ----------
    path : str or Path
        PNG file to write.
    ref : SpectrumMap
        The analytic map (drawn as coloured cells).
    engines : sequence of SpectrumMap
        Engine maps: their first overturning boundaries are overlaid on the
        analytic map; each also gets a small panel of its own cells.
    spec : BlockSpec
        The block (for the title).
    kind : {"sine", "cosine"}
        Pulse shape (for the title).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    n_eng = len(engines)
    ncols = min(n_eng, 3)
    nrows = 1 + (math.ceil(n_eng / 3) if n_eng else 0)
    fig = Figure(figsize=(11, 6.5 + 3.4 * (nrows - 1)), layout="constrained")
    FigureCanvasAgg(fig)
    heights = [2.0] + [1.0] * (nrows - 1)
    gs = fig.add_gridspec(nrows, max(ncols, 1), height_ratios=heights)
    ax = fig.add_subplot(gs[0, :])
    _draw_map(ax, ref)
    rock = spec.rock
    ax.set_xlabel("pulse frequency ω_p / p")
    ax.set_ylabel("pulse acceleration a_p / (g λ)")
    ax.set_xlim(_edges(ref.w_ratios)[0], _edges(ref.w_ratios)[-1])
    ax.set_ylim(_edges(ref.a_ratios)[0], _edges(ref.a_ratios)[-1])
    pulse = "a_p sin(ω_p t)" if kind == "sine" else "a_p cos(ω_p t)"
    ax.set_title(f"Overturning map, one-{kind} pulse ü_g = {pulse} — block {spec.name} "
                 f"({spec.block.width:g} × {spec.block.height:g} m, λ = {rock.lam:.4f} rad, "
                 f"p = {rock.p:.3f} rad/s); cells: {ref.method}", fontsize=10)
    # analytic boundaries: refined points of every boundary, the first one as a line
    handles: list[Any] = []
    pts = [b for b in ref.boundaries if b.kind != "mode"]
    if pts:
        ax.scatter([b.w_ratio for b in pts], [b.a_ratio for b in pts], s=6, c="k",
                   zorder=3, linewidths=0)
        handles.append(Line2D([], [], ls="", marker="o", ms=3, c="k",
                              label=f"{ref.method}: safe/overturn boundary points (bisection)"))
    handles.append(_draw_first(ax, ref, c="k", lw=1.8, zorder=4,
                               label=f"{ref.method}: minimum overturning a_p"))
    for k, em in enumerate(engines):
        handles.append(_draw_first(ax, em, zorder=5 + k, label=f"{em.method}: minimum "
                                   f"overturning a_p ({em.codes.shape[0]} columns, bisection)",
                                   **_engine_style(k)))
    uplift = 1.0 if "linear" in ref.method else math.tan(rock.lam) / rock.lam
    ax.axhline(uplift, c="0.4", lw=0.8, ls=":")
    handles.append(Line2D([], [], c="0.4", lw=0.8, ls=":", label="uplift threshold"))
    present = set(np.unique(_class_index(ref.codes)).tolist())
    for em in engines:
        present |= set(np.unique(_class_index(em.codes)).tolist())
    patches = [Patch(facecolor=c, edgecolor="0.5", label=lab)
               for k, (_, lab, c) in enumerate(_CLASSES) if k in present]
    fig.legend(handles=patches + handles, loc="outside lower center", fontsize=8, ncol=3,
               frameon=False)
    for k, em in enumerate(engines):
        sub = fig.add_subplot(gs[1 + k // 3, k % 3])
        _draw_map(sub, em)
        _draw_first(sub, ref, c="k", lw=1.2)
        _draw_first(sub, em, **(_engine_style(k) | {"ms": 4}))
        sub.set_xlim(_edges(ref.w_ratios)[0], _edges(ref.w_ratios)[-1])
        sub.set_ylim(_edges(ref.a_ratios)[0], _edges(ref.a_ratios)[-1])
        sub.set_title(f"{em.method}: {em.codes.shape[0]} × {em.codes.shape[1]} cells "
                      f"(black: {ref.method})", fontsize=9)
        sub.set_xlabel("ω_p / p", fontsize=8)
        sub.set_ylabel("a_p / (g λ)", fontsize=8)
        sub.tick_params(labelsize=7)
    path = Path(path)
    fig.savefig(path, dpi=120)
    return path
