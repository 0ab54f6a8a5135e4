"""The coefficient of restitution a free-rocking trajectory shows, impact by impact.

Between impacts a rigid block rocking on a fixed base conserves energy, so its kinetic
energy as it passes upright equals the potential it had at the last peak of |θ|:
V(θ) = m g R [cos(λ − |θ|) − cos λ]. Housner's impact multiplies the angular velocity
by η, hence the kinetic energy by η², and the next peak θ_{k+1} satisfies
V(θ_{k+1}) = η² V(θ_k). Read backwards, every pair of successive peaks gives the
*effective* coefficient of restitution of that impact,

    η_k = sqrt(V(θ_{k+1}) / V(θ_k)),

whatever produced the trajectory: the analytic model (η_k = the η it was given, to the
peaks' sampling), an engine (whose contact model has no η of its own: a soft contact
dissipates through its damping and its compliance, an impulse solver through its
restitution and its iterations), or a shake-table test. Peaks below a floor are left out:
there the contact's own jitter, not the impact, sets the ratio.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rockbench.errors import RockbenchError

__all__ = ["ImpactRestitution", "effective_restitution", "half_cycle_peaks", "PEAK_FLOOR"]

#: Peaks below this fraction of λ are not used: the contact's jitter dominates there.
PEAK_FLOOR = 0.02


@dataclass(frozen=True)
class ImpactRestitution:
    """The effective η of each impact of one free-rocking trajectory.

    Attributes
    ----------
    peaks : tuple of float
        |θ| of each half-cycle's peak (rad), from the release on.
    peak_times : tuple of float
        When each peak is reached (s).
    eta : tuple of float
        η_k between peaks k and k + 1 (one fewer than the peaks).
    """

    peaks: tuple[float, ...]
    peak_times: tuple[float, ...]
    eta: tuple[float, ...]

    @property
    def mean(self) -> float:
        """Mean η over the impacts (NaN without one)."""
        return float(np.mean(self.eta)) if self.eta else math.nan

    @property
    def spread(self) -> float:
        """Largest minus smallest η over the impacts (NaN without one)."""
        return float(np.ptp(self.eta)) if self.eta else math.nan


def half_cycle_peaks(t: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The peak of |θ| in each stretch between sign changes, refined between samples.

    The largest sample of a half-cycle and its two neighbours are fitted with a parabola,
    whose vertex is the peak: the error falls as the square of the sampling step.

    Returns
    -------
    times, peaks : ndarray
        When each half-cycle peaks (s) and its |θ| there (rad).
    """
    t, a = np.asarray(t, float), np.abs(np.asarray(theta, float))
    sign = np.sign(theta)
    cuts = np.nonzero(sign[:-1] * sign[1:] < 0)[0] + 1
    times, peaks = [], []
    for lo, hi in zip(np.r_[0, cuts], np.r_[cuts, a.size], strict=True):
        if hi - lo < 1:
            continue
        i = lo + int(np.argmax(a[lo:hi]))
        if 0 < i < a.size - 1 and lo < i < hi - 1:
            y0, y1, y2 = a[i - 1], a[i], a[i + 1]
            den = y0 - 2.0 * y1 + y2
            shift = 0.5 * (y0 - y2) / den if den < 0 else 0.0
            dt = 0.5 * (t[i + 1] - t[i - 1])
            times.append(t[i] + shift * dt)
            peaks.append(y1 - 0.25 * (y0 - y2) * shift)
        else:
            times.append(t[i])
            peaks.append(a[i])
    return np.asarray(times), np.asarray(peaks)


def effective_restitution(t: np.ndarray, theta: np.ndarray, lam: float, *,
                          floor: float = PEAK_FLOOR, impacts: int | None = None
                          ) -> ImpactRestitution:
    """η of each impact of a free-rocking trajectory (module docstring).

    Parameters
    ----------
    t, theta : ndarray
        Times (s) and rocking angle (rad) of one block released at rest on a still base.
    lam : float
        The block's slenderness angle λ (rad).
    floor : float
        Peaks below ``floor`` · λ end the series (the contact's jitter, not an impact).
    impacts : int, optional
        At most this many impacts.

    Raises
    ------
    RockbenchError
        λ not in (0, π/2), or a peak at or beyond λ (the block overturned: no impact).
    """
    if not 0.0 < lam < 0.5 * math.pi:
        raise RockbenchError(f"λ must be in (0, π/2) rad, got {lam!r}")
    times, peaks = half_cycle_peaks(t, theta)
    keep = np.cumprod(peaks >= floor * lam).astype(bool)
    times, peaks = times[keep], peaks[keep]
    if np.any(peaks >= lam):
        raise RockbenchError(f"a peak of {float(peaks.max()):.4g} rad reaches λ = {lam:.4g}: "
                             f"the block overturned, it has no impact to measure")
    if impacts is not None:
        times, peaks = times[:impacts + 1], peaks[:impacts + 1]
    energy = np.cos(lam - peaks) - math.cos(lam)
    eta = np.sqrt(energy[1:] / energy[:-1])
    return ImpactRestitution(tuple(float(v) for v in peaks), tuple(float(v) for v in times),
                             tuple(float(v) for v in eta))
