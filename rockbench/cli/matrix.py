"""``rockbench matrix`` (pass/fail grid) and ``rockbench history`` (a cell across runs)."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from rockbench.cli.common import (
    Progress,
    add_engine_arguments,
    add_run_arguments,
    check_output_path,
    engine_settings,
    execution_options,
    selected_engines,
    store_path,
)
from rockbench.errors import RockbenchError

__all__ = ["COMMANDS", "configure_matrix", "execute_matrix", "configure_history",
           "execute_history"]

#: The commands of this module: name → one-line help.
COMMANDS = {
    "matrix": "engines × scenarios pass/fail matrix",
    "history": "metrics of a cell across stored runs",
}


# ---------------------------------------------------------------------- matrix
def _scenarios(spec: str) -> list[Any]:
    """Scenarios of ``--suite``: a suite name (with a "did you mean"), or a comma list."""
    from pathlib import Path

    from rockbench.scenarios import catalog, get_suite, resolve_scenarios

    if "," not in spec and spec not in catalog() and not Path(spec).exists():
        get_suite(spec)  # raises UnknownScenario with suite suggestions
    return resolve_scenarios(spec)


def configure_matrix(p: argparse.ArgumentParser) -> None:
    """Options of ``rockbench matrix``."""
    p.add_argument("--suite", "-s", required=True, metavar="NAME",
                   help="suite name (see `rockbench scenarios`), or a comma list of scenarios, "
                        "suites and scenario files")
    add_engine_arguments(p, default="all")
    p.add_argument("--tolerances", "-t", required=True, metavar="FILE",
                   help="tolerance file (TOML); 'smoke' or 'paper' selects the shipped one")
    p.add_argument("--baseline", default=None, metavar="FILE",
                   help="JSON of earlier results: cells that got worse beyond the tolerance "
                        "file's [regression] margins fail")
    p.add_argument("--write-baseline", default=None, metavar="FILE",
                   help="write this matrix's results as a baseline JSON file")
    p.add_argument("--junit", default=None, metavar="FILE", help="write JUnit XML")
    p.add_argument("--resume", action="store_true",
                   help="reuse runs already in the store (same scenario content, engine "
                        "version, settings and rockbench version)")
    p.add_argument("--horizon-members", type=int, default=None, metavar="M",
                   help="perturbed analytic runs per scenario that measure the predictability "
                        "horizon t* the checked errors stop at (default 8; 0: errors over "
                        "the whole run)")
    add_run_arguments(p, timeout=600.0)
    p.epilog = "exit status: 0 all cells pass, 1 a cell failed or regressed, 2 bad input"


def execute_matrix(args: argparse.Namespace) -> int:
    """Run ``rockbench matrix``; returns 0, 1 (failures/regressions) or 2 (bad input)."""
    from rockbench.studies.baseline import load_baseline
    from rockbench.studies.matrix import run_matrix
    from rockbench.studies.tolerances import load_tolerances

    execution = execution_options(args)
    if args.horizon_members is not None and args.horizon_members < 0:
        raise RockbenchError(f"--horizon-members must be >= 0, got {args.horizon_members}")
    horizon = ({} if args.horizon_members is None
               else {"horizon_members": args.horizon_members})
    for flag, path in (("--junit", args.junit), ("--write-baseline", args.write_baseline)):
        if path:  # before the matrix runs, not after
            check_output_path(path, flag)
    scenarios = _scenarios(args.suite)
    if not scenarios:
        raise RockbenchError(f"--suite {args.suite!r} selects no scenario")
    engines = selected_engines(args.engine, include_analytic=False)
    settings = engine_settings(args, engines)
    tolerances = load_tolerances(args.tolerances)
    baseline = load_baseline(args.baseline) if args.baseline else None
    if tolerances.suite and tolerances.suite != args.suite:
        print(f"rockbench: note: {tolerances.source} was calibrated for suite "
              f"{tolerances.suite!r}, not {args.suite!r}", file=sys.stderr)
    db = store_path(args)
    with Progress(len(scenarios) * len(engines), "matrix") as bar:
        def on_cell(cell: Any) -> None:
            bar.advance(f"{cell.engine} × {cell.scenario}")
            if not sys.stderr.isatty():
                print(f"[{bar.done}/{bar.total}] {cell.engine} × {cell.scenario}: "
                      f"{cell.status.value}" + (" (stored)" if cell.reused else ""),
                      file=sys.stderr, flush=True)

        result = run_matrix(scenarios, engines, tolerances, settings=settings,
                            suite=args.suite, db=db, baseline=baseline,
                            resume=args.resume, execution=execution, on_cell=on_cell,
                            **horizon)
    _show(result)
    if args.junit:
        from rockbench.report.junit import write_junit

        print(f"wrote {write_junit(result, args.junit)}")
    if args.write_baseline:
        from rockbench.studies.baseline import baseline_data, write_baseline

        data = baseline_data({c.key: (c.status, c.settings, c.metrics)
                              for c in result.cells.values()}, result.suite)
        print(f"wrote {write_baseline(data, args.write_baseline)}")
    if db is not None:
        print(f"results appended to {db}")
    return result.exit_code


def _show(result: Any) -> None:
    """Print the grid: coloured on a terminal, plain text otherwise."""
    from rockbench.report.grid import format_grid, grid_table

    if sys.stdout.isatty():
        from rich.console import Console

        console = Console()
        table, legend = grid_table(result)
        console.print(table)
        for line in legend:
            style = ("red" if line.startswith("FAIL") else "magenta" if line.startswith("REGR")
                     else None)
            console.print(line, style=style, highlight=False, markup=False)
    else:
        print(format_grid(result), end="")


# ---------------------------------------------------------------------- history
_HISTORY_METRICS = ("max_error", "impact_time_error", "peak_error", "wall_time")
#: The ``kind`` of every study that records runs (its module's ``KIND``).
#: Studies that record runs (``kind`` in the store); a plugin study may add its own.
STUDY_KINDS = ("compare", "matrix", "sweep", "tune", "fragility", "tilting", "collapse",
               "ensemble")


def configure_history(p: argparse.ArgumentParser) -> None:
    """Options of ``rockbench history``."""
    from rockbench.evaluation import NUMERIC_METRICS
    from rockbench.store import DEFAULT_DB

    p.add_argument("scenario", nargs="?", default=None,
                   help="scenario name (default: list the stored cells)")
    p.add_argument("--engine", "-e", default=None, metavar="NAMES",
                   help="comma list of engines (default: every stored engine)")
    p.add_argument("--metric", "-m", action="append", default=None, metavar="NAME",
                   choices=sorted(NUMERIC_METRICS),
                   help=f"metric to show (repeatable; default: {', '.join(_HISTORY_METRICS)})")
    p.add_argument("--kind", default=None, metavar="KIND",
                   help=f"only runs made by this study ({', '.join(STUDY_KINDS)}, ...; "
                        "default: every study)")
    p.add_argument("--limit", type=int, default=50, metavar="N",
                   help="show the N latest runs per method (default: 50)")
    p.add_argument("--db", default=DEFAULT_DB, metavar="FILE",
                   help=f"results store (default: ./{DEFAULT_DB})")


def _cell(x: Any) -> str:
    if x is None:
        return "-"
    if isinstance(x, float):
        return f"{x:.4g}"
    if isinstance(x, (list, tuple)):
        return ",".join(_cell(v) for v in x)
    return str(x)


def _value(run: Any, name: str) -> float | None:
    """A metric of a stored run (None when its metrics cannot be read back)."""
    return None if run.metrics is None else run.metrics.value(name)


def execute_history(args: argparse.Namespace) -> int:
    """Show how a cell's metrics changed across stored runs and versions (any study)."""
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    from rockbench import provenance
    from rockbench.store import Store

    current = provenance.code_version("run")

    def made_by(r: Any) -> str:
        """The code that made a run: this code, other code, or an older rockbench."""
        if not r.code_version:
            return f"{r.rockbench_version} (older code)"
        return "this code" if r.code_version == current else r.code_version

    if args.limit < 1:
        raise RockbenchError(f"--limit must be >= 1, got {args.limit}")
    console = Console(width=160) if not sys.stdout.isatty() else Console()
    with Store(args.db, create=False) as store:
        runs = store.runs(scenario=args.scenario, kind=args.kind)
    engines = [e.strip() for e in args.engine.split(",")] if args.engine else None
    if engines:
        runs = [r for r in runs if r.engine in engines]
    if not runs:
        what = " ".join(x for x in (args.scenario, args.engine, args.kind) if x) or "anything"
        print(f"no stored runs for {what} in {args.db}")
        return 0
    if args.scenario is None:  # an overview of the cells
        table = Table(title=f"stored cells in {args.db}")
        for col in ("scenario", "method", "runs", "kinds", "last status", "last max|Δθ|/λ",
                    "last run", "versions"):
            table.add_column(col)
        cells: dict[tuple[str, str], list[Any]] = {}
        for r in runs:
            cells.setdefault((r.scenario, r.method), []).append(r)
        for (s, method), rs in sorted(cells.items()):
            last = rs[-1]
            versions = sorted({f"{r.engine_version}/{made_by(r)}" for r in rs})
            kinds = ",".join(sorted({r.kind for r in rs}))
            table.add_row(escape(s), escape(method), str(len(rs)), kinds, last.status.value,
                          _cell(_value(last, "max_error")), last.timestamp, " ".join(versions))
        console.print(table)
        console.print("run `rockbench history SCENARIO` for one scenario's runs")
        return 0
    names = args.metric or list(_HISTORY_METRICS)
    for method in sorted({r.method for r in runs}):
        rows = [r for r in runs if r.method == method][-args.limit:]
        table = Table(title=escape(f"{args.scenario} on {method}: {len(rows)} run(s)"))
        for col in ("time (UTC)", "kind", "made by", "engine version", "settings", "status",
                    *names, "Δ " + names[0]):
            table.add_column(col, justify="right" if col in names else "left")
        prev = None
        for r in rows:
            cur = _value(r, names[0])
            delta = "-"
            if cur is not None and prev:
                delta = f"{100 * (cur - prev) / abs(prev):+.0f}%"
            settings = " ".join(f"{k}={_cell(v)}" for k, v in r.settings.items()) or "default"
            status = r.status.value + ("" if r.metrics is not None else " (metrics unreadable)")
            table.add_row(r.timestamp.replace("+00:00", ""), r.kind, made_by(r),
                          r.engine_version, escape(settings), status,
                          *[_cell(_value(r, n)) for n in names], delta)
            prev = cur if cur is not None else prev
        console.print(table)
    return 0
