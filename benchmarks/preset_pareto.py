"""Presets against the cheapest settings that meet their accuracy (issue 19, item 2).

For each engine, a grid of its cost knobs (``GRIDS``: time step, sub-steps,
solver iterations, integrator or contact solver, ...; every combination, the
presets' own values and their neighbours among them) is searched on the
calibration set of issue 19 (``SUITES``): free rocking B0–B3 (``paper-free``,
ten cases of 20 s), the six Single #2 one-sine pulses (``paper-single-pulse``)
and the eight stack pulses (``paper-stack-pulse``), 24 cases.

Bounds. Each preset sets them (:meth:`CaseResult.meets`): on every case a
candidate must end with the same status and stay within ``SLACK`` × the
preset's own max |θ − θ_ref|/λ and |Δpeak|/peak against the analytic
reference, with floors ``ERROR_FLOOR`` = 1e-3 λ and ``PEAK_FLOOR`` = 0.2 %
(the accuracy class the ``accurate`` presets are documented for, e.g.
MuJoCo's "below 2e-3 λ and 0.11 % on pulse peaks", and issue 19's "B0 at
≤ 1e-3 λ"; without them a preset far more precise than needed on one case
would demand that precision of every cheaper candidate). The engines whose
``accurate`` step was set by the two well-posed stack sinusoids (``GUARDS``:
pymunk, DART) must also keep them within the stack-convergence limit
(:func:`guard_meets`: same status, worst block peak within
max(``SLACK`` × the preset's, ``GUARD_TOL`` = 5 %); their max |Δθ| is not
judged, every engine departs from the 4 mm one at 0.97 s); these two cases
are judged for ``accurate`` only and are not part of the cost. Cost is the
sum of the runs' CPU times over the calibration cases.

With ``--bounds group`` (:func:`group_bounds`) the same rule is applied
against the preset's *worst* error of the case's group (free rocking, single
pulses, stack pulses) instead of its error on that case: the accuracy class a
preset is documented for ("B0–B3 within x λ, pulse peaks within y %"), not its
error pattern case by case. A per-case bound asks a cheaper candidate to be
within 10 % of the preset on each of 24 cases, which impact-driven runs two
step sizes apart rarely are even when both are well inside the class.

Search (:func:`prune_search`). Both presets are first run on every case (they
set the bounds). Every other candidate is run on one cheap probe case
(``PROBE``); its estimated cost is its probe CPU × the smallest
cost/probe ratio of the two presets (an underestimate for most candidates,
so the pruning below errs towards running more). Candidates are then judged
in ascending order of estimated cost: each one's cases are run ``jobs`` at a
time, already-run cases first, then those where earlier candidates failed
(most failures first), then the cheapest; a candidate is abandoned at its
first case outside the bounds. The search stops once the next candidate's
estimate exceeds the cost of the cheapest candidate found meeting the bounds
(at first the preset itself). The reported "cheapest" is therefore the
cheapest of the grid under this pruning, not an exhaustive minimum: a
candidate whose estimate was too high is not run. Every candidate's judged
cases are recorded. ``cost(preset) / cost(cheapest)`` is reported (1.0: the
preset is on the front of this grid; goal ≤ 1.2).

Run ``python -m benchmarks.preset_pareto pymunk dem2d [--jobs 2]
[--bounds case|group] [--cases SPEC] [--budget S] [--cache FILE] [--out FILE]``
(chosen engines; ``--bounds`` the per-case rule (default) or the group rule above;
``--cases`` a comma list of suites or cases instead of the calibration set,
``--budget`` a wall-time limit on each engine's searches (after its presets and
probes) past which the remaining candidates are left unjudged, ``--cache`` a
JSON-lines file of runs reused on a rerun,
``--out`` appends the Markdown), or ``python -m benchmarks --only pareto``
(every engine). Blender runs only in its own interpreter:
``.venv-blender/bin/python -m benchmarks.preset_pareto blender``.
"""

from __future__ import annotations

import argparse
import hashlib
import inspect
import itertools
import json
import math
import sys
import time
from collections import Counter
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

from benchmarks import engine_status, load, warm
from rockbench import analytic
from rockbench.engines import engine_class
from rockbench.evaluation import evaluate_run
from rockbench.runner import ExecutionOptions, Job, run_jobs
from rockbench.scenarios import get_scenario, get_suite
from rockbench.trajectory import Status

__all__ = ["run", "main", "GRIDS", "SUITES", "GUARDS", "CaseResult", "Trial", "Search",
           "Judge", "guard_meets", "group_bounds", "prune_search", "candidates",
           "search_engine"]

#: The calibration set of issue 19.
SUITES = ("paper-free", "paper-single-pulse", "paper-stack-pulse")
#: The quick set (``run(quick=True)``): one case of each kind.
QUICK = ("free-b2-0.5", "single-pulse-3.0hz-8mm", "stack-pulse-4.0hz-4mm")
#: Cost probe: a cheap single-block case of the set (else the set's first case).
PROBE = "single-pulse-3.0hz-8mm"
#: Cases the replacement of an engine's ``accurate`` must also keep (its step was set on them).
GUARDS: dict[str, tuple[str, ...]] = {
    "pymunk": ("stack-sine-5.0hz-2mm", "stack-sine-5.0hz-4mm"),
    "dart": ("stack-sine-5.0hz-2mm", "stack-sine-5.0hz-4mm"),
}
#: Stack-convergence limit on the guards' worst peak error (docs/engines/stack-convergence.md).
GUARD_TOL = 0.05
#: A candidate may be this much worse than the preset on a case.
SLACK = 1.10
#: Smallest bounds: max |Δθ|/λ and |Δpeak|/peak.
ERROR_FLOOR = 1e-3
PEAK_FLOOR = 2e-3
#: The presets searched against.
PRESETS = ("accurate", "fast")


def _axis(key: str, *values: Any) -> tuple[dict[str, Any], ...]:
    return tuple({key: v} for v in values)


#: Knob grids per engine: axes of override dicts (every combination is a candidate; the
#: presets are added, combinations equal to a preset dropped).
GRIDS: dict[str, tuple[tuple[dict[str, Any], ...], ...]] = {
    "pymunk": (_axis("timestep", 1e-3, 5e-4, 2.5e-4, 1e-4, 5e-5, 4e-5, 2.5e-5, 2e-5),
               _axis("iterations", 5, 10, 20)),
    # fast's contact (no stiffer sliding contact), accurate's
    "dem2d": (({"kn": 1e8, "ks": 1e8, "slip_compliance": None}, {"kn": 1e9, "ks": 1e9}),
              _axis("compliance", 2e-5, 5e-5, 1e-4), _axis("impact_zeta", 2.0, 3.0),
              _axis("safety", 1.0, 2.0)),
    "dart": (_axis("timestep", 1e-3, 5e-4, 2.5e-4, 1e-4, 5e-5, 4e-5, 2.5e-5),
             _axis("collision_detector", "fcl", "ode")),
    "mujoco": (_axis("timestep", 1e-3, 5e-4, 2.5e-4, 2e-4, 1.25e-4, 1e-4),
               _axis("integrator", "Euler", "implicitfast"), _axis("timeconst_factor", 2.0, 4.0),
               ({}, {"iterations": 50, "tolerance": 1e-8}),
               ({}, {"dampratio": 1.0, "cone": "elliptic"})),  # accurate's contact, fast's
    # dt = 1 / ((substeps + 1) fps), fps 1000
    "bullet": (_axis("substeps", 0, 1, 2, 4, 9), _axis("solver_iterations", 10, 20, 50),
               ({}, {"chamfer_shape": "hull", "contact_breaking_threshold": 1e-3,
                     "solver_residual_threshold": 1e-7})),  # accurate's contact, fast's
    "opensees": (_axis("timestep", 5e-4, 2.5e-4, 1e-4, 5e-5), _axis("contact_frequency",
                                                                      200.0, 500.0, 1000.0),
                 _axis("tolerance", 1e-4, 1e-3)),
    "drake": (_axis("timestep", 5e-4, 2.5e-4, 1e-4, 5e-5),
              ({}, {"hunt_crossley_dissipation": None}),  # accurate's contact, fast's
              _axis("collision_slices", 2, 4)),
    # fps stays 1000 (the output rate): a lower fps is run as frames of one sub-step at
    # fps · n_s (the same number of Bullet steps, no cheaper), a higher one adds frames
    "blender": (_axis("substeps_per_frame", 1, 2, 5, 10), _axis("solver_iterations", 10, 20, 50)),
}


# ---------------------------------------------------------------------- judging
@dataclass(frozen=True)
class CaseResult:
    """One run of a candidate on one case."""

    status: Status
    error: float  # max |θ − θ_ref|/λ (inf: undefined)
    peak: float  # worst block |Δpeak|/peak (0 for free rocking; inf: undefined)
    cpu: float
    wall: float = 0.0

    def meets(self, bound: CaseResult) -> bool:
        """Same status as ``bound`` (the preset's run) and its accuracy within SLACK."""
        return (self.status == bound.status
                and self.error <= max(SLACK * bound.error, ERROR_FLOOR)
                and self.peak <= max(SLACK * bound.peak, PEAK_FLOOR))


def group_bounds(bound: Mapping[str, CaseResult],
                 groups: Sequence[Sequence[str]]) -> dict[str, CaseResult]:
    """Each case's bound raised to the preset's worst (finite) error and peak error over
    its group (status and CPU kept); cases in no group keep their own bound."""
    out = dict(bound)
    for g in groups:
        err = max((bound[n].error for n in g if math.isfinite(bound[n].error)), default=math.inf)
        peak = max((bound[n].peak for n in g if math.isfinite(bound[n].peak)), default=math.inf)
        for n in g:
            out[n] = CaseResult(bound[n].status, err, peak, bound[n].cpu, bound[n].wall)
    return out


def guard_meets(result: CaseResult, bound: CaseResult) -> bool:
    """A guard case (stack sinusoid): same status, peak within max(SLACK × preset, GUARD_TOL)."""
    return result.status == bound.status and result.peak <= max(SLACK * bound.peak, GUARD_TOL)


@dataclass(frozen=True)
class Trial:
    """One candidate judged against one preset's bounds."""

    label: str
    estimate: float  # estimated cost (s)
    ran: tuple[str, ...]  # cases judged, in the order run
    failed: str | None  # first case outside the bounds (None: every case met)
    cpu: float | None  # cost over the calibration cases when every case was met

    @property
    def met(self) -> bool:
        """Every case within the bounds."""
        return self.failed is None


@dataclass(frozen=True)
class Search:
    """The pruned search of one preset: trials in order, candidates not judged, the cheapest."""

    preset: str
    cost: float
    trials: tuple[Trial, ...]
    skipped: tuple[str, ...]  # estimate above the cheapest meeting found
    unjudged: tuple[str, ...]  # left when the time budget ran out
    best: Trial

    @property
    def ratio(self) -> float:
        """cost(preset) / cost(cheapest meeting its bounds)."""
        return self.cost / self.best.cpu if self.best.cpu else math.nan


class Judge(Protocol):
    """Where a search gets its runs (the engine runner, or a table in the tests)."""

    def known(self, label: str, case: str) -> bool:
        """Whether the run of ``label`` on ``case`` is already done."""

    def results(self, label: str, cases: Sequence[str]) -> Mapping[str, CaseResult]:
        """The runs of ``label`` on ``cases`` (run now, in parallel, if not yet known)."""


def prune_search(preset: str, bound: Mapping[str, CaseResult], estimates: Mapping[str, float],
                 judge: Judge, *, cost_cases: Sequence[str], guards: Sequence[str] = (),
                 jobs: int = 2, stop: Callable[[], bool] = lambda: False) -> Search:
    """Cheapest candidate meeting ``preset``'s bounds, with the pruning of the module docstring.

    Parameters
    ----------
    preset : str
        Label of the preset (its runs are ``bound``).
    bound : mapping
        The preset's result on every case of ``cost_cases`` and ``guards``.
    estimates : mapping
        Estimated cost of every candidate (the preset's own entry is ignored).
    judge : Judge
        Runs (or looks up) a candidate's cases.
    cost_cases : sequence of str
        Cases judged by :meth:`CaseResult.meets` and summed into the cost.
    guards : sequence of str
        Cases judged by :func:`guard_meets`, not counted in the cost.
    jobs : int
        Cases of one candidate run at once.
    stop : callable
        Polled before each candidate: True leaves the rest unjudged.
    """
    cases = [*cost_cases, *guards]
    cost = sum(bound[n].cpu for n in cost_cases)
    best = Trial(preset, cost, tuple(cases), None, cost)
    fails: Counter[str] = Counter()
    trials: list[Trial] = []
    ranked = sorted((lab for lab in estimates if lab != preset), key=lambda lab: estimates[lab])
    skipped: list[str] = []
    unjudged: list[str] = []
    for i, lab in enumerate(ranked):
        if estimates[lab] > best.cpu:  # sorted: every later estimate is higher too
            skipped = ranked[i:]
            break
        if stop():
            unjudged = ranked[i:]
            break
        queue = sorted(cases, key=lambda n: (not judge.known(lab, n), -fails[n], bound[n].cpu))
        ran: list[str] = []
        got: dict[str, CaseResult] = {}
        failed: str | None = None
        while failed is None and len(ran) < len(queue):
            nxt = queue[len(ran)]
            # a known run is judged alone (free); unknown ones go `jobs` at a time
            batch = [nxt] if judge.known(lab, nxt) else queue[len(ran):len(ran) + jobs]
            got.update(judge.results(lab, batch))
            ran += batch
            for n in batch:
                ok = (guard_meets if n in guards else CaseResult.meets)(got[n], bound[n])
                if not ok:
                    failed = n
                    fails[n] += 1
                    break
        cpu = sum(got[n].cpu for n in cost_cases) if failed is None else None
        trial = Trial(lab, estimates[lab], tuple(ran), failed, cpu)
        trials.append(trial)
        if cpu is not None and cpu < best.cpu:
            best = trial
    return Search(preset, cost, tuple(trials), tuple(skipped), tuple(unjudged), best)


# ---------------------------------------------------------------------- engine runs
def _label(settings: Mapping[str, Any]) -> str:
    return ", ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}"
                     for k, v in settings.items())


def candidates(engine: str) -> dict[str, dict[str, Any]]:
    """Label → job settings: the presets, then every grid combination not equal to one."""
    cls = engine_class(engine)
    out = {f"preset={p}": {"preset": p} for p in PRESETS}
    seen = [cls.settings(p) for p in PRESETS]
    for combo in itertools.product(*GRIDS[engine]):
        s = {k: v for d in combo for k, v in d.items()}
        resolved = cls.settings(**s)
        if resolved not in seen:
            seen.append(resolved)
            out[_label(s)] = s
    return out


def _result(sc: Any, traj: Any, ref: Any) -> CaseResult:
    m = evaluate_run(sc, traj, ref)
    inf = math.inf
    peak = 0.0 if sc.motion.is_free else (abs(m.peak_error) if m.peak_error is not None
                                          else inf)
    return CaseResult(traj.status, m.max_error if m.max_error is not None else inf, peak,
                      float(traj.cpu_time), float(traj.wall_time))


_REFS: dict[str, Any] = {}


def _reference(name: str) -> Any:
    """The analytic reference of catalog case ``name`` (computed once per process)."""
    if name not in _REFS:
        _REFS[name] = analytic.reference(get_scenario(name))
    return _REFS[name]


class _Runs:
    """The engine's runs, memoised (and kept in a JSON-lines cache file if given)."""

    def __init__(self, engine: str, cands: Mapping[str, dict[str, Any]], names: Sequence[str],
                 jobs: int, cache: Path | None, log: Any) -> None:
        self.engine, self.cands, self.jobs, self.cache, self.log = engine, cands, jobs, cache, log
        self.scen = {n: get_scenario(n) for n in names}
        self.refs = {n: _reference(n) for n in names}
        self.done: dict[tuple[str, str], CaseResult] = {}
        self.timeout = 1800.0
        # a cached run is reused only for the same resolved knobs (a preset may have moved)
        # and the same engine source (the engines are edited while studies run)
        cls = engine_class(engine)
        self.key = {lab: json.loads(json.dumps(cls.settings(**c).to_dict())) for lab, c in
                    cands.items()}
        self.source = hashlib.sha1(Path(inspect.getfile(cls)).read_bytes()).hexdigest()
        if cache is not None and cache.exists():
            for line in cache.read_text().splitlines():
                r = json.loads(line)
                if (r["engine"] == engine and r["label"] in cands and r["case"] in self.scen
                        and r.get("resolved") == self.key[r["label"]]
                        and r.get("source") == self.source):
                    self.done[r["label"], r["case"]] = CaseResult(
                        Status(r["status"]), r["error"], r["peak"], r["cpu"], r["wall"])

    def known(self, label: str, case: str) -> bool:
        return (label, case) in self.done

    def run_many(self, pairs: Sequence[tuple[str, str]]) -> None:
        todo = [p for p in dict.fromkeys(pairs) if p not in self.done]
        if not todo:
            return
        jobs = [Job(self.scen[n], self.engine, self.cands[lab], label=lab) for lab, n in todo]

        def done(job: Job, tr: Any) -> None:  # as each run ends (progress, cache)
            lab, n = job.label, job.scenario.name
            r = _result(self.scen[n], tr, self.refs[n])
            self.done[lab, n] = r
            print(f"[pareto] {self.engine} {lab} | {n}: {r.status} {r.error:.2e} λ "
                  f"{100 * r.peak:.2f} % {r.cpu:.2f} s CPU", file=self.log, flush=True)
            if self.cache is not None:
                with self.cache.open("a") as f:
                    f.write(json.dumps(dict(engine=self.engine, label=lab,
                                            settings=self.cands[lab],
                                            resolved=self.key[lab], source=self.source, case=n,
                                            status=r.status.value, error=r.error, peak=r.peak,
                                            cpu=r.cpu, wall=r.wall)) + "\n")

        run_jobs(jobs, ExecutionOptions(jobs=min(self.jobs, len(todo)), timeout=self.timeout),
                 on_result=done)

    def results(self, label: str, cases: Sequence[str]) -> dict[str, CaseResult]:
        self.run_many([(label, n) for n in cases])
        return {n: self.done[label, n] for n in cases}


@dataclass(frozen=True)
class EngineSearch:
    """Everything measured for one engine."""

    engine: str
    cases: tuple[str, ...]
    guards: tuple[str, ...]
    probe: str
    scale: float  # estimate = probe CPU × scale
    estimates: dict[str, float]
    runs: dict[tuple[str, str], CaseResult]
    searches: tuple[Search, ...]
    wall: float
    load_start: str
    load_end: str
    bounds_by: str = "case"


def _groups(cases: Sequence[str]) -> list[list[str]]:
    """The cases by kind (the part of the name before its parameters)."""
    kinds: dict[str, list[str]] = {}
    for n in cases:
        kinds.setdefault(n.split("-")[0] + ("" if n.startswith("free") else n.split("-")[1]),
                         []).append(n)
    return list(kinds.values())


def search_engine(engine: str, cases: Sequence[str], *, jobs: int = 2,
                  budget: float = math.inf, cache: Path | None = None, bounds_by: str = "case",
                  log: Any = sys.stderr) -> EngineSearch:
    """Run the presets, the probes and the pruned search of each preset for ``engine``
    (``bounds_by``: "case", or "group" for :func:`group_bounds`)."""
    t0, load0 = time.perf_counter(), load()
    if not engine_class(engine).fresh_process:  # (blender: one bpy session per process)
        warm(engine)  # libraries imported (and JIT-compiled) here: forked workers inherit them
    cands = candidates(engine)
    guards = GUARDS.get(engine, ())
    probe = PROBE if PROBE in cases else cases[0]
    runs = _Runs(engine, cands, [*cases, *guards], jobs, cache, log)
    runs.run_many([(f"preset={p}", n) for p in PRESETS for n in cases]
                  + [("preset=accurate", n) for n in guards])
    bounds = {p: {n: runs.done[f"preset={p}", n] for n in cases} for p in PRESETS}
    bounds["accurate"].update({n: runs.done["preset=accurate", n] for n in guards})
    costs = {p: sum(bounds[p][n].cpu for n in cases) for p in PRESETS}
    # a candidate far slower than the slowest preset run is not worth waiting for
    runs.timeout = max(120.0, 3.0 * max(r.wall for r in runs.done.values()))
    others = [lab for lab in cands if not lab.startswith("preset=")]
    runs.run_many([(lab, probe) for lab in others])
    scale = min(costs[p] / max(bounds[p][probe].cpu, 1e-9) for p in PRESETS)
    estimates = {f"preset={p}": costs[p] for p in PRESETS}
    estimates.update({lab: runs.done[lab, probe].cpu * scale for lab in others})

    t1 = time.perf_counter()  # the budget is the searches' (the presets and probes always run)

    def stop() -> bool:
        return time.perf_counter() - t1 > budget

    if bounds_by == "group":
        bounds = {p: group_bounds(b, _groups(cases)) for p, b in bounds.items()}
    searches = tuple(
        prune_search(f"preset={p}", bounds[p], estimates, runs, cost_cases=cases,
                     guards=guards if p == "accurate" else (), jobs=jobs, stop=stop)
        for p in ("fast", "accurate"))
    return EngineSearch(engine, tuple(cases), guards, probe, scale, estimates, dict(runs.done),
                        searches, time.perf_counter() - t0, load0, load(), bounds_by)


# ---------------------------------------------------------------------- report
def _worst(rs: Sequence[CaseResult], attr: str) -> float:
    vals = [getattr(r, attr) for r in rs if r.status is Status.OK and
            math.isfinite(getattr(r, attr))]
    return max(vals, default=math.nan)


def _cell(r: CaseResult | None) -> str:
    if r is None:
        return "·"
    if r.status is not Status.OK:
        return f"{r.status.value} ({r.cpu:.2f} s)"
    return f"{r.error:.1e} / {100 * r.peak:.2f} % ({r.cpu:.2f} s)"


def _verdict(s: Search, label: str) -> str:
    for t in s.trials:
        if t.label == label:
            if t.met:
                return f"meets ({t.cpu:.2f} s)"
            return f"fails {t.failed} after {len(t.ran)}: {', '.join(t.ran)}"
    if label in s.skipped:
        return "not run (estimate above the cheapest)"
    if label in s.unjudged:
        return "not judged (budget)"
    return "preset" if label == s.preset else "–"


def markdown(es: EngineSearch) -> list[str]:
    """The engine's table, its bounds and every candidate's trials."""
    e = es.engine
    grid = "; ".join(" | ".join(_label(d) or "(preset values)" for d in axis)
                     for axis in GRIDS[e])
    lines = [f"### {e}" + (" (group bounds)" if es.bounds_by == "group" else ""), "",
             f"{len(es.cases)} cases ({', '.join(es.cases)})"
             + (f"; guards of `accurate`: {', '.join(es.guards)}" if es.guards else "")
             + f". Grid (axes separated by ';'): {grid}. {len(es.estimates)} candidates, "
             f"{len(es.runs)} runs, {es.wall:.0f} s wall. Estimated cost = CPU on {es.probe} "
             f"× {es.scale:.1f}. Machine: {es.load_start} at the start, {es.load_end} at the "
             "end.", "",
             "| engine | preset | CPU (s) | worst max abs Δθ/λ | worst abs Δpeak | cheapest "
             "meeting its bounds | CPU (s) | worst max abs Δθ/λ | worst abs Δpeak "
             "| cost(preset)/cost(cheapest) | judged / not run / budget |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for s in sorted(es.searches, key=lambda s: PRESETS.index(s.preset.split("=")[1])):
        pre = [es.runs[s.preset, n] for n in es.cases]
        bst = [es.runs[s.best.label, n] for n in es.cases]
        lines.append(
            f"| {e} | {s.preset.split('=')[1]} | {s.cost:.2f} | {_worst(pre, 'error'):.2e} "
            f"| {100 * _worst(pre, 'peak'):.2f} % | {s.best.label} | {s.best.cpu:.2f} "
            f"| {_worst(bst, 'error'):.2e} | {100 * _worst(bst, 'peak'):.2f} % "
            f"| {s.ratio:.2f} | {len(s.trials)} / {len(s.skipped)} / {len(s.unjudged)} |")
    lines.append("")
    allc = [*es.cases, *es.guards]
    lines += [f"<details><summary>{e}: the presets' runs (the bounds) and the cheapest</summary>",
              "", "| case | " + " | ".join(["accurate", "fast"]
                                             + [f"cheapest for {s.preset.split('=')[1]}: "
                                                f"{s.best.label}" for s in es.searches]) + " |",
              "|---|---|---|---|---|"]
    for n in allc:
        cells = [_cell(es.runs.get((f"preset={p}", n))) for p in PRESETS]
        cells += [_cell(es.runs.get((s.best.label, n))) for s in es.searches]
        lines.append(f"| {n} | " + " | ".join(cells) + " |")
    lines += ["", "(cells: max |Δθ|/λ / worst |Δpeak|/peak (CPU); · not run)", "</details>", "",
              f"<details><summary>{e}: every candidate (ascending estimated cost)</summary>", "",
              "| candidate | est. CPU (s) | CPU on probe (s) | vs fast | vs accurate |",
              "|---|---|---|---|---|"]
    by = {s.preset: s for s in es.searches}
    for lab in sorted(es.estimates, key=lambda lab: es.estimates[lab]):
        pr = es.runs.get((lab, es.probe))
        lines.append(f"| {lab} | {es.estimates[lab]:.2f} | {pr.cpu if pr else math.nan:.3f} | "
                     f"{_verdict(by['preset=fast'], lab)} | "
                     f"{_verdict(by['preset=accurate'], lab)} |")
    lines += ["", "(fails C after k: the first case outside the bounds, after k cases run, "
              "listed in order)", "</details>", ""]
    return lines


def _names(spec: str | None) -> list[str]:
    if not spec:
        return [n for s in SUITES for n in get_suite(s)]
    out: list[str] = []
    for item in (x.strip() for x in spec.split(",") if x.strip()):
        try:
            out += get_suite(item)
        except Exception:  # not a suite: a case name (checked by get_scenario)
            get_scenario(item)
            out.append(item)
    return list(dict.fromkeys(out))


def run(quick: bool = False, engines: list[str] | None = None, *, cases: str | None = None,
        jobs: int = 2, budget: float = math.inf, cache: Path | None = None,
        bounds_by: str = "case") -> tuple[str, dict]:
    """Markdown section and raw numbers."""
    names = _names(",".join(QUICK) if quick and cases is None else cases)
    where = "its worst over the case's group" if bounds_by == "group" else "on that case"
    lines = ["## Presets against the cheapest settings meeting their bounds (issue 19)", "",
             f"Bounds: same status on every case, within {SLACK:g} × the preset's max |Δθ|/λ "
             f"and |Δpeak|/peak ({where}; "
             f"floors {ERROR_FLOOR:g}, {PEAK_FLOOR:g}); guards: peak within "
             f"max({SLACK:g} × the preset's, {GUARD_TOL:.0%}). Cost = sum of the runs' CPU "
             "times over the calibration cases. The cheapest is the cheapest of the grid under "
             "the pruning of `benchmarks/preset_pareto.py` (its docstring).", ""]
    data: dict[str, Any] = {}
    for e in engines or list(GRIDS):
        ok, what = engine_status(e)
        if not ok:
            lines += [f"### {e}", "", what, ""]
            continue
        es = search_engine(e, names, jobs=jobs, budget=budget, cache=cache, bounds_by=bounds_by)
        lines += markdown(es)
        data[e] = {s.preset: dict(cost=s.cost, best=s.best.label, best_cpu=s.best.cpu,
                                  ratio=s.ratio) for s in es.searches}
    return "\n".join(lines), data


def main(argv: list[str] | None = None) -> None:
    """Command line (module docstring)."""
    ap = argparse.ArgumentParser(prog="python -m benchmarks.preset_pareto")
    ap.add_argument("engines", nargs="*", help=f"engines (default: {' '.join(GRIDS)})")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--cases", help="comma list of suites/cases (default: the calibration set)")
    ap.add_argument("--budget", type=float, default=math.inf, help="wall s of the searches")
    ap.add_argument("--cache", type=Path, help="JSON-lines file of runs (read and appended)")
    ap.add_argument("--out", type=Path, help="append the Markdown to this file")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--bounds", choices=("case", "group"), default="case",
                    help="bound each case by the preset's error there, or by its group's worst")
    a = ap.parse_args(argv)
    text, _ = run(a.quick, a.engines or None, cases=a.cases, jobs=a.jobs, budget=a.budget,
                  cache=a.cache, bounds_by=a.bounds)
    print(text)
    if a.out is not None:
        with a.out.open("a") as f:
            f.write(text + "\n")


if __name__ == "__main__":
    main()
