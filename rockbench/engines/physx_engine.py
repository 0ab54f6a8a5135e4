"""PhysX engine plugin: rigid blocks in 3D through SAPIEN's physics-only ``sapien.physx`` API.

NVIDIA PhysX 5 (BSD-3; the physics of Unity, Unreal Engine 4, Omniverse and Isaac) is
reached from Python on the CPU through SAPIEN 3 (Apache-2.0), whose ``sapien.physx``
module wraps PxScene, rigid bodies, materials and shapes without a renderer: no GPU and
no Vulkan device are needed (the import warns that it found no system libvulkan; the
warning is silenced). PhysX is an impulse engine in single precision: a projected
Gauss–Seidel (PGS) or temporal Gauss–Seidel (TGS) solver of position and velocity
iterations per step, contacts made speculatively within a contact offset, restitution only
above a bounce threshold velocity. Each run owns one ``PhysxCpuSystem`` without worker
threads (everything on the calling thread: bit-identical runs, no oversubscription).

Scene: each block is a dynamic body whose frame is the block's (origin at its centre of
gravity), with one shape: a box, or the convex mesh of its prism (polygonal prisms and,
by default, chamfered blocks: ``chamfer_shape``); mass and inertia are set explicitly (a
prism's principal frame as the mass frame). A :class:`~rockbench.geometry.Cylinder` is
SAPIEN's cylinder (a PhysX convex mesh of 32 segments, its axis along the shape's x, turned
onto the body's z) with the cylinder's mass and inertia. A start in the x–z plane at rest
is placed from ``initial_poses`` (bit-identical planar runs); any other from
``initial_states``: position, quaternion, the centre of mass's velocity and the angular
velocity, in world axes. The base is a box whose top face is z = 0
carrying the fixed supports as more shapes: a static body on a still base, a kinematic
body under a moving one, driven by ``set_kinematic_target`` to the base's displacement at
the end of every step (PhysX moves it there and gives its contacts the step's secant
velocity). Base motion along x, y and z. No damping (PhysX's default angular
damping is 0.05; ``angular_damping`` sets it), no sleeping (sleep threshold 0), no CCD
unless asked. PhysX combines the coefficients of two materials by their AVERAGE and SAPIEN
exposes no other combine mode, so each body gets coefficients whose pairwise means are the
scenario's μ (μ_if between blocks) and restitution
(:func:`~rockbench.engines.friction.mean_frictions`).

Presets and knobs:

* ``accurate`` (the defaults): Δt 0.1 ms, PGS with PhysX's 4 position and 1 velocity
  iterations, friction in every iteration, PhysX's 2 cm contact offset, SAT contacts
  instead of persistent contact manifolds (PCM pushed touching convex meshes apart).
* ``fast``: Δt 0.2 ms, the cheapest step within the project's 0.05 λ on free rocking.
* ``game``: PhysX's own defaults at a 60 Hz step (what a game runs): PGS, 4 position
  and 1 velocity iterations, 2 cm contact offset, bounce threshold 2 m/s, angular damping
  0.05. Its step is longer than the 1 ms output interval of the catalog's scenarios, which
  the base loop refuses: it runs scenarios whose ``output_rate`` is at most 60 per second.
* ``timestep``, ``solver``, ``position_iterations``, ``velocity_iterations``,
  ``contact_offset``, ``rest_offset``, ``bounce_threshold``, ``friction_every_iteration``,
  ``pcm``, ``angular_damping``, ``max_depenetration_velocity``, ``planar``, ``ccd``,
  ``chamfer_shape``.

See :doc:`the engine's page </engines/physx>` in the documentation for its calibration,
measured accuracy, cost and known limits.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from types import ModuleType
from typing import Any, ClassVar, Literal

import numpy as np

from rockbench.engines.base import Capabilities, Engine
from rockbench.engines.bullet_engine import principal_frame
from rockbench.engines.friction import mean_frictions
from rockbench.engines.settings import EngineSettings, KnobRole
from rockbench.errors import UnsupportedScenario
from rockbench.geometry import Block, Cylinder, Support
from rockbench.scenarios import Scenario

__all__ = ["PhysxEngine", "PhysxSettings"]

#: Floats per rigid body in ``PhysxCpuSystem.pack()``: q (w, x, y, z), p, v, ω.
_PACKED = 13


def _sapien() -> Any:
    """The sapien module, imported on first use (rule 2 of the engine contract)."""
    return PhysxEngine.library("sapien")


def _physx() -> Any:
    """The ``sapien.physx`` submodule (PhysX's scene, bodies, shapes and materials)."""
    return PhysxEngine.library("sapien.physx")


@dataclass(frozen=True)
class PhysxSettings(EngineSettings):
    """Knobs of the PhysX engine (defaults = the ``accurate`` preset).

    Presets: ``accurate`` (the defaults), ``fast`` and ``game`` (PhysX's own defaults at
    a 60 Hz step). PhysX's default value is given with each knob.

    Parameters
    ----------
    timestep : float
        Physics time step in s (what a game passes to ``PxScene::simulate``: 1/60).
        Rounded so that a whole number of steps fits one output interval (the
        effective step is recorded in the trajectory's settings); PhysX stores it in
        float32.
    solver : {"pgs", "tgs"}
        ``PxSceneDesc::solverType``: projected Gauss–Seidel (PhysX's default) or the
        temporal Gauss–Seidel solver, which integrates the positions once per position
        iteration (SAPIEN's default).
    position_iterations : int
        Position iterations of every block's solver (PhysX: 4; SAPIEN: 10).
    velocity_iterations : int
        Velocity iterations of every block's solver (PhysX: 1).
    contact_offset : float
        Distance (m) within which two shapes make (speculative) contacts; each pair
        uses the sum of its two shapes' offsets (PhysX: 0.02 with a length scale of
        1 m; SAPIEN: 0.01).
    rest_offset : float
        Distance (m) at which two shapes come to rest (PhysX: 0).
    bounce_threshold : float
        Relative normal speed (m/s) below which a contact does not bounce, whatever its
        restitution (PhysX: 2 m/s, 0.2 times the speed scale of 10 m/s, above the
        corner speeds of most rocking impacts; 0.2 m/s here so that a scenario's
        restitution acts).
    friction_every_iteration : bool
        Solve friction in every position iteration (PhysX's
        ``eENABLE_FRICTION_EVERY_ITERATION``; PhysX: off, friction in the last three
        only; SAPIEN: on).
    pcm : bool
        Persistent contact manifolds (PhysX: on). Off here: PCM pushes touching convex
        meshes apart (the 9-voussoir arch at rest gains energy within 0.02 s) and tips a
        prism on a block; PhysX's SAT contacts hold them.
    angular_damping : float
        Angular damping of the blocks, 1/s (PhysX: 0.05). Linear damping is always 0
        (PhysX's default too).
    max_depenetration_velocity : float or None
        Largest speed (m/s) at which the solver pushes penetrating bodies apart; None
        keeps PhysX's default (unbounded).
    planar : bool
        Lock each block's translation along y and rotations about x and z (PhysX's
        rigid dynamic lock flags; not in PhysX's defaults), holding it in the x–z plane.
        A base motion along y is then unsupported.
    ccd : bool
        Continuous collision detection (PhysX: off).
    chamfer_shape : {"narrow_box", "hull"}
        Shape of a chamfered block: the convex mesh of the chamfered prism (default),
        or a box spanning its flat faces (its rocking pivots exactly, collided by
        PhysX's box routines). Without PCM the paper's stack follows the two-block
        solution as hulls (4 Hz / 4 mm: −0.23 %), not as narrow boxes (2.8 %).
    """

    timestep: float = 1e-4
    solver: Literal["pgs", "tgs"] = "pgs"
    position_iterations: int = 4
    velocity_iterations: int = 1
    contact_offset: float = 0.02
    rest_offset: float = 0.0
    bounce_threshold: float = 0.2
    friction_every_iteration: bool = True
    pcm: bool = False
    angular_damping: float = 0.0
    max_depenetration_velocity: float | None = None
    planar: bool = False
    ccd: bool = False
    chamfer_shape: Literal["narrow_box", "hull"] = "hull"

    def __post_init__(self) -> None:
        if not (math.isfinite(self.timestep) and self.timestep > 0):
            raise ValueError(f"timestep must be finite and > 0, got {self.timestep!r}")
        if not 1 <= self.position_iterations <= 255:
            raise ValueError("position_iterations must be in 1..255 (PhysX's range), got "
                             f"{self.position_iterations!r}")
        if not 0 <= self.velocity_iterations <= 255:
            raise ValueError("velocity_iterations must be in 0..255 (PhysX's range), got "
                             f"{self.velocity_iterations!r}")
        if not self.contact_offset > self.rest_offset >= 0:
            raise ValueError("PhysX needs contact_offset > rest_offset >= 0, got "
                             f"{self.contact_offset!r} and {self.rest_offset!r}")
        if self.bounce_threshold < 0 or self.angular_damping < 0:
            raise ValueError("bounce_threshold and angular_damping must be >= 0")
        if self.max_depenetration_velocity is not None and not self.max_depenetration_velocity > 0:
            raise ValueError("max_depenetration_velocity must be > 0, got "
                             f"{self.max_depenetration_velocity!r}")


class PhysxEngine(Engine):
    """NVIDIA PhysX 5 through SAPIEN 3 (``sapien.physx``), one CPU scene per simulation."""

    name: ClassVar[str] = "physx"
    capabilities: ClassVar[Capabilities] = Capabilities(dimensions=3, max_blocks=None,
                                                        chamfer=True, assemblies=True,
                                                        base_axes="xyz", cylinders=True,
                                                        start3d=True, moving_start=True)
    Settings: ClassVar[type[EngineSettings]] = PhysxSettings
    presets: ClassVar[dict[str, dict[str, Any]]] = {
        # calibration: docs/engines/physx.md
        "accurate": {},
        "fast": {"timestep": 2e-4},
        # PhysX's defaults (PxSceneDesc, PxTolerancesScale, PxRigidDynamic, PxShape) at
        # 60 Hz, the blocks free in 3D: what a game runs; its step is longer than a 1 ms
        # output interval
        "game": {"timestep": 1.0 / 60.0, "solver": "pgs", "position_iterations": 4,
                 "velocity_iterations": 1, "contact_offset": 0.02, "rest_offset": 0.0,
                 "bounce_threshold": 2.0, "friction_every_iteration": False, "pcm": True,
                 "angular_damping": 0.05, "max_depenetration_velocity": None,
                 "planar": False, "ccd": False},
    }
    requires: ClassVar[tuple[str, ...]] = ("sapien",)
    extra: ClassVar[str] = "physx"
    knob_roles: ClassVar[dict[str, KnobRole]] = {
        "timestep": KnobRole.TIME_STEP, "position_iterations": KnobRole.ITERATIONS,
        "contact_offset": KnobRole.COLLISION_MARGIN, "chamfer_shape": KnobRole.COLLISION_SHAPE}
    contact_model: ClassVar[str] = "impulse"
    known_failures: ClassVar[dict[str, str]] = {}

    def __init__(self) -> None:
        self._scene: Any = None
        self._system: Any = None
        self._base: Any = None
        self._bodies: list[Any] = []
        self._rows: np.ndarray = np.zeros(0, dtype=np.intp)
        self._dt = 0.0
        self._poses = np.zeros((0, 7))
        # the base's pose at the end of each step (kinematic targets), as sapien Poses
        self._u = np.zeros((0, 3))
        self._targets: list[Any] = []
        self._target0 = 0

    @classmethod
    def library(cls, module: str) -> ModuleType:
        """Import one of the engine's libraries (rule 2), without SAPIEN's Vulkan warning.

        SAPIEN warns at import that it found no system Vulkan library (it falls back to
        its own, which only its renderer would use): the physics never needs it.
        """
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message=".*libvulkan")
            return super().library(module)

    @classmethod
    def version(cls) -> str:
        """SAPIEN's version and the PhysX it wraps (``"3.0.3 (PhysX 5.3.1)"``)."""
        sapien = _sapien()
        physx = _physx().version()
        # "105.1-physx-5.3.1.patch0": the PhysX release follows "physx-"
        release = physx.split("physx-", 1)[-1].split(".patch", 1)[0]
        return f"{sapien.__version__} (PhysX {release})"

    # ------------------------------------------------------------------ hooks
    def _check_supported(self, scenario: Scenario) -> None:
        c = scenario.contact
        if mean_frictions(scenario.geometry, c.friction, c.block_friction) is None:
            raise UnsupportedScenario(
                "physx averages the two bodies' friction coefficients: with the blocks "
                f"touching each other and the base, an interface friction {c.block_friction} "
                f"above twice the base friction {c.friction} needs a negative coefficient")

    def _build(self, scenario: Scenario, settings: EngineSettings) -> float:
        assert isinstance(settings, PhysxSettings)  # resolve_settings made it one
        s = settings
        if s.planar and "y" in self.drive.axes:
            # settings are not visible to _check_supported, hence here
            raise UnsupportedScenario(
                "physx: planar=True locks the blocks' motion along y, so a base motion "
                "along y cannot drag them; run it with planar=false")
        sapien, px = _sapien(), _physx()
        out_dt = 1.0 / scenario.output_rate
        # a whole number of steps per output interval lets samples be taken after
        # whole steps (the longest such step not longer than asked); a step longer than
        # the interval is refused by the base loop
        dt = out_dt / max(1, math.ceil(out_dt / s.timestep - 1e-9)) \
            if s.timestep <= out_dt * (1 + 1e-9) else s.timestep
        self._dt = dt

        # the scene configuration is a process-wide default read when a system is
        # created: set all of it, every run, so that no earlier run leaks into this one
        px.set_scene_config(
            gravity=np.array([0.0, 0.0, -scenario.g], dtype=np.float32),
            bounce_threshold=s.bounce_threshold, enable_pcm=s.pcm,
            enable_tgs=s.solver == "tgs", enable_ccd=s.ccd,
            enable_enhanced_determinism=False,
            enable_friction_every_iteration=s.friction_every_iteration,
            cpu_workers=0)  # no worker threads: the calling thread runs it all
        system = px.PhysxCpuSystem()
        system.timestep = dt
        scene = sapien.Scene([system])

        geo = scenario.geometry
        c = scenario.contact
        mus = mean_frictions(geo, c.friction, c.block_friction)
        assert mus is not None  # _check_supported refused the other cases
        e = c.restitution

        def shaped(shape: Any) -> Any:
            shape.contact_offset = s.contact_offset
            shape.rest_offset = s.rest_offset
            return shape

        drive = self.drive
        blocks = scenario.blocks
        depth = max(b.depth for b in blocks)
        # wide enough for any toppled block, the base's travel and an assembly's spread
        reach = max(0.5 * b.width for b in blocks) + geo.total_height + drive.travel + geo.room
        half_x = max(1.0, 2.0 * reach)
        half_y = max(1.0, 2.0 * reach, depth)
        half_z = max(0.5, 0.5 * geo.total_height)
        base_mat = px.PhysxMaterial(mus[0], mus[0], e)
        ground = shaped(px.PhysxCollisionShapeBox(
            np.array([half_x, half_y, half_z], dtype=np.float32), base_mat))
        ground.set_local_pose(sapien.Pose(np.array([0.0, 0.0, -half_z], dtype=np.float32)))
        shapes = [ground] + [shaped(self._support_shape(sapien, px, sup, depth, base_mat))
                             for sup in geo.supports]
        moving = drive.moving
        if moving:
            base = px.PhysxRigidDynamicComponent()
            base.kinematic = True
        else:
            base = px.PhysxRigidStaticComponent()
        for shape in shapes:
            base.attach(shape)
        entity = sapien.Entity()
        entity.add_component(base)
        scene.add_entity(entity)
        self._base = base

        locked = [False, True, False, True, False, True] if s.planar else [False] * 6
        # a start in the x–z plane at rest is placed from its (x, z, angle) poses, as
        # always; any other from its 3D states (position, quaternion, velocities)
        in_plane = scenario.initial_azimuth == 0.0 and not scenario.moving_start
        states = scenario.initial_states()
        self._bodies = []
        for i, (blk, (cx, cz, th), mu) in enumerate(zip(blocks, scenario.initial_poses(),
                                                        mus[1:], strict=True)):
            mat = px.PhysxMaterial(mu, mu, e)
            body = px.PhysxRigidDynamicComponent()
            if isinstance(blk, Cylinder):
                body.attach(shaped(self._cylinder_shape(sapien, px, blk, mat)))
                # its own mass and inertia, its principal axes the body's
                phi, moments = 0.0, tuple(float(j) for j in blk.inertia)
            else:
                body.attach(shaped(self._block_shape(px, blk, s, mat)))
                # the block's own mass and inertia (a chamfered block's cut corners
                # neglected, as the analytic models do); a prism's principal frame is
                # turned by φ about y
                phi, moments = principal_frame(blk.inertia_tensor)
            body.mass = float(blk.m)
            body.inertia = np.array(moments, dtype=np.float32)
            body.cmass_local_pose = sapien.Pose(q=np.array(
                [math.cos(0.5 * phi), 0.0, math.sin(0.5 * phi), 0.0], dtype=np.float32))
            body.linear_damping = 0.0
            body.angular_damping = s.angular_damping
            if s.max_depenetration_velocity is not None:
                body.max_depenetration_velocity = s.max_depenetration_velocity
            body.sleep_threshold = 0.0  # kinetic energy never below 0: never asleep
            body.solver_position_iterations = s.position_iterations
            body.solver_velocity_iterations = s.velocity_iterations
            body.set_locked_motion_axes(locked)
            ent = sapien.Entity()
            ent.add_component(body)
            if in_plane:
                ent.pose = sapien.Pose(
                    np.array([cx, 0.0, cz], dtype=np.float32),
                    np.array([math.cos(0.5 * th), 0.0, math.sin(0.5 * th), 0.0],
                             dtype=np.float32))
            else:
                # SAPIEN's quaternions are (w, x, y, z), as the states'
                ent.pose = sapien.Pose(states[i, :3].astype(np.float32),
                                       states[i, 3:7].astype(np.float32))
            scene.add_entity(ent)
            if scenario.moving_start:
                # PhysX's velocities are the centre of mass's (the body's origin: the mass
                # frame is only turned) and the angular one, both in world axes
                body.linear_velocity = states[i, 7:10].astype(np.float32)
                body.angular_velocity = states[i, 10:13].astype(np.float32)
            self._bodies.append(body)
        self._scene, self._system = scene, system
        # pack() lists every dynamic body (the kinematic base too) in the system's own
        # order: find each block's row once
        comps = system.get_rigid_dynamic_components()
        self._rows = np.array([next(j for j, comp in enumerate(comps) if comp is body)
                               for body in self._bodies], dtype=np.intp)
        self._poses = np.zeros((len(blocks), 7))

        if moving:
            n = drive.steps_until_stop(dt) + int(math.ceil(out_dt / dt)) + 2
            self._u = drive.displacement(drive.grid(dt, n + 1))
            self._targets, self._target0 = [], 0
        return dt

    @staticmethod
    def _convex(px: Any, profile: np.ndarray, half_depth: float, mat: Any) -> Any:
        """A convex prism's shape: ``profile`` (x, z) extruded over ±``half_depth``."""
        points = np.array([(x, y, z) for x, z in np.asarray(profile, float)
                           for y in (-half_depth, half_depth)], dtype=np.float32)
        return px.PhysxCollisionShapeConvexMesh(points, np.ones(3, dtype=np.float32), mat)

    @classmethod
    def _block_shape(cls, px: Any, blk: Any, s: PhysxSettings, mat: Any) -> Any:
        """A block's shape in its body frame (origin at the centre of gravity)."""
        hy = 0.5 * blk.depth
        if isinstance(blk, Block) and (blk.chamfer == 0.0 or s.chamfer_shape == "narrow_box"):
            # a chamfered block as the box spanning its flat faces: its rocking pivots
            half_x = blk.pivot_half_width if blk.chamfer > 0.0 else blk.b
            return px.PhysxCollisionShapeBox(np.array([half_x, hy, blk.h], dtype=np.float32),
                                             mat)
        return cls._convex(px, blk.profile(), hy, mat)

    @staticmethod
    def _cylinder_shape(sapien: Any, px: Any, blk: Cylinder, mat: Any) -> Any:
        """A cylinder's shape in its body frame (origin at its centre of gravity).

        SAPIEN's cylinder is a PhysX convex mesh of 32 segments (a regular 32-gon prism
        inscribed in the circle, scaled to the radius and half-length) with its axis
        along its local x: the shape is turned by −90° about y (its x onto the body's z),
        which puts two of the polygon's vertices on the body's ±x axis.
        """
        shape = px.PhysxCollisionShapeCylinder(float(blk.radius), float(blk.h), mat)
        c = math.sqrt(0.5)
        shape.set_local_pose(sapien.Pose(q=np.array([c, 0.0, -c, 0.0], dtype=np.float32)))
        return shape

    @classmethod
    def _support_shape(cls, sapien: Any, px: Any, sup: Support, depth: float, mat: Any) -> Any:
        """A fixed support's shape in the base's frame (the world's at rest)."""
        v = sup.array
        lo, hi = v.min(axis=0), v.max(axis=0)
        if len(v) == 4 and all(len(set(col)) == 2 for col in v.T.tolist()):
            # an axis-aligned rectangle: a box, collided with box blocks exactly
            half, centre = 0.5 * (hi - lo), 0.5 * (hi + lo)
            shape = px.PhysxCollisionShapeBox(
                np.array([half[0], depth, half[1]], dtype=np.float32), mat)
            shape.set_local_pose(sapien.Pose(
                np.array([centre[0], 0.0, centre[1]], dtype=np.float32)))
            return shape
        return cls._convex(px, v, depth, mat)

    # ------------------------------------------------------------------ drive
    def _target(self, i: int) -> Any:
        """The base's pose at the end of step ``i`` (a kinematic target), made in chunks."""
        j = i - self._target0
        if not 0 <= j < len(self._targets):
            sapien = _sapien()
            end = min(i + 4096, len(self._u))
            self._targets = [sapien.Pose(p) for p in self._u[i:end].astype(np.float32)]
            self._target0, j = i, 0
        return self._targets[j]

    def _drive_base(self, t: float, dt: float) -> None:
        # PhysX moves a kinematic body to its target during the step, with the secant
        # velocity (u(t + dt) − u(t)) / dt in its contacts
        i = int(round(t / self._dt)) + 1
        self._base.set_kinematic_target(self._target(min(i, len(self._u) - 1)))

    def _advance_driven(self, t0: float, n: int, dt: float) -> None:
        # _drive_base + _advance(1) per step in one loop over local names
        i0 = int(round(t0 / self._dt)) + 1
        if i0 + n > len(self._u):  # past the precomputed window (should not happen)
            super()._advance_driven(t0, n, dt)
            return
        set_target, step, target = self._base.set_kinematic_target, self._system.step, \
            self._target
        for i in range(i0, i0 + n):
            set_target(target(i))
            step()

    def _fix_base(self) -> bool:
        # a kinematic body without a new target stays where it is, at rest
        return True

    def _advance(self, n: int) -> None:
        step = self._system.step
        for _ in range(n):
            step()

    def _read_poses(self) -> np.ndarray:
        packed = np.frombuffer(self._system.pack(), dtype=np.float32).reshape(-1, _PACKED)
        out = self._poses
        rows = packed[self._rows]
        out[:, :3] = rows[:, 4:7]
        out[:, 3:] = rows[:, :4]
        return out

    def _teardown(self) -> None:
        self._scene = self._system = self._base = None
        self._bodies, self._targets = [], []
        self._u = np.zeros((0, 3))
