"""The planarity report: when is 2D enough, per scene and engine, and what 3D costs.

:func:`write_report` renders a :class:`~rockbench.studies.planarity.PlanarityResult`: the
verdict of every engine on every scene (2D is enough or not, why, the worst incidence
angle, the cost of 3D against 2D), per scene and engine a table of every angle (the 2D
peaks, the 3D peak tilt, the out-of-plane rotation and twist, the outcomes), figures of
the peak against the incidence angle (planar against 3D, Housner's 2D beside them) and of
the centroid's path seen from above at the worst angle, and ``planarity.csv`` with every
run.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from rockbench.report.document import (
    Document,
    FigureItem,
    Section,
    report_date,
    run_header,
)
from rockbench.report.html import write_document
from rockbench.report.tables import Cell, Table
from rockbench.studies.planarity import (
    AngleComparison,
    Model,
    PlanarityResult,
    PlanarityRow,
    PlanarityVerdict,
    Scene,
    Verdict,
)

__all__ = ["write_report", "peak_figure", "path_figure", "CITATION"]

_DPI = 110
#: Where the peak figure draws an overturned block (its peak is meaningless past λ).
_OVER = 1.08
#: Housner's model (the 2D reference) and the study this benchmark reproduces.
CITATION = ("G. W. Housner, \u201cThe behavior of inverted pendulum structures during "
            "earthquakes\u201d, Bull. Seismol. Soc. Am. 53(2), 403\u2013417 (1963); "
            "Giordano et al. (2025), Structures, doi:10.1016/j.istruc.2025.110027")


def _f(v: float | None, fmt: str = "{:.3f}") -> str:
    return fmt.format(v) if v is not None and math.isfinite(v) else "–"


def _engines(result: PlanarityResult) -> list[str]:
    """Labels of the methods that ran in 3D (the engines compared)."""
    return list(dict.fromkeys(v.method for v in result.verdicts
                              if v.verdict is not Verdict.PLANAR_ONLY))


def _comps(result: PlanarityResult, scene: str, method: str) -> list[AngleComparison]:
    return [c for c in result.comparisons if c.scene == scene and c.method == method]


def _plot(v: float | None, overturned: bool) -> float:
    if overturned:
        return _OVER
    return min(v, _OVER) if v is not None and math.isfinite(v) else math.nan


def peak_figure(path: Path, result: PlanarityResult, scene: Scene) -> Path:
    """Peak over λ against the incidence angle, one panel per engine: the 3D peak tilt, the
    2D peak (the larger of the planar-x and planar-y runs), the 3D run's θ/λ_x and
    roll/λ_y, and Housner's 2D peak; overturned runs at the top."""
    methods = _engines(result)
    n = max(1, len(methods))
    fig = Figure(figsize=(max(4.6 * n, 7.5) + 0.4, 4.6))
    FigureCanvasAgg(fig)
    angles = list(scene.angles)
    ref = _comps(result, scene.name, result.methods[0].label)
    axes = [fig.add_subplot(1, n, k + 1) for k in range(n)]
    for ax, m in zip(axes, methods or [""], strict=True):
        comps = _comps(result, scene.name, m)
        if ref:
            ax.plot(angles, [_plot(c.planar, c.planar_overturned) for c in ref], color="0.55",
                    linestyle=":", linewidth=2.0, label="Housner, 2D")
        if comps:
            ax.plot(angles, [_plot(c.planar, c.planar_overturned) for c in comps],
                    color="#1f77b4", linestyle="--", marker="s", markerfacecolor="none",
                    label="engine, 2D (max of planar-x, planar-y)")
            ax.plot(angles, [_plot(c.three_d, c.three_d_overturned) for c in comps],
                    color="#d62728", marker="o", label="engine, 3D: tilt / λ(azimuth)")
            ax.plot(angles, [_plot(c.peak_theta, c.three_d_overturned) for c in comps],
                    color="#2ca02c", linewidth=0.9, alpha=0.8, label="3D: |θ| / λ_x")
            ax.plot(angles, [_plot(c.peak_roll, c.three_d_overturned) for c in comps],
                    color="#9467bd", linewidth=0.9, alpha=0.8, label="3D: |roll| / λ_y")
            bad = [c.angle for c in comps if c.note and not c.three_d_overturned]
            for a in bad:
                ax.axvline(a, color="#ff7f0e", alpha=0.4, linewidth=6)
        ax.axhline(1.0, color="0.3", linewidth=0.8)
        ax.text(angles[0], _OVER, " overturned", fontsize=7, va="bottom", color="0.3")
        ax.set_ylim(0.0, _OVER + 0.07)
        ax.set_xticks(angles)
        ax.set_xlabel("incidence angle α (° from the block's x axis)")
        ax.set_ylabel("peak / λ")
        ax.set_title(m or "no engine ran in 3D", fontsize=10)
        ax.grid(True, alpha=0.3)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.suptitle(f"{scene.name}: {scene.description}", fontsize=9)
    fig.legend(handles, labels, fontsize=7, loc="lower center", ncol=(3 if n == 1 else 5))
    fig.tight_layout(rect=(0.0, 0.12 if n == 1 else 0.09, 1.0, 0.95))
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=_DPI)
    return path


def path_figure(path: Path, result: PlanarityResult, scene: Scene) -> Path | None:
    """The bottom block's centroid seen from above, relative to the base, in the 3D run at
    each engine's worst angle, over the block's footprint and the direction of shaking."""
    paths = [p for p in result.paths if p.scene == scene.name]
    if not paths:
        return None
    n = len(paths)
    fig = Figure(figsize=(max(4.6 * n, 6.0) + 0.4, 4.8))
    FigureCanvasAgg(fig)
    for k, p in enumerate(paths):
        ax = fig.add_subplot(1, n, k + 1)
        b, a = p.half_width, p.half_depth
        ax.add_patch(Rectangle((-b * 1e3, -a * 1e3), 2e3 * b, 2e3 * a, fill=False,
                               edgecolor="0.5", linewidth=1.0, label="footprint"))
        x, y = 1e3 * p.x, 1e3 * p.y
        sc = ax.scatter(x, y, c=p.t, s=2, cmap="viridis")
        ax.plot(x[:1], y[:1], marker="o", color="k", linestyle="none", label="start")
        # zoomed on the path (the footprint's outline shows where it lies beyond the view)
        reach = max(float(np.nanmax(np.abs(np.concatenate([x, y])))), 2.0) * 1.3
        u = math.radians(p.angle)
        if scene.sweep.value == "direction":
            ax.annotate("", xy=(0.9 * reach * math.cos(u), 0.9 * reach * math.sin(u)),
                        xytext=(0.0, 0.0), arrowprops={"arrowstyle": "->", "color": "#d62728"})
            ax.plot([], [], color="#d62728", label=f"shaking along α = {p.angle:g}°")
        ax.set_xlim(-reach, reach)
        ax.set_ylim(-reach, reach)
        ax.set_aspect("equal")
        ax.set_xlabel("x − base (mm)")
        ax.set_ylabel("y − base (mm)")
        ax.set_title(f"{p.method}, worst α = {p.angle:g}°", fontsize=10)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="upper left")
        fig.colorbar(sc, ax=ax, shrink=0.8, label="t (s)")
    fig.suptitle(f"{scene.name}\ncentroid of the bottom block seen from above (3D run)",
                 fontsize=9)
    fig.tight_layout(rect=(0.0, 0.0, 1.0, 0.92))
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=_DPI)
    return path


def _verdict_cell(v: PlanarityVerdict) -> Cell:
    kind = {Verdict.ENOUGH: "", Verdict.NOT_ENOUGH: "overturned", Verdict.UNKNOWN: "crashed",
            Verdict.PLANAR_ONLY: "unsupported"}[v.verdict]
    return Cell(v.verdict.value, kind=kind, title=v.reason)


def _verdict_table(result: PlanarityResult, number: int) -> Table:
    tol = 100 * result.options.tolerance
    t = Table(
        key="verdicts", title=f"Table {number}. Is 2D enough? Per scene and engine",
        caption=(f"2D is enough when, at every incidence angle, the 2D analyses (planar-x and "
                 f"planar-y on the same engine) and the 3D run agree on the outcome and the "
                 f"2D peak is within {tol:g} % of the 3D peak tilt. Worst angle: the largest "
                 f"3D peak tilt (an overturning first). CPU: all planar runs, all 3D runs, "
                 f"per run."),
        columns=["scene", "engine", "verdict", "why", "worst α (°)", "3D peak there (λ)",
                 "largest |3D − 2D| / 3D", "CPU 2D (s)", "CPU 3D (s)", "3D / 2D cost",
                 "CPU per run 2D / 3D (s)"])
    for v in result.verdicts:
        if v.verdict is Verdict.PLANAR_ONLY:
            continue
        peak = ("overturned" if v.worst_overturned else _f(v.worst_peak))
        t.add_row([Cell(v.scene, kind="head"), v.method, _verdict_cell(v), v.reason,
                   _f(v.worst_angle, "{:g}"), peak,
                   _f(100 * v.largest_difference, "{:.1f} %"), f"{v.planar_cpu:.2f}",
                   f"{v.three_d_cpu:.2f}", _f(v.cost_ratio, "{:.2f}×"),
                   f"{_f(v.planar_cpu / max(v.planar_runs, 1), '{:.2f}')} / "
                   f"{_f(v.three_d_cpu / max(v.three_d_runs, 1), '{:.2f}')}"])
    return t


def _outcome(overturned: bool, value: float | None) -> str:
    return "overturned" if overturned else _f(value)


def _planar_cell(r: PlanarityRow | None) -> Cell:
    if r is None:
        return Cell("–")
    if not r.completed:
        return Cell(r.status.value, kind="crashed", title=r.message)
    return Cell(_outcome(r.overturned, r.peak), kind="overturned" if r.overturned else "",
                title=r.message)


def _angle_table(result: PlanarityResult, scene: Scene, method: str, number: int) -> Table:
    rows = [r for r in result.rows if r.scene == scene.name and r.method == method]
    t = Table(
        key=f"angles-{scene.name}-{method}",
        title=f"Table {number}. {scene.name} on {method}: {scene.description}",
        caption=(f"Per incidence angle α: Housner's 2D peak (analytic), the engine's planar-x "
                 f"(|θ|/λ_x, λ_x = {scene.lam_x:.4f} rad) and planar-y (the block turned by "
                 f"90°, λ_y = {scene.lam_y:.4f} rad) peaks, the 2D peak (their larger), the 3D "
                 f"peak tilt over the λ of its azimuth, the 3D run's |θ|/λ_x and |roll|/λ_y, "
                 f"the difference over the 3D peak, the 3D run's max |roll| and |twist| (rad), "
                 f"and the CPU time of the 2D and 3D runs."),
        columns=["α (°)", "Housner 2D", "planar-x", "planar-y", "2D", "3D tilt", "3D θ/λ_x",
                 "3D roll/λ_y", "3D − 2D", "max roll (rad)", "max twist (rad)",
                 "CPU 2D (s)", "CPU 3D (s)"])
    for c in _comps(result, scene.name, method):
        at = {r.model: r for r in rows if r.angle == c.angle}

        three = at.get(Model.THREE_D)
        if three is None:
            three_cell = Cell("–")
        elif not three.completed:
            three_cell = Cell(three.status.value, kind="crashed", title=three.message)
        else:
            three_cell = Cell(_outcome(three.overturned, three.peak_tilt),
                              kind="overturned" if three.overturned else "",
                              title=three.message)
        cpu2 = sum(r.cpu_time for m, r in at.items() if m is not Model.THREE_D)
        t.add_row([Cell(f"{c.angle:g}", kind="head"),
                   Cell(_f(c.reference) if c.reference is not None else "–", kind="ref"),
                   _planar_cell(at.get(Model.PLANAR_X)), _planar_cell(at.get(Model.PLANAR_Y)),
                   Cell(_outcome(c.planar_overturned, c.planar),
                        kind="overturned" if c.planar_overturned else ""),
                   three_cell,
                   _f(c.peak_theta) if not c.three_d_overturned else "–",
                   _f(c.peak_roll) if not c.three_d_overturned else "–",
                   _f(100 * c.relative, "{:+.1f} %"),
                   _f(c.max_roll, "{:.2e}") if not c.three_d_overturned else "–",
                   _f(c.max_twist, "{:.2e}") if not c.three_d_overturned else "–",
                   f"{cpu2:.2f}", f"{three.cpu_time:.2f}" if three else "–"])
    return t


def _write_csv(result: PlanarityResult, path: Path) -> Path:
    sweeps = {s.name: s.sweep.value for s in result.scenes}
    with path.open("w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(["scene", "sweep", "angle", "method", "engine", "model", "scenario",
                    "status", "lambda", "peak", "peak_tilt", "peak_roll", "max_roll",
                    "max_twist", "overturned", "cpu_time", "message"])
        for r in result.rows:
            w.writerow([r.scene, sweeps[r.scene], r.angle, r.method, r.engine, r.model.value,
                        r.scenario, r.status.value, r.lam, r.peak, r.peak_tilt, r.peak_roll,
                        r.max_roll, r.max_twist, r.overturned, r.cpu_time, r.message])
    return path


def _summary(result: PlanarityResult) -> list[str]:
    out = []
    for v in result.verdicts:
        if v.verdict is Verdict.PLANAR_ONLY:
            continue
        worst = ("" if v.worst_angle is None else
                 f" Worst angle {v.worst_angle:g}°"
                 + (" (overturns)" if v.worst_overturned else f" ({_f(v.worst_peak)} λ)") + ".")
        cost = ("" if not math.isfinite(v.cost_ratio) else
                f" 3D cost {v.cost_ratio:.2f}× the 2D runs' CPU.")
        out.append(f"{v.scene} on {v.method}: **{v.verdict.value}**: {v.reason}.{worst}{cost}")
    return out or ["No engine ran in 3D: only the planar analyses are shown."]


def write_report(result: PlanarityResult, out: Path, *, embed_figures: bool = True
                 ) -> list[Path]:
    """Write ``index.html``, ``report.md``, ``planarity.csv`` and ``figures/``.

    Returns
    -------
    list of Path
        The files written (figures excluded).
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    csv_path = _write_csv(result, out / "planarity.csv")
    sec = Section("verdict", "Is 2D enough?")
    sec.paragraphs += _summary(result)
    number = 1
    sec.items.append(_verdict_table(result, number))
    sections = [sec]
    for i, scene in enumerate(result.scenes, 1):
        ssec = Section(f"scene-{i}", f"{scene.name}")
        ssec.paragraphs.append(
            f"{scene.description}; {len(scene.angles)} angles ({scene.sweep.value} sweep). "
            f"λ_x = {scene.lam_x:.4f} rad (rocking about y), λ_y = {scene.lam_y:.4f} rad "
            f"(about x).")
        fig = peak_figure(out / "figures" / f"peaks-{i}.png", result, scene)
        ssec.items.append(FigureItem(str(fig.relative_to(out)), (
            "Peak over λ against the incidence angle: 3D (peak tilt over the λ of its "
            "azimuth) against 2D (the larger of the planar-x and planar-y runs of the same "
            "engine) and Housner's 2D; overturned runs at the top, failed ones shaded."),
            f"{scene.name}: peak against incidence angle"))
        walk = path_figure(out / "figures" / f"path-{i}.png", result, scene)
        if walk is not None:
            ssec.items.append(FigureItem(str(walk.relative_to(out)), (
                "The bottom block's centroid seen from above, relative to the base, in the "
                "3D run at each engine's worst angle (colour: time), over its footprint."),
                f"{scene.name}: centroid path at the worst angle"))
        for m in _engines(result):
            if _comps(result, scene.name, m):
                number += 1
                ssec.items.append(_angle_table(result, scene, m, number))
        sections.append(ssec)
    opts = result.options
    header = [
        ("Date", report_date()),
        ("Scenes", ", ".join(s.name for s in result.scenes)),
        ("Runs", f"{result.ran + result.reused}: {result.ran} run now, {result.reused} reused"),
        ("Tolerance", f"2D peak within {100 * opts.tolerance:g} % of the 3D peak"),
        *run_header(result.wall_time, opts.execution.jobs, result.versions, opts.command),
    ]
    doc = Document(
        title="rockbench planarity report", header=header,
        intro=["Each scene runs planar and in 3D on every engine, at several incidence angles "
               "of the base motion: is a 2D model (the two planar analyses along the block's "
               "axes) enough, where is the worst angle, and what does 3D cost?"],
        sections=sections, citation=CITATION)
    index, md = write_document(doc, out, embed=embed_figures, data=("planarity.csv",))
    return [index, md, csv_path]
