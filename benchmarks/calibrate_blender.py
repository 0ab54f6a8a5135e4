"""Calibrate the Blender (bpy) engine's presets against the Housner reference.

For each preset (``accurate``, ``fast``, ``paper``) it runs the catalog's
free-rocking cases (B0 at 0.5 λ; B1, B2, B3 at 0.2, 0.5, 0.99 λ; 20 s, 1 kHz
output, friction 1, restitution 0) and the six Single #2 sine pulses (4 s), and
prints Markdown tables: max |θ − θ_ref| / λ (until the reference comes to rest),
relative errors of the first three impact times, the largest out-of-plane
wobble, the pulse peak ratio and wall times. It ends with the worst free-rocking
error, the worst impact-time error and the worst pulse-peak deviation of each
preset, the figures of the engine table. Unless ``--no-overhead``, it also times
the plugin's hooks against a raw bpy loop (``scene.frame_set`` and
``matrix_world`` per frame) on B0.

``--bullet-breaking-threshold X`` is a diagnostic, not a Blender setting: before the
runs it writes X into Bullet's process-global ``gContactBreakingThreshold`` (default
0.02, which Bullet scales by each shape's bounding radius: 5 cm on B0) inside the
loaded bpy binary, found through the binary's symbol table (needs binutils' ``nm``).
Blender exposes no such knob; the option measures how much of the remaining error is
Bullet keeping a lifted corner's contact points in the manifold (see the engine's
module docstring).

Usage::

    python benchmarks/calibrate_blender.py [--preset accurate,fast,paper]
        [--set knob=value ...] [--only free|pulse] [--duration 20] [--cases substr,...]
        [--no-overhead] [--bullet-breaking-threshold 1e-4]

The reference is ``rockbench.analytic.housner.single_block_reference``.
"""

from __future__ import annotations

import ctypes
import math
import subprocess
import sys
import time
from typing import Any

import numpy as np

from rockbench.engines.blender_engine import BlenderEngine
from rockbench.scenarios import Scenario

try:
    from benchmarks import calibration as cal
except ImportError:  # run as a file: python benchmarks/calibrate_blender.py
    import calibration as cal

FREE_COLS = [*cal.CASE, cal.col("max err/λ (to rest)", "err", ".4f"),
             *cal.impact_cols("+.3f", "impact {} err %"),
             cal.col("wobble (rad)", lambda r: float(np.max(r["traj"].wobble)), ".1e"), cal.WALL_S]
PULSE_COLS = [cal.col("pulse", "case"), cal.col("status", "status"),
              cal.col("max θ/λ engine", "peak", ".4f"), cal.col("max θ/λ ref", "peak_ref", ".4f"),
              cal.ratio_col("+.2f"), cal.col("base drift (m)", "drift", ".1e"), cal.WALL_S]


def summary(free: list[dict], pulses: list[dict]) -> str:
    """One line: worst free-rocking error, worst impact-time error, worst pulse deviation."""
    parts = []
    if free:
        imp = [abs(x) for r in free for x in r["imp"] if math.isfinite(x)]
        parts.append(f"free rocking worst {max(r['err'] for r in free):.4f} λ, impact times "
                     f"within {max(imp, default=math.nan):.2f} %, wall per 20 s case "
                     f"{np.mean([r['wall'] for r in free]):.2f} s (mean)")
    if pulses:
        dev = [100 * (r["ratio"] - 1) for r in pulses]
        parts.append(f"pulse peaks {min(dev):+.2f} to {max(dev):+.2f} %")
    return "; ".join(parts)


def raw_loop(engine: BlenderEngine, scenario: Scenario, settings: Any, dt: float,
             k: int) -> float:
    """Wall time of a bare bpy loop on the plugin's scene: k frames, then one pose read.

    Timed like :func:`calibration.hooks_loop`: from the scene's build (a factory
    reset and a few operators, a large part of a short run) to its teardown.
    """
    t0 = time.perf_counter()
    cal.build(engine, scenario, settings)
    scene, ob = engine._scene, engine._blocks[0]
    n_out = scenario.output_times().size
    out = np.empty((n_out, 7))
    frame = 1
    for i in range(1, n_out):
        for _ in range(k):
            frame += 1
            scene.frame_set(frame)
        m = ob.matrix_world
        q, p = m.to_quaternion(), m.translation
        out[i] = (p.x, p.y, p.z, q.w, q.x, q.y, q.z)
    engine._teardown()
    return time.perf_counter() - t0


def set_breaking_threshold(value: float) -> float:
    """Write Bullet's ``gContactBreakingThreshold`` inside the loaded bpy; return the old value.

    bpy must be imported. The variable is located by its offset from ``PyInit_bpy`` in
    the binary's symbol table; the old value must be Bullet's default 0.02 as a double
    (Blender builds Bullet in double precision), else nothing is written.
    """
    with open("/proc/self/maps") as maps:
        so = next(line.split()[-1] for line in maps
                  if line.rstrip().endswith("bpy/__init__.so"))
    want = ("PyInit_bpy", "gContactBreakingThreshold")
    syms = {}
    for line in subprocess.run(["nm", so], capture_output=True, text=True,
                               check=True).stdout.splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[2] in want:
            syms[parts[2]] = int(parts[0], 16)
    init = ctypes.cast(ctypes.CDLL(so).PyInit_bpy, ctypes.c_void_p).value
    cell = ctypes.c_double.from_address(init - syms["PyInit_bpy"]
                                        + syms["gContactBreakingThreshold"])
    old = cell.value
    if old != 0.02:
        raise RuntimeError(f"gContactBreakingThreshold reads {old!r}, not Bullet's 0.02: "
                           "not this bpy build's layout, nothing written")
    cell.value = value
    return old


def main(argv: list[str] | None = None) -> int:
    ap = cal.parser(__doc__)
    ap.add_argument("--bullet-breaking-threshold", type=float, default=None, metavar="X",
                    help="diagnostic: Bullet's gContactBreakingThreshold (Blender: 0.02)")
    ap.set_defaults(preset="accurate,fast,paper")
    args = ap.parse_args(argv)
    engine = BlenderEngine()
    ov = cal.overrides(args)
    print(f"blender {engine.version()}; overrides {ov or 'none'}\n")
    if args.bullet_breaking_threshold is not None:
        old = set_breaking_threshold(args.bullet_breaking_threshold)
        print(f"diagnostic: Bullet's gContactBreakingThreshold {old:g} -> "
              f"{args.bullet_breaking_threshold:g} (not a Blender setting)\n")
    for preset in args.preset.split(","):
        s = engine.settings(preset, **ov)
        print(f"### preset `{preset}`: {s.to_dict()} (Δt = {s.dt:.3g} s)\n")
        free = pulses = []
        if args.only in ("free", "all"):
            free = cal.table(FREE_COLS, cal.select(cal.free_cases(args.duration), args.cases),
                             lambda sc, s=s: cal.measure_free(engine, s, sc))
            print()
        if args.only in ("pulse", "all"):
            pulses = cal.table(PULSE_COLS, cal.select(cal.pulse_cases(), args.cases),
                               lambda sc, s=s: cal.measure_pulse(engine, s, sc))
            print()
        print(f"{preset}: {summary(free, pulses)}\n", flush=True)
        if not args.no_overhead:
            cal.print_overhead("bpy", 5.0, cal.overhead(engine, s, 5.0, raw_loop))
    return 0


if __name__ == "__main__":
    sys.exit(main())
