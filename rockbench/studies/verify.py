"""Verification: which method to trust for *these* scenarios, with the evidence and the cost.

The study behind ``rockbench verify`` and the verdict of ``compare`` and ``run``:

1. every engine at every preset runs every scenario through the campaign (each
   run reused from the results store when it is there), measured against the
   analytic reference where one covers the scenario, up to its
   predictability horizon t*;
2. where no closed form covers a scenario (or with ``converge="all"``, on every
   scenario), each method climbs its convergence ladder
   (:mod:`rockbench.studies.convergence`: the preset's run is rung 0) and the
   converged engines of independent contact models form a consensus
   (:mod:`rockbench.studies.consensus`);
3. each method is judged on each scenario against the closed form, else the
   consensus (:mod:`rockbench.studies.verdict`), and the cheapest trusted method
   is named.

Where a closed form exists and ladders ran too, the consensus is compared with
the closed form (:attr:`VerifyResult.consensus_check`), which shows what a
consensus is worth.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from rockbench.analytic import critical_angle
from rockbench.campaign import CampaignOptions, PlannedRun, run_campaign
from rockbench.campaign.predictability import DEFAULT_MEMBERS, Predictability
from rockbench.engines import KnobRole, engine_class
from rockbench.errors import RockbenchError
from rockbench.evaluation import PEAK_FLOOR, RunResult
from rockbench.method import REFERENCE, Method
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Scenario
from rockbench.studies.consensus import Consensus, consensus
from rockbench.studies.convergence import (
    DEFAULT_MAX_LEVEL,
    Convergence,
    ConvergenceTolerances,
    converge_many,
    response,
)
from rockbench.studies.verdict import (
    Judgement,
    Trust,
    Verdict,
    VerdictTolerances,
    judge_closed_form,
    judge_consensus,
    summarise,
    unverified,
)
from rockbench.trajectory import Trajectory

__all__ = ["VerifyOptions", "VerifyResult", "ConsensusCheck", "run_verification",
           "verdict_of", "KIND"]

#: The store's ``kind`` of the runs made by this study (the ladders' rungs: ``convergence``).
KIND = "verify"

Converge = Literal["auto", "all", "none"]


@dataclass(frozen=True)
class VerifyOptions:
    """What to verify and how.

    Attributes
    ----------
    scenarios : list of Scenario
        The user's scenarios.
    engines : list of str
        The engines judged (the analytic reference runs besides).
    presets : list of str
        Each engine's presets judged.
    overrides : dict
        Per engine, knob overrides on top of every preset.
    converge : {"auto", "all", "none"}
        Where ladders run: where no closed form exists (``auto``), everywhere
        (``all``: also checks the consensus against the closed forms), nowhere.
    max_level : int
        The finest rung of a ladder (refinements beyond the preset).
    tolerances, convergence
        The verdict's tolerances and when two rungs agree.
    db : Path or None
        The results store (runs and rungs reused from it, new ones recorded).
    execution : ExecutionOptions
        Workers, time limit, executor.
    timeout : float or None
        Per-run time limit (None: the campaign's default).
    horizon_members : int
        Perturbed references that measure t* (0: none).
    suite : str
        A name for the scenario set (stored with the runs).
    """

    scenarios: list[Scenario]
    engines: list[str]
    presets: list[str] = field(default_factory=lambda: ["accurate", "fast"])
    overrides: dict[str, dict[str, Any]] = field(default_factory=dict)
    converge: Converge = "auto"
    max_level: int = DEFAULT_MAX_LEVEL
    tolerances: VerdictTolerances = field(default_factory=VerdictTolerances)
    convergence: ConvergenceTolerances = field(default_factory=ConvergenceTolerances)
    db: Path | None = None
    execution: ExecutionOptions = field(default_factory=ExecutionOptions)
    timeout: float | None = None
    horizon_members: int = DEFAULT_MEMBERS
    suite: str = ""

    def __post_init__(self) -> None:
        if self.converge not in ("auto", "all", "none"):
            raise RockbenchError(f"converge must be auto, all or none, got {self.converge!r}")
        if not self.scenarios:
            raise RockbenchError("nothing to verify: no scenario")
        if not [e for e in self.engines if e != REFERENCE]:
            raise RockbenchError("nothing to verify: no engine besides the analytic reference")


@dataclass(frozen=True)
class ConsensusCheck:
    """A consensus against the closed form of the same scenario.

    Attributes
    ----------
    scenario : str
        Scenario name.
    consensus : Consensus
        The consensus of the converged engines.
    peak_errors : tuple of float
        Per block, (consensus − closed form) / max(closed form, 0.02 λ).
    within : bool
        Every closed-form peak lies inside the consensus's uncertainty.
    """

    scenario: str
    consensus: Consensus
    peak_errors: tuple[float, ...]
    within: bool


@dataclass
class VerifyResult:
    """What a verification ran and concluded.

    Attributes
    ----------
    options : VerifyOptions
        What was asked.
    methods : list of Method
        The methods judged (engine × preset).
    results : list of RunResult
        Every method's own run on every scenario (the reference's too).
    trajectories : dict
        (scenario, method label) → trajectory of those runs.
    ladders : list of Convergence
        The convergence ladders that ran.
    verdict : Verdict
        The judgement of every method and the cheapest trusted one.
    consensus_check : list of ConsensusCheck
        Consensus against closed form, where both exist.
    horizons : dict
        Scenario name → its predictability horizon (where measured).
    run_cpu, verdict_cpu : float
        CPU time of the methods' own runs, and of the ladders' further rungs (s).
    wall_time : float
        Wall time of the study (s).
    """

    options: VerifyOptions
    methods: list[Method]
    results: list[RunResult]
    trajectories: dict[tuple[str, str], Trajectory]
    ladders: list[Convergence]
    verdict: Verdict
    consensus_check: list[ConsensusCheck]
    horizons: dict[str, Predictability]
    run_cpu: float
    verdict_cpu: float
    wall_time: float


def _methods(opts: VerifyOptions) -> list[Method]:
    engines = [e for e in dict.fromkeys(opts.engines) if e != REFERENCE]
    several = len(opts.presets) > 1
    return [Method.of(e, {"preset": p, **opts.overrides.get(e, {})}, qualified=several)
            for e in engines for p in opts.presets]


def _cpu(res: RunResult) -> float:
    m = res.metrics
    return float(m.cpu_time if m.cpu_time else m.wall_time)


def verdict_of(results: Sequence[RunResult], references: dict[str, Trajectory | None],
               ladders: Sequence[Convergence] = (),
               tolerances: VerdictTolerances | None = None,
               convergence: ConvergenceTolerances | None = None) -> tuple[Verdict,
                                                                         dict[str, Consensus]]:
    """Judge the methods' own runs (``results``) against the closed forms, else the
    consensus of ``ladders``; the analytic reference's own runs are not judged.

    Returns the :class:`Verdict` and each scenario's consensus (where ladders ran).
    """
    by_scenario: dict[str, list[Convergence]] = {}
    for lad in ladders:
        by_scenario.setdefault(lad.scenario.name, []).append(lad)
    cons = {name: consensus(lads, convergence) for name, lads in by_scenario.items()}
    ladder_of = {(lad.scenario.name, lad.method): lad for lad in ladders}
    judgements: list[Judgement] = []
    scenarios: list[str] = []
    for res in results:
        name = res.scenario.name
        if name not in scenarios:
            scenarios.append(name)
        if res.method.is_reference:
            continue
        ref = references.get(name)
        c = cons.get(name)
        ladder = ladder_of.get((name, res.method))
        if ref is not None and ref.status.completed:
            judgements.append(judge_closed_form(res, ref, tolerances))
        elif c is not None and c.formed and ladder is not None:
            judgements.append(judge_consensus(ladder, c, tolerances))
        elif c is not None and c.formed:
            judgements.append(Judgement(name, res.method, Trust.NOT_CONVERGED, "consensus",
                                        "no convergence ladder: the engine declares no "
                                        "knob to refine", _cpu(res)))
        else:
            why = (c.note if c is not None and not c.formed else
                   "no closed form covers it; a consensus needs convergence ladders "
                   "(`rockbench verify`)")
            judgements.append(unverified(name, res.method, _cpu(res), why))
    return summarise(judgements, scenarios, cons, tolerances), cons


def _consensus_check(cons: dict[str, Consensus],
                     references: dict[str, Trajectory | None],
                     scenarios: Sequence[Scenario]) -> list[ConsensusCheck]:
    out = []
    for sc in scenarios:
        c, ref = cons.get(sc.name), references.get(sc.name)
        if c is None or not c.formed or ref is None or not ref.status.completed:
            continue
        exact = response(ref, critical_angle(sc.geometry))
        errs, within = [], True
        for p, e in zip(exact.peaks, c.peaks, strict=False):
            scale = max(p, PEAK_FLOOR)
            errs.append((e.value - p) / scale)
            within &= abs(e.value - p) <= e.uncertainty + 1e-12
        out.append(ConsensusCheck(sc.name, c, tuple(errs), within))
    return out


def run_verification(opts: VerifyOptions,
                     progress: Callable[[int, str], Any] | None = None) -> VerifyResult:
    """Run the methods, climb the ladders where needed and judge (module docstring).

    Raises
    ------
    RockbenchError
        Bad input (an unknown engine or preset, an engine without a refinement knob
        where a ladder must climb).
    """
    start = time.perf_counter()
    methods = _methods(opts)
    plan = [PlannedRun(sc, m) for sc in opts.scenarios
            for m in [Method.reference(), *methods]]
    campaign = run_campaign(plan, CampaignOptions(
        kind=KIND, suite=opts.suite, db=opts.db, resume=opts.db is not None,
        archive=opts.db is not None, keep=True, execution=opts.execution, timeout=opts.timeout,
        horizon_members=opts.horizon_members), progress=progress)
    refs = campaign.references
    closed = {sc.name for sc in opts.scenarios
              if (ref := refs.get(sc.name)) is not None and ref.status.completed}
    climb = [sc for sc in opts.scenarios
             if opts.converge == "all" or (opts.converge == "auto" and sc.name not in closed)]
    horizons = {n: p.t_star for n, p in campaign.horizons.items()}
    refinable = set(engines_that_converge([m.engine for m in methods]))
    ladders = converge_many(
        [(sc, m) for sc in climb for m in methods if m.engine in refinable],
        tolerances=opts.convergence,
        max_level=opts.max_level, horizons=horizons, db=opts.db, execution=opts.execution,
        timeout=opts.timeout, progress=progress) if climb else []
    verdict, cons = verdict_of(campaign.results, refs, ladders, opts.tolerances,
                               opts.convergence)
    run_cpu = sum(_cpu(r) for r in campaign.results if not r.method.is_reference)
    verdict_cpu = sum(r.cpu_time for lad in ladders for r in lad.rungs[1:])
    return VerifyResult(
        options=opts, methods=methods, results=campaign.results,
        trajectories=campaign.trajectories, ladders=ladders, verdict=verdict,
        consensus_check=_consensus_check(cons, refs, opts.scenarios),
        horizons=campaign.horizons, run_cpu=run_cpu, verdict_cpu=verdict_cpu,
        wall_time=time.perf_counter() - start)


def engines_that_converge(engines: Sequence[str]) -> list[str]:
    """The engines whose ladders can climb (they declare a refinement knob)."""
    out = []
    for e in dict.fromkeys(engines):
        cls = engine_class(e)
        if not cls.capabilities.analytic and (cls.refinement in cls.knob_roles
                                              or cls.knob(KnobRole.TIME_STEP)):
            out.append(e)
    return out
