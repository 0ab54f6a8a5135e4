"""The one execution path of every study: plan → references → isolated jobs → metrics → store.

A study plans its runs (:class:`PlannedRun`: a scenario and a method) and hands
them to :func:`run_campaign`, which

1. takes each scenario's analytic reference from the store's cache or computes
   it (:func:`~rockbench.campaign.references.references`), and its
   predictability horizon t* where asked
   (:func:`~rockbench.campaign.predictability.predictability`);
2. with ``resume``, takes every run whose full identity
   (:class:`~rockbench.store.RunIdentity`: scenario content, engine and library
   version, resolved settings, code version) is in the store, and reruns the
   others (crashed and timed-out runs too);
3. runs the rest isolated and in parallel (:func:`rockbench.runner.run_jobs`);
4. measures every run once (:func:`rockbench.evaluation.evaluate_run`), records
   it in the store as it finishes and, where asked, archives its trajectory
   beside the store (written atomically), so an interrupted campaign loses
   nothing;

and returns typed results in the order planned. Studies plan and aggregate
only; reports render the results with options of their own.
"""

from __future__ import annotations

import contextlib
import time
import zipfile
from collections.abc import Callable, Collection, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rockbench.campaign.predictability import (
    Perturbation,
    Predictability,
    predictability,
)
from rockbench.campaign.references import references
from rockbench.campaign.standing import warn_cannot_stand
from rockbench.engines import engine_class
from rockbench.errors import RockbenchError
from rockbench.evaluation import RunMetrics, RunResult, evaluate_run
from rockbench.method import Method
from rockbench.runner import ExecutionOptions, Job, run_jobs
from rockbench.scenarios import Scenario, scenario_to_dict
from rockbench.store import RunIdentity, Store
from rockbench.trajectory import Status, Trajectory

__all__ = ["PlannedRun", "CampaignOptions", "Campaign", "run_campaign", "default_timeout",
           "RERUN"]

#: Statuses that ``resume`` runs again (possibly transient failures).
RERUN = frozenset({Status.CRASHED, Status.TIMEOUT})

#: ``progress(total, description)`` → a context manager with ``advance(text)``.
Progress = Callable[[int, str], Any]


def default_timeout(scenario: Scenario) -> float:
    """Generous per-run wall-time limit: 5 min plus 1 min per simulated second."""
    return 300.0 + 60.0 * scenario.duration


@dataclass(frozen=True)
class PlannedRun:
    """One run of a campaign before it ran: a scenario and a method.

    Attributes
    ----------
    scenario : Scenario
        What to simulate.
    method : Method
        Engine and settings (the analytic reference is ``Method.reference()``).
    suite : str
        Stored with the run instead of the campaign's suite ('' : the campaign's),
        e.g. the record and its provenance of a fragility run.
    """

    scenario: Scenario
    method: Method
    suite: str = ""

    @property
    def key(self) -> tuple[str, str]:
        """(scenario name, method label): how results are looked up."""
        return (self.scenario.name, self.method.label)

    @property
    def job(self) -> Job:
        """What the runner executes."""
        return Job(self.scenario, self.method.engine, self.method.settings,
                   label=self.method.label)


@dataclass(frozen=True)
class CampaignOptions:
    """How a campaign runs and what it keeps.

    Attributes
    ----------
    kind : str
        The study (the store's ``kind`` of its runs: ``compare``, ``matrix``...).
    suite : str
        Suite or set name, stored with the runs.
    db : Path or None
        The results store (None: record nothing; ``resume`` needs one).
    resume : bool
        Reuse stored runs of the same identity.
    archive : bool
        Keep every run's trajectory in the store's archive (needs ``db``): a
        resumed run then also gives back its trajectory.
    keep : bool
        Return every trajectory in memory (:attr:`Campaign.trajectories`).
    execution : ExecutionOptions
        Workers, time limit, executor, isolation.
    timeout : float or None
        Per-run wall-time limit in s; None: :func:`default_timeout` of each scenario.
    references : bool
        Measure the runs against the analytic references (computed or taken
        from the store's cache); False for studies whose reference is another
        (the tilting table's limit analysis).
    horizon_members : int
        Perturbed reference runs per scenario that measure its predictability
        horizon t* (errors stop there); 0: none.
    horizon_for : collection of str, optional
        The scenarios whose horizon is measured (None: every one with a reference).
    perturbation : Perturbation
        The perturbations of those ensembles.
    """

    kind: str
    suite: str = ""
    db: Path | None = None
    resume: bool = False
    archive: bool = False
    keep: bool = False
    execution: ExecutionOptions = field(default_factory=ExecutionOptions)
    timeout: float | None = None
    references: bool = True
    horizon_members: int = 0
    horizon_for: Collection[str] | None = None
    perturbation: Perturbation = field(default_factory=Perturbation)

    def __post_init__(self) -> None:
        if self.resume and self.db is None:
            raise RockbenchError("--resume reads finished runs from the results store: "
                                 "drop --no-db (or give --db FILE)")

    def limit(self, job: Job) -> float:
        """The time limit of a run."""
        return self.timeout if self.timeout else default_timeout(job.scenario)


@dataclass
class Campaign:
    """What a campaign ran and measured.

    Attributes
    ----------
    results : list of RunResult
        One per planned run, in plan order.
    trajectories : dict
        (scenario name, method label) → trajectory, with ``keep`` (and the
        references, always).
    references : dict
        Scenario name → its analytic reference (None where no model covers it).
    reference_notes : dict
        Scenario name → why it has no usable reference.
    horizons : dict
        Scenario name → its predictability horizon (where measured).
    versions : dict
        Engine → library version.
    ran, reused : int
        Runs executed now and runs taken from the store.
    wall_time : float
        Wall time of the campaign (s).
    """

    results: list[RunResult]
    trajectories: dict[tuple[str, str], Trajectory]
    references: dict[str, Trajectory | None]
    reference_notes: dict[str, str]
    horizons: dict[str, Predictability]
    versions: dict[str, str]
    ran: int
    reused: int
    wall_time: float

    def result(self, scenario: str, method: str) -> RunResult | None:
        """The result of one run, by scenario name and method label."""
        return next((r for r in self.results if r.key == (scenario, method)), None)


def _resolved(method: Method) -> dict[str, Any]:
    """Every knob's value of ``method``'s settings (raises SettingsError for bad ones)."""
    return engine_class(method.engine).resolve_settings(method.settings).to_dict()


def load_trajectory(path: Path) -> Trajectory | None:
    """A stored trajectory, or None if it is missing, empty or torn (it is then rerun)."""
    try:
        return Trajectory.load(path)
    except (OSError, ValueError, KeyError, TypeError, EOFError, zipfile.BadZipFile):
        return None


class _Context:
    """The state one campaign shares between its steps."""

    def __init__(self, plan: Sequence[PlannedRun], opts: CampaignOptions,
                 store: Store | None) -> None:
        self.plan, self.opts, self.store = plan, opts, store
        engines = dict.fromkeys(r.method.engine for r in plan)
        # bad settings are refused here, before anything runs
        self.resolved = {r.method: _resolved(r.method) for r in plan}
        self.versions = {e: engine_class(e).version() for e in engines}
        self.identities = {i: RunIdentity.of(r.scenario, r.method,
                                             engine_version=self.versions[r.method.engine],
                                             resolved=self.resolved[r.method])
                           for i, r in enumerate(plan)}
        self.results: dict[int, RunResult] = {}
        self.trajectories: dict[tuple[str, str], Trajectory] = {}
        self.refs: dict[str, Trajectory | None] = {}
        self.notes: dict[str, str] = {}
        self.horizons: dict[str, Predictability] = {}

    def archive_path(self, i: int) -> Path | None:
        """Where run ``i``'s trajectory is archived (None: not archived)."""
        if not self.opts.archive or self.store is None or self.store.archive is None:
            return None
        ident = self.identities[i]
        run = self.plan[i]
        return (self.store.archive / ident.scenario_hash /
                f"{run.method.slug}-{ident.resolved_key}-{ident.code_version.split('+')[-1]}"
                ".npz")

    def stored(self, i: int) -> tuple[RunMetrics, Trajectory | None] | None:
        """Run ``i`` from the store (with its archived trajectory when one is needed)."""
        if not self.opts.resume or self.store is None:
            return None
        rec = self.store.find(self.identities[i])
        if rec is None or rec.status in RERUN or rec.metrics is None:
            return None
        if not (self.opts.archive or self.opts.keep):
            return rec.metrics, None
        traj = load_trajectory(Path(rec.trajectory)) if rec.trajectory else None
        return None if traj is None else (rec.metrics, traj)

    def finish(self, i: int, traj: Trajectory | None, *, record: bool,
               metrics: RunMetrics | None = None) -> RunResult:
        """Measure (unless ``metrics`` are given: a reused run, whose trajectory may be
        None), archive and record run ``i``; keep its result."""
        run = self.plan[i]
        sc = run.scenario
        if metrics is None:
            assert traj is not None
            pred = self.horizons.get(sc.name)
            metrics = evaluate_run(
                sc, traj, self.refs.get(sc.name), is_reference=run.method.is_reference,
                settings_hash=self.identities[i].resolved_key,
                scenario_hash=self.identities[i].scenario_hash,
                engine_version=self.versions[run.method.engine],
                reference_note=self.notes.get(sc.name, ""),
                horizon=pred.t_star if pred is not None else None)
        path = self.archive_path(i)
        if record and traj is not None and path is not None:
            traj.scenario = traj.scenario or sc.name
            traj.save(path, scenario=scenario_to_dict(sc))
        if record and traj is not None and self.store is not None:
            self.store.record(sc, run.method, traj, metrics, self.identities[i],
                              kind=self.opts.kind, suite=run.suite or self.opts.suite,
                              trajectory=str(path) if path is not None else "")
        res = RunResult(sc, run.method, metrics, str(path) if path is not None else "",
                        reused=not record)
        self.results[i] = res
        if traj is not None and (self.opts.keep or run.method.is_reference):
            self.trajectories[run.key] = traj
        return res


def run_campaign(plan: Sequence[PlannedRun], options: CampaignOptions, *,
                 progress: Progress | None = None,
                 on_result: Callable[[RunResult, Trajectory | None], None] | None = None
                 ) -> Campaign:
    """Run a campaign (module docstring) and return its typed results.

    Parameters
    ----------
    plan : sequence of PlannedRun
        The runs, in the order the results are returned. Runs of
        ``Method.reference()`` take the analytic reference itself.
    options : CampaignOptions
        Store, resume, archive, execution, horizons.
    progress : callable, optional
        ``progress(total, description)`` → a context manager with ``advance(text)``.
    on_result : callable, optional
        Called as ``on_result(result, trajectory)`` as each run finishes (the
        trajectory is None for a run reused without one).

    Raises
    ------
    RockbenchError
        Bad input (an unknown engine, bad settings, ``resume`` without a store).
    """
    start = time.perf_counter()
    store = Store(options.db) if options.db is not None else None
    with store if store is not None else contextlib.nullcontext():
        ctx = _Context(plan, options, store)
        scenarios = list({r.scenario.name: r.scenario for r in plan}.values())
        warn_cannot_stand(scenarios)
        refs: dict[str, Trajectory | None] = {}
        notes: dict[str, str] = {}
        if options.references or any(r.method.is_reference for r in plan):
            refs, notes = references(scenarios, store, execution=options.execution)
        ctx.refs, ctx.notes = refs, notes
        if options.horizon_members:
            timed = [s for s in scenarios
                     if options.horizon_for is None or s.name in options.horizon_for]
            ctx.horizons = predictability(
                timed, members=options.horizon_members, perturbation=options.perturbation,
                store=store, execution=options.execution, nominal=refs) if timed else {}
        todo: list[int] = []
        fresh = 0  # reference runs recorded now (their trajectory is at hand, no job)
        for i, run in enumerate(plan):
            old = ctx.stored(i)
            if old is not None:
                metrics, traj = old
                _report(on_result, ctx.finish(i, traj, record=False, metrics=metrics), traj)
            elif run.method.is_reference:
                ref = refs.get(run.scenario.name) or Trajectory.failed(
                    Status.UNSUPPORTED, notes.get(run.scenario.name, ""),
                    n_blocks=run.scenario.n_blocks, engine=run.method.engine,
                    scenario=run.scenario.name)
                _report(on_result, ctx.finish(i, ref, record=True), ref)
                fresh += 1
            else:
                todo.append(i)
        jobs = [plan[i].job for i in todo]
        index = {id(job): i for job, i in zip(jobs, todo, strict=True)}
        with _bar(progress, len(jobs), options.kind) as bar:
            def done(job: Job, traj: Trajectory) -> None:
                res = ctx.finish(index[id(job)], traj, record=True)
                _report(on_result, res, traj)
                if bar is not None:
                    bar.advance(f"{job.scenario.name} {res.method.label} {traj.status}")

            size = _batch(options.execution)
            for b in range(0, len(jobs), size):
                run_jobs(jobs[b:b + size], options.execution, on_result=done,
                         timeout_of=options.limit)
    return Campaign(results=[ctx.results[i] for i in range(len(plan))],
                    trajectories=ctx.trajectories, references=refs, reference_notes=notes,
                    horizons=ctx.horizons, versions=ctx.versions, ran=len(todo) + fresh,
                    reused=len(plan) - len(todo) - fresh,
                    wall_time=time.perf_counter() - start)


def _batch(execution: ExecutionOptions) -> int:
    """Jobs per :func:`run_jobs` call: each call keeps its trajectories until it returns,
    so a local campaign of thousands of runs goes in batches; a Dask cluster takes the
    whole campaign at once (a local one starts once per call)."""
    if execution.executor == "dask":
        return 1 << 62
    return max(64, 16 * execution.jobs)


def _report(on_result: Callable[[RunResult, Trajectory | None], None] | None,
            res: RunResult, traj: Trajectory | None) -> None:
    if on_result is not None:
        on_result(res, traj)


@contextlib.contextmanager
def _bar(progress: Progress | None, total: int, what: str) -> Iterator[Any]:
    if progress is None or not total:
        yield None
        return
    with progress(total, what) as bar:
        yield bar

