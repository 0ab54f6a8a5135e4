"""``rockbench matrix`` (pass/fail grid) and ``rockbench history`` (a cell across runs)."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from rockbench.cli import Progress, add_engine_arguments, engine_settings
from rockbench.errors import RockbenchError

__all__ = ["configure_matrix", "execute_matrix", "configure_history", "execute_history",
           "add_run_arguments", "add_parallel_arguments", "check_parallel_arguments",
           "open_store"]


# ---------------------------------------------------------------------- shared options
def add_run_arguments(p: argparse.ArgumentParser, *, timeout: float | None = 600.0) -> None:
    """Options shared by matrix, sweep and tune: store, parallelism, time limit, executor."""
    from rockbench.store import DEFAULT_DB

    p.add_argument("--db", default=DEFAULT_DB, metavar="FILE",
                   help=f"results store (SQLite), appended as each run finishes "
                        f"(default: ./{DEFAULT_DB})")
    p.add_argument("--no-db", action="store_true", help="do not write the results store")
    add_parallel_arguments(p, timeout=timeout)


def add_parallel_arguments(p: argparse.ArgumentParser, *, timeout: float | None) -> None:
    """Parallelism, time limit and executor options of every command that runs engines."""
    from rockbench.runner import EXECUTORS, default_jobs

    p.add_argument("--jobs", "-j", type=int, default=default_jobs(), metavar="N",
                   help="parallel engine runs (default: the machine's cores, "
                        f"{default_jobs()} here)")
    p.add_argument("--timeout", type=float, default=timeout, metavar="S",
                   help=f"wall-time limit per engine run in s (default: {timeout:g})"
                   if timeout else "wall-time limit per engine run in s")
    p.add_argument("--executor", choices=EXECUTORS, default="process",
                   help="local processes (default) or a Dask distributed cluster")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="Dask scheduler address, e.g. tcp://10.0.0.1:8786 (with --executor "
                        "dask; default: a local Dask cluster)")


def open_store(args: argparse.Namespace) -> Any:
    """The results store named by ``--db`` (None with ``--no-db``)."""
    from rockbench.store import Store

    return None if getattr(args, "no_db", False) else Store(args.db)


def check_parallel_arguments(args: argparse.Namespace) -> None:
    """Reject bad ``--jobs``, ``--timeout`` and ``--scheduler`` values (one line, exit 2)."""
    if args.jobs < 1:
        raise RockbenchError(f"--jobs must be >= 1, got {args.jobs}")
    if args.timeout is not None and not args.timeout > 0:
        raise RockbenchError(f"--timeout must be > 0, got {args.timeout:g}")
    if getattr(args, "scheduler", None) and args.executor != "dask":
        raise RockbenchError("--scheduler needs --executor dask")


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
    add_run_arguments(p)
    p.epilog = "exit status: 0 all cells pass, 1 a cell failed or regressed, 2 bad input"


def execute_matrix(args: argparse.Namespace) -> int:
    """Run ``rockbench matrix``; returns 0, 1 (failures/regressions) or 2 (bad input)."""
    from rockbench.engines import resolve_engine_names
    from rockbench.report.matrix import (
        format_grid,
        grid_table,
        load_baseline,
        run_matrix,
        write_baseline,
        write_junit,
    )
    from rockbench.report.tolerances import load_tolerances
    check_parallel_arguments(args)
    scenarios = _scenarios(args.suite)
    if not scenarios:
        raise RockbenchError(f"--suite {args.suite!r} selects no scenario")
    engines = resolve_engine_names(args.engine, include_analytic=False)
    settings = engine_settings(args, engines)
    tolerances = load_tolerances(args.tolerances)
    baseline = load_baseline(args.baseline) if args.baseline else None
    if tolerances.suite and tolerances.suite != args.suite:
        print(f"rockbench: note: {tolerances.source} was calibrated for suite "
              f"{tolerances.suite!r}, not {args.suite!r}", file=sys.stderr)
    store = open_store(args)
    try:
        with Progress(len(scenarios) * len(engines), "matrix") as bar:
            def on_cell(cell: Any) -> None:
                bar.advance(f"{cell.engine} × {cell.scenario}")
                if not sys.stderr.isatty():
                    print(f"[{bar.done}/{bar.total}] {cell.engine} × {cell.scenario}: "
                          f"{cell.status.value}" + (" (stored)" if cell.reused else ""),
                          file=sys.stderr, flush=True)

            result = run_matrix(scenarios, engines, tolerances, settings=settings,
                                suite=args.suite, store=store, baseline=baseline,
                                resume=args.resume, n_jobs=args.jobs, timeout=args.timeout,
                                executor=args.executor, scheduler=args.scheduler,
                                on_cell=on_cell)
    finally:
        if store is not None:
            store.close()
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
    if args.junit:
        print(f"wrote {write_junit(result, args.junit)}")
    if args.write_baseline:
        print(f"wrote {write_baseline(result, args.write_baseline)}")
    if store is not None:
        print(f"results appended to {args.db}")
    return result.exit_code


# ---------------------------------------------------------------------- history
_HISTORY_METRICS = ("max_error", "impact_time_error", "peak_error", "wall_time")


def configure_history(p: argparse.ArgumentParser) -> None:
    """Options of ``rockbench history``."""
    p.add_argument("scenario", nargs="?", default=None,
                   help="scenario name (default: list the stored cells)")
    p.add_argument("--engine", "-e", default=None, metavar="NAMES",
                   help="comma list of engines (default: every stored engine)")
    p.add_argument("--metric", "-m", action="append", default=None, metavar="NAME",
                   help=f"metric to show (repeatable; default: {', '.join(_HISTORY_METRICS)})")
    p.add_argument("--kind", default=None, choices=("matrix", "sweep", "tune"),
                   help="only runs made by this command")
    p.add_argument("--limit", type=int, default=50, metavar="N",
                   help="show the N latest runs per engine (default: 50)")
    p.add_argument("--db", default="rockbench.db", metavar="FILE",
                   help="results store (default: ./rockbench.db)")


def _cell(x: Any) -> str:
    if x is None:
        return "-"
    if isinstance(x, float):
        return f"{x:.4g}"
    if isinstance(x, list):
        return ",".join(_cell(v) for v in x)
    return str(x)


def execute_history(args: argparse.Namespace) -> int:
    """Show how a cell's metrics changed across stored runs and versions."""
    from pathlib import Path

    from rich.console import Console
    from rich.table import Table

    from rockbench.store import Store

    if not Path(args.db).exists():
        raise RockbenchError(f"no results store at {args.db} (run `rockbench matrix` first "
                             "or pass --db)")
    console = Console(width=160) if not sys.stdout.isatty() else Console()
    with Store(args.db) as store:
        runs = store.runs(scenario=args.scenario, kind=args.kind)
    engines = [e.strip() for e in args.engine.split(",")] if args.engine else None
    if engines:
        runs = [r for r in runs if r.engine in engines]
    if not runs:
        what = " ".join(x for x in (args.scenario, args.engine) if x) or "anything"
        print(f"no stored runs for {what} in {args.db}")
        return 0
    if args.scenario is None:  # an overview of the cells
        table = Table(title=f"stored cells in {args.db}")
        for col in ("scenario", "engine", "runs", "last status", "last max|Δθ|/λ",
                    "last run", "versions"):
            table.add_column(col)
        cells: dict[tuple[str, str], list[Any]] = {}
        for r in runs:
            cells.setdefault((r.scenario, r.engine), []).append(r)
        for (s, e), rs in sorted(cells.items()):
            last = rs[-1]
            versions = sorted({f"{r.engine_version}/{r.rockbench_version}" for r in rs})
            table.add_row(s, e, str(len(rs)), last.status.value,
                          _cell(last.metrics.get("max_error")), last.timestamp,
                          " ".join(versions))
        console.print(table)
        console.print("run `rockbench history SCENARIO` for one scenario's runs")
        return 0
    names = args.metric or list(_HISTORY_METRICS)
    for engine in sorted({r.engine for r in runs}):
        rows = [r for r in runs if r.engine == engine][-args.limit:]
        table = Table(title=f"{args.scenario} on {engine}: {len(rows)} run(s)")
        for col in ("time (UTC)", "kind", "rockbench", engine, "settings", "status", *names,
                    "Δ " + names[0]):
            table.add_column(col, justify="right" if col in names else "left")
        prev = None
        for r in rows:
            cur = r.metrics.get(names[0])
            delta = "-"
            if isinstance(cur, (int, float)) and isinstance(prev, (int, float)) and prev:
                delta = f"{100 * (cur - prev) / abs(prev):+.0f}%"
            settings = " ".join(f"{k}={_cell(v)}" for k, v in r.settings.items()) or "default"
            table.add_row(r.timestamp.replace("+00:00", ""), r.kind, r.rockbench_version,
                          r.engine_version, settings, r.status.value,
                          *[_cell(r.metrics.get(n)) for n in names], delta)
            prev = cur if cur is not None else prev
        console.print(table)
    return 0
