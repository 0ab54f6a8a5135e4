"""The wobbling report: which engines keep planar rocking planar, and what the paper saw.

:func:`write_report` renders a :class:`~rockbench.studies.wobbling.WobblingResult`: the
verdict of every method on the symmetric and the asymmetric base motion (max |roll|,
max |twist|, whether halving the step gives the same), every run with its time step,
drift across the plane, peak and error against the planar reference, the paper's
findings beside them, two figures (roll and twist against time per engine; the centroid's
path seen from above) and ``wobbling.csv`` with every run.
"""

from __future__ import annotations

import csv
import math
import textwrap
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from rockbench.report.document import (
    Document,
    FigureItem,
    Section,
    report_date,
    run_header,
)
from rockbench.report.html import write_document
from rockbench.report.tables import Cell, Table
from rockbench.studies.wobbling import (
    CONVERGENCE_TOLERANCE,
    PAPER,
    Convergence,
    Variant,
    Verdict,
    WobblingResult,
    WobblingVerdict,
)

__all__ = ["write_report", "angles_figure", "path_figure", "summary", "CITATION"]

_DPI = 110
#: Floor of the logarithmic angle axes (rad): smaller values (round-off) are drawn on it.
_FLOOR = 1e-12
#: The paper, and the origin of the word.
CITATION = ("E. Giordano, Y. Han, A. Wang, G. Destro Bisol, S. Andrews, D. Malomo, "
            "\u201cDiscontinuum rocking of rigid masonry macro-blocks using physics engines: "
            "analytical, numerical and experimental benchmarking\u201d, Structures (2025), "
            "doi:10.1016/j.istruc.2025.110027 (the shake-table tests: Pe\u00f1a et al. 2008)")

_VERDICT_KIND = {Verdict.STAYS_PLANAR: "", Verdict.WOBBLES: "overturned",
                 Verdict.PLANAR_BY_CONSTRUCTION: "ref", Verdict.UNSUPPORTED: "unsupported",
                 Verdict.FAILED: "crashed"}


def _g(v: float | None, fmt: str = "{:.2g}") -> str:
    return fmt.format(v) if v is not None and math.isfinite(v) else "–"


def _pct(v: float | None) -> str:
    return f"{100 * v:+.1f} %" if v is not None and math.isfinite(v) else "–"


def _measured(result: WobblingResult) -> list[str]:
    """Labels of the methods that may leave the plane (in the methods' order)."""
    by = {v.method for v in result.verdicts if v.verdict is Verdict.PLANAR_BY_CONSTRUCTION}
    return [m.label for m in result.methods if m.label not in by]


def _max_abs(a: np.ndarray) -> float:
    return float(np.max(np.abs(a))) if a.size else 0.0


def _envelope(t: np.ndarray, v: np.ndarray, n: int = 1500) -> tuple[np.ndarray, np.ndarray]:
    """|v| as its running maximum over windows (at most ``n`` points), floored."""
    a = np.maximum(np.abs(v), _FLOOR)
    k = max(1, int(math.ceil(a.size / n)))
    m = a.size // k * k
    if m == 0:
        return t, a
    return t[:m:k], a[:m].reshape(-1, k).max(axis=1)


def angles_figure(path: Path, result: WobblingResult) -> Path:
    """|roll| and |twist| against time: a row per method that may leave the plane, a column
    per variant; the planar threshold as a dashed line."""
    rows = _measured(result)
    fig = Figure(figsize=(10.0, 1.0 + 1.9 * max(1, len(rows))))
    FigureCanvasAgg(fig)
    limit = result.options.threshold * result.lam
    top = max([limit * 10] + [float(np.max(np.abs(a))) for s in result.series
                              for a in (s.roll, s.twist) if a.size and s.method in rows])
    axes = fig.subplots(max(1, len(rows)), 2, sharex=True, sharey=True, squeeze=False)
    for i, label in enumerate(rows or ["(no 3D engine)"]):
        for j, variant in enumerate(Variant):
            ax = axes[i][j]
            s = result.series_of(label, variant)
            v = next((x for x in result.verdicts if x.method == label and x.variant == variant),
                     None)
            if s is not None:
                ax.semilogy(*_envelope(s.t, s.roll), color="#1f77b4", linewidth=0.9,
                            label="|roll| (about x)")
                ax.semilogy(*_envelope(s.t, s.twist), color="#d62728", linewidth=0.9,
                            label="|twist| (about the block's z)")
                if max(_max_abs(s.roll), _max_abs(s.twist)) < _FLOOR:
                    ax.text(0.5, 0.3, f"both below {_FLOOR:g} rad (round-off)",
                            transform=ax.transAxes, ha="center", fontsize=8, color="0.3")
            else:
                why = v.row.message if v is not None else "not run"
                ax.text(0.5, 0.5, textwrap.fill(f"no samples: {why}", 60)[:300],
                        transform=ax.transAxes, ha="center", va="center", fontsize=7)
                ax.set_yscale("log")
            ax.axhline(limit, color="0.3", linestyle="--", linewidth=0.9,
                       label=f"threshold {result.options.threshold:g} λ")
            ax.set_ylim(_FLOOR / 3, top * 5)
            title = f"{label}, {variant}"
            if v is not None:
                title += f": {v.verdict}"
            ax.set_title(title, fontsize=9)
            ax.grid(True, which="major", alpha=0.3)
            if j == 0:
                ax.set_ylabel("rad")
    for ax in axes[-1]:
        ax.set_xlabel("t (s)")
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="upper center", ncol=3, fontsize=8)
    fig.tight_layout(rect=(0.0, 0.0, 1.0, 1.0 - 0.45 / fig.get_figheight()))
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=_DPI)
    return path


def _unit(v: float) -> tuple[float, str]:
    for scale, name in ((1e3, "mm"), (1e6, "µm"), (1e9, "nm")):
        if v * scale >= 1.0:
            return scale, name
    return 1.0, "m"  # round-off: metres, with the axis's power of ten


def path_figure(path: Path, result: WobblingResult) -> Path:
    """The bottom block's centroid seen from above (x–y, relative to its start), a panel
    per method that may leave the plane, both variants overlaid; y in its own unit."""
    rows = _measured(result)
    n = max(1, len(rows))
    ncol = 2 if n > 1 else 1
    nrow = int(math.ceil(n / ncol))
    fig = Figure(figsize=(5.0 * ncol, 0.6 + 2.6 * nrow))
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrow, ncol, squeeze=False)
    colors = {Variant.SYMMETRIC: "#1f77b4", Variant.ASYMMETRIC: "#ff7f0e"}
    for k, label in enumerate(rows or ["(no 3D engine)"]):
        ax = axes[k // ncol][k % ncol]
        got = [s for s in (result.series_of(label, v) for v in Variant) if s is not None]
        peak = max([float(np.max(np.abs(s.y))) for s in got if s.y.size] + [0.0])
        scale, unit = _unit(peak) if peak > 0 else (1e6, "µm")
        for s in got:
            step = max(1, s.t.size // 4000)
            ax.plot(1e3 * s.x[::step], scale * s.y[::step], color=colors[s.variant],
                    linewidth=0.6, label=str(s.variant))
        if not got:
            ax.text(0.5, 0.5, "no samples", transform=ax.transAxes, ha="center")
        ax.set_title(label, fontsize=9)
        ax.set_xlabel("x − x(0) (mm)")
        ax.set_ylabel(f"y − y(0) − u_gy ({unit})")
        ax.grid(True, alpha=0.3)
        if got:
            ax.legend(fontsize=7, loc="best")
    for k in range(len(rows or [""]), nrow * ncol):
        axes[k // ncol][k % ncol].set_visible(False)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=_DPI)
    return path


def _verdict_cells(v: WobblingVerdict | None) -> list[Cell | str]:
    if v is None:
        return ["–"] * 4
    kind = _VERDICT_KIND[v.verdict]
    r = v.row
    by = v.verdict is Verdict.PLANAR_BY_CONSTRUCTION
    return [Cell(str(v.verdict), kind=kind, title=v.note),
            "0" if by else _g(r.max_roll), "0" if by else _g(r.max_twist),
            Cell(str(v.convergence), title=v.note)]


def _verdict_table(result: WobblingResult) -> Table:
    lim = result.options.threshold * result.lam
    t = Table(
        key="verdicts", title="Table 1. Who keeps it planar",
        caption=(f"Per method, on the base motion exactly along x (symmetric) and with a y "
                 f"component ε = {result.options.asymmetry:g} times it (asymmetric): the "
                 f"verdict at the preset's time step (stays planar: max |roll| and max |twist| "
                 f"≤ {result.options.threshold:g} λ = {lim:.3g} rad), those maxima (rad), and "
                 f"whether the halved time step gives the same (both planar, or within "
                 f"{100 * CONVERGENCE_TOLERANCE:.0f} %). Peak and error: max |θ|/λ on the "
                 "symmetric variant against the planar reference. CPU: every run of the "
                 "method."),
        columns=["method", "verdict", "max |roll|", "max |twist|", "converged",
                 "verdict", "max |roll|", "max |twist|", "converged",
                 "peak |θ|/λ", "error vs reference", "CPU (s)"],
        groups=[("", 1), ("symmetric", 4), (f"asymmetric (ε = {result.options.asymmetry:g})",
                                            4), ("", 3)])
    for m in result.methods:
        vs = {v.variant: v for v in result.verdicts if v.method == m.label}
        sym = vs.get(Variant.SYMMETRIC)
        cpu = sum(r.cpu_time for r in result.rows if r.method == m.label)
        row = [Cell(m.label, kind="head"), *_verdict_cells(sym),
               *_verdict_cells(vs.get(Variant.ASYMMETRIC)),
               _g(sym.row.peak, "{:.4f}") if sym else "–",
               _pct(sym.row.peak_error) if sym else "–", f"{cpu:.1f}"]
        t.add_row(row)
    return t


def _runs_table(result: WobblingResult) -> Table:
    t = Table(
        key="runs", title="Table 2. Every run",
        caption=("Rung 0: the preset's time step; rung 1: halved. Drift: the largest |y − y(0) "
                 "− u_gy(t)|, how far the centroid leaves the plane the base carries it in "
                 "(lean and slip across the plane). Error: (peak − reference peak) / reference "
                 "peak, both variants against the planar reference."),
        columns=["method", "variant", "rung", "Δt (s)", "status", "max |roll| (rad)",
                 "max |twist| (rad)", "max wobble (rad)", "drift (m)", "peak |θ|/λ",
                 "error", "CPU (s)"])
    for r in result.rows:
        status: Cell | str = (r.status.value if r.status.value == "ok"
                              else t.status_cell(r.status.value, r.message, r.method))
        t.add_row([Cell(r.method, kind="head"), str(r.variant), str(r.rung),
                   _g(r.timestep, "{:.3g}"), status, _g(r.max_roll), _g(r.max_twist),
                   _g(r.max_wobble), _g(r.max_drift), _g(r.peak, "{:.4f}"), _pct(r.peak_error),
                   f"{r.cpu_time:.2f}"])
    return t


def _paper_table() -> Table:
    t = Table(key="paper", title="Table 3. What the paper reports on this case",
              caption=("Giordano et al. (2025), Single #2 under the 5 Hz / 6 mm sinusoid: "
                       "whether each method rotated about a second axis, and Table 7's error "
                       "of max |θ| against the shake-table test (magnitude; the sign is not "
                       "printed, the analytical model underestimates)."),
              columns=["method", "wobbled", "Table 7: max |θ| vs experiment", "note"])
    for p in PAPER:
        wob = "planar by construction" if p.wobbled is None else "yes" if p.wobbled else "no"
        err = "collapsed" if p.error is None else f"{100 * p.error:.0f} %"
        t.add_row([Cell(p.method, kind="head"), Cell(wob, kind="paper"),
                   Cell(err, kind="paper"), p.note])
    return t


def _names(vs: list[WobblingVerdict]) -> str:
    return ", ".join(v.method for v in vs) or "none"


def summary(result: WobblingResult) -> list[str]:
    """The findings in sentences: who stays planar, wobbles, converges; the paper."""
    out = []
    for variant in Variant:
        vs = [v for v in result.verdicts if v.variant is variant]
        by = {k: [v for v in vs if v.verdict is k] for k in Verdict}
        conv = [v for v in vs if v.convergence is Convergence.NOT_CONVERGED]
        text = (f"{str(variant).capitalize()} base motion: stays planar: "
                f"{_names(by[Verdict.STAYS_PLANAR])}; wobbles: {_names(by[Verdict.WOBBLES])}; "
                f"planar by construction: {_names(by[Verdict.PLANAR_BY_CONSTRUCTION])}")
        if by[Verdict.UNSUPPORTED]:
            text += f"; unsupported (no y base motion): {_names(by[Verdict.UNSUPPORTED])}"
        if by[Verdict.FAILED]:
            text += f"; failed: {_names(by[Verdict.FAILED])}"
        if conv:
            text += f". Not converged when the step is halved: {_names(conv)}"
        out.append(text + ".")
    out.append(
        f"The reference stays planar: the y acceleration that lifts one end of the rocking "
        f"edge is {result.uplift_ratio:.3g} times the asymmetric variant's largest "
        f"(g·(d/2)/h_c); below it the y motion only carries the block along. The paper saw "
        "Vortex and 3DEC wobble on this case, Bullet and the shake-table block not.")
    return out


def _write_csv(result: WobblingResult, path: Path) -> Path:
    verdicts = {(v.method, v.variant): v for v in result.verdicts}
    with path.open("w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(["method", "engine", "preset", "variant", "rung", "timestep", "status",
                    "verdict", "convergence", "max_roll", "max_twist", "max_wobble",
                    "max_drift", "peak", "peak_error", "cpu_time", "lambda", "message"])
        for r in result.rows:
            v = verdicts.get((r.method, r.variant))
            rung0 = r.rung == 0 and v is not None
            w.writerow([r.method, r.engine, r.preset, r.variant.value, r.rung, r.timestep,
                        r.status.value, v.verdict.value if rung0 and v else "",
                        v.convergence.value if rung0 and v else "", r.max_roll, r.max_twist,
                        r.max_wobble, r.max_drift, r.peak, r.peak_error, r.cpu_time, r.lam,
                        r.message])
    return path


def write_report(result: WobblingResult, out: Path, *, embed_figures: bool = True
                 ) -> list[Path]:
    """Write ``index.html``, ``report.md``, ``wobbling.csv`` and ``figures/``.

    Returns
    -------
    list of Path
        The files written (figures excluded).
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    csv_path = _write_csv(result, out / "wobbling.csv")
    opts = result.options
    sec = Section("verdicts", "Who keeps planar rocking planar")
    sec.paragraphs += summary(result)
    sec.items.append(_verdict_table(result))
    fig1 = angles_figure(out / "figures" / "wobbling-angles.png", result)
    sec.items.append(FigureItem(str(fig1.relative_to(out)), (
        "|roll| (rotation about x) and |twist| (about the block's own vertical axis) against "
        f"time, running maxima, on a log scale (values below {_FLOOR:g} rad, round-off, drawn "
        "at the bottom); dashed: the planar threshold. Methods planar by construction are "
        "left out (both are 0)."), "Out-of-plane rotation"))
    fig2 = path_figure(out / "figures" / "wobbling-path.png", result)
    sec.items.append(FigureItem(str(fig2.relative_to(out)), (
        "The bottom block's centroid seen from above, relative to its start: x (rocking and "
        "the base's motion) against y less the base's y displacement u_gy (zero on the "
        "symmetric variant), i.e. how far the block leaves the plane the base carries it in "
        "(its own unit per panel). A run that stays planar stays on the line y = 0."),
        "Path seen from above"))
    runs = Section("runs", "Every run")
    runs.items.append(_runs_table(result))
    paper = Section("paper", "The paper")
    paper.paragraphs.append(
        "Giordano et al. ran this case in Bullet (inside Blender), Vortex and 3DEC: Vortex "
        "and 3DEC rotated the block about a second axis (wobbling), Bullet and the shake-table "
        "block did not. Their Table 7 gives each method's error of max |θ| against the test.")
    paper.items.append(_paper_table())
    ref = result.reference_peak
    header = [
        ("Date", report_date()),
        ("Scenario", f"{result.scenario.name} ({result.scenario.duration:g} s); asymmetric: "
                     f"{result.asymmetric.name}"),
        ("λ", f"{result.lam:.5f} rad; planar threshold {opts.threshold:g} λ = "
              f"{opts.threshold * result.lam:.3g} rad"),
        ("Reference", f"planar, max |θ|/λ = {_g(ref, '{:.4f}')}"),
        ("Runs", f"{result.ran + result.reused}: {result.ran} run now, {result.reused} "
                 "reused"),
        *run_header(result.wall_time, opts.execution.jobs, result.versions, opts.command),
    ]
    doc = Document(
        title="rockbench wobbling report", header=header,
        intro=["The paper's wobbling case, free in 3D: the block rocks about its long edge "
               "under a base motion exactly along x (a principal axis) and with a tiny y "
               "component. The rigid-body reference stays planar in both; an engine that "
               "rolls or twists adds its own out-of-plane motion."],
        sections=[sec, runs, paper], citation=CITATION)
    index, md = write_document(doc, out, embed=embed_figures, data=("wobbling.csv",))
    return [index, md, csv_path]

