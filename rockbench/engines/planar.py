"""What a planar (x–z) engine may build: the geometry fields known to be in the plane.

A 2D engine models every field of today's geometry model; a field it does not know (one
a subclass adds, e.g. for 3D content) is refused when it is set rather than silently
ignored: :func:`refuse_out_of_plane`.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from rockbench.errors import UnsupportedScenario
from rockbench.geometry import Block, Geometry, Prism, Support

__all__ = ["PLANAR_FIELDS", "refuse_out_of_plane"]

#: The fields of each geometry type that a planar engine models.
PLANAR_FIELDS: dict[type, frozenset[str]] = {
    Block: frozenset({"width", "depth", "height", "density", "mass", "chamfer"}),
    Prism: frozenset({"vertices", "depth", "density", "mass", "centre_of_gravity",
                      "_centroid", "_area", "_moments"}),
    Support: frozenset({"vertices"}),
    Geometry: frozenset({"bodies", "poses", "supports", "base", "_centroids", "_interfaces"}),
}


def _is_set(value: Any) -> bool:
    """True for a field value that differs from an empty/zero default."""
    try:
        return bool(np.any(np.asarray(value, dtype=float) != 0.0))
    except (TypeError, ValueError):
        return bool(value)


def refuse_out_of_plane(engine: str, geometry: Geometry) -> None:
    """Raise :class:`UnsupportedScenario` if ``geometry`` sets a field not in
    :data:`PLANAR_FIELDS` (on itself, a body or a support), naming ``engine``."""
    for obj in (geometry, *geometry.bodies, *geometry.supports):
        known = next((v for k, v in PLANAR_FIELDS.items() if isinstance(obj, k)), frozenset())
        for f in dataclasses.fields(obj):
            if f.name not in known and _is_set(getattr(obj, f.name)):
                raise UnsupportedScenario(
                    f"{engine} is a 2D engine (x–z plane); {type(obj).__name__}.{f.name} "
                    "may describe out-of-plane content, which it cannot model")
