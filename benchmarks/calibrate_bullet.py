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
        [--only free|pulse] [--duration 20] [--cases substr,...] [--no-overhead]
"""

from __future__ import annotations

import math
import time

import numpy as np
import pybullet as pb

from rockbench.engines.bullet_engine import BulletEngine
from rockbench.scenarios import Scenario, get_scenario

try:
    from benchmarks import calibration as cal
except ImportError:  # run as a file: python benchmarks/calibrate_bullet.py
    import calibration as cal

FREE_COLS = [*cal.CASE, cal.col("max err/λ (to rest)", "err", ".4f"),
             cal.col("max err/λ (20 s)", "err_all", ".4f"), *cal.impact_cols("+.3f"), cal.WALL]
PULSE_COLS = [cal.col("pulse", "case"), cal.col("status", "status"),
              cal.col("max|θ|/λ engine", "peak", ".4f"), cal.col("reference", "peak_ref", ".4f"),
              cal.ratio_col("+.2f"), cal.WALL]


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
            dt = cal.build(eng, sc, eng.resolve_settings(settings))
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
    args = cal.parser(__doc__).parse_args(argv)
    overrides = cal.overrides(args)
    engine = BulletEngine()
    for preset in args.preset.split(","):
        settings = engine.settings(preset, **overrides)
        print(f"\n### bullet `{preset}` ({', '.join(f'{k}={v}' for k, v in overrides.items())})"
              f"  effective dt = {settings.dt:.3g} s\n")
        if args.only != "pulse":
            rows = cal.table(FREE_COLS, cal.select(cal.free_cases(args.duration), args.cases),
                             lambda sc, s=settings: cal.measure_free(engine, s, sc))
            worst = max([0.0, *(r["err"] for r in rows)])
            print(f"\nworst free-rocking error: {worst:.4f} λ")
        if args.only != "free":
            print()
            cal.table(PULSE_COLS, cal.select(cal.pulse_cases(), args.cases),
                      lambda sc, s=settings: cal.measure_pulse(engine, s, sc))
        if not args.no_overhead:
            hooks, raw = overhead(settings, get_scenario("free-b0"))
            print(f"\nadapter overhead on free-b0: hooks {hooks:.2f} s vs raw loop {raw:.2f} s "
                  f"({100 * (hooks / raw - 1):+.1f} %)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
