"""Calibrate the DART engine's presets against Housner's single-block solution.

For each preset (``accurate``, ``fast`` by default) it runs the free-rocking
catalog cases (B0 at 0.5 λ; B1, B2, B3 at 0.2, 0.5, 0.99 λ; 20 s, 1 kHz,
friction 1, restitution 0) and the six Single #2 sine pulses (4 s), and prints
a Markdown table: max |θ − θ_ref|/λ (until the reference comes to rest), the
relative errors of the first three impact times (zero crossings of θ), the
pulse peak ratio, and wall time. It also measures the adapter overhead against
a minimal raw dartpy loop on B0.

Usage::

    python benchmarks/calibrate_dart.py [--presets accurate,fast] [--set knob=value ...]
        [--skip-free] [--skip-pulse] [--skip-overhead]
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from rockbench.engines.dart_engine import DartEngine
from rockbench.scenarios import Block, Scenario, SinePulse

FREE_BLOCKS = {
    "B0": Block(1.0, 0.2, 5.0, mass=1.0),
    "B1": Block(0.5, 0.2, 0.75, mass=1.0),
    "B2": Block(0.5, 0.2, 1.0, mass=1.0),
    "B3": Block(0.5, 0.2, 1.25, mass=1.0),
}
PULSES = [(3.0, 0.008), (3.3, 0.006), (3.3, 0.008), (5.0, 0.004), (5.0, 0.005), (5.0, 0.006)]
SINGLE2 = Block(width=0.17, depth=0.502, height=1.0, density=2670.0)


def free_cases() -> list[Scenario]:
    """The ten free-rocking catalog cases."""
    out = [Scenario("free-b0", FREE_BLOCKS["B0"], initial_tilt=0.5, duration=20.0)]
    for key in ("B1", "B2", "B3"):
        for tilt in (0.2, 0.5, 0.99):
            out.append(Scenario(f"free-{key.lower()}-{tilt}", FREE_BLOCKS[key],
                                initial_tilt=tilt, duration=20.0))
    return out


def pulse_cases() -> list[Scenario]:
    """The six Single #2 one-sine pulses."""
    return [Scenario(f"single-pulse-{f}hz-{a * 1000:g}mm", SINGLE2,
                     excitation=SinePulse(frequency=f, amplitude=a), duration=4.0)
            for f, a in PULSES]


# ---------------------------------------------------------------------- reference
def _housner_fallback(scenario: Scenario) -> np.ndarray:
    """Event-driven Housner solution on the output times (used until
    ``rockbench.analytic.housner`` exists). Returns θ_ref (rad)."""
    from scipy.integrate import solve_ivp

    blk = scenario.blocks[0]
    rp = blk.rocking(scenario.g)
    lam, p, g = rp.lam, rp.p, scenario.g
    eta = scenario.contact.eta if scenario.contact.eta is not None else rp.eta
    exc = scenario.excitation
    t_out = scenario.output_times()
    t_end = float(t_out[-1])

    def acc(t: float) -> float:
        return float(exc.acceleration(t))

    def rhs(t: float, y: np.ndarray) -> list[float]:
        s = 1.0 if y[0] > 0 else -1.0
        return [y[1], -p * p * (math.sin(s * lam - y[0]) + acc(t) / g * math.cos(s * lam - y[0]))]

    out = np.zeros_like(t_out)
    t, y = 0.0, np.array([scenario.theta0, 0.0])
    resting = scenario.theta0 == 0.0
    fine = np.linspace(0.0, t_end, int(t_end * 20000) + 1)
    a_fine = np.asarray(exc.acceleration(fine), float)
    while t < t_end:
        if resting:  # wait for the base acceleration to exceed g tan λ
            idx = np.nonzero((fine > t) & (np.abs(a_fine) > g * math.tan(lam)))[0]
            if idx.size == 0:
                break
            t = float(fine[idx[0]])
            y = np.array([-math.copysign(1e-12, a_fine[idx[0]]), 0.0])
            resting = False
            continue

        def hit(_t: float, yy: np.ndarray) -> float:
            return yy[0]

        hit.terminal = True  # type: ignore[attr-defined]
        hit.direction = -math.copysign(1.0, y[0])  # type: ignore[attr-defined]
        sol = solve_ivp(rhs, (t, t_end), y, method="DOP853", rtol=1e-11, atol=1e-13,
                        events=hit, dense_output=True, max_step=5e-3)
        m = (t_out >= t) & (t_out <= sol.t[-1])
        if m.any():
            out[m] = sol.sol(t_out[m])[0]
        if sol.status != 1:
            break
        t = float(sol.t_events[0][0])
        om = float(sol.y_events[0][0][1]) * eta
        if abs(om) < 1e-4:  # comes to rest (amplitude below ~1e-5 rad)
            resting = True
            continue
        y = np.array([math.copysign(1e-13, om), om])
    return out


def reference(scenario: Scenario) -> np.ndarray:
    """θ_ref on the scenario's output times (the project's reference if present)."""
    try:
        from rockbench.analytic.housner import single_block_reference
    except ImportError:
        return _housner_fallback(scenario)
    ref = single_block_reference(scenario)
    th = np.asarray(ref.theta)[:, 0] if np.ndim(ref.theta) == 2 else np.asarray(ref.theta)
    t = np.asarray(ref.t)
    t_out = scenario.output_times()
    if th.size != t_out.size or not np.allclose(t, t_out):
        th = np.interp(t_out, t, th)
    return th


# ---------------------------------------------------------------------- metrics
def crossings(t: np.ndarray, th: np.ndarray, n: int = 3) -> np.ndarray:
    """First ``n`` zero crossings of θ, linearly interpolated."""
    s = np.sign(th)
    idx = np.nonzero(s[:-1] * s[1:] < 0)[0][:n]
    tc = t[idx] - th[idx] * (t[idx + 1] - t[idx]) / (th[idx + 1] - th[idx])
    return np.concatenate([tc, np.full(n - tc.size, np.nan)])


def rest_index(th_ref: np.ndarray, lam: float) -> int:
    """Index after which the reference stays at rest (|θ| < 1e-6 λ)."""
    moving = np.nonzero(np.abs(th_ref) > 1e-6 * lam)[0]
    return int(moving[-1]) + 1 if moving.size else th_ref.size


def free_row(scenario: Scenario, preset: str, overrides: dict) -> dict:
    lam = scenario.critical_angle
    th_ref = reference(scenario)
    traj = DartEngine().simulate(scenario, {"preset": preset, **overrides})
    th = np.asarray(traj.theta)[:, 0]
    n = min(th.size, rest_index(th_ref, lam))
    err = float(np.max(np.abs(th[:n] - th_ref[:n])) / lam) if traj.status == "ok" else math.nan
    t = scenario.output_times()
    tc_ref = crossings(t, th_ref)
    tc = crossings(t[:th.size], th)
    return dict(case=scenario.name, status=str(traj.status), err=err,
                dt_imp=(tc - tc_ref) / tc_ref * 100.0, wall=traj.wall_time)


def pulse_row(scenario: Scenario, preset: str, overrides: dict) -> dict:
    lam = scenario.critical_angle
    th_ref = reference(scenario)
    traj = DartEngine().simulate(scenario, {"preset": preset, **overrides})
    th = np.asarray(traj.theta)[:, 0]
    peak_ref = float(np.max(np.abs(th_ref)) / lam)
    peak = float(np.max(np.abs(th)) / lam)
    return dict(case=scenario.name, status=str(traj.status), peak_ref=peak_ref, peak=peak,
                ratio=(peak / peak_ref - 1.0) * 100.0 if peak_ref > 0 else math.nan,
                wall=traj.wall_time)


def overhead(preset: str, repeats: int = 3) -> tuple[float, float]:
    """Best-of wall time of the adapter and of a minimal raw loop on B0 (20 s, 1 kHz)."""
    sc = free_cases()[0]
    eng = DartEngine()
    s = eng.settings(preset)
    t_ad, t_raw = math.inf, math.inf
    for _ in range(repeats):
        t_ad = min(t_ad, eng.simulate(sc, s).wall_time)
        # raw: same scene, a bare step loop sampling the block's coordinates
        raw = DartEngine()
        dt = raw._build(sc, s)
        k = int(round(1e-3 / dt))
        skel, step = raw._skels[0], raw._world.step
        out = np.empty((20001, 6))
        t0 = time.perf_counter()
        out[0] = skel.getPositions()
        for i in range(1, 20001):
            for _ in range(k):
                step()
            out[i] = skel.getPositions()
        t_raw = min(t_raw, time.perf_counter() - t0)
        raw._teardown()
    return t_ad, t_raw


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--presets", default="accurate,fast")
    ap.add_argument("--set", action="append", default=[], metavar="KNOB=VALUE")
    ap.add_argument("--skip-free", action="store_true")
    ap.add_argument("--skip-pulse", action="store_true")
    ap.add_argument("--skip-overhead", action="store_true")
    ap.add_argument("--cases", default="", help="comma list of case-name substrings")
    args = ap.parse_args()
    overrides = dict(kv.split("=", 1) for kv in args.set)
    sel = [c for c in args.cases.split(",") if c]

    def keep(sc: Scenario) -> bool:
        return not sel or any(c in sc.name for c in sel)

    print(f"DART {DartEngine.version()}; overrides: {overrides or 'none'}\n")
    for preset in args.presets.split(","):
        print(f"### preset `{preset}`: {DartEngine.settings(preset, **overrides).to_dict()}\n")
        if not args.skip_free:
            print("| case | status | max err/λ | impact 1 (%) | impact 2 (%) | impact 3 (%) "
                  "| wall (s) |")
            print("|---|---|---|---|---|---|---|")
            for sc in filter(keep, free_cases()):
                r = free_row(sc, preset, overrides)
                imp = " | ".join(f"{v:+.3f}" for v in r["dt_imp"])
                print(f"| {r['case']} | {r['status']} | {r['err']:.4f} | {imp} | {r['wall']:.2f} |",
                      flush=True)
            print()
        if not args.skip_pulse:
            print("| case | status | peak ref/λ | peak/λ | peak error (%) | wall (s) |")
            print("|---|---|---|---|---|---|")
            for sc in filter(keep, pulse_cases()):
                r = pulse_row(sc, preset, overrides)
                print(f"| {r['case']} | {r['status']} | {r['peak_ref']:.4f} | {r['peak']:.4f} | "
                      f"{r['ratio']:+.2f} | {r['wall']:.2f} |", flush=True)
            print()
        if not args.skip_overhead:
            t_ad, t_raw = overhead(preset)
            print(f"Adapter overhead on free-b0 (best of 3): adapter {t_ad:.2f} s, raw loop "
                  f"{t_raw:.2f} s, overhead {100 * (t_ad / t_raw - 1):+.1f} %\n", flush=True)


if __name__ == "__main__":
    main()
