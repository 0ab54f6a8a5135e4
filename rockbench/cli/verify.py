"""``rockbench verify``: which method to trust for these scenarios, and the cheapest that is right.

Examples::

    rockbench verify my-parapet.toml --engine all
    rockbench verify paper-stack-pulse --engine mujoco,pymunk,dem2d --converge all --out v

Prints the verdict in a few lines and writes DIR/index.html, DIR/report.md and
DIR/verdict.csv (:mod:`rockbench.report.verdict_report`); every run and every
rung of the convergence ladders is recorded in (and reused from) the results store.
"""

from __future__ import annotations

import argparse
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

__all__ = ["COMMANDS", "configure_verify", "execute_verify", "parse_tolerances"]

#: The commands of this module: name → one-line help.
COMMANDS = {"verify": "which engine and preset to trust for these scenarios (the verdict)"}


def configure_verify(p: argparse.ArgumentParser) -> None:
    """Add the ``verify`` options to ``p``."""
    from rockbench.studies.convergence import DEFAULT_MAX_LEVEL

    p.add_argument("scenarios", metavar="SCENARIOS",
                   help="comma list of catalog names, suite names and .toml scenario files")
    add_engine_arguments(p, default="all")
    p.add_argument("--presets", default="accurate,fast", metavar="P1,P2",
                   help="the presets judged for every engine (default: accurate,fast)")
    p.add_argument("--converge", choices=("auto", "all", "none"), default="auto",
                   help="where the convergence ladders run: where no closed form covers a "
                        "scenario (auto, the default), on every scenario (all: also shows "
                        "how far the consensus lies from the closed forms), nowhere (none)")
    p.add_argument("--max-level", type=int, default=DEFAULT_MAX_LEVEL, metavar="K",
                   help="the finest rung: K refinements by 2 of each engine's time step "
                        f"(default: {DEFAULT_MAX_LEVEL})")
    p.add_argument("--tolerance", action="append", default=[], metavar="NAME=VALUE",
                   help="a tolerance of the verdict: peak (relative, default 0.05), "
                        "overturn_time (relative, 0.02) or history (λ, 0.05); repeatable")
    p.add_argument("--horizon-members", type=int, default=None, metavar="M",
                   help="perturbed analytic runs per scenario that measure the "
                        "predictability horizon t* (default 8; 0: none)")
    p.add_argument("--out", "-o", default=None, metavar="DIR",
                   help="report directory (default: verify-<first scenario>)")
    p.add_argument("--link-figures", action="store_true",
                   help="link the PNGs from index.html instead of embedding them")
    p.add_argument("--quiet", "-q", action="store_true", help="print the verdict only")
    add_run_arguments(p)


def parse_tolerances(items: list[str]) -> dict[str, float]:
    """``NAME=VALUE`` options as verdict tolerances (one line, exit 2 on a bad one)."""
    from rockbench.studies.verdict import VerdictTolerances

    known = set(VerdictTolerances.__dataclass_fields__)
    out: dict[str, float] = {}
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or name not in known:
            raise RockbenchError(f"--tolerance expects NAME=VALUE with NAME one of "
                                 f"{', '.join(sorted(known))}, got {item!r}")
        try:
            v = float(value)
        except ValueError:
            v = float("nan")
        if not v > 0 or v == float("inf"):
            raise RockbenchError(f"--tolerance {name} must be a number > 0, got {value!r}")
        out[name] = v
    return out


def execute_verify(args: argparse.Namespace) -> int:
    """Verify, print the verdict, write the report; 0 when written."""
    from rockbench.method import REFERENCE, slug
    from rockbench.report.options import ReportOptions
    from rockbench.report.verdict_report import write_verify_report
    from rockbench.scenarios import resolve_scenarios
    from rockbench.studies.verdict import VerdictTolerances
    from rockbench.studies.verify import VerifyOptions, run_verification

    scenarios = resolve_scenarios(args.scenarios)
    if not scenarios:
        raise RockbenchError("verify names no scenario")
    engines = [e for e in selected_engines(args.engine) if e != REFERENCE]
    presets = [p.strip() for p in args.presets.split(",") if p.strip()]
    if not presets:
        raise RockbenchError("--presets names no preset")
    if args.max_level < 1:
        raise RockbenchError(f"--max-level must be >= 1, got {args.max_level}")
    if args.horizon_members is not None and args.horizon_members < 0:
        raise RockbenchError(f"--horizon-members must be >= 0, got {args.horizon_members}")
    settings = engine_settings(argparse.Namespace(**{**vars(args), "preset": None}), engines)
    if any("preset" in settings.get(e, {}) for e in engines):
        raise RockbenchError("select presets with --presets, not engine.preset in --set")
    out = Path(args.out or f"verify-{slug(scenarios[0].name)}")
    check_output_path(out / "verdict.csv", "--out")
    opts = VerifyOptions(
        scenarios=scenarios, engines=engines, presets=presets,
        overrides={e: dict(settings.get(e, {})) for e in engines}, converge=args.converge,
        max_level=args.max_level,
        tolerances=VerdictTolerances(**parse_tolerances(args.tolerance)),
        db=store_path(args), execution=execution_options(args), timeout=None,
        suite=args.scenarios,
        **({} if args.horizon_members is None else {"horizon_members": args.horizon_members}))

    def progress(total: int, description: str) -> Progress:
        return Progress(total, description, quiet=args.quiet)

    result = run_verification(opts, progress=None if args.quiet else progress)
    for line in result.verdict.lines():
        print(line)
    files = write_verify_report(result, ReportOptions(out, command=command_line(args),
                                                      embed_figures=not args.link_figures))
    if not args.quiet:
        print(f"verdict: {result.verdict_cpu:.3g} s CPU of ladders for {result.run_cpu:.3g} s "
              f"of runs judged; {result.wall_time:.1f} s wall")
        for f in files:
            print(f"wrote {f}")
    return 0
