"""Blender engine plugin: Bullet inside Blender through ``bpy``, the paper's own tool.

Every build starts from an empty factory scene (``bpy`` is one global Blender session;
a worker not on the thread that imported ``bpy`` empties it through the data API). Each
block is a mesh object with an ACTIVE rigid body of the block's mass and a ``box``,
``convex`` (hull) or ``mesh`` collision shape (``collision_shape``); the base is a
PASSIVE box whose top face is z = 0, kinematic ("animated") when it moves. Every
rigid-body property Blender would default (:data:`BLENDER_DEFAULTS`: damping, friction,
margin) is set explicitly, and deactivation is off. Bullet multiplies the two bodies'
friction and restitution, so each body gets a coefficient such that every pair's
product is the scenario's (:func:`~rockbench.engines.friction.product_frictions`).

Time stepping is Blender's: each frame of 1/``fps`` s is split into
``substeps_per_frame`` Bullet steps, Δt = 1 / (fps · n_s), and the simulation advances
only when the scene moves to the next frame, so the base class sees one frame as its
step. The base is placed at the exact u_g of every frame and Blender interpolates it
linearly in between, so its velocity is the frame's secant (``drive`` selects a motor
constraint instead). The base motion is applied along x, y and z (the base placed at
(u_x, u_y, u_z); ``drive="motor"`` slides it along x only). A base that travels
without bound (a :class:`~rockbench.scenarios.TiltTable`'s ramp) is kept still and
gravity is tilted by −ü_g instead: single-precision Bullet cannot follow a base tens of
metres away.

Presets and knobs:

* ``accurate`` (the defaults): 1000 fps × 10 sub-steps (Δt 0.1 ms), 20 iterations,
  ``planar``: each block held in the x–z plane by a rigid body constraint from the
  base, which removes the pivot creep and out-of-plane wobble of free blocks (ignored,
  the blocks built free, for a base moving along y or a 3D start).
* ``fast``: Δt 1 ms (one sub-step per frame), 50 iterations, ``planar``.
* ``paper``: the paper's set-up (240 fps × 20 sub-steps, 100 iterations, box shapes,
  1e-5 m margin, split impulse off, free blocks); the ``paper-sensitivity`` suite
  varies it.
* The paper's Table 2 knobs: ``fps``, ``substeps_per_frame``, ``solver_iterations``,
  ``collision_shape``, ``collision_margin`` (with ``use_margin``).

A :class:`~rockbench.geometry.Cylinder` is Blender's CYLINDER collision shape (Bullet's
btCylinderShapeZ, axis along the body's z), sized by its mesh's bounds, with the body's
mass; bpy exposes no inertia, so it is Bullet's own of the solid cylinder. 3D starts are
unsupported: Blender has no initial velocity for a rigid body.

Known limits: Bullet's contact breaking threshold, which Blender does not expose, keeps
a lifted corner in contact late in free rocking (the slender B0 is the least accurate);
convex polygonal prisms are unsupported (bpy sets no inertia); poses are float32.

See :doc:`the engine's page </engines/blender>` in the documentation for its
calibration, measured accuracy and cost.
"""

from __future__ import annotations

import math
import os
import sys
import threading
from dataclasses import dataclass
from types import ModuleType
from typing import Any, ClassVar, Literal

import numpy as np

from rockbench.engines.base import Capabilities, Engine
from rockbench.engines.drive import BaseDrive
from rockbench.engines.friction import product_frictions
from rockbench.engines.settings import EngineSettings, KnobRole
from rockbench.errors import EngineUnavailable, UnsupportedScenario
from rockbench.geometry import Cylinder, Support
from rockbench.scenarios import Scenario

__all__ = ["BlenderEngine", "BlenderSettings", "BLENDER_DEFAULTS", "BPY_PYTHON"]

#: The only Python (major, minor) for which bpy 5.0 wheels exist (checked with
#: ``pip index versions bpy`` / ``pip download``: Requires-Python ==3.11.*).
BPY_PYTHON = (3, 11)

#: Blender 5.0's defaults of a new rigid body (read back from bpy): none of them is
#: what a rocking benchmark wants, so every one is overwritten in ``_build``.
BLENDER_DEFAULTS: dict[str, Any] = {
    "linear_damping": 0.04, "angular_damping": 0.1, "friction": 0.5, "restitution": 0.0,
    "collision_margin": 0.04, "use_margin": False, "collision_shape": "CONVEX_HULL",
    "use_deactivation": False, "substeps_per_frame": 10, "solver_iterations": 10,
    "use_split_impulse": False, "fps": 24,
}

#: Process id and thread that imported bpy (see :func:`_empty_scene`).
_BPY_HOME: list[int] = []

_SHAPES = {"box": "BOX", "convex": "CONVEX_HULL", "mesh": "MESH"}
#: Largest integer frame rate Blender accepts (``render.fps``).
_MAX_FPS = 32767
#: Last frame Blender's scene and point cache accept (MAXFRAME).
_MAX_FRAME = 1048574
#: Mass of a motor-driven base per kg of blocks: contact impulses barely move it.
_MOTOR_BASE_MASS = 1e4


@dataclass(frozen=True)
class BlenderSettings(EngineSettings):
    """Knobs of the Blender engine: exactly those of the paper's Table 2 (defaults = ``accurate``).

    Parameters
    ----------
    fps : float
        Scene frame rate (frames per second); Blender's ``render.fps / render.fps_base``.
        The base motion is imposed once per frame.
    substeps_per_frame : int
        Rigid body world ``substeps_per_frame`` n_s: Bullet steps per frame, each of
        Δt = 1 / (fps · n_s) (measured; not the paper's 1 / ((n_s + 1) · fps)).
    solver_iterations : int
        Rigid body world ``solver_iterations`` (sequential-impulse iterations).
    use_split_impulse : bool
        Rigid body world ``use_split_impulse``: penetration recovery by a separate
        position-only impulse instead of Baumgarte velocity terms.
    collision_shape : {"box", "convex", "mesh"}
        Per object ``collision_shape``: BOX, CONVEX_HULL of the block's prism (used for
        chamfered blocks whatever this knob says, unless "mesh"), or MESH.
    use_margin : bool
        Per object ``use_margin``: use ``collision_margin`` (True) or Blender's implicit
        0.04 m (False; for hulls Blender then shrinks the hull by it and rounds its
        corners back out).
    collision_margin : float
        Per object ``collision_margin`` in m (paper: 1e-3, 1e-5, 1e-6), when ``use_margin``.
    friction : float or None
        Coulomb coefficient of every contact; None: the scenario's. Each body gets its
        square root (Bullet multiplies the two).
    restitution : float or None
        Restitution of every contact; None: the scenario's (square root per body).
    linear_damping, angular_damping : float
        Per object damping (Blender's defaults 0.04 and 0.1; here 0: no hidden damping).
    drive : {"kinematic", "motor"}
        How a moving base is driven. ``kinematic``: the paper's animated PASSIVE body,
        placed at u_g(t_f) at every frame (Bullet derives its velocity from the
        transforms Blender interpolates per sub-step). ``motor``: a velocity drive, the
        base an ACTIVE body (10⁴ × the blocks' mass) held by a GENERIC constraint to
        slide along x only and given the velocity (u_g(t_f) − u_g(t_{f−1})) · fps by a
        MOTOR constraint's target velocity, set every frame (Blender exposes no rigid
        body velocity to Python; the motor is the only velocity input).
    planar : bool
        Hold every block in the rocking plane with a rigid body constraint (GENERIC,
        from the base to the block, collisions kept): y translation, roll and yaw
        locked, x, z and the rocking angle free. Without it Bullet's contact friction
        lets the sticking pivot creep and the block twist out of plane, the main error
        of free rocking (see the engine's documentation page). The paper's blocks were free (False).
        Ignored (the blocks built free) for a base moving along y and for a 3D start.
    """

    fps: float = 1000.0
    substeps_per_frame: int = 10
    solver_iterations: int = 20
    use_split_impulse: bool = True
    collision_shape: Literal["box", "convex", "mesh"] = "box"
    use_margin: bool = True
    collision_margin: float = 1e-5
    friction: float | None = None
    restitution: float | None = None
    linear_damping: float = 0.0
    angular_damping: float = 0.0
    drive: Literal["kinematic", "motor"] = "kinematic"
    planar: bool = True

    def __post_init__(self) -> None:
        if not (math.isfinite(self.fps) and 0.0 < self.fps <= 32767.0):
            raise ValueError(f"fps must be in (0, 32767], got {self.fps!r}")
        if not 1 <= self.substeps_per_frame <= 32767:
            raise ValueError(f"substeps_per_frame must be in [1, 32767], "
                             f"got {self.substeps_per_frame!r}")
        if not 1 <= self.solver_iterations <= 1000:
            raise ValueError(f"solver_iterations must be in [1, 1000], "
                             f"got {self.solver_iterations!r}")
        if not 0.0 <= self.collision_margin <= 1.0:
            raise ValueError(f"collision_margin must be in [0, 1] m, got {self.collision_margin!r}")
        if self.friction is not None and not self.friction >= 0.0:
            raise ValueError(f"friction must be >= 0, got {self.friction!r}")
        if self.restitution is not None and not 0.0 <= self.restitution <= 1.0:
            raise ValueError(f"restitution must be in [0, 1], got {self.restitution!r}")
        for name in ("linear_damping", "angular_damping"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(f"{name} must be in [0, 1], got {getattr(self, name)!r}")

    @property
    def frame(self) -> float:
        """Frame period 1/fps (s): the unit in which Blender advances."""
        return 1.0 / self.fps

    @property
    def dt(self) -> float:
        """Bullet's physics time step Δt = 1 / (fps · substeps_per_frame) (s)."""
        return 1.0 / (self.fps * self.substeps_per_frame)


class BlenderEngine(Engine):
    """Bullet inside Blender (``bpy``), stepped frame by frame."""

    name: ClassVar[str] = "blender"
    capabilities: ClassVar[Capabilities] = Capabilities(
        dimensions=3, max_blocks=None, chamfer=True, assemblies=True, prisms=False,
        base_axes="xyz", cylinders=True, start3d=True,
        no_prisms=("Bullet gives a convex hull the inertia of its bounding box and bpy exposes "
                   "no inertia (a voussoir of arch-9v-t0.15 would get +16 to +70 % about y), "
                   "and hulls not symmetric about their centroid explode at the first step in "
                   "Blender (measured: an arch voussoir 250 m/s); the same Bullet builds prisms "
                   "through pybullet (--engine bullet)"))
    Settings: ClassVar[type[EngineSettings]] = BlenderSettings
    #: bpy is one global Blender session per process: a fresh worker for every run
    fresh_process: ClassVar[bool] = True
    requires: ClassVar[tuple[str, ...]] = ("bpy",)
    extra: ClassVar[str] = "blender"
    knob_roles: ClassVar[dict[str, KnobRole]] = {
        "fps": KnobRole.FRAME_RATE, "substeps_per_frame": KnobRole.SUBSTEPS,
        "solver_iterations": KnobRole.ITERATIONS, "collision_shape": KnobRole.COLLISION_SHAPE,
        "collision_margin": KnobRole.COLLISION_MARGIN}
    # the step is 1 / (fps · substeps_per_frame): doubling the frame rate halves it
    # (KnobRole.SUBSTEPS refines Bullet's (n + 1) convention, not Blender's n)
    refinement: ClassVar[str] = "fps"
    contact_model: ClassVar[str] = "impulse"
    presets: ClassVar[dict[str, dict[str, Any]]] = {
        # Δt 0.1 ms (1000 fps × 10 sub-steps), 20 iterations, blocks held in the rocking
        # plane (50 iterations: as accurate on free rocking, but one of the mirrored
        # 3 Hz/8 mm pulses rocks 0.6 % higher, 0.014 λ apart; 20: 0.0004 λ):
        # calibration on the engine's page (`rockbench calibrate blender`)
        "accurate": {},
        # Δt 1 ms, one step per frame, 50 iterations, planar
        "fast": {"fps": 1000.0, "substeps_per_frame": 1, "solver_iterations": 50},
        # the paper's Blender set-up as far as it is printed: box shapes, the middle
        # values of its Table 2 (100 iterations, 20 sub-steps, 1e-5 m margin) at its
        # highest rate, 240 fps (its 3.5 s per 20 s at 240 fps fits 20 sub-steps, not
        # 200; and 2 sub-steps at 240 fps stop B0 at 10.4 s, the paper's 10–11 s),
        # Blender's default split impulse (off), free blocks. Δt = 1/4800 s by Blender's
        # rule.
        "paper": {"fps": 240.0, "substeps_per_frame": 20, "solver_iterations": 100,
                  "use_split_impulse": False, "collision_shape": "box", "use_margin": True,
                  "collision_margin": 1e-5, "planar": False},
    }
    known_failures: ClassVar[dict[str, str]] = {}
    # Table 2 is the paper's study of its own Blender settings: vary them from there
    # (free blocks, not the planar constraint of accurate, which keeps B0 rocking to
    # 13.6 s where the paper's free block stops at 10-11 s at 240 fps, 2 sub-steps)
    sensitivity_preset: ClassVar[str] = "paper"

    def __init__(self) -> None:
        self._bpy: Any = None
        self._scene: Any = None
        self._blocks: list[Any] = []
        #: An assembly's support objects and their rest x (m).
        self._supports: list[tuple[Any, float]] = []
        self._base: Any = None
        self._motor: Any = None
        self._view_layer: Any = None
        self._frame = 1
        self._frame_length = 0.0
        #: A base that runs away (a tilting table), run in its own frame as tilted gravity.
        self._tilt = False
        self._g = 9.81
        self._u: list[Any] = []
        self._axes: tuple[str, ...] = ("x",)
        #: Rest locations of the base and the supports (x, y, z), moved by u_g off the x axis.
        self._base_rest: tuple[float, float, float] = (0.0, 0.0, 0.0)
        self._support_rest: list[tuple[float, ...]] = []
        self._poses = np.zeros((0, 7))
        #: Where the base ended (m along x), recorded at teardown.
        self.base_end = math.nan

    @classmethod
    def library(cls, module: str) -> ModuleType:
        """Import a library (rule 2), noting which process and thread first imported bpy."""
        fresh = module == "bpy" and module not in sys.modules
        try:
            lib = super().library(module)
        except EngineUnavailable as exc:
            if module == "bpy" and sys.version_info[:2] != BPY_PYTHON:
                raise EngineUnavailable(
                    f"{exc}; note: bpy (Blender as a Python module) is built only for the "
                    f"CPython that Blender embeds, {BPY_PYTHON[0]}.{BPY_PYTHON[1]} for Blender "
                    f"5.0, and this is Python {sys.version_info[0]}.{sys.version_info[1]}"
                ) from exc
            raise
        if fresh:
            _BPY_HOME[:] = [os.getpid(), threading.get_ident()]
        return lib

    @classmethod
    def version(cls) -> str:
        """Blender's version string (``bpy.app.version_string``)."""
        return str(cls.library("bpy").app.version_string)

    # ------------------------------------------------------------------ hooks
    def _check_supported(self, scenario: Scenario) -> None:
        c = scenario.contact
        if c.block_friction == 0.0 < c.friction and scenario.n_blocks > 1:
            raise UnsupportedScenario(
                "blender: Bullet multiplies the two bodies' friction coefficients: "
                "frictionless block-block joints with friction on the base cannot both hold")

    def _build(self, scenario: Scenario, settings: EngineSettings) -> float:
        assert isinstance(settings, BlenderSettings)  # resolve_settings made it one
        s = settings
        if s.collision_shape == "mesh" and scenario.n_blocks > 1:
            raise UnsupportedScenario("blender: collision_shape='mesh' models single blocks "
                                      "only (two concave meshes do not collide in Bullet)")
        # a frame longer than the output interval is run as n_s frames of one sub-step
        # each (same Bullet steps, same kinematic targets: bit-identical at the knob's frames)
        split = 1.0 / s.fps > (1.0 + 1e-9) / scenario.output_rate
        fps = s.fps * s.substeps_per_frame if split else s.fps
        substeps = 1 if split else s.substeps_per_frame
        frame = 1.0 / fps
        n_frames = int(math.ceil(scenario.duration / frame - 1e-9)) + 2
        if 1 + n_frames > _MAX_FRAME:
            raise UnsupportedScenario(f"blender: {scenario.duration:g} s at {fps:g} frames "
                                      f"per second is more than Blender's {_MAX_FRAME} frames")
        bpy = self._bpy = self.library("bpy")
        _empty_scene(bpy)
        scene = self._scene = bpy.context.scene
        # FPS = fps / fps_base: an integer fps (Blender's field, at most 32767) and a base
        scene.render.fps = min(_MAX_FPS, max(1, math.ceil(fps - 1e-9)))
        scene.render.fps_base = scene.render.fps / fps
        scene.frame_start, scene.frame_end = 1, 1 + n_frames
        scene.frame_set(1)
        bpy.ops.rigidbody.world_add()
        world = scene.rigidbody_world
        world.enabled = True
        world.time_scale = 1.0
        world.substeps_per_frame = substeps
        world.solver_iterations = s.solver_iterations
        world.use_split_impulse = s.use_split_impulse
        world.point_cache.frame_start = 1
        world.point_cache.frame_end = 1 + n_frames
        self._g = scenario.g
        scene.gravity = (0.0, 0.0, -scenario.g)
        scene.use_gravity = True

        c = scenario.contact
        if s.friction is not None:
            mus = [math.sqrt(s.friction)] * (scenario.n_blocks + 1)
        else:  # Bullet multiplies the two bodies' coefficients (every pair gets its own)
            mus = product_frictions(scenario.geometry, c.friction, c.block_friction)
        e = math.sqrt(c.restitution if s.restitution is None else s.restitution)

        drive = self.drive
        geo = scenario.geometry
        blocks = scenario.blocks
        # wide scenes (not a column) need the blocks' spread along x too (geo.room)
        reach = max(0.5 * b.width for b in blocks) + geo.total_height + drive.travel + geo.room
        depth = max(b.depth for b in blocks)
        half = (max(1.0, 2.0 * reach), max(1.0, 2.0 * reach, depth), 0.5)
        base = self._base = _prism(bpy, scene, "base", _box_profile(half[0], half[2]),
                                   half[1])
        base.location = (0.0, 0.0, -half[2])
        # a base that travels without bound (a tilting table) is run in its own frame, the
        # scene's gravity tilted (rule: _runs_away; see _drive_base)
        self._tilt = _runs_away(drive)
        moving = drive.moving and not self._tilt
        motor = moving and s.drive == "motor"
        self._axes = drive.axes
        if motor and self._axes != ("x",):
            raise UnsupportedScenario("blender: drive='motor' slides the base along x only; "
                                      "a base motion along y or z needs drive='kinematic'")
        # the planar constraint holds a block in the base's x–z plane: a scene that leaves it
        # (a base moving along y, a cylinder, a 3D start) builds free bodies whatever it says
        planar = s.planar and _stays_planar(scenario, drive)
        self._base_rest = (0.0, 0.0, -half[2])
        _rigid_body(bpy, base, s, type_="ACTIVE" if motor else "PASSIVE", shape="BOX",
                    mass=_MOTOR_BASE_MASS * sum(b.m for b in blocks) if motor else 1.0,
                    friction=mus[0], restitution=e, kinematic=moving and not motor)
        self._motor = _motor_drive(bpy, scene, base, s) if motor else None
        # an assembly's supports: PASSIVE bodies of the base's kind, placed with it
        self._supports = []
        for k, sup in enumerate(geo.supports):
            if motor:
                raise UnsupportedScenario("blender: drive='motor' moves the base body only; "
                                          "an assembly's supports need drive='kinematic'")
            ob, shape = _support(bpy, scene, k, sup, depth,
                                 s.collision_margin if s.use_margin else 0.0)
            _rigid_body(bpy, ob, s, type_="PASSIVE", shape=shape, mass=1.0,
                        friction=mus[0], restitution=e, kinematic=moving)
            self._supports.append((ob, float(ob.location.x)))
        self._support_rest = [tuple(ob.location) for ob, _ in self._supports]

        self._blocks = []
        states = scenario.initial_states()
        for i, (blk, (cx, cz, a), mu) in enumerate(zip(
                blocks, scenario.initial_poses(), mus[1:], strict=True)):
            if isinstance(blk, Cylinder):
                # Bullet's own cylinder (btCylinderShapeZ, axis along the object's z) sized
                # by the mesh's bounds; its mass set, its inertia Bullet's exact solid
                # cylinder's (bpy exposes none), its margin inside the radius and height
                ob = _cylinder(bpy, scene, f"block{i}", blk.radius, blk.height)
                ob.location = tuple(states[i, :3].tolist())
                ob.rotation_mode = "QUATERNION"
                ob.rotation_quaternion = tuple(states[i, 3:7].tolist())
                _rigid_body(bpy, ob, s, type_="ACTIVE", shape="CYLINDER", mass=blk.m,
                            friction=mu, restitution=e, kinematic=False)
                self._blocks.append(ob)
                if planar:
                    _planar_constraint(bpy, scene, base, ob)
                continue
            shape = _SHAPES[s.collision_shape]
            if blk.chamfer > 0.0 and shape == "BOX":
                shape = "CONVEX_HULL"
            # Bullet inflates hulls and triangles by the margin Blender gives it (a box
            # keeps its size): shrink the prism by it so the block has its own faces
            m = s.collision_margin if s.use_margin and shape != "BOX" else 0.0
            ob = _prism(bpy, scene, f"block{i}", _offset_polygon(blk.profile(), m),
                        0.5 * blk.depth - m)
            ob.rotation_mode = "QUATERNION"
            if scenario.initial_azimuth == 0.0:
                ob.location = (float(cx), 0.0, float(cz))
                ob.rotation_quaternion = (math.cos(0.5 * a), 0.0, math.sin(0.5 * a), 0.0)
            else:  # tilted toward an azimuth: a column's block (its frame is the block's)
                ob.location = tuple(states[i, :3].tolist())
                ob.rotation_quaternion = tuple(states[i, 3:7].tolist())
            _rigid_body(bpy, ob, s, type_="ACTIVE", shape=shape, mass=blk.m, friction=mu,
                        restitution=e, kinematic=False)
            self._blocks.append(ob)
            if planar:
                _planar_constraint(bpy, scene, base, ob)
        self._poses = np.zeros((len(blocks), 7))

        # base displacement at every frame end (frame f is time (f − 1) / fps); split
        # frames get Blender's sub-step targets, linear between the knob's frames
        if moving:
            t = drive.grid(frame, n_frames + 1)
            t_key = np.arange(n_frames // s.substeps_per_frame + 2) / s.fps if split else t
            u3 = drive.displacement(np.minimum(t_key, drive.end_time))
            if self._axes == ("x",):  # the planar benchmark's values, bit for bit
                u = u3[:, 0]
                self._u = (np.interp(t, t_key, u) if split else u).tolist()
            else:  # (x, y, z) per frame
                if split:
                    u3 = np.column_stack([np.interp(t, t_key, u3[:, k]) for k in range(3)])
                self._u = [tuple(p) for p in u3.tolist()]
        else:
            self._u = []
        self._view_layer = scene.view_layers[0]
        self._frame, self._frame_length = 1, frame
        scene.frame_set(1)
        return frame

    def _drive_base(self, t: float, dt: float) -> None:
        if self._tilt:
            # in the base's frame every body feels −m·ü_g besides its weight: exact for a
            # translating base; ü_g is linear in t, so its mid-frame value is the frame's mean
            if self._axes == ("x",):
                a = float(self.drive.acceleration(t + 0.5 * dt)[0])
                self._scene.gravity = (-a, 0.0, -self._g)
            else:
                ax, ay, az = self.drive.acceleration(t + 0.5 * dt).tolist()
                self._scene.gravity = (-ax, -ay, -self._g - az)
            return
        # the frame ending at t + dt: the base is there when Blender steps into it
        i = min(int(round(t / dt)) + 1, len(self._u) - 1)
        if self._motor is None:
            # evaluated now, before the frame step reads it (Blender sometimes stepped before
            # evaluating the base's new transform, and runs did not repeat)
            self._place_base(self._u[i])
        else:
            # a positive target velocity moves object2 (the base) toward −x (measured)
            self._motor.motor_lin_target_velocity = -(self._u[i] - self._u[i - 1]) / dt

    def _fix_base(self) -> bool:
        if self._motor is not None:
            self._motor.motor_lin_target_velocity = 0.0
        elif self._u:
            self._place_base(self._u[-1])
        return True

    def _place_base(self, u: float | tuple[float, ...]) -> None:
        """Put the base (and the supports) at displacement ``u`` and evaluate the scene.

        ``u`` is the x displacement of a base moving along x only (the planar benchmark's
        path, bit for bit), else the (x, y, z) displacement.
        """
        if isinstance(u, float):
            self._base.location.x = u
            for ob, x0 in self._supports:
                ob.location.x = x0 + u
        else:
            b0 = self._base_rest
            self._base.location = (b0[0] + u[0], b0[1] + u[1], b0[2] + u[2])
            for (ob, _), r in zip(self._supports, self._support_rest, strict=True):
                ob.location = (r[0] + u[0], r[1] + u[1], r[2] + u[2])
        self._view_layer.update()

    def _advance(self, n: int) -> None:
        frame_set, f = self._scene.frame_set, self._frame
        for j in range(f + 1, f + n + 1):
            frame_set(j)
        self._frame = f + n

    def _read_poses(self) -> np.ndarray:
        out = self._poses
        for i, ob in enumerate(self._blocks):
            m = ob.matrix_world
            q = m.to_quaternion()
            p = m.translation
            out[i] = (p.x, p.y, p.z, q.w, q.x, q.y, q.z)
        if self._tilt:  # from the base's frame to the world's
            if self._axes == ("x",):
                out[:, 0] += self._tilt_displacement()
            else:
                out[:, :3] += self.drive.displacement((self._frame - 1) * self._frame_length)
        return out

    def _tilt_displacement(self) -> float:
        """u_g at the current frame of a tilting table (the base's frame's offset)."""
        return float(self.drive.displacement((self._frame - 1) * self._frame_length)[0])

    def _teardown(self) -> None:
        if self._tilt:
            self.base_end = self._tilt_displacement()
        elif self._base is not None:
            self.base_end = float(self._base.matrix_world.translation.x)
        if self._bpy is not None:
            _empty_scene(self._bpy)
        self._bpy = self._scene = self._base = self._motor = self._view_layer = None
        self._tilt = False
        self._blocks = []
        self._supports = []
        self._u = []


def _stays_planar(scenario: Scenario, drive: BaseDrive) -> bool:
    """Whether the ``planar`` constraint may hold the scene's blocks in the x–z plane.

    It locks each block's y, roll and yaw to the base: a base moving along y would carry
    the blocks rigidly along y, and a 3D start's motion leaves the plane, so such a scene
    is built with free bodies (the knob ignored, not refused: the ``accurate`` and
    ``fast`` presets set it). A cylinder released in the plane keeps it.
    """
    return "y" not in drive.axes and scenario.planar_start and not scenario.moving_start


def _runs_away(drive: BaseDrive) -> bool:
    """Whether the base is run in its own frame, as tilted gravity (see :meth:`_drive_base`).

    The rule: the base's horizontal travel has no bound over unbounded time. Single-precision
    Bullet cannot follow such a base (a tilting table's ramp, u_g ∝ t³, reaches tens of
    metres at metres per second), while every bounded motion (pulses, sinusoids, records:
    centimetres to decimetres) is placed kinematically. Of today's motions this picks
    exactly the tilting table, whose uniformly growing ü_g also makes the mid-frame value
    the frame's mean; it needs nothing but the drive (never the excitation's type). A
    never-ending motion with no closed-form bound (its ``motion_bounds`` refuses an
    infinite horizon) is placed kinematically like any other.
    """
    if not drive.moving or math.isfinite(drive.end_time):
        return False  # a base that stops travels a bounded distance
    try:
        bound = drive.motion.horizontal_bounds()[0]
    except ValueError:
        return False
    return not math.isfinite(bound)


def _empty_scene(bpy: Any) -> None:
    """Reset Blender's global session to an empty factory scene.

    Blender loads files (the factory settings too) only on the thread that imported
    bpy: a process forked from another thread (the runner's pool forks its workers
    from a manager thread) crashes with SIGSEGV in ``read_factory_settings`` if its
    parent had imported bpy. There the scene is emptied through the data API instead
    (rigid body world, objects, meshes and collections removed; every setting the
    build uses is set again by the build). Rigid body constraints are removed by their
    operator first: removing the world with them in it crashed such workers (SIGSEGV in
    ``world_remove``, 4 of 8 planar stack runs of ``paper-stack-pulse``).
    """
    if _BPY_HOME == [os.getpid(), threading.get_ident()]:
        bpy.ops.wm.read_factory_settings(use_empty=True)
        return
    scene = bpy.context.scene
    for ob in [o for o in bpy.data.objects if o.rigid_body_constraint is not None]:
        _operator(bpy, scene, ob, bpy.ops.rigidbody.constraint_remove)
    if scene.rigidbody_world is not None:
        bpy.ops.rigidbody.world_remove()
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob, do_unlink=True)
    for mesh in list(bpy.data.meshes):
        bpy.data.meshes.remove(mesh)
    for coll in list(bpy.data.collections):
        bpy.data.collections.remove(coll)
    # a rigid body world added away from frame 1 starts from other transforms
    scene.frame_set(1)


def _box_profile(b: float, h: float) -> np.ndarray:
    return np.array([[-b, -h], [b, -h], [b, h], [-b, h]])


def _offset_polygon(poly: np.ndarray, m: float) -> np.ndarray:
    """Move every edge of a convex counter-clockwise polygon inward by ``m``."""
    if m == 0.0:
        return poly
    d_in = np.roll(poly, -1, axis=0) - poly  # edge j: vertex j → j + 1
    d_in /= np.linalg.norm(d_in, axis=1, keepdims=True)
    n = np.column_stack([-d_in[:, 1], d_in[:, 0]])  # inward normals (counter-clockwise)
    n_prev = np.roll(n, 1, axis=0)  # the edge ending at vertex j
    # vertex j moves along the sum of its two edges' normals, m away from both
    bis = n + n_prev
    return poly + bis * (m / np.sum(bis * n, axis=1, keepdims=True))


def _prism(bpy: Any, scene: Any, name: str, profile: np.ndarray, half_depth: float) -> Any:
    """A mesh object: the x–z profile (counter-clockwise) extruded over ±half_depth in y."""
    k = len(profile)
    verts = [(float(x), y, float(z)) for x, z in profile for y in (-half_depth, half_depth)]
    # side quads (outward for a counter-clockwise profile) and the two caps
    faces: list[tuple[int, ...]] = [(2 * j, 2 * ((j + 1) % k), 2 * ((j + 1) % k) + 1, 2 * j + 1)
                                    for j in range(k)]
    faces += [tuple(2 * j for j in range(k)), tuple(2 * j + 1 for j in reversed(range(k)))]
    return _mesh_object(bpy, scene, name, verts, faces)


def _mesh_object(bpy: Any, scene: Any, name: str, verts: list[tuple[float, float, float]],
                 faces: list[tuple[int, ...]]) -> Any:
    """A mesh object of these vertices and faces, linked into the scene."""
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    mesh.update()
    ob = bpy.data.objects.new(name, mesh)
    scene.collection.objects.link(ob)
    return ob


def _cylinder(bpy: Any, scene: Any, name: str, radius: float, height: float,
              n: int = 64) -> Any:
    """A mesh object: an ``n``-gon prism about z whose bounds are 2R × 2R × H (centred).

    Blender sizes a CYLINDER collision shape from the object's bounds (radius: half the
    larger of the x and y extents, height: the z extent), so its vertices include the
    four points (±R, 0) and (0, ±R) of the rim.
    """
    if n % 4:
        raise ValueError(f"n must be a multiple of 4, got {n}")
    ring = [(radius * math.cos(2 * math.pi * j / n), radius * math.sin(2 * math.pi * j / n))
            for j in range(n)]
    hz = 0.5 * height
    verts = [(x, y, z) for x, y in ring for z in (-hz, hz)]
    faces: list[tuple[int, ...]] = [(2 * j, 2 * ((j + 1) % n), 2 * ((j + 1) % n) + 1, 2 * j + 1)
                                    for j in range(n)]
    faces += [tuple(2 * j for j in reversed(range(n))), tuple(2 * j + 1 for j in range(n))]
    return _mesh_object(bpy, scene, name, verts, faces)


def _support(bpy: Any, scene: Any, k: int, sup: Support, depth: float,
             margin: float) -> tuple[Any, str]:
    """Mesh object of a fixed support at its rest place, and its collision shape.

    An axis-aligned rectangle is a BOX (exact corners against box blocks); any other
    convex polygon a CONVEX_HULL, shrunk by the ``margin`` Bullet inflates it by. The
    support is ``2 · depth`` deep, so every block's depth lies on it.
    """
    v = sup.array
    centre = 0.5 * (v.min(axis=0) + v.max(axis=0))
    box = len(v) == 4 and all(len(set(col)) == 2 for col in v.T.tolist())
    prof = v - centre if box else _offset_polygon(v - centre, margin)
    ob = _prism(bpy, scene, f"support{k}", prof, depth)
    ob.location = (float(centre[0]), 0.0, float(centre[1]))
    return ob, "BOX" if box else "CONVEX_HULL"


def _operator(bpy: Any, scene: Any, ob: Any, op: Any, **kw: Any) -> None:
    """Run an object operator on ``ob`` with its context given explicitly.

    Off Blender's main thread (a forked worker) ``bpy.context`` has no active object,
    and ``constraint_add`` also reads the view layer's (without it: SIGSEGV).
    """
    view_layer = scene.view_layers[0]
    view_layer.objects.active = ob
    with bpy.context.temp_override(scene=scene, view_layer=view_layer, object=ob,
                                   active_object=ob, selected_objects=[ob]):
        op(**kw)


def _rigid_body(bpy: Any, ob: Any, s: BlenderSettings, *, type_: str, shape: str, mass: float,
                friction: float, restitution: float, kinematic: bool) -> None:
    """Make ``ob`` a rigid body and set every property (none left at Blender's default)."""
    _operator(bpy, ob.users_scene[0], ob, bpy.ops.rigidbody.object_add, type=type_)
    rb = ob.rigid_body
    rb.enabled = True
    rb.collision_shape = shape
    rb.mesh_source = "BASE"
    rb.use_deform = False
    rb.kinematic = kinematic
    rb.mass = mass
    rb.friction = friction
    rb.restitution = restitution
    rb.linear_damping = s.linear_damping
    rb.angular_damping = s.angular_damping
    rb.use_margin = s.use_margin
    rb.collision_margin = s.collision_margin
    rb.use_deactivation = False
    rb.use_start_deactivated = False


def _planar_constraint(bpy: Any, scene: Any, base: Any, ob: Any) -> Any:
    """A GENERIC constraint from the base to block ``ob``: y, roll and yaw locked.

    The base is object1, so the linear limits are along the constraint frame's axes
    fixed to the base. The frame sits at the block's initial centroid, turned 90° about
    z so that its x axis is the world y axis: Bullet's 6-DOF constraint measures angles
    as Euler XYZ, whose middle angle (about the frame's y) is singular at ±90°, which an
    overturning block passes (free about the frame's y, one exploded there); its x angle
    covers ±180°. Collisions stay enabled.
    """
    empty = bpy.data.objects.new(f"planar_{ob.name}", None)
    scene.collection.objects.link(empty)
    empty.location = ob.location
    empty.rotation_euler = (0.0, 0.0, 0.5 * math.pi)
    _operator(bpy, scene, empty, bpy.ops.rigidbody.constraint_add, type="GENERIC")
    c = empty.rigid_body_constraint
    c.object1, c.object2, c.disable_collisions = base, ob, False
    c.use_breaking = False
    c.use_override_solver_iterations = False
    # frame x = world y (locked), frame y = world −x, frame z = world z (free); rotation
    # free about frame x (the rocking axis), locked about frame y and z
    for axis in ("lin_x", "lin_y", "lin_z", "ang_x", "ang_y", "ang_z"):
        locked = axis in ("lin_x", "ang_y", "ang_z")
        setattr(c, f"use_limit_{axis}", locked)
        if locked:
            setattr(c, f"limit_{axis}_lower", 0.0)
            setattr(c, f"limit_{axis}_upper", 0.0)
    return c


def _motor_drive(bpy: Any, scene: Any, base: Any, s: BlenderSettings) -> Any:
    """Constraints of the ``motor`` drive: returns the MOTOR constraint whose target is set.

    A PASSIVE anchor (collision group 20, which nothing else uses) holds the base
    through a GENERIC constraint locking every freedom but x, and a MOTOR constraint
    drives its x velocity with an impulse limit no contact reaches.
    """
    anchor = _prism(bpy, scene, "anchor", _box_profile(0.5, 0.5), 0.5)
    anchor.location = (0.0, 0.0, -10.0)
    _rigid_body(bpy, anchor, s, type_="PASSIVE", shape="BOX", mass=1.0, friction=0.0,
                restitution=0.0, kinematic=False)
    groups = anchor.rigid_body.collision_collections
    groups[19], groups[0] = True, False
    made = []
    for kind in ("GENERIC", "MOTOR"):
        ob = bpy.data.objects.new(kind.lower(), None)
        scene.collection.objects.link(ob)
        _operator(bpy, scene, ob, bpy.ops.rigidbody.constraint_add, type=kind)
        c = ob.rigid_body_constraint
        c.object1, c.object2, c.disable_collisions = anchor, base, True
        c.use_breaking = False
        c.use_override_solver_iterations = False
        made.append(c)
    lock, motor = made
    for axis in ("lin_y", "lin_z", "ang_x", "ang_y", "ang_z"):
        setattr(lock, f"use_limit_{axis}", True)
        setattr(lock, f"limit_{axis}_lower", 0.0)
        setattr(lock, f"limit_{axis}_upper", 0.0)
    lock.use_limit_lin_x = False
    motor.use_motor_lin, motor.use_motor_ang = True, False
    motor.motor_lin_max_impulse = 1e9
    motor.motor_lin_target_velocity = 0.0
    return motor
