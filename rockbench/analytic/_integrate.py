"""A scalar DOP853 integrator for θ'' = α(t, θ), with dense output and terminal events.

The forced phases of the Housner solver integrate a 2-state system
(θ, ω = θ̇) whose right-hand side costs about a microsecond in plain ``math``.
``scipy.integrate.solve_ivp`` spends most of its time in its own per-step
Python and NumPy calls on such a small system; this module does the same
computation on Python floats.

It is the algorithm of SciPy's ``DOP853`` (Hairer's Dormand–Prince 8(5,3)
pair, its Butcher tableau, error norm, step-size controller and initial-step
selection, the 7th-order dense output) and of ``solve_ivp``'s event handling
(sign change of each event function between two accepted steps, root by
Brent's method on the dense output with ``xtol = rtol = 4·eps``, earliest
terminal event wins), so the two give the same step sequence and agree to
rounding. The coefficients are those of ``scipy/integrate/_ivp/dop853_coefficients.py``
(E. Hairer's ``dop853.f``), rounded to double precision; only the non-zero
entries are listed.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.optimize import brentq

__all__ = ["DenseSolution", "PhaseResult", "integrate_phase"]

EPS = np.finfo(float).eps
SAFETY = 0.9
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0
#: −1 / (error estimator order + 1)
ERROR_EXPONENT = -1.0 / 8.0

#: Nodes c_i of the 16 stages (12 for the step, 3 more for the dense output).
C = (0.0, 0.05260015195876773, 0.0789002279381516, 0.1183503419072274, 0.2816496580927726,
     0.3333333333333333, 0.25, 0.3076923076923077, 0.6512820512820513, 0.6,
     0.8571428571428571, 1.0, 1.0, 0.1, 0.2, 0.7777777777777778)

#: Rows 1–15 of the Runge–Kutta matrix as ((j, a_ij), ...); row 12 holds the weights b_j.
A: tuple[tuple[tuple[int, float], ...], ...] = (
    (),
    ((0, 0.05260015195876773),),
    ((0, 0.0197250569845379), (1, 0.0591751709536137)),
    ((0, 0.02958758547680685), (2, 0.08876275643042054)),
    ((0, 0.2413651341592667), (2, -0.8845494793282861), (3, 0.924834003261792)),
    ((0, 0.037037037037037035), (3, 0.17082860872947386), (4, 0.12546768756682242)),
    ((0, 0.037109375), (3, 0.17025221101954405), (4, 0.06021653898045596), (5, -0.017578125)),
    ((0, 0.03709200011850479), (3, 0.17038392571223998), (4, 0.10726203044637328),
     (5, -0.015319437748624402), (6, 0.008273789163814023)),
    ((0, 0.6241109587160757), (3, -3.3608926294469414), (4, -0.868219346841726),
     (5, 27.59209969944671), (6, 20.154067550477894), (7, -43.48988418106996)),
    ((0, 0.47766253643826434), (3, -2.4881146199716677), (4, -0.590290826836843),
     (5, 21.230051448181193), (6, 15.279233632882423), (7, -33.28821096898486),
     (8, -0.020331201708508627)),
    ((0, -0.9371424300859873), (3, 5.186372428844064), (4, 1.0914373489967295),
     (5, -8.149787010746927), (6, -18.52006565999696), (7, 22.739487099350505),
     (8, 2.4936055526796523), (9, -3.0467644718982196)),
    ((0, 2.273310147516538), (3, -10.53449546673725), (4, -2.0008720582248625),
     (5, -17.9589318631188), (6, 27.94888452941996), (7, -2.8589982771350235),
     (8, -8.87285693353063), (9, 12.360567175794303), (10, 0.6433927460157636)),
    ((0, 0.054293734116568765), (5, 4.450312892752409), (6, 1.8915178993145003),
     (7, -5.801203960010585), (8, 0.3111643669578199), (9, -0.1521609496625161),
     (10, 0.20136540080403034), (11, 0.04471061572777259)),
    ((0, 0.056167502283047954), (6, 0.25350021021662483), (7, -0.2462390374708025),
     (8, -0.12419142326381637), (9, 0.15329179827876568), (10, 0.00820105229563469),
     (11, 0.007567897660545699), (12, -0.008298)),
    ((0, 0.03183464816350214), (5, 0.028300909672366776), (6, 0.053541988307438566),
     (7, -0.05492374857139099), (10, -0.00010834732869724932), (11, 0.0003825710908356584),
     (12, -0.00034046500868740456), (13, 0.1413124436746325)),
    ((0, -0.42889630158379194), (5, -4.697621415361164), (6, 7.683421196062599),
     (7, 4.06898981839711), (8, 0.3567271874552811), (12, -0.0013990241651590145),
     (13, 2.9475147891527724), (14, -9.15095847217987)),
)
#: Error estimators (3rd and 5th order) on stages 0–12.
E3 = ((0, -0.18980075407240762), (5, 4.450312892752409), (6, 1.8915178993145003),
      (7, -5.801203960010585), (8, -0.4226823213237919), (9, -0.1521609496625161),
      (10, 0.20136540080403034), (11, 0.02265179219836082))
E5 = ((0, 0.01312004499419488), (5, -1.2251564463762044), (6, -0.4957589496572502),
      (7, 1.6643771824549864), (8, -0.35032884874997366), (9, 0.3341791187130175),
      (10, 0.08192320648511571), (11, -0.022355307863886294))
#: Dense-output coefficients (rows 3–6 of the interpolant) on stages 0–15.
D = (
    ((0, -8.428938276109013), (5, 0.5667149535193777), (6, -3.0689499459498917),
     (7, 2.38466765651207), (8, 2.117034582445028), (9, -0.871391583777973),
     (10, 2.2404374302607883), (11, 0.6315787787694688), (12, -0.08899033645133331),
     (13, 18.148505520854727), (14, -9.194632392478356), (15, -4.436036387594894)),
    ((0, 10.427508642579134), (5, 242.28349177525817), (6, 165.20045171727028),
     (7, -374.5467547226902), (8, -22.113666853125306), (9, 7.733432668472264),
     (10, -30.674084731089398), (11, -9.332130526430229), (12, 15.697238121770845),
     (13, -31.139403219565178), (14, -9.35292435884448), (15, 35.81684148639408)),
    ((0, 19.985053242002433), (5, -387.0373087493518), (6, -189.17813819516758),
     (7, 527.8081592054236), (8, -11.57390253995963), (9, 6.8812326946963),
     (10, -1.0006050966910838), (11, 0.7777137798053443), (12, -2.778205752353508),
     (13, -60.19669523126412), (14, 84.32040550667716), (15, 11.99229113618279)),
    ((0, -25.69393346270375), (5, -154.18974869023643), (6, -231.5293791760455),
     (7, 357.6391179106141), (8, 93.40532418362432), (9, -37.45832313645163),
     (10, 104.0996495089623), (11, 29.8402934266605), (12, -43.53345659001114),
     (13, 96.32455395918828), (14, -39.17726167561544), (15, -149.72683625798564)),
)



def _combo(row: Sequence[tuple[int, float]], var: str) -> str:
    return " + ".join(f"{a!r} * k{j}{var}" for j, a in row)


def _generate() -> str:
    """Source of ``_step`` and ``_dense``: the tableau above, unrolled for the 2-state system.

    Stage i has θ' = ω_i (``k{i}t``) and ω' = α(t + c_i h, θ_i) (``k{i}w``). Unrolling
    the sparse sums into straight-line float arithmetic halves the cost of a step
    compared with loops over the tables.
    """
    ln = ["def _step(alpha, t, th, w, h, k0w):", "    k0t = w"]
    for i in range(1, 12):
        ln += [f"    k{i}t = w + ({_combo(A[i], 'w')}) * h",
               f"    k{i}w = alpha(t + {C[i]!r} * h, th + ({_combo(A[i], 't')}) * h)"]
    ln += [f"    th_new = th + ({_combo(A[12], 't')}) * h",
           f"    k12t = w + ({_combo(A[12], 'w')}) * h",
           "    k12w = alpha(t + h, th_new)"]
    ks = ", ".join(f"k{i}{{v}}" for i in range(13))
    ln += [f"    return (th_new, k12t, ({ks.format(v='t')}), ({ks.format(v='w')}),",
           f"            {_combo(E5, 't')},", f"            {_combo(E5, 'w')},",
           f"            {_combo(E3, 't')},", f"            {_combo(E3, 'w')})", "",
           "def _dense(alpha, t, th, w, h, th_new, w_new, kt, kw):",
           f"    {ks.format(v='t')} = kt", f"    {ks.format(v='w')} = kw"]
    for i in range(13, 16):
        ln += [f"    k{i}t = w + ({_combo(A[i], 'w')}) * h",
               f"    k{i}w = alpha(t + {C[i]!r} * h, th + ({_combo(A[i], 't')}) * h)"]
    ln += ["    dt = th_new - th", "    dw = w_new - w",
           "    return [t, h, th, w, dt, h * k0t - dt, 2.0 * dt - h * (k12t + k0t),",
           *[f"            h * ({_combo(r, 't')})," for r in D],
           "            dw, h * k0w - dw, 2.0 * dw - h * (k12w + k0w),",
           *[f"            h * ({_combo(r, 'w')})," for r in D],
           "            ]"]
    return "\n".join(ln) + "\n"


_ns: dict[str, Any] = {}
exec(compile(_generate(), "<rockbench.analytic._integrate generated>", "exec"), _ns)
_step: Callable[..., tuple[Any, ...]] = _ns["_step"]
_dense: Callable[..., list[float]] = _ns["_dense"]
del _ns

#: An event function g(t, θ, ω); an event is a crossing of g from ≥ 0 to ≤ 0.
Event = Callable[[float, float, float], float]


class DenseSolution:
    """Piecewise 7th-order interpolant of the accepted steps (as SciPy's ``OdeSolution``).

    ``coef`` has one row per step: t_old, h, θ_old, ω_old, then F_0..F_6 for θ
    and for ω (the ``Dop853DenseOutput`` polynomial).
    """

    def __init__(self, ts: list[float], coef: list[float]) -> None:
        self.ts = np.asarray(ts, dtype=float)
        self.coef = np.asarray(coef, dtype=float).reshape(-1, 18)

    def __call__(self, tt: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(θ, ω) at the sorted times ``tt`` (extrapolated by the end steps outside)."""
        tt = np.asarray(tt, dtype=float)
        n = self.coef.shape[0]
        seg = np.clip(np.searchsorted(self.ts, tt, side="left") - 1, 0, n - 1)
        c = self.coef[seg]
        x = (tt - c[:, 0]) / c[:, 1]
        # y = y_old + Σ_i F_i b_i(x), b = x, x(1−x), x²(1−x), x²(1−x)², ... (SciPy's Horner form)
        b = np.empty((x.size, 7))
        b[:, 0::2] = x[:, None]
        b[:, 1::2] = (1.0 - x)[:, None]
        np.cumprod(b, axis=1, out=b)
        yt = np.einsum("ij,ij->i", c[:, 4:11], b)
        yw = np.einsum("ij,ij->i", c[:, 11:18], b)
        return yt + c[:, 2], yw + c[:, 3]


@dataclass
class PhaseResult:
    """Outcome of :func:`integrate_phase`.

    ``status`` is 0 (reached ``t_bound``), 1 (terminal event ``event``) or −1
    (step size too small); ``t``, ``theta``, ``omega`` are the final state (at
    the event root for status 1); ``ts`` the step ends (starting with t0, the
    last one replaced by the root for an event) as ``solve_ivp``'s ``sol.t``.
    """

    status: int
    t: float
    theta: float
    omega: float
    event: int | None
    ts: list[float]
    dense: DenseSolution
    nfev: int


def _dense_scalar(row: Sequence[float], t: float) -> tuple[float, float]:
    """Evaluate one step's interpolant at a single time."""
    x = (t - row[0]) / row[1]
    x1 = 1.0 - x
    yt = yw = 0.0
    for i in range(7):
        f = x if i % 2 == 0 else x1
        yt = (yt + row[10 - i]) * f
        yw = (yw + row[17 - i]) * f
    return yt + row[2], yw + row[3]


def integrate_phase(
    alpha: Callable[[float, float], float],
    t0: float,
    theta0: float,
    omega0: float,
    t_bound: float,
    *,
    rtol: float,
    atol: float,
    events: Sequence[Event] = (),
    first_step: float | None = None,
) -> PhaseResult:
    """Integrate θ' = ω, ω' = α(t, θ) from t0 to t_bound (> t0) with DOP853.

    Each event is terminal with direction −1: the integration stops at the
    first root of g(t, θ(t), ω(t)) where g goes from ≥ 0 (previous step) to
    ≤ 0 (current step).
    """
    t, th, w = float(t0), float(theta0), float(omega0)
    t_bound = float(t_bound)
    a0 = alpha(t, th)
    nfev = 1
    sqrt = math.sqrt

    # ------------------------------------------------------ initial step (Hairer II.4)
    interval = t_bound - t
    if first_step is None:
        st_ = atol + abs(th) * rtol
        sw_ = atol + abs(w) * rtol
        d0 = sqrt(((th / st_) ** 2 + (w / sw_) ** 2) / 2.0)
        d1 = sqrt(((w / st_) ** 2 + (a0 / sw_) ** 2) / 2.0)
        h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
        h0 = min(h0, interval)
        a1 = alpha(t + h0, th + h0 * w)
        nfev += 1
        w1 = w + h0 * a0
        d2 = sqrt((((w1 - w) / st_) ** 2 + ((a1 - a0) / sw_) ** 2) / 2.0) / h0
        if d1 <= 1e-15 and d2 <= 1e-15:
            h1 = max(1e-6, h0 * 1e-3)
        else:
            h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
        h_abs = min(100.0 * h0, h1, interval)
    else:
        if not 0.0 < first_step <= interval:
            raise ValueError("first_step must be in (0, t_bound - t0]")
        h_abs = float(first_step)

    g_old = [ev(t, th, w) for ev in events]
    ts = [t]
    coef: list[float] = []
    status: int | None = None
    event: int | None = None
    while status is None:
        # ------------------------------------------------------------ one step
        min_step = 10.0 * abs(math.nextafter(t, math.inf) - t)
        h_abs = max(h_abs, min_step)
        rejected = False
        while True:
            if h_abs < min_step:
                return PhaseResult(-1, t, th, w, None, ts, DenseSolution(ts, coef), nfev)
            t_new = t + h_abs
            if t_new > t_bound:
                t_new = t_bound
            h = t_new - t
            h_abs = abs(h)
            th_new, w_new, kt, kw, e5t, e5w, e3t, e3w = _step(alpha, t, th, w, h, a0)
            nfev += 12
            sc_t = atol + max(abs(th), abs(th_new)) * rtol
            sc_w = atol + max(abs(w), abs(w_new)) * rtol
            e5 = (e5t / sc_t) ** 2 + (e5w / sc_w) ** 2
            e3 = (e3t / sc_t) ** 2 + (e3w / sc_w) ** 2
            if e5 == 0.0 and e3 == 0.0:
                err = 0.0
            else:
                err = h_abs * e5 / sqrt((e5 + 0.01 * e3) * 2.0)
            if err < 1.0:
                factor = MAX_FACTOR if err == 0.0 else min(MAX_FACTOR,
                                                           SAFETY * err ** ERROR_EXPONENT)
                if rejected:
                    factor = min(1.0, factor)
                h_abs *= factor
                break
            h_abs *= max(MIN_FACTOR, SAFETY * err ** ERROR_EXPONENT)
            rejected = True
        # -------------------------------------------------------- dense output
        row_ = _dense(alpha, t, th, w, h, th_new, w_new, kt, kw)
        nfev += 3
        coef += row_
        t_old = t
        t, th, w = t_new, th_new, w_new
        a0 = kw[12]
        if t_new == t_bound:
            status = 0
        # -------------------------------------------------------------- events
        if events:
            g_new = [ev(t, th, w) for ev in events]
            roots = []
            for i, (ga, gb) in enumerate(zip(g_old, g_new, strict=True)):
                if ga >= 0.0 and gb <= 0.0:
                    ev = events[i]
                    r = brentq(lambda x, ev=ev, rw=row_: ev(x, *_dense_scalar(rw, x)), t_old, t,
                               xtol=4 * EPS, rtol=4 * EPS)
                    roots.append((r, i))
            if roots:
                r, event = min(roots)
                status = 1
                t = r
                th, w = _dense_scalar(row_, r)
            g_old = g_new
        ts.append(t)
    return PhaseResult(status, t, th, w, event, ts, DenseSolution(ts, coef), nfev)
