"""Run a comparison (scenarios × engines × presets + the analytic reference) and write
its report: ``index.html``, ``report.md``, ``results.csv``, ``trajectories/``, ``figures/``.

This is the Python API behind ``rockbench compare``::

    from rockbench.report.compare import CompareOptions, run_comparison
    run_comparison(CompareOptions(scenarios=[...], engines=["mujoco"], out=Path("report")))
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

import rockbench
from rockbench.engines import engine_class
from rockbench.report import sensitivity as sens
from rockbench.report.comparison import (
    Context,
    error_table,
    free_tables,
    overview_table,
    paper_experiment_table,
    paper_findings,
    peak_tables,
    timing_table,
)
from rockbench.report.document import (
    Bullets,
    Document,
    FigureItem,
    Section,
    cpu_model,
    python_version,
    render_document_markdown,
)
from rockbench.report.figures import (
    SpeedPoint,
    accuracy_speed_figure,
    method_styles,
    peak_input_figure,
    time_history_figure,
    variations_speed_figure,
)
from rockbench.report.html import render_document_html
from rockbench.report.paper import citation, paper_tables
from rockbench.report.results import (
    REFERENCE,
    ResultsWriter,
    Run,
    compute_row,
    group_title,
    load_finished,
    method_slug,
    order_rows,
    run_slug,
    save_trajectory,
    scenario_group,
)
from rockbench.runner import Job, run_jobs
from rockbench.scenarios import Scenario, get_scenario
from rockbench.trajectory import Trajectory

__all__ = ["CompareOptions", "CompareResult", "run_comparison", "default_timeout",
           "method_label"]


def default_timeout(scenario: Scenario) -> float:
    """Generous per-run wall-time limit: 5 min plus 1 min per simulated second."""
    return 300.0 + 60.0 * scenario.duration


def method_label(engine: str, preset: str, several: bool) -> str:
    """``mujoco`` with a single preset, ``mujoco[fast]`` with several."""
    return f"{engine}[{preset}]" if several and engine != REFERENCE else engine


@dataclass
class CompareOptions:
    """What to compare and where to write it.

    Attributes
    ----------
    scenarios : list of Scenario
        The cases (may be empty with ``sensitivity_only``).
    engines : list of str
        Engines to run (the analytic reference is always run as well).
    out : Path
        Report directory.
    presets : list of str
        Each engine runs once per preset (method ``engine[preset]`` when several).
    overrides : dict
        Per engine, knob overrides applied on top of every preset (``--set``).
    jobs : int
        Parallel worker processes (1 gives clean timings).
    timeout : float or None
        Per-run wall-time limit in s (None: :func:`default_timeout`).
    resume : bool
        Reuse finished runs found in ``out/trajectories`` with identical settings
        hash, scenario and engine version.
    sensitivity : bool
        Also run the Table 2 sensitivity study on B0.
    isolate : bool
        Run each job in a child process (crash and hang protection).
    suite : str
        Name shown in the report header.
    command : str
        The command line shown in the report header.
    quiet : bool
        No progress output.
    embed_figures : bool
        Embed PNGs in index.html as base64 (else link ``figures/``).
    """

    scenarios: list[Scenario]
    engines: list[str]
    out: Path
    presets: list[str] = field(default_factory=lambda: ["accurate"])
    overrides: dict[str, dict[str, Any]] = field(default_factory=dict)
    jobs: int = 1
    timeout: float | None = None
    resume: bool = False
    sensitivity: bool = False
    isolate: bool = True
    suite: str = ""
    command: str = ""
    quiet: bool = False
    embed_figures: bool = True


@dataclass
class CompareResult:
    """What a comparison did and wrote."""

    out: Path
    rows: list[dict[str, Any]]
    ran: int
    reused: int
    wall_time: float
    files: list[Path]


# ------------------------------------------------------------------------- planning
class _Planner:
    def __init__(self, opts: CompareOptions) -> None:
        self.opts = opts
        self.versions: dict[str, str] = {}

    def version(self, engine: str) -> str:
        if engine not in self.versions:
            self.versions[engine] = engine_class(engine).version()
        return self.versions[engine]

    def make_run(self, job: Job, method: str, preset: str, variation: str,
                 knobs: Mapping[str, Any]) -> Run:
        cls = engine_class(job.engine)
        s = dict(job.settings)
        digest = cls.settings(s.pop("preset", None), **s).digest()
        return Run(job=job, method=method, preset=preset, variation=variation,
                   settings_hash=digest, engine_version=self.version(job.engine),
                   knobs=dict(knobs))

    def reference_run(self, scenario: Scenario) -> Run:
        return self.make_run(Job(scenario, REFERENCE, {}, label=REFERENCE), REFERENCE, "", "",
                             {})

    def main_runs(self) -> tuple[list[Run], list[str]]:
        o = self.opts
        engines = [e for e in o.engines if e != REFERENCE]
        several = len(o.presets) > 1
        methods = [REFERENCE] + [method_label(e, p, several) for e in engines
                                 for p in o.presets]
        runs = []
        for s in o.scenarios:
            runs.append(self.reference_run(s))
            for e in engines:
                for p in o.presets:
                    settings = {"preset": p, **o.overrides.get(e, {})}
                    label = method_label(e, p, several)
                    runs.append(self.make_run(Job(s, e, settings, label=label), label, p, "",
                                              {}))
        return runs, methods


# ------------------------------------------------------------------------- running
class _Recorder:
    """Stores each finished run, writes CSV rows as soon as the reference is known."""

    def __init__(self, out: Path, runs: Sequence[Run], writer: ResultsWriter) -> None:
        self.out = out
        self.runs = list(runs)
        self.writer = writer
        self.trajs: dict[tuple[str, str], Trajectory] = {}
        self.rows: dict[tuple[str, str], dict[str, Any]] = {}
        self.ref_planned = {r.scenario.name for r in runs if r.is_reference and not r.variation}

    def add(self, run: Run, traj: Trajectory, *, save: bool) -> None:
        if save:
            save_trajectory(self.out, run, traj)
        self.trajs[run.key] = traj
        self._flush(run.scenario.name)

    def _reference(self, scenario: str) -> tuple[bool, Trajectory | None, str]:
        if scenario not in self.ref_planned:
            return True, None, "no analytic reference was run"
        ref = self.trajs.get((scenario, REFERENCE))
        if ref is None:
            return False, None, ""
        if not ref.t.size:
            return True, None, f"no analytic reference ({ref.status}: {ref.message})"
        return True, ref, ""

    def _flush(self, scenario: str) -> None:
        ready, ref, reason = self._reference(scenario)
        if not ready:
            return
        for run in self.runs:
            key = run.key
            if run.scenario.name != scenario or key in self.rows or key not in self.trajs:
                continue
            path = trajectory_rel(run)
            row = compute_row(run, self.trajs[key], ref, ref_reason=reason, trajectory=path)
            self.rows[key] = row
            self.writer.append(row)


def trajectory_rel(run: Run) -> str:
    """Path of a run's trajectory relative to the report directory."""
    return f"trajectories/{method_slug(run.scenario.name)}/{run_slug(run)}.npz"


def run_comparison(opts: CompareOptions,
                   progress: Callable[[int, str], Any] | None = None) -> CompareResult:
    """Run every planned job (reusing finished ones with ``resume``) and write the report.

    Parameters
    ----------
    opts : CompareOptions
        What to run and where to write.
    progress : callable, optional
        ``progress(total, description)`` returns a context manager with an
        ``advance(text)`` method (e.g. :class:`rockbench.cli.Progress`).

    Returns
    -------
    CompareResult
        Rows, counts of runs executed and reused, total wall time, files written.
    """
    start = time.perf_counter()
    out = Path(opts.out)
    out.mkdir(parents=True, exist_ok=True)
    planner = _Planner(opts)
    runs, methods = planner.main_runs()
    b0: Scenario | None = None
    variations: list[sens.Variation] = []
    skipped: list[sens.Skipped] = []
    if opts.sensitivity:
        b0 = get_scenario(sens.SCENARIO)
        base = {e: {"preset": opts.presets[0], **opts.overrides.get(e, {})}
                for e in opts.engines}
        srun, variations, skipped = sens.plan_sensitivity(
            [e for e in opts.engines if e != REFERENCE], b0, base=base,
            make_run=planner.make_run)
        if not any(r.is_reference and r.scenario.name == b0.name for r in runs):
            runs.append(planner.reference_run(b0))
        runs += srun
    max_blocks = max([r.scenario.n_blocks for r in runs] + [1])
    writer = ResultsWriter(out / "results.csv", max_blocks)
    rec = _Recorder(out, runs, writer)
    todo: list[Run] = []
    reused = 0
    for run in runs:
        traj = load_finished(out, run) if opts.resume else None
        if traj is None:
            todo.append(run)
        else:
            rec.add(run, traj, save=False)
            reused += 1
    by_job = {id(r.job): r for r in todo}

    def limit(job: Job) -> float:
        return opts.timeout if opts.timeout else default_timeout(job.scenario)

    cm = progress(len(todo), "compare") if progress else contextlib.nullcontext(None)
    with cm as bar:
        def on_result(job: Job, traj: Trajectory) -> None:
            run = by_job[id(job)]
            rec.add(run, traj, save=True)
            if bar is not None:
                bar.advance(f"{run.scenario.name} {run.method} {traj.status}")

        if todo:
            run_jobs([r.job for r in todo], n_jobs=opts.jobs, timeout=limit,
                     isolate=opts.isolate, on_result=on_result)
    scen_names = [s.name for s in opts.scenarios] + ([b0.name] if b0 else [])
    all_methods = methods + [r.method for r in runs if r.method not in methods]
    rows = [dict(r) for r in order_rows(list(rec.rows.values()), scen_names, all_methods)]
    writer.rewrite(rows)
    files = [out / "results.csv"]
    doc_files = _write_report(opts, out, runs, methods, rec, rows, b0, variations, skipped,
                              planner, start, ran=len(todo), reused=reused)
    files += doc_files
    return CompareResult(out=out, rows=rows, ran=len(todo), reused=reused,
                         wall_time=time.perf_counter() - start, files=files)


# ------------------------------------------------------------------------- the report
def _speed_points(rows: Sequence[Mapping[str, Any]], methods: Sequence[str]) -> list[SpeedPoint]:
    points = []
    for m in methods:
        if m == REFERENCE:
            continue
        rs = [r for r in rows if r["method"] == m]
        done = [r for r in rs if r["status"] in ("ok", "overturned") and r["simulated_time"] > 0]
        sim = sum(r["simulated_time"] for r in done)
        if sim > 0:
            cost = sum(r["wall_time"] for r in done) / sim
        else:  # nothing completed: place the cross at wall time per requested second
            dur = sum(r["duration"] for r in rs)
            cost = sum(r["wall_time"] for r in rs) / dur if dur > 0 else math.nan
        errs = [r["max_error"] for r in rs if r["status"] == "ok" and math.isfinite(r["max_error"])]
        peaks = [abs(v) for r in rs if r["status"] == "ok"
                 for k, v in r.items() if k.startswith("peak_error_")
                 and isinstance(v, float) and math.isfinite(v)]
        points.append(SpeedPoint(
            method=m, cost=cost, error=float(np.median(errs)) if errs else math.nan,
            peak_error=float(np.median(peaks)) if peaks else math.nan,
            failed=sum(r["status"] != "ok" for r in rs), total=len(rs)))
    return points


def _history_methods(runs: Sequence[Run], methods: Sequence[str],
                     presets: Sequence[str]) -> list[str]:
    """Methods drawn in time histories: the reference and each engine at its first preset."""
    first = {r.method for r in runs if not r.variation and r.preset == presets[0]}
    return [m for m in methods if m == REFERENCE or m in first]


def _hms(seconds: float) -> str:
    s = int(round(seconds))
    return f"{s // 3600:d}:{s % 3600 // 60:02d}:{s % 60:02d} ({seconds:.1f} s)"


def _group_scenarios(scenarios: Sequence[Scenario]) -> dict[str, list[Scenario]]:
    groups: dict[str, list[Scenario]] = {}
    for s in scenarios:
        groups.setdefault(scenario_group(s), []).append(s)
    return groups


def _write_report(opts: CompareOptions, out: Path, runs: Sequence[Run], methods: list[str],
                  rec: _Recorder, rows: list[dict[str, Any]], b0: Scenario | None,
                  variations: Sequence[sens.Variation], skipped: Sequence[sens.Skipped],
                  planner: _Planner, start: float, *, ran: int, reused: int) -> list[Path]:
    main_rows = [r for r in rows if not r["variation"]]
    ctx = Context(opts.scenarios, methods, main_rows)
    styles = method_styles(methods)
    fig_dir = out / "figures"
    sections: list[Section] = []

    def fig(path: Path, caption: str, title: str = "") -> FigureItem:
        return FigureItem(path=str(path.relative_to(out)), caption=caption, title=title)

    groups = _group_scenarios(opts.scenarios)
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
                "crosses on the top edge; '(k/n not ok)' counts runs that failed, overturned or "
                "were unsupported."), "Accuracy versus speed"))
        sections.append(ov)
    for group, scen in groups.items():
        sec = Section(f"group-{group}", group_title(group))
        sec.paragraphs.append(_group_intro(group, scen))
        if group == "free":
            sec.items += free_tables(ctx, scen)
        else:
            sec.items += peak_tables(ctx, group, scen)
            if ctx.engines:
                sec.items.append(error_table(ctx, group, scen))
            exp = paper_experiment_table(ctx, scen) if group == "single-sine" else None
            if exp is not None:
                sec.items.append(exp)
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
        shown = _history_methods(runs, methods, opts.presets)
        for s in scen:
            trajs = {m: rec.trajs[(s.name, m)] for m in shown if (s.name, m) in rec.trajs}
            p = time_history_figure(fig_dir / f"history-{method_slug(s.name)}.png", s, trajs,
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
    if opts.scenarios:
        tsec = Section("timing", "Cost: wall time and real-time factor")
        tsec.paragraphs.append(
            "Wall-clock times exclude process start-up; each run is timed inside its own "
            "worker process" + (" (one run at a time, so timings do not compete for cores)."
                                if opts.jobs == 1 else
                                f" ({opts.jobs} runs in parallel: timings may be inflated)."))
        tsec.items.append(timing_table(ctx))
        sections.append(tsec)
    if b0 is not None:
        sections.append(_sensitivity_section(out, b0, variations, skipped, rows, rec, fig,
                                             ctx.next_number()))
    sections.append(_files_section(opts, rows))
    settings_desc = "; ".join(
        f"{r.method}: {r.settings_hash}" for r in runs
        if r.scenario.name == (opts.scenarios[0].name if opts.scenarios else "")
        and not r.variation)
    versions = ", ".join(f"{e} {planner.version(e)}" for e in
                         dict.fromkeys([REFERENCE, *opts.engines]))
    header = [
        ("Date", _dt.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M:%S %Z")),
        ("Suite", f"{opts.suite or 'custom'} ({len(opts.scenarios)} scenarios"
                  f"{', + sensitivity study' if b0 else ''})"),
        ("Total wall time", _hms(time.perf_counter() - start)),
        ("Runs", f"{ran} run now, {reused} reused from a previous run (--resume)"),
        ("rockbench", rockbench.__version__),
        ("Python", python_version()),
        ("Machine (CPU)", cpu_model()),
        ("Engine versions", versions),
        ("Presets", ", ".join(opts.presets)
         + (f"; overrides {opts.overrides}" if any(opts.overrides.values()) else "")),
        ("Settings hashes", settings_desc or "–"),
        ("Command", opts.command or "(Python API)"),
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
    # the header's wall time is re-measured just before writing
    doc.header[2] = ("Total wall time", _hms(time.perf_counter() - start))
    md = out / "report.md"
    md.write_text(render_document_markdown(doc), encoding="utf-8")
    index = out / "index.html"
    index.write_text(render_document_html(doc, out, embed=opts.embed_figures), encoding="utf-8")
    return [index, md]


def _group_intro(group: str, scen: Sequence[Scenario]) -> str:
    s = scen[0]
    if group == "free":
        return ("Free rocking from rest at an initial tilt (paper Section 4, blocks B0–B3, "
                "20 s). Housner's equation with η = 1 − 2mb²/I_O is the reference; an engine "
                "that dissipates too little keeps rocking, one that dissipates too much stops "
                "early.")
    text = (f"{len(scen)} case(s); λ = {s.critical_angle:.4f} rad for the first "
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


def _sensitivity_section(out: Path, b0: Scenario, variations: Sequence[sens.Variation],
                         skipped: Sequence[sens.Skipped], rows: Sequence[Mapping[str, Any]],
                         rec: _Recorder, fig: Callable[..., FigureItem],
                         number: int) -> Section:
    sec = Section("sensitivity", "Sensitivity study (paper Table 2)")
    sec.paragraphs.append(
        "The paper varied Bullet's solver iterations {10, 100, 1000}, collision shape {box, "
        "convex hull, mesh}, margin {1e-3, 1e-5, 1e-6 m}, sub-steps {2, 20, 200} and rate "
        "{10, 50, 240 fps} on B0. Here each variation is applied to every engine's closest "
        "knob, one at a time from its accurate preset. Engines with only a time step get "
        f"Δt = 1/((n_s + 1)·FPS) with FPS = {sens.SUBSTEP_FPS:g} for the sub-step study and "
        f"n_s = {sens.RATE_SUBSTEPS} for the rate study.")
    srows = {r["method"]: r for r in rows if r["variation"] and r["scenario"] == b0.name}
    ref_row = next((r for r in rows if r["scenario"] == b0.name and r["method"] == REFERENCE
                    and not r["variation"]), None)
    sec.items.append(sens.sensitivity_table(number, b0, variations, skipped, srows, ref_row))
    trajs = {m: t for (sn, m), t in rec.trajs.items() if sn == b0.name}
    ref = rec.trajs.get((b0.name, REFERENCE))
    for p, cap in sens.sensitivity_figures(out, b0, variations, trajs, ref):
        sec.items.append(fig(p, cap, f"Sensitivity: {p.stem.removeprefix('sensitivity-')}"))
    methods = [f"{v.engine}[{v.label}]" for v in variations]
    if methods:
        pts = _speed_points([r for r in rows if r["variation"] and r["scenario"] == b0.name],
                            methods)
        p = variations_speed_figure(
            out / "figures" / "sensitivity-accuracy-speed.png", pts,
            {f"{v.engine}[{v.label}]": v.engine for v in variations},
            {f"{v.engine}[{v.label}]": v.knob for v in variations},
            f"{b0.name}: every Table 2 variation, error against Housner versus cost")
        sec.items.append(fig(p, (
            "Every sensitivity variation as one point: colour = engine, marker = the knob "
            "varied; x = wall time per simulated second, y = max |θ − θ_ref|/λ against "
            "Housner on B0. The dashed line is the Pareto front (its points are labelled and "
            "black-edged); crosses on the top edge are variations that did not finish ok "
            "(see the table for their status and reason)."),
            "Sensitivity: accuracy versus speed"))
    return sec


def _files_section(opts: CompareOptions, rows: Sequence[Mapping[str, Any]]) -> Section:
    sec = Section("files", "Files and columns")
    sec.paragraphs.append(
        f"results.csv holds {len(rows)} rows (one per scenario × method, plus sensitivity "
        "variations marked in the 'variation' column). Columns: status and message (the "
        "reason of a non-ok status); peak_ratio_i = max |θ_i|/λ of block i (1 = bottom); "
        "max_error = max |θ − θ_ref|/λ; peak_error_i = signed relative peak error against the "
        "reference; impact_error_k = relative error of the k-th impact time; time_to_rest "
        "(|θ| < 0.01 λ from then on); error_note = why an error is missing; wall_time (s), "
        "time_per_simulated_second, realtime_factor; settings_hash, scenario_hash and "
        "engine_version identify a run for --resume; trajectory = the .npz time history "
        "(+ .json sidecar with settings and status) under trajectories/.")
    return sec
