"""The comparison study: scenarios × engines × presets, plus the analytic reference.

Each run's trajectory is written under ``DIR/trajectories/<scenario>/<method>.npz``
(+ ``.json`` sidecar, atomically) and its :class:`~rockbench.evaluation.RunMetrics`
recorded in the results store as soon as it finishes, so an interrupted
comparison loses nothing; ``--resume`` finds finished runs in the store (same
scenario content, method, engine and rockbench versions) and reads their
trajectories back, re-running those whose file is missing or torn.

This is the Python API behind ``rockbench compare``::

    from rockbench.studies.compare import CompareOptions, run_comparison
    result = run_comparison(CompareOptions(scenarios=[...], engines=["mujoco"], out=Path("r")))

Rendering the report from the result is :func:`rockbench.report.compare_report.write_report`.
"""

from __future__ import annotations

import contextlib
import time
import zipfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import rockbench
from rockbench import analytic
from rockbench.engines import engine_class
from rockbench.errors import RockbenchError
from rockbench.evaluation import RunResult
from rockbench.method import REFERENCE, Method, slug
from rockbench.runner import ExecutionOptions, Job, run_jobs
from rockbench.scenarios import Scenario, scenario_to_dict
from rockbench.store import Store
from rockbench.studies import sensitivity as sens
from rockbench.studies.ensembles import EnsembleComparison, compare_ensembles, run_ensembles
from rockbench.studies.predictability import (
    DEFAULT_MEMBERS,
    Perturbation,
    Predictability,
    predictability,
)
from rockbench.studies.recording import measure, record_run, settings_hash
from rockbench.studies.references import NO_MODEL, references
from rockbench.trajectory import Status, Trajectory

__all__ = ["CompareOptions", "CompareResult", "PlannedRun", "run_comparison", "default_timeout",
           "KIND"]

#: The store's ``kind`` of runs made by this study.
KIND = "compare"
#: Statuses that --resume runs again (possibly transient failures).
_RERUN = {Status.CRASHED, Status.TIMEOUT}


def default_timeout(scenario: Scenario) -> float:
    """Generous per-run wall-time limit: 5 min plus 1 min per simulated second."""
    return 300.0 + 60.0 * scenario.duration


@dataclass
class CompareOptions:
    """What to compare, where to write it and how to run it.

    Attributes
    ----------
    scenarios : list of Scenario
        The cases (may be empty with ``sensitivity``).
    engines : list of str
        Engines to run (the analytic reference is always run as well).
    out : Path
        Report directory (the trajectories go to ``out/trajectories``).
    presets : list of str
        Each engine runs once per preset (label ``engine[preset]`` when several).
    overrides : dict
        Per engine, knob overrides applied on top of every preset (``--settings``, ``--set``).
    execution : ExecutionOptions
        Workers, executor and isolation (one worker gives clean timings).
    timeout : float or None
        Per-run wall-time limit in s; None: :func:`default_timeout` of each
        scenario (``execution.timeout`` is not used).
    resume : bool
        Reuse finished runs found in the store.
    db : Path or None
        The results store (None: record nothing; ``resume`` then has nothing to read).
    sensitivity : bool
        Also run the Table 2 sensitivity study on B0.
    sensitivity_from : str or None
        The preset its variations start from (with ``overrides``); None: each
        engine's ``sensitivity_preset`` (``accurate``, Blender's ``paper``).
    suite : str
        Suite name (stored with the runs, shown in the report header).
    command : str
        The command line shown in the report header.
    embed_figures : bool
        Embed PNGs in index.html as base64 (else link ``figures/``).
    horizon_members : int
        Perturbed reference runs per scenario that measure its predictability
        horizon t* (errors are measured up to t*); 0: none, the whole run is compared.
    ensemble : int
        Perturbed members per scenario and method whose peak distributions are
        compared beyond t* (``--ensemble``); 0: off.
    perturbation : Perturbation
        The perturbations of both ensembles.
    """

    scenarios: list[Scenario]
    engines: list[str]
    out: Path
    presets: list[str] = field(default_factory=lambda: ["accurate"])
    overrides: dict[str, dict[str, Any]] = field(default_factory=dict)
    execution: ExecutionOptions = field(default_factory=ExecutionOptions)
    timeout: float | None = None
    resume: bool = False
    db: Path | None = None
    sensitivity: bool = False
    sensitivity_from: str | None = None
    suite: str = ""
    command: str = ""
    embed_figures: bool = True
    horizon_members: int = DEFAULT_MEMBERS
    ensemble: int = 0
    perturbation: Perturbation = field(default_factory=Perturbation)


@dataclass(frozen=True)
class PlannedRun:
    """One run of the comparison before it ran.

    Attributes
    ----------
    scenario : Scenario
        What to simulate.
    method : Method
        Engine and settings.
    """

    scenario: Scenario
    method: Method

    @property
    def job(self) -> Job:
        """What the runner executes."""
        return Job(self.scenario, self.method.engine, self.method.settings,
                   label=self.method.label)

    @property
    def trajectory(self) -> str:
        """Its trajectory file, relative to the report directory."""
        return f"trajectories/{slug(self.scenario.name)}/{self.method.slug}.npz"


@dataclass
class CompareResult:
    """What a comparison ran and found.

    Attributes
    ----------
    options : CompareOptions
        What was asked.
    runs : list of PlannedRun
        Every planned run, in report order.
    results : list of RunResult
        One per planned run, in report order.
    trajectories : dict
        (scenario name, method label) → trajectory.
    methods : list of Method
        The main comparison's methods, in column order (the reference first).
    variations, skipped
        The sensitivity study's plan (empty without it).
    b0 : Scenario or None
        The sensitivity study's scenario.
    versions : dict
        Engine → library version.
    ran, reused : int
        Runs executed now and runs taken from the store.
    wall_time : float
        Wall time of the study in s.
    predictability : dict
        Scenario name → its horizon t* (scenarios with an analytic model).
    ensembles : list of EnsembleComparison
        Each engine's peak distributions against the reference's (``ensemble`` > 0).
    """

    options: CompareOptions
    runs: list[PlannedRun]
    results: list[RunResult]
    trajectories: dict[tuple[str, str], Trajectory]
    methods: list[Method]
    variations: list[sens.Variation]
    skipped: list[sens.Skipped]
    b0: Scenario | None
    versions: dict[str, str]
    ran: int
    reused: int
    wall_time: float
    predictability: dict[str, Predictability] = field(default_factory=dict)
    ensembles: list[EnsembleComparison] = field(default_factory=list)


def _plan(opts: CompareOptions) -> tuple[list[PlannedRun], list[Method], Scenario | None,
                                         list[sens.Variation], list[sens.Skipped]]:
    engines = [e for e in opts.engines if e != REFERENCE]
    several = len(opts.presets) > 1
    methods = [Method.reference()] + [
        Method.of(e, {"preset": p, **opts.overrides.get(e, {})}, qualified=several)
        for e in engines for p in opts.presets]
    runs = [PlannedRun(s, m) for s in opts.scenarios for m in methods]
    b0: Scenario | None = None
    variations: list[sens.Variation] = []
    skipped: list[sens.Skipped] = []
    if opts.sensitivity:
        b0 = sens.sensitivity_scenario()
        base = {e: {"preset": opts.sensitivity_from or engine_class(e).sensitivity_preset,
                    **opts.overrides.get(e, {})} for e in engines}
        planned, variations, skipped = sens.plan_sensitivity(engines, base=base)
        if not any(r.method.is_reference and r.scenario.name == b0.name for r in runs):
            runs.append(PlannedRun(b0, Method.reference()))
        runs += [PlannedRun(b0, m) for m in planned]
    _check_names(runs)
    return runs, methods, b0, variations, skipped


def _check_names(runs: Sequence[PlannedRun]) -> None:
    """Two scenarios whose names map to one file name would overwrite each other's runs."""
    seen: dict[str, Scenario] = {}
    for r in runs:
        key = slug(r.scenario.name)
        other = seen.setdefault(key, r.scenario)
        if other is not r.scenario and other != r.scenario:
            raise RockbenchError(f"scenarios {other.name!r} and {r.scenario.name!r} would share "
                                 f"the result files of {key!r}: give them distinct names")


def load_trajectory(path: Path) -> Trajectory | None:
    """A stored trajectory, or None if it is missing, empty or torn (it is then rerun)."""
    try:
        return Trajectory.load(path)
    except (OSError, ValueError, KeyError, TypeError, EOFError, zipfile.BadZipFile):
        return None


def run_comparison(opts: CompareOptions,
                   progress: Callable[[int, str], Any] | None = None) -> CompareResult:
    """Run every planned job (reusing stored ones with ``resume``) and return the results.

    The analytic references are computed first (or taken from the store's
    cache), so that every engine run is evaluated and recorded as it finishes.

    Parameters
    ----------
    opts : CompareOptions
        What to run and where.
    progress : callable, optional
        ``progress(total, description)`` returns a context manager with an
        ``advance(text)`` method (e.g. :class:`rockbench.cli.common.Progress`).

    Raises
    ------
    RockbenchError
        Bad input: ``resume`` without a store, colliding scenario names, an
        unknown engine or bad settings.
    """
    start = time.perf_counter()
    if opts.resume and opts.db is None:
        raise RockbenchError("--resume reads finished runs from the results store: "
                             "drop --no-db (or give --db FILE)")
    out = Path(opts.out)
    runs, methods, b0, variations, skipped = _plan(opts)
    versions = {e: engine_class(e).version()
                for e in dict.fromkeys([REFERENCE, *(r.method.engine for r in runs)])}
    store = Store(opts.db) if opts.db is not None else None
    with store if store is not None else contextlib.nullcontext():
        trajs: dict[tuple[str, str], Trajectory] = {}
        results: dict[tuple[str, str], RunResult] = {}
        todo: list[PlannedRun] = []
        for run in runs:
            traj = _stored(store, run, out, versions) if opts.resume else None
            if traj is None:
                todo.append(run)
            else:
                trajs[(run.scenario.name, run.method.label)] = traj
        reused = len(runs) - len(todo)

        horizons: dict[str, Predictability] = {}

        def finished(run: PlannedRun, traj: Trajectory, *, record: bool) -> None:
            ref = trajs.get((run.scenario.name, REFERENCE))
            pred = horizons.get(run.scenario.name)
            m = measure(run.scenario, run.method, traj, ref,
                        engine_version=versions[run.method.engine],
                        horizon=pred.t_star if pred is not None else None)
            res = RunResult(run.scenario, run.method, m, run.trajectory)
            results[res.key] = res
            if record:
                record_run(store, run.scenario, run.method, traj, m, kind=KIND,
                           suite=opts.suite, trajectory=str((out / run.trajectory).resolve()))

        ref_runs = [r for r in todo if r.method.is_reference]
        engine_runs = [r for r in todo if not r.method.is_reference]
        refs, _ = references([r.scenario for r in ref_runs], store, execution=opts.execution)
        for run in ref_runs:
            traj = refs[run.scenario.name] or Trajectory.failed(
                Status.UNSUPPORTED, NO_MODEL, n_blocks=run.scenario.n_blocks,
                engine=REFERENCE, scenario=run.scenario.name)
            _save(out, run, traj)
            trajs[(run.scenario.name, REFERENCE)] = traj
        if opts.horizon_members:
            cases = list({r.scenario.name: r.scenario for r in runs}.values())
            horizons.update(predictability(
                cases, members=opts.horizon_members, perturbation=opts.perturbation,
                store=store, execution=opts.execution,
                nominal={s.name: trajs.get((s.name, REFERENCE)) for s in cases}))
        for run in ref_runs:
            finished(run, trajs[(run.scenario.name, REFERENCE)], record=True)
        jobs = [r.job for r in engine_runs]
        by_job = {id(job): run for job, run in zip(jobs, engine_runs, strict=True)}
        cm = progress(len(jobs), "compare") if progress else contextlib.nullcontext(None)
        with cm as bar:
            def on_result(job: Job, traj: Trajectory) -> None:
                run = by_job[id(job)]
                _save(out, run, traj)
                trajs[(run.scenario.name, run.method.label)] = traj
                finished(run, traj, record=True)
                if bar is not None:
                    bar.advance(f"{run.scenario.name} {run.method.label} {traj.status}")

            if jobs:
                run_jobs(jobs, opts.execution, on_result=on_result, timeout_of=_limit(opts))
        for run in runs:  # reused runs, evaluated against the (possibly reused) reference
            key = (run.scenario.name, run.method.label)
            if key not in results and key in trajs:
                finished(run, trajs[key], record=False)
        ensembles: list[EnsembleComparison] = []
        if opts.ensemble:
            n_jobs = opts.ensemble * (len(methods) - 1) * sum(
                analytic.has_reference(s) for s in opts.scenarios)
            cm = progress(n_jobs, "ensembles") if progress else contextlib.nullcontext(None)
            with cm as bar:
                def on_member(job: Job, traj: Trajectory) -> None:
                    if bar is not None:
                        bar.advance(f"{job.scenario.name} {job.label} {traj.status}")

                dists = run_ensembles(opts.scenarios, methods, opts.ensemble,
                                      opts.perturbation, store=store,
                                      execution=opts.execution, timeout_of=_limit(opts),
                                      on_result=on_member)
            ensembles = compare_ensembles(dists)
    ordered = [results[(r.scenario.name, r.method.label)] for r in runs
               if (r.scenario.name, r.method.label) in results]
    return CompareResult(options=opts, runs=runs, results=ordered, trajectories=trajs,
                         methods=methods, variations=variations, skipped=skipped, b0=b0,
                         versions=versions, ran=len(todo), reused=reused,
                         wall_time=time.perf_counter() - start, predictability=horizons,
                         ensembles=ensembles)


def _limit(opts: CompareOptions) -> Callable[[Job], float]:
    """Each run's time limit: ``opts.timeout``, else :func:`default_timeout` of its scenario."""
    def limit(job: Job) -> float:
        return opts.timeout if opts.timeout else default_timeout(job.scenario)
    return limit


def _save(out: Path, run: PlannedRun, traj: Trajectory) -> None:
    traj.scenario = traj.scenario or run.scenario.name
    # the file of a method is reused by later runs with other overrides: the hash
    # tells --resume whose trajectory it holds
    traj.extra = {**traj.extra, "method": run.method.label, "variation": run.method.variation,
                  "settings_hash": settings_hash(run.method)}
    traj.save(out / run.trajectory, scenario=scenario_to_dict(run.scenario))


def _stored(store: Store | None, run: PlannedRun, out: Path,
            versions: dict[str, str]) -> Trajectory | None:
    """The finished trajectory of ``run`` from the store, or None (then it is run)."""
    if store is None:
        return None
    rec = store.find(run.scenario, run.method, engine_version=versions[run.method.engine],
                     rockbench_version=rockbench.__version__)
    if rec is None or rec.status in _RERUN:
        return None
    path = Path(rec.trajectory) if rec.trajectory else out / run.trajectory
    traj = load_trajectory(path)
    if traj is None or traj.extra.get("settings_hash") != settings_hash(run.method):
        return None
    if path.resolve() != (out / run.trajectory).resolve():  # resumed into another folder
        _save(out, run, traj)
    return traj
