"""Planar assemblies of rigid blocks for limit analysis: bodies, supports, contact interfaces.

The input of :mod:`rockbench.analytic.limit_analysis`, kept independent of the
Scenario so that any later Scenario assembly can be converted to it. Geometry
lives in the x–z plane (z up, DESIGN.md); every body is a convex polygon given
counter-clockwise, extruded over a depth along y.

Interfaces are found, not declared: two bodies touch where an edge of one is
collinear with an edge of the other, the two outward normals are opposite and
the edges overlap over a positive length (all within a length tolerance). For
convex bodies such a pair is unique, so each pair of bodies has at most one
interface, a straight segment with two end points.

Bodies are numbered blocks first, then supports: ``Assembly.bodies`` is
``blocks + supports`` and :class:`Interface` refers to bodies by that index.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from rockbench.errors import ScenarioError

if TYPE_CHECKING:
    from rockbench.scenarios import Stack

__all__ = [
    "PlanarBlock",
    "Support",
    "Interface",
    "Assembly",
    "block_stack",
    "assembly_from_stack",
    "semicircular_arch",
]

#: Default length tolerance of contact detection, relative to the assembly's size.
RTOL = 1e-7


def _next(a: np.ndarray) -> np.ndarray:
    """The cyclic successor of each row (np.roll(a, -1, axis=0), without its overhead)."""
    return np.concatenate([a[1:], a[:1]])


def _polygon(vertices: ArrayLike, what: str) -> np.ndarray:
    """Validate a convex counter-clockwise polygon and return it as a read-only (n, 2) array."""
    try:
        v = np.array(vertices, dtype=float)
    except (TypeError, ValueError):
        raise ScenarioError(f"{what}: vertices must be an (n, 2) array of numbers") from None
    if v.ndim != 2 or v.shape[1] != 2 or v.shape[0] < 3:
        raise ScenarioError(f"{what}: vertices must have shape (n >= 3, 2), got {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ScenarioError(f"{what}: vertices must be finite")
    edges = _next(v) - v
    lengths = np.hypot(edges[:, 0], edges[:, 1])
    size = float(np.ptp(v, axis=0).max())
    if np.any(lengths <= 1e-12 * size):
        raise ScenarioError(f"{what}: repeated vertex (an edge of zero length)")
    area = 0.5 * float(np.sum(v[:, 0] * _next(v[:, 1]) - _next(v[:, 0]) * v[:, 1]))
    if area <= 0:
        raise ScenarioError(f"{what}: vertices must be counter-clockwise in the x–z plane "
                            f"(signed area {area:.6g} <= 0)")
    turn = edges[:, 0] * _next(edges[:, 1]) - edges[:, 1] * _next(edges[:, 0])
    if np.any(turn < -1e-12 * size * size):
        raise ScenarioError(f"{what}: polygon is not convex (vertex {int(np.argmin(turn)) + 1})")
    v.setflags(write=False)
    return v


def _area_centroid(v: np.ndarray) -> tuple[float, np.ndarray]:
    """Area and centroid of a counter-clockwise polygon (shoelace)."""
    x, z = v[:, 0], v[:, 1]
    x1, z1 = _next(x), _next(z)
    cross = x * z1 - x1 * z
    area = 0.5 * float(cross.sum())
    c = np.array([float(((x + x1) * cross).sum()), float(((z + z1) * cross).sum())])
    return area, c / (6.0 * area)


def _positive(value: float, what: str) -> float:
    v = float(value)
    if not (math.isfinite(v) and v > 0):
        raise ScenarioError(f"{what} must be finite and > 0, got {value!r}")
    return v


def _rotate(p: np.ndarray, angle: float, about: np.ndarray) -> np.ndarray:
    """Rotate points about +y by ``angle``: θ > 0 moves a point above ``about`` toward +x."""
    c, s = math.cos(angle), math.sin(angle)
    d = p - about
    return about + np.stack([d[..., 0] * c + d[..., 1] * s, -d[..., 0] * s + d[..., 1] * c],
                            axis=-1)


@dataclass(frozen=True, eq=False)
class PlanarBlock:
    """A rigid convex prism: a polygon in the x–z plane extruded over ``depth`` along y.

    Parameters
    ----------
    vertices : array_like (n, 2)
        Corners (x, z) in m, counter-clockwise seen with x to the right and z up,
        convex.
    depth : float
        Size along y (m).
    density : float, optional
        kg/m³; mass = density · area · depth. Give exactly one of ``density``
        and ``mass``.
    mass : float, optional
        kg.
    centroid : array_like (2,), optional
        Centre of gravity (x, z) if it is not the polygon's centroid (e.g. a
        voussoir whose curved intrados is drawn as a chord); must lie inside
        the polygon.

    Notes
    -----
    After construction ``mass`` and ``centroid`` are always set (computed
    from the polygon when not given). Like every class here that holds arrays,
    blocks compare by identity.
    """

    vertices: np.ndarray
    depth: float = 1.0
    density: float | None = None
    mass: float | None = None
    centroid: np.ndarray | None = None

    def __post_init__(self) -> None:
        v = _polygon(self.vertices, "block")
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "depth", _positive(self.depth, "block depth"))
        if (self.density is None) == (self.mass is None):
            raise ScenarioError("block needs exactly one of 'density' and 'mass'")
        area, c = _area_centroid(v)
        if self.density is not None:
            rho = _positive(self.density, "block density")
            object.__setattr__(self, "density", rho)
            object.__setattr__(self, "mass", rho * area * self.depth)
        else:
            object.__setattr__(self, "mass", _positive(self.mass, "block mass"))  # type: ignore[arg-type]
        if self.centroid is not None:
            c = np.array(self.centroid, dtype=float)
            if c.shape != (2,) or not np.all(np.isfinite(c)):
                raise ScenarioError(f"block centroid must be two finite numbers, got "
                                    f"{self.centroid!r}")
            if not _inside(v, c):
                raise ScenarioError(f"block centroid {c.tolist()} lies outside its polygon")
        c.setflags(write=False)
        object.__setattr__(self, "centroid", c)

    @classmethod
    def rectangle(cls, width: float, height: float, center: Sequence[float] = (0.0, 0.0), *,
                  depth: float = 1.0, density: float | None = None,
                  mass: float | None = None) -> PlanarBlock:
        """An axis-aligned rectangle ``width`` × ``height`` centred at ``center`` = (x, z)."""
        b = 0.5 * _positive(width, "block width")
        h = 0.5 * _positive(height, "block height")
        x, z = (float(c) for c in center)
        return cls(np.array([[x - b, z - h], [x + b, z - h], [x + b, z + h], [x - b, z + h]]),
                   depth=depth, density=density, mass=mass)

    @property
    def area(self) -> float:
        """Area of the polygon (m²)."""
        return _area_centroid(self.vertices)[0]

    def rotated(self, angle: float, about: Sequence[float] = (0.0, 0.0)) -> PlanarBlock:
        """The block rotated rigidly about +y by ``angle`` (rad) around ``about`` = (x, z)."""
        o = np.asarray(about, dtype=float)
        return PlanarBlock(_rotate(self.vertices, angle, o), self.depth, mass=self.mass,
                           centroid=_rotate(self.centroid, angle, o))  # type: ignore[arg-type]


@dataclass(frozen=True, eq=False)
class Support:
    """A fixed convex polygon (the ground, a wall top, an abutment) in the x–z plane.

    Parameters
    ----------
    vertices : array_like (n, 2)
        Corners (x, z) in m, counter-clockwise, convex.
    """

    vertices: np.ndarray

    def __post_init__(self) -> None:
        object.__setattr__(self, "vertices", _polygon(self.vertices, "support"))

    @classmethod
    def ground(cls, x_min: float, x_max: float, z: float = 0.0) -> Support:
        """The ground: a slab whose top face spans [x_min, x_max] at height ``z``."""
        if not x_max > x_min:
            raise ScenarioError(f"ground needs x_max > x_min, got [{x_min}, {x_max}]")
        d = x_max - x_min
        return cls(np.array([[x_min, z - d], [x_max, z - d], [x_max, z], [x_min, z]]))

    def rotated(self, angle: float, about: Sequence[float] = (0.0, 0.0)) -> Support:
        """The support rotated rigidly about +y by ``angle`` (rad) around ``about``."""
        return Support(_rotate(self.vertices, angle, np.asarray(about, dtype=float)))


@dataclass(frozen=True, eq=False)
class Interface:
    """A straight contact segment between two bodies of an :class:`Assembly`.

    Attributes
    ----------
    a, b : int
        Indices into ``Assembly.bodies`` (blocks first, then supports), ``a < b``.
    p0, p1 : ndarray (2,)
        End points (x, z) of the contact segment (m); ``p1 − p0`` points along
        :attr:`tangent`.
    normal : ndarray (2,)
        Unit normal, outward from body ``a``, i.e. pointing into body ``b``.
    """

    a: int
    b: int
    p0: np.ndarray
    p1: np.ndarray
    normal: np.ndarray

    @property
    def tangent(self) -> np.ndarray:
        """Unit tangent: the normal turned by +90° in the (x, z) plane, (−n_z, n_x)."""
        return np.array([-self.normal[1], self.normal[0]])

    @property
    def length(self) -> float:
        """Length of the contact segment (m)."""
        return float(np.hypot(*(self.p1 - self.p0)))

    @property
    def points(self) -> np.ndarray:
        """The two end points, shape (2, 2)."""
        return np.stack([self.p0, self.p1])


def _inside(v: np.ndarray, p: np.ndarray) -> bool:
    e = _next(v) - v
    d = p - v
    return bool(np.all(e[:, 0] * d[:, 1] - e[:, 1] * d[:, 0] >= 0))


@dataclass(frozen=True)
class _Edges:
    """Edge data of a convex counter-clockwise polygon."""

    start: np.ndarray  # (n, 2) first vertex of each edge
    tangent: np.ndarray  # (n, 2) unit direction
    normal: np.ndarray  # (n, 2) unit outward normal
    length: np.ndarray  # (n,)

    @classmethod
    def of(cls, v: np.ndarray) -> _Edges:
        e = _next(v) - v
        length = np.hypot(e[:, 0], e[:, 1])
        t = e / length[:, None]
        return cls(v, t, np.stack([t[:, 1], -t[:, 0]], axis=1), length)


def _penetration(u: np.ndarray, v: np.ndarray, eu: _Edges, ev: _Edges) -> float:
    """Smallest overlap of two convex polygons over their edge normals (≤ 0: disjoint/touching)."""
    n = np.concatenate([eu.normal, ev.normal])
    pu, pv = u @ n.T, v @ n.T
    overlap = np.minimum(pu.max(0), pv.max(0)) - np.maximum(pu.min(0), pv.min(0))
    return float(overlap.min())


def _contact(eu: _Edges, ev: _Edges, tol: float) -> tuple[np.ndarray, ...] | None:
    """End points and normal (out of ``u``) of the collinear overlap of two edges, if any."""
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


@dataclass(frozen=True, eq=False)
class Assembly:
    """Rigid blocks resting on fixed supports, with the contact interfaces between them.

    Parameters
    ----------
    blocks : sequence of PlanarBlock
        The movable bodies.
    supports : sequence of Support
        Fixed bodies; at least one (usually :meth:`Support.ground`).
    rtol : float
        Length tolerance of contact detection and of the overlap check, as a
        fraction of the assembly's size (the largest extent of its blocks).

    Attributes
    ----------
    interfaces : tuple of Interface
        Found automatically, ordered by (a, b).

    Raises
    ------
    ScenarioError
        (a ValueError) no blocks or no supports, overlapping bodies, a block
        not connected to a support through interfaces.
    """

    blocks: tuple[PlanarBlock, ...]
    supports: tuple[Support, ...]
    rtol: float = RTOL
    interfaces: tuple[Interface, ...] = field(init=False)

    def __post_init__(self) -> None:
        blocks, supports = tuple(self.blocks), tuple(self.supports)
        if not blocks or not all(isinstance(b, PlanarBlock) for b in blocks):
            raise ScenarioError("an assembly needs at least one PlanarBlock")
        if not supports or not all(isinstance(s, Support) for s in supports):
            raise ScenarioError("an assembly needs at least one Support (e.g. Support.ground)")
        object.__setattr__(self, "blocks", blocks)
        object.__setattr__(self, "supports", supports)
        rtol = _positive(self.rtol, "assembly rtol")
        tol = rtol * self.size
        polys = [body.vertices for body in self.bodies]
        edges = [_Edges.of(p) for p in polys]
        lo = np.array([p.min(0) for p in polys]) - tol
        hi = np.array([p.max(0) for p in polys]) + tol
        near = np.all((lo[:, None, :] <= hi[None, :, :]) & (lo[None, :, :] <= hi[:, None, :]),
                      axis=2)
        found: list[Interface] = []
        for a, b in zip(*np.nonzero(np.triu(near, 1)), strict=True):
            if a >= len(blocks):
                continue  # supports do not interact
            a, b = int(a), int(b)
            depth = _penetration(polys[a], polys[b], edges[a], edges[b])
            if depth > tol:
                raise ScenarioError(f"bodies {self.describe(a)} and {self.describe(b)} "
                                    f"overlap by {depth:.3g} m")
            hit = _contact(edges[a], edges[b], tol)
            if hit is not None:
                found.append(Interface(a, b, *hit))
        for itf in found:
            for arr in (itf.p0, itf.p1, itf.normal):
                arr.setflags(write=False)
        object.__setattr__(self, "interfaces", tuple(found))
        self._check_supported()

    def _check_supported(self) -> None:
        nb = len(self.blocks)
        reached = set(range(nb, nb + len(self.supports)))
        grew = True
        while grew:
            grew = False
            for itf in self.interfaces:
                if (itf.a in reached) != (itf.b in reached):
                    reached |= {itf.a, itf.b}
                    grew = True
        loose = [i for i in range(nb) if i not in reached]
        if loose:
            raise ScenarioError(f"block(s) {loose} touch no support, directly or through "
                                f"other blocks")

    @property
    def bodies(self) -> tuple[PlanarBlock | Support, ...]:
        """Blocks, then supports: the numbering of :class:`Interface`."""
        return self.blocks + self.supports

    @property
    def n_blocks(self) -> int:
        """Number of movable blocks."""
        return len(self.blocks)

    @property
    def size(self) -> float:
        """Largest extent of the blocks along x or z (m): the length scale."""
        v = np.concatenate([b.vertices for b in self.blocks])
        return float(np.ptp(v, axis=0).max())

    def is_support(self, body: int) -> bool:
        """True if ``body`` (an index into :attr:`bodies`) is a support."""
        return body >= len(self.blocks)

    def describe(self, body: int) -> str:
        """``"block i"`` or ``"support j"`` for a body index."""
        nb = len(self.blocks)
        return f"support {body - nb}" if body >= nb else f"block {body}"

    def rotated(self, angle: float, about: Sequence[float] = (0.0, 0.0)) -> Assembly:
        """Every body rotated about +y by ``angle`` (rad): the assembly on a tilted table.

        Tilting by ``angle`` > 0 leans the assembly toward +x, which for the
        blocks is gravity plus a horizontal load toward +x of ``tan(angle)``
        times their weight (scaled by cos(angle)).
        """
        return Assembly(tuple(b.rotated(angle, about) for b in self.blocks),
                        tuple(s.rotated(angle, about) for s in self.supports), self.rtol)


def block_stack(sizes: Iterable[tuple[float, float]], offsets: Sequence[float] | None = None, *,
                depth: float = 1.0, density: float = 2000.0) -> Assembly:
    """Rectangular blocks stacked on the ground, bottom first.

    Parameters
    ----------
    sizes : iterable of (width, height)
        Block sizes (m), bottom first.
    offsets : sequence of float, optional
        x of each block's centre (m); default all 0 (centred).
    depth, density : float
        Common depth (m) and density (kg/m³).
    """
    sizes = [(float(w), float(h)) for w, h in sizes]
    xs = [0.0] * len(sizes) if offsets is None else [float(o) for o in offsets]
    if len(xs) != len(sizes):
        raise ScenarioError(f"block_stack: {len(xs)} offsets for {len(sizes)} blocks")
    blocks, z = [], 0.0
    for (w, h), x in zip(sizes, xs, strict=True):
        blocks.append(PlanarBlock.rectangle(w, h, (x, z + 0.5 * h), depth=depth, density=density))
        z += h
    reach = max(abs(x) + 0.5 * w for (w, _), x in zip(sizes, xs, strict=True))
    return Assembly(tuple(blocks), (Support.ground(-2 * reach, 2 * reach),))


def assembly_from_stack(stack: Stack) -> Assembly:
    """The limit-analysis assembly of a Scenario :class:`~rockbench.scenarios.Stack`.

    Each block keeps its outline (chamfers included, so contacts end at the
    pivots ``b − chamfer``), its depth and its mass (that of the uncut box, as
    in the rocking models); the ground is the only support.
    """
    blocks = [
        PlanarBlock(b.profile() + c, b.depth, mass=b.m)
        for b, c in zip(stack.blocks, stack.centroids, strict=True)
    ]
    reach = max(float(np.abs(b.vertices[:, 0]).max()) for b in blocks)
    return Assembly(tuple(blocks), (Support.ground(-2 * reach, 2 * reach),))


def semicircular_arch(n: int, thickness: float, radius: float = 1.0, *, depth: float = 1.0,
                      density: float = 2000.0, arc_points: int = 4) -> Assembly:
    """A semicircular arch of ``n`` equal voussoirs with radial joints on two fixed supports.

    The centre of the mean circle is the origin; the springings lie on z = 0
    and each rests on a support below it. Each voussoir is an annular sector
    of mean radius ``radius`` and ``thickness``: its mass and centre of gravity
    are the sector's exactly; its polygon replaces the (concave) intrados arc by
    its chord and the extrados arc by ``arc_points`` chords, so that it is
    convex and its joints are exact.
    """
    if int(n) != n or n < 1:
        raise ScenarioError(f"an arch needs n >= 1 voussoirs, got {n!r}")
    r = _positive(radius, "arch radius")
    t = _positive(thickness, "arch thickness")
    if t >= 2 * r:
        raise ScenarioError(f"arch thickness {t} must be smaller than twice the radius {r}")
    ri, re = r - 0.5 * t, r + 0.5 * t
    dth = math.pi / n
    # centroid radius of an annular sector of angle dth
    rg = (2.0 / 3.0) * (re**3 - ri**3) / (re**2 - ri**2) * math.sin(0.5 * dth) / (0.5 * dth)
    mass = density * depth * r * t * dth
    blocks = []
    for k in range(n):
        a0, a1 = k * dth, (k + 1) * dth
        arc = np.linspace(a0, a1, arc_points + 1)
        pts = [(ri * math.cos(a0), ri * math.sin(a0))]
        pts += [(re * math.cos(a), re * math.sin(a)) for a in arc]
        pts.append((ri * math.cos(a1), ri * math.sin(a1)))
        am = 0.5 * (a0 + a1)
        blocks.append(PlanarBlock(np.array(pts), depth, mass=mass,
                                  centroid=np.array([rg * math.cos(am), rg * math.sin(am)])))
    # springings sit exactly on z = 0 (sin π is not 0 in floating point)
    for k in (0, n - 1):
        v = blocks[k].vertices.copy()
        v[np.abs(v[:, 1]) < 1e-12 * r, 1] = 0.0
        blocks[k] = PlanarBlock(v, depth, mass=mass, centroid=blocks[k].centroid)
    pad = t
    supports = (
        Support(np.array([[ri - pad, -t], [re + pad, -t], [re + pad, 0.0], [ri - pad, 0.0]])),
        Support(np.array([[-re - pad, -t], [-ri + pad, -t], [-ri + pad, 0.0],
                          [-re - pad, 0.0]])),
    )
    return Assembly(tuple(blocks), supports)
