"""``rockbench sweep`` (settings grids) and ``rockbench tune`` (cheapest settings for a target)."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

from rockbench.cli.common import (
    Progress,
    add_engine_arguments,
    add_run_arguments,
    add_settings_arguments,
    check_output_path,
    engine_settings,
    execution_options,
    selected_engines,
    store_path,
)
from rockbench.errors import RockbenchError

__all__ = ["COMMANDS", "configure_sweep", "execute_sweep", "configure_tune", "execute_tune"]

#: The commands of this module: name → one-line help.
COMMANDS = {
    "sweep": "settings grids: accuracy vs cost, stability",
    "tune": "find the cheapest settings meeting a target",
}


def _metric_arguments(p: argparse.ArgumentParser) -> None:
    from rockbench.studies.sweep import ERROR_METRICS

    p.add_argument("--metric", choices=ERROR_METRICS, default="max_error",
                   help="error measure against the analytic reference (default: max_error, "
                        "max |Δθ|/λ)")


def _knob_text(knobs: dict[str, Any]) -> str:
    return " ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}"
                    for k, v in knobs.items()) or "defaults"


def _set_text(engine: str, knobs: dict[str, Any]) -> str:
    return " ".join(f"--set {engine}.{k}={v}" for k, v in knobs.items())


def _progress_line(bar: Progress, text: str) -> None:
    bar.advance(text)
    if not sys.stderr.isatty():
        print(f"[{bar.done}/{bar.total}] {text}", file=sys.stderr, flush=True)


# ---------------------------------------------------------------------- sweep
def configure_sweep(p: argparse.ArgumentParser) -> None:
    """Options of ``rockbench sweep``."""
    p.add_argument("scenario", help="catalog name or scenario .toml file")
    add_engine_arguments(p, default="all")
    p.add_argument("--grid", "-g", action="append", default=[],
                   metavar="ENGINE.KNOB=V1,V2,...",
                   help="values of one knob (repeatable; the grid is their cartesian "
                        "product per engine), e.g. --grid mujoco.timestep=2e-3,1e-3,5e-4")
    p.add_argument("--target", type=float, default=None, metavar="ERR",
                   help="print the cheapest settings whose error is at most ERR")
    _metric_arguments(p)
    p.add_argument("--out", "-o", default=None, metavar="DIR",
                   help="where to write sweep.csv, stability-ENGINE.png and pareto.png "
                        "(default: sweep-SCENARIO)")
    p.add_argument("--resume", action="store_true",
                   help="reuse runs of identical points already in the store")
    add_run_arguments(p, timeout=300.0)
    p.epilog = ("A point's cost is the CPU time of its run (wall time where it is not "
                "measured); wall times grow with --jobs runs in parallel, CPU times less so.")


def execute_sweep(args: argparse.Namespace) -> int:
    """Run ``rockbench sweep``: the grid, its table, stability maps and the Pareto plot."""
    from rockbench.method import slug
    from rockbench.report.sweep_figures import pareto_plot, stability_map
    from rockbench.report.sweep_tables import format_table, write_table
    from rockbench.scenarios import get_scenario
    from rockbench.studies.sweep import cheapest, parse_grid, run_sweep

    execution = execution_options(args)
    if args.target is not None and not args.target > 0:
        raise RockbenchError(f"--target must be > 0, got {args.target:g}")
    scenario = get_scenario(args.scenario)
    engines = selected_engines(args.engine, include_analytic=False)
    base = engine_settings(args, engines)
    grid = parse_grid(args.grid, engines)
    n = sum(math.prod(len(v) for v in g.values()) for g in grid.values())
    # a scenario name is not a path: its slug names the default folder
    out = Path(args.out or f"sweep-{slug(scenario.name)}")
    check_output_path(out / "sweep.csv", "--out")
    db = store_path(args)
    with Progress(n, f"sweep {scenario.name}") as bar:
        result = run_sweep(scenario, grid, base=base, metric=args.metric, db=db,
                           resume=args.resume, execution=execution,
                           on_point=lambda p: _progress_line(
                               bar, f"{p.engine} {_knob_text(p.knobs)}: {p.status.value}"))
    if result.reference_note:
        print(f"note: {result.reference_note}; errors are not available")
    print(format_table(result, args.target), end="")
    written = [write_table(result, out / "sweep.csv")]
    for engine in engines:
        written.append(stability_map(result, engine, out / f"stability-{engine}.png",
                                     args.target))
    written.append(pareto_plot(result, out / "pareto.png", args.target))
    if args.target is not None:
        print(f"cheapest settings with {args.metric} ≤ {args.target:g}:")
        for engine in engines:
            best = cheapest(result.engine_points(engine), args.target, args.metric)
            if best is None:
                print(f"  {engine}: none of the {len(result.engine_points(engine))} points "
                      "meets the target")
            else:
                print(f"  {engine}: {_knob_text(best.knobs)} ({args.metric} "
                      f"{best.error(args.metric):.3g}, {best.cost:.3f} s)  "
                      f"{_set_text(engine, best.knobs)}")
    for w in written:
        print(f"wrote {w}")
    return 0


# ---------------------------------------------------------------------- tune
def configure_tune(p: argparse.ArgumentParser) -> None:
    """Options of ``rockbench tune``."""
    p.add_argument("scenario", help="catalog name or scenario .toml file")
    p.add_argument("--engine", "-e", required=True, metavar="NAME", help="engine to tune")
    add_settings_arguments(p)  # the starting point; --knob names what is searched
    p.add_argument("--target", type=float, required=True, metavar="ERR",
                   help="largest acceptable error (see --metric)")
    _metric_arguments(p)
    p.add_argument("--knob", "-k", action="append", default=None, metavar="NAME",
                   help="knob to tune (repeatable; default: the engine's time step, "
                        "iteration and sub-step knobs)")
    p.add_argument("--budget", type=int, default=30, metavar="N",
                   help="largest number of runs (default: 30)")
    p.add_argument("--out", "-o", default=None, metavar="FILE",
                   help="settings file to write (default: tuned-ENGINE.toml); pass it to "
                        "other commands with --settings FILE")
    add_run_arguments(p, timeout=300.0)
    p.epilog = "exit status: 0 settings found and written, 1 target not reached, 2 bad input"


def execute_tune(args: argparse.Namespace) -> int:
    """Run ``rockbench tune``; writes the settings file when the target is reached."""
    from rockbench.presets import write_settings_file
    from rockbench.scenarios import get_scenario
    from rockbench.studies.tune import tune

    execution = execution_options(args)
    if not args.target > 0:
        raise RockbenchError(f"--target must be > 0, got {args.target:g}")
    if args.budget < 1:
        raise RockbenchError(f"--budget must be >= 1, got {args.budget}")
    scenario = get_scenario(args.scenario)
    engines = selected_engines(args.engine, include_analytic=False)
    if len(engines) != 1:
        raise RockbenchError("tune takes exactly one engine")
    engine = engines[0]
    out = check_output_path(args.out or f"tuned-{engine}.toml", "--out")
    base = engine_settings(args, engines)[engine]
    db = store_path(args)
    with Progress(args.budget, f"tune {engine}") as bar:
        res = tune(scenario, engine, args.target, knobs=args.knob, base=base,
                   metric=args.metric, budget=args.budget, db=db,
                   execution=execution, on_point=lambda p: _progress_line(
                       bar, f"{_knob_text(p.knobs)}: {p.status.value} "
                            f"{args.metric}={p.error(args.metric):.3g}"))
    for p in sorted(res.evaluated, key=lambda p: p.cost):
        e = p.error(args.metric)
        mark = "*" if res.best is p else " "
        print(f" {mark} {_knob_text(p.knobs):40s} {p.status.value:10s} "
              f"{args.metric} {'-' if math.isnan(e) else f'{e:.4g}':>9s}  {p.cost:8.3f} s"
              + ("  drift" if p.drift else ""))
    if res.best is None:
        errs = [p.error(args.metric) for p in res.evaluated if p.as_reference]
        best = min((e for e in errs if math.isfinite(e)), default=math.nan)
        print(f"target {args.metric} ≤ {args.target:g} not reached in {len(res.evaluated)} "
              f"runs (best {best:.3g}); try a larger --budget or other --knob")
        return 1
    settings = {k: v for k, v in res.best.settings.items()}
    write_settings_file(out, {engine: settings}, comment=[
        f"rockbench tune {scenario.name} --engine {engine} --target {args.target:g} "
        f"--metric {args.metric}",
        f"{args.metric} = {res.best.error(args.metric):.4g}, cost (CPU time) "
        f"{res.best.cost:.3f} s ({len(res.evaluated)} runs searched)",
        "use with: rockbench run|compare|matrix|sweep|tune|spectrum ... --settings " + out.name,
    ])
    print(f"cheapest: {_knob_text(res.best.knobs)} ({args.metric} "
          f"{res.best.error(args.metric):.3g}, {res.best.cost:.3f} s)")
    print(f"wrote {out}")
    return 0
