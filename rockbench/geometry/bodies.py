"""Rigid bodies and fixed supports: rectangular blocks, convex prisms, cylinders, supports.

Every body shares one protocol, which engines, references and reports read:
``m`` (kg), ``depth`` (m, along y, centred on y = 0), ``width`` and ``height``
(extents in its own frame), ``chamfer``, ``centroid`` (its centre of gravity
in its own frame), ``profile()`` (its convex outline in the x–z plane about the
centre of gravity, counter-clockwise), ``inertia`` (principal centroidal
moments) and ``inertia_tensor``. A :class:`Cylinder` (a drum, a column) shows
its x–z silhouette, a rectangle, as its profile. A :class:`Support` is a fixed
convex polygon in world coordinates that moves with the base.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rockbench import checks
from rockbench.errors import ScenarioError
from rockbench.geometry.polygon import (
    area_centroid,
    contains,
    convex_polygon,
    rotate_about,
    second_moments,
)
from rockbench.geometry.rocking import RockingProperties, rocking_about

__all__ = ["Block", "Prism", "Cylinder", "Support", "Body", "Upright", "vertex_list",
           "footprint_pivot"]


def _mass(mass: float | None, density: float | None, volume: float) -> float:
    """The mass given, or the density times the volume (exactly one is given)."""
    if mass is not None:
        return mass
    assert density is not None  # exactly one of the two (_mass_or_density)
    return density * volume


def _mass_or_density(density: Any, mass: Any, what: str = "block"
                     ) -> tuple[float | None, float | None]:
    if (density is None) == (mass is None):
        raise ScenarioError(f"{what} needs exactly one of 'density' and 'mass'")
    if density is not None:
        return checks.number(density, f"{what} density", low=0.0, unit="kg/m³"), None
    return None, checks.number(mass, f"{what} mass", low=0.0, unit="kg")


@dataclass(frozen=True)
class Block:
    """A rectangular rigid block, optionally chamfered on its rocking edges.

    Parameters
    ----------
    width : float
        Size along x, the rocking direction (m).
    depth : float
        Size along y, out of plane (m).
    height : float
        Size along z (m).
    density : float, optional
        kg/m³. Give exactly one of ``density`` and ``mass``.
    mass : float, optional
        kg.
    chamfer : float
        45° cut on the four edges parallel to y (m), smaller than half the width
        and half the height. Mass and inertia of the cut corners are neglected.
    """

    width: float
    depth: float
    height: float
    density: float | None = None
    mass: float | None = None
    chamfer: float = 0.0

    def __post_init__(self) -> None:
        for name in ("width", "depth", "height"):
            object.__setattr__(self, name, checks.length(getattr(self, name), f"block {name}"))
        density, mass = _mass_or_density(self.density, self.mass)
        object.__setattr__(self, "density", density)
        object.__setattr__(self, "mass", mass)
        c = checks.length(self.chamfer, "block chamfer", strict=False)
        if c >= 0.5 * min(self.width, self.height):
            raise ScenarioError(
                f"block chamfer {c} must be smaller than half the width and half the height"
            )
        object.__setattr__(self, "chamfer", c)

    @property
    def volume(self) -> float:
        """Volume of the uncut box (m³)."""
        return self.width * self.depth * self.height

    @property
    def m(self) -> float:
        """Mass in kg."""
        return _mass(self.mass, self.density, self.volume)

    @property
    def b(self) -> float:
        """Half-width (m)."""
        return 0.5 * self.width

    @property
    def h(self) -> float:
        """Half-height (m)."""
        return 0.5 * self.height

    @property
    def pivot_half_width(self) -> float:
        """Half-distance between the two rocking pivots, b − chamfer (m)."""
        return self.b - self.chamfer

    @property
    def centroid(self) -> np.ndarray:
        """Centre of gravity in the block's own frame: its centre (0, 0)."""
        return np.zeros(2)

    @property
    def inertia(self) -> np.ndarray:
        """Principal centroidal moments of inertia (Ixx, Iyy, Izz) of the box (kg m²)."""
        w, d, h, m = self.width, self.depth, self.height, self.m
        return np.array([m * (d * d + h * h), m * (w * w + h * h), m * (w * w + d * d)]) / 12.0

    @property
    def inertia_tensor(self) -> np.ndarray:
        """Centroidal inertia tensor (3, 3): diagonal, the box's axes are principal."""
        return np.diag(self.inertia)

    def rocking(self, g: float = 9.81) -> RockingProperties:
        """Rocking constants λ, R, p, η about its own bottom pivots on a rigid base."""
        return rocking_about(self.m, self.pivot_half_width, self.h, self.inertia[1], g)

    def profile(self) -> np.ndarray:
        """Convex outline in the x–z plane about the centroid, counter-clockwise, shape (k, 2)."""
        b, h, c = self.b, self.h, self.chamfer
        if c == 0:
            return np.array([[-b, -h], [b, -h], [b, h], [-b, h]])
        return np.array([
            [-b + c, -h], [b - c, -h], [b, -h + c], [b, h - c],
            [b - c, h], [-b + c, h], [-b, h - c], [-b, -h + c],
        ])

    def mirrored(self) -> Block:
        """The mirror image in the plane x = 0 of its frame (the same block)."""
        return self

    def to_dict(self) -> dict[str, Any]:
        """Scenario-file representation (without the pose)."""
        d: dict[str, Any] = {"width": self.width, "depth": self.depth, "height": self.height}
        if self.mass is not None:
            d["mass"] = self.mass
        else:
            d["density"] = self.density
        d["chamfer"] = self.chamfer
        return d


def _unbounded(value: Any, what: str) -> float:
    """A finite coordinate in metres, of any size."""
    return checks.number(value, what, unit="m")


def vertex_list(raw: Any, what: str, *, bounded: bool = True
                ) -> tuple[tuple[float, float], ...]:
    """Validate a list of [x, z] pairs of finite numbers (convexity is checked separately).

    ``bounded``: each coordinate within :data:`rockbench.checks.MAX_LENGTH` of the
    origin (a body's; the ground slab, sized from the scene, is not bounded).
    """
    point = checks.coordinate if bounded else _unbounded
    if not isinstance(raw, (list, tuple, np.ndarray)) or len(raw) < 3:
        raise ScenarioError(f"{what} must be a list of at least 3 [x, z] pairs, got "
                            f"{checks.describe(raw)}")
    out = []
    for i, p in enumerate(raw, 1):
        if not isinstance(p, (list, tuple, np.ndarray)) or len(p) != 2:
            raise ScenarioError(f"{what}: vertex {i} must be an [x, z] pair, got "
                                f"{checks.describe(p)}")
        out.append((point(p[0], f"{what}: vertex {i} x"),
                    point(p[1], f"{what}: vertex {i} z")))
    return tuple(out)


@dataclass(frozen=True)
class Prism:
    """A rigid convex polygonal prism: a polygon in the x–z plane extruded over ``depth``.

    Parameters
    ----------
    vertices : sequence of (x, z)
        Corners in m in the body's own frame, counter-clockwise (x to the
        right, z up), convex.
    depth : float
        Size along y (m); the prism is centred on y = 0.
    density : float, optional
        kg/m³. Give exactly one of ``density`` and ``mass``.
    mass : float, optional
        kg.
    centre_of_gravity : (x, z), optional
        Where the centre of gravity lies in the body's frame when it is not the
        polygon's centroid (a voussoir whose curved intrados the polygon draws
        as a chord); inside the polygon. The inertia is then the polygon's,
        moved to that point (parallel axes).
    """

    vertices: tuple[tuple[float, float], ...]
    depth: float
    density: float | None = None
    mass: float | None = None
    centre_of_gravity: tuple[float, float] | None = None
    _centroid: np.ndarray = field(init=False, repr=False, compare=False)
    _area: float = field(init=False, repr=False, compare=False)
    _moments: tuple[float, float, float] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        v = vertex_list(self.vertices, "block vertices")
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "depth", checks.length(self.depth, "block depth"))
        density, mass = _mass_or_density(self.density, self.mass)
        object.__setattr__(self, "density", density)
        object.__setattr__(self, "mass", mass)
        poly = convex_polygon(np.array(v), "block")
        area, centroid = area_centroid(poly)
        if self.centre_of_gravity is not None:
            cg = np.array(self.centre_of_gravity, dtype=float)
            if cg.shape != (2,) or not np.all(np.isfinite(cg)):
                raise ScenarioError(f"block centre of gravity must be two finite numbers, got "
                                    f"{checks.describe(self.centre_of_gravity)}")
            if not contains(poly, cg):
                raise ScenarioError(f"block centre of gravity {cg.tolist()} lies outside its "
                                    f"polygon")
            object.__setattr__(self, "centre_of_gravity", (float(cg[0]), float(cg[1])))
            centroid = cg
        object.__setattr__(self, "_centroid", centroid)
        object.__setattr__(self, "_area", area)
        object.__setattr__(self, "_moments", second_moments(np.array(v) - centroid))

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
        return _mass(self.mass, self.density, self.volume)

    @property
    def centroid(self) -> np.ndarray:
        """Centre of gravity (x, z) in the body's own frame (m)."""
        return self._centroid

    @property
    def chamfer(self) -> float:
        """Always 0: a prism's corners are its vertices."""
        return 0.0

    @property
    def width(self) -> float:
        """Extent along x in the body's own frame (m)."""
        return float(np.ptp(np.array(self.vertices)[:, 0]))

    @property
    def height(self) -> float:
        """Extent along z in the body's own frame (m)."""
        return float(np.ptp(np.array(self.vertices)[:, 1]))

    def profile(self) -> np.ndarray:
        """Vertices about the centre of gravity, counter-clockwise, shape (k, 2)."""
        return np.array(self.vertices) - self._centroid

    @property
    def inertia_tensor(self) -> np.ndarray:
        """Centroidal inertia tensor in the body's frame (x, y, z axes), kg m², (3, 3).

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

    def mirrored(self) -> Prism:
        """The mirror image in the plane x = 0 of its frame."""
        v = tuple((-x, z) for x, z in reversed(self.vertices))
        cg = self.centre_of_gravity
        return Prism(v, self.depth, density=self.density, mass=self.mass,
                     centre_of_gravity=None if cg is None else (-cg[0], cg[1]))

    def to_dict(self) -> dict[str, Any]:
        """Scenario-file representation (without the pose)."""
        d: dict[str, Any] = {"vertices": [list(p) for p in self.vertices], "depth": self.depth}
        if self.mass is not None:
            d["mass"] = self.mass
        else:
            d["density"] = self.density
        return d


@dataclass(frozen=True)
class Cylinder:
    """A uniform solid circular cylinder standing on its base: a drum, a column, a statue's core.

    Its symmetry axis is the body's z axis. In the x–z plane it shows its
    silhouette, a 2R × H rectangle (:meth:`profile`), and rocks in that plane on
    a rim point as a block of half-width R does, with the cylinder's inertia
    (:meth:`rocking`); in 3D it rocks on its rim about any horizontal axis and
    may roll on it (:mod:`rockbench.analytic.rolling_cylinder`).

    Parameters
    ----------
    radius : float
        R (m), the radius of its base rim.
    height : float
        H (m); the centre of mass is H/2 above the base on the axis.
    density : float, optional
        kg/m³. Give exactly one of ``density`` and ``mass``.
    mass : float, optional
        kg.

    Raises
    ------
    ScenarioError
        A size or mass that is not a positive finite number, or both or neither
        of ``density`` and ``mass``.
    """

    radius: float
    height: float
    density: float | None = None
    mass: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", checks.length(self.radius, "cylinder radius"))
        object.__setattr__(self, "height", checks.length(self.height, "cylinder height"))
        density, mass = _mass_or_density(self.density, self.mass, "cylinder")
        object.__setattr__(self, "density", density)
        object.__setattr__(self, "mass", mass)

    @property
    def volume(self) -> float:
        """π R² H (m³)."""
        return math.pi * self.radius ** 2 * self.height

    @property
    def m(self) -> float:
        """Mass (kg)."""
        return _mass(self.mass, self.density, self.volume)

    @property
    def width(self) -> float:
        """Extent along x, the diameter 2R (m)."""
        return 2.0 * self.radius

    @property
    def depth(self) -> float:
        """Extent along y, the diameter 2R (m)."""
        return 2.0 * self.radius

    @property
    def chamfer(self) -> float:
        """Always 0."""
        return 0.0

    @property
    def b(self) -> float:
        """Half-width of its silhouette, R (m)."""
        return self.radius

    @property
    def h(self) -> float:
        """Height of the centre of mass above the base, H/2 (m)."""
        return 0.5 * self.height

    @property
    def pivot_half_width(self) -> float:
        """Distance from the axis to a rim pivot, R (m)."""
        return self.radius

    @property
    def centroid(self) -> np.ndarray:
        """Centre of gravity in the body's own frame: its centre (0, 0)."""
        return np.zeros(2)

    @property
    def i_axial(self) -> float:
        """Centroidal moment of inertia about the symmetry axis, m R²/2 (kg m²)."""
        return 0.5 * self.m * self.radius ** 2

    @property
    def i_transverse(self) -> float:
        """Centroidal moment of inertia about a diameter, m (3R² + H²)/12 (kg m²)."""
        return self.m * (3.0 * self.radius ** 2 + self.height ** 2) / 12.0

    @property
    def r(self) -> float:
        """Distance from a rim point to the centre of mass, √(R² + h²) (m)."""
        return math.hypot(self.radius, self.h)

    @property
    def alpha(self) -> float:
        """Tilt at which the centre of mass is above the contact point, atan(R/h) (rad)."""
        return math.atan2(self.radius, self.h)

    @property
    def i_pivot(self) -> float:
        """Moment of inertia about the rim tangent through the contact, I₁ + m r² (kg m²)."""
        return self.i_transverse + self.m * self.r ** 2

    @property
    def inertia(self) -> np.ndarray:
        """Principal centroidal moments (I₁, I₁, I₃) about x, y and the axis z (kg m²)."""
        return np.array([self.i_transverse, self.i_transverse, self.i_axial])

    @property
    def inertia_tensor(self) -> np.ndarray:
        """Centroidal inertia tensor (3, 3): diagonal."""
        return np.diag(self.inertia)

    def rocking(self, g: float = 9.81) -> RockingProperties:
        """Rocking constants λ, R, p, η on a rim point, in any vertical plane through its axis."""
        return rocking_about(self.m, self.radius, self.h, self.i_transverse, g)

    def profile(self) -> np.ndarray:
        """Its silhouette in the x–z plane about the centroid, counter-clockwise, shape (4, 2)."""
        b, h = self.radius, self.h
        return np.array([[-b, -h], [b, -h], [b, h], [-b, h]])

    def mirrored(self) -> Cylinder:
        """The mirror image in the plane x = 0 of its frame (the same cylinder)."""
        return self

    def to_dict(self) -> dict[str, Any]:
        """Scenario-file representation (without the pose)."""
        d: dict[str, Any] = {"radius": self.radius, "height": self.height}
        if self.mass is not None:
            d["mass"] = self.mass
        else:
            d["density"] = self.density
        return d


def footprint_pivot(body: Upright, azimuth: float) -> np.ndarray:
    """The point of a body's base footprint furthest toward the azimuth ψ, (x, y) in its frame.

    A body tilted toward the horizontal direction u = (cos ψ, sin ψ) pivots
    there: on a block, the edge's midpoint when u is along an axis, a corner
    otherwise; on a cylinder, the rim point at ψ.
    """
    c, s = math.cos(azimuth), math.sin(azimuth)
    if isinstance(body, Cylinder):
        return body.radius * np.array([c, s])
    # a component within rounding of zero is an axis: the pivot is the edge's midpoint
    sx = 0.0 if abs(c) < 1e-12 else math.copysign(1.0, c)
    sy = 0.0 if abs(s) < 1e-12 else math.copysign(1.0, s)
    return np.array([sx * body.pivot_half_width, sy * 0.5 * body.depth])


#: Any rigid body of a geometry.
Body = Block | Prism | Cylinder
#: A body that stands upright in a column and rocks on its bottom pivots.
Upright = Block | Cylinder


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
        v = vertex_list(self.vertices, "support vertices", bounded=False)
        convex_polygon(np.array(v), "support")
        object.__setattr__(self, "vertices", v)

    @classmethod
    def rectangle(cls, x_min: float, x_max: float, z_min: float, z_max: float) -> Support:
        """An axis-aligned rectangle [x_min, x_max] × [z_min, z_max]."""
        return cls(((x_min, z_min), (x_max, z_min), (x_max, z_max), (x_min, z_max)))

    @classmethod
    def ground(cls, x_min: float, x_max: float, z: float = 0.0) -> Support:
        """The ground as a slab whose top face spans [x_min, x_max] at height ``z``."""
        if not x_max > x_min:
            raise ScenarioError(f"ground needs x_max > x_min, got [{x_min}, {x_max}]")
        d = x_max - x_min
        return cls(((x_min, z - d), (x_max, z - d), (x_max, z), (x_min, z)))

    @property
    def array(self) -> np.ndarray:
        """Vertices as an (n, 2) array."""
        return np.array(self.vertices)

    def rotated(self, angle: float, about: Sequence[float] = (0.0, 0.0)) -> Support:
        """The support rotated rigidly about +y by ``angle`` (rad) around ``about``."""
        v = rotate_about(self.array, angle, np.asarray(about, dtype=float))
        return Support(tuple(map(tuple, v.tolist())))

    def mirrored(self) -> Support:
        """The mirror image in the plane x = 0."""
        return Support(tuple((-x, z) for x, z in reversed(self.vertices)))

    def to_dict(self) -> dict[str, Any]:
        """Scenario-file representation."""
        return {"vertices": [list(p) for p in self.vertices]}
