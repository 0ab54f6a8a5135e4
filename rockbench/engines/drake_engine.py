"""Drake engine plugin: rigid blocks as free bodies of a discrete MultibodyPlant.

A MultibodyPlant and SceneGraph diagram stepped by a Simulator. The plant is discrete
(period ``timestep``); its contact problem is solved by TAMSI or SAP
(``contact_approximation``), with point or hydroelastic contact (``contact_model``).
Each block is a free body at its centroid with the block's mass and inertia tensor; its
collision shape (a ``Box``, or a ``Convex`` prism for a chamfered block or a convex
prism) is cut along y into ``collision_slices`` slices, since Drake's point contact
gives one point per pair of shapes. With ``corner_radius`` (the default) small spheres
at the corners of every slice carry the contact instead, so that every corner has its
own point. The ground is a ``Box`` whose top face is z = 0: welded in free rocking,
otherwise a heavy body on a prismatic joint per axis along which the base moves
(chained, weightless, a force along z cancelling the blocks' weight; a motion along x
alone keeps the planar benchmark's single joint along x, bit for bit), whose positions
and velocities are overwritten before every step with u(t) and v(t + φ dt)
(φ = ``base_velocity_phase``), held still once the motion ends, so that steps are
batched in C++. The base motion is applied along x, y and z; off the x axis every block
also has corner spheres at its y faces, on which it rocks about x. Fixed supports are
shapes of the ground's body with corners of their own. A
:class:`~rockbench.geometry.Cylinder` is Drake's own ``Cylinder`` (axis along the body's
z), one shape with the cylinder's mass and inertia, on a ``HalfSpace`` ground (a rim on a
half-space is found in closed form). A start out of the x–z plane or moving is set from
:meth:`~rockbench.scenarios.Scenario.initial_states` (free-body pose and world-frame
spatial velocity of the centroid, the body's origin), a block's with the corner spheres
at its y faces too; a planar start at rest keeps the former code path. Friction is
Coulomb's (static = dynamic), combined harmonically per pair (:func:`harmonic_frictions`,
:func:`assembly_harmonic_frictions`); the point-contact
stiffness comes from ``static_penetration`` (or ``point_stiffness``), the dissipation
from ``hunt_crossley_dissipation`` (or SAP's ``relaxation_time``). Drake has no
restitution coefficient, no damping and no sleeping.

Presets and knobs:

* ``accurate`` (the defaults): TAMSI at Δt 0.05 ms, 4 slices with corner spheres of
  1e-5 m, a static penetration of 1e-8 m and a Hunt–Crossley dissipation of 1000 s/m,
  which makes a corner's landing plastic as in Housner's model.
* ``fast``: Δt 0.5 ms, 2 slices, Drake's own dissipation.
* Also: ``penetration_allowance``, ``near_rigid_threshold``, ``stiction_tolerance``
  and the hydroelastic knobs.

Known limits: the most expensive engine per step; restitution > 0, and on assemblies an
interface friction at most half the base's, are unsupported; at ``fast`` TAMSI may fail
on larger geometries (the run ends ``unstable``); TAMSI is removed after Drake 1.51.

See :doc:`the engine's page </engines/drake>` in the documentation for its
calibration, measured accuracy and cost.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any, ClassVar, Literal

import numpy as np

from rockbench.engines.base import Capabilities, Engine
from rockbench.engines.drive import AXIS
from rockbench.engines.settings import EngineSettings, KnobRole
from rockbench.errors import UnsupportedScenario
from rockbench.geometry import Block, Cylinder, Support
from rockbench.scenarios import Scenario

__all__ = ["DrakeEngine", "DrakeSettings"]

class _QuietTamsiDeprecation(logging.Filter):
    """Drop Drake's per-build TAMSI deprecation warning (documented in DrakeSettings) and
    its note that a half-space (the ground of a scene with cylinders) has no deformable
    contact (there are no deformable bodies)."""

    def filter(self, record: logging.LogRecord) -> bool:
        msg = record.getMessage()
        return ("TAMSI solver is deprecated" not in msg
                and "half spaces are not currently supported for deformable" not in msg)


logging.getLogger("drake").addFilter(_QuietTamsiDeprecation())
_log = logging.getLogger(__name__)

#: Base mass per kg of blocks: the contact reaction barely moves a driven base.
_BASE_MASS_RATIO = 1.0e6
#: Excitation samples precomputed per chunk (bounded memory for long records).
_CHUNK = 20000
#: Unit vector of each axis (the base's prismatic joints).
_UNIT = {"x": [1.0, 0.0, 0.0], "y": [0.0, 1.0, 0.0], "z": [0.0, 0.0, 1.0]}


@dataclass(frozen=True)
class DrakeSettings(EngineSettings):
    """Knobs of the Drake engine (defaults = the ``accurate`` preset).

    Parameters
    ----------
    timestep : float
        Period of the discrete plant in s (``MultibodyPlantConfig.time_step``),
        the main accuracy lever.
    contact_approximation : {"sap", "similar", "lagged", "tamsi"}
        ``discrete_contact_approximation``: the first three are solved by SAP
        (convex, with joint locking), ``"tamsi"`` by the older, cheaper TAMSI
        solver (deprecated by Drake, removed after 1.51), the only one that slides
        like Coulomb friction (see the engine's documentation page).
    contact_model : {"point", "hydroelastic", "hydroelastic_with_fallback"}
        Point contact (one point per geometry pair) or hydroelastic contact
        (a pressure field over the patch; blocks compliant, ground rigid).
    static_penetration : float or None
        Sets the point-contact stiffness from the penetration in m under the
        whole stack's weight W on one rocking edge: each geometry gets
        ``material/point_contact_stiffness`` = 2W/(Nδ) with N =
        ``collision_slices`` (two equal springs in series give W/δ over the N
        contacts of a rocking edge; N + 2 with the y faces' corner spheres of a base
        that leaves the x axis). Scaling with the weight keeps the contact time scale
        sqrt(δ/g) the same for every block. Ignored if ``point_stiffness`` is set.
    point_stiffness : float or None
        Absolute point-contact stiffness in N/m of every geometry (overrides
        ``static_penetration``). If both are None, Drake derives the stiffness
        from ``penetration_allowance``.
    penetration_allowance : float
        Drake's own penetration target in m (``MultibodyPlantConfig``), used for
        its stiffness estimate when neither knob above is set.
    relaxation_time : float or None
        SAP's linear dissipation time scale in s (``material/relaxation_time``,
        used by the ``"sap"`` approximation). None: Drake's default (0.1 s).
    hunt_crossley_dissipation : float or None
        Hunt–Crossley dissipation in s/m (used by TAMSI, ``"similar"`` and
        ``"lagged"``). None: Drake's default. 1000 (``accurate``) makes a corner
        landing on a block a plastic impact, as Housner's model has it: with
        Drake's default the upper block of a stack bounced off its new pivot and
        crept on the interface (stack sinusoids 32–39 % off, 1.3–1.9 mm of
        interface slip at 0.1–0.05 ms).
    near_rigid_threshold : float
        SAP's near-rigid threshold β (``sap_near_rigid_threshold``): contacts
        stiffer than the time step resolves are regularised as near rigid;
        0 disables the regularisation.
    stiction_tolerance : float
        Slip speed in m/s below which TAMSI treats friction as stiction (its
        friction regularisation; SAP ignores it).
    hydroelastic_modulus : float
        Hydroelastic modulus of the blocks in Pa (contact_model hydroelastic).
    hydroelastic_resolution : float
        Mesh resolution hint in m for the blocks' compliant hydroelastic meshes.
    base_velocity_phase : float
        Where in the step [t, t + dt] the driven base's velocity is sampled
        (0 = start, 0.5 = middle, 1 = end); 0.5 pairs the imposed acceleration
        with the blocks' positions as in leapfrog integration.
    collision_slices : int
        Number of equal slices along y (depth/N each, same x–z profile) of each
        block's collision shape. Point contact keeps one contact point per pair
        of shapes, so N slices give a rocking edge N points instead of one
        (1 reproduces the single-shape model and its out-of-plane wobble).
        ``static_penetration`` shares the weight among the N contacts.
    corner_radius : float or None
        None: the block's shape (box or prism slices) is its collision geometry.
        A radius r in m: spheres of radius r at the profile's vertices (inset to touch
        both edges there), one set per slice (and, when the base moves along y or z,
        one more at each y face: :func:`corner_ys`), are the contact geometry instead: each
        sphere is its own pair, so a face resting on the ground or on another block
        is held at both its corners. Point contact only.

    Notes
    -----
    The presets' calibration and their measured accuracy are on
    :doc:`the engine's page </engines/drake>` in the documentation.
    """

    timestep: float = 5.0e-5
    contact_approximation: Literal["sap", "similar", "lagged", "tamsi"] = "tamsi"
    contact_model: Literal["point", "hydroelastic", "hydroelastic_with_fallback"] = "point"
    static_penetration: float | None = 1.0e-8
    point_stiffness: float | None = None
    penetration_allowance: float = 1.0e-3
    relaxation_time: float | None = None
    hunt_crossley_dissipation: float | None = 1000.0
    near_rigid_threshold: float = 1.0
    stiction_tolerance: float = 1.0e-4
    hydroelastic_modulus: float = 1.0e9
    hydroelastic_resolution: float = 0.05
    base_velocity_phase: float = 0.5
    collision_slices: int = 4
    corner_radius: float | None = 1.0e-5

    def __post_init__(self) -> None:
        if not (math.isfinite(self.timestep) and self.timestep > 0):
            raise ValueError(f"timestep must be finite and > 0, got {self.timestep!r}")
        for name in ("static_penetration", "point_stiffness", "relaxation_time",
                     "hunt_crossley_dissipation"):
            v = getattr(self, name)
            if v is not None and not (math.isfinite(v) and v >= 0):
                raise ValueError(f"{name} must be None or finite and >= 0, got {v!r}")
        for name in ("static_penetration", "point_stiffness"):
            if getattr(self, name) is not None and getattr(self, name) <= 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)!r}")
        for name in ("penetration_allowance", "stiction_tolerance", "hydroelastic_modulus",
                     "hydroelastic_resolution"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)!r}")
        if not self.near_rigid_threshold >= 0:
            raise ValueError(f"near_rigid_threshold must be >= 0, got "
                             f"{self.near_rigid_threshold!r}")
        if isinstance(self.collision_slices, bool) or not (
                isinstance(self.collision_slices, int) and self.collision_slices >= 1):
            raise ValueError(f"collision_slices must be an integer >= 1, got "
                             f"{self.collision_slices!r}")
        if self.corner_radius is not None:
            if not (math.isfinite(self.corner_radius) and self.corner_radius > 0):
                raise ValueError(f"corner_radius must be None or finite and > 0, got "
                                 f"{self.corner_radius!r}")
            if self.contact_model != "point":
                raise ValueError("corner_radius needs contact_model 'point' (spheres have "
                                 "no hydroelastic mesh at that size)")
        if not 0.0 <= self.base_velocity_phase <= 1.0:
            raise ValueError(f"base_velocity_phase must be in [0, 1], got "
                             f"{self.base_velocity_phase!r}")


def prism_obj(profile: np.ndarray, depth: float) -> str:
    """Wavefront .obj text of a convex polygon (x, z) extruded along y over ``depth``."""
    hd = 0.5 * depth
    n = len(profile)
    pts = [(float(x), float(z)) for x, z in np.asarray(profile, float)]
    lines = [f"v {x!r} {y!r} {z!r}" for y in (-hd, hd) for x, z in pts]
    # faces are only needed for a valid file: Drake's Convex takes the vertices' hull
    lines.append("f " + " ".join(str(i + 1) for i in range(n)))
    lines.append("f " + " ".join(str(n + i + 1) for i in reversed(range(n))))
    for i in range(n):
        j = (i + 1) % n
        lines.append(f"f {i + 1} {j + 1} {n + j + 1} {n + i + 1}")
    return "\n".join(lines) + "\n"


def corner_centres(profile: np.ndarray, r: float) -> np.ndarray:
    """Centres (x, z) of radius-``r`` spheres touching both edges at each vertex of a
    convex counter-clockwise polygon: on the inward bisector, r / sin(α/2) from the vertex."""
    p = np.asarray(profile, float)
    a = np.roll(p, 1, axis=0) - p  # to the previous vertex
    b = np.roll(p, -1, axis=0) - p  # to the next one
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b /= np.linalg.norm(b, axis=1, keepdims=True)
    bis = a + b
    half = 0.5 * np.arccos(np.clip(np.sum(a * b, axis=1), -1.0, 1.0))
    return p + bis / np.linalg.norm(bis, axis=1, keepdims=True) * (r / np.sin(half))[:, None]


# pydrake's stubs type a 3-vector argument as `numpy.ndarray[numpy.float64[3, 1]]`, which
# no list or NumPy array type matches (pybind11 converts both): the calls that pass one
# ignore that error ("pydrake stub mistypes vectors").
def _convex_prism(profile: np.ndarray, depth: float, name: str) -> Any:
    """Drake ``Convex`` shape of ``profile`` (x, z) extruded over ``depth``, from memory."""
    from pydrake.geometry import Convex, InMemoryMesh

    try:
        from pydrake.common import MemoryFile
    except ImportError:  # older layout
        from pydrake.geometry import MemoryFile  # type: ignore[no-redef, attr-defined]  # Drake's older layout

    return Convex(InMemoryMesh(mesh_file=MemoryFile(prism_obj(profile, depth), ".obj",
                                                    f"{name}.obj")))


def _add_corners(plant: Any, body: Any, profile: np.ndarray, y: float, r: float,
                 props: Any, name: str) -> list[Any]:
    """Register spheres of radius ``r`` at the corners of ``profile`` (inset to touch both
    edges) on ``body`` at depth ``y``; return their geometry ids."""
    from pydrake.geometry import Sphere
    from pydrake.math import RigidTransform

    return [plant.RegisterCollisionGeometry(body, RigidTransform([x, y, z]), Sphere(r),  # type: ignore[call-overload]  # pydrake stub mistypes vectors
                                            f"{name}_{k}", props)
            for k, (x, z) in enumerate(corner_centres(profile, r))]


def corner_ys(depth: float, n: int, r: float, *, ends: bool) -> list[float]:
    """The y of each set of corner spheres of a body ``depth`` deep cut into ``n`` slices:
    the slices' centres and, with ``ends`` (a base that also moves along y or z), one set
    more at each y face (±(depth/2 − r), touching it), so that an edge along x rests on a
    sphere at each of its corners as an edge along y does, and the block rocks about x on
    its faces' edges. The centres stay: they are what holds a block on a narrower one."""
    d = depth / n
    ys = [(j + 0.5) * d - 0.5 * depth for j in range(n)]
    if ends:
        h = 0.5 * depth - r
        ys = [-h, *ys, h]
    return ys


def assembly_harmonic_frictions(mu: float, mu_if: float, n_blocks: int) -> list[float]:
    """Per-geometry coefficients (base and supports first) for a geometry that is not a column.

    A block may touch other blocks and the base at once, and blocks in contact may
    form odd cycles, so every block takes 1/μ_if (a block pair's a's sum to 2/μ_if)
    and the base and supports 2/μ − 1/μ_if, which is positive only for μ_if > μ/2
    (:meth:`DrakeEngine._check_supported` refuses the rest).
    """
    if mu_if == mu:  # (also both zero, where the formula would divide by zero)
        return [mu] * (n_blocks + 1)
    return [mu * mu_if / (2.0 * mu_if - mu)] + [mu_if] * n_blocks


def harmonic_frictions(mu: float, mu_if: float, n_blocks: int) -> list[float]:
    """Per-geometry coefficients (ground first) that Drake combines into μ and μ_if.

    Drake gives a pair 2 μ₁ μ₂ / (μ₁ + μ₂): with a = 1/μ per geometry, a pair's
    a's sum to 2/μ_pair. The bottom block takes a₀ = min(1/μ, 1/μ_if), which leaves
    every other a positive; the blocks above alternate 2/μ_if − a₀ and a₀.
    """
    if mu_if == mu:
        return [mu] * (n_blocks + 1)
    if mu == 0.0:  # a zero coefficient makes every pair it is in frictionless
        return [0.0] + [mu_if] * n_blocks
    if mu_if == 0.0:
        return [mu] + [mu if i % 2 == 0 else 0.0 for i in range(n_blocks)]
    a0 = min(1.0 / mu, 1.0 / mu_if)
    a_odd = 2.0 / mu_if - a0
    return [1.0 / (2.0 / mu - a0)] + [1.0 / (a0 if i % 2 == 0 else a_odd)
                                       for i in range(n_blocks)]


class DrakeEngine(Engine):
    """Drake (Toyota Research Institute) multibody plant with compliant convex contact."""

    name: ClassVar[str] = "drake"
    capabilities: ClassVar[Capabilities] = Capabilities(
        dimensions=3, max_blocks=None, chamfer=True, assemblies=True, base_axes="xyz",
        cylinders=True, start3d=True, moving_start=True)
    Settings: ClassVar[type[EngineSettings]] = DrakeSettings
    presets: ClassVar[dict[str, dict[str, Any]]] = {
        "accurate": {},
        # 10x the step, Drake's own dissipation: free rocking ≤ 0.011 λ (B0 over 20 s
        # 0.037 λ), the μ 0.15 sliding pulse 1.8 % off; 2 slices halve the contact pairs
        "fast": {"timestep": 5.0e-4, "collision_slices": 2, "hunt_crossley_dissipation": None},
    }
    requires: ClassVar[tuple[str, ...]] = ("pydrake",)
    extra: ClassVar[str] = "drake"
    knob_roles: ClassVar[dict[str, KnobRole]] = {
        "timestep": KnobRole.TIME_STEP, "penetration_allowance": KnobRole.CONTACT_SOFTNESS,
        "stiction_tolerance": KnobRole.TOLERANCE, "collision_slices": KnobRole.CONTACT_POINTS}
    contact_model: ClassVar[str] = "compliant-point"

    @classmethod
    def version(cls) -> str:
        """Drake's version (its submodules are imported in the methods that use them)."""
        from importlib.metadata import PackageNotFoundError
        from importlib.metadata import version as dist_version

        pydrake = cls.library("pydrake")
        try:
            return dist_version("drake")
        except PackageNotFoundError:  # a source build of pydrake
            return str(getattr(pydrake, "__version__", "unknown"))

    # ------------------------------------------------------------------ build
    def _check_supported(self, scenario: Scenario) -> None:
        if scenario.contact.restitution > 0:
            raise UnsupportedScenario(
                "drake's compliant contact has no restitution coefficient (impacts are "
                f"plastic); restitution {scenario.contact.restitution} cannot be modelled"
            )
        mu, mu_if = scenario.contact.friction, scenario.contact.block_friction
        if scenario.geometry.column is None and 0.0 < mu and mu_if <= 0.5 * mu:
            raise UnsupportedScenario(
                f"drake combines two geometries' frictions harmonically (2 μ₁μ₂/(μ₁ + μ₂)): "
                f"the blocks of a geometry other than a column get interface friction "
                f"{mu_if:g} next to base friction {mu:g} only when the interface's exceeds "
                f"half the base's")

    def _proximity(self, s: DrakeSettings, friction: float, stiffness: float | None,
                   compliant: bool) -> Any:
        """Proximity properties shared by every geometry (blocks and ground)."""
        from pydrake.geometry import (
            AddCompliantHydroelasticProperties,
            AddContactMaterial,
            AddRigidHydroelasticProperties,
            ProximityProperties,
        )
        from pydrake.multibody.plant import CoulombFriction

        p = ProximityProperties()
        AddContactMaterial(s.hunt_crossley_dissipation, stiffness,
                           CoulombFriction(friction, friction), p)
        if s.relaxation_time is not None:
            p.AddProperty("material", "relaxation_time", s.relaxation_time)
        if s.contact_model != "point":
            if compliant:
                AddCompliantHydroelasticProperties(s.hydroelastic_resolution,
                                                   s.hydroelastic_modulus, p)
            else:
                AddRigidHydroelasticProperties(s.hydroelastic_resolution, p)
        return p

    def _build(self, scenario: Scenario, settings: EngineSettings) -> float:
        from pydrake.common.eigen_geometry import Quaternion
        from pydrake.geometry import (
            Box,
            CollisionFilterDeclaration,
            GeometrySet,
            HalfSpace,
        )
        from pydrake.geometry import Cylinder as DrakeCylinder
        from pydrake.math import RigidTransform, RotationMatrix
        from pydrake.multibody.math import SpatialVelocity
        from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlantConfig
        from pydrake.multibody.tree import PrismaticJoint, SpatialInertia, UnitInertia
        from pydrake.systems.analysis import Simulator
        from pydrake.systems.framework import Diagram, DiagramBuilder

        assert isinstance(settings, DrakeSettings)
        s = settings
        geo = scenario.geometry
        blocks = scenario.blocks
        drive = self.drive
        # a base moving along x only keeps the planar benchmark's model, bit for bit: one
        # prismatic joint along x, corner spheres at the slices' centres
        planar = drive.axes == ("x",)
        # a block tilted toward an azimuth (or set moving out of the x–z plane) pivots on a
        # corner or rocks about x: corner spheres at its y faces too, as off the x axis
        ends = (drive.moving and not planar) or not scenario.planar_start
        builder = DiagramBuilder()
        cfg = MultibodyPlantConfig(
            time_step=s.timestep, contact_model=s.contact_model,
            discrete_contact_approximation=s.contact_approximation,
            penetration_allowance=s.penetration_allowance,
            stiction_tolerance=s.stiction_tolerance,
            sap_near_rigid_threshold=s.near_rigid_threshold,
        )
        plant, scene_graph = AddMultibodyPlant(cfg, builder)
        plant.mutable_gravity_field().set_gravity_vector([0.0, 0.0, -scenario.g])
        mu = scenario.contact.friction
        k = s.point_stiffness
        n_sl = s.collision_slices
        # contacts along a rocking edge (x: n_sl, or n_sl + 2 with the y faces' spheres)
        n_pts = n_sl + 2 if ends and s.corner_radius is not None else n_sl
        if k is None and s.static_penetration is not None:
            # the weight is shared by the n_pts contacts along the rocking edge
            k = 2.0 * sum(b.m for b in blocks) * scenario.g / (n_pts * s.static_penetration)
        # a column's blocks touch only the ones below and above them (alternating
        # coefficients); any other geometry's may touch other blocks and the base at once
        combine = harmonic_frictions if geo.column is not None else assembly_harmonic_frictions
        mus = combine(mu, scenario.contact.block_friction, len(blocks))
        p_blocks = {f: self._proximity(s, f, k, compliant=True) for f in set(mus[1:])}
        p_ground = self._proximity(s, mus[0], k, compliant=False)
        bodies = []
        shapes, corners = [], []  # geometry ids of the block shapes and corner spheres
        r = s.corner_radius
        for i, blk in enumerate(blocks):
            p_block = p_blocks[mus[i + 1]]
            if isinstance(blk, Cylinder):
                # Drake's own cylinder (axis along the body's z), the body's mass and
                # principal inertia; it rocks and rolls on its rim, one point per pair
                i1, _, i3 = (float(v) / blk.m for v in blk.inertia)
                body = plant.AddRigidBody(f"block{i}", SpatialInertia(
                    blk.m, np.zeros(3), UnitInertia(i1, i1, i3)))  # type: ignore[arg-type]  # pydrake stub mistypes vectors
                plant.RegisterCollisionGeometry(body, RigidTransform(),
                                                DrakeCylinder(blk.radius, blk.height),
                                                f"cylinder{i}", p_block)
                bodies.append(body)
                continue
            if isinstance(blk, Block):
                unit = UnitInertia(*(np.asarray(blk.inertia, float) / blk.m))
            else:  # a prism's x–z product of inertia is not zero: its full tensor
                t = blk.inertia_tensor / blk.m
                unit = UnitInertia(t[0, 0], t[1, 1], t[2, 2], t[0, 1], t[0, 2], t[1, 2])
            body = plant.AddRigidBody(f"block{i}", SpatialInertia(blk.m, np.zeros(3), unit))  # type: ignore[arg-type]  # pydrake stub mistypes vectors
            # n_sl slices along y, each with one contact point per pair of shapes
            d = blk.depth / n_sl
            if blk.chamfer > 0 or not isinstance(blk, Block):
                shape = _convex_prism(blk.profile(), d, f"prism{i}")
            else:
                shape = Box(blk.width, d, blk.height)
            for j in range(n_sl):
                y = (j + 0.5) * d - 0.5 * blk.depth
                shapes.append(plant.RegisterCollisionGeometry(
                    body, RigidTransform([0.0, y, 0.0]), shape, f"geom{i}_{j}", p_block))  # type: ignore[call-overload]  # pydrake stub mistypes vectors
                if r is not None and not ends:
                    corners += _add_corners(plant, body, blk.profile(), y, r, p_block,
                                            f"corner{i}_{j}")
            if r is not None and ends:
                for j, y in enumerate(corner_ys(blk.depth, n_sl, r, ends=True)):
                    corners += _add_corners(plant, body, blk.profile(), y, r, p_block,
                                            f"corner{i}_{j}")
            bodies.append(body)
        # a ground large enough for the geometry, its tilt and the base travel
        # (room: a wide geometry's spread along x too; none for a column)
        ext = geo.total_height + max(b.width for b in blocks) + geo.room
        lx = 2.0 * (2.0 * ext + 2.0 * drive.travel + 1.0)
        ly = 2.0 * (2.0 * max(b.depth for b in blocks) + 0.5)
        lz = 2.0 * (0.25 * ext + 0.1)
        if "y" in drive.axes:  # as wide as long: the base travels, the blocks rock along y
            ly = max(ly, lx)
        ground: Any = Box(lx, ly, lz)
        x_ground = RigidTransform([0.0, 0.0, -0.5 * lz])  # type: ignore[call-overload]  # pydrake stub mistypes vectors
        if scenario.has_cylinders:
            # a rim on a half-space is found in closed form (on a box by GJK/EPA)
            ground, x_ground = HalfSpace(), RigidTransform()
        self._joint = None
        self._joints: list[Any] = []  # the base's prismatic joints, one per moving axis
        self._hold = 0.0
        if not drive.moving:
            anchor = plant.world_body()  # the body of the ground and supports
            ground_id = plant.RegisterCollisionGeometry(anchor, x_ground, ground, "ground",
                                                        p_ground)
        elif planar:
            mb = _BASE_MASS_RATIO * sum(b.m for b in blocks)
            # the inertia is irrelevant (the base only slides) but must be valid
            base = plant.AddRigidBody("base", SpatialInertia(
                mb, np.zeros(3), UnitInertia.SolidBox(lx, ly, lz)))  # type: ignore[arg-type]  # pydrake stub mistypes vectors
            anchor = base
            ground_id = plant.RegisterCollisionGeometry(base, x_ground, ground, "ground",
                                                        p_ground)
            # no position limits (they would pull the base back), no damping
            self._joint = plant.AddJoint(PrismaticJoint(
                "slide", plant.world_frame(), base.body_frame(), [1.0, 0.0, 0.0],  # type: ignore[arg-type]  # pydrake stub mistypes vectors
                -math.inf, math.inf, 0.0))
            self._joints = [self._joint]
        else:
            anchor, self._joints = self._add_base_chain(plant, drive.axes, sum(b.m for b in blocks),
                                                        lx, ly, lz)
            ground_id = plant.RegisterCollisionGeometry(anchor, x_ground, ground, "ground",
                                                        p_ground)
            # the base has no weight (gravity off on its model instance) and a force along z
            # that cancels the blocks' weight on it: no net vertical force on base and
            # blocks, so the blocks' weight does not push the base down once it stands still
            # (TAMSI ignores locks), only their centroids' motion moves it, by 1e-6 of it
            self._hold = sum(b.m for b in blocks) * scenario.g if "z" in drive.axes else 0.0
        # the geometry's supports: shapes of the ground's body (welded to the moving base)
        depth = max(b.depth for b in blocks)
        for k_s, sup in enumerate(geo.supports):
            shapes.append(self._add_support(plant, anchor, sup, depth, p_ground,
                                            f"support{k_s}"))
            if r is not None:  # its corners on block faces, as the blocks' on its faces
                for j, y in enumerate(corner_ys(depth, n_sl, r, ends=ends)):
                    corners += _add_corners(plant, anchor, sup.array, y, r, p_ground,
                                            f"support{k_s}_corner{j}")
        plant.Finalize()
        if r is not None:
            # only corner–face pairs remain: a corner on the ground or on another block's
            # shape (a convex block touches a plane or a convex block at its vertices)
            manager = scene_graph.collision_filter_manager()
            manager.Apply(CollisionFilterDeclaration()
                          .ExcludeWithin(GeometrySet(shapes))
                          .ExcludeWithin(GeometrySet(corners))
                          .ExcludeBetween(GeometrySet(shapes), GeometrySet([ground_id])))
        diagram = builder.Build()
        sim = Simulator(diagram)
        root = sim.get_mutable_context()
        pc = plant.GetMyMutableContextFromRoot(root)
        if scenario.planar_start and not scenario.moving_start:
            for body, (cx, cz, a) in zip(bodies, scenario.initial_poses(), strict=True):
                plant.SetFreeBodyPose(pc, body, RigidTransform(RotationMatrix.MakeYRotation(a),  # type: ignore[call-overload]  # pydrake stub mistypes vectors
                                                               [cx, 0.0, cz]))
        else:
            # the 3D states: centroid (the body's origin), quaternion (w, x, y, z, as
            # Drake's), world-frame velocity of the centroid and angular velocity
            for body, st in zip(bodies, scenario.initial_states(), strict=True):
                q = Quaternion(*(float(v) for v in st[3:7] / np.linalg.norm(st[3:7])))
                plant.SetFreeBodyPose(pc, body, RigidTransform(q, st[:3]))
                plant.SetFreeBodySpatialVelocity(pc, body, SpatialVelocity(st[10:13], st[7:10]))
        if self._hold:
            tau = np.zeros(plant.num_velocities())
            tau[self._joints[-1].velocity_start()] = self._hold
            plant.get_applied_generalized_force_input_port().FixValue(pc, tau)
        sim.Initialize()
        # discrete state = [q; v]; a free body's q is (qw, qx, qy, qz, x, y, z)
        self._state = pc.get_discrete_state(0)
        starts = [b.floating_positions_start() for b in bodies]
        self._idx = np.array([[k + 4, k + 5, k + 6, k, k + 1, k + 2, k + 3] for k in starts])
        self._poses = np.empty((len(blocks), 7))
        self._plant, self._pc = plant, pc
        self._sim: Simulator | None = sim  # None after _teardown
        self._diagram: Diagram | None = diagram
        self._dt = float(s.timestep)
        self._steps = 0
        self._failed = False
        self._phase = s.base_velocity_phase
        self._sap = s.contact_approximation != "tamsi"
        self._chunk_start = -1
        self._planar = planar
        self._cols = [AXIS[a] for a in drive.axes]
        return self._dt

    @staticmethod
    def _add_base_chain(plant: Any, axes: tuple[str, ...], m_blocks: float, lx: float,
                        ly: float, lz: float) -> tuple[Any, list[Any]]:
        """The base of a motion that leaves the x axis: one prismatic joint per moving axis
        (x, y, z order), chained through bodies of the base's mass, the last one carrying
        the ground; gravity is off on them (a model instance of their own). Returns the
        ground's body and the joints."""
        from pydrake.multibody.tree import PrismaticJoint, SpatialInertia, UnitInertia

        instance = plant.AddModelInstance("base")
        mb = _BASE_MASS_RATIO * m_blocks
        parent, joints = plant.world_frame(), []
        for k, a in enumerate(axes):
            name = "base" if k == len(axes) - 1 else f"base_{a}"
            body = plant.AddRigidBody(name, instance, SpatialInertia(
                mb, np.zeros(3), UnitInertia.SolidBox(lx, ly, lz)))  # type: ignore[arg-type]  # pydrake stub mistypes vectors
            joints.append(plant.AddJoint(PrismaticJoint(
                f"slide_{a}", parent, body.body_frame(), _UNIT[a],  # type: ignore[arg-type]  # pydrake stub mistypes vectors
                -math.inf, math.inf, 0.0)))
            parent = body.body_frame()
        plant.set_gravity_enabled(instance, False)
        return body, joints

    @staticmethod
    def _add_support(plant: Any, body: Any, sup: Support, depth: float, props: Any,
                     name: str) -> Any:
        """Register a fixed support's shape on the base ``body``, twice ``depth`` deep:
        a ``Box`` if it is an axis-aligned rectangle, else the ``Convex`` of its prism."""
        from pydrake.geometry import Box
        from pydrake.math import RigidTransform

        v = sup.array
        lo, hi = v.min(axis=0), v.max(axis=0)
        if len(v) == 4 and all(len(set(col)) == 2 for col in v.T.tolist()):
            shape = Box(float(hi[0] - lo[0]), 2.0 * depth, float(hi[1] - lo[1]))
            pose = RigidTransform([0.5 * float(lo[0] + hi[0]), 0.0, 0.5 * float(lo[1] + hi[1])])  # type: ignore[call-overload]  # pydrake stub mistypes vectors
        else:  # vertices in the base's frame (world coordinates at t = 0)
            shape, pose = _convex_prism(v, 2.0 * depth, name), RigidTransform()
        return plant.RegisterCollisionGeometry(body, pose, shape, name, props)

    # ------------------------------------------------------------------ drive
    def _load_chunk(self, i0: int) -> None:
        """Precompute base displacement and velocity for steps i0…i0+_CHUNK (along x, or
        one column per moving axis)."""
        drive, dt = self.drive, self._dt
        cols: Any = 0 if self._planar else self._cols
        self._u = drive.displacement(drive.grid(dt, _CHUNK, start=i0))[:, cols]
        self._v = drive.velocity(drive.grid(dt, _CHUNK, start=i0, phase=self._phase))[:, cols]
        self._chunk_start = i0

    def _drive_base(self, t: float, dt: float) -> None:
        i = int(round(t / self._dt))
        j = i - self._chunk_start
        if self._chunk_start < 0 or j >= _CHUNK or j < 0:
            self._load_chunk(i)
            j = 0
        if self._planar:
            joint = self._joint
            assert joint is not None  # _build adds the joint whenever the base moves
            joint.set_translation(self._pc, self._u[j])
            joint.set_translation_rate(self._pc, self._v[j])
            return
        pc, u, v = self._pc, self._u[j], self._v[j]
        for k, joint in enumerate(self._joints):
            joint.set_translation(pc, u[k])
            joint.set_translation_rate(pc, v[k])

    def _fix_base(self) -> bool:
        drive, pc = self.drive, self._pc
        assert self._joints  # called only while the base moves: _build added the joints
        u_end = drive.displacement(drive.end_time)
        for j, c in zip(self._joints, self._cols, strict=True):
            j.set_translation(pc, float(u_end[c]))
            j.set_translation_rate(pc, 0.0)
            if self._sap:
                j.Lock(pc)  # a zero-velocity constraint in SAP: the base cannot creep
        # TAMSI ignores locks: the base's 10⁶ mass ratio keeps the drift negligible
        return True

    # ------------------------------------------------------------------ step/read
    def _advance(self, n: int) -> None:
        if self._failed:
            return
        self._steps += n
        assert self._sim is not None  # (built by _build)
        try:
            self._sim.AdvanceTo(self._steps * self._dt)
        except RuntimeError as exc:
            if "failed to converge" not in str(exc):
                raise
            # TAMSI's Newton iteration did not converge (a step too long for the stiff
            # contact): the run ends as unstable (NaN poses), Drake's reason logged
            _log.warning("drake: %s", str(exc).split(". ", 1)[0])
            self._failed = True

    def _read_poses(self) -> np.ndarray:
        if self._failed:
            self._poses.fill(math.nan)
        else:
            np.take(self._state.value(), self._idx, out=self._poses)
        return self._poses

    def _teardown(self) -> None:
        self._sim = None
        self._diagram = None
        self._plant = None
        self._pc = None
        self._state = None
        self._joint = None
        self._joints = []
