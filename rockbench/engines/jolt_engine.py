"""Jolt engine plugin: rigid blocks in 3D through the ``culverin`` bindings of Jolt Physics.

Jolt Physics (MIT; the default 3D physics of Godot 4, and of Horizon Forbidden West) is
a game engine: a sequential-impulse solver of velocity steps then position steps
(Baumgarte), contacts made speculatively within a few centimetres, positions in double
precision in this build, rotations and velocities in single precision. ``culverin``
(MIT, CPython ≥ 3.12, x86-64 with AVX2) reaches it from Python. It exposes little of
Jolt: the time step, the world's gravity and thread count, per-body friction,
restitution, motion type, allowed degrees of freedom, CCD, velocities and poses. Jolt's
own settings keep their defaults, whatever rockbench would choose: 10 velocity and 2
position steps, Baumgarte 0.2, a 2 cm speculative distance and a 2 cm penetration slop
(culverin 0.15 reads ``penetration_slop`` but never passes it on), a 5 cm convex radius
on boxes and hulls, linear and angular damping of 0.05 /s on every dynamic body, and
sleeping allowed. Each run owns one :class:`culverin.PhysicsWorld` with one worker
thread (runs are bit-identical).

Scene: each block is a dynamic body: a box (``SHAPE_BOX``) or the convex hull of its
prism (polygonal prisms, and chamfered blocks unless ``chamfer_shape`` asks for the box
spanning their flat faces), its mass given; Jolt computes the inertia from the shape's
volume (a box's exactly, a hull's with the cut corners of a chamfer), and culverin
reports the centre of mass as the body's position. The base is a box whose top face is
z = 0, and each fixed support is one more body (a box or a hull): static on a still
base, kinematic under a moving one. The blocks are free in 3D (``planar`` restricts
them to the x–z plane through Jolt's allowed degrees of freedom).
A :class:`~rockbench.geometry.Cylinder` is Jolt's cylinder (``SHAPE_CYLINDER``, its axis
along its local y): its Jolt body is the cylinder's frame turned by +90° about x, its mass
given, Jolt scaling the cylinder's exact inertia to it. A start in the x–z plane at rest is
placed from ``initial_poses`` as it always was; any other from ``initial_states``
(position, quaternion, then the velocity of the centre of mass and the angular velocity,
in world axes, once the bodies exist). Bodies exist in Jolt
only after culverin's first step: the scene is committed with a step of length 0.

The convex radius rounds the shapes that Jolt's GJK sees, but contacts between a
block's face and the base are clipped from the two shapes' actual faces, so a rocking
block still pivots on its sharp edge.

Hidden damping: Jolt multiplies every dynamic body's velocities by 1 − 0.05 dt each
step (0.05 /s of damping culverin cannot change; free rocking loses 2.5 % of its
angular velocity per half-second swing). With ``cancel_damping`` the engine divides the
blocks' velocities by that factor before every step and gravity by it once, so that
Jolt's step ends where an undamped one would.

Friction and restitution: Jolt gives a contact pair the geometric mean √(μ₁ μ₂) of its
bodies' frictions and the larger of their restitutions; each body gets coefficients
whose pairwise products are μ² (μ_if² between blocks,
:func:`~rockbench.engines.friction.product_frictions`) and the scenario's restitution.
Jolt bounces only above 1 m/s of approach speed.

Base driving (x, y and z): before each step from t_i the kinematic base gets the secant
velocity (u_g(t_{i+1}) − u_g(t_i)) / dt, which Jolt integrates (in double precision)
to u_g(t_{i+1}); its position is reset to the exact u_g at the first step of every call
(once per output sample). The blocks are woken at every call: a block at rest for half
a second falls asleep, and sleeping cannot be turned off through culverin.

Gyroscopic torque: Jolt leaves −ω × Iω out unless asked, and culverin does not ask; with
``gyroscopic`` the engine adds it before each step (Jolt's own form) to the boxes and
cylinders of a scene with a cylinder or a start out of the x–z plane.

Presets and knobs:

* ``accurate`` (the defaults): dt 0.1 ms, Jolt's damping cancelled and its dropped
  small turns added.
* ``fast``: dt 0.2 ms, the same corrections.
* ``game``: Jolt's and culverin's defaults at culverin's 60 Hz step (what a game runs):
  damping left on. Its step is longer than the 1 ms output interval of the catalog's
  scenarios, which the base loop refuses: it runs scenarios whose ``output_rate`` is at
  most 60 per second.
* ``timestep``, ``cancel_damping``, ``small_rotations``, ``gyroscopic``, ``planar``,
  ``ccd``, ``chamfer_shape``
  (:class:`JoltSettings`).

See :doc:`the engine's page </engines/jolt>` in the documentation for its calibration,
measured accuracy, cost and known limits.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar, Literal

import numpy as np

from rockbench.engines.base import Capabilities, Engine
from rockbench.engines.friction import product_frictions
from rockbench.engines.settings import EngineSettings, KnobRole
from rockbench.errors import UnsupportedScenario
from rockbench.geometry import Block, Cylinder, Support
from rockbench.geometry.polygon import area_centroid
from rockbench.scenarios import Scenario

__all__ = ["JoltEngine", "JoltSettings"]

#: Jolt's default linear and angular damping of a dynamic body (1/s), which culverin
#: leaves on: velocities are multiplied by 1 − DAMPING · dt every step.
DAMPING = 0.05

#: Jolt leaves a body's orientation unchanged in a step that turns it by 1e-6 rad or less
#: (``Body::AddRotationStep``); the square of that angle.
_SKIP2 = 1e-12

#: culverin's allowed-DOF bits for the x–z plane: translations x and z, rotation about y.
_DOF_XZ = 1 | 4 | 16


#: cos 45° = sin 45°: the half-angle terms of a quarter turn.
_HALF = math.sqrt(0.5)


def _times_x90(q: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
    """q · (a quarter turn about x), quaternions in culverin's order (x, y, z, w): the frame
    of a Jolt cylinder (axis along its y) whose axis is the z of the frame ``q``."""
    x, y, z, w = q
    return (_HALF * (w + x), _HALF * (y + z), _HALF * (z - y), _HALF * (w - x))


def _gyroscopic(q: list[float], w: tuple[float, float, float],
                inertia: tuple[float, float, float], dt: float) -> tuple[float, float, float]:
    """The angular velocity ``w`` (world axes) after the gyroscopic torque −ω × Iω of a step.

    Jolt's own ``ApplyGyroscopicForce``, in double precision: the angular momentum in the
    body's principal frame (``q``: x, y, z, w; ``inertia``: the principal moments) takes an
    explicit Euler step and is rescaled to its former magnitude, which keeps the step from
    adding energy.
    """
    qx, qy, qz, qw = q
    # into the body frame: v' = q* v q
    tx, ty, tz = 2 * (qz * w[1] - qy * w[2]), 2 * (qx * w[2] - qz * w[0]), \
        2 * (qy * w[0] - qx * w[1])
    lx = w[0] + qw * tx + (qz * ty - qy * tz)
    ly = w[1] + qw * ty + (qx * tz - qz * tx)
    lz = w[2] + qw * tz + (qy * tx - qx * ty)
    ix, iy, iz = inertia
    mx, my, mz = ix * lx, iy * ly, iz * lz
    nx = mx - dt * (ly * mz - lz * my)
    ny = my - dt * (lz * mx - lx * mz)
    nz = mz - dt * (lx * my - ly * mx)
    n2 = nx * nx + ny * ny + nz * nz
    if n2 == 0.0:
        return 0.0, 0.0, 0.0
    f = math.sqrt((mx * mx + my * my + mz * mz) / n2)
    lx, ly, lz = f * nx / ix, f * ny / iy, f * nz / iz
    # back to world axes: v = q v' q*
    tx, ty, tz = 2 * (qy * lz - qz * ly), 2 * (qz * lx - qx * lz), 2 * (qx * ly - qy * lx)
    return (lx + qw * tx + (qy * tz - qz * ty), ly + qw * ty + (qz * tx - qx * tz),
            lz + qw * tz + (qx * ty - qy * tx))


def _culverin() -> Any:
    """The culverin module, imported on first use (rule 2 of the engine contract)."""
    return JoltEngine.library("culverin")


@dataclass(frozen=True)
class JoltSettings(EngineSettings):
    """Knobs of the Jolt engine (defaults = the ``accurate`` preset).

    Presets: ``accurate`` (the defaults), ``fast`` and ``game`` (Jolt's and culverin's
    own defaults at culverin's 60 Hz step). The default of Jolt or culverin is given with
    each knob; the measurements behind the choices are on the engine's documentation
    page. Jolt's solver iterations, Baumgarte factor, speculative contact distance,
    penetration slop, convex radius and sleeping are not reachable through culverin.

    Parameters
    ----------
    timestep : float
        Physics time step in s (culverin's ``step()``: 1/60). Rounded to the nearest
        step that divides the output interval (the effective step is recorded in the
        trajectory's settings). The one knob of the solver culverin exposes.
    cancel_damping : bool
        Undo Jolt's linear and angular damping of 0.05 /s, which culverin leaves on
        every dynamic body (Jolt multiplies the velocities by 1 − 0.05 dt each step):
        the blocks' velocities are divided by that factor before every step and the
        world's gravity by it once, so that Jolt's step ends where an undamped step
        would. Off in Jolt (there is no damping to cancel) and in the ``game`` preset.
    small_rotations : bool
        Add the turns Jolt drops (Jolt: dropped). Jolt leaves a body's orientation as it
        was in a step that would turn it by 1e-6 rad or less (its float32 quaternion),
        while its centre of mass moves on: a block slower than 1e-6 / dt rad/s (0.01 rad/s
        at 0.1 ms) does not turn, and its pivot slides: a block released near λ starts
        that slowly. With this on, the engine adds the skipped turns up and applies them
        once they exceed 1e-6 rad.
    gyroscopic : bool
        Add the gyroscopic torque −ω × Iω (Jolt: left out; culverin does not set Jolt's
        ``mApplyGyroscopicForce``, so a free body keeps its angular velocity's direction
        in world axes), in Jolt's own form, before each step, to the boxes and cylinders of
        a scene with a cylinder or a start out of the x–z plane. Off in the ``game`` preset.
    planar : bool
        Restrict each block to the x–z plane (Jolt's allowed degrees of freedom:
        translations x and z, rotation about y; culverin: all six). A base motion along
        y is then unsupported.
    ccd : bool
        Continuous collision detection of the blocks (Jolt's ``LinearCast`` motion
        quality; culverin: off).
    chamfer_shape : {"hull", "narrow_box"}
        Shape of a chamfered block: the convex hull of the chamfered prism (default;
        its inertia is the prism's), or the box spanning its flat faces (its rocking
        pivots exactly, collided by Jolt's box routines, but its inertia is the
        narrower box's: about 1 % low on the paper's stack).
    """

    timestep: float = 1e-4
    cancel_damping: bool = True
    small_rotations: bool = True
    gyroscopic: bool = True
    planar: bool = False
    ccd: bool = False
    chamfer_shape: Literal["hull", "narrow_box"] = "hull"

    def __post_init__(self) -> None:
        if not (math.isfinite(self.timestep) and self.timestep > 0):
            raise ValueError(f"timestep must be finite and > 0, got {self.timestep!r}")


class JoltEngine(Engine):
    """Jolt Physics through ``culverin``, one single-threaded PhysicsWorld per simulation."""

    name: ClassVar[str] = "jolt"
    capabilities: ClassVar[Capabilities] = Capabilities(dimensions=3, max_blocks=None,
                                                        chamfer=True, assemblies=True,
                                                        base_axes="xyz", cylinders=True,
                                                        start3d=True, moving_start=True)
    Settings: ClassVar[type[EngineSettings]] = JoltSettings
    presets: ClassVar[dict[str, dict[str, Any]]] = {
        # calibration: docs/engines/jolt.md
        "accurate": {},
        "fast": {"timestep": 2e-4},
        # Jolt's and culverin's defaults at culverin's 60 Hz step, the blocks free in 3D
        # (what a game runs); its step is longer than a 1 ms output interval
        "game": {"timestep": 1.0 / 60.0, "cancel_damping": False, "small_rotations": False,
                 "gyroscopic": False, "planar": False,
                 "ccd": False},
    }
    requires: ClassVar[tuple[str, ...]] = ("culverin",)
    extra: ClassVar[str] = "jolt"
    knob_roles: ClassVar[dict[str, KnobRole]] = {
        "timestep": KnobRole.TIME_STEP, "chamfer_shape": KnobRole.COLLISION_SHAPE}
    contact_model: ClassVar[str] = "impulse"
    known_failures: ClassVar[dict[str, str]] = {}

    def __init__(self) -> None:
        self._world: Any = None
        self._c: Any = None
        self._base: list[int] = []
        self._bodies: list[int] = []
        self._rows = np.zeros(0, dtype=np.intp)
        self._pos = np.zeros((0, 4))
        self._rot = np.zeros((0, 4), dtype=np.float32)
        self._lin = np.zeros((0, 4), dtype=np.float32)
        self._ang = np.zeros((0, 4), dtype=np.float32)
        # each block's body origin from the centre of mass Jolt reports, in its frame
        self._offsets = np.zeros((0, 3))
        # which blocks are cylinders, whose Jolt frame is theirs turned by +90° about x
        self._turned = np.zeros(0, dtype=bool)
        self._any_turned = False
        self._boost = 1.0
        self._catch_up = False
        self._extra = False
        self._skipped: list[list[float]] = []
        # each block's principal moments in its Jolt frame, where the gyroscopic torque is
        # added (None: left to Jolt)
        self._gyro: list[tuple[float, float, float] | None] = []
        self._dt = 0.0
        self._poses = np.zeros((0, 7))
        # the base's displacement at each step start and its secant velocity over the step
        self._u: list[tuple[float, float, float]] = []
        self._v: list[tuple[float, float, float]] = []
        self._u_end: tuple[float, float, float] = (0.0, 0.0, 0.0)
        self._origins: list[tuple[float, float, float]] = []

    @classmethod
    def version(cls) -> str:
        """culverin's version (``"0.15.0"``; its build details follow in parentheses)."""
        return str(_culverin().__version__).split(" ", 1)[0]

    # ------------------------------------------------------------------ hooks
    def _check_supported(self, scenario: Scenario) -> None:
        c = scenario.contact
        if scenario.geometry.column is None and c.block_friction == 0.0 < c.friction:
            raise UnsupportedScenario(
                "jolt combines two bodies' frictions by their geometric mean: frictionless "
                "block-block joints with friction on the base cannot both hold in a geometry "
                "whose blocks touch each other and the base (not a column)")

    def _build(self, scenario: Scenario, settings: EngineSettings) -> float:
        assert isinstance(settings, JoltSettings)  # resolve_settings made it one
        s = settings
        if s.planar and "y" in self.drive.axes:
            # settings are not visible to _check_supported, hence here
            raise UnsupportedScenario(
                "jolt: planar=True locks the blocks' motion along y, so a base motion along "
                "y cannot drag them; run it with planar=false")
        if s.planar and (scenario.has_cylinders or not scenario.planar_start):
            raise UnsupportedScenario(
                "jolt: planar=True holds boxes in the x–z plane: run cylinders and starts "
                "out of that plane with planar=false")
        if s.planar and any(not isinstance(b, Block) or (b.chamfer > 0.0 and
                                                         s.chamfer_shape == "hull")
                            for b in scenario.blocks):
            raise UnsupportedScenario(
                "jolt: culverin's convex hulls take no allowed degrees of freedom, so "
                "planar=True holds boxes only: run prisms and chamfered blocks with "
                "planar=false (or chamfer_shape='narrow_box')")
        c = _culverin()
        self._c = c
        out_dt = 1.0 / scenario.output_rate
        # a whole number of steps per output interval lets samples be taken after
        # whole steps; a step longer than the interval is refused by the base loop
        dt = out_dt / max(1, round(out_dt / s.timestep)) if s.timestep <= out_dt * (1 + 1e-9) \
            else s.timestep
        self._dt = dt
        # Jolt damps v ← (v + g dt)(1 − c dt): velocities divided by (1 − c dt) before
        # the step and gravity divided by it once make the step end at v + g dt
        self._boost = 1.0 / (1.0 - DAMPING * dt) if s.cancel_damping else 1.0
        g = scenario.g * self._boost
        self._catch_up = s.small_rotations
        # the gyroscopic torque, in a scene that can turn a body off its principal axes:
        # one with a cylinder or started out of the x–z plane (a block started in it rocks
        # about a principal axis and is run as it always was)
        spin = s.gyroscopic and (scenario.has_cylinders or not scenario.planar_start)
        self._extra = s.cancel_damping or s.small_rotations or spin

        n_bodies = scenario.geometry.n_bodies + len(scenario.geometry.supports) + 1
        # one worker thread: bit-identical runs, and no oversubscription of shared cores
        world = c.PhysicsWorld(settings={"gravity": (0.0, 0.0, -g), "num_threads": 1,
                                         "max_bodies": max(16, 2 * n_bodies)})
        geo = scenario.geometry
        con = scenario.contact
        # the pair sees √(μ₁ μ₂): per-body coefficients whose products are μ²
        mus = product_frictions(geo, con.friction ** 2, con.block_friction ** 2)
        e = con.restitution  # Jolt takes the larger of the two: every body gets e

        drive = self.drive
        moving = drive.moving
        motion = c.MOTION_KINEMATIC if moving else c.MOTION_STATIC
        blocks = scenario.blocks
        depth = max(b.depth for b in blocks)
        # wide enough for any toppled block, the base's travel and an assembly's spread
        reach = max(0.5 * b.width for b in blocks) + geo.total_height + drive.travel + geo.room
        half_x = max(1.0, 2.0 * reach)
        half_y = max(1.0, 2.0 * reach, depth)
        half_z = max(0.5, 0.5 * geo.total_height)
        self._base = [world.create_body(pos=(0.0, 0.0, -half_z), size=(half_x, half_y, half_z),
                                        shape=c.SHAPE_BOX, motion=motion, friction=mus[0],
                                        restitution=e)]
        self._origins = [(0.0, 0.0, -half_z)]
        for sup in geo.supports:
            handle, origin = self._support_body(c, world, sup, depth, motion, mus[0], e)
            self._base.append(handle)
            self._origins.append(origin)

        self._bodies, offsets = [], []
        # a start in the x–z plane at rest is placed from its (x, z, angle) poses, as it
        # always was (bit-identical planar runs); any other from its 3D states
        in_plane = scenario.initial_azimuth == 0.0 and not scenario.moving_start
        states = scenario.initial_states()
        self._turned = np.array([isinstance(blk, Cylinder) for blk in blocks], dtype=bool)
        for i, (blk, (cx, cz, th), mu) in enumerate(zip(blocks, scenario.initial_poses(),
                                                        mus[1:], strict=True)):
            quat = (0.0, math.sin(0.5 * th), 0.0, math.cos(0.5 * th))  # culverin: x, y, z, w
            pos = (float(cx), 0.0, float(cz))
            if not in_plane:
                pos = (float(states[i, 0]), float(states[i, 1]), float(states[i, 2]))
                qw, qx, qy, qz = (float(v) for v in states[i, 3:7])
                quat = (qx, qy, qz, qw)
            if isinstance(blk, Cylinder):
                # Jolt's cylinder has its axis along its local y: the Jolt body's frame is
                # the cylinder's turned by +90° about x (its y onto the cylinder's z)
                quat = _times_x90(quat)
            kw = dict(rot=quat, mass=float(blk.m), friction=mu, restitution=e, ccd=s.ccd)
            hy = 0.5 * blk.depth
            if isinstance(blk, Cylinder):
                # (half height, radius); with the mass given Jolt scales the cylinder's
                # exact inertia to it: (I1, I3, I1) about its x, y, z
                handle = world.create_body(pos=pos, size=(float(blk.h), float(blk.radius)),
                                           shape=c.SHAPE_CYLINDER, **kw)
                offsets.append((0.0, 0.0, 0.0))
            elif isinstance(blk, Block) and (blk.chamfer == 0.0 or s.chamfer_shape == "narrow_box"):
                # a box (a chamfered block: the box spanning its flat faces, its pivots)
                hx = blk.pivot_half_width if blk.chamfer > 0.0 else blk.b
                handle = world.create_body(pos=pos, size=(hx, hy, blk.h), shape=c.SHAPE_BOX,
                                           allowed_dofs=_DOF_XZ if s.planar else 0, **kw)
                offsets.append((0.0, 0.0, 0.0))
            else:
                profile = np.asarray(blk.profile(), float)
                # Jolt puts the body at the hull's centre of mass, the profile's area
                # centroid, which a prism may place off its own centre of gravity
                o = np.asarray(area_centroid(profile)[1], float)
                handle = world.create_convex_hull(
                    pos=pos, points=self._prism_points(profile, hy), **kw)
                offsets.append((-o[0], 0.0, -o[1]))
            self._bodies.append(handle)
        # bodies exist in Jolt only after a step: commit the scene without moving it
        world.step(0.0)
        for handle in self._bodies:
            world.activate(handle)
        self._world = world
        self._offsets = np.array(offsets, float).reshape(-1, 3)
        self._any_turned = bool(self._turned.any())
        # the principal moments in each Jolt body's frame (a cylinder's axis: its y); hulls
        # (their inertia turned off the body's axes by Jolt) are left to Jolt
        self._gyro = [None if not spin or off.any() else
                      ((i[0], i[2], i[1]) if turned else (i[0], i[1], i[2]))
                      for off, turned, i in zip(self._offsets, self._turned.tolist(),
                                                (tuple(float(v) for v in b.inertia)
                                                 for b in blocks), strict=True)]
        if scenario.moving_start:
            self._set_velocities(states)
        self._skipped = [[0.0, 0.0, 0.0] for _ in self._bodies]
        # the shadow buffers (no body is created after this: a live view blocks resizing)
        self._rows = np.array([world.get_index(h) for h in self._bodies], dtype=np.intp)
        self._pos = np.frombuffer(world.positions, dtype=np.float64).reshape(-1, 4)
        self._rot = np.frombuffer(world.rotations, dtype=np.float32).reshape(-1, 4)
        self._lin = np.frombuffer(world.velocities, dtype=np.float32).reshape(-1, 4)
        self._ang = np.frombuffer(world.angular_velocities, dtype=np.float32).reshape(-1, 4)
        self._poses = np.zeros((len(blocks), 7))

        if moving:
            n = drive.steps_until_stop(dt) + int(math.ceil(out_dt / dt)) + 2
            u = drive.displacement(drive.grid(dt, n + 1))
            self._u = [tuple(p) for p in u[:-1].tolist()]
            self._v = [tuple(p) for p in (np.diff(u, axis=0) / dt).tolist()]
            self._u_end = tuple(drive.final_displacement().tolist())
        return dt

    def _set_velocities(self, states: np.ndarray) -> None:
        """Give each block the velocities of its start (:meth:`Scenario.initial_states`).

        The states' velocity is that of the block's centre of gravity (the body's origin)
        and its angular velocity is in world axes, as Jolt's; Jolt's linear velocity is that
        of the body's centre of mass (a hull's may lie off the origin, by −offset).
        """
        world = self._world
        for handle, state, o in zip(self._bodies, states, self._offsets, strict=True):
            v, w = np.array(state[7:10], float), np.array(state[10:13], float)
            if o.any():
                # the centre of mass lies at −o from the origin in the block's frame
                qw, qv = float(state[3]), np.array(state[4:7], float)
                t = 2.0 * np.cross(qv, -o)
                v += np.cross(w, -o + qw * t + np.cross(qv, t))
            world.set_linear_velocity(handle, *(float(a) for a in v))
            world.set_angular_velocity(handle, *(float(a) for a in w))

    @staticmethod
    def _prism_points(profile: np.ndarray, half_depth: float) -> np.ndarray:
        """The vertices of ``profile`` (x, z) extruded over ±``half_depth``, flat float32."""
        return np.array([(x, y, z) for x, z in profile for y in (-half_depth, half_depth)],
                        dtype=np.float32).ravel()

    @classmethod
    def _support_body(cls, c: Any, world: Any, sup: Support, depth: float, motion: int,
                      mu: float, e: float) -> tuple[int, tuple[float, float, float]]:
        """A fixed support as one more body of the base; returns it and its origin."""
        v = sup.array
        lo, hi = v.min(axis=0), v.max(axis=0)
        if len(v) == 4 and all(len(set(col)) == 2 for col in v.T.tolist()):
            # an axis-aligned rectangle: a box, collided with box blocks exactly
            half, centre = 0.5 * (hi - lo), 0.5 * (hi + lo)
            origin = (float(centre[0]), 0.0, float(centre[1]))
            return world.create_body(pos=origin, size=(float(half[0]), depth, float(half[1])),
                                     shape=c.SHAPE_BOX, motion=motion, friction=mu,
                                     restitution=e), origin
        # a hull placed at its centroid (Jolt reports hulls at their centre of mass)
        centroid = np.asarray(area_centroid(np.asarray(v, float))[1], float)
        origin = (float(centroid[0]), 0.0, float(centroid[1]))
        points = cls._prism_points(np.asarray(v, float) - centroid, depth)
        return world.create_convex_hull(pos=origin, rot=(0.0, 0.0, 0.0, 1.0), points=points,
                                        motion=motion, friction=mu, restitution=e), origin

    # ------------------------------------------------------------------ drive
    def _place_base(self, u: tuple[float, float, float], v: tuple[float, float, float]) -> None:
        world = self._world
        for handle, (ox, oy, oz) in zip(self._base, self._origins, strict=True):
            world.set_position(handle, ox + u[0], oy + u[1], oz + u[2])
            world.set_linear_velocity(handle, *v)

    def _drive_base(self, t: float, dt: float) -> None:
        i = int(round(t / self._dt))
        if i < len(self._v):
            self._place_base(self._u[i], self._v[i])
        else:  # beyond the precomputed window (should not happen): hold still
            self._place_base(self._u_end, (0.0, 0.0, 0.0))

    def _advance_driven(self, t0: float, n: int, dt: float) -> None:
        # _drive_base + _advance(1) per step in one loop, except that the base position
        # is reset at the first step of the call only: in between Jolt integrates it
        # from the secant velocity, which lands on u(t_{i+1})
        i0 = int(round(t0 / self._dt))
        if i0 + n > len(self._v):  # past the precomputed window (should not happen)
            super()._advance_driven(t0, n, dt)
            return
        world = self._world
        for handle in self._bodies:  # a block asleep on the base would not be dragged
            world.activate(handle)
        self._place_base(self._u[i0], self._v[i0])
        set_v, step, base = world.set_linear_velocity, world.step, self._base
        extra, pre = self._extra, self._pre_step
        for v in self._v[i0 + 1:i0 + n]:
            if extra:
                pre()
            step(dt)
            for handle in base:
                set_v(handle, *v)
        if extra:
            pre()
        step(dt)

    def _fix_base(self) -> bool:
        self._place_base(self._u_end, (0.0, 0.0, 0.0))
        return True

    def _pre_step(self) -> None:
        """What the engine adds before each Jolt step (``cancel_damping``, ``small_rotations``).

        Reads each block's velocities as Jolt left them: divides them by 1 − c dt, which
        Jolt's damping multiplies back; and adds the rotation Jolt skipped in the last step
        (|ω| dt ≤ 1e-6 rad) to the block's orientation once the skipped turns add up to
        more than that.
        """
        k, dt = self._boost, self._dt
        lin, ang, rot = self._lin, self._ang, self._rot
        world = self._world
        gyro = self._gyro
        for j, (handle, r) in enumerate(zip(self._bodies, self._rows.tolist(), strict=True)):
            wx, wy, wz, _ = ang[r].tolist()
            inertia = gyro[j]
            if inertia is not None:
                wx, wy, wz = _gyroscopic(rot[r].tolist(), (wx, wy, wz), inertia, dt)
                world.set_angular_velocity(handle, k * wx, k * wy, k * wz)
            if k != 1.0:
                vx, vy, vz, _ = lin[r].tolist()
                world.set_linear_velocity(handle, k * vx, k * vy, k * vz)
                if inertia is None:
                    world.set_angular_velocity(handle, k * wx, k * wy, k * wz)
            if not self._catch_up:
                continue
            acc = self._skipped[j]
            if (wx * wx + wy * wy + wz * wz) * dt * dt <= _SKIP2:
                # Jolt left the orientation as it was: keep the turn for later
                acc[0] += wx * dt
                acc[1] += wy * dt
                acc[2] += wz * dt
                turn2 = acc[0] * acc[0] + acc[1] * acc[1] + acc[2] * acc[2]
                if turn2 <= _SKIP2:
                    continue
            elif not (acc[0] or acc[1] or acc[2]):
                continue
            # q ← exp(acc / 2) · q, in double precision; Jolt stores it in float32
            angle = math.sqrt(acc[0] * acc[0] + acc[1] * acc[1] + acc[2] * acc[2])
            sa = math.sin(0.5 * angle) / angle
            dw, dx, dy, dz = math.cos(0.5 * angle), acc[0] * sa, acc[1] * sa, acc[2] * sa
            qx, qy, qz, qw = rot[r].tolist()
            world.set_rotation(handle,
                               dw * qx + dx * qw + dy * qz - dz * qy,
                               dw * qy - dx * qz + dy * qw + dz * qx,
                               dw * qz + dx * qy - dy * qx + dz * qw,
                               dw * qw - dx * qx - dy * qy - dz * qz)
            acc[0] = acc[1] = acc[2] = 0.0

    def _advance(self, n: int) -> None:
        step, dt = self._world.step, self._dt
        if not self._extra:
            for _ in range(n):
                step(dt)
            return
        pre = self._pre_step
        for _ in range(n):
            pre()
            step(dt)

    def _read_poses(self) -> np.ndarray:
        out = self._poses
        q = self._rot[self._rows].astype(float)  # x, y, z, w
        out[:, 3] = q[:, 3]
        out[:, 4:] = q[:, :3]
        if self._any_turned:
            # a cylinder's frame from its Jolt body's: q · (a quarter turn about −x)
            t = self._turned
            w, x, y, z = q[t, 3], q[t, 0], q[t, 1], q[t, 2]
            out[t, 3:] = _HALF * np.column_stack([w + x, x - w, y - z, y + z])
        p = self._pos[self._rows, :3]
        if self._offsets.any():
            # the body origin (the block's centre of gravity) from the centre of mass
            w, x, y, z = out[:, 3], out[:, 4], out[:, 5], out[:, 6]
            ox, oy, oz = self._offsets.T
            # o rotated by q (body frame → world), row by row
            tx, ty, tz = 2 * (y * oz - z * oy), 2 * (z * ox - x * oz), 2 * (x * oy - y * ox)
            p = p + np.column_stack([ox + w * tx + (y * tz - z * ty),
                                     oy + w * ty + (z * tx - x * tz),
                                     oz + w * tz + (x * ty - y * tx)])
        out[:, :3] = p
        return out

    def _teardown(self) -> None:
        # release the views of the shadow buffers before the world goes
        self._pos = np.zeros((0, 4))
        self._rot = self._lin = self._ang = np.zeros((0, 4), dtype=np.float32)
        self._world = self._c = None
        self._base, self._bodies, self._origins = [], [], []
        self._u, self._v = [], []
