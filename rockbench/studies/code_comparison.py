"""The code's verdict beside the dynamics: is the code conservative here, and by how much?

For one element and one site, :mod:`rockbench.studies.code_check` gives the code's verdict
and two accelerations at the element's base: the code's design value and, per check, the
capacity at which the check is exactly met. A fragility study of the same element, with
its levels in peak acceleration at that base (``pga``, or ``pga-uplift``), gives each
method's probability of overturning at the design value and its median overturning
acceleration. :func:`code_beside` puts them side by side: P(overturn | design PGA), and
the *margin* of each check, the median overturning PGA over the check's capacity PGA (above
1 the code is conservative: the element overturns, in the median, only at that many times
the acceleration the code accepts; below 1 the code accepts what the dynamics overturn).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rockbench.errors import RockbenchError
from rockbench.fragility import IntensityMeasure, LevelProbability
from rockbench.scenarios import Scenario
from rockbench.studies.code_check import CodeCheckResult
from rockbench.studies.fragility import FragilityResult, LimitState, uplift_acceleration

__all__ = ["MethodAgainstCode", "CodeBeside", "design_level", "code_beside"]


def _per_pga(measure: IntensityMeasure, scenario: Scenario) -> float:
    """The measure's value of a PGA of 1 m/s² (the measure must be a peak acceleration)."""
    if measure is IntensityMeasure.PGA:
        return 1.0
    if measure is IntensityMeasure.PGA_UPLIFT:
        return 1.0 / uplift_acceleration(scenario)
    raise RockbenchError(f"the code's design level is a peak acceleration at the element's "
                         f"base: the study's measure must be pga or pga-uplift, not "
                         f"{measure.value!r}")


def design_level(check: CodeCheckResult, measure: IntensityMeasure | str,
                 scenario: Scenario) -> float:
    """The code's design PGA at the element's base, in the units of ``measure``.

    Raises
    ------
    RockbenchError
        A measure that is not a peak acceleration (``pga``, ``pga-uplift``).
    """
    return check.design_pga * _per_pga(IntensityMeasure.parse(measure), scenario)


@dataclass(frozen=True)
class MethodAgainstCode:
    """One method's overturning fragility against the code.

    Attributes
    ----------
    method : str
        Method label.
    probability : LevelProbability or None
        P(overturning | PGA = the code's design PGA), with its interval (None: no fit).
    median_pga : float
        The median overturning PGA at the element's base (m/s²; NaN without a fit).
    linear_margin, nonlinear_margin : float
        ``median_pga`` over the capacity PGA of the linear and non-linear checks (NaN where
        either is missing).
    ec8_margin : float
        ``median_pga`` over the capacity PGA of Eurocode 8's element check (NaN without it).
    """

    method: str
    probability: LevelProbability | None
    median_pga: float
    linear_margin: float
    nonlinear_margin: float
    ec8_margin: float = math.nan


@dataclass(frozen=True)
class CodeBeside:
    """The code check of a fragility study's element, beside the study.

    Attributes
    ----------
    check : CodeCheckResult
        The code's verdict and accelerations.
    design_level : float
        The design PGA in the study's measure.
    methods : tuple of MethodAgainstCode
        Per method of the study, the reference first.
    """

    check: CodeCheckResult
    design_level: float
    methods: tuple[MethodAgainstCode, ...]


def code_beside(result: FragilityResult, check: CodeCheckResult) -> CodeBeside:
    """Each method's overturning fragility against the code's check (module docstring).

    Raises
    ------
    RockbenchError
        A study whose measure is not a peak acceleration.
    """
    scenario = result.options.scenario
    per = _per_pga(result.measure, scenario)
    level = check.design_pga * per
    cap_lin, cap_non = check.capacity_pga("linear"), check.capacity_pga("nonlinear")
    cap_ec8 = check.ec8.capacity_pga if check.ec8 is not None else math.nan
    rows = []
    for m in result.methods:
        boot = result.curve(m.label, LimitState.OVERTURNING).bootstrap
        ok = boot is not None and boot.fit.ok
        median = boot.fit.median / per if boot is not None and ok else math.nan
        rows.append(MethodAgainstCode(
            m.label, boot.probability_at(level) if boot is not None and ok else None, median,
            median / cap_lin, median / cap_non, median / cap_ec8))
    return CodeBeside(check, level, tuple(rows))
