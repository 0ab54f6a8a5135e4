"""Calibrate the opensees engine's presets against the Housner reference.

The knob that sets the energy an impact removes is the contact dashpots'
damping ratio ζ (``damping_ratio``). ``--search`` documents how it was chosen:
for each ζ of a grid it runs the four free-rocking blocks released from 0.5 λ
(B0–B3) up to just past their third impact and prints the worst of
max |θ − θ_ref| / λ and of the three impact-time errors; the preset takes the
ζ with the smallest worst error. The usual tables then measure each preset on
the catalog's free-rocking cases (B0 at 0.5 λ; B1, B2, B3 at 0.2, 0.5, 0.99 λ;
20 s, 1 kHz output, friction 1, restitution 0), the six Single #2 one-sine
pulses (4 s) and, with ``--stacks``, the paper's eight two-block pulses
against the project's two-block analytic model. Each row also counts the steps
taken with a fixed number of Newton iterations (see the engine's docstring).
The overhead line compares ``simulate()`` and the plugin's hooks with a raw
loop of ``analyze``/``nodeDisp`` calls on the same model (B0, free).

Usage::

    python benchmarks/calibrate_opensees.py [--preset accurate,fast] [--set knob=value ...]
        [--only free|pulse] [--duration 20] [--cases substr,...]
        [--search 1.0,1.3,1.6] [--stacks] [--no-overhead]

The reference is ``rockbench.analytic.housner.single_block_reference``.
"""

from __future__ import annotations

import sys
import time
from typing import Any

import numpy as np

from rockbench.analytic import critical_angle
from rockbench.analytic.housner import single_block_reference
from rockbench.engines.opensees_engine import OpenseesEngine
from rockbench.scenarios import Scenario, get_scenario

try:
    from benchmarks import calibration as cal
except ImportError:  # run as a file: python benchmarks/calibrate_opensees.py
    import calibration as cal

#: The free-rocking cases of the ζ search (each block from 0.5 λ).
SEARCH_CASES = ["free-b0", "free-b1-0.5", "free-b2-0.5", "free-b3-0.5"]

ENGINE = OpenseesEngine()
# a row is printed as soon as it is measured: the engine's count is that run's
UNCONVERGED = cal.col("fixed-iteration steps", lambda r: ENGINE.unconverged_steps, "d")
FREE_COLS = [*cal.CASE, cal.col("max err/λ (to rest)", "err", ".4f"),
             *cal.impact_cols(("+.3f", "+.3f", "+.3f"), "impact {} err %"), UNCONVERGED,
             cal.WALL_S, cal.CPU]
PULSE_COLS = [cal.col("pulse", "case"), cal.col("status", "status"),
              cal.col("max θ/λ engine", "peak", ".4f"), cal.col("max θ/λ ref", "peak_ref", ".4f"),
              cal.ratio_col("+.2f"), UNCONVERGED, cal.WALL_S, cal.CPU]


def search(knob: str, values: list[float], overrides: dict, preset: str,
           duration: float | None) -> None:
    """A grid of one knob on B0–B3: up to their third impact, or over ``duration`` s
    (errors until the reference comes to rest; module docstring)."""
    span = "third impact" if duration is None else f"{duration:g} s"
    print(f"### {knob} search up to the {span}, preset `{preset}`, overrides "
          f"{overrides or 'none'}\n")
    print(f"| {knob} | " + " | ".join(f"{c}: err/λ, impacts %" for c in SEARCH_CASES)
          + " | worst | CPU s |")
    print("|---|" + "---|" * (len(SEARCH_CASES) + 2))
    bound = 0.005 if duration is None else 0.01
    for value in values:
        s = OpenseesEngine.settings(preset, **overrides).replace(**{knob: value})
        cells, worst, cpu = [], 0.0, 0.0
        for name in SEARCH_CASES:
            sc0 = get_scenario(name)
            ref = single_block_reference(sc0)
            imp = np.asarray(ref.impacts)[:3]
            sc = sc0.replace(duration=float(imp[-1]) + 0.05 if duration is None else duration)
            r = cal.measure_free(ENGINE, s, sc)
            cpu += r["cpu"]
            worst = max(worst, r["err"] / bound, *(abs(x) / 0.5 for x in r["imp"]))
            cells.append(f"{r['err']:.4f}, " + "/".join(f"{x:+.2f}" for x in r["imp"]))
        # worst: the largest error as a fraction of its bound (0.005 λ to the third
        # impact or 0.01 λ over the run, 0.5 % on the impact times)
        print(f"| {value:g} | " + " | ".join(cells) + f" | {worst:.2f} | {cpu:.1f} |",
              flush=True)
    print()


def raw_loop(eng: OpenseesEngine, sc: Scenario, s: Any, dt: float, k: int) -> float:
    """A minimal raw OpenSees loop on the adapter's model (``analyze`` k steps, read the
    centroid node, per output sample); returns its wall time, model build included."""
    ops = OpenseesEngine.library("openseespy.opensees")
    n_out = sc.output_times().size
    t0 = time.perf_counter()
    cal.build(eng, sc, s)
    tag = eng._centroids[0]
    out = np.empty((n_out, 3))
    out[0] = ops.nodeDisp(tag)
    for i in range(1, n_out):
        ops.analyze(k, dt)
        out[i] = ops.nodeDisp(tag)
    elapsed = time.perf_counter() - t0
    eng._teardown()
    return elapsed


def run_stacks(settings: object) -> None:
    """The paper's two-block pulses: peaks of both blocks / λ against the analytic model."""
    from rockbench.analytic import reference
    from rockbench.scenarios.catalog import get_suite

    print("| stack pulse | status | top engine | top analytic | bottom engine "
          "| bottom analytic | wall s |")
    print("|---|---|---|---|---|---|---|")
    for name in get_suite("paper-stack-pulse"):
        sc = get_scenario(name)
        lam = critical_angle(sc.geometry)
        tr = ENGINE.simulate(sc, settings)
        pk = np.max(np.abs(tr.theta), axis=0) / lam
        ref = reference(sc)
        rk = np.max(np.abs(ref.theta), axis=0) / lam
        note = "" if str(ref.status) == "ok" else f" ({ref.status})"
        print(f"| {name} | {tr.status} | {pk[1]:.3f} | {rk[1]:.3f}{note} | {pk[0]:.3f} | "
              f"{rk[0]:.3f} | {tr.wall_time:.1f} |", flush=True)
    print()


def main(argv: list[str] | None = None) -> int:
    ap = cal.parser(__doc__)
    ap.add_argument("--search", default="", help="comma list of values to search (B0–B3)")
    ap.add_argument("--knob", default="damping_ratio", help="the knob --search varies")
    ap.add_argument("--search-duration", type=float, default=None,
                    help="search over this many seconds (default: to the third impact)")
    ap.add_argument("--stacks", action="store_true", help="also the two-block pulses")
    args = ap.parse_args(argv)
    if args.search:
        for preset in args.preset.split(","):
            search(args.knob, [float(z) for z in args.search.split(",")], cal.overrides(args),
                   preset, args.search_duration)
        return 0
    code = cal.run(args, ENGINE, "opensees", FREE_COLS, PULSE_COLS, total=True,
                   overhead=lambda s, dur: cal.print_overhead(
                       "OpenSees", dur, cal.overhead(OpenseesEngine(), s, dur, raw_loop)))
    if args.stacks:
        for preset in args.preset.split(","):
            print(f"### two-block pulses, preset `{preset}`\n")
            run_stacks(OpenseesEngine.settings(preset, **cal.overrides(args)))
    return code


if __name__ == "__main__":
    sys.exit(main())
