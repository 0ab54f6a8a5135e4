"""``rockbench check``: the Italian code's kinematic check of a block or assembly at a site.

Examples::

    rockbench check --scenario parapet-offset0.25 --site site.toml --out check
    rockbench check --block 0.25,1.25 --site roof.toml --friction inf --out check-roof

Writes DIR/report.md, DIR/check.json and DIR/figures/capacity.png
(:mod:`rockbench.report.code_check_report`) and prints a short summary. The site
file is described in :func:`rockbench.studies.code_check.load_site`.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from rockbench.cli.common import (
    BLOCK_DENSITY,
    check_output_path,
    command_line,
    scenario_or_block,
)
from rockbench.errors import RockbenchError

__all__ = ["COMMANDS", "configure_check", "execute_check"]

#: The commands of this module: name → one-line help.
COMMANDS = {"check": "NTC 2018 kinematic check (linear and non-linear) of a block or assembly "
                     "at a site"}



def configure_check(p: argparse.ArgumentParser) -> None:
    """Add the ``check`` options to ``p``."""
    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument("--scenario", metavar="NAME|FILE",
                      help="a catalog scenario or .toml file: its blocks, friction and gravity")
    what.add_argument("--block", metavar="WIDTH,HEIGHT",
                      help="a single block of this width and height (m), square in plan, "
                           f"{BLOCK_DENSITY:g} kg/m³")
    p.add_argument("--site", required=True, metavar="FILE.toml",
                   help="site file: code, ag (g), F0, TC_star (s), soil, topography, q, "
                        "confidence_factor and an optional [building] (height, "
                        "element_height, period, storeys)")
    p.add_argument("--friction", default=None, metavar="MU",
                   help="Coulomb friction of every joint instead of the scenario's "
                        "('inf': no sliding, the Circolare's traditional hypothesis)")
    p.add_argument("--out", "-o", required=True, metavar="DIR",
                   help="report directory (report.md, check.json, figures/capacity.png)")
    p.add_argument("--quiet", "-q", action="store_true", help="no summary on stdout")


def _friction(text: str | None) -> float | None:
    if text is None:
        return None
    try:
        mu = float(text)
    except ValueError:
        mu = math.nan
    if math.isnan(mu) or mu < 0:
        raise RockbenchError(f"--friction takes a number >= 0 or 'inf', got {text!r}")
    return mu


def execute_check(args: argparse.Namespace) -> int:
    """Run the check and write the report; 0 when it is written (whatever the verdict)."""
    from rockbench.report.code_check_report import summary_lines, write_code_check_report
    from rockbench.studies.code_check import code_check, load_site

    scenario = scenario_or_block(args)
    site = load_site(args.site)
    friction = _friction(args.friction)
    out = Path(args.out)
    check_output_path(out / "report.md", "--out")
    result = code_check(scenario, site, friction=friction)
    paths = write_code_check_report(out, result, command_line(args))
    if not args.quiet:
        for line in summary_lines(result):
            print(line)
        print(f"report: {paths['report']}")
    return 0
