"""``rockbench assemblies`` (tilting table and pulse to collapse) and ``rockbench collapse``.

Examples::

    rockbench assemblies --engine pymunk,mujoco,dem2d --out assemblies-report
    rockbench collapse --scenarios parapet-offset0.25 --frequencies 0.5,1,2 --out collapse

Both write DIR/index.html, DIR/report.md, DIR/results.csv and DIR/figures/
(:mod:`rockbench.report.assembly_report`); ``collapse`` runs the pulse-to-collapse
study only, ``assemblies`` the tilting table too. Every run is recorded in the
results store.
"""

from __future__ import annotations

import argparse
import time
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

__all__ = ["COMMANDS", "DEFAULT_SCENARIOS", "configure_assemblies",
           "execute_assemblies", "configure_collapse", "execute_collapse"]

#: The commands of this module: name → one-line help.
COMMANDS = {
    "assemblies": "assemblies up to collapse: tilting table vs limit analysis, pulse to collapse",
    "collapse": "pulse to collapse: smallest one-sine pulse that collapses each assembly",
}

#: A small set of one assembly per family (the walls' small bricks cost the DEM µs steps).
DEFAULT_SCENARIOS = "column-5drums,parapet-offset0.25,arch-9v-t0.20"


def _configure(p: argparse.ArgumentParser, *, tilting: bool) -> None:
    p.add_argument("--scenarios", default=DEFAULT_SCENARIOS, metavar="A,B,C",
                   help="comma list of catalog names, suite names (e.g. assemblies, "
                        "assembly-column) and .toml files (default: "
                        f"{DEFAULT_SCENARIOS})")
    add_engine_arguments(p, default="pymunk,mujoco,dem2d")
    if tilting:
        p.add_argument("--rate", type=float, default=0.05, metavar="R",
                       help="tilting-table dα/dt in 1/s; every case also runs at R/2 "
                            "(default: 0.05)")
        p.add_argument("--no-collapse", action="store_true",
                       help="the tilting table only")
    p.add_argument("--frequencies", default="0.25,0.5,1,2,4", metavar="F1,F2",
                   help="pulse frequencies in Hz (default: 0.25,0.5,1,2,4)")
    p.add_argument("--rtol", type=float, default=0.02, metavar="X",
                   help="bisection tolerance on the collapse amplitude (default: 0.02)")
    p.add_argument("--max-factor", type=float, default=16.0, metavar="K",
                   help="largest pulse tried, in units of the static factor (default: 16)")
    p.add_argument("--out", "-o", required=True, metavar="DIR",
                   help="report directory (index.html, report.md, results.csv, figures/)")
    p.add_argument("--link-figures", action="store_true",
                   help="link the PNGs from index.html instead of embedding them")
    p.add_argument("--no-isolate", action="store_true",
                   help="run engines in this process (no crash/hang protection, no timeout)")
    add_run_arguments(p)


def configure_assemblies(p: argparse.ArgumentParser) -> None:
    """Arguments of ``rockbench assemblies``."""
    _configure(p, tilting=True)


def configure_collapse(p: argparse.ArgumentParser) -> None:
    """Arguments of ``rockbench collapse``."""
    _configure(p, tilting=False)


def _frequencies(text: str) -> list[float]:
    try:
        out = [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise RockbenchError(f"--frequencies must be a comma list of Hz, got {text!r}") from None
    if not out or not all(0 < f < float("inf") for f in out):
        raise RockbenchError(f"--frequencies must be finite and > 0, got {text!r}")
    return out


def _run(args: argparse.Namespace, *, tilting: bool) -> int:
    from rockbench.engines import engine_class
    from rockbench.report.assembly_report import write_assembly_report
    from rockbench.scenarios import resolve_scenarios
    from rockbench.studies.collapse import pulse_to_collapse
    from rockbench.studies.tilting import tilting_table

    start = time.perf_counter()
    scenarios = resolve_scenarios(args.scenarios)
    if not scenarios:
        raise RockbenchError("--scenarios names no scenario")
    freqs = _frequencies(args.frequencies)
    if not (args.rtol > 0 and args.max_factor > 1):
        raise RockbenchError(f"need --rtol > 0 and --max-factor > 1, got {args.rtol:g}, "
                             f"{args.max_factor:g}")
    if tilting and not args.rate > 0:
        raise RockbenchError(f"--rate must be > 0, got {args.rate:g}")
    engines = [e for e in selected_engines(args.engine) if e != "analytic"]
    if not engines:
        raise RockbenchError("--engine selects no engine that builds assemblies")
    given = engine_settings(args, engines)
    explicit = bool(args.preset or args.settings_file or args.set_options)
    # without settings of their own each engine runs the preset it declares for assemblies
    settings = {e: given.get(e, {}) if explicit else {"preset": engine_class(e).assembly_preset}
                for e in engines}
    execution = execution_options(args, isolate=not args.no_isolate)
    out = Path(args.out)
    check_output_path(out / "results.csv", "--out")
    db = store_path(args)
    cmps = []
    study = None
    if tilting:
        with Progress(len(engines), "tilting engines") as bar:
            for e in engines:
                cmps += tilting_table(scenarios, e, rate=args.rate, settings=settings[e],
                                      execution=execution, db=db)
                bar.advance(e)
    if not (tilting and args.no_collapse):
        with Progress(len(scenarios) * len(engines) * len(freqs), "collapse runs") as bar:
            study = pulse_to_collapse(
                scenarios, engines, freqs, settings=settings, rtol=args.rtol,
                max_factor=args.max_factor, execution=execution, db=db,
                on_result=lambda res, _: bar.advance(
                    f"{res.scenario.name} {res.method.engine}"))
    files = write_assembly_report(out, scenarios, cmps, study, command=command_line(args),
                                  wall_time=time.perf_counter() - start,
                                  embed=not args.link_figures)
    for c in cmps:
        print(f"tilting {c.scenario:>22} {c.engine:>8}: onset {c.half.onset_factor:.4f}, LP "
              f"{c.limit.load_factor:.4f} ({100 * c.error:+.2f} %), "
              f"{c.run.cpu_time + c.half.cpu_time:.2f} s CPU")
    for p in (study.points if study else ()):
        print(f"collapse {p.scenario:>21} {p.engine:>8} {p.frequency:>5g} Hz: a_p/g "
              f"{p.acceleration_ratio:.4f} (α {p.static_factor:.4f}), {len(p.probes)} runs, "
              f"{p.cpu_time:.2f} s CPU")
    print(f"wrote {out / 'index.html'} and {len(files) - 1} more files")
    return 0


def execute_assemblies(args: argparse.Namespace) -> int:
    """Run ``rockbench assemblies``; returns the exit status."""
    return _run(args, tilting=True)


def execute_collapse(args: argparse.Namespace) -> int:
    """Run ``rockbench collapse``; returns the exit status."""
    return _run(args, tilting=False)
