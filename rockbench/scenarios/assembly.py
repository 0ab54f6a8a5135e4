"""Planar assemblies of rigid blocks at given poses on the base and on fixed supports.

The general case of :class:`~rockbench.scenarios.model.Stack`: any arrangement in the
x–z plane of rectangular blocks (:class:`~rockbench.scenarios.model.Block`) and
convex polygonal prisms (:class:`Prism`), each with a depth along y and placed at a
pose (x, z, angle), resting on the base (the plane z = 0) and on fixed convex
supports (:class:`Support`, e.g. an arch's springings) that move with the base.

Engines see the same protocol as for a stack: ``blocks`` (each with ``m``,
``inertia``, ``profile()`` about its centroid, ``depth``), ``centroids``, ``angles``
(each block's orientation about +y), ``total_height``; plus ``supports``.
:meth:`Assembly.to_limit` converts it to the limit-analysis
:class:`~rockbench.analytic.limit_geometry.Assembly`, whose construction also
validates the geometry: no two bodies overlap, and every block rests on a support
or on the base through face-to-face contacts (a block on a corner would be seen
by an engine but carried by no interface of the reference).

Poses: a :class:`Block` is placed by its centroid (x, z) and angle; a
:class:`Prism` by the frame its vertices are given in: world point = (x, z) +
R(angle) · vertex, with R the rotation about +y (θ > 0 turns the top toward +x).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from types import ModuleType
from typing import TYPE_CHECKING, Any

import numpy as np

from rockbench.errors import ScenarioError
from rockbench.scenarios import checks
from rockbench.scenarios.model import Block, Stack

if TYPE_CHECKING:
    from rockbench.analytic import limit_geometry

__all__ = ["Prism", "Support", "Assembly", "Pose", "rotate", "penetration", "limit_assembly",
           "drum_column",
           "parapet", "running_bond_wall", "voussoir_arch"]

#: (x, z, angle) of a block's frame: m, m, rad about +y.
Pose = tuple[float, float, float]


def _lg() -> ModuleType:
    """rockbench.analytic.limit_geometry, imported on use: the analytic package imports
    rockbench.scenarios, so a module-level import here would be circular."""
    from rockbench.analytic import limit_geometry

    return limit_geometry


def rotate(points: np.ndarray, angle: float) -> np.ndarray:
    """Rotate (x, z) points about the origin by ``angle`` about +y (θ > 0: +z toward +x)."""
    c, s = math.cos(angle), math.sin(angle)
    p = np.asarray(points, dtype=float)
    return np.stack([p[..., 0] * c + p[..., 1] * s, -p[..., 0] * s + p[..., 1] * c], axis=-1)


def penetration(a: np.ndarray, b: np.ndarray) -> float:
    """Depth by which two convex counter-clockwise polygons overlap (≤ 0: apart or touching).

    The smallest overlap of their projections over the edge normals of both
    (separating axis theorem).
    """
    normals = []
    for v in (a, b):
        e = np.roll(v, -1, axis=0) - v
        normals.append(np.stack([e[:, 1], -e[:, 0]], axis=1) / np.hypot(e[:, 0], e[:, 1])[:, None])
    n = np.concatenate(normals)
    pa, pb = a @ n.T, b @ n.T
    return float((np.minimum(pa.max(0), pb.max(0)) - np.maximum(pa.min(0), pb.min(0))).min())


def _vertices(raw: Any, what: str) -> tuple[tuple[float, float], ...]:
    """Validate a list of [x, z] pairs of finite numbers (convexity is checked by the caller)."""
    if not isinstance(raw, (list, tuple)) or len(raw) < 3:
        raise ScenarioError(f"{what} must be a list of at least 3 [x, z] pairs, got "
                            f"{checks.describe(raw)}")
    out = []
    for i, p in enumerate(raw, 1):
        if not isinstance(p, (list, tuple)) or len(p) != 2:
            raise ScenarioError(f"{what}: vertex {i} must be an [x, z] pair, got "
                                f"{checks.describe(p)}")
        out.append((checks.number(p[0], f"{what}: vertex {i} x", unit="m"),
                    checks.number(p[1], f"{what}: vertex {i} z", unit="m")))
    return tuple(out)


def _second_moments(v: np.ndarray) -> tuple[float, float, float]:
    """∫x² dA, ∫z² dA, ∫xz dA of a counter-clockwise polygon about the origin."""
    x, z = v[:, 0], v[:, 1]
    x1, z1 = np.roll(x, -1), np.roll(z, -1)
    cross = x * z1 - x1 * z
    ixx = float((cross * (x * x + x * x1 + x1 * x1)).sum()) / 12.0
    izz = float((cross * (z * z + z * z1 + z1 * z1)).sum()) / 12.0
    ixz = float((cross * (x * z1 + 2 * x * z + 2 * x1 * z1 + x1 * z)).sum()) / 24.0
    return ixx, izz, ixz


@dataclass(frozen=True)
class Prism:
    """A rigid convex polygonal prism: a polygon in the x–z plane extruded over ``depth``.

    Parameters
    ----------
    vertices : sequence of (x, z)
        Corners in m in the block's own frame, counter-clockwise (x to the
        right, z up), convex.
    depth : float
        Size along y (m); the prism is centred on y = 0.
    density : float, optional
        kg/m³. Give exactly one of ``density`` and ``mass``.
    mass : float, optional
        kg.
    """

    vertices: tuple[tuple[float, float], ...]
    depth: float
    density: float | None = None
    mass: float | None = None
    _centroid: np.ndarray = field(init=False, repr=False, compare=False)
    _area: float = field(init=False, repr=False, compare=False)
    _moments: tuple[float, float, float] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        v = _vertices(self.vertices, "block vertices")
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "depth", checks.number(self.depth, "block depth", low=0.0,
                                                        unit="m"))
        if (self.density is None) == (self.mass is None):
            raise ScenarioError("block needs exactly one of 'density' and 'mass'")
        if self.density is not None:
            object.__setattr__(self, "density", checks.number(self.density, "block density",
                                                              low=0.0, unit="kg/m³"))
        else:
            object.__setattr__(self, "mass", checks.number(self.mass, "block mass", low=0.0,
                                                           unit="kg"))
        # convexity, orientation and repeated vertices: the limit-analysis polygon's checks
        poly = _lg().PlanarBlock(np.array(v), self.depth, mass=1.0)
        object.__setattr__(self, "_centroid", poly.centroid)
        object.__setattr__(self, "_area", poly.area)
        object.__setattr__(self, "_moments", _second_moments(np.array(v) - poly.centroid))

    @property
    def area(self) -> float:
        """Area of the polygon (m²)."""
        return self._area

    @property
    def volume(self) -> float:
        """Volume of the prism (m³)."""
        return self._area * self.depth

    @property
    def m(self) -> float:
        """Mass in kg."""
        return self.mass if self.mass is not None else self.density * self.volume  # type: ignore[operator]

    @property
    def centroid(self) -> np.ndarray:
        """Centroid (x, z) of the polygon in the block's own frame (m)."""
        return self._centroid

    @property
    def chamfer(self) -> float:
        """Always 0: a prism's corners are its vertices (the Block protocol)."""
        return 0.0

    @property
    def width(self) -> float:
        """Extent along x in the block's own frame (m)."""
        return float(np.ptp(np.array(self.vertices)[:, 0]))

    @property
    def height(self) -> float:
        """Extent along z in the block's own frame (m)."""
        return float(np.ptp(np.array(self.vertices)[:, 1]))

    def profile(self) -> np.ndarray:
        """Vertices about the centroid in the block's frame, counter-clockwise, shape (k, 2)."""
        return np.array(self.vertices) - self._centroid

    @property
    def inertia_tensor(self) -> np.ndarray:
        """Centroidal inertia tensor in the block's frame (x, y, z axes), kg m², (3, 3).

        y is a principal axis (the prism is symmetric about y = 0); the x–z
        product of inertia is not zero for a general polygon.
        """
        jx, jz, jxz = self._moments  # ∫x² dA, ∫z² dA, ∫xz dA about the centroid
        rho = self.m / self._area  # mass per unit area of the section
        slab = self.m * self.depth**2 / 12.0
        return np.array([[slab + rho * jz, 0.0, -rho * jxz],
                         [0.0, rho * (jx + jz), 0.0],
                         [-rho * jxz, 0.0, slab + rho * jx]])

    @property
    def inertia(self) -> np.ndarray:
        """Diagonal (Ixx, Iyy, Izz) of :attr:`inertia_tensor` (kg m²); Iyy is exact for rocking."""
        return np.diag(self.inertia_tensor).copy()

    def to_dict(self) -> dict[str, Any]:
        """Scenario-file representation (without the pose)."""
        d: dict[str, Any] = {"vertices": [list(p) for p in self.vertices], "depth": self.depth}
        if self.mass is not None:
            d["mass"] = self.mass
        else:
            d["density"] = self.density
        return d


@dataclass(frozen=True)
class Support:
    """A fixed convex polygon in the x–z plane, rigidly attached to the base.

    Parameters
    ----------
    vertices : sequence of (x, z)
        Corners in world coordinates at t = 0 (m), counter-clockwise, convex.
        Its depth is that of the scene (every block's contact face).
    """

    vertices: tuple[tuple[float, float], ...]

    def __post_init__(self) -> None:
        v = _vertices(self.vertices, "support vertices")
        _lg().Support(np.array(v))  # convex, counter-clockwise, no repeated vertex
        object.__setattr__(self, "vertices", v)

    @classmethod
    def rectangle(cls, x_min: float, x_max: float, z_min: float, z_max: float) -> Support:
        """An axis-aligned rectangle [x_min, x_max] × [z_min, z_max]."""
        return cls(((x_min, z_min), (x_max, z_min), (x_max, z_max), (x_min, z_max)))

    @property
    def array(self) -> np.ndarray:
        """Vertices as an (n, 2) array."""
        return np.array(self.vertices)

    def to_dict(self) -> dict[str, Any]:
        """Scenario-file representation."""
        return {"vertices": [list(p) for p in self.vertices]}


@dataclass(frozen=True)
class Assembly:
    """Rigid blocks at given poses on the base (z = 0) and on fixed supports.

    Parameters
    ----------
    blocks : sequence of Block or Prism
        The movable bodies.
    poses : sequence of (x, z, angle)
        One per block: a Block's centroid and orientation, a Prism's frame
        (module docstring). |angle| < π/2 (a block turned further is the same
        block described with its sides swapped).
    supports : sequence of Support
        Fixed bodies besides the base.

    Raises
    ------
    ScenarioError
        Bad values, overlapping bodies, or a block that no face-to-face contact
        chain connects to the base or a support.
    """

    blocks: tuple[Block | Prism, ...]
    poses: tuple[Pose, ...]
    supports: tuple[Support, ...] = ()
    _centroids: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        blocks, supports = tuple(self.blocks), tuple(self.supports)
        if not blocks:
            raise ScenarioError("an assembly needs at least one block")
        if not all(isinstance(b, (Block, Prism)) for b in blocks):
            raise ScenarioError("assembly blocks must be Block or Prism instances")
        if not all(isinstance(s, Support) for s in supports):
            raise ScenarioError("assembly supports must be Support instances")
        poses = tuple(self.poses)
        if len(poses) != len(blocks):
            raise ScenarioError(f"an assembly needs one pose per block: {len(poses)} poses for "
                                f"{len(blocks)} blocks")
        checked = []
        for i, p in enumerate(poses, 1):
            if not isinstance(p, (list, tuple)) or len(p) != 3:
                raise ScenarioError(f"block #{i} pose must be (x, z, angle), got "
                                    f"{checks.describe(p)}")
            x = checks.number(p[0], f"block #{i} x", unit="m")
            z = checks.number(p[1], f"block #{i} z", unit="m")
            a = checks.number(p[2], f"block #{i} angle", unit="rad")
            if not abs(a) < 0.5 * math.pi:
                raise ScenarioError(f"block #{i} angle must be within (-π/2, π/2) rad, got {a!r}: "
                                    f"describe a block turned further with its sides swapped")
            checked.append((x, z, a))
        object.__setattr__(self, "blocks", blocks)
        object.__setattr__(self, "poses", tuple(checked))
        object.__setattr__(self, "supports", supports)
        cents = []
        for b, (x, z, a) in zip(blocks, checked, strict=True):
            local = b.centroid if isinstance(b, Prism) else np.zeros(2)
            cents.append(np.array([x, z]) + rotate(local, a))
        c = np.array(cents)
        c.setflags(write=False)
        object.__setattr__(self, "_centroids", c)
        try:
            _limit(self)
        except ScenarioError as exc:
            nb, ns = len(blocks), len(supports)
            raise ScenarioError(
                f"assembly geometry: {exc} (blocks 0..{nb - 1} and supports 0..{ns - 1} in the "
                f"order given; support {ns} is the base, z <= 0)") from None

    def __len__(self) -> int:
        return len(self.blocks)

    @property
    def centroids(self) -> np.ndarray:
        """World centroid (x, z) of each block at rest, shape (n, 2) (m)."""
        return self._centroids.copy()

    @property
    def angles(self) -> np.ndarray:
        """Orientation of each block about +y (rad), shape (n,)."""
        return np.array([p[2] for p in self.poses])

    def world_vertices(self, i: int) -> np.ndarray:
        """Corners of block ``i`` in world coordinates at rest, counter-clockwise, (k, 2)."""
        b = self.blocks[i]
        return self._centroids[i] + rotate(b.profile(), self.poses[i][2])

    @property
    def total_height(self) -> float:
        """Height of the highest block corner above the base (m)."""
        return max(float(self.world_vertices(i)[:, 1].max()) for i in range(len(self.blocks)))

    @property
    def size(self) -> float:
        """Largest extent of the blocks together along x or z (m): the scene's length scale."""
        v = np.concatenate([self.world_vertices(i) for i in range(len(self.blocks))])
        return float(np.ptp(v, axis=0).max())

    @property
    def reach(self) -> float:
        """Largest |x| of any block or support corner (m)."""
        pts = [self.world_vertices(i) for i in range(len(self.blocks))]
        pts += [s.array for s in self.supports]
        return float(np.abs(np.concatenate(pts)[:, 0]).max())

    def to_limit(self) -> limit_geometry.Assembly:
        """The limit-analysis assembly: blocks, supports, and the base as a ground slab."""
        return _limit(self)

    def critical_angle(self, g: float = 9.81) -> float:
        """The no-sliding tilting-table angle atan(α) of the first mechanism (rad).

        The normalising λ of an assembly: the limit-analysis collapse factor α
        with no sliding (μ = ∞), the smaller of the two directions; the
        smallest block's own λ = atan(b/h) for an assembly with no mechanism.
        It is a unit, not the collapse angle where head joints matter: a
        running-bond wall gets atan 1.0 here (the associative LP leans on friction
        at head joints nothing presses) and collapses at atan(11/19) with real
        Coulomb joints (``limit_analysis(..., flow="non-associative")``, which the
        tilting table and pulse to collapse use).
        """
        return _critical_angle(self, float(g))

    def mirrored(self) -> Assembly:
        """The mirror image in the plane x = 0 (for symmetry checks)."""
        blocks = []
        for b in self.blocks:
            if isinstance(b, Prism):
                v = tuple((-x, z) for x, z in reversed(b.vertices))
                blocks.append(Prism(v, b.depth, density=b.density, mass=b.mass))
            else:
                blocks.append(b)
        poses = tuple((-x, z, -a) for x, z, a in self.poses)
        sup = tuple(Support(tuple((-x, z) for x, z in reversed(s.vertices)))
                    for s in self.supports)
        return Assembly(tuple(blocks), poses, sup)

    def to_dict(self) -> dict[str, Any]:
        """``blocks`` and ``supports`` tables of the scenario file."""
        out = []
        for b, (x, z, a) in zip(self.blocks, self.poses, strict=True):
            d = b.to_dict()
            d.update({"x": x, "z": z, "angle": a})
            out.append(d)
        tables: dict[str, Any] = {"blocks": out}
        if self.supports:
            tables["supports"] = [s.to_dict() for s in self.supports]
        return tables


def limit_assembly(stack: Stack | Assembly) -> limit_geometry.Assembly:
    """The limit-analysis assembly of a scenario's stack or assembly."""
    if isinstance(stack, Assembly):
        return stack.to_limit()
    return _lg().assembly_from_stack(stack)


@functools.lru_cache(maxsize=128)
def _limit(assembly: Assembly) -> limit_geometry.Assembly:
    lg = _lg()
    blocks = tuple(lg.PlanarBlock(assembly.world_vertices(i), b.depth, mass=b.m)
                   for i, b in enumerate(assembly.blocks))
    reach = 2.0 * max(assembly.reach, assembly.size)
    return lg.Assembly(blocks, tuple(lg.Support(s.array) for s in assembly.supports)
                       + (lg.Support.ground(-reach, reach),))


@functools.lru_cache(maxsize=128)
def _critical_angle(assembly: Assembly, g: float) -> float:
    from rockbench.analytic.limit_analysis import limit_analysis

    lim = _limit(assembly)
    alphas = [r.load_factor for r in (limit_analysis(lim, direction=d, g=g) for d in (1, -1))
              if r.status == "collapse"]
    if alphas:
        return math.atan(min(alphas))
    return min(math.atan2(0.5 * b.width, 0.5 * b.height) for b in assembly.blocks)


# ---------------------------------------------------------------- builders (catalog families)
def drum_column(n: int, *, width: float = 0.6, drum_height: float = 0.5, depth: float = 0.6,
                density: float = 2600.0) -> Assembly:
    """A column of ``n`` equal drums (rectangular in the x–z plane) on the base, centred."""
    n = int(checks.integer(n, "drum column n", low=1))
    blk = Block(width, depth, drum_height, density=density)
    return Assembly((blk,) * n, tuple((0.0, (k + 0.5) * drum_height, 0.0) for k in range(n)))


def parapet(offset: float, *, wall: tuple[float, float] = (0.6, 1.2),
            top: tuple[float, float] = (0.3, 0.8), depth: float = 0.4,
            density: float = 2000.0) -> Assembly:
    """A parapet block on a wall block, its centre ``offset`` (m) from the wall's along x.

    ``wall`` and ``top`` are (width, height) in m; an offset beyond half the
    difference of the widths makes the parapet overhang the wall's edge, which
    shortens its lever on that side.
    """
    (ww, wh), (pw, ph) = wall, top
    return Assembly((Block(ww, depth, wh, density=density), Block(pw, depth, ph, density=density)),
                    ((0.0, 0.5 * wh, 0.0), (float(offset), wh + 0.5 * ph, 0.0)))


def running_bond_wall(courses: int, bricks: int, *, length: float = 0.24, height: float = 0.12,
                      depth: float = 0.12, density: float = 1800.0) -> Assembly:
    """A dry-stack wall panel in running bond, centred on x = 0.

    ``courses`` courses of ``bricks`` bricks ``length`` × ``height``; every
    second course (from the second) is shifted by half a brick, with half
    bricks at both ends, so that every course spans ``bricks · length``.
    """
    nc = int(checks.integer(courses, "wall courses", low=1))
    nb = int(checks.integer(bricks, "wall bricks per course", low=1))
    full = Block(length, depth, height, density=density)
    half = Block(0.5 * length, depth, height, density=density)
    x0 = -0.5 * nb * length
    blocks: list[Block | Prism] = []
    poses: list[Pose] = []
    for c in range(nc):
        z = (c + 0.5) * height
        if c % 2 == 0:
            row = [(full, x0 + (k + 0.5) * length) for k in range(nb)]
        else:
            row = [(half, x0 + 0.25 * length)]
            row += [(full, x0 + (k + 1.0) * length) for k in range(nb - 1)]
            row.append((half, -x0 - 0.25 * length))
        for blk, x in row:
            blocks.append(blk)
            poses.append((x, z, 0.0))
    return Assembly(tuple(blocks), tuple(poses))


def voussoir_arch(n: int, thickness: float, radius: float = 1.0, *, depth: float = 0.5,
                  density: float = 2000.0) -> Assembly:
    """A semicircular arch of ``n`` voussoirs on two fixed supports (springer pads).

    The voussoirs are the convex polygons of
    :func:`rockbench.analytic.limit_geometry.semicircular_arch` (radial joints,
    intrados drawn as a chord), with the mass and centroid of those polygons;
    its two supports, ``thickness`` high, stand on the base, so the springings
    lie at z = ``thickness`` and the mean circle's centre at (0, thickness).
    """
    ref = _lg().semicircular_arch(n, thickness, radius, depth=depth, density=density)
    lift = np.array([0.0, float(thickness)])
    blocks = tuple(Prism(tuple(map(tuple, (b.vertices + lift).tolist())), depth, density=density)
                   for b in ref.blocks)
    supports = tuple(Support(tuple(map(tuple, (s.vertices + lift).tolist())))
                     for s in ref.supports)
    return Assembly(blocks, ((0.0, 0.0, 0.0),) * len(blocks), supports)
