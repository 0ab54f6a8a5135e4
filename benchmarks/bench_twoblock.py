"""Time the two-block analytic reference on the paper's eight stack cases.

Runs every (f, A) pair of Giordano et al. (2025), Section 6, as a one-sine pulse
(4 s) and as a ramped sinusoid (10 s), output at 1000 Hz, and prints a Markdown
table (also written to ``--out`` if given). Not part of the test run::

    python benchmarks/bench_twoblock.py [--out twoblock.md] [--repeat 3]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from rockbench.analytic import critical_angle
from rockbench.analytic.twoblock import two_block_reference
from rockbench.geometry import Geometry
from rockbench.scenarios import Block, Scenario, SinePulse, Sinusoid, stack

CASES = [(3.3, 4), (4.0, 3), (4.0, 4), (4.0, 5), (5.0, 2), (5.0, 3), (5.0, 4), (6.5, 2)]
#: Published analytical max |θ|/λ (Table 9 top block, Table 10 bottom block); None = not given.
PAPER_TOP = {(4.0, 3): 0.022, (4.0, 4): 0.225, (4.0, 5): 0.572, (5.0, 2): 0.022,
             (5.0, 3): 0.247, (5.0, 4): 0.480, (6.5, 2): 0.213}
PAPER_BOTTOM = {(4.0, 3): 0.022, (4.0, 4): 0.114, (4.0, 5): 0.125, (5.0, 2): 0.022,
                (5.0, 3): 0.055, (5.0, 4): 0.061, (6.5, 2): 0.026}


def paper_stack() -> Geometry:
    """Peña et al. (2008) two-block specimen as modelled in the paper."""
    bottom = Block(width=0.20, depth=0.40, height=0.60, density=2670, chamfer=0.005)
    top = Block(width=0.15, depth=0.55, height=0.60, density=2670, chamfer=0.005)
    return stack((bottom, top))


def scenarios() -> list[tuple[str, tuple[float, int], Scenario]]:
    """The 16 benchmark scenarios (pulse and sine for each case)."""
    out = []
    for f, a in CASES:
        amp = a * 1e-3
        out.append(("pulse", (f, a), Scenario(f"stack-pulse-{f}hz-{a}mm", paper_stack(),
                                               excitation=SinePulse(f, amp), duration=4.0,
                                               output_rate=1000.0, g=9.81)))
        out.append(("sine", (f, a), Scenario(f"stack-sine-{f}hz-{a}mm", paper_stack(),
                                              excitation=Sinusoid(f, amp, ramp_cycles=1),
                                              duration=10.0, output_rate=1000.0, g=9.81)))
    return out


def _fmt(x: float | None) -> str:
    return "–" if x is None else f"{x:.3f}"


def main(argv: list[str] | None = None) -> str:
    """Run the benchmark and return the Markdown table."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, help="write the Markdown table to this file")
    ap.add_argument("--repeat", type=int, default=1, help="runs per case (best time kept)")
    args = ap.parse_args(argv)
    lines = [
        "| input | f (Hz) | A (mm) | status | t_over (s) | phases | impacts | wall (s) "
        "| max|θ1|/λ | paper bottom | max|θ2|/λ | paper top |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for kind, key, sc in scenarios():
        best = np.inf
        for _ in range(max(1, args.repeat)):
            t0 = time.perf_counter()
            tr = two_block_reference(sc)
            best = min(best, time.perf_counter() - t0)
        lam = critical_angle(sc.geometry)
        mx = np.nanmax(np.abs(tr.theta), axis=0) / lam
        t_over = tr.extra.get("overturn_time")
        pb = PAPER_BOTTOM.get(key) if kind == "pulse" else None
        pt = PAPER_TOP.get(key) if kind == "pulse" else None
        lines.append(
            f"| {kind} | {key[0]} | {key[1]} | {tr.status} "
            f"| {'–' if t_over is None else f'{t_over:.4f}'} | {tr.extra['n_phases']} "
            f"| {len(tr.impacts)} | {best:.3f} | {mx[0]:.3f} | {_fmt(pb)} | {mx[1]:.3f} "
            f"| {_fmt(pt)} |"
        )
    lam = critical_angle(scenarios()[0][2].geometry)
    text = "\n".join(lines) + f"\n\nλ = critical_angle(geometry) = {lam:.6f} rad " \
        f"({np.degrees(lam):.3f}°)\n"
    print(text)
    if args.out:
        args.out.write_text(text)
    return text


if __name__ == "__main__":
    main()
