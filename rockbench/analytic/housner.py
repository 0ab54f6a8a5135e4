"""Housner's single rocking block: an event-driven reference solver.

Model (``two-block-model.md`` §2.2 and §4, rockbench's sign convention)::

    θ'' = −p² [(1 + ü_z/g) sin(s λ − θ) + (ü_g/g) cos(s λ − θ)],   s = sgn θ

θ > 0 when the top moves toward +x (pivot on the +x bottom edge); a positive
base acceleration tips a resting block to θ < 0. ü_g is the horizontal base
acceleration along x and ü_z the vertical one (0 unless the scenario's base
moves vertically): the block's weight is then m (g + ü_z).

* **Uplift** from rest when |ü_g| > (g + ü_z) tan λ (linearised model: (g + ü_z) λ),
  on the side s = −sgn ü_g. The crossing time is located by a sampled scan of ü_g (step
  ``SCAN_STEP``, local maxima refined by a bounded minimisation so that short
  exceedances between samples are not missed) followed by Brent's method; the
  returned time is on the exceeding side of the threshold.
* **Impact** when θ returns to 0: θ̇⁺ = η θ̇⁻ (η is a *velocity* ratio), the pivot
  switches.
* **Rest (Zeno arrest).** The number of impacts before rest is infinite but their
  total duration is finite. After an impact with |θ̇⁺| < w_rest the block is put
  at rest (θ = θ̇ = 0) and waits for the next uplift time. The default
  ``w_rest = 1e-3 · p · λ`` (spec §5.5) is the impact speed of a free swing of
  amplitude ≈ 5e-7 λ (linearised: θ_a/λ ≈ ½ (w/(pλ))²); the neglected remainder
  of the free Zeno sequence lasts about 2 (w/(pλ)) η/((1−η) p), i.e. 19 ms for
  the 1 m × 5 m block B0.
* **Overturning** when |θ| reaches π/2 (terminal).
* **Flight.** Where g + ü_z < 0 the base falls faster than the block and the
  block leaves the ground, which the model does not follow: the solution stops
  there (status ``"flight"``).

Forced phases are integrated with DOP853 (rtol 1e-10, atol 1e-12, dense output,
terminal events), restarted at every excitation breakpoint. The default
implementation is a scalar copy of SciPy's (:mod:`rockbench.analytic._integrate`:
same tableau, step-size control and event location, on Python floats, about 5×
faster on this 2-state system); ``integrator="scipy"`` uses
``scipy.integrate.solve_ivp`` itself, and the two agree to rounding. A phase that
starts on θ = 0 (after an impact or an uplift) uses the impact event
g(t) = s θ / (t − t0), g(t0) := 1, so that the start itself cannot be reported
as a root (spec §5.3).

Free phases (after ``end_time``, when ü_g ≡ 0) have a closed form, used by
default: between impacts the block is an inverted pendulum, and with
φ = λ − sθ, m = k² = cos²(φ_a/2), k' = sin(φ_a/2) (φ_a at the apex) and
u = p (t − t_apex), Jacobi's elliptic functions give exactly

    θ = s [λ − 2 atan2(k', k cn(u|m))],   θ̇ = −2 s p k k' sn(u|m) / dn(u|m),

and the half-cycle from an impact at speed ω back to the next impact lasts
2 F(ψ|m)/p, sin ψ = ω / (2 p k sin(λ/2)). The linearised model gives
θ = s [λ − d cosh u], θ̇ = −s p d sinh u, d = λ − θ_a. Output samples are
evaluated from these formulas (no time stepping), so free rocking costs a few
milliseconds however long it lasts. ``free_closed_form=False`` integrates the free
half-cycles with the ODE instead (used in the tests as a cross-check).
"""

from __future__ import annotations

import math
import time
from bisect import bisect_right
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, minimize_scalar
from scipy.special import ellipj, ellipkinc

from rockbench import provenance
from rockbench.analytic._integrate import integrate_phase
from rockbench.errors import UnsupportedScenario
from rockbench.geometry import RockingProperties
from rockbench.scenarios import Motion, Scenario
from rockbench.trajectory import Status, Trajectory

__all__ = [
    "SingleBlockSolution", "solve_single", "single_block_reference", "scalar_acceleration",
    "SCAN_STEP", "INTEGRATORS", "flight_time",
]

#: Sampling step (s) of the scan for the next uplift time.
SCAN_STEP = 1e-4
#: Default arrest threshold as a fraction of p·λ (spec §5.5).
REST_FACTOR = 1e-3
#: Closed-form free phases are used only for amplitudes below (1 − this)·λ;
#: closer to the saddle the ODE takes over.
_SADDLE_MARGIN = 1e-3
_HALF_PI = 0.5 * math.pi
#: ODE integrators of the forced phases: the built-in scalar DOP853
#: (:mod:`rockbench.analytic._integrate`, the default) or ``scipy.integrate.solve_ivp``.
INTEGRATORS = ("builtin", "scipy")


@dataclass(frozen=True)
class SingleBlockSolution:
    """Response of a single rocking block.

    Attributes
    ----------
    t : ndarray
        Output times (s), truncated after overturning (or where the run stopped).
    theta, theta_dot : ndarray
        Rotation (rad) and rate (rad/s) at ``t``.
    status : str
        ``"ok"``, ``"overturned"`` or ``"incomplete"`` (``max_phases`` reached).
    impacts : ndarray
        Impact times (s).
    uplift_times : ndarray
        Times (s) when rocking started from rest.
    rest_time : float or None
        Time when the block came to rest for good (it stays at rest until the end
        of the output), or None if it is still rocking or overturned.
    message : str
        Human-readable outcome.
    overturn_time : float or None
        Time when |θ| reached π/2.
    impact_rates : ndarray
        θ̇ just after each impact (rad/s); 0 where the impact arrested the block.
    n_phases : int
        Number of phases (ODE segments, closed-form sequences, rest intervals).
    """

    t: np.ndarray
    theta: np.ndarray
    theta_dot: np.ndarray
    status: str
    impacts: np.ndarray
    uplift_times: np.ndarray
    rest_time: float | None
    message: str = ""
    overturn_time: float | None = None
    impact_rates: np.ndarray = field(default_factory=lambda: np.zeros(0))
    n_phases: int = 0


@dataclass
class _Run:
    """Mutable state of one solve."""

    t_out: np.ndarray
    theta: np.ndarray
    omega: np.ndarray
    impacts: list[float] = field(default_factory=list)
    rates: list[float] = field(default_factory=list)
    uplifts: list[float] = field(default_factory=list)
    rest_since: float | None = None
    overturn: float | None = None
    t_reached: float = 0.0
    phases: int = 0
    incomplete: bool = False

    def fill(self, ta: float, tb: float, fn: Callable[[np.ndarray], tuple[Any, Any]]) -> None:
        """Evaluate ``fn`` on the output times in [ta, tb]."""
        i0 = int(np.searchsorted(self.t_out, ta, side="left"))
        i1 = int(np.searchsorted(self.t_out, tb, side="right"))
        if i1 > i0:
            th, om = fn(self.t_out[i0:i1])
            self.theta[i0:i1] = th
            self.omega[i0:i1] = om

    def zero(self, ta: float, tb: float) -> None:
        """Block at rest on [ta, tb]."""
        i0 = int(np.searchsorted(self.t_out, ta, side="left"))
        i1 = int(np.searchsorted(self.t_out, tb, side="right"))
        self.theta[i0:i1] = 0.0
        self.omega[i0:i1] = 0.0


class _Solver:
    def __init__(self, rock: RockingProperties, g: float, accel: Callable[[Any], Any],
                 accel_scalar: Callable[[float], float] | None, eta: float, linear: bool,
                 rtol: float, atol: float, rest_factor: float,
                 integrator: str = "builtin",
                 vertical: tuple[Callable[[Any], Any], Callable[[float], float]] | None = None
                 ) -> None:
        if integrator not in INTEGRATORS:
            raise ValueError(f"integrator must be one of {INTEGRATORS}, got {integrator!r}")
        self.integrator = integrator
        self.lam = float(rock.lam)
        self.p = float(rock.p)
        self.p2 = self.p * self.p
        self.g = float(g)
        self.accel = accel
        self.acc1: Callable[[float], Any] = accel_scalar if accel_scalar is not None else accel
        self.eta = float(eta)
        self.linear = bool(linear)
        self.rtol, self.atol = float(rtol), float(atol)
        self.thr = self.g * (self.lam if linear else math.tan(self.lam))
        self.w_rest = rest_factor * self.p * self.lam
        self.sin_half = math.sin(0.5 * self.lam)
        self.last_step: float | None = None
        # the vertical base acceleration (vectorised, scalar), None when the base moves
        # horizontally only (then every formula below is the horizontal one as it was)
        self.vertical = vertical

    # ------------------------------------------------------------------ forcing
    def a(self, t: float) -> float:
        return float(self.acc1(t))

    def _shortfall(self, t: float) -> float:
        """What minimize_scalar minimises near a peak: −|ü_g| (threshold − |ü_g| with a
        vertical motion, whose threshold moves)."""
        if self.vertical is None:
            return -abs(self.a(t))
        return self.threshold(t) - abs(self.a(t))

    def _exceeds(self, res: Any) -> bool:
        """The minimum found by :meth:`_shortfall` lies beyond the threshold."""
        if self.vertical is None:
            return -res.fun > self.thr
        return res.fun < 0.0

    def threshold(self, t: Any) -> Any:
        """Uplift threshold |ü_g| must exceed at ``t``: (g + ü_z) tan λ (scalar or array)."""
        if self.vertical is None:
            return self.thr
        az = self.vertical[1](t) if isinstance(t, float) else np.asarray(self.vertical[0](t))
        return self.thr * (1.0 + az / self.g)

    def rhs(self, s: float, forced: bool) -> Callable[[float, np.ndarray], list[float]]:
        if forced and self.vertical is not None:
            alpha = self.alpha(s, forced)
            return lambda t, y: [y[1], alpha(t, y[0])]
        p2, lam, g, acc = self.p2, self.lam, self.g, self.acc1
        sl = s * lam
        if self.linear:
            if forced:
                return lambda t, y: [y[1], -p2 * (sl - y[0] + float(acc(t)) / g)]
            return lambda t, y: [y[1], -p2 * (sl - y[0])]
        sin, cos = math.sin, math.cos
        if forced:
            def f(t: float, y: np.ndarray) -> list[float]:
                ph = sl - y[0]
                return [y[1], -p2 * (sin(ph) + float(acc(t)) / g * cos(ph))]
            return f
        return lambda t, y: [y[1], -p2 * sin(sl - y[0])]

    def alpha(self, s: float, forced: bool) -> Callable[[float, float], float]:
        """θ'' as a function of (t, θ) on side ``s`` (the scalar form of :meth:`rhs`)."""
        p2, lam, g, acc = self.p2, self.lam, self.g, self.acc1
        sl = s * lam
        if forced and self.vertical is not None:
            az = self.vertical[1]
            if self.linear:
                return lambda t, th: -p2 * ((1.0 + az(t) / g) * (sl - th) + float(acc(t)) / g)

            def fz(t: float, th: float) -> float:
                ph = sl - th
                return -p2 * ((1.0 + az(t) / g) * math.sin(ph) + float(acc(t)) / g * math.cos(ph))
            return fz
        if self.linear:
            if forced:
                return lambda t, th: -p2 * (sl - th + float(acc(t)) / g)
            return lambda t, th: -p2 * (sl - th)
        sin, cos = math.sin, math.cos
        if forced:
            def f(t: float, th: float) -> float:
                ph = sl - th
                return -p2 * (sin(ph) + float(acc(t)) / g * cos(ph))
            return f
        return lambda t, th: -p2 * sin(sl - th)

    # ------------------------------------------------------------------ uplift
    def _crossing(self, lo: float, hi: float, sign: float) -> float:
        """Time in (lo, hi] where sign·ü_g first exceeds the threshold, on the exceeding side."""
        def f(t: float) -> float:
            return sign * self.a(t) - self.threshold(t)
        r = brentq(f, lo, hi, xtol=1e-14, rtol=1e-15)
        step = 2e-14 * max(1.0, abs(r))
        while f(r) <= 0.0 and r < hi:
            r = min(hi, r + step)
            step *= 2.0
        return r

    def next_uplift(self, ta: float, tb: float) -> float | None:
        """First time in [ta, tb] when |ü_g| exceeds the uplift threshold, or None."""
        if abs(self.a(ta)) > self.threshold(ta):
            return ta
        dt = SCAN_STEP
        n_tot = int(math.ceil((tb - ta) / dt))
        j0, chunk = 0, 512
        while j0 < n_tot:
            j1 = min(n_tot, j0 + chunk)
            tt = np.minimum(ta + dt * np.arange(max(j0 - 1, 0), j1 + 1), tb)
            av = np.abs(np.asarray(self.accel(tt), dtype=float) * np.ones_like(tt))
            thr = self.threshold(tt)
            over = np.flatnonzero(av > thr)
            first = over[0] if over.size else av.size
            # local maxima below the threshold but close to it: refine between samples
            inner = np.arange(1, min(first, av.size - 1))
            if inner.size:
                if self.vertical is None:
                    pk = inner[(av[inner] > av[inner - 1]) & (av[inner] >= av[inner + 1])
                               & (av[inner] > 0.98 * thr)]
                else:  # maxima of the excess over a threshold that moves
                    ex = av - thr
                    pk = inner[(ex[inner] > ex[inner - 1]) & (ex[inner] >= ex[inner + 1])
                               & (ex[inner] > -0.02 * thr[inner])]
                for i in pk:
                    res = minimize_scalar(self._shortfall, bounds=(tt[i - 1], tt[i + 1]),
                                          method="bounded", options={"xatol": 1e-12})
                    if self._exceeds(res):
                        tp = float(res.x)
                        return self._crossing(float(tt[i - 1]), tp, math.copysign(1, self.a(tp)))
            if over.size:
                i = int(first)
                if i == 0:
                    return float(tt[0])
                return self._crossing(float(tt[i - 1]), float(tt[i]),
                                      math.copysign(1.0, self.a(float(tt[i]))))
            j0 = j1
            chunk = min(2 * chunk, 65536)
        return None

    # ------------------------------------------------------------------ ODE phase
    def ode_phase(self, run: _Run, t0: float, th0: float, om0: float, s: float,
                  t_stop: float, zero_start: bool, forced: bool) -> tuple[str, float, float, float]:
        """Integrate one phase on side ``s``. Returns (outcome, t, theta, omega).

        outcome is ``"stop"`` (reached ``t_stop``), ``"impact"`` (state just before
        the impact) or ``"overturn"``.
        """
        if zero_start:
            def g_impact(t: float, th: float, om: float = 0.0) -> float:
                return 1.0 if t <= t0 else s * th / (t - t0)
        else:
            def g_impact(t: float, th: float, om: float = 0.0) -> float:
                return s * th

        def g_overturn(t: float, th: float, om: float = 0.0) -> float:
            return _HALF_PI - abs(th)

        def impact(t: float, y: np.ndarray) -> float:
            return g_impact(t, y[0])
        # solve_ivp reads these attributes of an event function
        impact.terminal = True  # type: ignore[attr-defined]
        impact.direction = -1  # type: ignore[attr-defined]

        def overturn(t: float, y: np.ndarray) -> float:
            return g_overturn(t, y[0])
        overturn.terminal = True  # type: ignore[attr-defined]
        overturn.direction = -1  # type: ignore[attr-defined]

        first_step = None
        if self.last_step is not None and not zero_start:
            # continuing across a breakpoint: reuse the last accepted step size
            first_step = min(self.last_step, t_stop - t0)
        if self.integrator == "builtin":
            res = integrate_phase(
                self.alpha(s, forced), t0, th0, om0, t_stop, rtol=self.rtol, atol=self.atol,
                events=(g_impact, g_overturn),
                first_step=first_step)
            if res.status < 0:
                raise RuntimeError(f"ODE integration failed at t={res.t:.6g}: step size "
                                   f"too small")
            ts, status, dense = res.ts, res.status, res.dense
            ev_over = res.event == 1
            t_ev, y_ev = res.t, (res.theta, res.omega)
        else:
            opts: dict[str, Any] = {} if first_step is None else {"first_step": first_step}
            sol = solve_ivp(self.rhs(s, forced), (t0, t_stop), [th0, om0], method="DOP853",
                            rtol=self.rtol, atol=self.atol, events=[impact, overturn],
                            dense_output=True, **opts)
            if sol.status < 0:
                raise RuntimeError(f"ODE integration failed at t={sol.t[-1]:.6g}: {sol.message}")
            ts, status, dense = sol.t, sol.status, sol.sol
            ev_over = status == 1 and sol.t_events[1].size > 0
            if status == 1:
                k = 1 if ev_over else 0
                t_ev, y_ev = float(sol.t_events[k][0]), sol.y_events[k][0]
            else:
                t_ev, y_ev = float(ts[-1]), sol.y[:, -1]
        n = len(ts)
        if n > 2:
            self.last_step = float(ts[-2] - ts[-3]) if n > 3 else None
        elif n == 2 and status == 0:
            self.last_step = max(float(ts[-1] - ts[0]), self.last_step or 0.0)
        t_end = float(ts[-1])
        run.fill(t0, t_end, dense)
        outcome = "stop"
        if status == 1:
            outcome = "overturn" if ev_over else "impact"
        return outcome, float(t_ev), float(y_ev[0]), float(y_ev[1])

    # ------------------------------------------------------------------ free closed form
    def _segment(self, omega: float) -> tuple[float, float, float] | None:
        """Half-cycle leaving θ = 0 at speed |omega|: (quarter time, k, k') or (q, d, 0) linear.

        None if the swing reaches the saddle (closer than the margin): the ODE takes over.
        """
        w = abs(omega)
        lam, p = self.lam, self.p
        if self.linear:
            d2 = lam * lam - (w / p) ** 2
            if d2 <= (_SADDLE_MARGIN * lam) ** 2:
                return None
            d = math.sqrt(d2)
            return math.asinh(w / (p * d)) / p, d, 0.0
        kp2 = self.sin_half**2 - (w / (2.0 * p)) ** 2
        if kp2 <= math.sin(0.5 * _SADDLE_MARGIN * lam) ** 2:
            return None
        kp = math.sqrt(kp2)
        k = math.sqrt(1.0 - kp2)
        sn = min(1.0, w / (2.0 * p * k * self.sin_half))
        return float(ellipkinc(math.asin(sn), k * k)) / p, k, kp

    def _apex_segment(self, amp: float) -> tuple[float, float, float, float] | None:
        """From rest at |θ| = amp: (quarter time, k or d, k', impact speed)."""
        lam, p = self.lam, self.p
        if amp >= (1.0 - _SADDLE_MARGIN) * lam:
            return None
        if self.linear:
            w = p * math.sqrt(amp * (2.0 * lam - amp))
        else:
            w = 2.0 * p * math.sqrt(math.sin(0.5 * amp) * math.sin(lam - 0.5 * amp))
        seg = self._segment(w)
        if seg is None:
            return None
        return seg[0], seg[1], seg[2], w

    def _eval(self, tt: np.ndarray, t_apex: np.ndarray, s: np.ndarray, k: np.ndarray,
              kp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        u = self.p * (tt - t_apex)
        if self.linear:
            d = k
            return s * (self.lam - d * np.cosh(u)), -s * self.p * d * np.sinh(u)
        sn, cn, dn, _ = ellipj(u, k * k)
        th = s * (self.lam - 2.0 * np.arctan2(kp, k * cn))
        om = -2.0 * s * self.p * k * kp * sn / dn
        return th, om

    def free_closed(self, run: _Run, t0: float, th0: float, om0: float,
                    t_end: float) -> tuple[str, float, float] | None:
        """Free rocking from an apex (om0 = 0) or from an impact (th0 = 0) until t_end or rest.

        Returns (outcome, t, omega) with outcome ``"end"``, ``"rest"``, or
        ``"ode"`` (continue with the ODE from an impact at t with post-impact
        speed omega), or None if not applicable at the start.
        """
        seg_t0: list[float] = []
        seg_apex: list[float] = []
        seg_s: list[float] = []
        seg_k: list[float] = []
        seg_kp: list[float] = []
        if om0 == 0.0:
            first = self._apex_segment(abs(th0))
            if first is None:
                return None
            q, k, kp, w = first
            s = math.copysign(1.0, th0)
            seg_t0.append(t0)
            seg_apex.append(t0)
            seg_s.append(s)
            seg_k.append(k)
            seg_kp.append(kp)
            t_imp = t0 + q
            omega = self.eta * (-s * w)  # post-impact velocity
        else:
            t_imp, omega = t0, om0
        outcome = "end"
        t_stop = t_end
        while t_imp <= t_end:
            # impact at t_imp (except a start on θ = 0 at t0 with a given velocity)
            arrest = abs(omega) < self.w_rest
            if not (om0 != 0.0 and t_imp == t0 and not seg_t0):
                run.impacts.append(t_imp)
                run.rates.append(0.0 if arrest else omega)
            if arrest:
                outcome, t_stop = "rest", t_imp
                break
            seg = self._segment(omega)
            if seg is None:
                outcome, t_stop = "ode", t_imp
                break
            q, k, kp = seg
            s = math.copysign(1.0, omega)
            seg_t0.append(t_imp)
            seg_apex.append(t_imp + q)
            seg_s.append(s)
            seg_k.append(k)
            seg_kp.append(kp)
            t_imp = t_imp + 2.0 * q
            omega = -self.eta * omega
            run.phases += 1
        # sample all segments at once
        starts = np.asarray(seg_t0)
        i0 = int(np.searchsorted(run.t_out, t0, side="left"))
        i1 = int(np.searchsorted(run.t_out, t_stop, side="right"))
        if starts.size and i1 > i0:
            tt = run.t_out[i0:i1]
            j = np.clip(np.searchsorted(starts, tt, side="right") - 1, 0, starts.size - 1)
            th, om = self._eval(tt, np.asarray(seg_apex)[j], np.asarray(seg_s)[j],
                                np.asarray(seg_k)[j], np.asarray(seg_kp)[j])
            run.theta[i0:i1] = th
            run.omega[i0:i1] = om
        if outcome == "rest":
            run.zero(t_stop, math.inf)
        return outcome, t_stop, omega


def flight_time(az: Callable[[Any], Any], az1: Callable[[float], float], g: float,
                t_end: float) -> float | None:
    """First time in [0, t_end] when g + ü_z < 0 (the block leaves the ground), or None."""
    if not t_end > 0:
        return None
    tt = np.linspace(0.0, t_end, max(2, int(math.ceil(t_end / SCAN_STEP)) + 1))
    low = np.flatnonzero(g + np.asarray(az(tt), float) < 0.0)
    if low.size == 0:
        return None
    i = int(low[0])
    if i == 0:
        return 0.0
    return float(brentq(lambda t: g + az1(t), float(tt[i - 1]), float(tt[i]), xtol=1e-14))


def scalar_acceleration(exc: Motion) -> Callable[[float], float] | None:
    """A fast scalar ü_g(t) for the ODE right-hand side, or None to use ``exc.acceleration``.

    Evaluating an excitation's vectorised method on one float costs tens of µs,
    which dominates long forced integrations. Each excitation gives a plain-float
    form (:meth:`~rockbench.scenarios.Excitation.scalar_acceleration`); it is
    checked against ``exc.acceleration`` on a grid (including both sides of every
    breakpoint) and discarded if they differ by more than 1e-12 of the peak.
    """
    fast = exc.scalar_acceleration()
    end = exc.end_time if math.isfinite(exc.end_time) else 30.0
    bps = np.asarray(exc.breakpoints, dtype=float)
    grid = np.concatenate([np.linspace(-0.1, end + 0.1, 1009), bps, bps * (1 + 1e-12),
                           bps * (1 - 1e-12), [0.0]])
    ref = np.asarray(exc.acceleration(grid), dtype=float) * np.ones_like(grid)
    got = np.array([fast(float(t)) for t in grid])
    tol = 1e-12 * (1.0 + float(np.max(np.abs(ref))))
    return fast if np.all(np.abs(got - ref) <= tol) else None


def solve_single(
    rock: RockingProperties,
    *,
    g: float,
    accel: Callable[[Any], Any],
    breakpoints: Sequence[float] = (),
    end_time: float = math.inf,
    theta0: float = 0.0,
    omega0: float = 0.0,
    t_out: Sequence[float] | np.ndarray,
    accel_scalar: Callable[[float], float] | None = None,
    eta: float | None = None,
    linear: bool = False,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    max_phases: int = 100_000,
    rest_factor: float = REST_FACTOR,
    free_closed_form: bool = True,
    integrator: str = "builtin",
    vertical: tuple[Callable[[Any], Any], Callable[[float], float]] | None = None,
) -> SingleBlockSolution:
    """Solve Housner's single-block rocking problem.

    Parameters
    ----------
    rock : RockingProperties
        Block constants (``lam``, ``p``, ``eta`` are used).
    g : float
        Gravity (m/s²).
    accel : callable
        Vectorised base acceleration ü_g(t) in m/s² (positive toward +x).
    breakpoints : sequence of float
        Times where ü_g is not smooth; the integration restarts there.
    end_time : float
        Time after which ü_g ≡ 0 (free rocking; closed form from the next impact).
    theta0, omega0 : float
        Initial rotation (rad, |θ0| < π/2) and rate (rad/s) at t = 0.
    t_out : array_like
        Non-decreasing output times ≥ 0 (s); the last one ends the simulation.
    accel_scalar : callable, optional
        A fast scalar version of ``accel`` (float -> float) for the ODE right-hand
        side; it must return the same values.
    eta : float, optional
        Velocity ratio at impact (default ``rock.eta``).
    linear : bool
        Linearised model: sin x ≈ x, cos x ≈ 1, uplift at g λ.
    rtol, atol : float
        DOP853 tolerances of the forced phases.
    max_phases : int
        Guard against chattering; the result is ``"incomplete"`` when exceeded.
    rest_factor : float
        Arrest threshold w_rest = rest_factor · p · λ (see the module docstring).
    free_closed_form : bool
        Use the exact closed form for free phases (default) instead of the ODE.
    integrator : {"builtin", "scipy"}
        DOP853 implementation of the ODE phases: the built-in scalar one
        (default, same algorithm, several times faster) or
        ``scipy.integrate.solve_ivp``.
    vertical : (callable, callable), optional
        The vertical base acceleration ü_z(t) in m/s² (positive up), vectorised
        and for one float; its breakpoints must be in ``breakpoints`` and it
        must vanish after ``end_time``. None: the base moves horizontally only.

    Returns
    -------
    SingleBlockSolution
        Status ``"flight"`` when g + ü_z turns negative: the solution stops there.
    """
    t_out = np.asarray(t_out, dtype=float).reshape(-1)
    if t_out.size == 0:
        raise ValueError("t_out must contain at least one time")
    if np.any(np.diff(t_out) < 0) or t_out[0] < 0 or not np.all(np.isfinite(t_out)):
        raise ValueError("t_out must be finite, >= 0 and non-decreasing")
    if not abs(theta0) < _HALF_PI:
        raise ValueError(f"|theta0| must be < pi/2, got {theta0!r}")
    if not rest_factor > 0.0:
        raise ValueError(f"rest_factor must be > 0 (Zeno arrest), got {rest_factor!r}")
    # Housner's 1 − 2mb²/I_O goes negative past λ ≈ 54.7° (a squat block): no
    # rebound is possible, the block stops at its first impact (η clipped at 0)
    eta = float(max(rock.eta, 0.0) if eta is None else eta)
    if not 0.0 <= eta <= 1.0:
        raise ValueError(f"eta must be in [0, 1], got {eta!r}")
    sv = _Solver(rock, g, accel, accel_scalar, eta, linear, rtol, atol, rest_factor, integrator,
                 vertical)
    t_fin = float(t_out[-1])
    t_flight = (None if vertical is None else
                flight_time(vertical[0], vertical[1], float(g), min(float(end_time), t_fin)))
    if t_flight is not None:
        t_fin = t_flight
    end_time = float(end_time)
    bps = sorted({float(b) for b in breakpoints if 0.0 < b < t_fin}
                 | ({end_time} if 0.0 < end_time < t_fin else set()))
    run = _Run(t_out, np.zeros(t_out.size), np.zeros(t_out.size))

    t, th, om = 0.0, float(theta0), float(omega0)
    resting = th == 0.0 and om == 0.0
    s = math.copysign(1.0, th if th != 0.0 else om)
    zero_start = th == 0.0 and not resting
    if resting:
        run.rest_since = 0.0
    closed_ok = free_closed_form

    while t < t_fin:
        run.phases += 1
        if run.phases > max_phases:
            run.incomplete = True
            break
        if resting:
            horizon = min(end_time, t_fin)
            t_up = sv.next_uplift(t, horizon) if t < horizon else None
            if t_up is None:
                run.zero(t, math.inf)
                t = t_fin
                break
            run.zero(t, t_up)
            run.uplifts.append(t_up)
            run.rest_since = None
            t, th, om = t_up, 0.0, 0.0
            s = -math.copysign(1.0, sv.a(t_up))
            resting, zero_start = False, True
            continue
        free = t >= end_time
        if free and closed_ok and (zero_start or om == 0.0):
            res = sv.free_closed(run, t, th, om, t_fin)
            if res is not None:
                outcome, t_at, w = res
                if outcome == "end":
                    t = t_fin
                    break
                if outcome == "rest":
                    run.rest_since = t_at
                    t = t_fin
                    break
                # near the saddle: continue with the ODE from this impact
                t, th, om = t_at, 0.0, w
                s, zero_start = math.copysign(1.0, w), True
                closed_ok = False
        ib = bisect_right(bps, t)
        nxt = bps[ib] if ib < len(bps) else t_fin
        if nxt - t <= 1e-13 * max(1.0, abs(t)):
            t = nxt
            continue
        outcome, t_e, th_e, om_e = sv.ode_phase(run, t, th, om, s, nxt, zero_start, not free)
        if outcome == "overturn":
            run.overturn = t_e
            t = t_e
            break
        if outcome == "stop":
            t, th, om, zero_start = t_e, th_e, om_e, False
            continue
        # impact
        run.impacts.append(t_e)
        om_plus = eta * om_e
        t = t_e
        arrest = abs(om_plus) < sv.w_rest or om_e * s > 0.0
        run.rates.append(0.0 if arrest else om_plus)
        if arrest:
            resting = True
            run.rest_since = t_e
            th = om = 0.0
        else:
            th, om = 0.0, om_plus
            s = math.copysign(1.0, om_plus)
            zero_start = True
            closed_ok = free_closed_form
    run.t_reached = t

    if run.overturn is not None:
        n = int(np.searchsorted(t_out, run.overturn, side="right"))
        status = "overturned"
        message = f"overturned at t = {run.overturn:.6f} s"
    elif t_flight is not None and not run.incomplete:
        n = max(1, int(np.searchsorted(t_out, t_flight, side="right")))
        status = "flight"
        message = (f"the base falls faster than gravity at t = {t_flight:.6f} s (g + ü_z < 0): "
                   f"the block leaves the ground, which the model does not follow")
    elif run.incomplete:
        n = int(np.searchsorted(t_out, run.t_reached, side="right"))
        status = "incomplete"
        message = (f"stopped after max_phases={max_phases} phases at t = {run.t_reached:.6f} s "
                   f"(chattering); outputs truncated")
    else:
        n = t_out.size
        status = "ok"
        message = (f"at rest from t = {run.rest_since:.6f} s" if run.rest_since is not None
                   else "rocking at the end of the output")
    rest_time = run.rest_since if status == "ok" else None
    return SingleBlockSolution(
        t=t_out[:n].copy(), theta=run.theta[:n].copy(), theta_dot=run.omega[:n].copy(),
        status=status, impacts=np.asarray(run.impacts, dtype=float),
        uplift_times=np.asarray(run.uplifts, dtype=float), rest_time=rest_time,
        message=message, overturn_time=run.overturn,
        impact_rates=np.asarray(run.rates, dtype=float), n_phases=run.phases,
    )


def single_block_reference(
    scenario: Scenario, *, linear: bool = False, rtol: float = 1e-10, atol: float = 1e-12,
    integrator: str = "builtin",
) -> Trajectory:
    """Housner reference trajectory of a one-block scenario.

    Parameters
    ----------
    scenario : Scenario
        One centred block; ``contact.eta`` overrides Housner's η when given.
    linear : bool
        Use the linearised model.
    rtol, atol : float
        Integrator tolerances of the forced phases.
    integrator : {"builtin", "scipy"}
        DOP853 implementation (see :func:`solve_single`).

    Returns
    -------
    Trajectory
        θ, centroid x (including the base displacement u_g) and z in the ground
        frame, zero wobble, the impact times, and ``extra["rest_time"]``.

    Raises
    ------
    UnsupportedScenario
        More than one block, or a non-zero offset.
    """
    col = scenario.geometry.column
    if col is None or len(col) != 1 or not col.centred:
        raise UnsupportedScenario(
            f"the Housner single-block reference needs one centred block, scenario "
            f"{scenario.name!r} has another geometry")
    motion = scenario.motion
    if "y" in motion.axes:
        raise UnsupportedScenario("the Housner reference is planar: no base motion along y")
    block = col.blocks[0]
    rock = block.rocking(scenario.g)
    eta = scenario.contact.eta
    exc, up = motion.x, motion.z
    vertical = None
    if not up.is_free:
        fast = scalar_acceleration(up)
        vertical = (up.acceleration, fast if fast is not None
                    else (lambda t: float(up.acceleration(t))))
    t_out = scenario.output_times()
    start = time.perf_counter()
    sol = solve_single(
        rock, g=scenario.g, accel=exc.acceleration, accel_scalar=scalar_acceleration(exc),
        breakpoints=motion.breakpoints,
        end_time=motion.end_time, theta0=scenario.theta0, t_out=t_out, eta=eta,
        linear=linear, rtol=rtol, atol=atol, integrator=integrator, vertical=vertical,
    )
    th = sol.theta
    bp, h = block.pivot_half_width, block.h
    sgn = np.where(th >= 0.0, 1.0, -1.0)
    ct, st = np.cos(th), np.sin(th)
    # pivot (s·bp + u_g, 0); upright pivot→centroid vector (−s·bp, h) rotated by θ about +y
    x = np.asarray(exc.displacement(sol.t), float) + sgn * bp + (-sgn * bp * ct + h * st)
    z = sgn * bp * st + h * ct
    if vertical is not None:
        z = z + np.asarray(up.displacement(sol.t), float)
    wall = time.perf_counter() - start
    status = {"ok": Status.OK, "overturned": Status.OVERTURNED,
              "flight": Status.UNSUPPORTED}.get(sol.status, Status.CRASHED)
    return Trajectory(
        t=sol.t, theta=th[:, None], x=x[:, None], z=z[:, None], wobble=np.zeros((th.size, 1)),
        status=status, message=sol.message, wall_time=wall, engine="analytic",
        engine_version=f"housner-{provenance.code_version('reference')}",
        settings={"rtol": rtol, "atol": atol, "linear": linear,
                  "eta": float(rock.eta if eta is None else eta)},
        scenario=scenario.name, impacts=sol.impacts,
        extra={"rest_time": sol.rest_time, "uplift_times": sol.uplift_times.tolist(),
               "overturn_time": sol.overturn_time, "model": "housner-single"},
    )
