"""Beyond the predictability horizon: distributions of an ensemble, per method.

Past t* (:mod:`rockbench.campaign.predictability`) the reference's own peaks and
outcome depend on perturbations of one part in 10⁶; what an engine can get
right there is their distribution. Each method (the analytic reference and
every engine) runs the same ``n`` perturbed members of a scenario
(:func:`rockbench.campaign.predictability.ensemble_scenarios`), through the
campaign (:func:`rockbench.campaign.run_campaign`: isolated, parallel or on
Dask, every member recorded in the store; reference members cached there).
Per method and block:

* the distribution of the peak max |θ_i|/λ over the whole run, over the members
  that completed without overturning (each member's peaks from
  :func:`rockbench.evaluation.evaluate_run`);
* the probability of overturning: overturned members / completed members;
* the distance to the reference's distribution: the 1-Wasserstein distance
  W₁ (in units of λ: the mean shift of the peaks needed to turn one
  distribution into the other), with a bias-corrected percentile bootstrap
  interval: both ensembles are resampled with replacement, and since the
  distance of two resamples is positive even between identical
  distributions, the percentiles are shifted by the bootstrap bias
  (mean of the resampled distances − the distance) and clipped at 0. Two
  finite samples of one distribution are at a positive distance, so no
  interval of W₁ covers 0: the **noise floor** says what "zero" looks like at
  these ensemble sizes, the 95th percentile of W₁ between random splits of the
  pooled members (a permutation test: a distance above it differs at the 5 %
  level). Measured on normal samples of 60: the interval covers the true W₁
  in 92-95 % of draws once it exceeds σ/5, and the noise floor is exceeded in
  5 % of draws of identical distributions.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import wasserstein_distance

from rockbench import analytic
from rockbench.campaign import CampaignOptions, PlannedRun, run_campaign
from rockbench.campaign.predictability import Perturbation, ensemble_scenarios
from rockbench.evaluation import RunMetrics
from rockbench.method import Method
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Scenario
from rockbench.trajectory import Status

__all__ = ["KIND", "Distance", "PeakDistribution", "EnsembleComparison", "bootstrap_distance",
           "peak_distribution", "run_ensembles", "compare_ensembles", "N_BOOTSTRAP", "LEVEL"]

#: The store's ``kind`` of the ensembles' runs.
KIND = "ensemble"
#: Bootstrap resamples of a distance.
N_BOOTSTRAP = 1000
#: Confidence level of the bootstrap interval.
LEVEL = 0.95


@dataclass(frozen=True)
class Distance:
    """W₁ between two samples (λ), its bootstrap interval and its noise floor.

    Attributes
    ----------
    value : float
        W₁ of the two samples.
    low, high : float
        Bias-corrected percentile bootstrap interval.
    noise : float
        95th percentile of W₁ between random splits of the pooled samples.
    """

    value: float
    low: float
    high: float
    noise: float = 0.0

    @property
    def significant(self) -> bool:
        """The samples differ beyond the noise of their sizes (5 % level)."""
        return self.value > self.noise


@dataclass(frozen=True)
class PeakDistribution:
    """One method's ensemble on one scenario.

    Attributes
    ----------
    scenario, method : str
        Scenario name and method label.
    peaks : tuple of tuple of float
        Per block (bottom first), max |θ_i|/λ of each member that completed ``ok``.
    overturned : int
        Members that overturned.
    failed : int
        Members that did not complete (crashed, unstable, unsupported, ...).
    members : int
        Members run.
    """

    scenario: str
    method: str
    peaks: tuple[tuple[float, ...], ...]
    overturned: int
    failed: int
    members: int

    @property
    def completed(self) -> int:
        """Members that ended ``ok`` or ``overturned``."""
        return self.members - self.failed

    @property
    def p_overturn(self) -> float | None:
        """Probability of overturning (None when no member completed)."""
        return self.overturned / self.completed if self.completed else None


@dataclass(frozen=True)
class EnsembleComparison:
    """An engine's ensemble against the reference's on one scenario.

    Attributes
    ----------
    engine, reference : PeakDistribution
        The two ensembles.
    distances : tuple of Distance or None
        Per block, W₁ of the peak distributions (None where either has fewer
        than two peaks).
    overturn_difference : float or None
        p_overturn(engine) − p_overturn(reference).
    """

    engine: PeakDistribution
    reference: PeakDistribution
    distances: tuple[Distance | None, ...]
    overturn_difference: float | None

    @property
    def scenario(self) -> str:
        """Scenario name."""
        return self.engine.scenario

    @property
    def method(self) -> str:
        """The engine's method label."""
        return self.engine.method


def bootstrap_distance(a: Sequence[float], b: Sequence[float], *, n_boot: int = N_BOOTSTRAP,
                       level: float = LEVEL, seed: int = 0) -> Distance:
    """W₁(a, b) with a bias-corrected percentile bootstrap interval at ``level``.

    Raises
    ------
    ValueError
        Either sample is empty.
    """
    x, y = np.asarray(a, float), np.asarray(b, float)
    if x.size == 0 or y.size == 0:
        raise ValueError("a distance needs two non-empty samples")
    rng = np.random.default_rng(seed)
    boots = np.array([wasserstein_distance(rng.choice(x, x.size), rng.choice(y, y.size))
                      for _ in range(n_boot)])
    value = float(wasserstein_distance(x, y))
    q = (1.0 - level) / 2.0
    bias = float(np.mean(boots)) - value
    lo, hi = np.maximum(np.quantile(boots, [q, 1.0 - q]) - bias, 0.0)
    pool = np.concatenate([x, y])
    null = []
    for _ in range(n_boot):
        perm = rng.permutation(pool)
        null.append(wasserstein_distance(perm[:x.size], perm[x.size:]))
    return Distance(value, float(lo), float(hi), float(np.quantile(null, 0.95)))


def peak_distribution(scenario: Scenario, method: str,
                      members: Sequence[tuple[Scenario, RunMetrics]]) -> PeakDistribution:
    """The distribution of one method's members (each measured by ``evaluate_run``)."""
    peaks: list[list[float]] = [[] for _ in range(scenario.n_blocks)]
    over = failed = 0
    for _, m in members:
        if m.status is Status.OVERTURNED:
            over += 1
        elif m.status is not Status.OK:
            failed += 1
        else:
            for i, p in enumerate(m.peaks):
                if p is not None:
                    peaks[i].append(p)
    return PeakDistribution(scenario.name, method, tuple(tuple(p) for p in peaks), over,
                            failed, len(members))


def run_ensembles(
    scenarios: Sequence[Scenario],
    methods: Sequence[Method],
    n: int,
    perturbation: Perturbation | None = None,
    *,
    db: Path | None = None,
    execution: ExecutionOptions | None = None,
    timeout: float | None = None,
    progress: Callable[[int, str], Any] | None = None,
) -> dict[tuple[str, str], PeakDistribution]:
    """Run ``n`` perturbed members of each scenario with an analytic model on each method.

    Parameters
    ----------
    scenarios : sequence of Scenario
        The cases (those without an analytic model are left out).
    methods : sequence of Method
        The reference and the engines (the reference is always included).
    n : int
        Members per scenario and method (>= 2).
    perturbation : Perturbation, optional
        Default :class:`Perturbation` ``()``.
    db, execution, timeout, progress
        The results store (every member is recorded), how the runs are
        executed, the per-run time limit (None: the campaign's default) and a
        progress factory (see :func:`rockbench.campaign.run_campaign`).

    Returns
    -------
    dict
        (scenario name, method label) → :class:`PeakDistribution`.
    """
    if n < 2:
        raise ValueError(f"a distribution needs at least 2 members, got {n}")
    pert = perturbation or Perturbation()
    cases = [s for s in scenarios if analytic.has_reference(s)]
    members = {s.name: ensemble_scenarios(s, n, pert) for s in cases}
    every = [Method.reference()] + [m for m in methods if not m.is_reference]
    plan = [PlannedRun(m, meth) for s in cases for meth in every for m in members[s.name]]
    campaign = run_campaign(plan, CampaignOptions(
        kind=KIND, db=db, execution=execution or ExecutionOptions(), timeout=timeout),
        progress=progress)
    got: dict[tuple[str, str], list[tuple[Scenario, RunMetrics]]] = {}
    for res in campaign.results:
        base = res.scenario.name.rsplit("~p", 1)[0]
        got.setdefault((base, res.method.label), []).append((res.scenario, res.metrics))
    by_name = {s.name: s for s in cases}
    return {(name, label): peak_distribution(by_name[name], label, runs)
            for (name, label), runs in got.items()}


def compare_ensembles(dists: Mapping[tuple[str, str], PeakDistribution], *,
                      n_boot: int = N_BOOTSTRAP, seed: int = 0) -> list[EnsembleComparison]:
    """Each engine's distribution against the reference's, per scenario (input order)."""
    ref_label = Method.reference().label
    out = []
    for (name, label), d in dists.items():
        ref = dists.get((name, ref_label))
        if label == ref_label or ref is None:
            continue
        dist = tuple(bootstrap_distance(a, b, n_boot=n_boot, seed=seed)
                     if len(a) >= 2 and len(b) >= 2 else None
                     for a, b in zip(d.peaks, ref.peaks, strict=True))
        po, pr = d.p_overturn, ref.p_overturn
        out.append(EnsembleComparison(d, ref, dist, None if po is None or pr is None
                                      else po - pr))
    return out
