"""The critical angle λ that every result is normalised by, and the uplift ratio.

λ is the tilting-table angle atan(α) of a geometry's first rocking mechanism
(no sliding): for one block or two centred stacked blocks the closed form of
:meth:`rockbench.geometry.Column.critical_angle` (each block's own angle on
its support and the stack's as one body), for any other geometry the
limit-analysis collapse factor α with μ = ∞, the smaller of the two
directions (:func:`~rockbench.analytic.static_collapse.limit_analysis`).
It is a unit, not the collapse angle where friction matters: a running-bond
wall gets atan 1.0 here and collapses at atan(11/19) with real Coulomb joints.
"""

from __future__ import annotations

import functools
import math

from rockbench.analytic.static_collapse import limit_analysis
from rockbench.geometry import Geometry
from rockbench.scenarios import Scenario

__all__ = ["critical_angle", "uplift_ratio"]


@functools.lru_cache(maxsize=256)
def critical_angle(geometry: Geometry) -> float:
    """λ of ``geometry`` in rad (module docstring)."""
    col = geometry.column
    if col is not None and len(col) <= 2 and col.centred:
        return col.critical_angle()
    alphas = [r.load_factor for r in (limit_analysis(geometry, direction=d) for d in (1, -1))
              if r.status == "collapse"]
    if alphas:
        return math.atan(min(alphas))
    return min(math.atan2(0.5 * b.width, 0.5 * b.height) for b in geometry.bodies)


def uplift_ratio(scenario: Scenario) -> float:
    """Peak horizontal base acceleration over the static uplift threshold g · tan λ."""
    return scenario.motion.peak_acceleration(scenario.duration) / (
        scenario.g * math.tan(critical_angle(scenario.geometry)))
