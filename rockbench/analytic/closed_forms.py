"""Closed forms of the single rocking block (Housner 1963) in rockbench's convention.

All formulas follow ``two-block-model.md`` §4. Notation: ``lam`` is the critical
angle λ = atan(b/h), ``p`` the frequency parameter sqrt(m g R / I_O) (rad/s),
``eta`` the angular-velocity ratio at impact (θ̇⁺ = η θ̇⁻; *not* the energy ratio
η²). Angles in rad, times in s.

Differences of cosines are evaluated through half-angle products
(cos A − cos B = 2 sin((B−A)/2) sin((A+B)/2)) so that small amplitudes and
amplitudes close to λ keep full relative precision.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
from scipy import integrate, optimize
from scipy.special import ellipkinc

__all__ = [
    "free_period",
    "quarter_period",
    "amplitude_after_impacts",
    "impact_velocity",
    "free_impact_times",
    "rectangular_pulse_min_overturn",
    "sine_pulse_linear_response",
    "cosine_pulse_linear_response",
]


def _amplitude(lam: float, theta0: float | np.ndarray) -> np.ndarray:
    th = np.abs(np.asarray(theta0, dtype=float))
    if lam <= 0 or not math.isfinite(lam):
        raise ValueError(f"critical angle lam must be finite and > 0, got {lam!r}")
    if np.any(th >= lam) or not np.all(np.isfinite(th)):
        raise ValueError(f"|theta0| must be smaller than lam = {lam:g} (no overturning)")
    return th


def quarter_period(
    p: float, lam: float, theta0: float | np.ndarray, *, linear: bool = False
) -> float | np.ndarray:
    """Time from rest at ``theta0`` to the impact (a quarter of the free period).

    Parameters
    ----------
    p : float
        Frequency parameter (rad/s).
    lam : float
        Critical angle λ (rad).
    theta0 : float or ndarray
        Release angle (rad), 0 ≤ |θ0| < λ; the sign is irrelevant.
    linear : bool
        Use the linearised equation (sin x ≈ x, cos x ≈ 1):
        ``arccosh(1 / (1 − θ0/λ)) / p``. Default: the exact nonlinear equation,
        ``F(φ | m) / p`` with ``m = cos²((λ−θ0)/2)`` and
        ``sin²φ = (sin²(λ/2) − sin²((λ−θ0)/2)) / (sin²(λ/2) cos²((λ−θ0)/2))``.

    Returns
    -------
    float or ndarray
        Quarter period in s (same shape as ``theta0``).
    """
    th = _amplitude(lam, theta0)
    if linear:
        d = lam - th
        q = np.arcsinh(np.sqrt(th * (2.0 * lam - th)) / d) / p
    else:
        half = 0.5 * (lam - th)
        # sin²(λ/2) − sin²((λ−θ0)/2) = sin(θ0/2) sin(λ − θ0/2)
        num = np.sin(0.5 * th) * np.sin(lam - 0.5 * th)
        sin_phi = np.sqrt(num) / (math.sin(0.5 * lam) * np.cos(half))
        q = ellipkinc(np.arcsin(np.minimum(sin_phi, 1.0)), np.cos(half) ** 2) / p
    return float(q) if np.ndim(q) == 0 else q


def free_period(
    p: float, lam: float, theta0: float | np.ndarray, *, linear: bool = False
) -> float | np.ndarray:
    """Full free-rocking period without energy loss (η = 1), released from rest at ``theta0``.

    Four times :func:`quarter_period`: ``T = 4 F(φ | m) / p`` (exact) or
    ``T = (4/p) arccosh(1 / (1 − θ0/λ))`` (linearised, Housner 1963).
    Parameters as in :func:`quarter_period`.
    """
    return 4.0 * quarter_period(p, lam, theta0, linear=linear)


def amplitude_after_impacts(
    lam: float, theta0: float, eta: float, n: int | np.ndarray, *, linear: bool = False
) -> float | np.ndarray:
    """Free-rocking amplitude |θ_n| after ``n`` impacts, released from rest at ``theta0``.

    Exact: ``cos(λ − θ_n) = cos λ + η^{2n} [cos(λ − θ0) − cos λ]``;
    linearised (Housner): ``θ_n/λ = 1 − sqrt(1 − η^{2n} [1 − (1 − θ0/λ)²])``.

    Parameters
    ----------
    lam : float
        Critical angle λ (rad).
    theta0 : float
        Release angle (rad), |θ0| < λ.
    eta : float
        Velocity ratio at impact, 0 ≤ η ≤ 1.
    n : int or ndarray of int
        Number of impacts (0 gives |θ0|).
    linear : bool
        Use the linearised formula.

    Returns
    -------
    float or ndarray
        Amplitude |θ_n| (rad), non-negative; its sign alternates in the motion.
    """
    th = _amplitude(lam, theta0)
    n = np.asarray(n)
    r = float(eta) ** (2 * n)
    if linear:
        x = th / lam
        out = lam * (1.0 - np.sqrt(1.0 - r * (1.0 - (1.0 - x) ** 2)))
    else:
        # sin²((λ−θn)/2) = sin²(λ/2) − η^{2n} sin(θ0/2) sin(λ − θ0/2)
        s2 = math.sin(0.5 * lam) ** 2 - r * math.sin(0.5 * th) * math.sin(lam - 0.5 * th)
        out = lam - 2.0 * np.arcsin(np.sqrt(s2))
    return float(out) if np.ndim(out) == 0 else out


def impact_velocity(
    p: float, lam: float, amplitude: float | np.ndarray, *, linear: bool = False
) -> float | np.ndarray:
    """Angular speed |θ̇| at θ = 0 reached from rest at ``amplitude`` (no loss on the way).

    Exact: ``sqrt(2 p² [cos(λ − θ) − cos λ])``; linearised: ``p sqrt(λ² − (λ − θ)²)``.

    Returns
    -------
    float or ndarray
        |θ̇| in rad/s.
    """
    th = _amplitude(lam, amplitude)
    if linear:
        w = p * np.sqrt(th * (2.0 * lam - th))
    else:
        w = 2.0 * p * np.sqrt(np.sin(0.5 * th) * np.sin(lam - 0.5 * th))
    return float(w) if np.ndim(w) == 0 else w


def free_impact_times(
    p: float, lam: float, theta0: float, eta: float, n: int, *, linear: bool = False
) -> np.ndarray:
    """Times of the first ``n`` impacts of free rocking released from rest at ``theta0``.

    The first impact comes after a quarter period T(θ0)/4; between impacts k and
    k+1 the block swings out to the amplitude θ_k (:func:`amplitude_after_impacts`)
    and back, which takes half a period T(θ_k)/2 = 2 × quarter period.

    Returns
    -------
    ndarray, shape (n,)
        Impact times in s.
    """
    if n <= 0:
        return np.zeros(0)
    amps = amplitude_after_impacts(lam, theta0, eta, np.arange(n), linear=linear)
    q = np.atleast_1d(quarter_period(p, lam, amps, linear=linear))
    return np.cumsum(np.concatenate([[q[0]], 2.0 * q[1:]]))


def rectangular_pulse_min_overturn(
    p: float, lam: float, t1: float, g: float, *, linear: bool = False
) -> float:
    """Smallest rectangular-pulse acceleration ``a_p`` (ü_g = a_p on [0, t1]) that overturns.

    The block overturns at the end of the pulse without impact when its energy
    there reaches the saddle (centre of gravity above the pivot).

    Parameters
    ----------
    p, lam : float
        Frequency parameter (rad/s) and critical angle (rad).
    t1 : float
        Pulse duration (s).
    g : float
        Gravity (m/s²).
    linear : bool
        Housner's linearised closed form ``g λ / (1 − exp(−p t1))``. Default: the
        nonlinear semi-analytic boundary: the rotation at the end of the pulse
        must be ``θ_e = arcsin(sin λ − (1 − cos λ) g/a_p) − λ`` (in magnitude), and
        the pulse duration needed to reach it from rest, a quadrature, is
        solved for ``a_p`` with Brent's method.

    Returns
    -------
    float
        a_p in m/s² (positive; a positive pulse rotates the block to θ < 0).
    """
    if t1 <= 0:
        raise ValueError(f"pulse duration must be > 0, got {t1!r}")
    if linear:
        return g * lam / -math.expm1(-p * t1)

    sl, cl = math.sin(lam), math.cos(lam)

    def duration(a: float) -> float:
        ratio = a / g
        # |θ_e|, the rotation magnitude at the end of the pulse (θ = −x)
        x_e = lam - math.asin(sl - (1.0 - cl) / ratio)

        def integrand(w: float) -> float:
            # substitution x = x_e w² removes the 1/sqrt singularity at x = 0
            x = x_e * w * w
            # cos λ − cos(λ − x) + r (sin λ − sin(λ − x)) (θ = −x), as a product
            bracket = 2.0 * math.sin(0.5 * x) * (ratio * math.cos(lam - 0.5 * x)
                                                 - math.sin(lam - 0.5 * x))
            return 2.0 * x_e * w / math.sqrt(2.0 * p * p * bracket)

        with warnings.catch_warnings():
            # near the threshold (long pulses) quadpack reports roundoff at ~1e-12 relative
            warnings.simplefilter("ignore", integrate.IntegrationWarning)
            val, _ = integrate.quad(integrand, 0.0, 1.0, epsabs=0.0, epsrel=1e-12, limit=200)
        return val

    # bracket [lo, hi] without evaluating at the threshold g tan λ, where t1(a) diverges
    thr = g * math.tan(lam)
    lo, hi = thr, 2.0 * thr
    while duration(hi) > t1:
        lo, hi = hi, 2.0 * hi
    if lo == thr:
        lo = thr + 0.5 * (hi - thr)
        while duration(lo) < t1:
            hi, lo = lo, thr + 0.5 * (lo - thr)
    return optimize.brentq(lambda a: duration(a) - t1, lo, hi, xtol=1e-14, rtol=1e-14)


def sine_pulse_linear_response(
    p: float, lam: float, a_p: float, omega_p: float, g: float, t: float | np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Linearised response to a one-sine pulse ``ü_g = a_p sin(ω_p t)``, before the first impact.

    Rocking starts at ``t_s = arcsin(g λ / a_p) / ω_p`` (``a_p > g λ``) with θ < 0;
    afterwards ``θ = A cosh p(t−t_s) + B sinh p(t−t_s) − λ + K sin ω_p t`` with
    ``K = (a_p/g) p²/(p² + ω_p²)``, ``A = λ ω_p²/(p² + ω_p²)``,
    ``B = −K ω_p cos(ω_p t_s)/p``. Valid while θ < 0 and t ≤ 2π/ω_p.

    Parameters
    ----------
    p, lam : float
        Frequency parameter (rad/s) and critical angle (rad).
    a_p : float
        Pulse amplitude (m/s²), > g λ.
    omega_p : float
        Pulse circular frequency (rad/s).
    g : float
        Gravity (m/s²).
    t : float or ndarray
        Times (s).

    Returns
    -------
    theta, theta_dot : ndarray
        Rotation (rad) and rate (rad/s); zero before ``t_s``.
    """
    if a_p <= g * lam:
        raise ValueError("a_p must exceed g*lam for the linearised block to uplift")
    t = np.asarray(t, dtype=float)
    ts = math.asin(g * lam / a_p) / omega_p
    den = p * p + omega_p * omega_p
    k = a_p / g * p * p / den
    a = lam * omega_p**2 / den
    b = -k * omega_p * math.cos(omega_p * ts) / p
    tau = p * (t - ts)
    th = a * np.cosh(tau) + b * np.sinh(tau) - lam + k * np.sin(omega_p * t)
    om = p * (a * np.sinh(tau) + b * np.cosh(tau)) + k * omega_p * np.cos(omega_p * t)
    before = t < ts
    return np.where(before, 0.0, th), np.where(before, 0.0, om)


def cosine_pulse_linear_response(
    p: float, lam: float, a_p: float, omega_p: float, g: float, t: float | np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Linearised response to a one-cosine pulse ``ü_g = a_p cos(ω_p t)``, before the first impact.

    With ``|a_p| > g λ`` rocking starts at t = 0 on the side ``s = −sgn a_p``;
    afterwards ``θ = s λ − s C cos ω_p t − s (λ − C) cosh p t`` with
    ``C = (|a_p|/g) p²/(p² + ω_p²)`` (θ(0) = θ̇(0) = 0). Valid while ``s θ > 0``
    and ``t ≤ 2π/ω_p``.

    Parameters
    ----------
    p, lam : float
        Frequency parameter (rad/s) and critical angle (rad).
    a_p : float
        Pulse amplitude (m/s², signed), ``|a_p| > g λ``.
    omega_p : float
        Pulse circular frequency (rad/s).
    g : float
        Gravity (m/s²).
    t : float or ndarray
        Times (s), ≥ 0.

    Returns
    -------
    theta, theta_dot : ndarray
        Rotation (rad) and rate (rad/s).
    """
    if abs(a_p) <= g * lam:
        raise ValueError("|a_p| must exceed g*lam for the linearised block to uplift at t = 0")
    t = np.asarray(t, dtype=float)
    s = -math.copysign(1.0, a_p)
    c = abs(a_p) / g * p * p / (p * p + omega_p * omega_p)
    th = s * (lam - c * np.cos(omega_p * t) - (lam - c) * np.cosh(p * t))
    om = s * (c * omega_p * np.sin(omega_p * t) - p * (lam - c) * np.sinh(p * t))
    return th, om
