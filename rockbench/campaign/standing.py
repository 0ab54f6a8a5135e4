"""A structure that cannot stand at rest: warned of before its runs, which then go on.

A parapet whose centre of mass overhangs its wall, or an arch thinner than its least
thickness, falls under its own weight: every engine reports it overturned whatever the
base does, which reads as a fragility or as an engine's fault. Limit analysis tells
beforehand (:func:`rockbench.analytic.stands`: no compressive, frictionally admissible
contact forces balance the weights), so :func:`warn_cannot_stand` says so, as a
:class:`~rockbench.errors.PlausibilityWarning`, once per structure.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterable

from rockbench.analytic import stands
from rockbench.errors import PlausibilityWarning
from rockbench.scenarios import Scenario

__all__ = ["warn_cannot_stand"]


def warn_cannot_stand(scenarios: Iterable[Scenario]) -> list[str]:
    """Warn of each structure among ``scenarios`` that cannot stand under its own weight.

    Centred stacks stand by construction (their builder refuses one that cannot); every
    other geometry is checked once, with the larger of the contact's two friction
    coefficients, so that a warning means no friction the scenario allows could hold it.

    Returns
    -------
    list of str
        The names of the scenarios warned of.
    """
    seen: set[int] = set()
    warned = []
    for sc in scenarios:
        col = sc.geometry.column
        if (col is not None and col.centred) or id(sc.geometry) in seen:
            continue
        seen.add(id(sc.geometry))
        mu = max(sc.contact.friction, sc.contact.block_friction)
        if not stands(sc.geometry, friction=mu, g=sc.g):
            warned.append(sc.name)
            warnings.warn(
                f"scenario {sc.name!r} cannot stand at rest under its own weight (limit "
                f"analysis finds no contact forces that balance it with friction {mu:g}): it "
                f"falls without any base motion, so its runs measure that fall",
                PlausibilityWarning, stacklevel=3)
    return warned
