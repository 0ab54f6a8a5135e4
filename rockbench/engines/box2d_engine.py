"""Box2D engine plugin: planar rocking in the x–z plane through Box2D v3 (``box2d-python``).

Box2D v3 (Erin Catto; MIT; the 2D physics of many games) is reached through the CFFI
binding ``box2d-python`` (import name ``box2d``), whose low-level ``box2d._box2d.lib``
exposes Box2D's C API; the plugin calls it directly. Box2D is a 2D engine: its (x, y)
plane is our (x, z) plane. Its solver is a "soft step": each step is split into
sub-steps, each solving soft contact constraints (a spring of natural frequency
``contact_hertz`` and damping ratio ``contact_damping_ratio``), integrating, and relaxing
without the soft bias; restitution is applied after the sub-steps, above a threshold
speed. Single precision (float32), one thread per world: runs are bit-identical.
Its angle is counter-clockwise positive, while our θ (about +y) is positive when a
block's top moves toward +x, so θ = −angle, and the quaternion is (cos θ/2, 0, sin θ/2, 0).

Scene: each block is a dynamic body whose origin is the block's centre of gravity, with
one polygon of :meth:`~rockbench.geometry.Block.profile` (chamfers included; radius 0);
its mass and its moment about y are set explicitly (the depth only scales the mass, so any
planar stack is exact). The polygons are built from the profile directly, not through
Box2D's ``b2ComputeHull``, which welds vertices closer than its linear slop (5 mm) and
would drop the chamfer corners of the paper's stack; a profile of more than Box2D's 8
vertices is split into convex pieces of one body. The base is a KINEMATIC body carrying a
box whose top face is z = 0 and the fixed supports (more polygons of it). No damping,
sleeping off.

Friction and restitution: Box2D mixes two shapes' frictions as √(μ_a μ_b) unless a
friction callback is given. The plugin gives the world a callback that returns the
scenario's μ for any pair with the base (or a support) and μ_if between blocks (each
shape's material id says which it is), so every pair sees its own coefficient, an
interface friction of 0 included. Restitution mixes as the larger of the two: every shape
gets the scenario's e.

Base driving (x and z: ``Capabilities.base_axes`` is ``"xz"``): before each step from
t_i the base gets the secant velocity (u_g(t_i+1) − u_g(t_i)) / dt, so that Box2D's
integration of its position over the sub-steps lands on u_g(t_i+1) and the contacts see
the step's mean velocity; its position is reset to the exact u_g at the first step of
every call (once per output sample), so that float32 rounding does not accumulate.

Presets and knobs:

* ``accurate`` (the defaults): dt 0.1 ms in 8 sub-steps, 3 kHz contacts.
* ``fast``: dt 1 ms in 16 sub-steps, 1 kHz contacts.
* ``game``: Box2D's own ``b2DefaultWorldDef`` values and 4 sub-steps at a 60 Hz step
  (what a game runs). Its step is longer than the 1 ms output interval of the catalog's
  scenarios, which the base loop refuses: it runs scenarios whose ``output_rate`` is at
  most 60 per second.
* ``timestep``, ``substeps``, ``contact_hertz``, ``contact_damping_ratio``,
  ``contact_push_max_speed``, ``restitution_threshold``, ``warm_starting``,
  ``continuous`` (:class:`Box2dSettings`).

Known limits: 2D only (a base motion along y is refused); float32; restitution acts only on
contacts approaching faster than ``restitution_threshold`` (Box2D's 1 m/s, faster than many
rocking corners: lower it for a scenario with e > 0).

See :doc:`the engine's page </engines/box2d>` in the documentation for its calibration,
measured accuracy, cost and known limits.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from rockbench.engines.base import Capabilities, Engine
from rockbench.engines.planar import refuse_out_of_plane
from rockbench.engines.settings import EngineSettings, KnobRole
from rockbench.scenarios import Scenario

__all__ = ["Box2dEngine", "Box2dSettings"]

#: Box2D's largest polygon (``B2_MAX_POLYGON_VERTICES``).
_MAX_VERTICES = 8
#: Material ids of the shapes (what the friction callback reads).
_BASE, _BLOCK = 1, 2


def _lib() -> Any:
    """Box2D's C API (``box2d._box2d.lib``), imported on first use (rule 2)."""
    return Box2dEngine.library("box2d._box2d").lib


def _ffi() -> Any:
    """The CFFI ``ffi`` object of the binding (structs, callbacks)."""
    return Box2dEngine.library("box2d._box2d").ffi


@dataclass(frozen=True)
class Box2dSettings(EngineSettings):
    """Knobs of the Box2D engine (defaults = the ``accurate`` preset).

    Presets: ``accurate`` (the defaults), ``fast`` and ``game`` (Box2D's own defaults at a
    60 Hz step). Box2D's default value is given with each knob; the measurements behind
    the choices are on the engine's documentation page.

    Parameters
    ----------
    timestep : float
        Physics time step in s (Box2D's samples: 1/60). Rounded to the nearest step that
        divides the output interval (the effective step is recorded in the trajectory's
        settings).
    substeps : int
        Sub-steps per step (the ``subStepCount`` of ``b2World_Step``; Box2D: 4). Each
        sub-step solves the soft contacts once, integrates, and relaxes them once: they
        are Box2D's solver iterations.
    contact_hertz : float
        Natural frequency in Hz of the soft contact constraint (``contactHertz``; Box2D:
        30). Box2D caps it at a quarter of the sub-step rate and doubles it for a contact
        with a body of infinite mass (the kinematic base and its supports).
    contact_damping_ratio : float
        Damping ratio of the soft contact (``contactDampingRatio``; Box2D: 10).
    contact_push_max_speed : float
        Largest speed in m/s at which an overlap is pushed apart
        (``contactPushMaxSpeed``; Box2D: 3 m/s).
    restitution_threshold : float
        Approach speed in m/s below which restitution is not applied
        (``restitutionThreshold``; Box2D: 1 m/s).
    warm_starting : bool
        Start each step's contact solve from the last step's impulses (Box2D: on).
    continuous : bool
        Continuous collision of fast dynamic bodies against static ones
        (``enableContinuous``; Box2D: on). The base is kinematic, so it hardly acts.
    """

    timestep: float = 1e-4
    substeps: int = 8
    contact_hertz: float = 3000.0
    contact_damping_ratio: float = 10.0
    contact_push_max_speed: float = 3.0
    restitution_threshold: float = 1.0
    warm_starting: bool = True
    continuous: bool = True

    def __post_init__(self) -> None:
        if not (math.isfinite(self.timestep) and self.timestep > 0):
            raise ValueError(f"timestep must be finite and > 0, got {self.timestep!r}")
        if self.substeps < 1:
            raise ValueError(f"substeps must be >= 1, got {self.substeps!r}")
        for name in ("contact_hertz", "contact_push_max_speed"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)!r}")
        for name in ("contact_damping_ratio", "restitution_threshold"):
            if not getattr(self, name) >= 0:
                raise ValueError(f"{name} must be >= 0, got {getattr(self, name)!r}")


def _pieces(profile: np.ndarray) -> list[np.ndarray]:
    """A convex counter-clockwise polygon as convex pieces of at most 8 vertices (a fan)."""
    k = len(profile)
    if k <= _MAX_VERTICES:
        return [profile]
    out = []
    i = 1
    while i < k - 1:
        j = min(i + _MAX_VERTICES - 2, k - 1)
        out.append(np.vstack([profile[:1], profile[i:j + 1]]))
        i = j
    return out


class Box2dEngine(Engine):
    """Box2D v3 (``box2d-python``, float32), a planar soft-step impulse engine."""

    name: ClassVar[str] = "box2d"
    capabilities: ClassVar[Capabilities] = Capabilities(dimensions=2, max_blocks=None,
                                                        chamfer=True, assemblies=True,
                                                        base_axes="xz")
    Settings: ClassVar[type[EngineSettings]] = Box2dSettings
    presets: ClassVar[dict[str, dict[str, Any]]] = {
        # calibration: docs/engines/box2d.md
        "accurate": {},
        "fast": {"timestep": 1e-3, "substeps": 16, "contact_hertz": 1000.0},
        # b2DefaultWorldDef() and 4 sub-steps at Box2D's 60 Hz step (what a game runs); its
        # step is longer than a 1 ms output interval
        "game": {"timestep": 1.0 / 60.0, "substeps": 4, "contact_hertz": 30.0,
                 "contact_damping_ratio": 10.0, "contact_push_max_speed": 3.0,
                 "restitution_threshold": 1.0, "warm_starting": True, "continuous": True},
    }
    requires: ClassVar[tuple[str, ...]] = ("box2d",)
    extra: ClassVar[str] = "box2d"
    knob_roles: ClassVar[dict[str, KnobRole]] = {
        "timestep": KnobRole.TIME_STEP, "substeps": KnobRole.ITERATIONS,
        "contact_hertz": KnobRole.CONTACT_STIFFNESS}
    contact_model: ClassVar[str] = "impulse"
    known_failures: ClassVar[dict[str, str]] = {}

    def __init__(self) -> None:
        self._world: Any = None
        self._base: Any = None
        self._bodies: list[Any] = []
        self._callback: Any = None
        self._dt = 0.0
        self._substeps = 1
        self._poses = np.zeros((0, 7))
        # the base's x, z at each step start and its secant velocity over the step
        self._u: list[tuple[float, float]] = []
        self._v: list[tuple[float, float]] = []
        self._u_end: tuple[float, float] = (0.0, 0.0)

    @classmethod
    def version(cls) -> str:
        """Box2D's version, with the binding's (``3.1.0 (box2d-python 0.1.2)``)."""
        from importlib import metadata

        v = _lib().b2GetVersion()
        try:
            binding = metadata.version("box2d-python")
        except metadata.PackageNotFoundError:  # pragma: no cover - a source checkout
            binding = "unknown"
        return f"{v.major}.{v.minor}.{v.revision} (box2d-python {binding})"

    # ------------------------------------------------------------------ hooks
    def _check_supported(self, scenario: Scenario) -> None:
        """Refuse out-of-plane content, which a planar engine cannot model.

        As for pymunk: every field of today's geometry model is planar (a base motion along
        y is refused by ``base_axes``); a field of the geometry, a body or a support that
        this adapter does not know to be planar (one a subclass adds) is refused when it
        is set, rather than silently ignored.
        """
        refuse_out_of_plane(self.name, scenario.geometry)

    def _build(self, scenario: Scenario, settings: EngineSettings) -> float:
        assert isinstance(settings, Box2dSettings)  # resolve_settings made it one
        s = settings
        lib, ffi = _lib(), _ffi()
        out_dt = 1.0 / scenario.output_rate
        # a whole number of steps per output interval lets samples be taken after
        # whole steps; a step longer than the interval is refused by the base loop
        dt = out_dt / max(1, round(out_dt / s.timestep)) if s.timestep <= out_dt * (1 + 1e-9) \
            else s.timestep
        self._dt, self._substeps = dt, int(s.substeps)

        wd = lib.b2DefaultWorldDef()
        wd.gravity.x, wd.gravity.y = 0.0, -scenario.g
        wd.enableSleep = False
        wd.enableContinuous = bool(s.continuous)
        wd.contactHertz = s.contact_hertz
        wd.contactDampingRatio = s.contact_damping_ratio
        wd.contactPushMaxSpeed = s.contact_push_max_speed
        wd.restitutionThreshold = s.restitution_threshold
        wd.workerCount = 1  # one thread: bit-identical runs
        c = scenario.contact
        mu, mu_if = float(c.friction), float(c.block_friction)

        # every pair sees its own coefficient: μ with the base or a support, μ_if between
        # blocks (Box2D's default mixing, √(μ_a μ_b), cannot give μ_if = 0 beside μ > 0).
        # Called when a contact is created, not per step.
        @ffi.callback("float(float, int, float, int)")
        def friction(_fa: float, ma: int, _fb: float, mb: int) -> float:
            return mu if _BASE in (ma, mb) else mu_if

        self._callback = friction
        wd.frictionCallback = friction
        world = lib.b2CreateWorld(ffi.addressof(wd))
        lib.b2World_EnableWarmStarting(world, bool(s.warm_starting))
        self._world = world

        geo = scenario.geometry
        drive = self.drive
        e = float(c.restitution)
        w_max = max(b.width for b in scenario.blocks)
        # wide enough for any toppled block, the base's travel and an assembly's spread;
        # thick enough that nothing tunnels through it
        half = 2.0 * (geo.total_height + w_max) + drive.travel + 1.0 + geo.room
        thick = max(1.0, 0.5 * geo.total_height)
        bd = lib.b2DefaultBodyDef()
        bd.type = lib.b2_kinematicBody
        bd.enableSleep = False
        base = lib.b2CreateBody(world, ffi.addressof(bd))
        ground = np.array([[-half, -thick], [half, -thick], [half, 0.0], [-half, 0.0]])
        for poly in (ground, *(sup.array for sup in geo.supports)):
            self._add_polygon(base, poly, e, mu, _BASE)
        self._base = base

        self._bodies = []
        md = ffi.new("b2MassData *")
        for blk, (cx, cz, th) in zip(scenario.blocks, scenario.initial_poses(), strict=True):
            bd = lib.b2DefaultBodyDef()
            bd.type = lib.b2_dynamicBody
            bd.enableSleep = False
            bd.position.x, bd.position.y = float(cx), float(cz)
            # Box2D's angle is counter-clockwise: angle = −θ
            bd.rotation.c, bd.rotation.s = math.cos(th), -math.sin(th)
            body = lib.b2CreateBody(world, ffi.addressof(bd))
            self._add_polygon(body, np.asarray(blk.profile(), dtype=float), e, mu_if, _BLOCK)
            # the block's own mass and moment about its centre of gravity (the origin)
            md.mass = float(blk.m)
            md.center.x = md.center.y = 0.0
            md.rotationalInertia = float(blk.inertia[1])
            lib.b2Body_SetMassData(body, md[0])
            self._bodies.append(body)
        self._poses = np.zeros((len(self._bodies), 7))

        if drive.moving:
            n = drive.steps_until_stop(dt) + int(math.ceil(out_dt / dt)) + 2
            u = drive.displacement(drive.grid(dt, n + 1))[:, ::2]  # x and z
            self._u = [tuple(p) for p in u[:-1].tolist()]
            self._v = [tuple(p) for p in (np.diff(u, axis=0) / dt).tolist()]
            self._u_end = tuple(drive.final_displacement()[::2].tolist())
        return dt

    def _add_polygon(self, body: Any, profile: np.ndarray, restitution: float,
                     friction: float, material: int) -> None:
        """Polygons of ``profile`` (body frame, counter-clockwise) on ``body``.

        The hull is filled in directly: ``b2ComputeHull`` would weld vertices closer than
        the linear slop and drop collinear ones within twice it (the chamfer corners).
        """
        lib, ffi = _lib(), _ffi()
        sd = lib.b2DefaultShapeDef()
        sd.friction = friction
        sd.restitution = restitution
        sd.material = material
        sd.updateBodyMass = False  # the blocks' mass is set explicitly
        sd.density = 0.0
        for piece in _pieces(profile):
            hull = ffi.new("b2Hull *")
            for i, (x, z) in enumerate(piece.tolist()):
                hull.points[i].x, hull.points[i].y = x, z
            hull.count = len(piece)
            poly = ffi.new("b2Polygon *", lib.b2MakePolygon(hull, 0.0))
            lib.b2CreatePolygonShape(body, ffi.addressof(sd), poly)

    def _drive_base(self, t: float, dt: float) -> None:
        lib = _lib()
        i = int(round(t / self._dt))
        if i < len(self._v):
            u, v = self._u[i], self._v[i]
        else:  # beyond the precomputed window (should not happen): hold still
            u, v = self._u_end, (0.0, 0.0)
        lib.b2Body_SetTransform(self._base, u, (1.0, 0.0))
        lib.b2Body_SetLinearVelocity(self._base, v)

    def _advance_driven(self, t0: float, n: int, dt: float) -> None:
        # _drive_base + _advance(1) per step in one loop, except that the base position is
        # reset at the first step of the call only: in between Box2D integrates it from the
        # secant velocity, which lands on u(t_{i+1}) up to float32 rounding
        i0 = int(round(t0 / self._dt))
        if i0 + n > len(self._v):  # past the precomputed window (should not happen)
            super()._advance_driven(t0, n, dt)
            return
        lib = _lib()
        step, set_vel, world, base = (lib.b2World_Step, lib.b2Body_SetLinearVelocity,
                                      self._world, self._base)
        h, sub = self._dt, self._substeps
        lib.b2Body_SetTransform(base, self._u[i0], (1.0, 0.0))
        for v in self._v[i0:i0 + n]:
            set_vel(base, v)
            step(world, h, sub)

    def _fix_base(self) -> bool:
        lib = _lib()
        lib.b2Body_SetTransform(self._base, self._u_end, (1.0, 0.0))
        lib.b2Body_SetLinearVelocity(self._base, (0.0, 0.0))
        return True

    def _advance(self, n: int) -> None:
        step, world, h, sub = _lib().b2World_Step, self._world, self._dt, self._substeps
        for _ in itertools.repeat(None, n):
            step(world, h, sub)

    def _sample_free(self, out: np.ndarray, k: int) -> None:
        """All ``len(out)`` samples in one loop over locally bound C calls."""
        lib = _lib()
        step, world, h, sub = lib.b2World_Step, self._world, self._dt, self._substeps
        get_pos, get_rot, atan2 = lib.b2Body_GetPosition, lib.b2Body_GetRotation, math.atan2
        cos, sin, bodies, repeat = math.cos, math.sin, self._bodies, itertools.repeat
        rows: list[tuple[float, ...]] = []
        add = rows.append
        for _ in repeat(None, out.shape[0]):
            for _ in repeat(None, k):
                step(world, h, sub)
            for b in bodies:
                p, q = get_pos(b), get_rot(b)
                half = -0.5 * atan2(q.s, q.c)  # θ/2 with θ = −angle
                add((p.x, 0.0, p.y, cos(half), 0.0, sin(half), 0.0))
        out.reshape(-1, 7)[:] = rows

    def _read_poses(self) -> np.ndarray:
        lib = _lib()
        out = self._poses
        for i, b in enumerate(self._bodies):
            p, q = lib.b2Body_GetPosition(b), lib.b2Body_GetRotation(b)
            half = -0.5 * math.atan2(q.s, q.c)  # θ/2 with θ = −angle
            out[i] = (p.x, 0.0, p.y, math.cos(half), 0.0, math.sin(half), 0.0)
        return out

    def _teardown(self) -> None:
        if self._world is not None:
            lib = _lib()
            lib.b2DestroyWorld(self._world)
        self._world = self._base = self._callback = None
        self._bodies = []
        self._u, self._v = [], []
