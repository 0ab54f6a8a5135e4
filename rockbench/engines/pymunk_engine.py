"""pymunk (Chipmunk2D) engine plugin: planar rocking in the x–z plane.

pymunk is a 2D engine; its (x, y) plane is our (x, z) plane. Its angle is
counter-clockwise positive, while our θ (rotation about +y) is positive when a
block's top moves toward +x (clockwise in pymunk's plane), so θ = −angle and the
returned quaternion is a rotation θ about +y: (cos θ/2, 0, sin θ/2, 0).

Scene: one dynamic body per block with a convex :class:`pymunk.Poly` from
:meth:`Block.profile` (chamfers included, radius 0), mass ``Block.m`` and moment
``Block.inertia[1]`` (the depth only scales the mass, so any planar stack is
exact), and a KINEMATIC base body carrying a box whose top face is z = 0.

Base driving: before each step starting at t the base gets the velocity
u̇_g(t + dt/2) (midpoint rule: the position integrated by Chipmunk over the step
is then exact to O(dt³), and the contact solver sees the mean velocity of the
step). Chipmunk integrates a kinematic body's position as p += v dt, so the
midpoint errors would accumulate to O(dt²) drift; the position is therefore
reset to the exact u_g(t) at every step start. Both series are precomputed
once (vectorised); :meth:`_advance_driven` drives and steps in one tight loop.

Pitfalls handled (see docs/engine-notes.md): Chipmunk's default
``collision_slop`` of 0.1 m lets shapes sink 0.1 m (set to 0 by default here);
sleeping is disabled; ``damping`` is 1 (none); Chipmunk multiplies the friction
and elasticity of the two shapes in contact, so every shape gets the square
root of the scenario's coefficient and each contact pair sees exactly
``scenario.contact.friction`` and ``scenario.contact.restitution``. With an
interface friction μ_if ≠ μ, a stack's blocks alternate 1 and μ_if over a base of
μ; an assembly's blocks, which touch blocks and the base at once, each get √μ_if
over a base and supports of μ/√μ_if (:func:`~rockbench.engines.friction.assembly_frictions`;
μ_if = 0 < μ is then unsupported). Tested: two blocks side by side on the base stay
put at 0.2 g on μ = 0.3 whatever μ_if, and slide as the exact Coulomb slider at 0.5 g
on μ = 0.15.

Calibration (``benchmarks/calibrate_pymunk.py``, pymunk 7.3, free rocking B0–B3
over 20 s and the six Single #2 pulses): ``accurate`` (dt 0.1 ms) max
|θ − θ_ref| ≤ 0.0019 λ, impact times within 0.1 %, pulse peaks within 0.11 %;
``fast`` (dt 1 ms) ≤ 0.015 λ, impact times within 0.42 %, peaks within 1.4 %.
dt 0.2 ms already gives 0.0076 λ on B0, hence 0.1 ms was enough for single blocks.
The paper stack needs 0.025 ms (``benchmarks/stack_convergence.py``): at 0.1 ms the
6.5 Hz / 2 mm pulse's top peak is 2.4 % low, at 0.05 ms the 5 Hz / 2 mm sinusoid's
8.3 % high; at 0.025 ms every stack pulse is within 0.5 % and both well-posed
sinusoids within 3.2 % (0.02 ms: 0.52 % and 1.7 %; 0.01 ms: 0.15 % and 1.2 %).
``accurate`` is dt 0.025 ms, the cheapest step of ``benchmarks/preset_pareto.py``'s grid
that keeps the accurate bounds (the stack sines within 5 %); at 0.02 ms it cost 1.24×
as much (16.5 against 13.2 CPU s over the 24 calibration cases). ``fine`` keeps 0.02 ms
(the sines within 1.7 %, 0.004 λ up to their third impact against 0.032 λ), ``single``
the 0.1 ms that single blocks need, at a quarter of accurate's cost.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from rockbench.engines.base import Capabilities, Engine
from rockbench.engines.friction import assembly_frictions
from rockbench.engines.settings import EngineSettings
from rockbench.errors import UnsupportedScenario
from rockbench.scenarios import Scenario

__all__ = ["PymunkEngine", "PymunkSettings"]

# Scenario fields known to be planar (x–z) or to act only through mass/inertia
# (a Block's or a Prism's; a Stack's or an Assembly's)
_PLANAR_BLOCK_FIELDS = frozenset({"width", "depth", "height", "density", "mass", "chamfer",
                                  "vertices", "_centroid", "_area", "_moments"})
_PLANAR_STACK_FIELDS = frozenset({"blocks", "offsets", "poses", "supports", "_centroids"})


def _is_set(value: Any) -> bool:
    """True for a field value that differs from an empty/zero default."""
    try:
        return bool(np.any(np.asarray(value, dtype=float) != 0.0))
    except (TypeError, ValueError):
        return bool(value)


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
                                                        chamfer=True, assemblies=True)
    Settings: ClassVar[type[EngineSettings]] = PymunkSettings
    presets: ClassVar[dict[str, dict[str, Any]]] = {
        "accurate": {},
        # calibrated with benchmarks/calibrate_pymunk.py (figures in the module docstring)
        "fast": {"timestep": 1e-3, "iterations": 20},
        # the former accurate: the stack sinusoids within 1.7 % instead of 3.2 %, at 1.24×
        "fine": {"timestep": 2e-5},
        # single blocks as accurate, stacks 2.4 % / 8.3 % off (see above)
        "single": {"timestep": 1e-4},
    }
    requires: ClassVar[tuple[str, ...]] = ("pymunk",)
    extra: ClassVar[str] = "pymunk"

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
        self._v_mid = np.zeros(1)
        self._u_start = np.zeros(1)
        self._u_list: list[float] = []
        self._v_list: list[float] = []

    @classmethod
    def version(cls) -> str:
        """Version of pymunk."""
        return str(_pymunk().version)

    # ------------------------------------------------------------------ hooks
    def _check_supported(self, scenario: Scenario) -> None:
        """Refuse out-of-plane content, which a planar engine cannot model.

        Every field the scenario model has today is planar-symmetric (blocks
        centred in depth, offsets along x, base motion along x; the depth only
        scales mass and inertia), so every current scenario is supported. A
        Block or Stack field this adapter does not know to be planar is
        refused when it is set (truthy), rather than silently ignored.
        """
        c = scenario.contact
        if scenario.is_assembly and c.block_friction == 0.0 < c.friction:
            raise UnsupportedScenario(
                "pymunk multiplies two shapes' frictions, so an interface friction of 0 "
                f"with μ = {c.friction:g} on the base cannot both hold in an assembly, whose "
                "blocks touch each other and the base")
        for obj, known in ((scenario.stack, _PLANAR_STACK_FIELDS),) + tuple(
            (b, _PLANAR_BLOCK_FIELDS) for b in scenario.blocks
        ):
            for f in dataclasses.fields(obj):
                if f.name not in known and _is_set(getattr(obj, f.name)):
                    raise UnsupportedScenario(
                        f"pymunk is a 2D engine (x–z plane); {type(obj).__name__}.{f.name} "
                        f"may describe out-of-plane content, which it cannot model"
                    )

    def _build(self, scenario: Scenario, settings: EngineSettings) -> float:
        pymunk = _pymunk()
        s: PymunkSettings = settings  # type: ignore[assignment]
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
        # (an interface friction: the base carries μ, a stack's blocks alternate 1 and
        # μ_if; an assembly's blocks touch blocks and the base at once: each √μ_if)
        c = scenario.contact
        if scenario.is_assembly:
            mus = assembly_frictions(c.friction, c.block_friction, scenario.n_blocks)
        elif c.block_friction == c.friction:
            mus = [math.sqrt(c.friction)] * (scenario.n_blocks + 1)
        else:
            mus = [c.friction] + [1.0 if i % 2 == 0 else c.block_friction
                                  for i in range(scenario.n_blocks)]
        e = math.sqrt(scenario.contact.restitution)

        exc = scenario.excitation
        h_tot = scenario.stack.total_height
        w_max = max(b.width for b in scenario.blocks)
        t_end = min(exc.end_time, scenario.duration) if not exc.is_free else 0.0
        n_drive = int(math.ceil(t_end / dt)) + 2 if t_end > 0 else 0
        if n_drive:
            t0 = np.arange(n_drive) * dt
            u_start = np.asarray(exc.displacement(t0), dtype=float)
            v_mid = np.asarray(exc.velocity(t0 + 0.5 * dt), dtype=float)
            u_max = float(np.max(np.abs(u_start)))
        else:
            u_start = v_mid = np.zeros(1)
            u_max = 0.0
        self._u_start, self._v_mid = u_start, v_mid
        # plain floats for the stepping loop (cheaper to slice and pass than NumPy scalars)
        self._u_list, self._v_list = u_start.tolist(), v_mid.tolist()

        # base: wide enough for any toppled block plus the base travel, and
        # thick enough that nothing tunnels through it
        half = 2.0 * (h_tot + w_max) + u_max + 1.0
        if scenario.is_assembly:  # wide scenes: the blocks' spread along x too
            half += scenario.stack.reach + scenario.stack.size
        thick = max(1.0, 0.5 * h_tot)
        base = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        base.position = (0.0, 0.0)
        base_shape = pymunk.Poly(base, [(-half, -thick), (half, -thick), (half, 0.0),
                                        (-half, 0.0)], radius=0.0)
        base_shape.friction = mus[0]
        base_shape.elasticity = e
        space.add(base, base_shape)
        # an assembly's fixed supports: more shapes of the base body (the base is at
        # x = 0 now, so base coordinates are world coordinates)
        for sup in getattr(scenario.stack, "supports", ()):
            shape = pymunk.Poly(base, [tuple(map(float, v)) for v in sup.vertices], radius=0.0)
            shape.friction = mus[0]
            shape.elasticity = e
            space.add(shape)

        centroids, th0 = scenario.initial_poses()
        blocks = []
        for blk, (cx, cz), th, mu in zip(scenario.blocks, centroids,
                                         th0 + scenario.block_angles, mus[1:], strict=True):
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
        i = min(int(round(t / self._dt)), self._v_mid.size - 1)  # past the motion: hold
        # exact position at the step start (no drift), midpoint velocity for the step
        self._base.position = (float(self._u_start[i]), 0.0)
        self._base.velocity = (float(self._v_mid[i]), 0.0)

    def _advance_driven(self, t0: float, n: int, dt: float) -> None:
        # the same as _drive_base + _advance(1) per step, in one tight loop
        if self._space_ptr is None:  # pragma: no cover - other pymunk layouts
            super()._advance_driven(t0, n, dt)
            return
        set_pos, set_vel, bptr = self._set_pos, self._set_vel, self._base_ptr
        step, ptr, h = self._step, self._space_ptr, self._dt
        i0 = int(round(t0 / h))
        if i0 + n <= len(self._v_list):
            us, vs = self._u_list[i0:i0 + n], self._v_list[i0:i0 + n]
        else:  # steps past the precomputed motion repeat its last, still, value
            idx = np.minimum(np.arange(i0, i0 + n), self._v_mid.size - 1)
            us, vs = self._u_start[idx].tolist(), self._v_mid[idx].tolist()
        for u, v in zip(us, vs, strict=True):
            set_pos(bptr, (u, 0.0))
            set_vel(bptr, (v, 0.0))
            step(ptr, h)

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
        set_pos, set_vel, bptr = self._set_pos, self._set_vel, self._base_ptr
        step, ptr, h = self._step, self._space_ptr, self._dt
        get_pos, get_angle, cos, sin = self._get_pos, self._get_angle, math.cos, math.sin
        bps = self._body_ptrs
        m = out.shape[0]
        n = m * k
        if step0 + n <= len(self._v_list):
            us, vs = self._u_list[step0:step0 + n], self._v_list[step0:step0 + n]
        else:  # steps past the precomputed motion repeat its last, still, value
            idx = np.minimum(np.arange(step0, step0 + n), self._v_mid.size - 1)
            us, vs = self._u_start[idx].tolist(), self._v_mid[idx].tolist()
        rows: list[tuple[float, ...]] = []
        add = rows.append
        for j in range(0, n, k):
            for u, v in zip(us[j:j + k], vs[j:j + k], strict=True):
                set_pos(bptr, (u, 0.0))
                set_vel(bptr, (v, 0.0))
                step(ptr, h)
            for bp in bps:
                p = get_pos(bp)
                half = -0.5 * get_angle(bp)
                add((p.x, 0.0, p.y, cos(half), 0.0, sin(half), 0.0))
        out.reshape(-1, 7)[:] = rows

    def _fix_base(self) -> bool:
        self._base.position = (float(self._u_start[-1]), 0.0)
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
        self._blocks = []
