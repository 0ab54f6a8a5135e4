"""Calibrate the DART engine's presets against Housner's single-block solution.

For each preset (``accurate``, ``fast`` by default) it runs the free-rocking
catalog cases (B0 at 0.5 λ; B1, B2, B3 at 0.2, 0.5, 0.99 λ; 20 s, 1 kHz,
friction 1, restitution 0) and the six Single #2 sine pulses (4 s), and prints
a Markdown table: max |θ − θ_ref|/λ (until the reference comes to rest; NaN if
the run failed), the relative errors of the first three impact times (zero
crossings of the engine's and of the reference's sampled θ), the pulse peak
ratio, and wall time. It also measures the adapter overhead against a minimal
raw dartpy loop on B0.

Usage::

    python benchmarks/calibrate_dart.py [--presets accurate,fast] [--set knob=value ...]
        [--skip-free] [--skip-pulse] [--skip-overhead] [--cases substr,...]
        [--only free|pulse] [--duration 20]
"""

from __future__ import annotations

import math
import time

import numpy as np

from rockbench.engines.dart_engine import DartEngine

try:
    from benchmarks import calibration as cal
except ImportError:  # run as a file: python benchmarks/calibrate_dart.py
    import calibration as cal

FREE_COLS = [*cal.CASE, cal.col("max err/λ", "err", ".4f"), *cal.impact_cols("+.3f"), cal.WALL]
PULSE_COLS = [*cal.CASE, cal.col("peak ref/λ", "peak_ref", ".4f"), cal.col("peak/λ", "peak", ".4f"),
              cal.ratio_col("+.2f", "peak error (%)"), cal.WALL]


def _first3(t: np.ndarray, th: np.ndarray) -> np.ndarray:
    """The first three zero crossings of θ (NaN where there are fewer)."""
    tc = cal.zero_crossings(t, th)[:3]
    return np.concatenate([tc, np.full(3 - tc.size, np.nan)])


def free_row(r: dict) -> dict:
    """DART's variant of the free-rocking row: impact times are compared as zero
    crossings of both sampled θ histories, and a failed run has no error figure."""
    tr, ref = r["traj"], r["ref"]
    tc_ref = _first3(ref.t, ref.theta[:, 0])
    r["imp"] = list((_first3(tr.t, tr.theta[:, 0]) - tc_ref) / tc_ref * 100.0)
    if r["status"] != "ok":
        r["err"] = math.nan
    return r


def raw_loop(eng: DartEngine, sc, s, dt: float, k: int) -> float:
    """A bare dartpy step loop sampling the block's coordinates on the adapter's scene
    (built outside the timing); returns its wall time."""
    raw = DartEngine()
    cal.build(raw, sc, s)
    skel, step = raw._skels[0], raw._world.step
    n_out = sc.output_times().size
    out = np.empty((n_out, 6))
    t0 = time.perf_counter()
    out[0] = skel.getPositions()
    for i in range(1, n_out):
        for _ in range(k):
            step()
        out[i] = skel.getPositions()
    elapsed = time.perf_counter() - t0
    raw._teardown()
    return elapsed


def main(argv: list[str] | None = None) -> int:
    ap = cal.parser(__doc__)
    ap.add_argument("--skip-free", action="store_true")
    ap.add_argument("--skip-pulse", action="store_true")
    args = ap.parse_args(argv)
    if args.skip_free or args.skip_pulse:
        args.only = {(True, False): "pulse", (False, True): "free"}.get(
            (args.skip_free, args.skip_pulse), "none")
    return cal.run(args, DartEngine(), "DART", FREE_COLS, PULSE_COLS, free_row=free_row,
                   overhead=lambda s, dur: cal.print_overhead(
                       "dartpy", dur, cal.overhead(DartEngine(), s, dur, raw_loop)))


if __name__ == "__main__":
    raise SystemExit(main())
