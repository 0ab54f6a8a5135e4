"""The verdict: which method to trust on these scenarios, against which reference, at what cost.

Each method (an engine at a preset) is judged on each scenario
(:class:`Judgement`) against the best reference there is:

``closed form``
    the analytic reference (Housner, the two-block model, the Coulomb slider),
    where one covers the scenario and completed;
``consensus``
    otherwise the consensus of converged engines of independent contact models
    (:mod:`rockbench.studies.consensus`); a method judged against it must have
    converged itself (:mod:`rockbench.studies.convergence`), else it is *not
    converged*, never trusted;
``none``
    neither exists: the method is *unverified* there.

A method is *trusted* on a scenario when it ends as the reference does and, up
to the predictability horizon t* where one is known (beyond it the reference
itself is not predictable), its peaks, its overturning time (when both
overturn) and its time history lie within the tolerances
(:class:`VerdictTolerances`), widened by the consensus's own uncertainty.
Over several scenarios, one *not trusted* makes the method not trusted, one
*not converged* (and none worse) not converged, and one *unverified* (and
none worse) unverified. The cheapest trusted method is the trusted one of
least CPU time over the scenarios.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from rockbench.evaluation import PEAK_FLOOR, RunMetrics, RunResult
from rockbench.method import Method
from rockbench.studies.consensus import Consensus
from rockbench.studies.convergence import Convergence
from rockbench.trajectory import Status, Trajectory

__all__ = ["Trust", "VerdictTolerances", "Judgement", "MethodVerdict", "Verdict",
           "judge_closed_form", "judge_consensus", "unverified", "summarise"]


class Trust(enum.Enum):
    """How far a method can be trusted (worst first)."""

    NOT_TRUSTED = "not trusted"
    NOT_CONVERGED = "not converged"
    UNVERIFIED = "unverified"
    TRUSTED = "trusted"

    @property
    def rank(self) -> int:
        """0 for the worst."""
        return list(Trust).index(self)


@dataclass(frozen=True)
class VerdictTolerances:
    """How close to the reference a trusted method is.

    Attributes
    ----------
    peak : float
        Each block's peak, relative to max(reference peak, 0.02 λ).
    overturn_time : float
        The overturning time, relative (both overturn).
    history : float
        max |θ − θ_ref|/λ up to t* (or to the reference's overturning).
    """

    peak: float = 0.05
    overturn_time: float = 0.02
    history: float = 0.05


@dataclass(frozen=True)
class Judgement:
    """One method on one scenario.

    Attributes
    ----------
    scenario : str
        Scenario name.
    method : Method
        Engine and preset.
    trust : Trust
        The verdict here.
    reference : str
        ``closed form``, ``consensus`` or ``none``.
    evidence : str
        The numbers behind it, one line.
    cpu_time : float
        CPU time of the method's own run (s).
    """

    scenario: str
    method: Method
    trust: Trust
    reference: str
    evidence: str
    cpu_time: float


def _cpu(m: RunMetrics) -> float:
    return float(m.cpu_time if m.cpu_time else m.wall_time)


def _ends(status: Status) -> str:
    return "overturned" if status is Status.OVERTURNED else status.value


def judge_closed_form(result: RunResult, reference: Trajectory,
                      tol: VerdictTolerances | None = None) -> Judgement:
    """``result`` (measured against the analytic reference) judged against it.

    The run's metrics hold its errors against the reference, up to t*
    (:func:`rockbench.evaluation.evaluate_run`); the overturning time is compared
    with the reference's.
    """
    tol = tol or VerdictTolerances()
    m = result.metrics
    ref = reference.status

    def judged(trust: Trust, evidence: str) -> Judgement:
        return Judgement(result.scenario.name, result.method, trust, "closed form", evidence,
                         _cpu(m))

    if not m.status.completed:
        return judged(Trust.NOT_TRUSTED, f"{m.status.value}: {m.message}")
    horizon = math.inf if m.horizon is None else m.horizon  # t* (none known: no limit)
    chaotic = horizon < m.duration
    t_ref = float(reference.t[-1]) if reference.t.size else 0.0
    # beyond t* the reference is not predictable: how the run ends there is not judged
    predictable_end = not chaotic or (ref is Status.OVERTURNED and t_ref <= horizon)
    if m.status is not ref and predictable_end:
        return judged(Trust.NOT_TRUSTED, f"ends {_ends(m.status)}, the closed form "
                                         f"{_ends(ref)}")
    upto = f" up to t* = {horizon:.2f} s" if chaotic else ""
    parts, bad = [], []
    if m.status is Status.OVERTURNED and ref is Status.OVERTURNED and predictable_end:
        t_run = m.simulated_time
        err = (t_run - t_ref) / t_ref
        parts.append(f"overturned at {t_run:.4g} s (closed form {t_ref:.4g} s, "
                     f"{100 * err:+.2g} %)")
        if abs(err) > tol.overturn_time:
            bad.append("overturning time")
    errs = [e for e in m.peak_errors if e is not None]
    if errs:
        worst = max(errs, key=abs)
        parts.append(f"peaks{upto} within {100 * abs(worst):.2g} %")
        if abs(worst) > tol.peak:
            bad.append("peaks")
    if m.max_error is not None:
        before = " before overturning" if ref is Status.OVERTURNED else upto
        parts.append(f"max |Δθ|{before} {m.max_error:.2g} λ")
        if m.max_error > tol.history:
            bad.append("time history")
    if not parts:
        return judged(Trust.UNVERIFIED, m.error_note or "no error could be measured")
    evidence = "; ".join(parts)
    if bad:
        return judged(Trust.NOT_TRUSTED, f"{evidence} (beyond the tolerance: "
                                         f"{', '.join(bad)})")
    return judged(Trust.TRUSTED, evidence)


def judge_consensus(ladder: Convergence, cons: Consensus,
                    tol: VerdictTolerances | None = None) -> Judgement:
    """A method's preset run (rung 0 of ``ladder``) judged against the consensus."""
    tol = tol or VerdictTolerances()
    rung = ladder.preset
    run = rung.response

    def judged(trust: Trust, evidence: str) -> Judgement:
        return Judgement(ladder.scenario.name, ladder.method, trust, "consensus", evidence,
                         rung.cpu_time)

    if not ladder.converged:
        return judged(Trust.NOT_CONVERGED, ladder.reason)
    if not run.completed:
        return judged(Trust.NOT_TRUSTED, f"{run.status.value}: {rung.result.metrics.message}")
    if run.status is not cons.outcome:
        return judged(Trust.NOT_TRUSTED, f"ends {_ends(run.status)}, the consensus "
                                         f"{_ends(cons.outcome or Status.OK)}")
    parts, bad = [], []
    if cons.overturn_time is not None and run.overturn_time is not None:
        c = cons.overturn_time
        err = (run.overturn_time - c.value) / c.value
        parts.append(f"overturned at {run.overturn_time:.4g} s (consensus {c}, "
                     f"{100 * err:+.2g} %)")
        if abs(err) > tol.overturn_time + c.uncertainty / c.value:
            bad.append("overturning time")
    worst, allowed = 0.0, tol.peak
    for p, c in zip(run.peaks, cons.peaks, strict=False):
        scale = max(c.value, PEAK_FLOOR)
        err = (p - c.value) / scale
        if abs(err) > abs(worst):
            worst, allowed = err, tol.peak + c.uncertainty / scale
    if cons.peaks:
        parts.append(f"peaks within {100 * abs(worst):.2g} % of the consensus "
                     f"(± {100 * (allowed - tol.peak):.2g} %)")
        if abs(worst) > allowed:
            bad.append("peaks")
    evidence = "; ".join(parts) or "no quantity to compare"
    if bad:
        return judged(Trust.NOT_TRUSTED, f"{evidence} (beyond the tolerance: "
                                         f"{', '.join(bad)})")
    return judged(Trust.TRUSTED, evidence)


def unverified(scenario: str, method: Method, cpu_time: float, why: str) -> Judgement:
    """A method on a scenario that no reference covers."""
    return Judgement(scenario, method, Trust.UNVERIFIED, "none", why, cpu_time)


@dataclass(frozen=True)
class MethodVerdict:
    """One method over every scenario judged.

    Attributes
    ----------
    method : Method
        Engine and preset.
    trust : Trust
        The worst of its judgements.
    judgements : tuple of Judgement
        One per scenario.
    """

    method: Method
    trust: Trust
    judgements: tuple[Judgement, ...]

    @property
    def cpu_time(self) -> float:
        """CPU time of its runs over the scenarios (s)."""
        return sum(j.cpu_time for j in self.judgements)

    @property
    def counts(self) -> dict[Trust, int]:
        """How many scenarios gave each verdict."""
        return {t: sum(j.trust is t for j in self.judgements) for t in Trust}

    @property
    def references(self) -> dict[str, int]:
        """How many scenarios each kind of reference judged."""
        out: dict[str, int] = {}
        for j in self.judgements:
            out[j.reference] = out.get(j.reference, 0) + 1
        return out

    def worst(self) -> Judgement | None:
        """The judgement that set its verdict."""
        return next((j for j in self.judgements if j.trust is self.trust), None)


@dataclass(frozen=True)
class Verdict:
    """Every method's verdict over the scenarios, and the cheapest trusted one.

    Attributes
    ----------
    methods : tuple of MethodVerdict
        In the order judged.
    scenarios : tuple of str
        The scenarios judged.
    cheapest : MethodVerdict or None
        The trusted method of least CPU time (None if none is trusted).
    consensus : dict
        Scenario name → its consensus (where ladders ran).
    tolerances : VerdictTolerances
        The tolerances used.
    """

    methods: tuple[MethodVerdict, ...]
    scenarios: tuple[str, ...]
    cheapest: MethodVerdict | None
    consensus: Mapping[str, Consensus]
    tolerances: VerdictTolerances

    def lines(self) -> list[str]:
        """The verdict in a few lines of text (what ``run`` and ``verify`` print)."""
        out = []
        n = len(self.scenarios)
        for mv in self.methods:
            refs = ", ".join(f"{k} {v}" for k, v in sorted(mv.references.items()))
            head = f"{mv.method.label}: {mv.trust.value} on {n} scenario{'s' * (n != 1)} ({refs})"
            worst = mv.worst()
            if worst is not None and mv.trust is not Trust.TRUSTED:
                head += f"; {worst.scenario}: {worst.evidence}"
            elif n == 1 and worst is not None:
                head += f"; {worst.evidence}"
            out.append(head)
        if self.cheapest is not None:
            out.append(f"use {self.cheapest.method.label}: the cheapest trusted method "
                       f"({self.cheapest.cpu_time:.3g} s CPU over {n} scenario"
                       f"{'s' * (n != 1)})")
        else:
            out.append("no method is trusted on these scenarios")
        return out


def summarise(judgements: Sequence[Judgement], scenarios: Sequence[str],
              consensus: Mapping[str, Consensus] | None = None,
              tolerances: VerdictTolerances | None = None) -> Verdict:
    """The :class:`Verdict` of a set of judgements (methods in first-seen order)."""
    by_method: dict[Method, list[Judgement]] = {}
    for j in judgements:
        by_method.setdefault(j.method, []).append(j)
    methods = tuple(MethodVerdict(m, min((j.trust for j in js), key=lambda t: t.rank),
                                  tuple(js)) for m, js in by_method.items())
    trusted = [mv for mv in methods if mv.trust is Trust.TRUSTED]
    cheapest = min(trusted, key=lambda mv: mv.cpu_time) if trusted else None
    return Verdict(methods, tuple(scenarios), cheapest, dict(consensus or {}),
                   tolerances or VerdictTolerances())

