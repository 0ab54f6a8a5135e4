"""Scenario groups: how reports gather scenarios into sections, and their titles."""

from __future__ import annotations

import re

from rockbench.scenarios import Scenario

__all__ = ["scenario_group", "group_title", "GROUP_TITLES"]

#: Titles of scenario groups, in report order.
GROUP_TITLES: dict[str, str] = {
    "free": "Free rocking of a single block",
    "single-pulse": "Single block, one-cycle sine pulse",
    "single-sine": "Single block, sinusoidal base motion",
    "single-record": "Single block, recorded ground motion",
    "stack-free": "Two stacked blocks, free rocking",
    "stack-pulse": "Two stacked blocks, one-cycle sine pulse",
    "stack-sine": "Two stacked blocks, sinusoidal base motion",
    "stack-record": "Two stacked blocks, recorded ground motion",
}


def scenario_group(scenario: Scenario) -> str:
    """Group of a scenario: ``free``, ``single-pulse``, ``stack-sine``, ``stack3-pulse`` ...

    The excitation names its own part (:attr:`Excitation.report_group`), the
    number of blocks the rest.
    """
    kind = scenario.excitation.report_group
    nb = scenario.n_blocks
    if kind == "free" and nb == 1:
        return "free"
    prefix = "single" if nb == 1 else "stack" if nb == 2 else f"stack{nb}"
    return f"{prefix}-{kind}"


def group_title(group: str) -> str:
    """Human title of a scenario group."""
    if group in GROUP_TITLES:
        return GROUP_TITLES[group]
    m = re.match(r"stack(\d+)-(\w+)", group)
    if m:
        return f"Stacks of {m.group(1)} blocks, {m.group(2)}"
    return group
