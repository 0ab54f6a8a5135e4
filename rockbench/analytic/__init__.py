"""Analytic references: Housner's single block, the two-stacked-block model, Coulomb sliding.

:func:`reference` picks the model that fits a scenario. This package never
imports :mod:`rockbench.engines`: a reference must not depend on what it checks.
"""

from __future__ import annotations

from rockbench.analytic.closed_forms import (
    amplitude_after_impacts,
    free_impact_times,
    free_period,
    impact_velocity,
    quarter_period,
)
from rockbench.analytic.housner import SingleBlockSolution, single_block_reference, solve_single
from rockbench.analytic.limit_analysis import (
    BlockMotion,
    InterfaceForce,
    InterfaceMotion,
    LimitResult,
    limit_analysis,
    minimum_stable,
    stands,
)
from rockbench.analytic.limit_geometry import (
    Assembly,
    Interface,
    PlanarBlock,
    Support,
    assembly_from_stack,
    block_stack,
    semicircular_arch,
)
from rockbench.analytic.overturning import (
    minimum_overturning_acceleration,
    pulse_outcome,
    scan_column,
)
from rockbench.analytic.sliding import (
    Regime,
    RegimeThresholds,
    SlidingSolution,
    SlipPhase,
    onset_regime,
    regime_thresholds,
    slides,
    sliding_reference,
    slip_of,
    solve_sliding,
)
from rockbench.analytic.twoblock import (
    BlockParams,
    TwoBlockSolution,
    solve_two_blocks,
    two_block_reference,
)
from rockbench.errors import UnsupportedScenario
from rockbench.scenarios import Scenario
from rockbench.trajectory import Trajectory

__all__ = [
    "reference", "has_reference", "solve_single", "single_block_reference",
    "SingleBlockSolution", "solve_two_blocks", "two_block_reference", "BlockParams",
    "TwoBlockSolution", "free_period", "quarter_period", "amplitude_after_impacts",
    "impact_velocity", "free_impact_times", "pulse_outcome", "scan_column",
    "minimum_overturning_acceleration", "solve_sliding", "sliding_reference", "slides",
    "slip_of", "SlidingSolution", "SlipPhase", "Regime", "RegimeThresholds",
    "regime_thresholds", "onset_regime",
    "limit_analysis", "stands", "minimum_stable", "LimitResult", "BlockMotion",
    "InterfaceMotion", "InterfaceForce", "Assembly", "PlanarBlock", "Support", "Interface",
    "block_stack", "semicircular_arch", "assembly_from_stack",
]


def has_reference(scenario: Scenario) -> bool:
    """True if an analytic model exists for this scenario (1 or 2 centred blocks; a block
    assembly has its static limit-analysis reference, no dynamic one)."""
    if scenario.is_assembly:
        return False
    return scenario.n_blocks <= 2 and not any(scenario.stack.offsets)


def reference(scenario: Scenario, *, linear: bool = False) -> Trajectory:
    """The analytic reference trajectory of ``scenario``.

    Upright blocks whose friction is below every uplift ratio and whose base
    acceleration exceeds μ g slide without rocking: they get the exact Coulomb
    sliding reference (:func:`sliding_reference`, for either value of
    ``linear``). Otherwise one block gets Housner's solution and two blocks
    the two-block model.

    Parameters
    ----------
    scenario : Scenario
        One block, or two centred stacked blocks.
    linear : bool
        Single rocking blocks only: Housner's linearised equation (sin x ≈ x,
        cos x ≈ 1, uplift at g·λ) instead of the exact one.

    Raises
    ------
    UnsupportedScenario
        More than two blocks, or off-centre blocks.
    """
    if not has_reference(scenario):
        raise UnsupportedScenario(
            "analytic references exist for one block or two centred stacked blocks only"
        )
    if slides(scenario):
        return sliding_reference(scenario)
    if scenario.n_blocks == 1:
        return single_block_reference(scenario, linear=linear)
    if linear:
        raise UnsupportedScenario("the linearised model is implemented for single blocks only")
    return two_block_reference(scenario)
