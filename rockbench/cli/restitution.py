"""``rockbench restitution``: the coefficient of restitution each engine and preset produces.

Examples::

    rockbench restitution --engine all --out restitution
    rockbench restitution --engine bullet,pymunk --restitution 0,0.3,0.6 --out eta

Writes DIR/index.html, DIR/report.md, DIR/restitution.csv (the η of every impact) and
DIR/figures/restitution.png (:mod:`rockbench.report.restitution_report`); every run is
recorded in the results store with its trajectory, so ``--resume`` measures it again.
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

__all__ = ["COMMANDS", "configure_restitution", "execute_restitution"]

#: The commands of this module: name → one-line help.
COMMANDS = {"restitution": "η asked, obtained, measured: each engine's coefficient of "
                           "restitution in free rocking"}


def configure_restitution(p: argparse.ArgumentParser) -> None:
    """Add the ``restitution`` options to ``p``."""
    from rockbench.studies.restitution import DEFAULT_SCENARIOS

    p.add_argument("--scenarios", default=",".join(DEFAULT_SCENARIOS), metavar="A,B",
                   help="free-rocking single blocks: catalog names, suites or .toml files "
                        f"(default: {','.join(DEFAULT_SCENARIOS)})")
    add_engine_arguments(p, default="all")
    p.add_argument("--presets", default="accurate,fast", metavar="P1,P2",
                   help="the presets of every engine (default: accurate,fast)")
    p.add_argument("--restitution", default="0", metavar="E1,E2",
                   help="the engines' bounce coefficients e to run (contact.restitution, in "
                        "[0, 1]; default: 0, a plastic impact, which Housner's η models)")
    p.add_argument("--impacts", type=int, default=5, metavar="N",
                   help="impacts measured per run, at most (default: 5)")
    p.add_argument("--out", "-o", default="restitution", metavar="DIR",
                   help="report directory (default: restitution)")
    p.add_argument("--resume", action="store_true",
                   help="reuse the runs (and their trajectories) found in the results store")
    add_run_arguments(p)
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar or summary")


def execute_restitution(args: argparse.Namespace) -> int:
    """Run the study and write the report; 0 when the report is written."""
    from rockbench.report.restitution_report import write_report
    from rockbench.scenarios import resolve_scenarios
    from rockbench.studies.restitution import RestitutionOptions, run_restitution

    scenarios = resolve_scenarios(args.scenarios)
    engines = [e for e in selected_engines(args.engine) if e != "analytic"]
    settings = engine_settings(argparse.Namespace(**{**vars(args), "preset": None}), engines)
    if any("preset" in s for s in settings.values()):
        raise RockbenchError("select the presets with --presets, not ENGINE.preset")
    presets = [p.strip() for p in args.presets.split(",") if p.strip()]
    if not presets:
        raise RockbenchError("--presets names no preset")
    try:
        bounce = tuple(float(v) for v in args.restitution.split(",") if v.strip())
    except ValueError:
        raise RockbenchError(f"--restitution takes numbers in [0, 1] 'E1,E2', got "
                             f"{args.restitution!r}") from None
    out = Path(args.out)
    check_output_path(out / "restitution.csv", "--out")
    opts = RestitutionOptions(
        scenarios=scenarios, engines=engines, presets=presets,
        overrides={e: dict(settings.get(e, {})) for e in engines}, restitution=bounce,
        impacts=args.impacts, execution=execution_options(args), resume=args.resume,
        db=store_path(args), command=command_line(args))

    def progress(total: int, description: str) -> Progress:
        return Progress(total, description, quiet=args.quiet)

    result = run_restitution(opts, progress=None if args.quiet else progress)
    files = write_report(result, out)
    if not args.quiet:
        for r in result.rows:
            got = (f"η = {r.mean:.4f} ({r.ratio:.4f} of Housner's {r.housner:.4f}) over "
                   f"{len(r.impacts.eta)} impacts" if r.impacts else r.note)
            print(f"{r.scenario:>14} {r.method:>20} e={r.restitution:<4g} {got}")
        print(f"{result.ran + result.reused} runs ({result.ran} run, {result.reused} reused); "
              f"{result.wall_time:.1f} s")
        for f in files:
            print(f"wrote {f}")
    return 0
