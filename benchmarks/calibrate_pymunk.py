"""Calibrate the pymunk engine's presets against the Housner reference.

For each preset (``accurate``, ``fast``) it runs the catalog's free-rocking
cases (B0 at 0.5 λ; B1, B2, B3 at 0.2, 0.5, 0.99 λ; 20 s, 1 kHz output,
friction 1, restitution 0) and the six Single #2 sine pulses (4 s), and prints
a Markdown table: max |θ − θ_ref| / λ (until the reference comes to rest),
relative errors of the first three impact times, peak ratio for the pulses and
wall time.

Usage::

    python benchmarks/calibrate_pymunk.py [--preset accurate,fast] [--set knob=value ...]

The reference is ``rockbench.analytic.housner.single_block_reference`` when it
exists, else a local event-driven Housner integration (scipy DOP853, tight
tolerances) with the same conventions.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from rockbench.engines.pymunk_engine import PymunkEngine
from rockbench.scenarios import Block, Contact, Scenario, SinePulse

FREE_BLOCKS = {
    "B0": (1.0, 0.2, 5.0),
    "B1": (0.5, 0.2, 0.75),
    "B2": (0.5, 0.2, 1.0),
    "B3": (0.5, 0.2, 1.25),
}
PULSES = [(3.0, 0.008), (3.3, 0.006), (3.3, 0.008), (5.0, 0.004), (5.0, 0.005), (5.0, 0.006)]


def free_cases(duration: float = 20.0) -> list[Scenario]:
    """The catalog's free-rocking scenarios."""
    out = []
    for name, (w, d, h) in FREE_BLOCKS.items():
        for tilt in (0.5,) if name == "B0" else (0.2, 0.5, 0.99):
            out.append(Scenario(f"free-{name.lower()}-{tilt}", Block(w, d, h, mass=1.0),
                                Contact(1.0, 0.0), initial_tilt=tilt, duration=duration,
                                output_rate=1000.0))
    return out


def pulse_cases(duration: float = 4.0) -> list[Scenario]:
    """The six Single #2 one-sine pulses."""
    blk = Block(0.17, 0.502, 1.0, density=2670.0)
    return [Scenario(f"single-pulse-{f}hz-{a * 1e3:g}mm", blk, Contact(1.0, 0.0),
                     SinePulse(f, a), duration=duration, output_rate=1000.0)
            for f, a in PULSES]


# ---------------------------------------------------------------- reference
@dataclass
class Reference:
    """Sampled reference: θ at the output times, impact times, time it comes to rest."""

    theta: np.ndarray
    impacts: np.ndarray
    t_rest: float


def housner_local(scenario: Scenario) -> Reference:
    """Event-driven Housner single block (rigid base, no sliding, no bouncing).

    θ'' = −p² [sin(sλ − θ) + (ü_g/g) cos(sλ − θ)], s = sign of the side it rocks
    on; at θ = 0 the angular velocity is multiplied by η and s flips; at rest it
    stays until |ü_g| > g tan λ (then rocks to the side −sign ü_g).
    """
    blk = scenario.blocks[0]
    rp = blk.rocking(scenario.g)
    lam, p, g = rp.lam, rp.p, scenario.g
    eta = scenario.contact.eta if scenario.contact.eta is not None else rp.eta
    exc = scenario.excitation
    t_out = scenario.output_times()
    T = float(t_out[-1])
    acc = exc.acceleration
    theta = np.zeros_like(t_out)
    impacts: list[float] = []
    breaks = sorted(b for b in exc.breakpoints if 0 < b < T)

    def rhs_for(s: float):
        def rhs(t: float, y: np.ndarray) -> list[float]:
            a = s * lam - y[0]
            return [y[1], -p * p * (math.sin(a) + float(acc(t)) / g * math.cos(a))]
        return rhs

    t, th, om = 0.0, scenario.theta0, 0.0
    s = math.copysign(1.0, th) if th != 0 else 0.0
    t_rest = T
    thr = g * math.tan(lam)
    while t < T:
        if s == 0.0:  # at rest: wait for uplift
            grid = np.linspace(t, T, max(2, int((T - t) * 20000) + 1))
            over = np.nonzero(np.abs(acc(grid)) > thr)[0]
            if exc.is_free or over.size == 0:
                t_rest = t
                break
            k = over[0]
            if k > 0:
                a_s = math.copysign(1.0, float(acc(grid[k])))
                t = brentq(lambda x, a_s=a_s: a_s * float(acc(x)) - thr, grid[k - 1], grid[k],
                           xtol=1e-14)
            else:
                t = grid[0]
            s = -math.copysign(1.0, float(acc(grid[k])))
            th, om = 0.0, 0.0
            continue
        ev = lambda tt, y: y[0]  # noqa: E731
        ev.terminal = True
        ev.direction = -s  # crossing zero from the current side
        t_stop = min([b for b in breaks if b > t + 1e-12] + [T])
        sol = solve_ivp(rhs_for(s), (t, t_stop), [th, om], method="DOP853", rtol=1e-11,
                        atol=1e-13, events=ev, dense_output=True)
        t_end = sol.t[-1]
        m = (t_out >= t) & (t_out <= t_end)
        if m.any():
            theta[m] = sol.sol(t_out[m])[0]
        th, om = sol.y[0, -1], sol.y[1, -1]
        if sol.status == 1:  # impact
            impacts.append(t_end)
            om *= eta
            th = 0.0
            s = -s
            if abs(om) < 1e-7 or (len(impacts) > 1 and impacts[-1] - impacts[-2] < 1e-6):
                s, om = 0.0, 0.0
        elif sol.status < 0:
            raise RuntimeError(sol.message)
        t = t_end
    after = t_out > t_rest
    theta[after] = 0.0
    return Reference(theta, np.array(impacts), t_rest)


def reference(scenario: Scenario) -> Reference:
    """The project's Housner reference if available, else the local one."""
    try:
        from rockbench.analytic.housner import single_block_reference
    except ImportError:
        return housner_local(scenario)
    tr = single_block_reference(scenario)
    th = np.interp(scenario.output_times(), tr.t, tr.theta[:, 0])
    imp = np.asarray(tr.impacts if tr.impacts is not None else zero_crossings(tr.t, th))
    rest = (tr.extra or {}).get("rest_time")
    rest = scenario.duration if rest is None else float(rest)
    return Reference(th, imp, rest)


def zero_crossings(t: np.ndarray, th: np.ndarray) -> np.ndarray:
    """Times where θ changes sign (linear interpolation)."""
    s = np.sign(th)
    i = np.nonzero(s[:-1] * s[1:] < 0)[0]
    return t[i] - th[i] * (t[i + 1] - t[i]) / (th[i + 1] - th[i])


# ---------------------------------------------------------------- runs
def run_free(sc: Scenario, preset: str, overrides: dict) -> dict:
    ref = reference(sc)
    tr = PymunkEngine().simulate(sc, {"preset": preset, **overrides})
    lam = sc.critical_angle
    th = tr.theta[:, 0]
    n = min(th.size, ref.theta.size)
    upto = tr.t[:n] <= ref.t_rest
    err = float(np.max(np.abs(th[:n] - ref.theta[:n])[upto])) / lam
    zc = zero_crossings(tr.t, th)
    imp_err = [(zc[k] - ref.impacts[k]) / ref.impacts[k] * 100 if k < zc.size else math.nan
               for k in range(3)]
    return dict(case=sc.name, status=str(tr.status), err=err, imp=imp_err, wall=tr.wall_time,
                t_rest=ref.t_rest)


def run_pulse(sc: Scenario, preset: str, overrides: dict) -> dict:
    ref = reference(sc)
    tr = PymunkEngine().simulate(sc, {"preset": preset, **overrides})
    lam = sc.critical_angle
    pk = float(np.max(np.abs(tr.theta[:, 0]))) / lam
    pk_ref = float(np.max(np.abs(ref.theta))) / lam
    return dict(case=sc.name, status=str(tr.status), peak=pk, peak_ref=pk_ref,
                ratio=pk / pk_ref, wall=tr.wall_time)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--preset", default="accurate,fast")
    ap.add_argument("--set", action="append", default=[], metavar="KNOB=VALUE")
    ap.add_argument("--duration", type=float, default=20.0)
    args = ap.parse_args(argv)
    overrides = dict(kv.split("=", 1) for kv in args.set)
    print(f"pymunk {PymunkEngine.version()}; overrides {overrides or 'none'}\n")
    for preset in args.preset.split(","):
        s = PymunkEngine.settings(preset, **overrides)
        print(f"### preset `{preset}`: {s.to_dict()}\n")
        print("| case | status | max err/λ (to rest) | impact 1 err % | impact 2 err % "
              "| impact 3 err % | wall s |")
        print("|---|---|---|---|---|---|---|")
        t0 = time.perf_counter()
        for sc in free_cases(args.duration):
            r = run_free(sc, preset, overrides)
            print(f"| {r['case']} | {r['status']} | {r['err']:.5f} | {r['imp'][0]:+.4f} | "
                  f"{r['imp'][1]:+.4f} | {r['imp'][2]:+.4f} | {r['wall']:.2f} |", flush=True)
        print("\n| pulse | status | max θ/λ engine | max θ/λ ref | ratio − 1 (%) | wall s |")
        print("|---|---|---|---|---|---|")
        for sc in pulse_cases():
            r = run_pulse(sc, preset, overrides)
            print(f"| {r['case']} | {r['status']} | {r['peak']:.5f} | {r['peak_ref']:.5f} | "
                  f"{(r['ratio'] - 1) * 100:+.3f} | {r['wall']:.2f} |", flush=True)
        print(f"\n(total {time.perf_counter() - t0:.1f} s)\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
