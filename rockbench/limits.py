"""Plausibility limits checked before a run allocates anything: the memory budget.

A run holds its output samples in memory: the engine's poses (7 numbers per
block and sample) and the trajectory it returns (θ, x, z and wobble per block,
plus time), about :data:`BYTES_PER_SAMPLE` bytes per block and sample with the
working copies. A scenario whose ``duration × output_rate`` would need more
than the budget is refused before anything is allocated, with the reason, so
that a typo (``duration = 1e6``, ``output_rate = 1e7``) costs one line instead
of an out-of-memory kill.

The budget is :data:`DEFAULT_BUDGET_GB` GB per run; the environment variable
``ROCKBENCH_MAX_MEMORY`` (in GB, inherited by every engine child) raises or
lowers it, and every command that runs engines sets it from ``--max-memory``.
"""

from __future__ import annotations

import math
import os

from rockbench.errors import ScenarioError
from rockbench.scenarios import Scenario

__all__ = ["estimated_bytes", "memory_budget", "check_memory", "DEFAULT_BUDGET_GB",
           "BUDGET_ENV", "BYTES_PER_SAMPLE"]

#: Default memory budget of one run, in GB.
DEFAULT_BUDGET_GB = 2.0
#: Environment variable holding the budget in GB.
BUDGET_ENV = "ROCKBENCH_MAX_MEMORY"
#: Bytes held per block and output sample (poses, trajectory arrays, working copies).
BYTES_PER_SAMPLE = 8 * (7 + 4 + 7 + 4)


def estimated_bytes(scenario: Scenario) -> float:
    """Memory a run of ``scenario`` holds for its output samples, in bytes."""
    samples = scenario.duration * scenario.output_rate + 1.0
    return samples * (scenario.n_blocks * BYTES_PER_SAMPLE + 8.0)


def memory_budget() -> float:
    """The budget in bytes (``ROCKBENCH_MAX_MEMORY`` GB, default :data:`DEFAULT_BUDGET_GB`).

    Raises
    ------
    ScenarioError
        The variable is not a positive finite number.
    """
    text = os.environ.get(BUDGET_ENV, "")
    if not text:
        return DEFAULT_BUDGET_GB * 1e9
    try:
        gb = float(text)
    except ValueError:
        gb = math.nan
    if not (math.isfinite(gb) and gb > 0):
        raise ScenarioError(f"{BUDGET_ENV} must be a positive number of GB, got {text!r}")
    return gb * 1e9


def check_memory(scenario: Scenario) -> None:
    """Refuse a scenario whose output would not fit the memory budget.

    Raises
    ------
    ScenarioError
        With the estimate, the budget and how to change either.
    """
    need, budget = estimated_bytes(scenario), memory_budget()
    if need > budget:
        samples = scenario.duration * scenario.output_rate
        raise ScenarioError(
            f"scenario {scenario.name!r}: {samples:.3g} output samples (duration "
            f"{scenario.duration:g} s × output_rate {scenario.output_rate:g}/s) would hold about "
            f"{need / 1e9:.3g} GB per run, over the {budget / 1e9:g} GB budget: lower the "
            f"duration or output_rate, or raise the budget with --max-memory GB "
            f"(or {BUDGET_ENV})")
