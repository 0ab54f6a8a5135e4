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
        [--only free|pulse] [--duration 20] [--cases substr,...] [--no-overhead]
"""

from __future__ import annotations

import math
import time

import numpy as np

from rockbench.engines.drake_engine import DrakeEngine

try:
    from benchmarks import calibration as cal
except ImportError:  # run as a file: python benchmarks/calibrate_drake.py
    import calibration as cal

FREE_COLS = [*cal.CASE, cal.col("max err/λ", "err", ".5f"), *cal.impact_cols("+.3f"),
             cal.col("max wobble (rad)", lambda r: np.max(r["traj"].wobble), ".1e"),
             cal.col("ref rest (s)", "rest", ".2f"), cal.WALL, cal.CPU]
PULSE_COLS = [*cal.CASE, cal.col("peak/λ", "peak", ".4f"), cal.col("ref peak/λ", "peak_ref", ".4f"),
              cal.ratio_col("+.3f"), cal.col("max err/λ", "err", ".4f"),
              cal.col("base drift (m)", "drift", ".1e"), cal.WALL, cal.CPU]


class _Probe(DrakeEngine):
    """Records where the base ended (drift check of ``_fix_base``)."""

    base_end: float = math.nan

    def _teardown(self) -> None:
        if self._joint is not None:
            self.base_end = float(self._joint.get_translation(self._pc))
        super()._teardown()


def raw_loop(eng: DrakeEngine, sc, s, dt: float, k: int) -> float:
    """A minimal raw Drake loop on the adapter's plant (``AdvanceTo`` per sample and
    ``GetPositions``); returns its wall time."""
    n_out = sc.output_times().size
    t0 = time.perf_counter()
    cal.build(eng, sc, s)
    sim, plant, pc = eng._sim, eng._plant, eng._pc
    raw = np.empty((n_out, 7))
    raw[0] = plant.GetPositions(pc)
    for i in range(1, n_out):
        sim.AdvanceTo(i * k * dt)
        raw[i] = plant.GetPositions(pc)
    elapsed = time.perf_counter() - t0
    eng._teardown()
    return elapsed


def main(argv: list[str] | None = None) -> int:
    args = cal.parser(__doc__).parse_args(argv)
    return cal.run(args, DrakeEngine(), "Drake", FREE_COLS, PULSE_COLS, pulse_engine=_Probe(),
                   overhead=lambda s, dur: cal.print_overhead(
                       "Drake", dur, cal.overhead(DrakeEngine(), s, dur, raw_loop)))


if __name__ == "__main__":
    raise SystemExit(main())
