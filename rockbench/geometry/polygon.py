"""Convex polygons in the x–z plane: validation, area and moments, rotation, contact.

Every body outline and support of a :class:`~rockbench.geometry.Geometry` is a
convex polygon given counter-clockwise (x to the right, z up). Rotations are
about +y, positive when a point above the centre moves toward +x (the sign of θ,
DESIGN.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from rockbench.errors import ScenarioError

__all__ = ["convex_polygon", "area_centroid", "second_moments", "rotate", "rotate_about",
           "contains", "penetration", "Edges", "face_contact"]


def _next(a: np.ndarray) -> np.ndarray:
    """The cyclic successor of each row (np.roll(a, -1, axis=0), without its overhead)."""
    return np.concatenate([a[1:], a[:1]])


def convex_polygon(vertices: ArrayLike, what: str) -> np.ndarray:
    """Validate a convex counter-clockwise polygon and return it as a read-only (n, 2) array.

    Raises
    ------
    ScenarioError
        Not an (n ≥ 3, 2) array of finite numbers, a repeated vertex, clockwise
        order or a reflex vertex; the message starts with ``what``.
    """
    try:
        v = np.array(vertices, dtype=float)
    except (TypeError, ValueError):
        raise ScenarioError(f"{what}: vertices must be an (n, 2) array of numbers") from None
    if v.ndim != 2 or v.shape[1] != 2 or v.shape[0] < 3:
        raise ScenarioError(f"{what}: vertices must have shape (n >= 3, 2), got {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ScenarioError(f"{what}: vertices must be finite")
    # absurd sizes overflow the products below: the checks then fail or pass as they may,
    # and the sizes themselves are judged elsewhere
    with np.errstate(over="ignore", invalid="ignore"):
        edges = _next(v) - v
        lengths = np.hypot(edges[:, 0], edges[:, 1])
        size = float(np.ptp(v, axis=0).max())
        area = 0.5 * float(np.sum(v[:, 0] * _next(v[:, 1]) - _next(v[:, 0]) * v[:, 1]))
        turn = edges[:, 0] * _next(edges[:, 1]) - edges[:, 1] * _next(edges[:, 0])
        reflex = np.any(turn < -1e-12 * size * size)
    if np.any(lengths <= 1e-12 * size):
        raise ScenarioError(f"{what}: repeated vertex (an edge of zero length)")
    if area <= 0:
        raise ScenarioError(f"{what}: vertices must be counter-clockwise in the x–z plane "
                            f"(signed area {area:.6g} <= 0)")
    if reflex:
        raise ScenarioError(f"{what}: polygon is not convex (vertex {int(np.argmin(turn)) + 1})")
    v.setflags(write=False)
    return v


def area_centroid(v: np.ndarray) -> tuple[float, np.ndarray]:
    """Area and centroid of a counter-clockwise polygon (shoelace)."""
    x, z = v[:, 0], v[:, 1]
    x1, z1 = _next(x), _next(z)
    cross = x * z1 - x1 * z
    area = 0.5 * float(cross.sum())
    c = np.array([float(((x + x1) * cross).sum()), float(((z + z1) * cross).sum())])
    return area, c / (6.0 * area)


def second_moments(v: np.ndarray) -> tuple[float, float, float]:
    """∫x² dA, ∫z² dA, ∫xz dA of a counter-clockwise polygon about the origin."""
    x, z = v[:, 0], v[:, 1]
    x1, z1 = np.roll(x, -1), np.roll(z, -1)
    cross = x * z1 - x1 * z
    ixx = float((cross * (x * x + x * x1 + x1 * x1)).sum()) / 12.0
    izz = float((cross * (z * z + z * z1 + z1 * z1)).sum()) / 12.0
    ixz = float((cross * (x * z1 + 2 * x * z + 2 * x1 * z1 + x1 * z)).sum()) / 24.0
    return ixx, izz, ixz


def rotate(points: ArrayLike, angle: float) -> np.ndarray:
    """Rotate (x, z) points about the origin by ``angle`` about +y (θ > 0: +z toward +x)."""
    c, s = math.cos(angle), math.sin(angle)
    p = np.asarray(points, dtype=float)
    return np.stack([p[..., 0] * c + p[..., 1] * s, -p[..., 0] * s + p[..., 1] * c], axis=-1)


def rotate_about(p: np.ndarray, angle: float, about: np.ndarray) -> np.ndarray:
    """Rotate points about +y by ``angle`` around ``about`` = (x, z)."""
    c, s = math.cos(angle), math.sin(angle)
    d = p - about
    return about + np.stack([d[..., 0] * c + d[..., 1] * s, -d[..., 0] * s + d[..., 1] * c],
                            axis=-1)


def contains(v: np.ndarray, p: np.ndarray) -> bool:
    """True if point ``p`` lies inside or on the counter-clockwise convex polygon ``v``."""
    e = _next(v) - v
    d = p - v
    return bool(np.all(e[:, 0] * d[:, 1] - e[:, 1] * d[:, 0] >= 0))


@dataclass(frozen=True)
class Edges:
    """Edge data of a convex counter-clockwise polygon."""

    start: np.ndarray  # (n, 2) first vertex of each edge
    tangent: np.ndarray  # (n, 2) unit direction
    normal: np.ndarray  # (n, 2) unit outward normal
    length: np.ndarray  # (n,)

    @classmethod
    def of(cls, v: np.ndarray) -> Edges:
        """The edges of polygon ``v``."""
        e = _next(v) - v
        length = np.hypot(e[:, 0], e[:, 1])
        t = e / length[:, None]
        return cls(v, t, np.stack([t[:, 1], -t[:, 0]], axis=1), length)


def penetration(a: np.ndarray, b: np.ndarray, ea: Edges | None = None,
                eb: Edges | None = None) -> float:
    """Depth by which two convex counter-clockwise polygons overlap (≤ 0: apart or touching).

    The smallest overlap of their projections over the edge normals of both
    (separating axis theorem); ``ea``, ``eb`` are their :class:`Edges` if known.
    """
    n = np.concatenate([(ea or Edges.of(a)).normal, (eb or Edges.of(b)).normal])
    pa, pb = a @ n.T, b @ n.T
    return float((np.minimum(pa.max(0), pb.max(0)) - np.maximum(pa.min(0), pb.min(0))).min())


def face_contact(eu: Edges, ev: Edges, tol: float) -> tuple[np.ndarray, ...] | None:
    """End points and normal (out of ``u``) of the collinear overlap of two edges, if any.

    Two convex polygons touch face to face where an edge of one is collinear
    with an edge of the other, the outward normals are opposite and the edges
    overlap over more than ``tol``; for convex polygons such a pair is unique.
    """
    # the edges of touching faces run opposite ways
    for i, j in zip(*np.nonzero(eu.tangent @ ev.tangent.T < -1.0 + 1e-9), strict=True):
        t, n, o = eu.tangent[i], eu.normal[i], eu.start[i]
        q0 = ev.start[j]
        q1 = q0 + ev.length[j] * ev.tangent[j]
        if abs((q0 - o) @ n) > tol or abs((q1 - o) @ n) > tol:
            continue
        s0, s1 = sorted(((q0 - o) @ t, (q1 - o) @ t))
        lo, hi = max(0.0, s0), min(eu.length[i], s1)
        if hi - lo > tol:
            return o + lo * t, o + hi * t, n
    return None
