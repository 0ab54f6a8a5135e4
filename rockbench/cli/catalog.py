"""``rockbench engines`` and ``rockbench scenarios``: what can be run, and on what."""

from __future__ import annotations

import argparse

__all__ = ["COMMANDS", "configure_engines", "execute_engines", "configure_scenarios",
           "execute_scenarios"]

#: The commands of this module: name → one-line help.
COMMANDS = {
    "engines": "list engine plugins, availability and versions",
    "scenarios": "list the built-in scenarios and suites",
}


def configure_engines(p: argparse.ArgumentParser) -> None:
    """Options of ``rockbench engines``."""
    p.add_argument("--json", action="store_true", help="machine-readable output")


def execute_engines(args: argparse.Namespace) -> int:
    """List every registered engine: availability (with the install hint), version, dims."""
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
        table.add_row(i.name, "yes" if i.available else "no", escape(i.version),
                      "" if i.dimensions is None else f"{i.dimensions}D", note)
    Console(width=120).print(table)
    return 0


def configure_scenarios(p: argparse.ArgumentParser) -> None:
    """Options of ``rockbench scenarios``."""
    p.add_argument("--suite", default=None, help="list only this suite's scenarios")
    p.add_argument("--show", default=None, metavar="NAME",
                   help="print one scenario as a TOML file (a starting point for your own)")


def execute_scenarios(args: argparse.Namespace) -> int:
    """List the catalog (or a suite), or print one scenario as TOML."""
    from rich.console import Console
    from rich.table import Table

    from rockbench import analytic
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
        exc = s.excitation.to_table()
        desc = exc.pop("type") + " " + " ".join(f"{k}={v}" for k, v in exc.items()
                                                if k in ("frequency", "amplitude"))
        if s.initial_tilt:
            desc += f" tilt={s.initial_tilt} λ"
        table.add_row(n, str(s.n_blocks), f"{analytic.critical_angle(s.geometry):.4f}", desc,
                      f"{analytic.uplift_ratio(s):.2f}" if not s.motion.is_free else "-",
                      f"{s.duration:g}")
    console = Console(width=120)
    console.print(table)
    if not args.suite:
        console.print("suites: " + "; ".join(f"{k} ({len(v)})" for k, v in suites().items()))
    return 0
