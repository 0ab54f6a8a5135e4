"""Analytic reference for two stacked rigid blocks rocking on a moving rigid base.

Phase-by-phase integration of the model of ``two-block-model.md`` (§5): one
motion pattern at a time (``R``, ``M(s)``, ``U(s2)``, ``B(s1,s2)``) with SciPy's
``solve_ivp`` (DOP853) and terminal events for impacts, uplift and overturning;
impact outcomes by candidate enumeration (§3.5); arming hysteresis for gaps that
start at zero (§5.3); consistency at every phase start (§5.4); Zeno arrest
(§5.5); rest → wait for the next threshold crossing of |ü_g|.

Vertical base motion (optional, ``vertical=``): with a vertical base
acceleration ü_z the blocks' weight is m (g + ü_z), so g + ü_z replaces g in the
equations of motion of every pattern, in the uplift indicators and in the
thresholds from rest, (g + ü_z) min(tan α2, tan αM)
(:mod:`rockbench.analytic.twoblock_model`); impacts are unchanged. The work
integral then includes the work of the vertical inertial forces −m_i ü_z on
the centroids' heights, so that T + V(g) − W_base stays constant between
impacts. Where g + ü_z < 0 the base falls faster than the blocks, which leave
the ground: the model does not follow flight, and the solution stops there
(status ``"flight"``), as Housner's single-block solution does. Without a
vertical motion every formula is the horizontal one, unchanged.

Public entry points: :func:`solve_two_blocks` (plain parameters, any
acceleration function) and :func:`two_block_reference` (a rockbench
:class:`~rockbench.scenarios.Scenario` → :class:`~rockbench.trajectory.Trajectory`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import partial
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from rockbench import provenance
from rockbench.analytic.housner import flight_time, scalar_acceleration
from rockbench.analytic.twoblock_model import (
    BlockParams,
    Pattern,
    TwoBlockModel,
    parse_pattern,
)
from rockbench.errors import UnsupportedScenario
from rockbench.scenarios import Motion, Scenario
from rockbench.trajectory import Status, Trajectory

__all__ = [
    "BlockParams",
    "Pattern",
    "TwoBlockModel",
    "TwoBlockSolution",
    "parse_pattern",
    "solve_two_blocks",
    "two_block_reference",
]

#: Arming hysteresis ε (rad) for gaps that start at zero (§5.3).
EPS_ARM = 1e-11
_HALF_PI = 0.5 * math.pi


@dataclass
class TwoBlockSolution:
    """Result of :func:`solve_two_blocks`.

    Attributes
    ----------
    t : ndarray (n,)
        Output times (s).
    theta, theta_dot : ndarray (n, 2)
        Absolute rotations θ1 (lower), θ2 (upper) and their rates; NaN after an
        overturn or after the run stopped early.
    status : str
        ``"ok"``, ``"overturned"``, ``"incomplete"`` (``max_phases`` reached) or
        ``"flight"`` (g + ü_z < 0: the samples after ``flight_time`` are NaN).
    impacts : list of (float, str, str, str)
        (time, ``"base"`` or ``"interface"``, pattern before, pattern after).
    patterns : list of (float, str)
        (start time, pattern name) each time the pattern changes.
    overturn_time : float or None
        Time when max(|θ1|, |θ2|) reached π/2.
    overturned_block : str or None
        ``"stack"`` (monolithic), ``"lower"`` or ``"upper"``.
    message : str
        Notes (why the run stopped early, ...).
    work : ndarray (n,)
        Work of the base-inertia forces W_base(t) (J), for energy balances:
        ∫ −ü_g Σ m_i ẋ_Gi dt, plus ∫ −ü_z Σ m_i ż_Gi dt with a vertical motion.
    impact_losses : list of float
        Kinetic energy lost at each impact (J), same order as ``impacts``.
    n_phases : int
        Number of integration phases.
    contacts : ndarray (n, 2) of int
        Pattern at each sample as (base, interface) contact states: 0 for a
        closed face, ±1 for the pivot side (see :class:`Pattern`).
    model : TwoBlockModel
        The model (constants, energy function, ...).
    flight_time : float or None
        First time when g + ü_z < 0 (the run stopped there), None if never.
    """

    t: np.ndarray
    theta: np.ndarray
    theta_dot: np.ndarray
    status: str
    impacts: list[tuple[float, str, str, str]]
    patterns: list[tuple[float, str]]
    overturn_time: float | None
    overturned_block: str | None
    message: str
    work: np.ndarray
    impact_losses: list[float]
    n_phases: int
    contacts: np.ndarray
    model: TwoBlockModel = field(repr=False)
    flight_time: float | None = None

    def energy(self) -> np.ndarray:
        """Mechanical energy T + V (J) at the output times (pivots of each sample's pattern)."""
        th, w, c = self.theta, self.theta_dot, self.contacts
        return self.model.energy(th[:, 0], th[:, 1], w[:, 0], w[:, 1], c[:, 0], c[:, 1])

    @property
    def pattern_names(self) -> list[str]:
        """Pattern name at each sample."""
        return [Pattern(int(a), int(b)).name for a, b in self.contacts]

    @property
    def impact_times(self) -> np.ndarray:
        """Impact times (s)."""
        return np.array([i[0] for i in self.impacts], float)


class _Run:
    """One simulation: the phase loop of §5.8."""

    def __init__(
        self, model: TwoBlockModel, accel: Callable[[Any], Any], breakpoints: Sequence[float],
        end_time: float, t_out: np.ndarray, rtol: float, atol: float, w_rest: float,
        max_phases: int, legacy: bool, vertical: Callable[[Any], Any] | None = None,
        t_stop: float | None = None,
    ) -> None:
        self.m = model
        self.accel = accel
        # vertical base acceleration ü_z(t), None when the base moves horizontally only
        # (then every right-hand side, event and threshold is the horizontal one as it was)
        self.vertical = vertical
        self.end_time = float(end_time)
        self.t_out = t_out
        self.t_final = float(t_out[-1]) if t_stop is None else min(float(t_out[-1]), t_stop)
        bps = {float(b) for b in breakpoints if np.isfinite(b)}
        if math.isfinite(self.end_time):
            bps.add(self.end_time)
        self.bps = np.array(sorted(b for b in bps if t_out[0] < b < self.t_final))
        self.rtol, self.atol = rtol, atol
        self.w_rest = w_rest
        self.max_phases = max_phases
        self.legacy = legacy
        n = t_out.size
        self.y = np.full((n, 5), np.nan)
        self.pat = np.zeros((n, 2), dtype=int)
        self.impacts: list[tuple[float, str, str, str]] = []
        self.losses: list[float] = []
        self.patterns: list[tuple[float, str]] = []
        self.status = "ok"
        self.message = ""
        self.t_over: float | None = None
        self.over_block: str | None = None
        self.n_phases = 0
        wscale = model.mt * model.g * (model.h1 + model.h2)
        self.atol_vec = np.array([atol, atol, atol, atol, max(atol, 1e-10 * wscale)])

    # ------------------------------------------------------------- helpers
    def a(self, t: float) -> float:
        return float(self.accel(t))

    def az(self, t: float) -> float:
        """Vertical base acceleration ü_z(t) (0 without a vertical motion)."""
        return 0.0 if self.vertical is None else float(self.vertical(t))

    def fill(self, ta: float, tb: float, fn: Callable[[np.ndarray], np.ndarray],
             last: bool, p: Pattern) -> None:
        i0 = int(np.searchsorted(self.t_out, ta, "left"))
        i1 = self.t_out.size if last else int(np.searchsorted(self.t_out, tb, "left"))
        if i1 > i0:
            self.y[i0:i1] = fn(self.t_out[i0:i1])
            self.pat[i0:i1] = p

    def set_pattern(self, t: float, p: Pattern) -> None:
        if not self.patterns or self.patterns[-1][1] != p.name:
            self.patterns.append((t, p.name))

    def next_start(self, t: float) -> float | None:
        """First time ≥ t when |ü_g| exceeds the rest threshold (sampled scan + brentq).

        With a vertical motion the threshold is (g + ü_z) min(tan α2, tan αM).
        """
        thr = self.m.threshold
        if t >= self.end_time:
            return None
        vert = self.vertical
        if vert is None:
            def excess(s: float) -> float:
                return abs(self.a(s)) - thr
        else:
            def excess(s: float) -> float:
                return abs(self.a(s)) - self.m.threshold_at(self.az(s))
        ta = t
        t_end = min(self.t_final, self.end_time)
        while ta < t_end:
            tb = min(ta + 1.0, t_end)
            n = max(3, int(math.ceil((tb - ta) / 1e-4)) + 1)
            ts = np.linspace(ta, tb, n)
            f = np.abs(np.asarray(self.accel(ts), float)) - thr
            if vert is not None:
                f = f - thr * np.asarray(vert(ts), float) / self.m.g
            hit = np.flatnonzero(f > 0)
            if hit.size:
                i = int(hit[0])
                if i == 0:
                    return ta
                return brentq(excess, ts[i - 1], ts[i], xtol=1e-15, rtol=8.9e-16)
            ta = tb
        return None

    # ----------------------------------------------------- right-hand sides
    def rhs(self, p: Pattern) -> Callable[[float, np.ndarray], list[float]]:
        """The right-hand side of pattern ``p``: with a vertical base acceleration ü_z,
        gravity g + ü_z and the work of the vertical inertial forces −m_i ü_z (power
        −ü_z Σ m_i ż_Gi) in z[4]; without one, ü_z = 0 adds exact zeros."""
        m = self.m
        acc = self.accel
        vert = self.vertical
        g = m.g
        sin, cos = math.sin, math.cos
        k = p.kind
        if k == "M":
            s = p.base
            sa, pm2, bm = s * m.alphaM, m.pM**2, m.mt * m.RM

            def f_m(t: float, z: np.ndarray) -> list[float]:
                a = float(acc(t))
                az = float(vert(t)) if vert is not None else 0.0
                arg = sa - z[0]
                c, n = cos(arg), sin(arg)
                # composite centroid height RM cos(arg): ż = RM sin(arg) θ̇
                return [z[2], 0.0, -pm2 * ((1.0 + az / g) * n + a / g * c), 0.0,
                        -a * bm * c * z[2] - az * bm * n * z[2]]

            return f_m
        if k == "U":
            s2 = p.iface
            sa, p22, bu = s2 * m.alpha2, m.p2**2, m.m2 * m.R2

            def f_u(t: float, z: np.ndarray) -> list[float]:
                a = float(acc(t))
                az = float(vert(t)) if vert is not None else 0.0
                arg = sa - z[1]
                c, n = cos(arg), sin(arg)
                return [0.0, z[3], 0.0, -p22 * ((1.0 + az / g) * n + a / g * c),
                        -a * bu * c * z[3] - az * bu * n * z[3]]

            return f_u
        s1, s2 = p.base, p.iface
        m1, m2 = m.m1, m.m2
        vx, vy = s2 * m.bc - s1 * m.b1, 2 * m.h1
        ux, uy = -s2 * m.bc, m.h2
        ex0, ey0 = -s1 * m.b1, m.h1
        m11 = m.IO1 + m2 * (vx * vx + vy * vy)
        m22 = m.IC2

        def f_b(t: float, z: np.ndarray) -> list[float]:
            th1, ph, w1, wp = z[0], z[1], z[2], z[3]
            th2 = th1 + ph
            w2 = w1 + wp
            c1, n1, c2, n2 = cos(th1), sin(th1), cos(th2), sin(th2)
            cx, cy = vx * c1 + vy * n1, -vx * n1 + vy * c1
            dx, dy = ux * c2 + uy * n2, -ux * n2 + uy * c2
            ex, ey = ex0 * c1 + ey0 * n1, -ex0 * n1 + ey0 * c1
            m12 = m2 * (cx * dx + cy * dy)
            sd = m2 * (cx * dy - cy * dx)
            a = float(acc(t))
            az = float(vert(t)) if vert is not None else 0.0
            ge = g + az
            b1 = m1 * ey + m2 * cy
            b2 = m2 * dy
            # gravity's generalised forces (the centroid heights ey, cy + dy have
            # ∂/∂θ1 = −ex, −cx and ∂/∂θ2 = −dx); a downward ü_z acts alike
            q1 = m1 * ex + m2 * cx
            r1 = -a * b1 - sd * w2 * w2 + ge * q1
            r2 = -a * b2 + sd * w1 * w1 + ge * m2 * dx
            det = m11 * m22 - m12 * m12
            d1 = (m22 * r1 - m12 * r2) / det
            d2 = (m11 * r2 - m12 * r1) / det
            return [w1, wp, d1, d2 - d1,
                    -a * (b1 * w1 + b2 * w2) + az * (q1 * w1 + m2 * dx * w2)]

        return f_b

    # -------------------------------------------------------------- events
    def events(self, p: Pattern, z: np.ndarray, t0: float) -> tuple[list[Callable], list[str]]:
        m = self.m
        acc = self.accel
        evs: list[Callable] = []
        names: list[str] = []

        def add(fn: Callable, direction: float, name: str) -> None:
            # solve_ivp reads these attributes of an event function
            fn.terminal = True  # type: ignore[attr-defined]
            fn.direction = direction  # type: ignore[attr-defined]
            evs.append(fn)
            names.append(name)

        add(lambda t, y: _HALF_PI - max(abs(y[0]), abs(y[0] + y[1])), -1.0, "overturn")
        for idx, s, label in ((0, p.base, "base"), (1, p.iface, "interface")):
            if s == 0:
                continue
            rate0 = s * z[idx + 2]
            if s * z[idx] > 0.5 * EPS_ARM:
                add(lambda t, y, i=idx, s=s: s * y[i], -1.0, f"impact:{label}")
            elif rate0 >= 0.5 * self.w_rest and rate0 > 0:
                # gap opening at a finite rate (after an impact): the divided gap
                # s·gap/(t − t0) starts at the opening rate and vanishes when it closes (§5.3)
                def divided(t: float, y: np.ndarray, i: int = idx, s: int = s,
                            r0: float = rate0) -> float:
                    return s * y[i] / (t - t0) if t > t0 else r0

                add(divided, -1.0, f"impact:{label}")
            else:
                add(lambda t, y, i=idx, s=s: s * y[i] - EPS_ARM, 1.0, f"arm:{label}")
                add(lambda t, y, i=idx, s=s: s * y[i] + EPS_ARM, -1.0, f"fail:{label}")
        vert = self.vertical
        if vert is None:
            if p.kind == "M":
                for sg in (1, -1):
                    add(lambda t, y, sg=sg: m.lambda_if(p.base, sg, y[0], y[2], float(acc(t))),
                        -1.0, f"uplift:{sg}")
            elif p.kind == "U":
                for sg in (1, -1):
                    add(lambda t, y, sg=sg: m.lambda_b(p.iface, sg, y[1], y[3], float(acc(t))),
                        -1.0, f"uplift:{sg}")
        elif p.kind == "M":
            for sg in (1, -1):
                add(lambda t, y, sg=sg: m.lambda_if(p.base, sg, y[0], y[2], float(acc(t)),
                                                    az=float(vert(t))),
                    -1.0, f"uplift:{sg}")
        elif p.kind == "U":
            for sg in (1, -1):
                add(lambda t, y, sg=sg: m.lambda_b(p.iface, sg, y[1], y[3], float(acc(t)),
                                                   az=float(vert(t))),
                    -1.0, f"uplift:{sg}")
        return evs, names

    def consistent(self, t: float, p: Pattern, z: np.ndarray) -> Pattern:
        """§5.4: switch M/U to B at once if an uplift indicator is already negative."""
        m = self.m
        if p.kind == "M":
            a, az = self.a(t), self.az(t)
            lam = {sg: m.lambda_if(p.base, sg, z[0], z[2], a, az=az) for sg in (1, -1)}
            sg = min(lam, key=lam.__getitem__)
            if lam[sg] < 0:
                return Pattern(p.base, sg)
        elif p.kind == "U":
            a, az = self.a(t), self.az(t)
            lam = {sg: m.lambda_b(p.iface, sg, z[1], z[3], a, az=az) for sg in (1, -1)}
            sg = min(lam, key=lam.__getitem__)
            if lam[sg] < 0:
                return Pattern(sg, p.iface)
        return p

    def impact(self, t: float, p: Pattern, kind: str, z: np.ndarray) -> tuple[Pattern, np.ndarray]:
        m = self.m
        z = z.copy()
        if kind == "base":
            z[0] = 0.0
        else:
            z[1] = 0.0
        th1, th2 = z[0], z[0] + z[1]
        w1, w2 = z[2], z[2] + z[3]
        post, a1, a2 = m.impact_outcome(p, kind, th1, th2, w1, w2, legacy=self.legacy,
                                        w_rest=self.w_rest)
        t_pre = m.kinetic_energy(p, th1, th2, w1, w2)
        t_post = m.kinetic_energy(post, th1, th2, a1, a2)
        self.impacts.append((t, kind, p.name, post.name))
        self.losses.append(t_pre - t_post)
        if post.kind == "R":
            z[:4] = 0.0
        else:
            z[2], z[3] = a1, a2 - a1
        return post, z

    # ---------------------------------------------------------------- loop
    def run(self, p: Pattern, z: np.ndarray) -> None:
        t = float(self.t_out[0])
        m = self.m
        stall = 0
        while t < self.t_final:
            if self.n_phases >= self.max_phases:
                self.status = "incomplete"
                self.message = (f"stopped after max_phases={self.max_phases} integration phases "
                                f"at t={t:.6g} s (chattering); later samples are not computed")
                return
            self.n_phases += 1
            if p.kind == "R":
                self.set_pattern(t, p)
                w = z[4]
                tn = self.next_start(t)
                last = tn is None or tn >= self.t_final

                def rest(ts: np.ndarray, w: float = w) -> np.ndarray:
                    out = np.zeros((ts.size, 5))
                    out[:, 4] = w
                    return out

                self.fill(t, self.t_final if tn is None else tn, rest, last, p)
                if tn is None or last:
                    return
                t = float(tn)
                a0 = self.a(t)
                t1 = t + 1e-9 * max(1.0, t)
                a1 = self.a(t1)
                use1 = abs(a1) > abs(a0) or a0 * a1 < 0
                ap = a1 if use1 else a0
                azp = self.az(t1 if use1 else t)
                thr = m.threshold_at(azp)
                if abs(ap) <= thr * (1 + 1e-9):
                    ap = math.copysign(thr * (1 + 1e-9), ap if ap != 0 else a0)
                p = m.start_pattern(ap, az=azp)
                z = np.array([0.0, 0.0, 0.0, 0.0, w])
                continue
            q = self.consistent(t, p, z)
            if q != p:
                z = z.copy()
                if p.kind == "M":
                    z[1], z[3] = 0.0, 0.0
                else:
                    z[0], z[2] = 0.0, 0.0
                p = q
            self.set_pattern(t, p)
            k = int(np.searchsorted(self.bps, t * (1 + 1e-14) + 1e-14, "right"))
            t_stop = float(self.bps[k]) if k < self.bps.size else self.t_final
            evs, names = self.events(p, z, t)
            sol = solve_ivp(self.rhs(p), (t, t_stop), z, method="DOP853", rtol=self.rtol,
                            atol=self.atol_vec, events=evs, dense_output=True)
            if sol.status < 0:
                self.status = "incomplete"
                self.message = f"integration failed at t={t:.6g} s: {sol.message}"
                return
            t_end = float(sol.t[-1])
            self.fill(t, t_end, partial(_dense_states, sol), t_end >= self.t_final, p)
            stall = stall + 1 if t_end <= t else 0
            if stall > 100:
                self.status = "incomplete"
                self.message = f"no progress at t={t:.6g} s in pattern {p.name}"
                return
            t = t_end
            z = sol.y[:, -1].copy()
            if sol.status != 1:
                continue
            fired = [names[i] for i, te in enumerate(sol.t_events) if te.size and te[-1] == t_end]
            if not fired:  # pragma: no cover - defensive
                fired = [names[i] for i, te in enumerate(sol.t_events) if te.size]
            prio = ("overturn", "impact", "fail", "uplift", "arm")
            ev = min(fired, key=lambda n: prio.index(n.split(":")[0]))
            what, _, arg = ev.partition(":")
            if what == "overturn":
                self.status = "overturned"
                self.t_over = t
                if p.kind == "M":
                    self.over_block = "stack"
                else:
                    self.over_block = "upper" if abs(z[0] + z[1]) >= abs(z[0]) else "lower"
                who = ("the whole stack" if self.over_block == "stack"
                       else f"the {self.over_block} block")
                self.message = f"{who} overturned at t={t:.6f} s"
                i0 = int(np.searchsorted(self.t_out, t, "left"))
                self.y[i0:] = np.nan
                return
            if what in ("impact", "fail"):
                p, z = self.impact(t, p, arg, z)
            elif what == "uplift":
                sg = int(arg)
                p = Pattern(p.base, sg) if p.kind == "M" else Pattern(sg, p.iface)
            # "arm": nothing to do; the next phase sees an armed gap


def _dense_states(sol: Any, ts: np.ndarray) -> np.ndarray:
    """An ODE solution's dense output at the times ``ts``, one row of states per time."""
    return sol.sol(ts).T


def _initial_pattern(theta0: tuple[float, float], omega0: tuple[float, float]) -> Pattern:
    th1, th2 = theta0
    w1, w2 = omega0

    def s(x: float, w: float) -> int:
        if x != 0:
            return 1 if x > 0 else -1
        return 1 if w >= 0 else -1

    if th1 == 0 and w1 == 0:
        if th2 == 0 and w2 == 0:
            return Pattern(0, 0)
        return Pattern(0, s(th2, w2))
    if th1 == th2 and w1 == w2:
        return Pattern(s(th1, w1), 0)
    return Pattern(s(th1, w1), s(th2 - th1, w2 - w1))


def solve_two_blocks(
    lower: BlockParams,
    upper: BlockParams,
    *,
    g: float,
    accel: Callable[[Any], Any],
    breakpoints: Sequence[float] = (),
    end_time: float = math.inf,
    theta0: tuple[float, float] = (0.0, 0.0),
    omega0: tuple[float, float] = (0.0, 0.0),
    t_out: Sequence[float] | np.ndarray,
    pattern: str | Pattern | None = None,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    w_rest: float | None = None,
    max_phases: int = 200000,
    legacy: bool = False,
    vertical: Callable[[Any], Any] | None = None,
) -> TwoBlockSolution:
    """Rocking response of two stacked rigid blocks on a moving rigid base.

    Parameters
    ----------
    lower, upper : BlockParams
        Lower and upper block (pivot half-width, half-height, mass, centroidal
        inertia). The interface pivots are at ``bc = min(lower.b, upper.b)``.
    g : float
        Gravity (m/s²).
    accel : callable
        Base acceleration ü_g(t) (m/s², positive toward +x). Must accept a float
        and a NumPy array of times.
    breakpoints : sequence of float
        Times where ü_g (or ü_z) is not smooth; the integration restarts there.
    end_time : float
        Time after which ü_g ≡ 0 and ü_z ≡ 0 (used to stop waiting at rest).
    theta0, omega0 : tuple of float
        Initial absolute rotations (θ1, θ2) and rates (rad, rad/s). Equal
        rotations mean a rigidly tilted stack (pattern ``M``).
    t_out : array_like
        Increasing output times (s); the simulation runs from ``t_out[0]`` to
        ``t_out[-1]``.
    pattern : str or Pattern, optional
        Initial pattern (e.g. ``"B(+1,+1)"``, ``"U(+1)"``); inferred from the
        initial state by default.
    rtol, atol : float
        Tolerances of the DOP853 integrator.
    w_rest : float, optional
        Zeno arrest threshold (rad/s); default ``1e-3 min(pM αM, p2 α2)`` (§5.5).
    max_phases : int
        Maximum number of integration phases (guards chattering).
    legacy : bool
        Simplified impact rule (``M``→``M``, ``U``→``U`` always), for comparison.
    vertical : callable, optional
        Vertical base acceleration ü_z(t) (m/s², positive up), like ``accel``
        (a float and a NumPy array of times); its breakpoints must be in
        ``breakpoints``. The blocks' weight is then m (g + ü_z). None: the base
        moves horizontally only.

    Returns
    -------
    TwoBlockSolution
        Sampled response, impacts, pattern history and outcome; status
        ``"flight"`` when g + ü_z turns negative (before any overturn): the
        solution stops there.
    """
    model = TwoBlockModel(lower, upper, g)
    t_out = np.asarray(t_out, float).reshape(-1)
    if t_out.size == 0 or np.any(np.diff(t_out) < 0):
        raise ValueError("t_out must be a non-empty increasing sequence of times")
    th1, th2 = (float(v) for v in theta0)
    w1, w2 = (float(v) for v in omega0)
    p = _initial_pattern((th1, th2), (w1, w2)) if pattern is None else parse_pattern(pattern)
    if p.kind == "M" and (th1 != th2 or w1 != w2):
        raise ValueError(f"pattern {p.name} needs equal initial rotations and rates")
    if p.kind == "U" and (th1 != 0 or w1 != 0):
        raise ValueError(f"pattern {p.name} needs a lower block at rest (θ1 = 0)")
    if p.kind == "R" and any(v != 0 for v in (th1, th2, w1, w2)):
        raise ValueError("pattern R needs a zero initial state")
    if w_rest is None:
        w_rest = 1e-3 * min(model.pM * model.alphaM, model.p2 * model.alpha2)
    t_flight = None
    if vertical is not None:
        # flight_time scans [0, t_end]: shift it to the run's start t_out[0]
        t0 = float(t_out[0])
        vz = vertical
        t_flight = flight_time(lambda t: vz(np.asarray(t, float) + t0),
                               lambda t: float(vz(t + t0)), model.g,
                               min(float(end_time), float(t_out[-1])) - t0)
        if t_flight is not None:
            t_flight += t0
    run = _Run(model, accel, breakpoints, end_time, t_out, rtol, atol, float(w_rest),
               int(max_phases), legacy, vertical=vertical, t_stop=t_flight)
    z = np.array([th1, th2 - th1, w1, w2 - w1, 0.0])
    run.run(p, z)
    if t_flight is not None and run.status == "ok":
        # the stack leaves the ground at t_flight: nothing after it is computed
        if not np.isfinite(run.y[0, 0]):  # flight from the start
            run.y[0], run.pat[0] = z, p
        run.y[int(np.searchsorted(t_out, t_flight, "right")):] = np.nan
        run.pat[int(np.searchsorted(t_out, t_flight, "right")):] = 0
        run.status = "flight"
        run.message = (f"the base falls faster than gravity at t = {t_flight:.6f} s "
                       f"(g + ü_z < 0): the stack leaves the ground, which the model does "
                       f"not follow")
    y = run.y
    theta = np.column_stack([y[:, 0], y[:, 0] + y[:, 1]])
    theta_dot = np.column_stack([y[:, 2], y[:, 2] + y[:, 3]])
    return TwoBlockSolution(
        t=t_out, theta=theta, theta_dot=theta_dot, status=run.status, impacts=run.impacts,
        patterns=run.patterns, overturn_time=run.t_over, overturned_block=run.over_block,
        message=run.message, work=y[:, 4].copy(), impact_losses=run.losses,
        n_phases=run.n_phases, contacts=run.pat, model=model, flight_time=t_flight,
    )


# ---------------------------------------------------------------- scenarios
class _ScalarAccel:
    """Fast scalar evaluation of a known excitation, falling back to the vectorised one."""

    def __init__(self, exc: Motion, scalar: Callable[[float], float] | None) -> None:
        self.exc = exc
        self.scalar = scalar

    def __call__(self, t: Any) -> Any:
        if self.scalar is not None and isinstance(t, float):
            return self.scalar(t)
        return self.exc.acceleration(t)


def _fast_accel(exc: Motion) -> _ScalarAccel:
    # the single-block solver's checked plain-math copies of the excitations
    return _ScalarAccel(exc, scalar_acceleration(exc))


def two_block_reference(scenario: Scenario) -> Trajectory:
    """Analytic reference trajectory of a two-block scenario.

    The stack starts tilted rigidly by ``scenario.theta0`` (pattern ``M``) or at
    rest, and is driven by the scenario's base acceleration along x and, if
    the base moves vertically, along z (weight m (g + ü_z)). Pivots are at the
    chamfer corners on the faces (lever arms with ``b − chamfer``), inertia of
    the full boxes.

    Parameters
    ----------
    scenario : rockbench.scenarios.Scenario
        A scenario with exactly two blocks and zero offsets.

    Returns
    -------
    rockbench.trajectory.Trajectory
        θ of both blocks, centroid x (including the base displacement u_g) and
        z (including the base's vertical displacement) in the ground frame,
        status ``ok`` or ``overturned`` (the samples end at the last output time
        before the overturn; the message and ``extra`` name the overturned
        block, ``"stack"``, ``"lower"`` or ``"upper"``, and the overturn time),
        impact times, and ``extra`` with the pattern history and the impacts. A
        run stopped early (``max_phases``) ends at its last computed sample with
        status ``timeout``; where g + ü_z < 0 (the stack leaves the ground, which
        the model does not follow) the samples end at that time with status
        ``unsupported`` and a message saying so, as Housner's reference does.

    Raises
    ------
    rockbench.errors.UnsupportedScenario
        If the scenario does not have exactly two centred blocks, or its base
        moves along y.
    """
    col = scenario.geometry.column
    if col is None or len(col) != 2:
        raise UnsupportedScenario(
            f"two-block reference needs exactly 2 stacked blocks, scenario {scenario.name!r} "
            f"has another geometry")
    if not col.centred:
        raise UnsupportedScenario(
            f"two-block reference needs centred blocks (zero offsets), got {col.offsets}")
    motion = scenario.motion
    if "y" in motion.axes:
        raise UnsupportedScenario("the two-block reference is planar: no base motion along y")
    lo_blk, up_blk = col.blocks
    lower, upper = BlockParams.from_block(lo_blk), BlockParams.from_block(up_blk)
    exc, up = motion.x, motion.z
    accel = _fast_accel(exc)
    vertical = None if up.is_free else _fast_accel(up)
    # without a vertical motion: x's own breakpoints and end time, as always
    breakpoints, end_time = ((exc.breakpoints, exc.end_time) if vertical is None
                             else (motion.breakpoints, motion.end_time))
    t_out = scenario.output_times()
    th0 = float(scenario.theta0)
    settings: dict[str, Any] = {"method": "DOP853", "rtol": 1e-10, "atol": 1e-12,
                                "max_phases": 200000, "legacy": False, "eps_arm": EPS_ARM}
    t0 = time.perf_counter()
    sol = solve_two_blocks(
        lower, upper, g=scenario.g, accel=accel, breakpoints=breakpoints,
        end_time=end_time, theta0=(th0, th0), t_out=t_out, rtol=settings["rtol"],
        atol=settings["atol"], max_phases=settings["max_phases"], vertical=vertical,
    )
    wall = time.perf_counter() - t0
    model = sol.model
    settings["w_rest"] = 1e-3 * min(model.pM * model.alphaM, model.p2 * model.alpha2)
    # the solver leaves NaN after an overturn or an early stop: the trajectory ends at
    # its last computed sample instead (as the single-block reference and the engines
    # do), so that no NaN is presented as a result
    computed = np.isfinite(sol.theta[:, 0])
    n = t_out.size if computed.all() else int(np.argmin(computed))
    t_out, theta = t_out[:n], sol.theta[:n]
    g1, g2 = model.positions(theta[:, 0], theta[:, 1])
    ug = np.asarray(exc.displacement(t_out), float)
    x = np.column_stack([g1[:, 0] + ug, g2[:, 0] + ug])
    z = np.column_stack([g1[:, 1], g2[:, 1]])
    if vertical is not None:
        z = z + np.asarray(up.displacement(t_out), float)[:, None]
    status = {"ok": Status.OK, "overturned": Status.OVERTURNED,
              "flight": Status.UNSUPPORTED}.get(sol.status, Status.TIMEOUT)
    msg = sol.message
    if scenario.contact.eta is not None:
        msg = (msg + "; " if msg else "") + "contact.eta ignored (two-block impacts follow " \
            "from momentum conservation)"
    return Trajectory(
        t=t_out, theta=theta, x=x, z=z, wobble=np.zeros_like(theta), status=status,
        message=msg, wall_time=wall, engine="analytic",
        engine_version=f"twoblock-{provenance.code_version('reference')}", settings=settings,
        scenario=scenario.name, impacts=sol.impact_times,
        extra={
            "patterns": [[float(t), n] for t, n in sol.patterns],
            "impacts": [[float(t), k, a, b] for t, k, a, b in sol.impacts],
            "overturned_block": sol.overturned_block,
            "overturn_time": sol.overturn_time,
            "n_phases": sol.n_phases,
            **({} if vertical is None else {"flight_time": sol.flight_time}),
        },
    )
