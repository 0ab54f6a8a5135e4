"""``rockbench spectrum``: overturning maps of one-sine / one-cosine pulses, per method.

Example::

    rockbench spectrum --block 1x5 --pulse sine --engine mujoco,bullet --out spectrum-out

writes ``spectrum.png`` (the analytic map with each engine's minimum-overturning
boundary, one panel per engine), ``boundary.csv`` (refined boundary points),
``cells.csv`` (every grid cell) and ``spectrum.json`` (block constants, timings).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from rockbench.cli.common import (
    Progress,
    add_engine_arguments,
    add_parallel_arguments,
    check_output_path,
    engine_settings,
    execution_options,
    selected_engines,
)
from rockbench.errors import RockbenchError

__all__ = ["COMMANDS", "configure_spectrum", "execute_spectrum"]

#: The commands of this module: name → one-line help.
COMMANDS = {"spectrum": "overturning spectra: min overturning acceleration vs pulse frequency"}


def _range(text: str, what: str) -> tuple[float, float]:
    try:
        lo, hi = (float(x) for x in text.split(":"))
    except ValueError:
        raise RockbenchError(f"{what} must be LOW:HIGH, got {text!r}") from None
    return lo, hi


def configure_spectrum(p: argparse.ArgumentParser) -> None:
    """Arguments of ``rockbench spectrum``."""
    p.add_argument("--block", "-b", default="1x5", metavar="SPEC",
                   help="catalog scenario or scenario .toml (its first block and contact), or "
                        "WIDTHxHEIGHT in m (default: 1x5)")
    p.add_argument("--pulse", choices=("sine", "cosine"), default="sine",
                   help="one-sine (a_p sin ω_p t) or one-cosine (a_p cos ω_p t) pulse, one "
                        "period (default: sine)")
    add_engine_arguments(p, default="analytic")
    p.add_argument("--linear", action="store_true",
                   help="linearised Housner model for the analytic map (sin x ≈ x, cos x ≈ 1, "
                        "uplift at g λ)")
    p.add_argument("--eta", type=float, default=None, metavar="ETA",
                   help="analytic velocity ratio at impact (default: the scenario's eta, "
                        "else Housner's 1 - 1.5 sin² λ)")
    p.add_argument("--grid", default="40x60", metavar="NxM",
                   help="analytic grid: N frequencies × M accelerations (default: 40x60)")
    p.add_argument("--engine-grid", default="12x16", metavar="NxM",
                   help="engine grid; every cell is a simulation (default: 12x16)")
    p.add_argument("--freq", default="0.5:10", metavar="LOW:HIGH",
                   help="range of ω_p/p (default: 0.5:10)")
    p.add_argument("--accel", default="0:12", metavar="LOW:HIGH",
                   help="range of a_p/(g λ) (default: 0:12)")
    p.add_argument("--tol", type=float, default=1e-3, metavar="X",
                   help="analytic bisection tolerance in a_p/(g λ) (default: 1e-3)")
    p.add_argument("--refine", type=int, default=3, metavar="N",
                   help="bisection steps on each engine's first boundary (default: 3)")
    p.add_argument("--settle", type=float, default=4.0, metavar="K",
                   help="engine runs last the pulse plus K/p seconds (default: 4)")
    p.add_argument("--out", "-o", default="spectrum-out", metavar="DIR",
                   help="output directory (default: spectrum-out)")
    add_parallel_arguments(p, timeout=300.0)


def execute_spectrum(args: argparse.Namespace) -> int:
    """Run ``rockbench spectrum``; returns the exit status."""
    from rich.console import Console
    from rich.table import Table

    from rockbench.report import spectrum_figures as fig
    from rockbench.studies import spectrum as sp

    execution = execution_options(args)
    if not (args.tol > 0 and math.isfinite(args.tol)):
        raise RockbenchError(f"--tol must be > 0, got {args.tol}")
    if args.eta is not None and not 0.0 <= args.eta <= 1.0:
        raise RockbenchError(f"--eta must be in [0, 1], got {args.eta}")
    if not (args.settle > 0 and math.isfinite(args.settle)):
        raise RockbenchError(f"--settle must be a finite number > 0, got {args.settle}")
    if args.refine < 0:
        raise RockbenchError(f"--refine must be >= 0, got {args.refine}")
    spec = sp.parse_block(args.block)
    w_range, a_range = _range(args.freq, "--freq"), _range(args.accel, "--accel")
    w, a = sp.grid_axes(*sp.parse_grid(args.grid), w_range, a_range)
    ew, ea = sp.grid_axes(*sp.parse_grid(args.engine_grid), w_range, a_range)
    engines = [e for e in selected_engines(args.engine) if e != "analytic"]
    settings = engine_settings(args, engines)
    out = Path(args.out)
    check_output_path(out / "spectrum.png", "--out")  # before the maps are computed
    out.mkdir(parents=True, exist_ok=True)

    with Progress(w.size, "analytic columns") as bar:
        ref = sp.analytic_map(spec, args.pulse, w, a, linear=args.linear, eta=args.eta,
                              tol=args.tol, on_column=lambda c: bar.advance(f"{c.w_ratio:.3g}"),
                              execution=execution)
    maps = [ref]
    eng_maps = []
    for e in engines:
        n_cells = ew.size * int((ea > 0).sum())
        with Progress(n_cells + args.refine * ew.size, f"{e} cells") as bar:
            em = sp.engine_map(e, spec, args.pulse, ew, ea, settings=settings[e],
                               refine=args.refine, settle=args.settle, execution=execution,
                               on_result=lambda job, tr: bar.advance())
        eng_maps.append(em)
        maps.append(em)

    files = [
        fig.spectrum_figure(out / "spectrum.png", ref, eng_maps, spec, args.pulse),
        fig.write_boundary_csv(out / "boundary.csv", maps, spec, args.pulse),
        fig.write_cells_csv(out / "cells.csv", maps),
        fig.write_summary_json(out / "spectrum.json", maps, spec, args.pulse,
                              {"linear": args.linear, "eta_used": args.eta}),
    ]
    rock = spec.rock
    table = Table(title=f"overturning spectrum, one-{args.pulse} pulse, block {spec.name} "
                        f"(λ = {rock.lam:.4f} rad, p = {rock.p:.3f} rad/s)")
    for col in ("method", "grid", "runs", "wall (s)", "min a_p/(gλ)", "at ω_p/p", "note"):
        table.add_column(col)
    for m in maps:
        fb = m.first_boundary()
        if np.isfinite(fb).any():
            j = int(np.nanargmin(fb))
            best, at = f"{fb[j]:.4f}", f"{m.w_ratios[j]:.3g}"
        else:
            best, at = "-", "-"
        note = f"{len(m.notes)} failed runs" if m.notes else ""
        table.add_row(m.method, f"{m.codes.shape[0]}×{m.codes.shape[1]}", str(m.n_runs),
                      f"{m.wall_time:.1f}", best, at, note)
    Console(width=120).print(table)
    for f in files:
        print(f"wrote {f}")
    return 0
