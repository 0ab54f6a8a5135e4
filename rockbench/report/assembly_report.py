"""The report of the assembly studies: pictures, tilting table against limit analysis, pulse
to collapse.

Writes, in the report directory, ``index.html`` and ``report.md`` (the same
document), ``results.csv`` (one row per tilting-table comparison and per
pulse-to-collapse point, with its cost) and ``figures/``:

* ``assembly-<name>.png``: each assembly drawn to scale (blocks, supports
  hatched, the base), with the limit-analysis mechanism of its governing
  direction: the moving blocks filled, an arrow of each one's centroid
  velocity and a cross at each rotation centre (:func:`draw_assembly`);
* ``collapse-<name>.png``: a_p/g of the pulse that collapses it against the
  pulse frequency, per engine, with the static factor α as the
  low-frequency limit.
"""

from __future__ import annotations

import csv
import math
import os
import platform
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import FancyArrow, Polygon, Rectangle
from matplotlib.ticker import NullFormatter

from rockbench import provenance
from rockbench.analytic.static_collapse import LimitResult
from rockbench.report.document import (
    Document,
    FigureItem,
    Section,
    cpu_model,
)
from rockbench.report.figures import save_figure
from rockbench.report.html import write_document
from rockbench.report.tables import Cell, Table
from rockbench.scenarios import Scenario
from rockbench.studies.collapse import (
    FREE_TIME,
    RESIDUAL_DISPLACEMENT,
    RESIDUAL_DROP,
    RESIDUAL_ROTATION,
    CollapsePoint,
    CollapseStudy,
)
from rockbench.studies.tilting import TiltComparison, reference

__all__ = ["AssemblyDrawing", "block_polygons", "draw_assembly", "assembly_figure",
           "collapse_figure", "write_assembly_report", "CITATION"]

CITATION = ("the paper's closing question: physics engines against DEM for multi-block "
            "dry-joint systems, up to collapse")
_BLOCK = "#d9d4c7"
_MOVING = "#f0a04b"
_SUPPORT = "#9a9a9a"


@dataclass(frozen=True)
class AssemblyDrawing:
    """What :func:`draw_assembly` drew.

    Attributes
    ----------
    blocks : int
        Block polygons drawn.
    supports : int
        Fixed bodies drawn hatched (the base included).
    moving : tuple of int
        Blocks drawn as moving in the mechanism (filled, with an arrow).
    centres : int
        Rotation centres marked.
    """

    blocks: int
    supports: int
    moving: tuple[int, ...]
    centres: int


def block_polygons(scenario: Scenario) -> list[np.ndarray]:
    """World corners (x, z) of every block at rest, counter-clockwise."""
    geo = scenario.geometry
    return [geo.world_vertices(i) for i in range(geo.n_bodies)]


def _governing(scenario: Scenario) -> LimitResult | None:
    """The limit analysis of the direction with the smaller collapse factor."""
    found = [r for r in (reference(scenario, d) for d in (1, -1)) if r.status == "collapse"]
    # equal factors (a symmetric assembly) within the LP tolerance: loads toward +x
    return min(found, key=lambda r: (round(r.load_factor, 9), -r.direction)) if found else None


def draw_assembly(ax: Axes, scenario: Scenario, limit: LimitResult | None) -> AssemblyDrawing:
    """Draw ``scenario``'s blocks to scale, its supports and base hatched, and ``limit``'s
    mechanism (moving blocks filled, centroid velocity arrows, rotation centres)."""
    polys = block_polygons(scenario)
    moving = limit.moving_blocks if limit is not None else ()
    pts = np.concatenate(polys)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    size = float(max(hi - lo))
    for i, p in enumerate(polys):
        ax.add_patch(Polygon(p, closed=True, facecolor=_MOVING if i in moving else _BLOCK,
                             edgecolor="black", linewidth=0.8))
    supports = list(scenario.geometry.supports)
    for s in supports:
        ax.add_patch(Polygon(s.array, closed=True, facecolor="white", edgecolor=_SUPPORT,
                             hatch="///", linewidth=0.8))
        pts = np.concatenate([pts, s.array])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    pad = 0.15 * size
    base_h = 0.08 * size
    ax.add_patch(Rectangle((lo[0] - pad, -base_h), hi[0] - lo[0] + 2 * pad, base_h,
                           facecolor="white", edgecolor=_SUPPORT, hatch="///", linewidth=0.8))
    centres = 0
    if limit is not None:
        cents = np.array([_centroid(p) for p in polys])
        vmax = max((float(np.hypot(*limit.mechanism[i].velocity[:2])) for i in moving),
                   default=0.0)
        for i in moving:
            m = limit.mechanism[i]
            v = m.velocity[:2]
            scale = 0.25 * size / vmax if vmax > 0 else 0.0
            tip = cents[i] + v * scale
            pts = np.vstack([pts, tip])
            head = min(0.04 * size, 0.5 * float(np.hypot(*v)) * scale)  # short arrows too
            ax.add_patch(FancyArrow(cents[i, 0], cents[i, 1], v[0] * scale, v[1] * scale,
                                    width=0.008 * size, head_width=head,
                                    head_length=head, length_includes_head=True,
                                    color="#b22222"))
            if m.centre is not None:
                ax.plot([m.centre[0]], [m.centre[1]], marker="x", color="#1f3b73",
                        markersize=8, markeredgewidth=2)
                ax.plot([m.centre[0], cents[i, 0]], [m.centre[1], cents[i, 1]],
                        color="#1f3b73", linewidth=0.6, linestyle="--")
                pts = np.vstack([pts, m.centre])
                centres += 1
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(-base_h, hi[1] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("z (m)")
    return AssemblyDrawing(len(polys), len(supports) + 1, tuple(moving), centres)


def _centroid(p: np.ndarray) -> np.ndarray:
    """Area centroid of a counter-clockwise polygon."""
    x, z = p[:, 0], p[:, 1]
    x1, z1 = np.roll(x, -1), np.roll(z, -1)
    cross = x * z1 - x1 * z
    a = 0.5 * cross.sum()
    return np.array([((x + x1) * cross).sum(), ((z + z1) * cross).sum()]) / (6.0 * a)


def assembly_figure(path: Path, scenario: Scenario) -> tuple[Path, AssemblyDrawing]:
    """``path``: the assembly to scale with its governing limit-analysis mechanism."""
    lim = _governing(scenario)
    fig = Figure(figsize=(6.0, 4.2), layout="constrained")
    ax = fig.add_subplot()
    drawing = draw_assembly(ax, scenario, lim)
    if lim is not None:
        sense = "+x" if lim.direction > 0 else "−x"
        ax.set_title(f"{scenario.name}: α = {lim.load_factor:.4f} (loads toward {sense}, "
                     f"{lim.governing_mode})", fontsize=10)
    else:
        ax.set_title(f"{scenario.name}: no mechanism", fontsize=10)
    return save_figure(fig, path), drawing


def collapse_figure(path: Path, study: CollapseStudy, scenario: Scenario) -> Path:
    """``path``: a_p/g of the collapse pulse against f_p, per engine, and α."""
    fig = Figure(figsize=(6.0, 4.0), layout="constrained")
    ax = fig.add_subplot()
    alpha = math.nan
    for k, e in enumerate(study.engines):
        pts = study.curve(scenario.name, e)
        if not pts:
            continue
        alpha = pts[0].static_factor
        f = np.array([p.frequency for p in pts])
        a = np.array([p.acceleration_ratio for p in pts])
        lo = np.array([p.lower * p.static_factor for p in pts])
        ok = np.isfinite(a)
        # the bar reaches down to the bracket's lower end (did not collapse)
        # open markers, each smaller than the last: engines that agree stay visible
        ax.errorbar(f[ok], a[ok], yerr=[a[ok] - lo[ok], np.zeros(ok.sum())],
                    marker="os^vD"[k % 5], markersize=11 - 2 * (k % 4), markerfacecolor="none",
                    markeredgewidth=1.5, capsize=3, label=e)
        if (~ok).any():  # no collapse: a triangle at the largest pulse tried
            tried = [max(q.factor for q in p.probes) * p.static_factor
                     for p, good in zip(pts, ok, strict=True) if not good]
            ax.plot(f[~ok], tried, linestyle="none", marker="^", color=f"C{k}",
                    markersize=11 - 2 * (k % 4), markerfacecolor="none",
                    label=f"{e}: no collapse up to △")
    if math.isfinite(alpha):
        ax.axhline(alpha, color="black", linestyle="--", linewidth=1,
                   label=f"static factor α = {alpha:.4f}")
    ax.set_xscale("log")
    ax.set_xticks(list(study.frequencies), [f"{f:g}" for f in study.frequencies])
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("pulse frequency f_p (Hz)")
    ax.set_ylabel("collapse a_p / g")
    ax.set_ylim(bottom=0)
    ax.set_title(f"one-sine pulse to collapse: {scenario.name}", fontsize=10)
    ax.legend(fontsize=8)
    return save_figure(fig, path)


def _pct(x: float) -> str:
    return f"{100 * x:+.2f} %" if math.isfinite(x) else "–"


def _tilting_table(cmps: Sequence[TiltComparison]) -> Table:
    t = Table("tilting", "Table 1. Tilting table against limit analysis",
              "Onset α of each engine at the slower rate against the LP factor, the "
              "rate^(2/3)-extrapolated onset, the change when the rate is halved (quasi-statics), "
              "whether the blocks that moved are the LP mechanism's, and the CPU time of the "
              "two runs.",
              ["assembly", "engine", "α LP", "α onset", "error", "extrapolated", "halving",
               "mechanism", "CPU s"])
    for c in cmps:
        t.rows.append([Cell(c.scenario, "head"), Cell(c.engine),
                       Cell(f"{c.limit.load_factor:.4f}", "ref"),
                       Cell(f"{c.half.onset_factor:.4f}"), Cell(_pct(c.error)),
                       Cell(_pct(c.extrapolated_error)), Cell(_pct(c.rate_change)),
                       Cell("yes" if c.mechanism_matches else f"no {c.half.moved}"),
                       Cell(f"{c.run.cpu_time + c.half.cpu_time:.2f}")])
    return t


def _collapse_table(study: CollapseStudy) -> Table:
    t = Table("collapse", "Table 2. Pulse to collapse",
              "Smallest one-sine a_p/g that collapses each assembly (the bracket's upper end; "
              "the lower end did not collapse), in units of g and of the static factor α, the "
              "runs of the bisection and their CPU time.",
              ["assembly", "engine", "f_p (Hz)", "α", "a_p/g", "a_p/(αg)", "bracket (α)",
               "runs", "CPU s"])
    for p in study.points:
        text = f"{p.acceleration_ratio:.4f}" if math.isfinite(p.upper) else "none"
        t.rows.append([Cell(p.scenario, "head"), Cell(p.engine), Cell(f"{p.frequency:g}"),
                       Cell(f"{p.static_factor:.4f}", "ref"), Cell(text),
                       Cell(f"{p.factor:.3f}" if math.isfinite(p.upper) else "–"),
                       Cell(f"{p.lower:.3f} … {p.upper:.3f}"),
                       _runs_cell(p),
                       Cell(f"{p.cpu_time:.2f}")])
    return t


def _runs_cell(p: CollapsePoint) -> Cell:
    """The number of runs; a run that failed stopped the bisection: its status, marked."""
    bad = [q for q in p.probes if q.collapsed is None]
    if not bad:
        return Cell(str(len(p.probes)))
    return Cell(f"{len(p.probes)} (stopped: {bad[0].status} at {bad[0].factor:.3f} α)",
                str(bad[0].status), title="the bracket is not closed: the run failed")


def _cost_table(cmps: Sequence[TiltComparison], study: CollapseStudy | None) -> Table:
    t = Table("cost", "Table 3. Cost next to accuracy, per engine",
              "Total CPU time of each study per engine, with the median |error| of the "
              "tilting-table onset against the LP and, for pulse to collapse, the median "
              "a_p/(αg) at the lowest frequency (→ 1 as f_p → 0).",
              ["engine", "tilting CPU s", "median |error|", "collapse CPU s", "runs",
               "median a_p/(αg) at lowest f_p"])
    engines = list(dict.fromkeys([c.engine for c in cmps]
                                 + (list(study.engines) if study else [])))
    for e in engines:
        cs = [c for c in cmps if c.engine == e]
        errs = [abs(c.error) for c in cs if math.isfinite(c.error)]
        row = [Cell(e, "head"),
               Cell(f"{sum(c.run.cpu_time + c.half.cpu_time for c in cs):.1f}" if cs else "–"),
               Cell(f"{100 * float(np.median(errs)):.2f} %" if errs else "–")]
        if study is not None and e in study.engines:
            ps = [p for p in study.points if p.engine == e]
            f0 = min(study.frequencies)
            low = [p.factor for p in ps if p.frequency == f0 and math.isfinite(p.upper)]
            row += [Cell(f"{sum(p.cpu_time for p in ps):.1f}"),
                    Cell(str(sum(len(p.probes) for p in ps))),
                    Cell(f"{float(np.median(low)):.3f}" if low else "–")]
        else:
            row += [Cell("–"), Cell("–"), Cell("–")]
        t.rows.append(row)
    return t


def _write_csv(path: Path, cmps: Sequence[TiltComparison], study: CollapseStudy | None) -> Path:
    tmp = path.with_suffix(".csv.tmp")
    with tmp.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["study", "scenario", "engine", "rate_or_frequency", "static_factor",
                    "value", "lower", "error", "extrapolated_error", "mechanism_matches",
                    "runs", "cpu_time", "wall_time"])
        for c in cmps:
            w.writerow(["tilting", c.scenario, c.engine, c.half.rate, c.limit.load_factor,
                        c.half.onset_factor, "", c.error, c.extrapolated_error,
                        c.mechanism_matches, 2, c.run.cpu_time + c.half.cpu_time,
                        c.run.wall_time + c.half.wall_time])
        for p in (study.points if study else ()):
            w.writerow(["collapse", p.scenario, p.engine, p.frequency, p.static_factor,
                        p.acceleration_ratio, p.lower * p.static_factor, "", "", "",
                        len(p.probes), p.cpu_time, p.wall_time])
    os.replace(tmp, path)
    return path


def write_assembly_report(out: Path, scenarios: Sequence[Scenario],
                          tilting: Sequence[TiltComparison] = (),
                          collapse: CollapseStudy | None = None, *, command: str = "",
                          wall_time: float | None = None, embed: bool = True) -> list[Path]:
    """Write ``index.html``, ``report.md``, ``results.csv`` and the figures into ``out``.

    Parameters
    ----------
    out : Path
        Report directory (created).
    scenarios : sequence of Scenario
        The assemblies at rest (one picture each).
    tilting : sequence of TiltComparison
        Tilting-table results (any engines); empty: no tilting section.
    collapse : CollapseStudy, optional
        Pulse-to-collapse results; None: no collapse section.
    command : str
        The command line shown in the header.
    wall_time : float, optional
        Wall time of the whole command (s).
    embed : bool
        Embed the PNGs in index.html.

    Returns
    -------
    list of Path
        The files written (figures included).
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    files: list[Path] = []
    pictures = Section("assemblies", "Assemblies and their limit-analysis mechanisms", [
        "Each assembly to scale: blocks (grey), supports and the base (hatched); the blocks "
        "that move in the limit-analysis mechanism of the governing direction are filled "
        "orange, with the virtual velocity of their centroid (red arrow) and their rotation "
        "centre (blue cross)."])
    for sc in scenarios:
        path, _ = assembly_figure(out / "figures" / f"assembly-{sc.name}.png", sc)
        files.append(path)
        pictures.items.append(FigureItem(str(path.relative_to(out)), sc.name))
    sections = [pictures]
    if tilting:
        sections.append(Section("tilting", "Tilting table", [
            "Each engine tilts the table through a base-acceleration ramp α(t) = rate · t at "
            "two rates (the second half the first) and records the α at which the assembly "
            "starts to move relative to the base (its developed motion extrapolated back to "
            "the onset thresholds, rockbench.studies.tilting); the error is that onset at the "
            "slower rate against the static factor of limit analysis with real "
            "(non-associative) Coulomb joints. The onset lags the threshold by ∝ rate^(2/3), "
            "which the extrapolated column removes."],
            [_tilting_table(tilting)]))
    if collapse is not None:
        sec = Section("collapse", "Pulse to collapse", [
            "For each assembly, engine and pulse frequency, the smallest one-sine peak "
            "acceleration that collapses the assembly, by bisection on the amplitude "
            f"(tolerance {100 * collapse.rtol:g} %; rockbench.studies.collapse). A run "
            "collapses if a block overturns, or if at the end of the run (the pulse plus "
            f"{FREE_TIME:g} s of still base) a block stays turned by more than "
            f"{RESIDUAL_ROTATION:g} λ or lower than at rest by more than {RESIDUAL_DROP:g} of "
            "its height; blocks that only translated (by more than "
            f"{RESIDUAL_DISPLACEMENT:g} of their size relative to the base, e.g. a wall "
            "sliding on the base) slid, which is not collapse. There is no analytic dynamic "
            "reference "
            "for a multi-block assembly: the figures show the engines' spread and the "
            "static factor α, the low-frequency limit."], [_collapse_table(collapse)])
        for sc in scenarios:
            if any(collapse.curve(sc.name, e) for e in collapse.engines):
                path = collapse_figure(out / "figures" / f"collapse-{sc.name}.png", collapse, sc)
                files.append(path)
                sec.items.append(FigureItem(str(path.relative_to(out)),
                                            f"pulse to collapse of {sc.name}"))
        sections.append(sec)
    if tilting or collapse is not None:
        sections.append(Section("cost", "Cost", [
            "CPU seconds of every run, summed per engine and study, in-process on this "
            "machine."], [_cost_table(tilting, collapse)]))
    header = [("Date", time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())),
              ("Machine", cpu_model()), ("Python", platform.python_version()),
              ("rockbench", provenance.describe())]
    if wall_time is not None:
        header.append(("Wall time", f"{wall_time:.1f} s"))
    if command:
        header.append(("Command", command))
    doc = Document("rockbench: masonry assemblies up to collapse", header, [
        "Multi-block dry-joint assemblies (drum columns, parapets, running-bond walls, "
        "voussoir arches) in physics engines and the DEM, against the static collapse "
        "factor and mechanism of rigid-block limit analysis."], sections, CITATION)
    files.append(_write_csv(out / "results.csv", tilting, collapse))
    html, md = write_document(doc, out, embed=embed, data=("results.csv",))
    return files + [md, html]
