"""Analytic references: Housner's single block and the two-stacked-block model.

:func:`reference` picks the model that fits a scenario. This package never
imports :mod:`rockbench.engines`: a reference must not depend on what it checks.
"""

from __future__ import annotations

from rockbench.errors import UnsupportedScenario
from rockbench.scenarios import Scenario
from rockbench.trajectory import Trajectory

__all__ = ["reference", "has_reference"]


def has_reference(scenario: Scenario) -> bool:
    """True if an analytic model exists for this scenario (1 or 2 centred blocks)."""
    return scenario.n_blocks <= 2 and not any(scenario.stack.offsets)


def reference(scenario: Scenario) -> Trajectory:
    """The analytic reference trajectory of ``scenario``.

    Raises
    ------
    UnsupportedScenario
        More than two blocks, or off-centre blocks.
    """
    if not has_reference(scenario):
        raise UnsupportedScenario(
            "analytic references exist for one block or two centred stacked blocks only"
        )
    if scenario.n_blocks == 1:
        from rockbench.analytic.housner import single_block_reference

        return single_block_reference(scenario)
    from rockbench.analytic.twoblock import two_block_reference

    return two_block_reference(scenario)
