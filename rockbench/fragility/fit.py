"""Lognormal fragility functions fitted by maximum likelihood, with bootstrap intervals.

A fragility function gives the probability that a limit state (overturning, a
rocking-angle threshold) is exceeded at intensity x. The lognormal form

    P(x) = Φ(ln(x / θ) / β)

has median θ and dispersion β. Following Baker (2015), θ and β are estimated
from z_j exceedances in n_j runs at each intensity level x_j by maximising the
binomial log-likelihood

    ln L(θ, β) = Σ_j [ z_j ln Φ(ln(x_j/θ)/β) + (n_j − z_j) ln(1 − Φ(ln(x_j/θ)/β)) ]

(the constant Σ ln C(n_j, z_j) is left out). In the variables a = −ln θ / β
and b = 1 / β this is a probit regression on ln x, whose log-likelihood is
concave: the maximum is unique when it exists. It does not exist when the
data are separated (no level, or one level only, has both exceedances and
non-exceedances) or when nothing or everything is exceeded; the fit then
says so in its :class:`FitStatus` and gives the bounds on θ the data do
support, never a number the likelihood cannot back.

Bootstrap confidence intervals resample the runs within each level (so a
level's resampled count is binomial with the observed fraction) and refit.

References
----------
J. W. Baker (2015), Efficient analytical fragility function fitting using
dynamic structural analysis, Earthquake Spectra 31(1), 579–599.
A. Albert, J. A. Anderson (1984), On the existence of maximum likelihood
estimates in logistic regression models, Biometrika 71(1), 1–10 (separation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import Enum
from typing import Any

import numpy as np
from scipy import special

from rockbench.errors import RockbenchError

__all__ = ["ExceedanceData", "FitStatus", "FragilityFit", "FragilityBootstrap",
           "LevelProbability", "FragilityError", "fit_fragility", "bootstrap_fragility"]


class FragilityError(RockbenchError, ValueError):
    """Exceedance data that cannot be fitted at all (bad shapes or counts)."""


@dataclass(frozen=True)
class ExceedanceData:
    """Runs and exceedances of one limit state at each intensity level.

    Attributes
    ----------
    levels : tuple of float
        Intensity levels x_j (> 0, distinct), in increasing order.
    runs : tuple of int
        Number of runs n_j at each level (≥ 1).
    exceeded : tuple of int
        Number of runs z_j that exceeded the limit state (0 ≤ z_j ≤ n_j).
    """

    levels: tuple[float, ...]
    runs: tuple[int, ...]
    exceeded: tuple[int, ...]

    def __post_init__(self) -> None:
        x = np.asarray(self.levels, float)
        n = np.asarray(self.runs)
        z = np.asarray(self.exceeded)
        if x.ndim != 1 or x.shape != n.shape or x.shape != z.shape or x.size == 0:
            raise FragilityError(
                f"levels, runs and exceeded must be 1-D of the same non-zero length, got "
                f"{x.shape}, {n.shape}, {z.shape}")
        if not np.all(np.isfinite(x) & (x > 0)):
            raise FragilityError("intensity levels must be finite and > 0")
        if np.any(np.diff(x) <= 0):
            raise FragilityError("intensity levels must be distinct and increasing")
        if not (np.all(n == np.round(n)) and np.all(z == np.round(z))):
            raise FragilityError("runs and exceeded must be whole numbers")
        if np.any(n < 1) or np.any(z < 0) or np.any(z > n):
            raise FragilityError("need runs >= 1 and 0 <= exceeded <= runs at every level")
        object.__setattr__(self, "levels", tuple(float(v) for v in x))
        object.__setattr__(self, "runs", tuple(int(v) for v in n))
        object.__setattr__(self, "exceeded", tuple(int(v) for v in z))

    @classmethod
    def from_outcomes(cls, levels: np.ndarray | list[float],
                      outcomes: np.ndarray) -> ExceedanceData:
        """Counts from a table of outcomes, one row per record (or run) and one column per level.

        Parameters
        ----------
        levels : array_like, shape (L,)
            Intensity levels, increasing.
        outcomes : array_like, shape (R, L)
            1 (or True) where the run exceeded the limit state, 0 where it did
            not, NaN where the run is missing (failed or not run); missing runs
            are left out of that level's count. Levels with no run are dropped.
        """
        x = np.asarray(levels, float)
        o = np.asarray(outcomes, float)
        if o.ndim != 2 or o.shape[1] != x.size:
            raise FragilityError(f"outcomes must have shape (runs, {x.size}), got {o.shape}")
        done = ~np.isnan(o)
        if np.any((o[done] != 0) & (o[done] != 1)):
            raise FragilityError("outcomes must be 0, 1 or NaN")
        n = done.sum(axis=0)
        z = np.where(done, o, 0.0).sum(axis=0)
        keep = n > 0
        return cls(tuple(x[keep]), tuple(n[keep]), tuple(z[keep]))

    @property
    def fractions(self) -> np.ndarray:
        """Observed fraction exceeded z_j / n_j at each level."""
        return np.asarray(self.exceeded, float) / np.asarray(self.runs, float)

    @property
    def total_runs(self) -> int:
        """Σ n_j."""
        return int(sum(self.runs))


class FitStatus(Enum):
    """Whether the likelihood has a finite maximum, and if not, why."""

    #: Finite maximum-likelihood median and dispersion.
    OK = "ok"
    #: No run exceeded: θ lies above the highest level; β is not identified.
    NONE_EXCEEDED = "none-exceeded"
    #: Every run exceeded: θ lies below the lowest level; β is not identified.
    ALL_EXCEEDED = "all-exceeded"
    #: Nothing exceeded up to one level and everything from the next on: the
    #: likelihood grows as β → 0 with θ anywhere between the two levels.
    SEPARATED = "separated"
    #: Only one level has both outcomes (all below none, all above every run):
    #: the likelihood grows as β → 0 with θ → that level.
    SINGLE_TRANSITION = "single-transition"
    #: The fractions do not increase with intensity overall: the best
    #: increasing lognormal is the constant one (β → ∞). See
    #: :func:`rockbench.fragility.monotonicity.find_non_monotone`.
    NOT_INCREASING = "not-increasing"


@dataclass(frozen=True)
class FragilityFit:
    """A lognormal fragility fitted by maximum likelihood (Baker 2015).

    Attributes
    ----------
    status : FitStatus
        ``OK`` for a finite fit; otherwise why there is none.
    median : float
        θ, in the units of the levels. Finite for ``OK``; the limit of the
        estimate (the transition level) for ``SINGLE_TRANSITION``; NaN otherwise.
    dispersion : float
        β (dimensionless, > 0) for ``OK``; NaN otherwise (it tends to 0 for
        ``SEPARATED`` and ``SINGLE_TRANSITION``, to ∞ for ``NOT_INCREASING``).
    median_range : tuple of float
        The interval the data confine θ to: (θ, θ) for ``OK``; e.g.
        (highest level, inf) for ``NONE_EXCEEDED``; (0, inf) for ``NOT_INCREASING``.
    log_likelihood : float
        The maximised ln L (its supremum for the degenerate cases), without
        the binomial constant.
    n_levels : int
        Number of intensity levels.
    n_runs : int
        Total number of runs.
    level_range : tuple of float
        Lowest and highest intensity level of the data.
    """

    status: FitStatus
    median: float
    dispersion: float
    median_range: tuple[float, float]
    log_likelihood: float
    n_levels: int
    n_runs: int
    level_range: tuple[float, float]

    @property
    def ok(self) -> bool:
        """True for a finite fit."""
        return self.status is FitStatus.OK

    @property
    def extrapolated(self) -> bool:
        """True for a finite fit whose median lies outside the tested levels.

        The maximum exists but rests on the tail of the curve only (data that
        barely change over the levels give a large β and a far median): report
        it as an extrapolation, not as a measured median.
        """
        return self.ok and not self.level_range[0] <= self.median <= self.level_range[1]

    def probability(self, x: float | np.ndarray) -> np.ndarray:
        """P(exceed | x) = Φ(ln(x/θ)/β) of the fitted curve.

        Raises
        ------
        FragilityError
            If the fit is not ``OK`` (there is no curve to evaluate).
        """
        if not self.ok:
            raise FragilityError(f"no fragility curve: the fit is {self.status.value}")
        return special.ndtr(np.log(np.asarray(x, float) / self.median) / self.dispersion)

    def to_dict(self) -> dict[str, object]:
        """JSON-ready form (status as its name, non-finite numbers as None)."""
        def num(v: float) -> float | None:
            return v if math.isfinite(v) else None
        return {"status": self.status.value, "median": num(self.median),
                "dispersion": num(self.dispersion),
                "median_range": [num(v) for v in self.median_range],
                "log_likelihood": num(self.log_likelihood), "n_levels": self.n_levels,
                "n_runs": self.n_runs, "level_range": list(self.level_range),
                "extrapolated": self.extrapolated}


@dataclass(frozen=True)
class FragilityBootstrap:
    """Bootstrap confidence intervals on the median and dispersion of a fragility fit.

    Attributes
    ----------
    fit : FragilityFit
        The fit of the original data.
    confidence : float
        Two-sided confidence level of the intervals (e.g. 0.95).
    median_interval, dispersion_interval : tuple of float
        Percentile intervals (low, high) of θ and β over the resamples that
        have a finite fit; (NaN, NaN) when the original fit is not ``OK`` (then
        nothing is resampled) or no resample has a finite fit.
    n_resamples : int
        Number of resamples drawn.
    n_degenerate : int
        Resamples without a finite fit (their statuses are not ``OK``), left
        out of the intervals. The intervals are conditional on a finite fit, so
        a large share of degenerate resamples (sparse data near the transition)
        means they understate the uncertainty.
    seed : int
        Seed of the random generator.
    resampled : tuple of ndarray
        θ and β of the resamples with a finite fit (empty when nothing was resampled).
    """

    fit: FragilityFit
    confidence: float
    median_interval: tuple[float, float]
    dispersion_interval: tuple[float, float]
    n_resamples: int
    n_degenerate: int
    seed: int
    resampled: tuple[np.ndarray, np.ndarray] = field(
        default=(np.empty(0), np.empty(0)), repr=False, compare=False)

    @property
    def degenerate_fraction(self) -> float:
        """n_degenerate / n_resamples (0 when nothing was resampled)."""
        return self.n_degenerate / self.n_resamples if self.n_resamples else 0.0

    def probability_at(self, level: float) -> LevelProbability:
        """P(exceeded | IM = ``level``) = Φ(ln(level/θ)/β), with its percentile interval.

        The interval is that of the same probability over the resamples with a finite
        fit; everything is NaN when the fit itself is not ``OK``.
        """
        level = float(level)
        if not (math.isfinite(level) and level > 0.0):
            raise FragilityError(f"the design level must be a finite number > 0, got {level!r}")
        if not self.fit.ok:
            return LevelProbability(level, math.nan, (math.nan, math.nan))
        p = float(special.ndtr(math.log(level / self.fit.median) / self.fit.dispersion))
        theta, beta = self.resampled
        ps = special.ndtr(np.log(level / theta) / beta)
        return LevelProbability(level, p, percentile_interval(ps, self.confidence))


@dataclass(frozen=True)
class LevelProbability:
    """The probability of exceeding a limit state at one intensity level.

    Attributes
    ----------
    level : float
        The intensity level (the study's measure and units).
    probability : float
        Φ(ln(level/θ)/β) of the fit.
    interval : tuple of float
        Its bootstrap percentile interval.
    """

    level: float
    probability: float
    interval: tuple[float, float]


def _centre(levels: np.ndarray) -> tuple[np.ndarray, float]:
    """ln x − c with c the mean of ln x, which keeps the probit (a, b) well conditioned."""
    lx = np.log(levels)
    c = float(lx.mean())
    return lx - c, c


def _log_likelihood(a: np.ndarray | float, b: np.ndarray | float, x: np.ndarray,
                    n: np.ndarray, z: np.ndarray) -> np.ndarray:
    """ln L at u = a + b x (broadcast over leading axes of a, b, z); log_ndtr keeps the tails."""
    u = np.asarray(a)[..., None] + np.asarray(b)[..., None] * x
    return np.sum(z * special.log_ndtr(u) + (n - z) * special.log_ndtr(-u), axis=-1)


def _score_terms(u: np.ndarray, n: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """d lnL/du and −d² lnL/du² (≥ 0: ln Φ is concave) at each level."""
    log_phi = -0.5 * u * u - 0.5 * math.log(2.0 * math.pi)
    h_up = np.exp(log_phi - special.log_ndtr(u))     # φ/Φ = d ln Φ(u)/du
    h_down = np.exp(log_phi - special.log_ndtr(-u))  # φ/(1−Φ) = −d ln(1 − Φ(u))/du
    return (z * h_up - (n - z) * h_down,
            z * h_up * (u + h_up) + (n - z) * h_down * (h_down - u))


def _classify(n: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per row of (R, L) counts: the index of the highest level with a non-exceedance,
    the lowest with an exceedance, and whether the row has exceedances at all."""
    levels = np.arange(n.shape[-1])
    has_no = z < n
    has_yes = z > 0
    hi_no = np.where(has_no, levels, -1).max(axis=-1)
    lo_yes = np.where(has_yes, levels, n.shape[-1]).min(axis=-1)
    return hi_no, lo_yes, np.asarray(has_yes.any(axis=-1))


def _degenerate(data: ExceedanceData) -> FragilityFit | None:
    """The fit of separated data (no finite maximum), or None when the data overlap."""
    x = np.asarray(data.levels)
    n = np.asarray(data.runs)
    z = np.asarray(data.exceeded)
    hi_no, lo_yes, any_yes = (int(v) for v in _classify(n, z))
    common = _common(data)
    nan = math.nan
    if not any_yes:
        return FragilityFit(FitStatus.NONE_EXCEEDED, nan, nan, (float(x[-1]), math.inf),
                            0.0, **common)
    if hi_no < 0:
        return FragilityFit(FitStatus.ALL_EXCEEDED, nan, nan, (0.0, float(x[0])), 0.0, **common)
    if hi_no < lo_yes:
        return FragilityFit(FitStatus.SEPARATED, nan, nan, (float(x[hi_no]), float(x[lo_yes])),
                            0.0, **common)
    if hi_no == lo_yes:
        i = hi_no
        f = z[i] / n[i]
        ll = float(z[i] * math.log(f) + (n[i] - z[i]) * math.log1p(-f))
        lo = float(x[i - 1]) if i > 0 else 0.0
        hi = float(x[i + 1]) if i + 1 < x.size else math.inf
        return FragilityFit(FitStatus.SINGLE_TRANSITION, float(x[i]), nan, (lo, hi), ll,
                            **common)
    return None


def _common(data: ExceedanceData) -> dict[str, Any]:
    """The fields every fit of ``data`` shares."""
    return {"n_levels": len(data.levels), "n_runs": data.total_runs,
            "level_range": (data.levels[0], data.levels[-1])}


def _not_increasing(data: ExceedanceData) -> FragilityFit:
    """The constant-probability limit (β → ∞) that an increasing lognormal tends to."""
    n = np.asarray(data.runs, float)
    z = np.asarray(data.exceeded, float)
    p = z.sum() / n.sum()
    ll = float(np.sum(z * math.log(p) + (n - z) * math.log1p(-p)))
    return FragilityFit(FitStatus.NOT_INCREASING, math.nan, math.nan, (0.0, math.inf), ll,
                        **_common(data))


def fit_fragility(data: ExceedanceData) -> FragilityFit:
    """Maximum-likelihood lognormal fragility of exceedance data (Baker 2015).

    Parameters
    ----------
    data : ExceedanceData
        Runs and exceedances per intensity level.

    Returns
    -------
    FragilityFit
        Status ``OK`` with θ and β, or a degenerate status with the bounds on
        θ that the data support (see :class:`FitStatus`).
    """
    degenerate = _degenerate(data)
    if degenerate is not None:
        return degenerate
    x, c = _centre(np.asarray(data.levels))
    n = np.asarray(data.runs, float)
    z = np.asarray(data.exceeded, float)

    def objective(q: np.ndarray) -> tuple[float, np.ndarray]:
        u = q[0] + q[1] * x
        r, _ = _score_terms(u, n, z)
        return -float(_log_likelihood(q[0], q[1], x, n, z)), -np.array([r.sum(), r @ x])

    # imported here: scipy.optimize takes about a second to import, and scenario files
    # reach this package (for the record intensities) without fitting anything
    from scipy import optimize

    p = z.sum() / n.sum()
    res = optimize.minimize(objective, np.array([special.ndtri(p), 1.0]), jac=True,
                            method="BFGS", options={"gtol": 1e-10, "maxiter": 500})
    a, b = float(res.x[0]), float(res.x[1])
    # the slope b = 1/β must be positive; b ≤ 0 means no increasing fit beats a constant one
    if not b > 0:
        return _not_increasing(data)
    if not res.success and np.max(np.abs(res.jac)) > 1e-6 * max(1.0, data.total_runs):
        raise FragilityError(f"fragility fit did not converge: {res.message}")
    # a nearly flat fit can put θ beyond the floats (it is then flagged extrapolated)
    ln_theta = c - a / b
    theta = math.exp(ln_theta) if ln_theta < 709.0 else math.inf
    return FragilityFit(FitStatus.OK, theta, 1.0 / b, (theta, theta), -float(res.fun),
                        **_common(data))


def _fit_batch(x: np.ndarray, n: np.ndarray, z: np.ndarray, iterations: int = 100,
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Probit MLE (a, b) of many count rows z (R, L) at once, by Newton's method.

    The bootstrap refits hundreds of resamples; one vectorised Newton
    iteration over all of them costs about as much as one scipy fit. Each
    step is capped (a trust region on u) and halved until the log-likelihood
    does not decrease (it is concave, so this converges). Returns a, b and a
    mask of the rows that converged.
    """
    rows = z.shape[0]
    p = np.clip(z.sum(axis=1) / np.broadcast_to(n, z.shape).sum(axis=1), 1e-6, 1.0 - 1e-6)
    a = special.ndtri(p)
    b = np.ones(rows)
    ll = _log_likelihood(a, b, x, n, z)
    done = np.zeros(rows, bool)
    failed = np.zeros(rows, bool)
    for _ in range(iterations):
        u = a[:, None] + b[:, None] * x
        r, w = _score_terms(u, n, z)
        g0, g1 = r.sum(axis=1), (r * x).sum(axis=1)
        i00, i01, i11 = w.sum(axis=1), (w * x).sum(axis=1), (w * x * x).sum(axis=1)
        det = i00 * i11 - i01 * i01
        with np.errstate(divide="ignore", invalid="ignore"):
            da, db = (i11 * g0 - i01 * g1) / det, (i00 * g1 - i01 * g0) / det
        # a vanishing information (a row running off to separation) stops that row
        failed |= ~(np.isfinite(da) & np.isfinite(db))
        frozen = done | failed
        da, db = np.where(frozen, 0.0, da), np.where(frozen, 0.0, db)
        # a trust region: no step moves a level's u = a + b x by more than 2, so that an
        # overshoot cannot land where Φ saturates and the information vanishes
        du = np.max(np.abs(da[:, None] + db[:, None] * x), axis=1)
        step = np.minimum(1.0, 2.0 / np.maximum(du, 1e-300))
        for _ in range(40):
            ll_new = _log_likelihood(a + step * da, b + step * db, x, n, z)
            worse = ll_new < ll - 1e-12 * np.abs(ll)
            if not worse.any():
                break
            step = np.where(worse, 0.5 * step, step)
        a, b, ll = a + step * da, b + step * db, np.maximum(ll, ll_new)
        done |= ~failed & (np.maximum(np.abs(step * da), np.abs(step * db)) < 1e-10)
        if (done | failed).all():
            break
    return a, b, done


def bootstrap_fragility(data: ExceedanceData, n_resamples: int = 1000,
                        confidence: float = 0.95, seed: int = 0) -> FragilityBootstrap:
    """Fit, then bootstrap percentile intervals on θ and β by resampling runs within levels.

    Each resample draws, at every level, n_j runs with replacement from that
    level's n_j observed outcomes (so z*_j ~ Binomial(n_j, z_j/n_j)), and is
    refitted by maximum likelihood.

    Parameters
    ----------
    data : ExceedanceData
        Runs and exceedances per intensity level.
    n_resamples : int
        Number of bootstrap resamples (≥ 1).
    confidence : float
        Two-sided confidence level in (0, 1).
    seed : int
        Seed of :func:`numpy.random.default_rng`; the same seed gives the same intervals.

    Returns
    -------
    FragilityBootstrap
        The fit and the intervals; no resampling (NaN intervals) when the fit
        is not ``OK``.
    """
    if int(n_resamples) != n_resamples or n_resamples < 1:
        raise FragilityError(f"n_resamples must be a positive integer, got {n_resamples!r}")
    if not 0.0 < confidence < 1.0:
        raise FragilityError(f"confidence must be in (0, 1), got {confidence!r}")
    fit = fit_fragility(data)
    nan2 = (math.nan, math.nan)
    if not fit.ok:
        return FragilityBootstrap(fit, confidence, nan2, nan2, 0, 0, seed)
    rng = np.random.default_rng(seed)
    n = np.asarray(data.runs)
    z_star = rng.binomial(n, data.fractions, size=(int(n_resamples), n.size))
    theta, beta = refit(np.asarray(data.levels), n, z_star)
    good = np.isfinite(theta)
    return FragilityBootstrap(fit, confidence, percentile_interval(theta[good], confidence),
                              percentile_interval(beta[good], confidence), int(n_resamples),
                              int(n_resamples) - int(good.sum()), seed,
                              (theta[good], beta[good]))


def refit(levels: np.ndarray, runs: np.ndarray, exceeded: np.ndarray,
          ) -> tuple[np.ndarray, np.ndarray]:
    """θ and β fitted to each row of counts, NaN where a row has no finite fit.

    For resampling: ``exceeded`` has shape (B, L) and ``runs`` (L,) or (B, L);
    a level with no run in a row (n = 0) adds nothing to that row's likelihood.
    """
    z = np.asarray(exceeded, float)
    n = np.broadcast_to(np.asarray(runs, float), z.shape)
    hi_no, lo_yes, any_yes = _classify(n, z)
    overlap = any_yes & (hi_no >= 0) & (hi_no > lo_yes)
    x, c = _centre(np.asarray(levels, float))
    a, b, converged = _fit_batch(x, n[overlap], z[overlap])
    good = converged & (b > 0)
    rows = np.flatnonzero(overlap)[good]
    theta = np.full(z.shape[0], math.nan)
    beta = np.full(z.shape[0], math.nan)
    with np.errstate(over="ignore"):
        theta[rows] = np.exp(c - a[good] / b[good])
    beta[rows] = 1.0 / b[good]
    return theta, beta


def percentile_interval(values: np.ndarray, confidence: float) -> tuple[float, float]:
    """The two-sided percentile interval of ``values``; (NaN, NaN) if there are none."""
    if values.size == 0:
        return math.nan, math.nan
    q = 100.0 * np.array([0.5 * (1.0 - confidence), 0.5 * (1.0 + confidence)])
    lo, hi = np.percentile(values, q)
    return float(lo), float(hi)
