"""Fragility studies: intensity measures, lognormal fragility fits, non-monotone exceedance."""

from rockbench.fragility.compare import MedianComparison, compare_medians
from rockbench.fragility.fit import (
    ExceedanceData,
    FitStatus,
    FragilityBootstrap,
    FragilityError,
    FragilityFit,
    LevelProbability,
    bootstrap_fragility,
    fit_fragility,
)
from rockbench.fragility.monotonicity import Island, find_non_monotone
from rockbench.scenarios.intensity import (
    IntensityMeasure,
    PulseRatios,
    intensity,
    peak_ground_acceleration,
    peak_ground_velocity,
    pulse_ratios,
    scale_factor,
    scale_record,
)

__all__ = [
    "ExceedanceData", "FitStatus", "FragilityBootstrap", "FragilityError", "FragilityFit",
    "LevelProbability",
    "bootstrap_fragility", "fit_fragility",
    "IntensityMeasure", "PulseRatios", "intensity", "peak_ground_acceleration",
    "peak_ground_velocity", "pulse_ratios", "scale_factor", "scale_record",
    "Island", "find_non_monotone", "MedianComparison", "compare_medians",
]
