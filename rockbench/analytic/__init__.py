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
from rockbench.analytic.normalisation import critical_angle, uplift_ratio
from rockbench.analytic.overturning import (
    minimum_overturning_acceleration,
    pulse_outcome,
    scan_column,
)
from rockbench.analytic.rolling_cylinder import (
    RollingOutcome,
    RollingSolution,
    SteadyPrecession,
    solve_rolling,
    steady_precession,
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
from rockbench.analytic.static_collapse import (
    BlockMotion,
    InterfaceForce,
    InterfaceMotion,
    LimitResult,
    limit_analysis,
    minimum_stable,
    stands,
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
    "InterfaceMotion", "InterfaceForce", "critical_angle", "uplift_ratio", "coverage",
    "solve_rolling", "steady_precession", "RollingSolution", "RollingOutcome",
    "SteadyPrecession",
]


def coverage(scenario: Scenario) -> str:
    """Why no analytic model covers ``scenario`` ('' when one does).

    The models are planar: one block (Housner) or two stacked centred blocks
    (the two-block model), both with the vertical base motion in g + ü_z, and
    the Coulomb slider (horizontal base motion only); other geometries have
    their static limit-analysis reference only.
    """
    col = scenario.geometry.column
    if col is None or len(col) > 2 or not col.centred:
        return "no analytic model: one block or two centred stacked blocks only"
    axes = scenario.motion.axes
    if "y" in axes:
        return "no analytic model: the planar models take no base motion along y"
    if "z" in axes and slides(scenario):
        return ("no analytic model: the vertical base motion enters the rocking models "
                "only, not the Coulomb sliding reference")
    return ""


def has_reference(scenario: Scenario) -> bool:
    """True if an analytic model covers this scenario (:func:`coverage`)."""
    return not coverage(scenario)


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
        No model covers it (:func:`coverage` says why).
    """
    why = coverage(scenario)
    if why:
        raise UnsupportedScenario(why)
    if slides(scenario):
        return sliding_reference(scenario)
    if scenario.n_blocks == 1:
        return single_block_reference(scenario, linear=linear)
    if linear:
        raise UnsupportedScenario("the linearised model is implemented for single blocks only")
    return two_block_reference(scenario)
