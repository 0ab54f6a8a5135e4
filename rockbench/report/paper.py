"""The published numbers of Giordano et al. (2025), shown beside rockbench's results.

The numbers live in ``rockbench/report/data/paper_tables.toml`` with their
citation; this module only reads them and matches them to catalog scenarios.
No rockbench result is ever computed from them.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from typing import Any

from rockbench.scenarios import Scenario
from rockbench.tomlfile import loads

__all__ = ["PaperTable", "paper_data", "citation", "paper_tables", "case_key",
           "paper_runtimes", "paper_summary", "is_catalog_case"]

_CASE = re.compile(r"^(?P<prefix>(?:single|stack)-(?:pulse|sine))-(?P<case>\d+\.\dhz-\d+mm)$")


@dataclass(frozen=True)
class PaperTable:
    """One published table: per case, one value per method.

    Attributes
    ----------
    key : str
        Identifier in the data file (``table6`` ...).
    number : str
        The paper's table number as printed.
    title : str
        What the table holds.
    quantity : str
        ``peak_ratio`` (max |θ|/λ) or ``error_vs_experiment_percent``.
    scenario_prefix : str
        Catalog scenarios it applies to (``single-pulse`` ...).
    block : int
        1-based block index the values refer to (1 = bottom).
    methods : tuple of str
        Column names (``analytical``, ``Bullet``, ``Vortex``, ``DEM``).
    cases : dict
        Case key (``3.0hz-8mm``) → values (float, or a string such as ``–``).
    note : str
        Caveat printed with the table.
    """

    key: str
    number: str
    title: str
    quantity: str
    scenario_prefix: str
    block: int
    methods: tuple[str, ...]
    cases: dict[str, tuple[float | str, ...]]
    note: str = ""

    def values(self, scenario: Scenario) -> tuple[float | str, ...] | None:
        """The published values for ``scenario``, or None if it is not one of the cases."""
        key = case_key(scenario)
        if key is None or not scenario.name.startswith(self.scenario_prefix + "-"):
            return None
        return self.cases.get(key)


@lru_cache(maxsize=1)
def paper_data() -> dict[str, Any]:
    """The parsed data file (tables, summaries, run times, citation)."""
    text = resources.files("rockbench.report").joinpath("data/paper_tables.toml").read_text(
        encoding="utf-8")
    return loads(text)


def citation() -> str:
    """Full citation string of the paper."""
    c = paper_data()["citation"]
    return (f"{c['authors']}, \u201c{c['title']}\u201d, {c['journal']} ({c['year']}), "
            f"doi:{c['doi']}")


def paper_tables() -> dict[str, PaperTable]:
    """Published tables keyed ``table6``, ``table7``, ``table9``, ``table10``."""
    out = {}
    for key, t in paper_data()["tables"].items():
        out[key] = PaperTable(
            key=key, number=str(t["number"]), title=t["title"], quantity=t["quantity"],
            scenario_prefix=t["scenario_prefix"], block=int(t["block"]),
            methods=tuple(t["methods"]), note=t.get("note", ""),
            cases={k: tuple(v) for k, v in t["cases"].items()},
        )
    return out


def paper_summary(key: str) -> dict[str, Any]:
    """A published summary (``tables11_12``, ``free``): number, title, findings."""
    return dict(paper_data()["summaries"][key])


def paper_runtimes() -> list[dict[str, str]]:
    """The paper's run-time table (case, scenario or scenario_prefix, engines, dem)."""
    return [dict(r) for r in paper_data()["runtimes"]]


@lru_cache(maxsize=256)
def _catalog_dict(name: str) -> str | None:
    from rockbench.scenarios import get_scenario, scenario_to_dict
    from rockbench.scenarios.catalog import catalog

    if name not in catalog():
        return None
    return repr(scenario_to_dict(get_scenario(name)))


def is_catalog_case(scenario: Scenario) -> bool:
    """True if ``scenario`` is exactly the catalog scenario of the same name."""
    from rockbench.scenarios import scenario_to_dict

    ref = _catalog_dict(scenario.name)
    return ref is not None and ref == repr(scenario_to_dict(scenario))


def case_key(scenario: Scenario) -> str | None:
    """``3.0hz-8mm`` for the catalog's paper cases (unchanged), else None."""
    m = _CASE.match(scenario.name)
    if m is None or not is_catalog_case(scenario):
        return None
    return m.group("case")
