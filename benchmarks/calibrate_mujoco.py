"""Calibrate the MuJoCo engine's presets against the Housner reference.

For each preset (``accurate``, ``fast``) it runs the catalog's free-rocking
cases (B0 at 0.5 λ; B1, B2, B3 at 0.2, 0.5, 0.99 λ; 20 s, 1 kHz output,
friction 1, restitution 0) and the six Single #2 sine pulses (4 s), and prints
Markdown tables: max |θ − θ_ref| / λ (until the reference comes to rest),
relative errors of the first three impact times, peak ratio for the pulses,
how far the base drifted after the excitation ended, and wall time. It also
times the adapter against a minimal raw MuJoCo loop on B0 (overhead).

Usage::

    python benchmarks/calibrate_mujoco.py [--preset accurate,fast] [--set knob=value ...]
        [--only free|pulse] [--duration 20] [--cases substr,...] [--no-overhead]
"""

from __future__ import annotations

import math
import time

import numpy as np

from rockbench.engines.mujoco_engine import MujocoEngine

try:
    from benchmarks import calibration as cal
except ImportError:  # run as a file: python benchmarks/calibrate_mujoco.py
    import calibration as cal

FREE_COLS = [*cal.CASE, cal.col("max err/λ", "err", ".5f"), *cal.impact_cols("+.3f"),
             cal.col("ref rest (s)", "rest", ".2f"), cal.WALL]
PULSE_COLS = [*cal.CASE, cal.col("peak/λ", "peak", ".4f"), cal.col("ref peak/λ", "peak_ref", ".4f"),
              cal.ratio_col("+.3f"), cal.col("max err/λ", "err", ".4f"),
              cal.col("base drift (m)", "drift", ".1e"), cal.WALL]


class _Probe(MujocoEngine):
    """Records where the base ended (drift check of ``_fix_base``)."""

    base_end: float = math.nan

    def _teardown(self) -> None:
        d = self._data
        if d is not None and self.drive.moving:
            self.base_end = float(d.qpos[self._jq])
        super()._teardown()


def raw_loop(eng: MujocoEngine, sc, s, dt: float, k: int) -> float:
    """A minimal raw MuJoCo loop on the adapter's model; returns its wall time."""
    import mujoco

    n_out = sc.output_times().size
    t0 = time.perf_counter()
    m = mujoco.MjModel.from_xml_string(eng.mjcf(sc, s))
    d = mujoco.MjData(m)
    out = np.empty((n_out, 7))
    out[0] = d.qpos[:7]
    for i in range(1, n_out):
        mujoco.mj_step(m, d, k)
        out[i] = d.qpos[:7]
    return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> int:
    args = cal.parser(__doc__).parse_args(argv)
    return cal.run(args, MujocoEngine(), "MuJoCo", FREE_COLS, PULSE_COLS, pulse_engine=_Probe(),
                   overhead=lambda s, dur: cal.print_overhead(
                       "MuJoCo", dur, cal.overhead(MujocoEngine(), s, dur, raw_loop)))


if __name__ == "__main__":
    raise SystemExit(main())
