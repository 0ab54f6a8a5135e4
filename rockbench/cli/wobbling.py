"""``rockbench wobbling``: which engines keep planar rocking planar (the paper's wobbling case).

Examples::

    rockbench wobbling --engine mujoco,bullet,rapier --out wobbling
    rockbench wobbling --engine all --asymmetry 1e-2 --no-converge --out wob

Runs the scenario (default: Single #2 under the 5 Hz / 6 mm sinusoid) free in 3D with the
base moving exactly along x and with a y component ε times the x one, on the analytic
reference and every engine, at the preset's time step and halved. Writes DIR/index.html,
DIR/report.md, DIR/wobbling.csv and DIR/figures/ (:mod:`rockbench.report.wobbling_report`);
every run is recorded in the results store with its trajectory, so ``--resume`` redraws it.
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

__all__ = ["COMMANDS", "configure_wobbling", "execute_wobbling"]

#: The commands of this module: name → one-line help.
COMMANDS = {"wobbling": "the paper's wobbling case: which engines keep planar rocking planar, "
                        "with and without a tiny out-of-plane perturbation"}


def configure_wobbling(p: argparse.ArgumentParser) -> None:
    """Add the ``wobbling`` options to ``p``."""
    from rockbench.studies.wobbling import DEFAULT_SCENARIO, THRESHOLD

    p.add_argument("--scenario", default=DEFAULT_SCENARIO, metavar="NAME",
                   help=f"a block excited along x: catalog name or .toml file (default: "
                        f"{DEFAULT_SCENARIO})")
    add_engine_arguments(p, default="all")
    p.set_defaults(preset="accurate")  # here a comma list: every engine at each preset
    p.add_argument("--asymmetry", type=float, default=1e-3, metavar="EPS",
                   help="ε: the asymmetric variant's y base motion is ε times the x one "
                        "(> 0; default: 1e-3, an incidence of 0.06°)")
    p.add_argument("--threshold", type=float, default=THRESHOLD, metavar="FRAC",
                   help=f"planar while max |roll| and |twist| stay below FRAC λ (default: "
                        f"{THRESHOLD:g})")
    p.add_argument("--duration", type=float, default=None, metavar="S",
                   help="simulated time (default: the scenario's)")
    p.add_argument("--no-converge", action="store_true",
                   help="do not run each engine again at its time step halved")
    p.add_argument("--out", "-o", default="wobbling", metavar="DIR",
                   help="report directory (default: wobbling)")
    p.add_argument("--resume", action="store_true",
                   help="reuse the runs (and their trajectories) found in the results store")
    add_run_arguments(p)
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar or summary")


def execute_wobbling(args: argparse.Namespace) -> int:
    """Run the study and write the report; 0 when the report is written."""
    from rockbench.report.wobbling_report import write_report
    from rockbench.scenarios import get_scenario
    from rockbench.studies.wobbling import WobblingOptions, asymmetric_scenario, run_wobbling

    if not (math.isfinite(args.asymmetry) and args.asymmetry > 0):
        raise RockbenchError(f"--asymmetry takes ε > 0 (e.g. 1e-3), got {args.asymmetry:g}")
    if not (math.isfinite(args.threshold) and args.threshold > 0):
        raise RockbenchError(f"--threshold takes a fraction of λ > 0, got {args.threshold:g}")
    if args.duration is not None and not (math.isfinite(args.duration) and args.duration > 0):
        raise RockbenchError(f"--duration takes seconds > 0, got {args.duration:g}")
    scenario = get_scenario(args.scenario)
    asymmetric_scenario(scenario, args.asymmetry)  # refuse a scenario it cannot perturb now
    presets = [p.strip() for p in (args.preset or "").split(",") if p.strip()]
    if not presets:
        raise RockbenchError("--preset names no preset")
    engines = [e for e in selected_engines(args.engine) if e != "analytic"]
    settings = engine_settings(argparse.Namespace(**{**vars(args), "preset": None}), engines)
    out = Path(args.out)
    check_output_path(out / "wobbling.csv", "--out")
    opts = WobblingOptions(
        scenario=scenario, engines=engines, presets=presets,
        overrides={e: dict(settings.get(e, {})) for e in engines}, asymmetry=args.asymmetry,
        converge=not args.no_converge, duration=args.duration, threshold=args.threshold,
        execution=execution_options(args), resume=args.resume, db=store_path(args),
        command=command_line(args))

    def progress(total: int, description: str) -> Progress:
        return Progress(total, description, quiet=args.quiet)

    result = run_wobbling(opts, progress=None if args.quiet else progress)
    files = write_report(result, out)
    if not args.quiet:
        for v in result.verdicts:
            r = v.row
            got = (f"max |roll| {r.max_roll:.2g} rad, |twist| {r.max_twist:.2g} rad, "
                   f"{v.convergence}" if r.max_roll is not None and r.max_twist is not None
                   else v.note)
            print(f"{v.method:>22} {v.variant.value:>10}: {v.verdict.value:<22} {got}")
        print(f"{result.ran + result.reused} runs ({result.ran} run, {result.reused} reused); "
              f"{result.wall_time:.1f} s")
        for f in files:
            print(f"wrote {f}")
    return 0
