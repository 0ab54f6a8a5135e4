"""Analytic references: Housner's block, the two-block model, sliding, the rolling cylinder.

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
from rockbench.analytic.cylinder_reference import RollingStart, rolling_reference, rolling_start
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
    "SteadyPrecession", "RollingStart", "rolling_start", "rolling_reference",
]


def coverage(scenario: Scenario) -> str:
    """Why no analytic model covers ``scenario`` ('' when one does).

    The models are planar: one block (Housner) or two stacked centred blocks
    (the two-block model), both with the vertical base motion in g + ü_z (a
    cylinder rocks in the plane as a block of half-width R does), and the
    Coulomb slider (horizontal base motion only); in 3D, one cylinder tilted on
    its rim rolls without slipping (:func:`rolling_reference`), from any start
    and under base motion along x, y and z. Other geometries have
    their static limit-analysis reference only.
    """
    col = scenario.geometry.column
    if col is None or len(col) > 2 or not col.centred:
        return "no analytic model: one block or two centred stacked blocks only"
    axes = scenario.motion.axes
    if _rolls(scenario):
        return ""
    if scenario.moving_start or not scenario.planar_start:
        return ("no analytic model: a start out of the x–z plane or a moving one has the "
                "rolling reference of a tilted cylinder only")
    if "y" in axes:
        return "no analytic model: the planar models take no base motion along y"
    if "z" in axes and slides(scenario):
        return ("no analytic model: the vertical base motion enters the rocking models "
                "only, not the Coulomb sliding reference")
    return ""


def _rolls(scenario: Scenario) -> bool:
    """A tilted cylinder alone that starts out of the plane, moving, or under motion along y:
    the rolling reference (a planar one rocks as Housner's block, impacts included)."""
    return (scenario.n_blocks == 1 and scenario.has_cylinders and scenario.theta0 != 0.0
            and (scenario.moving_start or not scenario.planar_start
                 or "y" in scenario.motion.axes))


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
    if _rolls(scenario):
        return rolling_reference(scenario)
    if slides(scenario):
        return sliding_reference(scenario)
    if scenario.n_blocks == 1:
        return single_block_reference(scenario, linear=linear)
    if linear:
        raise UnsupportedScenario("the linearised model is implemented for single blocks only")
    return two_block_reference(scenario)
