"""pymunk (Chipmunk2D) engine plugin: planar rocking in the x–z plane.

pymunk is a 2D engine; its (x, y) plane is our (x, z) plane. Its angle is
counter-clockwise positive, while our θ (about +y) is positive when a block's top moves
toward +x, so θ = −angle and the returned quaternion is (cos θ/2, 0, sin θ/2, 0).

Each block is a dynamic body with a convex :class:`pymunk.Poly` of
:meth:`~rockbench.geometry.Block.profile` (chamfers included, radius 0), the block's
mass and moment about y (the depth only scales the mass, so any planar stack is exact);
the base is a KINEMATIC body carrying a box whose top face is z = 0. The base motion is
applied along x and z (``Capabilities.base_axes`` is ``"xz"``): before each step from t
the base gets the velocity u̇_g(t + dt/2) (midpoint rule, the contact solver sees the
step's mean velocity) and its position is reset to the exact u_g(t), so no drift
accumulates; ``_advance_driven`` drives and steps in one loop.
Chipmunk's ``collision_slop`` is 0 here (its default 0.1 m lets shapes sink), sleeping is
off and ``damping`` is 1 (none). Chipmunk multiplies the friction and elasticity of two
shapes, so every shape gets coefficients whose products are the scenario's
(:func:`~rockbench.engines.friction.product_frictions` for an interface friction).

Presets and knobs:

* ``accurate`` (the defaults): dt 0.025 ms, the step at which the paper's stacks
  converge.
* ``fine``: dt 0.02 ms (the stack sinusoids closer).
* ``single``: dt 0.1 ms, enough for single blocks; the assembly studies' preset.
* ``fast``: dt 1 ms, 20 iterations.
* ``timestep``, ``iterations``, ``collision_slop``, ``collision_bias``.

Known limits: 2D only; a base motion along y is refused.

See :doc:`the engine's page </engines/pymunk>` in the documentation for its
calibration, measured accuracy and cost.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from rockbench.engines.base import Capabilities, Engine
from rockbench.engines.friction import product_frictions
from rockbench.engines.planar import refuse_out_of_plane
from rockbench.engines.settings import EngineSettings, KnobRole
from rockbench.errors import UnsupportedScenario
from rockbench.scenarios import Scenario

__all__ = ["PymunkEngine", "PymunkSettings"]

def _pymunk() -> Any:
    """The pymunk module, imported on first use (rule 2 of the engine contract)."""
    return PymunkEngine.library("pymunk")


@dataclass(frozen=True)
class PymunkSettings(EngineSettings):
    """Knobs of the pymunk engine (defaults = the ``accurate`` preset).

    Presets: ``accurate`` (the defaults: dt 0.025 ms, where the paper's stacks converge),
    ``fine`` (dt 0.02 ms: the stack sinusoids closer), ``fast`` (dt 1 ms, 20 iterations)
    and ``single`` (dt 0.1 ms: enough for single blocks).

    Parameters
    ----------
    timestep : float
        Physics time step in s. The main accuracy lever: impacts are resolved
        within one step and contact penetration scales with it. Best chosen
        to divide the output interval (otherwise the base loop reads every
        step and interpolates, which costs time).
    iterations : int
        Sequential-impulse solver iterations per step (pymunk default 10).
        Gauss–Seidel sweeps the contact points in a fixed order, so too few
        iterations break mirror symmetry at coarse steps (dt 1 ms: a mirrored
        sine pulse differs by 0.020 λ with 10 iterations, 0.002 λ with 20).
        With 20, single blocks match 50 and the paper stack's peak angles
        change by < 0.2 % from 20 to 50.
    collision_slop : float
        Overlap in m that Chipmunk tolerates without correction (pymunk
        default 0.1 m, far too large for blocks of a few metres; 0 here).
    collision_bias : float
        Fraction of overlap left uncorrected after one second (pymunk default
        (1 − 0.1)^60 ≈ 1.8e-3). Smaller values push penetrating shapes apart
        faster; the correction is position-level and adds no energy beyond
        the overlap it removes.
    """

    timestep: float = 2.5e-5
    iterations: int = 20
    collision_slop: float = 0.0
    collision_bias: float = (1.0 - 0.1) ** 60

    def __post_init__(self) -> None:
        if not (math.isfinite(self.timestep) and self.timestep > 0):
            raise ValueError(f"timestep must be finite and > 0, got {self.timestep!r}")
        if self.iterations < 1:
            raise ValueError(f"iterations must be >= 1, got {self.iterations!r}")
        if not (math.isfinite(self.collision_slop) and self.collision_slop >= 0):
            raise ValueError(f"collision_slop must be finite and >= 0, got {self.collision_slop!r}")
        if not (0.0 < self.collision_bias <= 1.0):
            raise ValueError(f"collision_bias must be in (0, 1], got {self.collision_bias!r}")


class PymunkEngine(Engine):
    """Rocking blocks in pymunk (Chipmunk2D), a planar impulse-based engine."""

    name: ClassVar[str] = "pymunk"
    capabilities: ClassVar[Capabilities] = Capabilities(dimensions=2, max_blocks=None,
                                                        chamfer=True, assemblies=True,
                                                        base_axes="xz")
    Settings: ClassVar[type[EngineSettings]] = PymunkSettings
    presets: ClassVar[dict[str, dict[str, Any]]] = {
        "accurate": {},
        # its calibration: the engine's page; reproduce with `rockbench calibrate pymunk`
        "fast": {"timestep": 1e-3, "iterations": 20},
        # the former accurate: the stack sinusoids within 1.7 % instead of 3.2 %, at 1.24×
        "fine": {"timestep": 2e-5},
        # single blocks as accurate, stacks 2.4 % / 8.3 % off (see above)
        "single": {"timestep": 1e-4},
    }
    requires: ClassVar[tuple[str, ...]] = ("pymunk",)
    extra: ClassVar[str] = "pymunk"
    knob_roles: ClassVar[dict[str, KnobRole]] = {
        "timestep": KnobRole.TIME_STEP, "iterations": KnobRole.ITERATIONS,
        "collision_slop": KnobRole.CONTACT_SLOP}
    contact_model: ClassVar[str] = "impulse"
    # the fast preset moves early on the tilting table; 0.1 ms meets the limit analysis
    assembly_preset: ClassVar[str] = "single"

    def __init__(self) -> None:
        self._space: Any = None
        self._blocks: list[Any] = []
        self._base: Any = None
        self._dt = 0.0
        self._step: Any = None
        self._space_ptr: Any = None
        self._body_ptrs: list[Any] = []
        self._base_ptr: Any = None
        # Chipmunk's C functions, bound once per build (see _build)
        self._set_pos: Any = None
        self._set_vel: Any = None
        self._get_pos: Any = None
        self._get_angle: Any = None
        self._poses = np.zeros((0, 7))
        # the base's x and z at each step start and velocities at each step's midpoint
        self._v_mid = np.zeros((1, 2))
        self._u_start = np.zeros((1, 2))
        self._u_list: list[float] = []
        self._v_list: list[float] = []
        # their z components; None while the base is still along z
        self._uz_list: list[float] | None = None
        self._vz_list: list[float] | None = None

    @classmethod
    def version(cls) -> str:
        """Version of pymunk."""
        return str(_pymunk().version)

    # ------------------------------------------------------------------ hooks
    def _check_supported(self, scenario: Scenario) -> None:
        """Refuse out-of-plane content, which a planar engine cannot model.

        Every field the geometry model has today is planar (bodies and supports
        are x–z polygons centred in depth, poses are x, z and an angle about +y;
        the depth only scales mass and inertia), so every current geometry is
        supported; a base motion along y is refused by ``base_axes``. A field of
        the geometry, a body or a support that this adapter does not know to be
        planar (one a subclass adds) is refused when it is set (truthy), rather
        than silently ignored.
        """
        geo = scenario.geometry
        c = scenario.contact
        if geo.column is None and c.block_friction == 0.0 < c.friction:
            raise UnsupportedScenario(
                "pymunk multiplies two shapes' frictions, so an interface friction of 0 "
                f"with μ = {c.friction:g} on the base cannot both hold in this geometry, "
                "whose blocks may touch each other and the base at once")
        refuse_out_of_plane(self.name, geo)

    def _build(self, scenario: Scenario, settings: EngineSettings) -> float:
        pymunk = _pymunk()
        assert isinstance(settings, PymunkSettings)  # resolve_settings made it one
        s = settings
        dt = float(s.timestep)
        space = pymunk.Space()
        space.gravity = (0.0, -scenario.g)
        space.iterations = int(s.iterations)
        space.collision_slop = float(s.collision_slop)
        space.collision_bias = float(s.collision_bias)
        space.damping = 1.0  # velocity kept each step: no hidden damping
        space.sleep_time_threshold = math.inf  # never sleep
        # Chipmunk multiplies the two shapes' coefficients: the square root on
        # every shape gives each contact pair exactly the scenario's values
        # (an interface friction: the base carries μ, a column's blocks alternate 1 and
        # μ_if; other geometries' blocks touch blocks and the base at once: each √μ_if)
        geo = scenario.geometry
        c = scenario.contact
        mus = product_frictions(geo, c.friction, c.block_friction)
        e = math.sqrt(scenario.contact.restitution)

        drive = self.drive
        h_tot = geo.total_height
        w_max = max(b.width for b in scenario.blocks)
        n_drive = drive.steps_until_stop(dt) + 2 if drive.stop > 0 else 0
        if n_drive:
            t0 = drive.grid(dt, n_drive)
            # x and z (pymunk's x and y) of the base
            u_start = drive.displacement(t0)[:, ::2]
            v_mid = drive.velocity(drive.grid(dt, n_drive, phase=0.5))[:, ::2]
            u_max = float(np.max(np.abs(u_start[:, 0])))
        else:
            u_start = v_mid = np.zeros((1, 2))
            u_max = 0.0
        self._u_start, self._v_mid = u_start, v_mid
        # plain floats for the stepping loop (cheaper to slice and pass than NumPy scalars)
        self._u_list, self._v_list = u_start[:, 0].tolist(), v_mid[:, 0].tolist()
        if "z" in drive.axes:
            self._uz_list, self._vz_list = u_start[:, 1].tolist(), v_mid[:, 1].tolist()
        else:
            self._uz_list = self._vz_list = None

        # base: wide enough for any toppled block plus the base travel (and, for a
        # geometry other than a column, the blocks' spread along x), and thick
        # enough that nothing tunnels through it
        half = 2.0 * (h_tot + w_max) + u_max + 1.0
        half += geo.room
        thick = max(1.0, 0.5 * h_tot)
        base = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        base.position = (0.0, 0.0)
        base_shape = pymunk.Poly(base, [(-half, -thick), (half, -thick), (half, 0.0),
                                        (-half, 0.0)], radius=0.0)
        base_shape.friction = mus[0]
        base_shape.elasticity = e
        space.add(base, base_shape)
        # the fixed supports: more shapes of the base body (the base is at
        # x = 0 now, so base coordinates are world coordinates)
        for sup in geo.supports:
            shape = pymunk.Poly(base, [tuple(map(float, v)) for v in sup.vertices], radius=0.0)
            shape.friction = mus[0]
            shape.elasticity = e
            space.add(shape)

        blocks = []
        for blk, (cx, cz, th), mu in zip(scenario.blocks, scenario.initial_poses(), mus[1:],
                                         strict=True):
            body = pymunk.Body(float(blk.m), float(blk.inertia[1]))
            body.position = (float(cx), float(cz))
            body.angle = -float(th)  # pymunk's angle is counter-clockwise: θ = −angle
            shape = pymunk.Poly(body, [tuple(map(float, v)) for v in blk.profile()],
                                radius=0.0)
            shape.friction = mu
            shape.elasticity = e
            space.add(body, shape)
            blocks.append(body)

        self._space, self._base, self._blocks, self._dt = space, base, blocks, dt
        try:  # the C functions and pointers behind pymunk's Space.step and Body properties
            from pymunk._chipmunk import lib

            self._step, self._space_ptr = lib.cpSpaceStep, space._space
            self._body_ptrs = [body._body for body in blocks]
            self._base_ptr = base._body
            self._set_pos, self._set_vel = lib.cpBodySetPosition, lib.cpBodySetVelocity
            self._get_pos, self._get_angle = lib.cpBodyGetPosition, lib.cpBodyGetAngle
        except (ImportError, AttributeError):  # pragma: no cover - other pymunk layouts
            self._step, self._space_ptr, self._body_ptrs = space.step, None, []
        self._poses = np.zeros((len(blocks), 7))
        return dt

    def _drive_base(self, t: float, dt: float) -> None:
        i = min(int(round(t / self._dt)), len(self._v_mid) - 1)  # past the motion: hold
        # exact position at the step start (no drift), midpoint velocity for the step
        self._base.position = tuple(self._u_start[i].tolist())
        self._base.velocity = tuple(self._v_mid[i].tolist())

    def _series(self, i0: int, n: int) -> tuple[list[float], ...]:
        """The base's u_x, u̇_x, u_z, u̇_z (z: empty while still) for steps i0 … i0 + n − 1."""
        if i0 + n <= len(self._v_list):
            us, vs = self._u_list[i0:i0 + n], self._v_list[i0:i0 + n]
            if self._uz_list is None or self._vz_list is None:
                return us, vs, [], []
            return us, vs, self._uz_list[i0:i0 + n], self._vz_list[i0:i0 + n]
        # steps past the precomputed motion repeat its last, still, value
        idx = np.minimum(np.arange(i0, i0 + n), len(self._v_mid) - 1)
        u, v = self._u_start[idx], self._v_mid[idx]
        if self._uz_list is None:
            return u[:, 0].tolist(), v[:, 0].tolist(), [], []
        return u[:, 0].tolist(), v[:, 0].tolist(), u[:, 1].tolist(), v[:, 1].tolist()

    def _drive_steps(self, us: list[float], vs: list[float], uzs: list[float],
                     vzs: list[float]) -> None:
        """One step per entry of ``us``, the base set before each (z too if ``uzs``)."""
        set_pos, set_vel, bptr = self._set_pos, self._set_vel, self._base_ptr
        step, ptr, h = self._step, self._space_ptr, self._dt
        if not uzs:  # the base still along z: the horizontal-only loop
            for u, v in zip(us, vs, strict=True):
                set_pos(bptr, (u, 0.0))
                set_vel(bptr, (v, 0.0))
                step(ptr, h)
            return
        for u, v, uz, vz in zip(us, vs, uzs, vzs, strict=True):
            set_pos(bptr, (u, uz))
            set_vel(bptr, (v, vz))
            step(ptr, h)

    def _advance_driven(self, t0: float, n: int, dt: float) -> None:
        # the same as _drive_base + _advance(1) per step, in one tight loop
        if self._space_ptr is None:  # pragma: no cover - other pymunk layouts
            super()._advance_driven(t0, n, dt)
            return
        self._drive_steps(*self._series(int(round(t0 / self._dt)), n))

    def _sample_free(self, out: np.ndarray, k: int) -> None:
        """All ``len(out)`` samples in one loop over locally bound C calls."""
        if self._space_ptr is None:  # pragma: no cover - other pymunk layouts
            super()._sample_free(out, k)
            return
        step, ptr, h = self._step, self._space_ptr, self._dt
        get_pos, get_angle, cos, sin = self._get_pos, self._get_angle, math.cos, math.sin
        bps, repeat = self._body_ptrs, itertools.repeat
        rows: list[tuple[float, ...]] = []
        add = rows.append
        for _ in repeat(None, out.shape[0]):
            for _ in repeat(None, k):
                step(ptr, h)
            for bp in bps:
                v = get_pos(bp)
                half = -0.5 * get_angle(bp)  # θ/2 with θ = −angle
                add((v.x, 0.0, v.y, cos(half), 0.0, sin(half), 0.0))
        out.reshape(-1, 7)[:] = rows

    def _sample_driven(self, out: np.ndarray, step0: int, k: int, dt: float) -> None:
        """Like :meth:`_sample_free`, setting the base before every step (as _advance_driven)."""
        if self._space_ptr is None:  # pragma: no cover - other pymunk layouts
            super()._sample_driven(out, step0, k, dt)
            return
        get_pos, get_angle, cos, sin = self._get_pos, self._get_angle, math.cos, math.sin
        bps, drive = self._body_ptrs, self._drive_steps
        m = out.shape[0]
        n = m * k
        us, vs, uzs, vzs = self._series(step0, n)
        rows: list[tuple[float, ...]] = []
        add = rows.append
        for j in range(0, n, k):
            drive(us[j:j + k], vs[j:j + k], uzs[j:j + k], vzs[j:j + k])
            for bp in bps:
                p = get_pos(bp)
                half = -0.5 * get_angle(bp)
                add((p.x, 0.0, p.y, cos(half), 0.0, sin(half), 0.0))
        out.reshape(-1, 7)[:] = rows

    def _fix_base(self) -> bool:
        self._base.position = tuple(self._u_start[-1].tolist())
        self._base.velocity = (0.0, 0.0)
        return True

    def _advance(self, n: int) -> None:
        # pymunk has no multi-step call. Space.step wraps cpSpaceStep in Python
        # bookkeeping (deferred adds/removes, post-step callbacks) that this scene
        # never uses and that triples the per-step cost of a small scene, so the
        # C function is called directly when pymunk exposes it.
        step, dt = self._step, self._dt
        if self._space_ptr is not None:
            ptr = self._space_ptr
            for _ in itertools.repeat(None, n):
                step(ptr, dt)
        else:
            for _ in itertools.repeat(None, n):
                step(dt)

    def _read_poses(self) -> np.ndarray:
        p = self._poses
        if self._body_ptrs:
            # C getters: Body.position builds a Vec2d, 10× the cost of the read
            get_pos, get_angle, cos, sin = self._get_pos, self._get_angle, math.cos, math.sin
            for i, bp in enumerate(self._body_ptrs):
                v = get_pos(bp)
                half = -0.5 * get_angle(bp)  # θ/2 with θ = −angle
                p[i, 0], p[i, 2], p[i, 3], p[i, 5] = v.x, v.y, cos(half), sin(half)
            return p
        for i, body in enumerate(self._blocks):  # pragma: no cover - other pymunk layouts
            x, z = body.position
            half = -0.5 * body.angle
            p[i, 0], p[i, 2], p[i, 3], p[i, 5] = x, z, math.cos(half), math.sin(half)
        return p

    def _teardown(self) -> None:
        self._space = None
        self._space_ptr = self._step = None
        self._body_ptrs = []
        self._base = self._base_ptr = None
        self._set_pos = self._set_vel = self._get_pos = self._get_angle = None
        self._u_list, self._v_list = [], []
        self._uz_list = self._vz_list = None
        self._blocks = []
