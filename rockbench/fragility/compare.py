"""A method's fragility median against a reference's, with a paired bootstrap interval.

In an incremental dynamic analysis every method (an engine, the analytic
reference) runs the same records at the same levels. The record-to-record
variability is then common to both, and the uncertainty of their difference
is much smaller than that of either median. :func:`compare_medians`
therefore resamples the records (rows of the outcome tables) with the *same*
draw for both methods, refits both, and gives the percentile interval of the
ratio θ_method / θ_reference. Resampling a row resamples that record's run
at every level, i.e. the runs within each level, jointly across levels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rockbench.fragility.fit import (
    ExceedanceData,
    FragilityError,
    FragilityFit,
    fit_fragility,
    percentile_interval,
    refit,
)

__all__ = ["MedianComparison", "compare_medians"]


@dataclass(frozen=True)
class MedianComparison:
    """θ_method / θ_reference and its paired bootstrap interval.

    Attributes
    ----------
    method, reference : FragilityFit
        The two fits of the original outcomes.
    ratio : float
        θ_method / θ_reference; NaN unless both fits are ``OK``.
    ratio_interval : tuple of float
        Percentile interval of the ratio over the resamples where both fits
        are finite; (NaN, NaN) when ``ratio`` is NaN.
    confidence : float
        Two-sided confidence level.
    n_resamples : int
        Resamples drawn (0 when ``ratio`` is NaN).
    n_degenerate : int
        Resamples where either fit has no finite maximum (left out).
    seed : int
        Seed of the random generator.
    """

    method: FragilityFit
    reference: FragilityFit
    ratio: float
    ratio_interval: tuple[float, float]
    confidence: float
    n_resamples: int
    n_degenerate: int
    seed: int

    @property
    def log_difference(self) -> float:
        """ln(θ_method / θ_reference), on the scale of the dispersions β."""
        return math.log(self.ratio) if self.ratio > 0 else math.nan


def _counts(outcomes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Runs and exceedances per level of each resampled table, shape (B, L)."""
    done = ~np.isnan(outcomes)
    return done.sum(axis=-2), np.where(done, outcomes, 0.0).sum(axis=-2)


def compare_medians(levels: np.ndarray | list[float], outcomes: np.ndarray,
                    reference_outcomes: np.ndarray, n_resamples: int = 1000,
                    confidence: float = 0.95, seed: int = 0) -> MedianComparison:
    """Compare a method's fragility median with a reference's over the same records.

    Parameters
    ----------
    levels : array_like, shape (L,)
        Intensity levels, increasing.
    outcomes, reference_outcomes : array_like, shape (R, L)
        Outcome tables (1 exceeded, 0 not, NaN missing; see
        :meth:`ExceedanceData.from_outcomes`) of the method and of the
        reference, row i being the same record in both.
    n_resamples : int
        Bootstrap resamples of the records.
    confidence : float
        Two-sided confidence level in (0, 1).
    seed : int
        Seed of :func:`numpy.random.default_rng`.
    """
    x = np.asarray(levels, float)
    method, reference = np.asarray(outcomes, float), np.asarray(reference_outcomes, float)
    if method.shape != reference.shape or method.ndim != 2 or method.shape[1] != x.size:
        raise FragilityError(f"outcome tables must both have shape (records, {x.size}), got "
                             f"{method.shape} and {reference.shape}")
    tables = np.stack([method, reference])
    if int(n_resamples) != n_resamples or n_resamples < 1:
        raise FragilityError(f"n_resamples must be a positive integer, got {n_resamples!r}")
    if not 0.0 < confidence < 1.0:
        raise FragilityError(f"confidence must be in (0, 1), got {confidence!r}")
    fits = [fit_fragility(ExceedanceData.from_outcomes(x, t)) for t in tables]
    nan2 = (math.nan, math.nan)
    if not (fits[0].ok and fits[1].ok):
        return MedianComparison(fits[0], fits[1], math.nan, nan2, confidence, 0, 0, seed)
    rng = np.random.default_rng(seed)
    rows = rng.integers(0, tables.shape[1], size=(int(n_resamples), tables.shape[1]))
    thetas = []
    for table in tables:
        n, z = _counts(table[rows])
        thetas.append(refit(x, n, z)[0])
    # a far-extrapolated refit can put θ at 0 or inf: no ratio for that resample
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = thetas[0] / thetas[1]
    good = np.isfinite(ratio) & (ratio > 0)
    return MedianComparison(fits[0], fits[1], fits[0].median / fits[1].median,
                            percentile_interval(ratio[good], confidence), confidence,
                            int(n_resamples), int(n_resamples) - int(good.sum()), seed)
