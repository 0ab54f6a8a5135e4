"""Calibrate the pymunk engine's presets against the Housner reference.

For each preset (``accurate``, ``fast``) it runs the catalog's free-rocking
cases (B0 at 0.5 λ; B1, B2, B3 at 0.2, 0.5, 0.99 λ; 20 s, 1 kHz output,
friction 1, restitution 0) and the six Single #2 sine pulses (4 s), and prints
a Markdown table: max |θ − θ_ref| / λ (until the reference comes to rest),
relative errors of the first three impact times, peak ratio for the pulses and
wall time.

Usage::

    python benchmarks/calibrate_pymunk.py [--preset accurate,fast] [--set knob=value ...]
        [--only free|pulse] [--duration 20] [--cases substr,...]

The reference is ``rockbench.analytic.housner.single_block_reference``.
"""

from __future__ import annotations

import sys

from rockbench.engines.pymunk_engine import PymunkEngine

try:
    from benchmarks import calibration as cal
except ImportError:  # run as a file: python benchmarks/calibrate_pymunk.py
    import calibration as cal

FREE_COLS = [*cal.CASE, cal.col("max err/λ (to rest)", "err", ".5f"),
             *cal.impact_cols("+.4f", "impact {} err %"), cal.WALL_S]
PULSE_COLS = [cal.col("pulse", "case"), cal.col("status", "status"),
              cal.col("max θ/λ engine", "peak", ".5f"), cal.col("max θ/λ ref", "peak_ref", ".5f"),
              cal.ratio_col("+.3f"), cal.WALL_S]


def main(argv: list[str] | None = None) -> int:
    args = cal.parser(__doc__, overhead=False).parse_args(argv)
    return cal.run(args, PymunkEngine(), "pymunk", FREE_COLS, PULSE_COLS, total=True)


if __name__ == "__main__":
    sys.exit(main())
