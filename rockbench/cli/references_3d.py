"""``rockbench references-3d``: each engine against the 3D references (cylinders, corners).

Examples::

    rockbench references-3d --engine mujoco,bullet,dart --out references-3d
    rockbench references-3d --engine mujoco --preset accurate --duration 10 --no-converge

Runs three scenes with a closed-form answer that no planar case shows (a drum rocking on
its rim, a pillar rocking on a corner along its diagonal, a slender cylinder in steady
precession) on the analytic reference and every engine that builds cylinders or 3D
starts (what it cannot build is reported ``unsupported``), at each preset's time step and
halved. Writes DIR/index.html, DIR/report.md,
DIR/references-3d.csv and DIR/figures/ (:mod:`rockbench.report.references_3d_report`);
every run is recorded in the results store with its trajectory, so ``--resume`` redraws
it.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from rockbench.cli.common import (
    Progress,
    add_engine_arguments,
    add_run_arguments,
    check_output_path,
    command_line,
    engine_settings,
    execution_options,
    selected_engines,
    store_path,
)
from rockbench.errors import RockbenchError

__all__ = ["COMMANDS", "configure_references_3d", "execute_references_3d"]

#: The commands of this module: name → one-line help.
COMMANDS = {"references-3d": "each engine against the 3D references: a drum on its rim, a "
                             "pillar on its corner, a cylinder in steady precession"}


def configure_references_3d(p: argparse.ArgumentParser) -> None:
    """Add the ``references-3d`` options to ``p``."""
    add_engine_arguments(p, default="all")
    p.set_defaults(preset="accurate,fast")  # here a comma list: every engine at each preset
    p.add_argument("--duration", type=float, default=5.0, metavar="S",
                   help="simulated time of the precession (default: 5)")
    p.add_argument("--no-converge", action="store_true",
                   help="do not run each engine again at its time step halved")
    p.add_argument("--out", "-o", default="references-3d", metavar="DIR",
                   help="report directory (default: references-3d)")
    p.add_argument("--resume", action="store_true",
                   help="reuse the runs (and their trajectories) found in the results store")
    add_run_arguments(p)
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar or summary")


def execute_references_3d(args: argparse.Namespace) -> int:
    """Run the study and write the report; 0 when the report is written."""
    from rockbench.engines import engine_class
    from rockbench.report.references_3d_report import write_report
    from rockbench.studies.references_3d import References3DOptions, run_references_3d

    if not (math.isfinite(args.duration) and args.duration > 0):
        raise RockbenchError(f"--duration takes seconds > 0, got {args.duration:g}")
    presets = [p.strip() for p in (args.preset or "").split(",") if p.strip()]
    if not presets:
        raise RockbenchError("--preset names no preset")
    chosen = selected_engines(args.engine)
    # engines that build neither cylinders nor 3D starts would only report "unsupported"
    engines = [e for e in chosen if e != "analytic" and (
        engine_class(e).capabilities.cylinders or engine_class(e).capabilities.start3d)]
    skipped = sorted(set(chosen) - set(engines) - {"analytic"})
    settings = engine_settings(argparse.Namespace(**{**vars(args), "preset": None}), engines)
    out = Path(args.out)
    check_output_path(out / "references-3d.csv", "--out")
    opts = References3DOptions(
        engines=engines, presets=presets, overrides={e: dict(settings.get(e, {}))
                                                     for e in engines},
        converge=not args.no_converge, duration=args.duration,
        execution=execution_options(args), resume=args.resume, db=store_path(args),
        command=command_line(args))

    def progress(total: int, description: str) -> Progress:
        return Progress(total, description, quiet=args.quiet)

    result = run_references_3d(opts, progress=None if args.quiet else progress)
    files = write_report(result, out)
    if not args.quiet:
        if skipped:
            print(f"skipped (no cylinders or 3D starts): {', '.join(skipped)}")
        for r in result.rows:
            if r.method.is_reference:
                print(f"{r.label:>22}: holds the precession's tilt to {r.tilt_drift:.2g} rad "
                      f"(the corner's reference is its closed-form landing time)")
            elif r.rung == 0:
                fin = result.finer(r)
                conv = "" if fin is None else (
                    ", converged" if r.converged(fin) else ", not converged")
                within = {True: "within bounds", False: "outside bounds",
                          None: "failed"}[r.within_bounds()]
                print(f"{r.label:>22}: tilt drift {r.tilt_drift:.2g} rad, corner landing "
                      f"{100 * r.corner_landing:+.3f} %, {within}{conv}")
        print(f"{result.ran + result.reused} runs ({result.ran} run, {result.reused} reused); "
              f"{result.wall_time:.1f} s")
        for f in files:
            print(f"wrote {f}")
    return 0
