"""``rockbench records``: the earthquake record sets, their records, and what to install.

Examples::

    rockbench records
    rockbench records --set fema-p695-far-field
    rockbench records --json
"""

from __future__ import annotations

import argparse

__all__ = ["COMMANDS", "configure_records", "execute_records"]

#: The commands of this module: name → one-line help.
COMMANDS = {"records": "list the earthquake record sets and records (and what to install)"}


def configure_records(p: argparse.ArgumentParser) -> None:
    """Options of ``rockbench records``."""
    p.add_argument("--set", dest="record_set", default=None, metavar="NAME",
                   help="list only this set's records")
    p.add_argument("--json", action="store_true", help="machine-readable output")


def execute_records(args: argparse.Namespace) -> int:
    """List every installed set's records; one line per unavailable set with its pip hint."""
    import dataclasses
    import json

    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    from rockbench.scenarios.excitation import STANDARD_GRAVITY
    from rockbench.scenarios.record_sets import (
        RecordSet,
        UnavailableRecordSet,
        get_record_set,
        record_sets,
    )

    sets: tuple[RecordSet | UnavailableRecordSet, ...] = (
        (get_record_set(args.record_set),) if args.record_set else record_sets())
    if args.json:
        print(json.dumps([{**dataclasses.asdict(s), "available": isinstance(s, RecordSet),
                           **({} if isinstance(s, RecordSet) else
                              {"install": s.install_hint})} for s in sets], indent=2))
        return 0
    console = Console(width=160)
    for s in sets:
        if isinstance(s, UnavailableRecordSet):
            continue
        table = Table(title=f"{s.name}: {s.description} ({s.distribution} {s.version})",
                      title_justify="left")
        for col in ("record", "event", "year", "station", "comp.", "dt (s)", "duration (s)",
                    "PGA (g)", "PGV (m/s)", "provenance"):
            table.add_column(col, overflow="fold", no_wrap=col in ("record", "comp.", "year"))
        for r in s.records + s.verticals:
            comp = f"{r.component} (vertical)" if r in s.verticals else r.component
            table.add_row(r.name, escape(r.event), str(r.year or ""), escape(r.station),
                          escape(comp), f"{r.dt:g}", f"{r.duration:.2f}",
                          f"{r.pga / STANDARD_GRAVITY:.3f}", f"{r.pgv:.3f}", escape(r.provenance))
        console.print(table)
        if s.motions:
            console.print(f"{s.name}: {len(s.motions)} ground motions (--components xz in "
                          "fragility): " + "; ".join(
                              f"{m.name} = " + ", ".join(f"{a} {getattr(m, a)}" for a in m.axes)
                              for m in s.motions), highlight=False)
    for s in sets:
        if isinstance(s, UnavailableRecordSet):
            console.print(f"{s.name}: unavailable ({escape(s.reason)}); install it with: "
                          f"{escape(s.install_hint)}", highlight=False)
    return 0
