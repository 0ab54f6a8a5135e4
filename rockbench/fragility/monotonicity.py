"""Non-monotone exceedance over intensity levels: the rocking "safe islands".

A rocking block that overturns under a record scaled to some intensity may
survive the same record scaled higher (the overturning spectra of Housner-type
blocks have such islands of safety; e.g. Dimitrakopoulos & DeJong 2012). An
incremental dynamic analysis therefore gives exceedance fractions that can
drop as the intensity grows. They are reported here as they are, level by
level, rather than smoothed into a monotone curve: a lognormal fit of such
data describes the trend, not the islands.

The same routine serves one record's 0/1 outcomes over its levels and the
fraction of a set of records exceeded at each level (there, since every
record is run at every level, a drop means that some record has an island).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rockbench.fragility.fit import FragilityError

__all__ = ["Island", "find_non_monotone"]


@dataclass(frozen=True)
class Island:
    """A run of consecutive levels whose fraction lies below one reached at a lower level.

    Attributes
    ----------
    first_level, last_level : float
        The first and last intensity levels of the run.
    fraction : float
        The lowest fraction exceeded inside the run.
    peak_level : float
        The lowest level below the run at which ``peak_fraction`` was reached.
    peak_fraction : float
        The highest fraction at any level below the run.
    """

    first_level: float
    last_level: float
    fraction: float
    peak_level: float
    peak_fraction: float

    @property
    def drop(self) -> float:
        """peak_fraction − fraction (> 0)."""
        return self.peak_fraction - self.fraction


def find_non_monotone(levels: Sequence[float] | np.ndarray,
                      fractions: Sequence[float] | np.ndarray,
                      tolerance: float = 0.0) -> tuple[Island, ...]:
    """The islands where the exceedance fraction falls as the intensity grows.

    A level is in an island when its fraction is lower, by more than
    ``tolerance``, than the highest fraction at any lower level; consecutive
    such levels form one island.

    Parameters
    ----------
    levels : array_like, shape (L,)
        Intensity levels, strictly increasing.
    fractions : array_like, shape (L,)
        Fraction exceeded at each level, in [0, 1] (0/1 for a single record).
    tolerance : float
        Smallest drop reported (≥ 0); 0 reports every drop.

    Returns
    -------
    tuple of Island
        Empty when the fractions never decrease.
    """
    x = np.asarray(levels, float)
    f = np.asarray(fractions, float)
    if x.ndim != 1 or x.shape != f.shape:
        raise FragilityError(f"levels and fractions must be 1-D of one length, got "
                             f"{x.shape} and {f.shape}")
    if np.any(np.diff(x) <= 0):
        raise FragilityError("levels must be strictly increasing")
    if not (np.all(np.isfinite(f)) and np.all((f >= 0) & (f <= 1))):
        raise FragilityError("fractions must be finite and in [0, 1]")
    if not tolerance >= 0:
        raise FragilityError(f"tolerance must be >= 0, got {tolerance!r}")
    islands: list[Island] = []
    peak_i = 0
    start = -1
    for i in range(1, f.size + 1):
        low = i < f.size and f[i] < f[peak_i] - tolerance
        if low and start < 0:
            start = i
        if not low and start >= 0:
            inside = f[start:i]
            islands.append(Island(float(x[start]), float(x[i - 1]), float(inside.min()),
                                  float(x[peak_i]), float(f[peak_i])))
            start = -1
        # the peak is taken over the levels below the current one, including islands
        if i < f.size and f[i] > f[peak_i]:
            peak_i = i
    return tuple(islands)
