"""``rockbench run``: one scenario on engines and the analytic reference."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from rockbench.cli.common import (
    Progress,
    add_engine_arguments,
    check_output_path,
    engine_settings,
    execution_options,
    selected_engines,
)
from rockbench.errors import RockbenchError

__all__ = ["COMMANDS", "configure_run", "execute_run"]

#: The commands of this module: name → one-line help.
COMMANDS = {"run": "run one scenario on engines and the analytic reference"}


def configure_run(p: argparse.ArgumentParser) -> None:
    """Options of ``rockbench run``."""
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


def _check_out(path: Path) -> None:
    """The trajectory and its ``.json`` sidecar can be written, and the sidecar would not
    replace a JSON file that is not this trajectory's."""
    side = path.with_suffix(".json")
    if side.exists() and not path.exists():
        raise RockbenchError(f"--out {path}: would overwrite {side}, which was not written with "
                             f"it (a trajectory's sidecar is FILE.json): choose another name")
    check_output_path(path, "--out")
    check_output_path(side, "--out")


def execute_run(args: argparse.Namespace) -> int:
    """Run the engines (and the reference), print a table, write trajectories if asked."""
    from rich.console import Console
    from rich.table import Table

    from rockbench import analytic
    from rockbench.campaign import CampaignOptions, PlannedRun, run_campaign
    from rockbench.method import Method
    from rockbench.scenarios import get_scenario, scenario_to_dict
    from rockbench.studies.verify import verdict_of

    execution = execution_options(args, isolate=not args.no_isolate)
    scenario = get_scenario(args.scenario)
    engines = selected_engines(args.engine)
    settings = engine_settings(args, engines)
    if args.out:
        for e in engines:
            _check_out(_out_path(args.out, e, len(engines) > 1))
    has_ref = analytic.has_reference(scenario)
    plan = [PlannedRun(scenario, Method.of(e, settings[e])) for e in engines if e != "analytic"]
    if "analytic" in engines or has_ref:
        plan.insert(0, PlannedRun(scenario, Method.reference()))
    written: list[str] = []

    with Progress(len(plan), scenario.name) as bar:
        def on_result(res: Any, traj: Any) -> None:
            engine = res.method.engine
            if args.out and engine in engines and traj is not None:
                path = _out_path(args.out, engine, len(engines) > 1)
                traj.save(path, scenario=scenario_to_dict(scenario))
                written.append(str(path))
            bar.advance(engine)

        campaign = run_campaign(plan, CampaignOptions(kind="run", keep=True,
                                                      execution=execution,
                                                      timeout=execution.timeout),
                                on_result=on_result)
    lam = analytic.critical_angle(scenario.geometry)
    table = Table(title=f"{scenario.name}  (λ = {lam:.4f} rad)")
    table.add_column("engine")
    table.add_column("status")
    for i in range(scenario.n_blocks):
        table.add_column(f"max|θ{i + 1}|/λ", justify="right")
    table.add_column("max|Δθ|/λ vs analytic", justify="right")
    table.add_column("wall (s)", justify="right")
    table.add_column("note")
    for res in campaign.results:
        name = res.method.engine
        label = "analytic (reference)" if name == "analytic" and name not in engines else name
        m = res.metrics
        table.add_row(label, m.status.value, *[_fmt(p) for p in m.peaks],
                      _fmt(m.max_error), f"{m.wall_time:.3f}", m.message)
    Console(width=140).print(table)
    for w in written:
        print(f"wrote {w}")
    if [r for r in campaign.results if not r.method.is_reference]:
        verdict, _ = verdict_of(campaign.results, campaign.references)
        print("verdict: " + "\n         ".join(verdict.lines()))
        if not has_ref:
            print(f"no closed form covers {scenario.name}: `rockbench verify {args.scenario} "
                  f"--engine {args.engine}` judges the engines against a consensus")
    return 0


def _fmt(x: float | None) -> str:
    return "-" if x is None else f"{x:.4f}"
