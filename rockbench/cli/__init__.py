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
from typing import Any, NoReturn

import numpy as np

import rockbench
from rockbench.errors import RockbenchError

__all__ = ["main", "build_parser", "add_engine_arguments", "add_settings_arguments",
           "engine_settings", "Progress"]

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


def add_engine_arguments(p: argparse.ArgumentParser, default: str = "all") -> None:
    """The engine selection and settings flags shared by every command that runs engines."""
    p.add_argument("--engine", "-e", default=default, metavar="NAMES",
                   help=f"'all' or a comma list of engines (default: {default})")
    add_settings_arguments(p)


def add_settings_arguments(p: argparse.ArgumentParser) -> None:
    """``--preset``, ``--settings FILE`` and ``--set``: the layers of :func:`engine_settings`."""
    p.add_argument("--preset", default=None, metavar="NAME",
                   help="settings preset for every engine (e.g. accurate, fast)")
    p.add_argument("--settings", dest="settings_file", default=None, metavar="FILE",
                   help="TOML file of engine knobs ([engine] knob = value), e.g. written by "
                        "`rockbench tune`; it overrides --preset, and --set overrides it")
    p.add_argument("--set", dest="set_options", action="append", default=[],
                   metavar="ENGINE.KNOB=VALUE",
                   help="override an engine knob, e.g. --set bullet.substeps=20 (repeatable)")


def engine_settings(args: argparse.Namespace, engines: Sequence[str]) -> dict[str, dict[str, Any]]:
    """Per-engine settings from ``--preset``, ``--settings FILE`` and ``--set``, validated now.

    See :func:`rockbench.presets.layered_settings` (values typed, later layers win).

    Raises
    ------
    SettingsError
        Bad settings file, unknown knob or preset, or a value of the wrong type.
    UnknownEngine
        ``--set`` names an engine that is not selected or does not exist.
    """
    from rockbench.presets import layered_settings

    return layered_settings(engines, preset=args.preset, settings_file=args.settings_file,
                            set_options=args.set_options)


class Progress:
    """A progress bar on a terminal (rich), a plain line per finished job otherwise."""

    def __init__(self, total: int, description: str, *, quiet: bool = False) -> None:
        self.total = total
        self.description = description
        self.done = 0
        self.quiet = quiet
        self._bar = None
        if not quiet and sys.stderr.isatty():
            from rich.progress import BarColumn, MofNCompleteColumn, TextColumn, TimeElapsedColumn
            from rich.progress import Progress as RichProgress

            self._bar = RichProgress(TextColumn("{task.description}"), BarColumn(),
                                     MofNCompleteColumn(), TimeElapsedColumn(),
                                     transient=True)

    def __enter__(self) -> Progress:
        if self._bar is not None:
            self._bar.start()
            self._task = self._bar.add_task(self.description, total=self.total)
        return self

    def advance(self, text: str = "") -> None:
        """Count one finished job (``text`` describes it)."""
        self.done += 1
        if self._bar is not None:
            self._bar.update(self._task, advance=1, description=f"{self.description} {text}")

    def __exit__(self, *exc: object) -> None:
        if self._bar is not None:
            self._bar.stop()


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
    p.add_argument("--timeout", type=float, default=None, metavar="S",
                   help="wall-time limit per engine run (default: none)")
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

    from rockbench import analytic, metrics
    from rockbench.engines import resolve_engine_names
    from rockbench.runner import Job, run_jobs
    from rockbench.scenarios import get_scenario, scenario_to_dict

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

        trajs = run_jobs(jobs, n_jobs=1, timeout=args.timeout, isolate=not args.no_isolate,
                         on_result=on_result)
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
        peaks = metrics.peak_ratio(traj, lam)
        err = (metrics.max_error(traj, ref, lam)
               if ref is not None and traj is not ref and traj.t.size and ref.t.size else np.nan)
        table.add_row(label, str(traj.status), *[_fmt(p) for p in peaks], _fmt(err),
                      f"{traj.wall_time:.3f}", traj.message)
    Console(width=140).print(table)
    for w in written:
        print(f"wrote {w}")
    return 0


def _fmt(x: float) -> str:
    return "-" if not np.isfinite(x) else f"{x:.4f}"


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
