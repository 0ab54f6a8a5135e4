"""The comparison study: scenarios × engines × presets, plus the analytic reference.

The study plans its runs and hands them to the campaign
(:func:`rockbench.campaign.run_campaign`), which records each run in the
results store and archives its trajectory beside it as soon as it finishes, so
an interrupted comparison loses nothing; ``--resume`` takes every finished run
whose identity (scenario content, engine and library version, resolved
settings, code version) is in the store. Beyond each scenario's predictability
horizon the ensembles compare distributions (``ensemble``).

This is the Python API behind ``rockbench compare``::

    from rockbench.studies.compare import CompareOptions, run_comparison
    result = run_comparison(CompareOptions(scenarios=[...], engines=["mujoco"]))

Rendering the report from the result is :func:`rockbench.report.compare_report.write_report`.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rockbench.campaign import CampaignOptions, PlannedRun, run_campaign
from rockbench.campaign.predictability import DEFAULT_MEMBERS, Perturbation, Predictability
from rockbench.engines import engine_class
from rockbench.errors import RockbenchError
from rockbench.evaluation import RunResult
from rockbench.method import REFERENCE, Method, slug
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Scenario
from rockbench.studies import sensitivity as sens
from rockbench.studies.ensembles import EnsembleComparison, compare_ensembles, run_ensembles
from rockbench.studies.verdict import Verdict
from rockbench.studies.verify import verdict_of
from rockbench.trajectory import Trajectory

__all__ = ["CompareOptions", "CompareResult", "run_comparison", "KIND"]

#: The store's ``kind`` of runs made by this study.
KIND = "compare"


@dataclass
class CompareOptions:
    """What to compare, where to write it and how to run it.

    Attributes
    ----------
    scenarios : list of Scenario
        The cases (may be empty with ``sensitivity``).
    engines : list of str
        Engines to run (the analytic reference is always run as well).
    presets : list of str
        Each engine runs once per preset (label ``engine[preset]`` when several).
    overrides : dict
        Per engine, knob overrides applied on top of every preset (``--settings``, ``--set``).
    execution : ExecutionOptions
        Workers, executor and isolation.
    timeout : float or None
        Per-run wall-time limit in s; None: :func:`rockbench.campaign.default_timeout`
        of each scenario (``execution.timeout`` is not used).
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
    presets: list[str] = field(default_factory=lambda: ["accurate"])
    overrides: dict[str, dict[str, Any]] = field(default_factory=dict)
    execution: ExecutionOptions = field(default_factory=ExecutionOptions)
    timeout: float | None = None
    resume: bool = False
    db: Path | None = None
    sensitivity: bool = False
    sensitivity_from: str | None = None
    suite: str = ""
    horizon_members: int = DEFAULT_MEMBERS
    ensemble: int = 0
    perturbation: Perturbation = field(default_factory=Perturbation)


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
        (scenario name, method label) → trajectory (every run's).
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
    verdict : Verdict or None
        Each method judged against the closed forms (the main comparison's runs;
        scenarios without one are unverified: ``rockbench verify`` builds a consensus).
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
    verdict: Verdict | None = None


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
    runs, methods, b0, variations, skipped = _plan(opts)
    campaign = run_campaign(runs, CampaignOptions(
        kind=KIND, suite=opts.suite, db=opts.db, resume=opts.resume, archive=True, keep=True,
        execution=opts.execution, timeout=opts.timeout, horizon_members=opts.horizon_members,
        perturbation=opts.perturbation), progress=progress)
    ensembles: list[EnsembleComparison] = []
    if opts.ensemble:
        ensembles = compare_ensembles(run_ensembles(
            opts.scenarios, methods, opts.ensemble, opts.perturbation, db=opts.db,
            execution=opts.execution, timeout=opts.timeout, progress=progress))
    main = [r for r in campaign.results if not r.method.variation]
    verdict = verdict_of(main, campaign.references)[0] if opts.scenarios else None
    return CompareResult(options=opts, runs=runs, results=campaign.results,
                         trajectories=campaign.trajectories, methods=methods,
                         variations=variations, skipped=skipped, b0=b0,
                         versions=campaign.versions,
                         ran=campaign.ran, reused=campaign.reused,
                         wall_time=time.perf_counter() - start,
                         predictability=campaign.horizons, ensembles=ensembles,
                         verdict=verdict)
