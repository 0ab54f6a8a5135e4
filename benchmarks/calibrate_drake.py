"""Calibrate the Drake engine's presets against the Housner reference.

For each preset (``accurate``, ``fast``) it runs the catalog's free-rocking
cases (B0 at 0.5 λ; B1, B2, B3 at 0.2, 0.5, 0.99 λ; 20 s, 1 kHz output,
friction 1, restitution 0) and the six Single #2 sine pulses (4 s), and prints
Markdown tables: max |θ − θ_ref| / λ (until the reference comes to rest),
relative errors of the first three impact times, peak ratio for the pulses,
how far the base drifted after the excitation ended, out-of-plane wobble,
wall and CPU time (the machine may be shared: CPU time is the steadier cost
measure). It also times the adapter against a minimal raw Drake loop on B0
(overhead).

Usage::

    python benchmarks/calibrate_drake.py [--preset accurate,fast] [--set knob=value ...]
        [--only free|pulse] [--duration 20]
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from rockbench.engines.drake_engine import DrakeEngine
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


class _Probe(DrakeEngine):
    """Records where the base ended (drift check of ``_fix_base``)."""

    base_end: float = math.nan

    def _teardown(self) -> None:
        if self._joint is not None:
            self.base_end = float(self._joint.get_translation(self._pc))
        super()._teardown()


@dataclass
class Reference:
    """Reference θ at the output times (column per block), impact times, rest time."""

    theta: np.ndarray
    impacts: np.ndarray
    rest: float


def housner_local(sc: Scenario) -> Reference:
    """Event-driven Housner single block (fallback if the project's reference fails)."""
    rp = sc.blocks[0].rocking(sc.g)
    lam, p, g = rp.lam, rp.p, sc.g
    eta = sc.contact.eta if sc.contact.eta is not None else rp.eta
    exc = sc.excitation
    t_out = sc.output_times()
    T = float(t_out[-1])
    th_out = np.zeros_like(t_out)
    breaks = sorted(b for b in exc.breakpoints if 0 < b < T) + [T]
    thr = g * math.tan(lam)

    def rhs(t: float, y: np.ndarray, s: float) -> list[float]:
        a = s * lam - y[0]
        return [y[1], -p * p * (math.sin(a) + float(exc.acceleration(t)) / g * math.cos(a))]

    t, y = 0.0, np.array([sc.theta0, 0.0])
    s = float(np.sign(y[0]))
    impacts: list[float] = []
    rest = sc.duration
    while t < T - 1e-12:
        tb = min(b for b in breaks if b > t + 1e-12)
        if s == 0:  # at rest: wait for |ü_g| > g tan λ
            ts = np.linspace(t, tb, max(2, int((tb - t) * 20000)))
            idx = np.nonzero(np.abs(exc.acceleration(ts)) > thr)[0]
            if idx.size == 0:
                if exc.end_time <= t:
                    rest = min(rest, t)
                t = tb
                continue
            t, s, y = ts[idx[0]], -float(np.sign(exc.acceleration(ts[idx[0]]))), np.zeros(2)
            continue

        def ev(tt: float, yy: np.ndarray, s: float) -> float:
            return yy[0]

        ev.terminal, ev.direction = True, -s
        sol = solve_ivp(rhs, (t, tb), y, method="DOP853", rtol=1e-11, atol=1e-13, args=(s,),
                        events=ev, dense_output=True, first_step=1e-6)
        m = (t_out >= t) & (t_out <= sol.t[-1])
        if m.any():
            th_out[m] = sol.sol(t_out[m])[0]
        if sol.status == 1:
            t = float(sol.t_events[0][0])
            impacts.append(t)
            v = float(sol.y_events[0][0][1]) * eta
            s, y = (0.0, np.zeros(2)) if abs(v) < 1e-5 * p * lam else (np.sign(v), np.array([0, v]))
        else:
            t, y = float(sol.t[-1]), sol.y[:, -1]
    return Reference(th_out[:, None], np.array(impacts), rest)


def reference(sc: Scenario) -> Reference:
    """The project's Housner reference, or the local one if it is missing or fails."""
    try:
        from rockbench.analytic.housner import single_block_reference

        tr = single_block_reference(sc)
        rest = (tr.extra or {}).get("rest_time") or sc.duration
        return Reference(np.asarray(tr.theta), np.asarray(tr.impacts), float(rest))
    except Exception as exc:  # noqa: BLE001 - a reference under development may fail
        print(f"<!-- project reference failed on {sc.name} ({exc}); local Housner used -->")
        return housner_local(sc)


def zero_crossings(t: np.ndarray, th: np.ndarray) -> np.ndarray:
    """Times where θ changes sign (linear interpolation)."""
    s = np.sign(th)
    i = np.nonzero(s[:-1] * s[1:] < 0)[0]
    return t[i] - th[i] * (t[i + 1] - t[i]) / (th[i + 1] - th[i])


def run_free(sc: Scenario, settings: object) -> dict:
    ref = reference(sc)
    rest = ref.rest
    c0 = time.process_time()
    tr = DrakeEngine().simulate(sc, settings)
    cpu = time.process_time() - c0
    lam = sc.critical_angle
    th = tr.theta[:, 0]
    n = min(th.size, ref.theta.shape[0])
    upto = tr.t[:n] <= rest
    err = float(np.max(np.abs(th[:n] - ref.theta[:n, 0])[upto])) / lam
    zc = zero_crossings(tr.t, th)
    imp = np.asarray(ref.impacts)
    imp_err = [(zc[k] - imp[k]) / imp[k] * 100 if k < zc.size else math.nan for k in range(3)]
    return dict(case=sc.name, status=str(tr.status.value if hasattr(tr.status, "value")
                                         else tr.status),
                err=err, imp=imp_err, wall=tr.wall_time, rest=rest, cpu=cpu,
                wobble=float(np.max(tr.wobble)))


def run_pulse(sc: Scenario, settings: object) -> dict:
    ref = reference(sc)
    eng = _Probe()
    c0 = time.process_time()
    tr = eng.simulate(sc, settings)
    cpu = time.process_time() - c0
    lam = sc.critical_angle
    pk = float(np.max(np.abs(tr.theta[:, 0]))) / lam
    pk_ref = float(np.max(np.abs(ref.theta[:, 0]))) / lam
    u_end = float(sc.excitation.displacement(sc.excitation.end_time))
    return dict(case=sc.name, status=str(tr.status.value if hasattr(tr.status, "value")
                                         else tr.status),
                peak=pk, peak_ref=pk_ref, ratio=pk / pk_ref, wall=tr.wall_time, cpu=cpu,
                drift=eng.base_end - u_end,
                err=float(np.max(np.abs(tr.theta[:, 0] - ref.theta[: tr.t.size, 0]))) / lam)


def overhead(settings: object, duration: float) -> tuple[float, float, float]:
    """Best-of-3 wall times on B0 (1 kHz sampling): simulate(), the plugin's hooks alone
    (build, advance, read poses: no watchdog), and a minimal raw Drake loop (the same
    plant, ``AdvanceTo`` per sample and ``GetPositions``)."""
    sc = free_cases(duration)[0]
    eng = DrakeEngine()
    s = eng.resolve_settings(settings)
    n_out = sc.output_times().size
    best_sim = min(eng.simulate(sc, s).wall_time for _ in range(3))
    best_hooks = best_raw = math.inf
    for _ in range(3):
        t0 = time.perf_counter()
        dt = eng._build(sc, s)
        k = max(1, round(1.0 / (sc.output_rate * dt)))
        out = np.empty((n_out, 1, 7))
        out[0] = eng._read_poses()
        for i in range(1, n_out):
            eng._advance(k)
            out[i] = eng._read_poses()
        eng._teardown()
        best_hooks = min(best_hooks, time.perf_counter() - t0)
        t0 = time.perf_counter()
        eng._build(sc, s)
        sim, plant, pc = eng._sim, eng._plant, eng._pc
        raw = np.empty((n_out, 7))
        raw[0] = plant.GetPositions(pc)
        for i in range(1, n_out):
            sim.AdvanceTo(i * k * dt)
            raw[i] = plant.GetPositions(pc)
        best_raw = min(best_raw, time.perf_counter() - t0)
        eng._teardown()
    return best_sim, best_hooks, best_raw


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--preset", default="accurate,fast")
    ap.add_argument("--set", action="append", default=[], metavar="KNOB=VALUE")
    ap.add_argument("--duration", type=float, default=20.0)
    ap.add_argument("--only", choices=["free", "pulse", "all"], default="all")
    ap.add_argument("--cases", default="", help="comma list of substrings of case names")
    ap.add_argument("--no-overhead", action="store_true")
    args = ap.parse_args(argv)
    overrides = dict(kv.split("=", 1) for kv in args.set)
    keep = [c for c in args.cases.split(",") if c]
    print(f"Drake {DrakeEngine.version()}; overrides {overrides or 'none'}\n")
    for preset in args.preset.split(","):
        s = DrakeEngine.settings(preset, **overrides)
        print(f"### preset `{preset}`: {s.to_dict()}\n")
        if args.only in ("free", "all"):
            print("| case | status | max err/λ | impact 1 (%) | impact 2 (%) | impact 3 (%) "
                  "| max wobble (rad) | ref rest (s) | wall (s) | CPU (s) |")
            print("|---|---|---|---|---|---|---|---|---|---|")
            for sc in free_cases(args.duration):
                if keep and not any(k in sc.name for k in keep):
                    continue
                r = run_free(sc, s)
                imp = " | ".join(f"{x:+.3f}" for x in r["imp"])
                print(f"| {r['case']} | {r['status']} | {r['err']:.5f} | {imp} | "
                      f"{r['wobble']:.1e} | {r['rest']:.2f} | {r['wall']:.2f} | "
                      f"{r['cpu']:.2f} |", flush=True)
            print()
        if args.only in ("pulse", "all"):
            print("| case | status | peak/λ | ref peak/λ | ratio − 1 (%) | max err/λ "
                  "| base drift (m) | wall (s) | CPU (s) |")
            print("|---|---|---|---|---|---|---|---|---|")
            for sc in pulse_cases():
                if keep and not any(k in sc.name for k in keep):
                    continue
                r = run_pulse(sc, s)
                print(f"| {r['case']} | {r['status']} | {r['peak']:.4f} | {r['peak_ref']:.4f} "
                      f"| {100 * (r['ratio'] - 1):+.3f} | {r['err']:.4f} | {r['drift']:.1e} "
                      f"| {r['wall']:.2f} | {r['cpu']:.2f} |", flush=True)
            print()
        if not args.no_overhead:
            a, h, r = overhead(s, args.duration)
            print(f"Overhead on B0 ({args.duration:g} s, best of 3): raw Drake loop {r:.3f} s; "
                  f"plugin hooks {h:.3f} s ({100 * (h / r - 1):+.1f} %); full simulate() "
                  f"{a:.3f} s ({100 * (a / r - 1):+.1f} %, includes the base-class watchdog)\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
