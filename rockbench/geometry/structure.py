"""One geometry for every scene: rigid bodies at poses on the base and on fixed supports.

A :class:`Geometry` is what rocks: bodies (:class:`~rockbench.geometry.bodies.Block`,
:class:`~rockbench.geometry.bodies.Prism`) each placed at a pose (x, z, angle) in
the x–z plane, resting on the base (the plane z = 0) and on fixed convex
supports that move with the base. Its construction finds the contacts at rest
(:class:`Interface`: face-to-face, a segment with two end points) and refuses
overlapping bodies and bodies that no chain of face contacts ties to the base
or a support. A single block, a stack, a column of drums, a parapet on a wall,
a running-bond wall and an arch are all geometries
(:mod:`rockbench.geometry.builders`).

Bodies are numbered bodies first, then supports, then the base
(:attr:`Geometry.fixed` holds the supports and the base as a ground slab);
:class:`Interface` refers to them by that index.

Where a geometry is a :class:`Column` (rectangular blocks, upright, each on the
one below, the bottom one on the base, no supports) the closed-form rocking
models apply; :attr:`Geometry.column` gives that view, or None.

Poses: a :class:`~rockbench.geometry.bodies.Block` is placed by its centroid
(x, z) and angle; a :class:`~rockbench.geometry.bodies.Prism` by the frame its
vertices are given in: world point = (x, z) + R(angle) · vertex, with R the
rotation about +y (θ > 0 turns the top toward +x).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np

from rockbench import checks
from rockbench.errors import ScenarioError
from rockbench.geometry.bodies import Block, Body, Cylinder, Prism, Support, Upright
from rockbench.geometry.polygon import Edges, face_contact, penetration, rotate
from rockbench.geometry.rocking import RockingProperties, rocking_about

__all__ = ["Geometry", "Interface", "Column", "Pose", "RTOL"]

#: (x, z, angle) of a body's frame: m, m, rad about +y.
Pose = tuple[float, float, float]

#: Length tolerance of contact detection, relative to the geometry's size.
RTOL = 1e-7


@dataclass(frozen=True, eq=False)
class Interface:
    """A straight contact segment at rest between two bodies of a :class:`Geometry`.

    Attributes
    ----------
    a, b : int
        Indices of the two bodies (bodies, then supports, then the base), ``a < b``.
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


def _pose(p: Any, i: int) -> Pose:
    if not isinstance(p, (list, tuple)) or len(p) != 3:
        raise ScenarioError(f"block #{i} pose must be (x, z, angle), got {checks.describe(p)}")
    x = checks.coordinate(p[0], f"block #{i} x")
    z = checks.coordinate(p[1], f"block #{i} z")
    a = checks.number(p[2], f"block #{i} angle", unit="rad")
    if not abs(a) < 0.5 * math.pi:
        raise ScenarioError(f"block #{i} angle must be within (-π/2, π/2) rad, got {a!r}: "
                            f"describe a block turned further with its sides swapped")
    return x, z, a


@dataclass(frozen=True)
class Geometry:
    """Rigid bodies at given poses on the base (z = 0) and on fixed supports.

    Parameters
    ----------
    bodies : sequence of Block, Prism or Cylinder
        The movable bodies (bottom first for a stack).
    poses : sequence of (x, z, angle)
        One per body: a Block's centroid and orientation, a Prism's frame
        (module docstring). |angle| < π/2 (a body turned further is the same
        body described with its sides swapped).
    supports : sequence of Support
        Fixed bodies besides the base.
    base : bool
        Whether the base plane z = 0 carries bodies (every scene an engine runs
        has it; :meth:`rotated` turns it into a tilted support).

    Raises
    ------
    ScenarioError
        Bad values, overlapping bodies, or a body that no face-to-face contact
        chain connects to the base or a support.
    """

    bodies: tuple[Body, ...]
    poses: tuple[Pose, ...]
    supports: tuple[Support, ...] = ()
    base: bool = True
    _centroids: np.ndarray = field(init=False, repr=False, compare=False)
    _interfaces: tuple[Interface, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        bodies, supports = tuple(self.bodies), tuple(self.supports)
        if not bodies:
            raise ScenarioError("a geometry needs at least one block")
        if not all(isinstance(b, (Block, Prism, Cylinder)) for b in bodies):
            raise ScenarioError("geometry bodies must be Block, Prism or Cylinder instances")
        if not all(isinstance(s, Support) for s in supports):
            raise ScenarioError("geometry supports must be Support instances")
        poses = tuple(self.poses)
        if len(poses) != len(bodies):
            raise ScenarioError(f"a geometry needs one pose per block: {len(poses)} poses for "
                                f"{len(bodies)} blocks")
        if not (self.base or supports):
            raise ScenarioError("a geometry without the base needs a support")
        checked = tuple(_pose(p, i) for i, p in enumerate(poses, 1))
        object.__setattr__(self, "bodies", bodies)
        object.__setattr__(self, "poses", checked)
        object.__setattr__(self, "supports", supports)
        object.__setattr__(self, "base", bool(self.base))
        cents = [np.array([x, z]) + rotate(b.centroid, a) if isinstance(b, Prism)
                 else np.array([x, z]) for b, (x, z, a) in zip(bodies, checked, strict=True)]
        c = np.array(cents)
        c.setflags(write=False)
        object.__setattr__(self, "_centroids", c)
        try:
            object.__setattr__(self, "_interfaces", self._find_interfaces())
        except ScenarioError as exc:
            nb, ns = len(bodies), len(supports)
            base = f"; support {ns} is the base, z <= 0" if self.base else ""
            raise ScenarioError(
                f"geometry: {exc} (blocks 0..{nb - 1} and supports 0..{ns - 1} in the order "
                f"given{base})") from None

    # ------------------------------------------------------------------ contacts at rest
    def _find_interfaces(self) -> tuple[Interface, ...]:
        tol = RTOL * self.size
        nb = len(self.bodies)
        polys = [self.world_vertices(i) for i in range(nb)] + [s.array for s in self.fixed]
        edges = [Edges.of(p) for p in polys]
        lo = np.array([p.min(0) for p in polys]) - tol
        hi = np.array([p.max(0) for p in polys]) + tol
        near = np.all((lo[:, None, :] <= hi[None, :, :]) & (lo[None, :, :] <= hi[:, None, :]),
                      axis=2)
        found: list[Interface] = []
        for a, b in zip(*np.nonzero(np.triu(near, 1)), strict=True):
            if a >= nb:
                continue  # fixed bodies do not interact
            a, b = int(a), int(b)
            depth = penetration(polys[a], polys[b], edges[a], edges[b])
            if depth > tol:
                raise ScenarioError(f"bodies {self.describe(a)} and {self.describe(b)} "
                                    f"overlap by {depth:.3g} m")
            hit = face_contact(edges[a], edges[b], tol)
            if hit is not None:
                for arr in hit:
                    arr.setflags(write=False)
                found.append(Interface(a, b, *hit))
        reached = set(range(nb, nb + len(self.fixed)))
        grew = True
        while grew:
            grew = False
            for itf in found:
                if (itf.a in reached) != (itf.b in reached):
                    reached |= {itf.a, itf.b}
                    grew = True
        loose = [i for i in range(nb) if i not in reached]
        if loose:
            raise ScenarioError(f"block(s) {loose} touch no support, directly or through "
                                f"other blocks")
        return tuple(found)

    @property
    def interfaces(self) -> tuple[Interface, ...]:
        """The face-to-face contacts at rest, ordered by (a, b)."""
        return self._interfaces

    # ------------------------------------------------------------------ bodies
    def __len__(self) -> int:
        return len(self.bodies)

    @property
    def n_bodies(self) -> int:
        """Number of movable bodies."""
        return len(self.bodies)

    @property
    def centroids(self) -> np.ndarray:
        """World centre of gravity (x, z) of each body at rest, shape (n, 2) (m)."""
        return self._centroids.copy()

    @property
    def angles(self) -> np.ndarray:
        """Orientation of each body about +y at rest (rad), shape (n,)."""
        return np.array([p[2] for p in self.poses])

    @property
    def masses(self) -> np.ndarray:
        """Mass of each body (kg), shape (n,)."""
        return np.array([b.m for b in self.bodies])

    def world_vertices(self, i: int) -> np.ndarray:
        """Corners of body ``i`` in world coordinates at rest, counter-clockwise, (k, 2)."""
        b = self.bodies[i]
        return self._centroids[i] + rotate(b.profile(), self.poses[i][2])

    @property
    def total_height(self) -> float:
        """Height of the highest body corner above the base (m); a column's is the sum of
        its blocks' heights."""
        if self.column is not None:
            return self.column.height
        return max(float(self.world_vertices(i)[:, 1].max()) for i in range(len(self.bodies)))

    @property
    def size(self) -> float:
        """Largest extent of the bodies together along x or z (m): the scene's length scale."""
        v = np.concatenate([self.world_vertices(i) for i in range(len(self.bodies))])
        return float(np.ptp(v, axis=0).max())

    @property
    def reach(self) -> float:
        """Largest |x| of any body or support corner (m)."""
        pts = [self.world_vertices(i) for i in range(len(self.bodies))]
        pts += [s.array for s in self.supports]
        return float(np.abs(np.concatenate(pts)[:, 0]).max())

    @property
    def room(self) -> float:
        """Horizontal room (m) a scene needs beyond its height and widest body.

        A column topples within its height and width; any other geometry also
        spreads over its reach and size.
        """
        return 0.0 if self.column is not None else self.reach + self.size

    # ------------------------------------------------------------------ fixed bodies
    @functools.cached_property
    def fixed(self) -> tuple[Support, ...]:
        """The supports, then the base as a ground slab (when the geometry has it)."""
        if not self.base:
            return self.supports
        reach = 2.0 * max(self.reach, self.size)
        return self.supports + (Support.ground(-reach, reach),)

    @property
    def all_bodies(self) -> int:
        """Number of bodies, supports and base: the range of :class:`Interface` indices."""
        return len(self.bodies) + len(self.fixed)

    def is_fixed(self, k: int) -> bool:
        """True if index ``k`` (bodies, then supports, then the base) is a fixed body."""
        return k >= len(self.bodies)

    def describe(self, k: int) -> str:
        """``"block i"``, ``"support j"`` or ``"the base"`` for an index (numbered from 0)."""
        nb = len(self.bodies)
        if k < nb:
            return f"block {k}"
        if self.base and k == nb + len(self.supports):
            return "the base"
        return f"support {k - nb}"

    # ------------------------------------------------------------------ columns
    @functools.cached_property
    def column(self) -> Column | None:
        """This geometry as a :class:`Column`, or None where it is not one."""
        nb = len(self.bodies)
        if self.supports or not self.base or any(a != 0.0 for _, _, a in self.poses):
            return None
        if not all(isinstance(b, (Block, Cylinder)) for b in self.bodies):
            return None
        base = nb  # the ground slab follows the bodies (no supports)
        pairs = {(i.a, i.b) for i in self.interfaces}
        if pairs != {(0, base)} | {(k - 1, k) for k in range(1, nb)}:
            return None
        return Column(self)

    # ------------------------------------------------------------------ transforms
    def mirrored(self) -> Geometry:
        """The mirror image in the plane x = 0 (for symmetry checks)."""
        return Geometry(tuple(b.mirrored() for b in self.bodies),
                        tuple((-x, z, -a) for x, z, a in self.poses),
                        tuple(s.mirrored() for s in self.supports), self.base)

    def rotated(self, angle: float, about: Sequence[float] = (0.0, 0.0)) -> Geometry:
        """Every body and support rotated about +y by ``angle`` (rad) around ``about``.

        The base becomes a support (the tilted ground slab): the geometry on a
        tilted table, for static checks. Tilting by ``angle`` > 0 leans it toward
        +x, which for the bodies is gravity plus a horizontal load toward +x of
        ``tan(angle)`` times their weight (scaled by cos(angle)).
        """
        o = np.asarray(about, dtype=float)
        c, s = math.cos(angle), math.sin(angle)
        poses = []
        for (x, z, a) in self.poses:
            dx, dz = x - o[0], z - o[1]
            poses.append((o[0] + dx * c + dz * s, o[1] - dx * s + dz * c, a + angle))
        return Geometry(self.bodies, tuple(poses),
                        tuple(f.rotated(angle, about) for f in self.fixed), base=False)


@dataclass(frozen=True, eq=False)
class Column:
    """A geometry of upright blocks or cylinders, each on the one below, the bottom on the base.

    The view the closed-form rocking models read (stacks of the paper, drum
    columns, a parapet on its wall).

    Parameters
    ----------
    geometry : Geometry
        The geometry (its :attr:`Geometry.column`).
    """

    geometry: Geometry

    @property
    def blocks(self) -> tuple[Upright, ...]:
        """The blocks (or drums), bottom first."""
        # every body is a Block or a Cylinder: Geometry.column builds a Column only then
        return cast("tuple[Upright, ...]", self.geometry.bodies)

    def __len__(self) -> int:
        return len(self.geometry.bodies)

    @property
    def offsets(self) -> tuple[float, ...]:
        """Horizontal position of each block's centre (m)."""
        return tuple(p[0] for p in self.geometry.poses)

    @property
    def height(self) -> float:
        """Sum of the blocks' heights (m)."""
        return sum(b.height for b in self.blocks)

    @property
    def centred(self) -> bool:
        """True when every block is centred on x = 0."""
        return not any(self.offsets)

    @property
    def centroids(self) -> np.ndarray:
        """Upright centroid (x, z) of each block, shape (n, 2)."""
        return self.geometry.centroids

    def monolithic(self, g: float = 9.81) -> RockingProperties:
        """Rocking constants of the whole column rocking as one body on the bottom pivots."""
        blocks = self.blocks
        ms = np.array([b.m for b in blocks])
        c = self.centroids
        m = ms.sum()
        xbar = float(ms @ c[:, 0] / m)
        zbar = float(ms @ c[:, 1] / m)
        i_c = sum(b.inertia[1] for b in blocks) + float(
            ms @ ((c[:, 0] - xbar) ** 2 + (c[:, 1] - zbar) ** 2)
        )
        return rocking_about(m, blocks[0].pivot_half_width, zbar, i_c, g)

    def overlap(self, i: int) -> tuple[float, float]:
        """World x (m) of the left and right pivots between block ``i`` (i ≥ 1) and the
        block below it: the shared part of their faces (chamfers taken off)."""
        lo, up = self.blocks[i - 1], self.blocks[i]
        o_lo, o_up = self.offsets[i - 1], self.offsets[i]
        return (max(o_lo - lo.pivot_half_width, o_up - up.pivot_half_width),
                min(o_lo + lo.pivot_half_width, o_up + up.pivot_half_width))

    def interface(self, i: int, g: float = 9.81) -> RockingProperties:
        """Rocking constants of block ``i`` (i ≥ 1) alone on the block below it.

        The lever b_c is the shorter of the horizontal distances from the block's
        centre to the two ends of :meth:`overlap` (the pivot it tips over first); on
        a centred column, the smaller of the two facing pivot half-widths.
        """
        up, o_up = self.blocks[i], self.offsets[i]
        left, right = self.overlap(i)
        bc = min(right - o_up, o_up - left)
        return rocking_about(up.m, bc, up.h, up.inertia[1], g)

    def critical_angle(self, g: float = 9.81) -> float:
        """Smallest critical angle: each block's own (on its support) and the whole column's.

        The closed form of a centred column's first mechanism (the limit
        analysis gives the same angle).
        """
        lams = [self.blocks[0].rocking(g).lam]
        lams += [self.interface(i, g).lam for i in range(1, len(self.blocks))]
        if len(self.blocks) > 1:
            lams.append(self.monolithic(g).lam)
        return min(lams)
