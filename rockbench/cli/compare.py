"""``rockbench compare``: run a suite on engines and the analytic reference, write the report.

Examples::

    rockbench compare --suite paper --engine all --out report
    rockbench compare --suite paper-sensitivity --engine mujoco,pymunk --out sens
    rockbench compare --scenarios free-b2-0.5,my_case.toml --engine pymunk --out r --resume
"""

from __future__ import annotations

import argparse
from pathlib import Path

from rockbench.cli.common import (
    Progress,
    add_engine_arguments,
    add_store_arguments,
    check_output_path,
    command_line,
    engine_settings,
    execution_options,
    selected_engines,
)
from rockbench.errors import RockbenchError, UnknownScenario

__all__ = ["COMMANDS", "configure_compare", "execute_compare", "DEFAULT_PRESETS"]

#: The commands of this module: name → one-line help.
COMMANDS = {"compare": "run a suite on engines and write the report"}

#: Presets run by default: see the --presets help for why both.
DEFAULT_PRESETS = ("accurate", "fast")


def configure_compare(p: argparse.ArgumentParser) -> None:
    """Add the ``compare`` options to ``p``."""
    from rockbench.studies.sensitivity import SUITE

    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument("--suite", metavar="NAME",
                      help="a named suite (see `rockbench scenarios`: paper, paper-free, "
                           f"paper-single-pulse, ..., smoke) or {SUITE} (the paper's Table 2 "
                           "study on B0 only)")
    what.add_argument("--scenarios", metavar="A,B,C",
                      help="comma list of catalog names, suite names and .toml scenario files")
    add_engine_arguments(p, default="all")
    p.add_argument("--presets", default=None, metavar="P1,P2",
                   help="run each engine once per preset (default: "
                        f"{','.join(DEFAULT_PRESETS)}). The fast preset costs roughly a "
                        "third of the accurate one, so it adds about a third to the run time "
                        "and gives every engine two points on the accuracy-versus-speed chart "
                        "(one point per engine cannot show a trade-off). Use --presets accurate "
                        "for tables with one column per engine, like the paper's")
    p.add_argument("--out", "-o", required=True, metavar="DIR",
                   help="report directory (index.html, report.md, results.csv, "
                        "trajectories/, figures/)")
    p.add_argument("--jobs", "-j", type=int, default=None, metavar="N",
                   help="parallel worker processes (default: the usable cores; 1 gives "
                        "uncontended timings)")
    p.add_argument("--timeout", type=float, default=None, metavar="S",
                   help="wall-time limit per run in s (default: 300 s + 60 s per simulated "
                        "second, generous)")
    p.add_argument("--resume", action="store_true",
                   help="reuse finished runs found in the results store (same scenario "
                        "content, engine and library version, resolved settings and code "
                        "version) whose trajectory file is intact; crashed, timed-out and "
                        "torn runs are redone")
    add_store_arguments(p)
    p.add_argument("--sensitivity", action="store_true",
                   help=f"also run the sensitivity study on B0 (the {SUITE} pseudo-suite)")
    p.add_argument("--ensemble", type=int, default=0, metavar="N",
                   help="beyond each case's predictability horizon t*, compare distributions: "
                        "run N perturbed copies of every scenario (input amplitude and initial "
                        "tilt changed by 1e-9..1e-6) on every method and compare the peaks' "
                        "distributions and the overturning probability with the reference's "
                        "(costs N runs per scenario and method; default 0: off)")
    p.add_argument("--horizon-members", type=int, default=None, metavar="M",
                   help="perturbed analytic runs per scenario that measure t* (default "
                        "8; 0: no horizon, errors over the whole run)")
    p.add_argument("--link-figures", action="store_true",
                   help="link the PNGs in figures/ from index.html instead of embedding them")
    p.add_argument("--no-isolate", action="store_true",
                   help="run engines in this process (no crash/hang protection, no timeout)")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar or summary")


def execute_compare(args: argparse.Namespace) -> int:
    """Run the comparison and write the report; 0 when the report is written."""
    from rockbench.engines import engine_class
    from rockbench.method import REFERENCE
    from rockbench.report.compare_report import write_report
    from rockbench.report.options import ReportOptions
    from rockbench.scenarios import get_scenario, get_suite, resolve_scenarios, suites
    from rockbench.studies.compare import CompareOptions, run_comparison
    from rockbench.studies.sensitivity import SUITE

    sensitivity = bool(args.sensitivity)
    if args.suite == SUITE:
        scenarios = []
        sensitivity = True
    elif args.suite:
        if args.suite not in suites():
            raise UnknownScenario(args.suite, [*suites(), SUITE], kind="suite")
        scenarios = [get_scenario(n) for n in get_suite(args.suite)]
    else:
        scenarios = resolve_scenarios(args.scenarios)
        if not scenarios:
            raise RockbenchError("--scenarios names no scenario")
    execution = execution_options(args, isolate=not args.no_isolate)
    if args.preset and args.presets:
        raise RockbenchError("give either --preset or --presets, not both")
    if args.preset:
        presets = [args.preset]
    elif args.presets:
        presets = [p.strip() for p in args.presets.split(",") if p.strip()]
        if not presets:
            raise RockbenchError("--presets names no preset")
    else:
        presets = list(DEFAULT_PRESETS)
    engines = selected_engines(args.engine)
    ns = argparse.Namespace(**{**vars(args), "preset": None})
    settings = engine_settings(ns, engines)
    overrides: dict[str, dict[str, object]] = {}
    for e in engines:
        if e == REFERENCE:
            continue
        ov = dict(settings.get(e, {}))
        if "preset" in ov:
            raise RockbenchError(f"select presets with --presets, not {e}.preset in --set or "
                                 "--settings")
        cls = engine_class(e)
        for p in presets:
            cls.settings(p, **ov)  # unknown preset or bad knob: one line, exit 2
        overrides[e] = ov
    if args.ensemble < 0 or args.ensemble == 1:
        raise RockbenchError(f"--ensemble must be 0 (off) or >= 2, got {args.ensemble}")
    if args.horizon_members is not None and args.horizon_members < 0:
        raise RockbenchError(f"--horizon-members must be >= 0, got {args.horizon_members}")
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise RockbenchError(f"--out {args.out!r} exists and is not a directory")
    check_output_path(out / "results.csv", "--out")
    if not args.no_db:
        check_output_path(args.db, "--db")
    label = args.suite or "custom"
    opts = CompareOptions(
        scenarios=scenarios, engines=[e for e in engines if e != REFERENCE],
        presets=presets, overrides=overrides, timeout=args.timeout,
        execution=execution,
        resume=args.resume, db=None if args.no_db else Path(args.db),
        sensitivity=sensitivity,
        # the Table 2 variations start from the preset asked for, else each engine's own
        sensitivity_from=presets[0] if (args.preset or args.presets) else None,
        suite=label, ensemble=args.ensemble,
        **({} if args.horizon_members is None else {"horizon_members": args.horizon_members}))

    def progress(total: int, description: str) -> Progress:
        return Progress(total, description, quiet=args.quiet)

    result = run_comparison(opts, progress=None if args.quiet else progress)
    files = write_report(result, ReportOptions(out, command=command_line(args),
                                               embed_figures=not args.link_figures))
    if not args.quiet:
        counts: dict[str, int] = {}
        for r in result.results:
            counts[r.status.value] = counts.get(r.status.value, 0) + 1
        summary = ", ".join(f"{n} {s}" for s, n in sorted(counts.items()))
        print(f"{len(result.results)} results ({summary}); {result.ran} run, "
              f"{result.reused} reused; {result.wall_time:.1f} s")
        for f in files:
            print(f"wrote {f}")
        if opts.db is not None:
            print(f"runs recorded in {opts.db} (see `rockbench history`)")
    return 0
