"""Calibrate the pybullet engine's presets against the Housner reference.

For each preset it runs the catalog's free-rocking cases (B0 at 0.5 λ; B1, B2, B3
at 0.2, 0.5, 0.99 λ; 20 s, 1 kHz output, friction 1, restitution 0) and the six
Single #2 sine pulses (4 s), and prints Markdown tables: max |θ − θ_ref| / λ until
the reference comes to rest (and over the whole 20 s), relative errors (%) of the
first three impact times, the pulse peak ratio max|θ| / max|θ_ref| and wall times.
It also measures the adapter overhead: the engine's hooks driven like the base
class drives them, against a minimal raw pybullet loop with the same settings.

Usage::

    python benchmarks/calibrate_bullet.py [--preset accurate,fast] [--set knob=value ...]
        [--only free|pulse] [--no-overhead]
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
import pybullet as pb

from rockbench.analytic.housner import single_block_reference
from rockbench.engines.bullet_engine import BulletEngine
from rockbench.scenarios import Scenario, get_scenario

FREE = ["free-b0"] + [f"free-{b}-{t}" for b in ("b1", "b2", "b3") for t in (0.2, 0.5, 0.99)]
PULSES = [f"single-pulse-{f:.1f}hz-{a}mm" for f, a in
          ((3.0, 8), (3.3, 6), (3.3, 8), (5.0, 4), (5.0, 5), (5.0, 6))]


def zero_crossings(t: np.ndarray, th: np.ndarray) -> np.ndarray:
    """Times where θ changes sign (linear interpolation)."""
    s = np.sign(th)
    i = np.nonzero(s[1:] * s[:-1] < 0)[0]
    return t[i] - th[i] * (t[i + 1] - t[i]) / (th[i + 1] - th[i])


def run_free(engine: BulletEngine, sc: Scenario, settings: object) -> dict:
    ref = single_block_reference(sc)
    tr = engine.simulate(sc, settings)
    lam = sc.critical_angle
    th, th_ref = tr.theta[:, 0], ref.theta[: tr.t.size, 0]
    rest = ref.extra.get("rest_time") or sc.duration
    upto = tr.t <= rest
    err = np.abs(th - th_ref) / lam
    zc = zero_crossings(tr.t, th)
    imp = np.asarray(ref.impacts)
    ie = [100 * (zc[k] - imp[k]) / imp[k] if k < min(zc.size, imp.size) else math.nan
          for k in range(3)]
    return dict(name=sc.name, status=str(tr.status), err=float(err[upto].max()),
                err_all=float(err.max()), imp=ie, wall=tr.wall_time)


def run_pulse(engine: BulletEngine, sc: Scenario, settings: object) -> dict:
    ref = single_block_reference(sc)
    tr = engine.simulate(sc, settings)
    lam = sc.critical_angle
    peak, peak_ref = np.max(np.abs(tr.theta[:, 0])), np.max(np.abs(ref.theta[:, 0]))
    return dict(name=sc.name, status=str(tr.status), peak=peak / lam, peak_ref=peak_ref / lam,
                ratio=peak / peak_ref, wall=tr.wall_time)


def overhead(settings: object, sc: Scenario, repeat: int = 3) -> tuple[float, float]:
    """Best-of wall times of the engine hooks and of a raw pybullet loop on the same scene.

    Both start from the scene built by ``_build`` (identical physics); the hooks run
    the base class's free-motion loop without its watchdog, the raw loop calls
    ``stepSimulation`` and ``getBasePositionAndOrientation`` directly.
    """
    n_out = sc.output_times().size
    best_hooks = best_raw = math.inf
    for _ in range(repeat):
        for raw in (False, True):
            eng = BulletEngine()
            dt = eng._build(sc, eng.resolve_settings(settings))
            k = max(1, round(1.0 / (sc.output_rate * dt)))
            poses = np.full((n_out, sc.n_blocks, 7), np.nan)
            t0 = time.perf_counter()
            if raw:
                kw, body = eng._kw, eng._bodies[0]
                pb.setPhysicsEngineParameter(fixedTimeStep=k * dt, numSubSteps=k, **kw)
                for i in range(1, n_out):
                    pb.stepSimulation(**kw)
                    p, q = pb.getBasePositionAndOrientation(body, **kw)
                    poses[i, 0, :3] = p
                    poses[i, 0, 3:] = q
                best_raw = min(best_raw, time.perf_counter() - t0)
            else:
                for i in range(1, n_out):
                    eng._advance(k)
                    poses[i] = eng._read_poses()
                best_hooks = min(best_hooks, time.perf_counter() - t0)
            eng._teardown()
    return best_hooks, best_raw


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--preset", default="accurate,fast")
    ap.add_argument("--set", action="append", default=[], metavar="KNOB=VALUE")
    ap.add_argument("--only", choices=("free", "pulse"))
    ap.add_argument("--no-overhead", action="store_true")
    args = ap.parse_args(argv)
    overrides = dict(kv.split("=", 1) for kv in args.set)
    engine = BulletEngine()
    for preset in args.preset.split(","):
        settings = engine.settings(preset, **overrides)
        print(f"\n### bullet `{preset}` ({', '.join(f'{k}={v}' for k, v in overrides.items())})"
              f"  effective dt = {settings.dt:.3g} s\n")
        if args.only != "pulse":
            print("| case | status | max err/λ (to rest) | max err/λ (20 s) | "
                  "impact 1 (%) | impact 2 (%) | impact 3 (%) | wall (s) |")
            print("|---|---|---|---|---|---|---|---|")
            worst = 0.0
            for name in FREE:
                r = run_free(engine, get_scenario(name), settings)
                worst = max(worst, r["err"])
                i1, i2, i3 = r["imp"]
                print(f"| {r['name']} | {r['status']} | {r['err']:.4f} | {r['err_all']:.4f} | "
                      f"{i1:+.3f} | {i2:+.3f} | {i3:+.3f} | {r['wall']:.2f} |", flush=True)
            print(f"\nworst free-rocking error: {worst:.4f} λ")
        if args.only != "free":
            print("\n| pulse | status | max|θ|/λ engine | reference | ratio − 1 (%) | wall (s) |")
            print("|---|---|---|---|---|---|")
            for name in PULSES:
                r = run_pulse(engine, get_scenario(name), settings)
                print(f"| {r['name']} | {r['status']} | {r['peak']:.4f} | {r['peak_ref']:.4f} | "
                      f"{100 * (r['ratio'] - 1):+.2f} | {r['wall']:.2f} |", flush=True)
        if not args.no_overhead:
            hooks, raw = overhead(settings, get_scenario("free-b0"))
            print(f"\nadapter overhead on free-b0: hooks {hooks:.2f} s vs raw loop {raw:.2f} s "
                  f"({100 * (hooks / raw - 1):+.1f} %)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
