"""The comparison report: ``index.html`` and ``report.md`` from a :class:`CompareResult`,
``results.csv`` (one row per run, :mod:`rockbench.report.results_csv`) and every run's
time history under ``trajectories/``.

Everything here is drawn from the typed results of
:func:`rockbench.studies.compare.run_comparison`; nothing is simulated or
measured here.
"""

from __future__ import annotations

import dataclasses
import datetime as _dt
import math
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from rockbench import provenance
from rockbench.analytic import critical_angle
from rockbench.evaluation import RunResult
from rockbench.method import REFERENCE, Method, slug
from rockbench.report.comparison import (
    Context,
    group_tables,
    overview_table,
    paper_findings,
    timing_table,
)
from rockbench.report.document import (
    Bullets,
    Document,
    FigureItem,
    Section,
    cpu_model,
    python_version,
)
from rockbench.report.ensemble_report import predictability_section, write_ensemble_files
from rockbench.report.figures import (
    SpeedPoint,
    accuracy_speed_figure,
    method_styles,
    peak_input_figure,
    time_history_figure,
    variations_speed_figure,
)
from rockbench.report.groups import group_title, scenario_group
from rockbench.report.html import write_document
from rockbench.report.options import ReportOptions
from rockbench.report.paper import citation, paper_tables
from rockbench.report.results_csv import ResultsWriter
from rockbench.report.sensitivity_report import sensitivity_figures, sensitivity_table
from rockbench.report.verdict_report import verdict_section
from rockbench.scenarios import Scenario, scenario_to_dict
from rockbench.studies import sensitivity as sens
from rockbench.studies.compare import CompareResult
from rockbench.trajectory import Status

__all__ = ["write_report", "write_results_csv"]


def trajectory_file(r: RunResult) -> str:
    """Where a run's time history lies in the report folder (relative path)."""
    return f"trajectories/{slug(r.scenario.name)}/{r.method.slug}.npz"


def write_trajectories(result: CompareResult, out: Path) -> list[RunResult]:
    """Every run's time history under ``out/trajectories`` (``.npz`` + ``.json`` sidecar,
    atomically); returns the results with their file in the report."""
    rows = []
    for r in result.results:
        traj = result.trajectories.get(r.key)
        if traj is None:
            rows.append(dataclasses.replace(r, trajectory=""))
            continue
        traj.extra = {**traj.extra, "method": r.method.label, "variation": r.method.variation}
        traj.save(out / trajectory_file(r), scenario=scenario_to_dict(r.scenario))
        rows.append(dataclasses.replace(r, trajectory=trajectory_file(r)))
    return rows


def write_results_csv(result: CompareResult, out: Path,
                      rows: Sequence[RunResult] | None = None) -> Path:
    """``results.csv`` in ``out``: one row per run, in report order (written atomically)."""
    max_blocks = max([r.scenario.n_blocks for r in result.runs] + [1])
    writer = ResultsWriter(out / "results.csv", max_blocks)
    writer.rewrite(result.results if rows is None else rows)
    return writer.path


def write_report(result: CompareResult, options: ReportOptions,
                 start: float | None = None) -> list[Path]:
    """Write ``results.csv``, ``index.html``, ``report.md``, the figures and trajectories.

    Parameters
    ----------
    result : CompareResult
        From :func:`rockbench.studies.compare.run_comparison`.
    options : ReportOptions
        The report folder, the command shown, whether figures are embedded.
    start : float, optional
        ``time.perf_counter()`` when the study began (the header's total wall
        time); default: the study's own wall time.

    Returns
    -------
    list of Path
        The files written (figures and trajectories excluded).
    """
    out = Path(options.out)
    files = [write_results_csv(result, out, write_trajectories(result, out))]
    files += write_ensemble_files(result, out)
    files += _write_document(result, options, start)
    return files


def _speed_points(rows: Sequence[RunResult], methods: Sequence[str]) -> list[SpeedPoint]:
    """One point per method label: cost per simulated second against median errors."""
    points = []
    for m in methods:
        if m == REFERENCE:
            continue
        rs = [r for r in rows if r.method.label == m]
        done = [r.metrics for r in rs if r.metrics.completed and r.metrics.simulated_time > 0]
        sim = sum(x.simulated_time for x in done)
        if sim > 0:
            cost = sum(x.wall_time for x in done) / sim
        else:  # nothing completed: place the cross at wall time per requested second
            dur = sum(r.metrics.duration for r in rs)
            cost = sum(r.metrics.wall_time for r in rs) / dur if dur > 0 else math.nan
        # a run that ends as its reference does (overturning where it overturns) is
        # compared; its error before the overturning is measured
        agree = [r.metrics for r in rs if _ends_as_reference(r)]
        errs = [x.max_error for x in agree if x.max_error is not None]
        peaks = [abs(v) for x in agree for v in x.peak_errors if v is not None]
        points.append(SpeedPoint(
            method=m, cost=cost, error=float(np.median(errs)) if errs else math.nan,
            peak_error=float(np.median(peaks)) if peaks else math.nan,
            failed=len(rs) - len(agree), total=len(rs), compared=len(errs)))
    return points


def _ends_as_reference(r: RunResult) -> bool:
    """The run completed and ended as its reference (or as ok where there is none)."""
    m = r.metrics
    ref = m.reference_status if m.reference_status is not None else Status.OK
    return m.status.completed and m.status is ref


def _history_methods(result: CompareResult) -> list[str]:
    """Methods drawn in time histories: the reference and each engine at its first preset."""
    first = result.options.presets[0]
    return [m.label for m in result.methods if m.is_reference or m.preset == first]


def _hms(seconds: float) -> str:
    s = int(round(seconds))
    return f"{s // 3600:d}:{s % 3600 // 60:02d}:{s % 60:02d} ({seconds:.1f} s)"


def _group_scenarios(scenarios: Sequence[Scenario]) -> dict[str, list[Scenario]]:
    groups: dict[str, list[Scenario]] = {}
    for s in scenarios:
        groups.setdefault(scenario_group(s), []).append(s)
    return groups


def _write_document(result: CompareResult, options: ReportOptions,
                    start: float | None) -> list[Path]:
    opts = result.options
    out = Path(options.out)
    rows = result.results
    methods = [m.label for m in result.methods]
    main_rows = [r for r in rows if not r.method.variation]
    ctx = Context(opts.scenarios, result.methods, main_rows)
    styles = method_styles(result.methods)
    fig_dir = out / "figures"
    sections: list[Section] = []

    def fig(path: Path, caption: str, title: str = "") -> FigureItem:
        return FigureItem(path=str(path.relative_to(out)), caption=caption, title=title)

    groups = _group_scenarios(opts.scenarios)
    if result.verdict is not None:
        sections.append(verdict_section(result.verdict, ctx.next_number))
    if opts.scenarios:
        ov = Section("overview", "Overview: accuracy and cost per method")
        ov.paragraphs.append(
            "Every scenario was run on every selected engine and on the analytic reference "
            "(Housner's single-block equation; the two-block model for stacks) with the "
            "same base kinematics. Angles are normalised by the scenario's critical angle λ "
            "(for stacks the smallest of each block's and the whole stack's, computed from the "
            "modelled geometry). Errors are measured against our analytic reference.")
        ov.items.append(overview_table(ctx, ctx.next_number()))
        points = _speed_points(main_rows, methods)
        if points:
            p = accuracy_speed_figure(fig_dir / "accuracy-speed.png", points, styles,
                                      subtitle=opts.suite)
            ov.items.append(fig(p, (
                "Each engine × settings preset is one point: x = its total wall time divided by "
                "the simulated time over the completed runs, y = the median over scenarios of "
                "(a) max |θ − θ_ref|/λ and (b) |Δpeak|/peak against the analytic reference. "
                "Points with a black edge lie on the Pareto front (dashed): no other method is "
                "both faster and more accurate. Methods with no successful comparison are "
                "crosses on the top edge; '(k/n unlike the reference)' counts runs that did not "
                "end as the reference did (an overturning the reference shares is compared "
                "up to it), '[k of n scenarios]' how many scenarios stand behind a point "
                "when not all do."), "Accuracy versus speed"))
        sections.append(ov)
    for group, scen in groups.items():
        sec = Section(f"group-{group}", group_title(group))
        sec.paragraphs.append(_group_intro(group, scen))
        sec.items += group_tables(ctx, group, scen)
        found = paper_findings(group, scen)
        if found is not None:
            sec.items.append(Bullets(*found))
        if group != "free" and any(not s.excitation.is_free for s in scen):
            published = []
            for pt in paper_tables().values():
                if pt.quantity != "peak_ratio":
                    continue
                for s in scen:
                    vals = pt.values(s)
                    if vals:
                        published += [(pt.block, m, float(v), s) for m, v in
                                      zip(pt.methods, vals, strict=True)
                                      if isinstance(v, (int, float))]
            p = peak_input_figure(fig_dir / f"peaks-{group}.png",
                                  f"{group_title(group)}: peak response against input",
                                  scen, methods, ctx.rows, styles, published)
            sec.items.append(fig(p, (
                "Maximum normalised rocking angle against the normalised input acceleration "
                "ü_g/(g tan λ), one marker per method (analytic reference: hollow black "
                "circles)" + ("; grey hollow markers: the paper's published values"
                              if published else "")
                + "; crosses on the dotted top line: runs that failed or overturned (paper "
                  "Figs. 8, 11, 13, 15)."), "Peak response against input"))
        shown = _history_methods(result)
        for s in scen:
            trajs = {m: result.trajectories[(s.name, m)] for m in shown
                     if (s.name, m) in result.trajectories}
            p = time_history_figure(fig_dir / f"history-{slug(s.name)}.png", s, trajs,
                                    styles)
            sec.items.append(fig(p, (
                (f"{s.description}. " if s.description else "") + "Rocking angle θ/λ against time"
                + (" for each block (top block above)" if s.n_blocks > 1 else "")
                + "; analytic reference as a wide grey band, engines in colour"
                + (f" at their {opts.presets[0]} preset (the other presets' histories are in "
                   "trajectories/)" if len(opts.presets) > 1 else "")
                + "; a cross marks where a run stopped (overturned, unstable, crashed)."),
                f"Time history, {s.name}"))
        sections.append(sec)
    psec = predictability_section(result, out, fig, ctx.next_number) if opts.scenarios else None
    if psec is not None:
        sections.append(psec)
    if opts.scenarios:
        tsec = Section("timing", "Cost: wall time and real-time factor")
        tsec.paragraphs.append(
            "Wall-clock times exclude process start-up; each run is timed inside its own "
            "worker process" + (" (one run at a time, so timings do not compete for cores)."
                                if opts.execution.jobs == 1 else
                                f" ({opts.execution.jobs} runs in parallel: timings may be "
                                "inflated)."))
        tsec.items.append(timing_table(ctx))
        sections.append(tsec)
    if result.b0 is not None:
        sections.append(_sensitivity_section(result, out, fig, ctx.next_number()))
    sections.append(_files_section(rows))
    first = opts.scenarios[0].name if opts.scenarios else ""
    settings_desc = "; ".join(f"{r.method.label}: {r.metrics.settings_hash}" for r in main_rows
                              if r.scenario.name == first)
    versions = ", ".join(f"{e} {v}" for e, v in result.versions.items())
    total = time.perf_counter() - start if start is not None else result.wall_time
    b0 = result.b0
    header = [
        ("Date", _dt.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M:%S %Z")),
        ("Suite", f"{opts.suite or 'custom'} ({len(opts.scenarios)} scenarios"
                  f"{', + sensitivity study' if b0 else ''})"),
        ("Total wall time", _hms(total)),
        ("Runs", f"{result.ran} run now, {result.reused} reused from a previous run "
                 "(--resume)"),
        ("rockbench", provenance.describe()),
        ("Python", python_version()),
        ("Machine (CPU)", cpu_model()),
        ("Engine versions", versions),
        ("Presets", ", ".join(opts.presets)
         + (f"; overrides {opts.overrides}" if any(opts.overrides.values()) else "")),
        ("Settings hashes", settings_desc or "–"),
        ("Command", options.command or "(Python API)"),
    ]
    doc = Document(
        title=f"rockbench comparison report — {opts.suite or 'custom suite'}",
        header=header,
        intro=[("A structural engineer's benchmark of physics engines on rigid-block "
                "rocking: every table below is laid out like the paper's, with our engines "
                "and our analytic reference side by side and, where the case is one of the "
                "paper's, its published values in italics. Raw numbers: results.csv (one row "
                "per scenario × method); raw time histories: trajectories/.")],
        sections=sections, citation=citation())
    return list(write_document(doc, out, embed=options.embed_figures,
                              data=("results.csv", "trajectories/")))


def _group_intro(group: str, scen: Sequence[Scenario]) -> str:
    s = scen[0]
    if group == "free":
        return ("Free rocking from rest at an initial tilt (paper Section 4, blocks B0–B3, "
                "20 s). Housner's equation with η = 1 − 2mb²/I_O is the reference; an engine "
                "that dissipates too little keeps rocking, one that dissipates too much stops "
                "early.")
    text = (f"{len(scen)} case(s); λ = {critical_angle(s.geometry):.4f} rad for the first "
            f"({s.name}). ")
    from rockbench.report.paper import is_catalog_case

    paper = all(is_catalog_case(x) for x in scen)
    if group.startswith("single") and paper:
        text += ("The paper's Single #2 granite block rocks about its 0.17 m side; λ is "
                 "computed from the modelled geometry, so ü_g/(g tan λ) differs from the "
                 "paper's printed ratio (which implies tan λ ≈ 0.2265).")
    elif group.startswith("stack") and paper:
        text += ("Two stacked, chamfered blocks (Peña et al. 2008). Angles are normalised by "
                 "the smallest critical angle of the system; block 1 is the bottom block "
                 "(the paper's Table 10), block 2 the top block (Table 9).")
    elif group.startswith("stack"):
        text += ("Angles are normalised by the smallest critical angle of the stack (each "
                 "block's own and the whole stack's).")
    return text


def _sensitivity_section(result: CompareResult, out: Path, fig: Callable[..., FigureItem],
                         number: int) -> Section:
    b0 = result.b0
    assert b0 is not None
    variations, skipped = result.variations, result.skipped
    sec = Section("sensitivity", "Sensitivity study (paper Table 2)")
    sec.paragraphs.append(
        "The paper varied Bullet's solver iterations {10, 100, 1000}, collision shape {box, "
        "convex hull, mesh}, margin {1e-3, 1e-5, 1e-6 m}, sub-steps {2, 20, 200} and rate "
        "{10, 50, 240 fps} on B0. Here each variation is applied to every engine's closest "
        "knob, one at a time from its accurate preset. Engines with only a time step get "
        f"Δt = 1/((n_s + 1)·FPS) with FPS = {sens.SUBSTEP_FPS:g} for the sub-step study and "
        f"n_s = {sens.RATE_SUBSTEPS} for the rate study.")
    var_rows = [r for r in result.results if r.method.variation and r.scenario.name == b0.name]
    srows = {r.method.label: r for r in var_rows}
    ref_row = next((r for r in result.results if r.scenario.name == b0.name
                    and r.method.is_reference), None)
    sec.items.append(sensitivity_table(number, b0, variations, skipped, srows, ref_row))
    trajs = {m: t for (sn, m), t in result.trajectories.items() if sn == b0.name}
    ref = result.trajectories.get((b0.name, REFERENCE))
    for p, cap in sensitivity_figures(out, b0, variations, trajs, ref):
        sec.items.append(fig(p, cap, f"Sensitivity: {p.stem.removeprefix('sensitivity-')}"))
    labels = {Method(v.engine, variation=v.label).label: v for v in variations}
    if labels:
        pts = _speed_points(var_rows, list(labels))
        p = variations_speed_figure(
            out / "figures" / "sensitivity-accuracy-speed.png", pts,
            {m: v.engine for m, v in labels.items()}, {m: v.knob for m, v in labels.items()},
            f"{b0.name}: every Table 2 variation, error against Housner versus cost")
        sec.items.append(fig(p, (
            "Every sensitivity variation as one point: colour = engine, marker = the knob "
            "varied; x = wall time per simulated second, y = max |θ − θ_ref|/λ against "
            "Housner on B0. The dashed line is the Pareto front (its points are labelled and "
            "black-edged); crosses on the top edge are variations that did not finish ok "
            "(see the table for their status and reason)."),
            "Sensitivity: accuracy versus speed"))
    return sec


def _files_section(rows: Sequence[RunResult]) -> Section:
    sec = Section("files", "Files and columns")
    sec.paragraphs.append(
        f"results.csv holds {len(rows)} rows (one per scenario × method, plus sensitivity "
        "variations marked in the 'variation' column). Columns: status and message (the "
        "reason of a non-ok status); peak_ratio_i = max |θ_i|/λ of block i (1 = bottom); "
        "max_error = max |θ − θ_ref|/λ (max_error_early: up to the reference's third "
        "impact); peak_error_i = signed relative peak error against the reference, over "
        "max(reference peak, 0.02 λ); impact_error_k = relative error of the k-th impact time "
        "(zero crossings after |θ| reached 0.01 λ, interpolated, the same for every method); "
        "horizon = the predictability horizon t* the errors stop at; time_to_rest "
        "(|θ| < 0.01 λ from then on); error_note = why an error is missing; wall_time and "
        "cpu_time (s), time_per_simulated_second, realtime_factor (simulated s per wall s); "
        "slide and max_wobble (bottom block sliding, m; out-of-plane rotation, rad); "
        "settings_hash, scenario_hash and engine_version identify a run (the store's "
        "--resume); trajectory = the .npz time history (+ .json sidecar with settings and "
        "status) under trajectories/.")
    return sec
