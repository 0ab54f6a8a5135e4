"""Analytic speed: rockbench's Housner reference against a plain DOP853 integration.

:func:`plain_housner` is written here independently of
:mod:`rockbench.analytic.housner`: SciPy ``solve_ivp`` (DOP853, dense output)
integrates Housner's equation phase by phase with a terminal impact event
(θ = 0, crossing toward the other pivot) and an overturning event, applies
θ̇⁺ = η θ̇⁻ at each impact, restarts at the excitation's breakpoints, arrests the
block when the post-impact speed falls below 1e-3 · p · λ (the reference's Zeno
rule), and finds uplift from rest by a sampled scan of |ü_g| > g tan λ refined by
Brent's method. It never uses a closed form.

The reference (``single_block_reference``) uses the exact elliptic-function
closed form between impacts once the base is still, and DOP853 (rtol 1e-10)
for forced phases. Both must agree (max |Δθ| / λ); a tighter plain run
(rtol 1e-12) estimates the error of each.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from benchmarks import best_of, fmt_time, load
from rockbench.analytic import critical_angle, single_block_reference
from rockbench.scenarios import Scenario, get_scenario, get_suite

__all__ = ["plain_housner", "run"]

#: Goals of issue 7.
SPEEDUP_GOAL = 10.0
CASE_GOAL = 0.050


def _uplift_time(acc, ta: float, tb: float, thr: float, dt: float = 1e-4) -> float | None:
    """First time in [ta, tb] where |ü_g| > thr (sampled scan + Brent), or None."""
    n = int(math.ceil((tb - ta) / dt)) + 1
    t = np.linspace(ta, tb, max(n, 2))
    a = np.abs(np.asarray(acc(t), float) * np.ones_like(t)) - thr
    hit = np.nonzero(a > 0)[0]
    if hit.size == 0:
        return None
    j = int(hit[0])
    if j == 0:
        return ta
    root = brentq(lambda x: abs(float(acc(x))) - thr, t[j - 1], t[j], xtol=1e-14)
    # step to the exceeding side
    for eps in (0.0, 1e-13, 1e-12, 1e-11, 1e-10):
        if abs(float(acc(root + eps))) > thr:
            return root + eps
    return float(t[j])


def plain_housner(sc: Scenario, rtol: float = 1e-10, atol: float = 1e-12) -> np.ndarray:
    """θ(t_out) of a single-block scenario by plain event-driven DOP853 (no closed form)."""
    blk = sc.blocks[0]
    rock = blk.rocking(sc.g)
    lam, p = rock.lam, rock.p
    eta = rock.eta if sc.contact.eta is None else sc.contact.eta
    g = sc.g
    exc = sc.motion.x  # the horizontal component (the paper cases move along x only)
    t_out = sc.output_times()
    theta = np.zeros(t_out.size)
    t_fin = float(t_out[-1])
    end = min(exc.end_time, t_fin) if not exc.is_free else 0.0
    stops = sorted({b for b in (*exc.breakpoints, end) if 0.0 < b < t_fin} | {t_fin})
    acc = exc.acceleration
    w_rest = 1e-3 * p * lam
    thr = g * math.tan(lam)
    p2 = p * p

    def fill(ta: float, tb: float, fn) -> None:
        i0, i1 = np.searchsorted(t_out, [ta, tb], side="left")
        if tb >= t_fin:
            i1 = t_out.size
        if i1 > i0:
            theta[i0:i1] = fn(t_out[i0:i1])

    t, th, om = 0.0, float(sc.theta0), 0.0
    resting = th == 0.0
    s = math.copysign(1.0, th) if th else 1.0
    while t < t_fin:
        if resting:
            tu = _uplift_time(acc, t, end, thr) if t < end else None
            if tu is None:
                break
            t, th, om, resting = tu, 0.0, 0.0, False
            s = -math.copysign(1.0, float(acc(tu)))
            continue
        forced = t < end
        t_stop = next(b for b in stops if b > t + 1e-13)

        def rhs(tt, y, s=s, forced=forced):
            phi = s * lam - y[0]
            a = float(acc(tt)) / g if forced else 0.0
            return [y[1], -p2 * (math.sin(phi) + a * math.cos(phi))]

        def impact(tt, y):
            return y[0]
        impact.terminal = True
        impact.direction = -s

        def over(tt, y):
            return abs(y[0]) - 0.5 * math.pi
        over.terminal = True

        sol = solve_ivp(rhs, (t, t_stop), [th, om], method="DOP853", rtol=rtol, atol=atol,
                        dense_output=True, events=(impact, over))
        t_end = float(sol.t[-1])
        fill(t, t_end, lambda x, sol=sol: sol.sol(x)[0])
        if sol.status == 1 and sol.t_events[1].size:  # overturned
            theta[np.searchsorted(t_out, t_end, side="right"):] = np.nan
            break
        if sol.status == 1:  # impact
            om_minus = float(sol.y_events[0][0][1])
            om_plus = eta * om_minus
            t, th = float(sol.t_events[0][0]), 0.0
            if abs(om_plus) < w_rest:
                resting, om = True, 0.0
            else:
                om = om_plus
                s = math.copysign(1.0, om_plus)
            continue
        t, th, om = t_end, float(sol.y[0, -1]), float(sol.y[1, -1])
    return theta


def run(quick: bool = False, repeat: int | None = None) -> tuple[str, dict]:
    """Markdown section and raw numbers."""
    repeat = repeat or (2 if quick else 3)
    out: dict = {"load": None}
    lines = ["## 2. Analytic reference speed", ""]

    # B0 20 s: reference vs plain DOP853 at rtol 1e-10
    b0 = get_scenario("free-b0")
    lam = critical_angle(b0.geometry)
    r_ref = best_of(lambda: single_block_reference(b0), repeat)
    r_plain = best_of(lambda: plain_housner(b0, 1e-10), repeat)
    th_ref = r_ref.result.theta[:, 0]
    d_ref_plain = float(np.max(np.abs(th_ref - r_plain.result))) / lam
    tight = None
    if not quick:
        tight = plain_housner(b0, 1e-12, 1e-14)
    speed = r_plain.cpu / r_ref.cpu
    speed_w = r_plain.wall / r_ref.wall
    out["b0"] = dict(ref_cpu=r_ref.cpu, ref_wall=r_ref.wall, plain_cpu=r_plain.cpu,
                     plain_wall=r_plain.wall, speedup=speed, diff=d_ref_plain)
    acc_txt = f"max |θ_ref − θ_DOP853| = {d_ref_plain:.1e} λ"
    if tight is not None:
        e_ref = float(np.max(np.abs(th_ref - tight))) / lam
        e_plain = float(np.max(np.abs(r_plain.result - tight))) / lam
        out["b0"].update(err_ref=e_ref, err_plain=e_plain)
        acc_txt += (f"; against a DOP853 run at rtol 1e-12: reference {e_ref:.1e} λ, "
                    f"DOP853 rtol 1e-10 {e_plain:.1e} λ")
    lines += [
        f"B0 free rocking, 20 s, 1 kHz output ({len(r_ref.result.impacts)} impacts), "
        f"best of {repeat}:",
        "",
        "| method | CPU | wall |",
        "|---|---|---|",
        f"| `single_block_reference` (closed form between impacts) | {fmt_time(r_ref.cpu)} "
        f"| {fmt_time(r_ref.wall)} |",
        f"| plain DOP853 with events, rtol 1e-10 | {fmt_time(r_plain.cpu)} "
        f"| {fmt_time(r_plain.wall)} |",
        f"| **speed-up** | **{speed:.0f}×** {'✓' if speed >= SPEEDUP_GOAL else '✗'} "
        f"(goal ≥ {SPEEDUP_GOAL:.0f}×) | {speed_w:.0f}× |",
        "",
        f"Accuracy: {acc_txt}.",
        "",
    ]

    # every paper single-block case
    names = get_suite("paper-single-pulse") + get_suite("paper-single-sine")
    if quick:
        names = [names[0], names[5], names[6], names[11]]
    lines += [
        f"Every paper single-block case (Single #2, 4 s pulses, 10 s sinusoids, 1 kHz "
        f"output), best of {repeat} (goal ≤ {CASE_GOAL * 1e3:.0f} ms, on CPU time):",
        "",
        "| case | impacts | reference CPU | reference wall | plain DOP853 CPU | "
        "max \\|Δθ\\| / λ |",
        "|---|---|---|---|---|---|",
    ]
    cases = []
    for n in names:
        sc = get_scenario(n)
        r = best_of(lambda sc=sc: single_block_reference(sc), repeat)
        pl = best_of(lambda sc=sc: plain_housner(sc), 1)
        lam = critical_angle(sc.geometry)
        d = float(np.nanmax(np.abs(r.result.theta[:, 0] - pl.result))) / lam
        ok = "✓" if r.cpu <= CASE_GOAL else "✗"
        cases.append(dict(case=n, cpu=r.cpu, wall=r.wall, plain_cpu=pl.cpu, diff=d,
                          impacts=len(r.result.impacts)))
        lines.append(f"| {n} | {len(r.result.impacts)} | {fmt_time(r.cpu)} {ok} | "
                     f"{fmt_time(r.wall)} | {fmt_time(pl.cpu)} | {d:.0e} |")
    out["cases"] = cases
    out["load"] = load()
    lines += ["", f"({out['load']} at the end of this section.)", ""]
    return "\n".join(lines) + "\n", out


if __name__ == "__main__":  # pragma: no cover
    import sys

    print(run("--quick" in sys.argv)[0])
