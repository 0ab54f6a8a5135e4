"""The Pareto front of accuracy against cost (the one definition every study and figure uses)."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from typing import TypeVar

__all__ = ["pareto_front"]

T = TypeVar("T")


def pareto_front(points: Iterable[T], cost: Callable[[T], float],
                 error: Callable[[T], float]) -> list[T]:
    """The points no other point beats in both cost and error, cheapest first.

    A point belongs to the front when every cheaper (or equally cheap) point
    has a larger error; of points equal in both, the first given is kept.
    Points whose cost or error is not finite take no part.

    Parameters
    ----------
    points : iterable
        Anything; ``cost`` and ``error`` read the two coordinates (lower is better).
    cost, error : callable
        ``point → float``.

    Returns
    -------
    list
        The front, by increasing cost (and so decreasing error).
    """
    valid = [p for p in points if math.isfinite(cost(p)) and math.isfinite(error(p))]
    valid.sort(key=lambda p: (cost(p), error(p)))  # stable: ties keep their order
    front: list[T] = []
    best = math.inf
    for p in valid:
        if error(p) < best:
            front.append(p)
            best = error(p)
    return front
