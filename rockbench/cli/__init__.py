"""The ``rockbench`` command line.

Each sub-command lives in a module exposing ``configure(parser)`` and
``execute(args) -> int``; this module wires them together and turns bad input
into one clear line on stderr with exit status 2.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import NoReturn

import rockbench
from rockbench.cli.common import Progress, add_engine_arguments, engine_settings, execution_options
from rockbench.errors import RockbenchError

__all__ = ["main", "build_parser", "COMMANDS"]

#: Sub-commands: name → (module, one-line help). Modules are imported on use.
COMMANDS: dict[str, tuple[str, str]] = {
    "engines": ("rockbench.cli", "list engine plugins, availability and versions"),
    "scenarios": ("rockbench.cli", "list the built-in scenarios and suites"),
    "run": ("rockbench.cli", "run one scenario on engines and the analytic reference"),
    "compare": ("rockbench.cli.compare", "run a suite on engines and write the report"),
    "matrix": ("rockbench.cli.matrix", "engines × scenarios pass/fail matrix"),
    "sweep": ("rockbench.cli.sweep", "settings grids: accuracy vs cost, stability"),
    "tune": ("rockbench.cli.sweep", "find the cheapest settings meeting a target"),
    "history": ("rockbench.cli.matrix", "metrics of a cell across stored runs"),
    "spectrum": ("rockbench.cli.spectrum",
                 "overturning spectra: min overturning acceleration vs pulse frequency"),
}


class _Parser(argparse.ArgumentParser):
    """argparse that reports errors as a single line (exit status 2)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


# ---------------------------------------------------------------------- engines
def _configure_engines(p: argparse.ArgumentParser) -> None:
    p.add_argument("--json", action="store_true", help="machine-readable output")


def _execute_engines(args: argparse.Namespace) -> int:
    import json

    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    from rockbench.engines import list_engines

    infos = list_engines()
    if args.json:
        print(json.dumps([i.__dict__ for i in infos], indent=2))
        return 0
    table = Table(title="rockbench engines")
    for col in ("engine", "available", "version", "dims", "note"):
        table.add_column(col)
    for i in infos:
        note = "analytic reference" if i.analytic else ("" if i.available else escape(i.reason))
        table.add_row(i.name, "yes" if i.available else "no", i.version,
                      "" if i.dimensions is None else f"{i.dimensions}D", note)
    Console(width=120).print(table)
    return 0


# ---------------------------------------------------------------------- scenarios
def _configure_scenarios(p: argparse.ArgumentParser) -> None:
    p.add_argument("--suite", default=None, help="list only this suite's scenarios")
    p.add_argument("--show", default=None, metavar="NAME",
                   help="print one scenario as a TOML file (a starting point for your own)")


def _execute_scenarios(args: argparse.Namespace) -> int:
    from rich.console import Console
    from rich.table import Table

    from rockbench.scenarios import catalog, get_scenario, get_suite, scenario_to_dict, suites

    if args.show:
        import tomli_w

        print(tomli_w.dumps(scenario_to_dict(get_scenario(args.show))), end="")
        return 0
    names = get_suite(args.suite) if args.suite else catalog()
    table = Table(title=f"scenarios{' in ' + args.suite if args.suite else ''}")
    for col in ("name", "blocks", "λ (rad)", "excitation", "ü/(g tan λ)", "duration (s)"):
        table.add_column(col)
    for n in names:
        s = get_scenario(n)
        exc = s.excitation.to_dict()
        desc = exc.pop("type") + " " + " ".join(f"{k}={v}" for k, v in exc.items()
                                                if k in ("frequency", "amplitude"))
        if s.initial_tilt:
            desc += f" tilt={s.initial_tilt} λ"
        table.add_row(n, str(s.n_blocks), f"{s.critical_angle:.4f}", desc,
                      f"{s.uplift_ratio:.2f}" if not s.excitation.is_free else "-",
                      f"{s.duration:g}")
    console = Console(width=120)
    console.print(table)
    if not args.suite:
        console.print("suites: " + "; ".join(f"{k} ({len(v)})" for k, v in suites().items()))
    return 0


# ---------------------------------------------------------------------- run
def _configure_run(p: argparse.ArgumentParser) -> None:
    p.add_argument("scenario", help="catalog name or scenario .toml file")
    add_engine_arguments(p, default="analytic")
    p.add_argument("--out", "-o", default=None, metavar="FILE",
                   help="write trajectories (.csv or .npz, + .json sidecar); with several "
                        "engines the engine name is appended to the file stem")
    from rockbench.runner import DEFAULT_TIMEOUT

    p.add_argument("--timeout", type=float, default=DEFAULT_TIMEOUT, metavar="S",
                   help=f"wall-time limit per engine run in s (default: {DEFAULT_TIMEOUT:g})")
    p.add_argument("--no-isolate", action="store_true",
                   help="run engines in this process (no crash/hang protection)")


def _out_path(out: str, engine: str, several: bool) -> Path:
    path = Path(out)
    if path.suffix not in (".csv", ".npz"):
        raise RockbenchError(f"--out must end in .csv or .npz, got {out!r}")
    return path.with_name(f"{path.stem}-{engine}{path.suffix}") if several else path


def _execute_run(args: argparse.Namespace) -> int:
    from rich.console import Console
    from rich.table import Table

    from rockbench import analytic
    from rockbench.engines import resolve_engine_names
    from rockbench.evaluation import evaluate_run
    from rockbench.runner import Job, run_jobs
    from rockbench.scenarios import get_scenario, scenario_to_dict

    execution = execution_options(args, isolate=not args.no_isolate)
    scenario = get_scenario(args.scenario)
    engines = resolve_engine_names(args.engine)
    settings = engine_settings(args, engines)
    if args.out:
        for e in engines:
            _out_path(args.out, e, len(engines) > 1)
    has_ref = analytic.has_reference(scenario)
    if has_ref and "analytic" not in engines:
        engines_run = ["analytic", *engines]
        settings["analytic"] = {}
    else:
        engines_run = engines
    jobs = [Job(scenario, e, settings[e]) for e in engines_run]
    written: list[str] = []

    def save(job: Job, traj: object) -> None:
        if args.out and job.engine in engines:
            path = _out_path(args.out, job.engine, len(engines) > 1)
            traj.save(path, scenario=scenario_to_dict(scenario))  # type: ignore[attr-defined]
            written.append(str(path))

    with Progress(len(jobs), scenario.name) as bar:
        def on_result(job: Job, traj: object) -> None:
            save(job, traj)
            bar.advance(job.engine)

        trajs = run_jobs(jobs, execution, on_result=on_result)
    by_engine = dict(zip(engines_run, trajs, strict=True))
    ref = by_engine.get("analytic") if has_ref else None
    lam = scenario.critical_angle
    table = Table(title=f"{scenario.name}  (λ = {lam:.4f} rad)")
    table.add_column("engine")
    table.add_column("status")
    for i in range(scenario.n_blocks):
        table.add_column(f"max|θ{i + 1}|/λ", justify="right")
    table.add_column("max|Δθ|/λ vs analytic", justify="right")
    table.add_column("wall (s)", justify="right")
    table.add_column("note")
    for name, traj in by_engine.items():
        if name == "analytic" and name not in engines:
            label = "analytic (reference)"
        else:
            label = name
        m = evaluate_run(scenario, traj, ref, is_reference=traj is ref)
        table.add_row(label, str(traj.status), *[_fmt(p) for p in m.peaks],
                      _fmt(m.max_error), f"{m.wall_time:.3f}", traj.message)
    Console(width=140).print(table)
    for w in written:
        print(f"wrote {w}")
    return 0


def _fmt(x: float | None) -> str:
    return "-" if x is None else f"{x:.4f}"


# ---------------------------------------------------------------------- main
_LOCAL = {
    "engines": (_configure_engines, _execute_engines),
    "scenarios": (_configure_scenarios, _execute_scenarios),
    "run": (_configure_run, _execute_run),
}


def build_parser() -> argparse.ArgumentParser:
    """The full argument parser."""
    parser = _Parser(prog="rockbench", description=(
        "Benchmark rigid-block rocking in physics engines against Housner-type analytical "
        "solutions (Giordano et al. 2025)."))
    parser.add_argument("--version", action="version", version=f"rockbench {rockbench.__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name, (module, help_text) in COMMANDS.items():
        p = sub.add_parser(name, help=help_text, description=help_text)
        if name in _LOCAL:
            configure, _ = _LOCAL[name]
        else:
            try:
                mod = importlib.import_module(module)
            except ImportError:
                continue  # command not available in this build
            configure = getattr(mod, f"configure_{name}", None) or mod.configure
        configure(p)
        p.set_defaults(_command=name, _module=module)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``rockbench`` console script; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "_command", None):
        parser.print_help()
        return 2
    try:
        if args._command in _LOCAL:
            return _LOCAL[args._command][1](args)
        mod = importlib.import_module(args._module)
        execute = getattr(mod, f"execute_{args._command}", None) or mod.execute
        return int(execute(args))
    except RockbenchError as exc:
        print(f"rockbench: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("rockbench: interrupted; results written so far are kept", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
