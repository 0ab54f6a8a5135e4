"""``rockbench calibrate``: search an engine's declared knobs on the calibration cases.

Examples::

    rockbench calibrate pymunk
    rockbench calibrate mujoco --cases free --preset fast --levels 1 --knobs timestep
    rockbench calibrate pymunk --from-store          # the report again, nothing runs

Prints the table of settings and writes DIR/index.html, DIR/report.md,
DIR/calibration.csv and DIR/figures/calibration.png
(:mod:`rockbench.report.calibration_report`); every run is recorded in (and
reused from) the results store, so a second calibration on the same store runs
nothing, and ``--from-store`` makes the report from the store alone.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from rockbench.cli.common import (
    Progress,
    add_run_arguments,
    check_output_path,
    command_line,
    execution_options,
    store_path,
)
from rockbench.errors import RockbenchError

__all__ = ["COMMANDS", "configure_calibrate", "execute_calibrate", "parse_tolerances"]

#: The commands of this module: name → one-line help.
COMMANDS = {"calibrate": "search an engine's knobs on the calibration cases (error against "
                         "cost, the cheapest setting meeting the tolerances)"}


def configure_calibrate(p: argparse.ArgumentParser) -> None:
    """Add the ``calibrate`` options to ``p``."""
    from rockbench.studies.calibration import ERROR_METRICS
    from rockbench.studies.calibration_plan import DEFAULT_LEVELS, MAX_LEVELS

    p.add_argument("engine", metavar="ENGINE", help="the engine to calibrate (see "
                                                    "`rockbench engines`)")
    p.add_argument("--cases", default="all", metavar="free|pulses|stack|all|NAME,...",
                   help="the calibration cases: the ten 20 s free-rocking cases (free), the "
                        "six Single #2 one-sine pulses (pulses), both (all, the default), the "
                        "paper's two-block stack (stack: 8 pulses, 2 well-posed sinusoids), or "
                        "a comma list of groups, suites and catalog scenarios")
    p.add_argument("--preset", default="accurate", metavar="P",
                   help="the preset the search starts from (default: accurate)")
    p.add_argument("--levels", type=int, default=DEFAULT_LEVELS, metavar="N",
                   help=f"rungs on either side of each knob's preset value, each a factor of 2 "
                        f"(0 to {MAX_LEVELS}; default: {DEFAULT_LEVELS})")
    p.add_argument("--knobs", default=None, metavar="K,...",
                   help="search only these of the engine's declared knobs (default: all)")
    p.add_argument("--no-presets", action="store_true",
                   help="leave out the engine's other named presets")
    p.add_argument("--duration", type=float, default=None, metavar="S",
                   help="run every case for S seconds instead (a quick look: other cases, "
                        "with other references)")
    p.add_argument("--tolerance", action="append", default=[], metavar="NAME=VALUE",
                   help="a tolerance of the cheapest setting: max_error (λ, default 0.005), "
                        "peak_error (relative, 0.02) or impact_time_error (relative, 0.005); "
                        "VALUE none: not judged; repeatable")
    p.add_argument("--metric", choices=ERROR_METRICS, default="max_error",
                   help="the error of the Pareto front and the chart (default: max_error)")
    p.add_argument("--from-store", action="store_true",
                   help="make the report from the runs in the results store (--db) only: "
                        "no engine runs")
    p.add_argument("--out", "-o", default=None, metavar="DIR",
                   help="report directory (default: calibrate-ENGINE)")
    p.add_argument("--link-figures", action="store_true",
                   help="link the PNG from index.html instead of embedding it")
    p.add_argument("--quiet", "-q", action="store_true", help="print the table only")
    add_run_arguments(p)


def parse_tolerances(items: list[str]) -> dict[str, float | None]:
    """``NAME=VALUE`` options as calibration tolerances (one line, exit 2 on a bad one).

    Raises
    ------
    RockbenchError
        An unknown name, or a value that is neither ``none`` nor a number > 0.
    """
    from rockbench.studies.calibration import ERROR_METRICS

    out: dict[str, float | None] = {}
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or name not in ERROR_METRICS:
            raise RockbenchError(f"--tolerance expects NAME=VALUE with NAME one of "
                                 f"{', '.join(ERROR_METRICS)}, got {item!r}")
        if value.strip().lower() == "none":
            out[name] = None
            continue
        try:
            v = float(value)
        except ValueError:
            v = float("nan")
        if not v > 0 or v == float("inf"):
            raise RockbenchError(f"--tolerance {name} expects a number > 0 or none, "
                                 f"got {value!r}")
        out[name] = v
    return out


def execute_calibrate(args: argparse.Namespace) -> int:
    """Calibrate (or read the calibration from the store), print the table, write the
    report; 0 when written."""
    from rockbench.method import slug
    from rockbench.report.calibration_report import format_calibration, write_calibration_report
    from rockbench.report.options import ReportOptions
    from rockbench.studies.calibration import (
        Tolerances,
        calibration_cases,
        max_timestep,
        run_plan,
        stored_calibration,
    )
    from rockbench.studies.calibration_plan import plan_search

    scenarios = calibration_cases(args.cases, args.duration)
    knobs = None
    if args.knobs is not None:
        knobs = [k.strip() for k in args.knobs.split(",") if k.strip()]
        if not knobs:
            raise RockbenchError("--knobs names no knob")
    plan = plan_search(args.engine, preset=args.preset, knobs=knobs, levels=args.levels,
                       presets=not args.no_presets, max_timestep=max_timestep(scenarios))
    tolerances = Tolerances(**parse_tolerances(args.tolerance))
    out = Path(args.out or f"calibrate-{slug(plan.engine)}")
    check_output_path(out / "calibration.csv", "--out")
    if args.from_store:
        if args.no_db:
            raise RockbenchError("--from-store reads the results store: drop --no-db")
        cal = stored_calibration(plan, scenarios, Path(args.db), tolerances=tolerances,
                                 metric=args.metric)
        if not cal.reused:
            raise RockbenchError(f"--from-store: {args.db} holds no run of this calibration "
                                 f"of {plan.engine}; run it without --from-store first")
    else:
        execution = execution_options(args)
        db = store_path(args)

        def progress(total: int, description: str) -> Progress:
            return Progress(total, description, quiet=args.quiet)

        cal = run_plan(plan, scenarios, tolerances=tolerances, metric=args.metric, db=db,
                       execution=execution, progress=None if args.quiet else progress)
    print(format_calibration(cal), end="")
    files = write_calibration_report(cal, ReportOptions(out, command=command_line(args),
                                                        embed_figures=not args.link_figures))
    if not args.quiet:
        missing = sum(len(r.missing) for r in cal.results)
        if args.from_store:
            print(f"from the store: {cal.reused} runs made by {', '.join(cal.made_by)}"
                  + (f"; {missing} not in the store" if missing else ""))
        else:
            print(f"calibration: {cal.ran} runs now, {cal.reused} reused from the store; "
                  f"{cal.wall_time:.1f} s wall")
        for f in files:
            print(f"wrote {f}")
    return 0
