"""Comparison metrics between trajectories (neutral module: engines' conformance kit
and the report both use it, so it sits beside :mod:`rockbench.trajectory`).

All angles are normalised by a critical angle λ given by the caller
(:func:`rockbench.analytic.critical_angle`).
"""

from __future__ import annotations

import numpy as np

from rockbench.trajectory import Trajectory

__all__ = ["peak_ratio", "zero_crossings", "first_zero", "impact_times", "max_error",
           "impact_time_errors", "time_to_rest", "peak_relative_error"]


def peak_ratio(traj: Trajectory, lam: float) -> np.ndarray:
    """max |θ| / λ of each block (NaN for an empty trajectory)."""
    if traj.t.size == 0:
        return np.full(traj.n_blocks, np.nan)
    return np.max(np.abs(traj.theta), axis=0) / lam


def zero_crossings(t: np.ndarray, theta: np.ndarray,
                   level: float = 0.0) -> np.ndarray:
    """Times where ``theta`` changes sign, linearly interpolated between samples.

    With ``level`` > 0 a crossing counts only if |θ| reached ``level`` since the
    previous counted crossing (or the start): contact jitter around θ = 0
    before uplift is not an impact.
    """
    idx = np.nonzero(np.sign(theta[:-1]) * np.sign(theta[1:]) < 0)[0]
    if level > 0.0:
        keep, last = [], 0
        for i in idx:
            if np.max(np.abs(theta[last:i + 1])) >= level:
                keep.append(i)
                last = int(i) + 1
        idx = np.asarray(keep, dtype=int)
    return t[idx] - theta[idx] * (t[idx + 1] - t[idx]) / (theta[idx + 1] - theta[idx])


def first_zero(t: np.ndarray, theta: np.ndarray) -> float:
    """The first time ``theta`` changes sign (:func:`zero_crossings`), or NaN if it never does."""
    z = zero_crossings(t, theta)
    return float(z[0]) if z.size else float("nan")


def impact_times(traj: Trajectory, block: int = 0) -> np.ndarray:
    """Times where θ of ``block`` changes sign, linearly interpolated between samples.

    For the analytic reference the exact event times are preferred when stored
    (``traj.impacts``) and the block is the bottom one of a single-block run.
    """
    if traj.impacts is not None and traj.n_blocks == 1 and block == 0:
        return np.asarray(traj.impacts, float)
    return zero_crossings(traj.t, traj.theta[:, block])


def max_error(traj: Trajectory, ref: Trajectory, lam: float, t_end: float | None = None) -> float:
    """max over common samples (up to ``t_end``) of |θ − θ_ref| / λ, over all blocks.

    Both trajectories must be sampled at the same times (they are when they
    come from the same scenario). NaN if either is empty.
    """
    n = min(traj.t.size, ref.t.size)
    if t_end is not None:
        n = min(n, int(np.searchsorted(ref.t, t_end, side="right")))
    if n == 0:
        return float("nan")
    if not np.allclose(traj.t[:n], ref.t[:n], atol=1e-9):
        raise ValueError("trajectories are not sampled at the same times")
    return float(np.max(np.abs(traj.theta[:n] - ref.theta[:n])) / lam)


def impact_time_errors(traj: Trajectory, ref: Trajectory, n: int = 3) -> np.ndarray:
    """Relative errors of the first ``n`` impact times of the bottom block (NaN if missing)."""
    t_ref = impact_times(ref)[:n]
    t_eng = impact_times(traj)[:n]
    out = np.full(n, np.nan)
    k = min(t_ref.size, t_eng.size)
    out[:k] = np.abs(t_eng[:k] - t_ref[:k]) / t_ref[:k]
    return out


def time_to_rest(traj: Trajectory, lam: float, threshold: float = 0.01) -> float:
    """First time after which |θ| stays below ``threshold`` λ for every block (NaN if never)."""
    if traj.t.size == 0:
        return float("nan")
    moving = np.any(np.abs(traj.theta) > threshold * lam, axis=1)
    if not moving.any():
        return 0.0
    last = int(np.nonzero(moving)[0][-1])
    return float(traj.t[last + 1]) if last + 1 < traj.t.size else float("nan")


def peak_relative_error(traj: Trajectory, ref: Trajectory, lam: float) -> np.ndarray:
    """(peak_engine − peak_ref) / peak_ref per block (signed)."""
    p, r = peak_ratio(traj, lam), peak_ratio(ref, lam)
    with np.errstate(divide="ignore", invalid="ignore"):
        return (p - r) / r
