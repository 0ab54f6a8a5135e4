"""Settings sweeps: stability maps, accuracy versus cost, and automatic tuning.

:func:`run_sweep` runs the cartesian grid of engine knobs given as
``engine.knob=v1,v2,...`` on one scenario, isolated like every run, and
measures each point against the analytic reference. :func:`stability_map`
draws, per engine, a heat map over two knobs (colour = error, markers for
unstable / crashed / timeout / drifting runs and for runs that end unlike the
reference); :func:`pareto_plot` draws error against wall time with each
engine's Pareto front. :func:`cheapest` picks the cheapest point that meets a
target error, and :func:`tune` searches knob ladders for it automatically.
"""

from __future__ import annotations

import csv
import itertools
import math
import typing
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rockbench.engines import engine_class
from rockbench.errors import RockbenchError
from rockbench.presets import typed_settings
from rockbench.report.matrix import references, run_metrics
from rockbench.runner import Job, run_jobs
from rockbench.scenarios import Scenario
from rockbench.store import Store
from rockbench.trajectory import Status, Trajectory

__all__ = ["SweepError", "SweepPoint", "SweepResult", "parse_grid", "run_sweep", "cheapest",
           "pareto_front", "stability_map", "pareto_plot", "write_table", "format_table",
           "tune", "TuneResult", "tunable_knobs", "ERROR_METRICS", "DRIFT_WIDTH", "DRIFT_WOBBLE"]

#: Metrics a sweep may rank by (lower is better).
ERROR_METRICS = ("max_error", "max_error_early", "impact_time_error", "peak_error")
#: Sliding of the bottom block beyond this fraction of its width is non-physical drift.
DRIFT_WIDTH = 0.05
#: Out-of-plane wobble beyond this (rad) is non-physical drift in a planar problem.
DRIFT_WOBBLE = 0.05


class SweepError(RockbenchError, ValueError):
    """A bad ``--grid`` option or sweep request."""


def parse_grid(options: Sequence[str], engines: Sequence[str]) -> dict[str, dict[str, list[Any]]]:
    """Parse ``engine.knob=v1,v2,...`` options into typed value lists per engine.

    Values are converted to the knob's type (and checked) now. Engines without
    a grid option run a single point (their settings as given).

    Raises
    ------
    SweepError
        Malformed option, an engine that is not selected, or a repeated knob.
    SettingsError
        Unknown knob or a value of the wrong type.
    """
    from rockbench.engines.registry import ALIASES

    grid: dict[str, dict[str, list[Any]]] = {e: {} for e in engines}
    for opt in options:
        key, sep, values = opt.partition("=")
        engine, dot, knob = key.strip().partition(".")
        engine = ALIASES.get(engine.strip().lower(), engine.strip().lower())
        knob = knob.strip()
        items = [v.strip() for v in values.split(",") if v.strip()]
        if not (sep and dot and engine and knob and items):
            raise SweepError(f"--grid expects engine.knob=v1,v2,..., got {opt!r}")
        if engine not in grid:
            raise SweepError(f"--grid names engine {engine!r}, which is not selected "
                             f"(--engine {','.join(engines)})")
        if knob in grid[engine]:
            raise SweepError(f"--grid gives {engine}.{knob} twice")
        typed = [typed_settings(engine, {knob: v})[knob] for v in items]
        grid[engine][knob] = list(dict.fromkeys(typed))  # drop repeats, keep order
    return grid


@dataclass
class SweepPoint:
    """One point of a sweep.

    Attributes
    ----------
    engine : str
        Engine name.
    knobs : dict
        The grid knobs' values at this point.
    settings : dict
        The full requested settings (base settings plus ``knobs``).
    status : Status
        How the run ended.
    message : str
        Reason or note.
    metrics : dict
        From :func:`rockbench.report.matrix.run_metrics`.
    """

    engine: str
    knobs: dict[str, Any]
    settings: dict[str, Any]
    status: Status
    message: str
    metrics: dict[str, Any]

    @property
    def cost(self) -> float:
        """Wall time of the run in s."""
        return float(self.metrics.get("wall_time") or math.nan)

    def error(self, metric: str = "max_error") -> float:
        """The error metric (NaN if it could not be computed)."""
        v = self.metrics.get(metric)
        return math.nan if v is None else float(v)

    @property
    def drift(self) -> bool:
        """Non-physical sliding or out-of-plane wobble."""
        return bool(self.metrics.get("drift"))

    @property
    def as_reference(self) -> bool:
        """The run ends as the reference does (ok/overturned; any completion without one)."""
        ref = self.metrics.get("reference_status")
        return self.status.completed and (ref is None or self.status.value == ref)

    def meets(self, target: float, metric: str = "max_error") -> bool:
        """Ends as the reference, without drift, with the metric ≤ ``target``."""
        e = self.error(metric)
        return self.as_reference and not self.drift and math.isfinite(e) and e <= target

    def kind(self) -> str:
        """Marker class: ok, mismatch (ends unlike the reference), drift, or the status."""
        if not self.status.completed:
            return self.status.value
        if not self.as_reference:
            return "mismatch"
        return "drift" if self.drift else "ok"


@dataclass
class SweepResult:
    """Points of a sweep on one scenario."""

    scenario: Scenario
    grid: dict[str, dict[str, list[Any]]]
    points: list[SweepPoint] = field(default_factory=list)
    metric: str = "max_error"
    reference_note: str = ""

    def engine_points(self, engine: str) -> list[SweepPoint]:
        """The points of one engine, in grid order."""
        return [p for p in self.points if p.engine == engine]

    @property
    def engines(self) -> list[str]:
        """Engines in the sweep, in order."""
        return list(self.grid)


def _drift(m: Mapping[str, Any], scenario: Scenario) -> bool:
    slide, wobble = m.get("slide"), m.get("max_wobble")
    return bool((slide is not None and slide > DRIFT_WIDTH * scenario.blocks[0].width)
                or (wobble is not None and wobble > DRIFT_WOBBLE))


def _points(grid: Mapping[str, Sequence[Any]]) -> list[dict[str, Any]]:
    knobs = list(grid)
    return [dict(zip(knobs, combo, strict=True))
            for combo in itertools.product(*(grid[k] for k in knobs))]


def run_sweep(
    scenario: Scenario,
    grid: Mapping[str, Mapping[str, Sequence[Any]]],
    *,
    base: Mapping[str, Mapping[str, Any]] | None = None,
    metric: str = "max_error",
    store: Store | None = None,
    resume: bool = False,
    kind: str = "sweep",
    n_jobs: int | None = 1,
    timeout: float | None = None,
    executor: str = "process",
    scheduler: Any = None,
    on_point: Callable[[SweepPoint], None] | None = None,
    reference: Trajectory | None = None,
) -> SweepResult:
    """Run every grid point of every engine on ``scenario``.

    Parameters
    ----------
    scenario : Scenario
        The problem.
    grid : mapping
        Engine → knob → values (from :func:`parse_grid`); an engine with an
        empty mapping runs once.
    base : mapping, optional
        Engine → settings applied under the grid knobs (preset, ``--set``).
    metric : str
        Error metric of :data:`ERROR_METRICS` used for ranking.
    store : Store, optional
        Every run is appended as it finishes (``kind``), the reference cached.
    resume : bool
        Reuse stored runs of identical points.
    kind : str
        Label of the runs in the store.
    n_jobs, timeout, executor, scheduler
        Passed to :func:`rockbench.runner.run_jobs`.
    on_point : callable, optional
        Called with each finished point.
    reference : Trajectory, optional
        The analytic reference if already known.
    """
    if metric not in ERROR_METRICS:
        raise SweepError(f"unknown metric {metric!r}; choose one of {', '.join(ERROR_METRICS)}")
    base = base or {}
    note = ""
    if reference is None:
        refs, notes = references([scenario], store, n_jobs=1, timeout=timeout,
                                 executor=executor, scheduler=scheduler)
        reference, note = refs[scenario.name], notes.get(scenario.name, "")
    result = SweepResult(scenario, {e: dict(g) for e, g in grid.items()}, metric=metric,
                         reference_note=note)
    versions = {e: engine_class(e).version() for e in grid}
    jobs, knobs_of = [], {}
    for engine, g in grid.items():
        for knobs in _points(g):
            settings = {**base.get(engine, {}), **knobs}
            old = (store.find(scenario, engine, settings, engine_version=versions[engine])
                   if resume and store is not None else None)
            if old is not None:
                point = SweepPoint(engine, knobs, settings, old.status, old.message,
                                   old.metrics)
                result.points.append(point)
                if on_point is not None:
                    on_point(point)
                continue
            job = Job(scenario, engine, settings)
            knobs_of[id(job)] = knobs
            jobs.append(job)

    def finished(job: Job, traj: Trajectory) -> None:
        m = run_metrics(traj, reference, scenario)
        m["drift"] = _drift(m, scenario)
        if store is not None:
            store.record(scenario, job.engine, job.settings, traj, m, kind=kind,
                         engine_version=versions[job.engine])
        point = SweepPoint(job.engine, knobs_of[id(job)], dict(job.settings), traj.status,
                           traj.message, m)
        result.points.append(point)
        if on_point is not None:
            on_point(point)

    run_jobs(jobs, n_jobs=n_jobs, timeout=timeout, on_result=finished, executor=executor,
             scheduler=scheduler)
    order = {(e, tuple(sorted(k.items()))): i for i, (e, k) in enumerate(
        (e, k) for e, g in grid.items() for k in _points(g))}
    result.points.sort(key=lambda p: order.get((p.engine, tuple(sorted(p.knobs.items()))), 0))
    return result


def cheapest(points: Sequence[SweepPoint], target: float,
             metric: str = "max_error") -> SweepPoint | None:
    """The lowest-cost point that meets ``target`` (None if none does)."""
    ok = [p for p in points if p.meets(target, metric) and math.isfinite(p.cost)]
    return min(ok, key=lambda p: (p.cost, p.error(metric))) if ok else None


def pareto_front(points: Sequence[SweepPoint], metric: str = "max_error") -> list[SweepPoint]:
    """Points not beaten in both cost and error by another, cheapest first.

    Only runs that end as the reference does, without drift, take part.
    """
    valid = sorted((p for p in points if p.as_reference and not p.drift
                    and math.isfinite(p.error(metric)) and math.isfinite(p.cost)),
                   key=lambda p: (p.cost, p.error(metric)))
    front: list[SweepPoint] = []
    best = math.inf
    for p in valid:
        if p.error(metric) < best:
            front.append(p)
            best = p.error(metric)
    return front


# ---------------------------------------------------------------------- tables
def _value(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def write_table(result: SweepResult, path: str | Path) -> Path:
    """Write every point as CSV (engine, knobs, status, errors, cost, drift, message)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    knobs = list(dict.fromkeys(k for g in result.grid.values() for k in g))
    cols = ["engine", *knobs, "status", *ERROR_METRICS, "wall_time", "realtime_factor",
            "slide", "drift", "message"]
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(cols)
        for p in result.points:
            w.writerow([p.engine, *[p.knobs.get(k, "") for k in knobs], p.status.value,
                        *["" if p.metrics.get(m) is None else p.metrics[m] for m in ERROR_METRICS],
                        p.metrics.get("wall_time"), p.metrics.get("realtime_factor") or "",
                        "" if p.metrics.get("slide") is None else p.metrics["slide"],
                        int(p.drift), p.message])
    return path


def format_table(result: SweepResult, target: float | None = None) -> str:
    """Plain-text table of the points per engine, cheapest first."""
    lines = []
    m = result.metric
    for engine in result.engines:
        pts = sorted(result.engine_points(engine), key=lambda p: p.cost)
        knobs = list(result.grid[engine])
        head = [*knobs, "status", m, "wall (s)", "note"]
        rows = []
        for p in pts:
            note = "drift" if p.drift else ("unlike reference" if p.kind() == "mismatch"
                                            else "")
            if target is not None and p.meets(target, m):
                note = "meets target"
            if not p.status.completed:
                note = p.message[:60]
            err = p.error(m)
            rows.append([*[_value(p.knobs[k]) for k in knobs], p.status.value,
                         "-" if not math.isfinite(err) else f"{err:.4g}",
                         f"{p.cost:.3f}", note])
        widths = [max(len(str(r[i])) for r in [head, *rows]) for i in range(len(head))]
        lines.append(f"{engine} on {result.scenario.name}:")
        for r in [head, ["-" * w for w in widths], *rows]:
            lines.append("  " + "  ".join(str(x).ljust(w) for x, w in
                                          zip(r, widths, strict=True)).rstrip())
        lines.append("")
    return "\n".join(lines)


# ---------------------------------------------------------------------- figures
_MARKERS = {  # kind → (marker, colour, label)
    "unstable": ("^", "red", "unstable (NaN / explosion / energy gain)"),
    "crashed": ("X", "black", "crashed"),
    "timeout": ("s", "darkorange", "timeout"),
    "drift": ("D", "magenta", "non-physical drift (sliding / wobble)"),
    "mismatch": ("v", "royalblue", "ends unlike the reference"),
    "unsupported": ("o", "grey", "unsupported"),
}


def _fmt_knob(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.3g}"
    return str(v)


def _norm(result: SweepResult) -> tuple[float, float]:
    errs = [p.error(result.metric) for p in result.points if p.status.completed]
    errs = [e for e in errs if math.isfinite(e) and e > 0]
    if not errs:
        return 1e-4, 1.0
    lo, hi = min(errs), max(errs)
    if hi / lo < 10:
        lo, hi = lo / 3.0, hi * 3.0
    return lo, hi


def stability_map(result: SweepResult, engine: str, path: str | Path,
                  target: float | None = None) -> Path:
    """Heat map of the error over two of the engine's grid knobs, with failure markers.

    The first grid knob is the x axis, the second the y axis; further knobs
    give one panel per combination. Colour: log of the error metric; markers:
    unstable, crashed, timeout, drift and runs ending unlike the reference;
    a bold outline: the point meets ``target``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch, Rectangle

    path = Path(path)
    g = result.grid[engine]
    knobs = list(g)
    xk = knobs[0] if knobs else None
    yk = knobs[1] if len(knobs) > 1 else None
    rest = knobs[2:]
    xs = g[xk] if xk else [None]
    ys = g[yk] if yk else [None]
    panels = _points({k: g[k] for k in rest}) or [{}]
    pts = {tuple(sorted(p.knobs.items())): p for p in result.engine_points(engine)}
    lo, hi = _norm(result)
    norm = LogNorm(vmin=lo, vmax=hi)
    cmap = plt.get_cmap("viridis").copy()
    ncol = min(3, len(panels))
    nrow = math.ceil(len(panels) / ncol)
    cw = max(0.9, min(1.3, 9.0 / max(len(xs), 1)))
    fig_w = min(18.0, ncol * (1.8 + cw * len(xs))) + 1.6
    fig_h = nrow * (1.4 + 0.7 * len(ys)) + 1.8
    fig, axes = plt.subplots(nrow, ncol, figsize=(fig_w, fig_h), squeeze=False,
                             layout="constrained")
    seen: set[str] = set()
    for ax, extra in zip(axes.flat, panels, strict=False):
        data = np.full((len(ys), len(xs)), np.nan)
        for iy, yv in enumerate(ys):
            for ix, xv in enumerate(xs):
                knob = {**extra}
                if xk:
                    knob[xk] = xv
                if yk:
                    knob[yk] = yv
                p = pts.get(tuple(sorted(knob.items())))
                if p is None:
                    continue
                e = p.error(result.metric)
                kind = p.kind()
                if p.status.completed and math.isfinite(e):
                    data[iy, ix] = max(e, lo)
                    ax.text(ix, iy, f"{e:.2g}", ha="center", va="center", fontsize=8,
                            color="white" if norm(max(e, lo)) < 0.6 else "black")
                if kind != "ok":
                    mk, col, _ = _MARKERS.get(kind, ("o", "grey", kind))
                    ax.plot(ix, iy + (0.22 if math.isfinite(data[iy, ix]) else 0.0), mk,
                            color=col, markersize=11 if math.isnan(data[iy, ix]) else 7,
                            markeredgecolor="white", markeredgewidth=0.8)
                    seen.add(kind)
                if target is not None and p.meets(target, result.metric):
                    ax.add_patch(Rectangle((ix - 0.5, iy - 0.5), 1, 1, fill=False,
                                           edgecolor="red", linewidth=2.2))
                    seen.add("target")
        ax.set_facecolor("#e6e6e6")
        im = ax.imshow(np.ma.masked_invalid(data), cmap=cmap, norm=norm, origin="lower",
                       aspect="auto")
        ax.set_xticks(range(len(xs)), [_fmt_knob(v) for v in xs] if xk else [""])
        ax.set_yticks(range(len(ys)), [_fmt_knob(v) for v in ys] if yk else [""])
        ax.set_xlabel(xk or "")
        ax.set_ylabel(yk or "")
        ax.set_xlim(-0.5, len(xs) - 0.5)
        ax.set_ylim(-0.5, len(ys) - 0.5)
        if extra:
            ax.set_title(", ".join(f"{k}={_fmt_knob(v)}" for k, v in extra.items()),
                         fontsize=9)
    for ax in list(axes.flat)[len(panels):]:
        ax.axis("off")
    cbar = fig.colorbar(im, ax=axes.ravel().tolist(), shrink=0.9)
    cbar.set_label(_metric_label(result.metric))
    handles: list[Any] = [Line2D([], [], linestyle="", marker=_MARKERS[k][0],
                                 color=_MARKERS[k][1], markersize=9, label=_MARKERS[k][2])
                          for k in _MARKERS if k in seen]
    if "target" in seen:
        handles.append(Patch(fill=False, edgecolor="red", linewidth=2,
                             label=f"meets target {result.metric} ≤ {target:g}"))
    if handles:
        fig.legend(handles=handles, loc="outside lower center", ncol=min(3, len(handles)),
                   fontsize=8, frameon=False)
    fig.suptitle(f"{engine} stability map: {result.scenario.name}", fontsize=11)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _metric_label(metric: str) -> str:
    return {"max_error": "max |Δθ|/λ vs analytic",
            "max_error_early": "max |Δθ|/λ up to the 3rd impact",
            "impact_time_error": "impact-time relative error",
            "peak_error": "peak |θ|/λ relative error"}.get(metric, metric)


def pareto_plot(result: SweepResult, path: str | Path, target: float | None = None) -> Path:
    """Error against wall time for every point, each engine's Pareto front as a line.

    Runs that failed or ended unlike the reference are drawn in a band above
    the plot with their marker; the cheapest point meeting ``target`` is
    circled and labelled with its knobs.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    path = Path(path)
    fig, ax = plt.subplots(figsize=(8.0, 5.4))
    colours = plt.get_cmap("tab10")
    lo, hi = _norm(result)
    band = max(hi, target or 0.0) * 4.0
    seen: set[str] = set()
    for i, engine in enumerate(result.engines):
        col = colours(i % 10)
        pts = result.engine_points(engine)
        good = [p for p in pts if p.kind() == "ok" and math.isfinite(p.error(result.metric))]
        ax.scatter([p.cost for p in good], [max(p.error(result.metric), lo) for p in good],
                   color=col, s=28, alpha=0.75, label=engine, zorder=3)
        for p in pts:
            kind = p.kind()
            if kind == "ok" or not math.isfinite(p.cost) or p.cost <= 0:
                continue
            mk, mcol, _ = _MARKERS.get(kind, ("o", "grey", kind))
            y = p.error(result.metric) if kind == "drift" else band
            ax.plot(p.cost, max(y, lo) if math.isfinite(y) else band, mk, color=col,
                    markeredgecolor=mcol, markeredgewidth=1.5, markersize=8, zorder=3)
            seen.add(kind)
        front = pareto_front(pts, result.metric)
        if front:
            ax.step([p.cost for p in front], [max(p.error(result.metric), lo) for p in front],
                    where="post", color=col, linewidth=1.6, zorder=2)
        if target is not None:
            best = cheapest(pts, target, result.metric)
            if best is not None:
                ax.scatter([best.cost], [max(best.error(result.metric), lo)], s=160,
                           facecolors="none", edgecolors=col, linewidths=2, zorder=4)
                ax.annotate(" ".join(f"{k}={_fmt_knob(v)}" for k, v in best.knobs.items())
                            or "defaults", (best.cost, max(best.error(result.metric), lo)),
                            textcoords="offset points", xytext=(8, -14), fontsize=8,
                            color=col)
    if target is not None:
        ax.axhline(target, color="red", linestyle="--", linewidth=1)
        ax.text(0.01, target, f"target {target:g}", transform=ax.get_yaxis_transform(),
                color="red", va="bottom", fontsize=8)
    if seen - {"drift"}:
        ax.axhspan(band / 1.6, band * 1.6, color="#eeeeee", zorder=0)
        ax.text(0.01, band * 1.6, "failed / unlike the reference (error not meaningful)",
                transform=ax.get_yaxis_transform(), va="bottom", fontsize=8, color="dimgray")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time per run (s)")
    ax.set_ylabel(_metric_label(result.metric))
    ax.set_title(f"accuracy vs cost: {result.scenario.name}")
    ax.grid(True, which="both", alpha=0.25)
    handles, _ = ax.get_legend_handles_labels()
    handles += [Line2D([], [], linestyle="", marker=_MARKERS[k][0], color="white",
                       markeredgecolor=_MARKERS[k][1], markeredgewidth=1.5, markersize=8,
                       label=_MARKERS[k][2]) for k in _MARKERS if k in seen]
    handles.append(Line2D([], [], color="black", linewidth=1.6, label="Pareto front"))
    ax.legend(handles=handles, fontsize=8, loc="best")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


# ---------------------------------------------------------------------- tuning
_FINER_SMALLER = ("timestep", "time_step", "dt")
_FINER_LARGER = ("iterations", "substeps", "sub_steps", "num_substeps", "solver_iterations",
                 "num_solver_iterations")


def tunable_knobs(engine: str) -> dict[str, str]:
    """Cost knobs of an engine recognised by name: knob → ``"smaller"`` or ``"larger"``.

    ``smaller`` means a smaller value is finer (time steps, tolerances),
    ``larger`` a larger one (iterations, sub-steps).
    """
    cls = engine_class(engine).Settings
    hints = typing.get_type_hints(cls)
    out = {}
    for name, kind in hints.items():
        low = name.lower()
        if kind is float and low in _FINER_SMALLER:
            out[name] = "smaller"
        elif kind is int and low in _FINER_LARGER:
            out[name] = "larger"
    return out


def _ladder(default: Any, direction: str, kind: type) -> list[Any]:
    """Values of a knob from the coarsest (cheapest) to the finest."""
    if direction == "smaller":
        return [float(f"{default * 2.0 ** k:.6g}") for k in (3, 2, 1, 0, -1, -2, -3)]
    vals = sorted({max(1, round(default * 2.0 ** k)) for k in (-3, -2, -1, 0, 1, 2, 3)})
    return [kind(v) for v in vals]


@dataclass
class TuneResult:
    """Outcome of :func:`tune`."""

    engine: str
    target: float
    metric: str
    best: SweepPoint | None
    evaluated: list[SweepPoint]
    ladders: dict[str, list[Any]]


def tune(
    scenario: Scenario,
    engine: str,
    target: float,
    *,
    knobs: Sequence[str] | None = None,
    base: Mapping[str, Any] | None = None,
    metric: str = "max_error",
    budget: int = 30,
    store: Store | None = None,
    n_jobs: int | None = 1,
    timeout: float | None = None,
    executor: str = "process",
    scheduler: Any = None,
    on_point: Callable[[SweepPoint], None] | None = None,
) -> TuneResult:
    """Search the cheapest settings of ``engine`` that meet ``target`` on ``scenario``.

    Each tuned knob gets a ladder of values around its default (×2 steps, from
    8× coarser to 8× finer). Starting from the defaults, while the target is
    not met every round evaluates (in parallel) the points one rung finer in
    each knob and moves to the one with the smallest error; once it is met,
    it moves one rung coarser in the knob that saves most while the target
    still holds. At most ``budget`` runs. Among the points that meet the
    target and cost within 15 % of the cheapest (wall times are noisy), the
    coarsest settings win.

    Parameters
    ----------
    scenario : Scenario
        The problem.
    engine : str
        Engine to tune.
    target : float
        Largest acceptable error metric.
    knobs : sequence of str, optional
        Knobs to tune (default: :func:`tunable_knobs`).
    base : mapping, optional
        Other settings (preset, fixed knobs).
    metric : str
        One of :data:`ERROR_METRICS`.
    budget : int
        Largest number of runs.
    store, n_jobs, timeout, executor, scheduler, on_point
        As in :func:`run_sweep`.

    Raises
    ------
    SweepError
        No tunable knob, or an unknown one.
    """
    auto = tunable_knobs(engine)
    cls = engine_class(engine)
    hints = typing.get_type_hints(cls.Settings)
    if knobs:
        bad = [k for k in knobs if k not in hints]
        if bad:
            raise SweepError(f"engine {engine!r} has no knob {bad[0]!r}; knobs: "
                             f"{', '.join(hints)}")
        kinds = {k: auto.get(k, "larger" if hints[k] is int else "smaller") for k in knobs}
        wrong = [k for k in knobs if hints[k] not in (int, float)]
        if wrong:
            raise SweepError(f"--knob {wrong[0]} is not numeric: it cannot be tuned")
    else:
        kinds = auto
    if not kinds:
        raise SweepError(f"no cost knob of {engine!r} recognised; name them with --knob")
    base = dict(base or {})
    preset = base.get("preset")
    defaults = cls.settings(preset, **{k: v for k, v in base.items() if k != "preset"})
    ladders = {k: _ladder(getattr(defaults, k), d, hints[k]) for k, d in kinds.items()}
    names = list(ladders)
    ref_traj = references([scenario], store, n_jobs=1, timeout=timeout, executor=executor,
                          scheduler=scheduler)[0][scenario.name]
    seen: dict[tuple[int, ...], SweepPoint] = {}

    def evaluate(idxs: list[tuple[int, ...]]) -> None:
        idxs = [i for i in dict.fromkeys(idxs) if i not in seen][:max(0, budget - len(seen))]
        if not idxs:
            return
        wanted = {tuple(ladders[n][j] for n, j in zip(names, i, strict=True)): i for i in idxs}
        for p in _run_points(scenario, engine, names, list(wanted), base, store, n_jobs,
                             timeout, executor, scheduler, ref_traj):
            i = wanted[tuple(p.knobs[n] for n in names)]
            seen[i] = p
            if on_point is not None:
                on_point(p)

    def score(i: tuple[int, ...]) -> tuple[float, float]:
        p = seen[i]
        e = p.error(metric)
        ok = p.as_reference and not p.drift and math.isfinite(e)
        return (e if ok else math.inf, p.cost)

    # start from the (calibrated) defaults: refine until the target holds, then coarsen
    cur = tuple(ladders[n].index(_closest(ladders[n], getattr(defaults, n))) for n in names)
    evaluate([cur])
    while len(seen) < budget and not seen[cur].meets(target, metric):
        nbrs = [tuple(j + (1 if n == k else 0) for n, j in zip(range(len(names)), cur,
                                                                strict=True))
                for k in range(len(names)) if cur[k] + 1 < len(ladders[names[k]])]
        if not nbrs:
            break
        evaluate(nbrs)
        done = [i for i in nbrs if i in seen]
        if not done:
            break
        cur = min(done, key=score)
    # coarsen while the target still holds
    while len(seen) < budget and cur in seen and seen[cur].meets(target, metric):
        nbrs = [tuple(j - (1 if n == k else 0) for n, j in zip(range(len(names)), cur,
                                                                strict=True))
                for k in range(len(names)) if cur[k] > 0]
        nbrs = [i for i in nbrs if i not in seen]
        if not nbrs:
            break
        evaluate(nbrs)
        better = [i for i in nbrs if i in seen and seen[i].meets(target, metric)]
        if not better:
            break
        cur = min(better, key=lambda i: seen[i].cost)
    # wall times are noisy: among points within 15 % of the cheapest, take the coarsest
    meeting = [(i, p) for i, p in seen.items() if p.meets(target, metric)]
    best = None
    if meeting:
        c_min = min(p.cost for _, p in meeting)
        near = [(i, p) for i, p in meeting if p.cost <= 1.15 * c_min]
        best = min(near, key=lambda ip: (sum(ip[0]), ip[1].cost))[1]
    return TuneResult(engine, target, metric, best, list(seen.values()), ladders)


def _closest(ladder: list[Any], value: Any) -> Any:
    return min(ladder, key=lambda v: abs(math.log(max(v, 1e-300) / max(value, 1e-300))))


def _run_points(scenario: Scenario, engine: str, names: list[str],
                values: list[tuple[Any, ...]], base: Mapping[str, Any],
                store: Store | None, n_jobs: int | None, timeout: float | None,
                executor: str, scheduler: Any, ref: Trajectory | None) -> list[SweepPoint]:
    """Run an explicit list of knob combinations (not a cartesian grid)."""
    version = engine_class(engine).version()
    jobs = [Job(scenario, engine, {**base, **dict(zip(names, v, strict=True))})
            for v in values]
    out = []

    def finished(job: Job, traj: Trajectory) -> None:
        m = run_metrics(traj, ref, scenario)
        m["drift"] = _drift(m, scenario)
        if store is not None:
            store.record(scenario, engine, job.settings, traj, m, kind="tune",
                         engine_version=version)
        out.append(SweepPoint(engine, {n: job.settings[n] for n in names}, dict(job.settings),
                              traj.status, traj.message, m))

    run_jobs(jobs, n_jobs=n_jobs, timeout=timeout, on_result=finished, executor=executor,
             scheduler=scheduler)
    return out
