"""Rapier engine plugin: rigid blocks in 3D through the ``rapier3d`` Python bindings.

Rapier (Rust, the physics of the Bevy game engine; Apache-2.0) is a game engine: an
impulse-based TGS-soft solver whose contacts are soft constraints (a spring of given
natural frequency and damping ratio, ``contact_softness``), with sub-steps, and
positions and velocities in single precision (the ``rapier3d`` wheel is the f32
build). Each run owns one :class:`rapier3d.PhysicsWorld` on one worker thread (runs
are bit-identical).

Scene: each block is a dynamic body whose frame is the block's (origin at its centre
of gravity), with one collider: a cuboid, the box spanning a chamfered block's flat
faces (its rocking pivots), or the rounded convex hull of a polygonal prism; its mass
and inertia are set explicitly (a prism's principal frame as the inertia's local
frame). A cylinder is Rapier's cylinder collider, turned so that its axis is the body's z,
with its mass and inertia set explicitly. The base is a KINEMATIC velocity-based body
carrying a cuboid whose top face is z = 0 (the half-space z ≤ 0 in a scene with a
cylinder: parry's cylinder–cuboid contact drops a rolling rim's contact for steps at a
time) and the fixed supports (more colliders of it: they move with the base). A start in
the x–z plane at rest is placed from ``initial_poses`` as it always was (bit-identical
planar results); any other from ``initial_states``: position, quaternion, velocity of the
centre of gravity and angular velocity, in world axes. The blocks are free in 3D
(``planar`` holds them in the x–z plane by joints to the base).
No damping, no sleeping, no CCD unless asked. Rapier combines the coefficients of two
colliders by the higher of their combine rules: every collider's rule is ``MULTIPLY``
and its coefficients the product-splitting ones
(:func:`~rockbench.engines.friction.product_frictions`, the square root of the
restitution), so each pair sees the scenario's μ (μ_if between blocks) and
restitution. Against a kinematic base Rapier applies ``contact_softness``
(``static_contact_softness`` acts on FIXED bodies only).

Base driving (x, y and z): before each step from t_i the base gets the secant
velocity (u_g(t_{i+1}) − u_g(t_i)) / dt, so that Rapier's integration of its
position lands on u_g(t_{i+1}) and the contacts see the step's mean velocity; its
position is reset to the exact u_g at the first step of every call (once per output
sample), so that float32 rounding does not accumulate.

Presets and knobs:

* ``accurate`` (the defaults): dt 0.1 ms, one sub-step, friction solved in the biased
  pass and no stabilization pass, 3 kHz contacts, contact recycling off.
* ``fast``: dt 1 ms in 10 sub-steps (the same 0.1 ms sub-step), 6× cheaper.
* ``game``: Rapier's own defaults at its 60 Hz step (what a game runs). Its step is
  longer than the 1 ms output interval of the catalog's scenarios, which the base
  loop refuses: it runs scenarios whose ``output_rate`` is at most 60 per second.
* every field of Rapier's ``IntegrationParameters`` that matters here, ``planar``,
  ``ccd`` and ``hull_radius`` (:class:`RapierSettings`).

Known limits: float32 (errors grow again below a 0.05 ms sub-step); impacts dissipate
slightly more than Housner's (0.2–0.3 % of the amplitude per impact on slender blocks);
the mirror symmetry of a rocking assembly (``known_failures``).

See :doc:`the engine's page </engines/rapier>` in the documentation for its
calibration, measured accuracy and cost.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any, ClassVar, Literal

import numpy as np

from rockbench.engines.base import Capabilities, Engine
from rockbench.engines.bullet_engine import principal_frame
from rockbench.engines.friction import product_frictions
from rockbench.engines.settings import EngineSettings, KnobRole
from rockbench.errors import UnsupportedScenario
from rockbench.geometry import Block, Cylinder, Support
from rockbench.scenarios import Scenario

__all__ = ["RapierEngine", "RapierSettings"]


def _rapier() -> Any:
    """The rapier3d module, imported on first use (rule 2 of the engine contract)."""
    return RapierEngine.library("rapier3d")


@dataclass(frozen=True)
class RapierSettings(EngineSettings):
    """Knobs of the Rapier engine (defaults = the ``accurate`` preset).

    Presets: ``accurate`` (the defaults), ``fast`` and ``game`` (Rapier's own defaults at
    its 60 Hz step). Rapier's default value is given with each knob; the measurements
    behind the choices are on the engine's documentation page.

    Parameters
    ----------
    timestep : float
        Physics time step in s (Rapier: 1/60). Rounded to the nearest step that
        divides the output interval (the effective step is recorded in the
        trajectory's settings); Rapier stores it in float32.
    solver_iterations : int
        ``num_solver_iterations``: sub-steps of the TGS-soft solver per step, each
        solving the contacts and integrating the positions once (Rapier: 4). What
        matters for rocking is the sub-step ``timestep / solver_iterations``: 0.1 ms
        at ``accurate`` and ``fast``. Below about 0.05 ms the float32 positions round
        the per-sub-step displacements (a block's centre 0.5 m up moves ~1e-7 m per
        5 µs sub-step, against a spacing of 6e-8 m between float32 numbers there) and
        a heavy slender block sinks into the base at a few mm/s: the error grows again.
    pgs_iterations : int
        ``num_internal_pgs_iterations``: projected Gauss–Seidel passes per sub-step
        (Rapier: 1).
    stabilization_iterations : int
        ``num_internal_stabilization_iterations``: passes without the penetration
        bias after each sub-step (Rapier: 1). 0 here: with friction solved in the
        biased pass, they only added dissipation at impacts (free rocking 0.043 λ
        with one, 0.018 λ without).
    friction_model : {"coulomb", "simplified"}
        ``"simplified"`` (Rapier's default): one friction constraint per manifold of
        up to four points plus a twist constraint, bounded by the sum of their normal
        impulses. ``"coulomb"``: one Coulomb friction constraint per contact point;
        a block then slides 3–7 % off the exact Coulomb slider.
    friction_in_bias_pass : bool
        Solve friction in the biased pass of each sub-step too (Rapier: off). With it
        off, a block at rest on a still base creeps sideways at about 10 µm/s.
    contact_frequency : float
        Natural frequency in Hz of the ``contact_softness`` spring that corrects
        penetrations (Rapier: 30 Hz). It acts on every contact here: Rapier gives
        contacts with a FIXED body ``static_contact_softness`` instead, but the base
        is kinematic. At 30 Hz a block at rest sinks 0.11 mm (1 ms steps), and a
        voussoir arch settles by 4e-3 λ below 3 kHz.
    contact_damping_ratio : float
        Damping ratio ζ of that spring (Rapier: 10).
    allowed_linear_error : float
        Penetration (m) left uncorrected (``normalized_allowed_linear_error`` with a
        length unit of 1 m; Rapier: 5 mm). No measurable effect on rocking.
    prediction_distance : float
        Distance (m) within which speculative contacts are made (Rapier: 2 cm).
        No measurable effect on rocking.
    max_corrective_velocity : float
        Largest speed (m/s) at which a penetration is corrected (Rapier: 3 m/s).
    contact_clustering : bool
        Reduce a manifold of many points to at most four (Rapier: on).
    contact_recycling : bool
        Keep last step's contact points while the bodies moved less than a fraction
        of the prediction distance (Rapier: on). Off here: the recycled points let a
        rocking block's pivot slide inward (0.3 mm within the first swing of
        free-b2-0.5, its first impact 1 % late; the Single #2 pulse peaks 6 % low).
    ccd : bool
        Continuous collision detection of the blocks (Rapier: off).
    planar : bool
        Hold each block in the x–z plane of the base by a joint to the base that locks
        its translation along y and its rotations about x and z (Rapier's
        ``GenericJoint``; off in Rapier and here). A base motion along y is then
        unsupported. The blocks free in 3D wobble out of plane by less than 1e-4 rad
        at the accurate preset and rock as accurately (0.013 λ against 0.018 λ with
        the joint on the paper's free cases); with Rapier's default solver passes
        (one stabilization pass, friction not in the biased pass) the Gauss–Seidel
        order of a rocking edge's two contact points rolled and twisted the block by
        up to 0.06 rad, and the joint halved the error. (Rapier's ``locked_axes``
        would be cheaper, but with the rotations about x and z locked a block fell as
        if its inertia about y were smaller.)
    hull_radius : float
        Border radius (m) of the colliders of polygonal prisms and of supports that
        are not rectangles: the prism is shrunk by it and rounded by it
        (``round_convex_hull``), so the swept shape has its faces exactly. Sharp
        hulls (0) threw the voussoirs of an arch at rest apart at the first step.
    """

    timestep: float = 1e-4
    solver_iterations: int = 1
    pgs_iterations: int = 1
    stabilization_iterations: int = 0
    friction_model: Literal["coulomb", "simplified"] = "simplified"
    friction_in_bias_pass: bool = True
    contact_frequency: float = 3000.0
    contact_damping_ratio: float = 10.0
    allowed_linear_error: float = 0.005
    prediction_distance: float = 0.02
    max_corrective_velocity: float = 3.0
    contact_clustering: bool = True
    contact_recycling: bool = False
    ccd: bool = False
    planar: bool = False
    hull_radius: float = 1e-4

    def __post_init__(self) -> None:
        if not (math.isfinite(self.timestep) and self.timestep > 0):
            raise ValueError(f"timestep must be finite and > 0, got {self.timestep!r}")
        for name in ("solver_iterations", "pgs_iterations"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} must be >= 1, got {getattr(self, name)!r}")
        if self.stabilization_iterations < 0:
            raise ValueError("stabilization_iterations must be >= 0, got "
                             f"{self.stabilization_iterations!r}")
        if not self.contact_frequency > 0:
            raise ValueError(f"contact_frequency must be > 0, got {self.contact_frequency!r}")
        for name in ("contact_damping_ratio", "allowed_linear_error", "prediction_distance",
                     "hull_radius"):
            if getattr(self, name) < 0:
                raise ValueError(f"{name} must be >= 0, got {getattr(self, name)!r}")
        if not self.max_corrective_velocity > 0:
            raise ValueError("max_corrective_velocity must be > 0, got "
                             f"{self.max_corrective_velocity!r}")


class RapierEngine(Engine):
    """Rapier (``rapier3d``, float32), one single-threaded PhysicsWorld per simulation."""

    name: ClassVar[str] = "rapier"
    capabilities: ClassVar[Capabilities] = Capabilities(dimensions=3, max_blocks=None,
                                                        chamfer=True, assemblies=True,
                                                        base_axes="xyz", cylinders=True,
                                                        start3d=True, moving_start=True)
    Settings: ClassVar[type[EngineSettings]] = RapierSettings
    presets: ClassVar[dict[str, dict[str, Any]]] = {
        # calibration: docs/engines/rapier.md
        "accurate": {},
        "fast": {"timestep": 1e-3, "solver_iterations": 10},
        # Rapier's IntegrationParameters::default() at its 60 Hz step, the blocks free in
        # 3D (what a game runs); its step is longer than a 1 ms output interval
        "game": {"timestep": 1.0 / 60.0, "solver_iterations": 4, "pgs_iterations": 1,
                 "stabilization_iterations": 1, "friction_model": "simplified",
                 "friction_in_bias_pass": False, "contact_frequency": 30.0,
                 "contact_damping_ratio": 10.0, "allowed_linear_error": 0.005,
                 "prediction_distance": 0.02, "max_corrective_velocity": 3.0,
                 "contact_clustering": True, "contact_recycling": True, "planar": False},
    }
    requires: ClassVar[tuple[str, ...]] = ("rapier3d",)
    extra: ClassVar[str] = "rapier"
    knob_roles: ClassVar[dict[str, KnobRole]] = {
        "timestep": KnobRole.TIME_STEP, "solver_iterations": KnobRole.ITERATIONS,
        "contact_frequency": KnobRole.CONTACT_STIFFNESS,
        "allowed_linear_error": KnobRole.CONTACT_SLOP}
    contact_model: ClassVar[str] = "impulse"
    known_failures: ClassVar[dict[str, str]] = {
        "assembly_mirror_symmetry": (
            "the kit's scene under a pulse at twice its collapse acceleration and its mirror "
            "image rotate 1.25e-2 λ apart (limit 1e-2 λ; 3.3e-2 λ at the fast preset): one "
            "projected Gauss-Seidel pass per sub-step leaves the contacts' order visible, "
            "and the mirrored scene orders them differently; 2 or 3 passes bring it within "
            "the limit but make the paper's free rocking 0.029 λ off instead of 0.013 λ"),
    }

    def __init__(self) -> None:
        self._world: Any = None
        self._base: Any = None
        self._bodies: list[Any] = []
        self._dt = 0.0
        self._poses = np.zeros((0, 7))
        # the base's displacement at each step start and its secant velocity over the step
        self._u: list[tuple[float, float, float]] = []
        self._v: list[tuple[float, float, float]] = []
        self._u_end: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @classmethod
    def version(cls) -> str:
        """Version of the rapier3d bindings (they follow Rapier's own version)."""
        return str(_rapier().__version__)

    # ------------------------------------------------------------------ hooks
    def _check_supported(self, scenario: Scenario) -> None:
        c = scenario.contact
        if scenario.geometry.column is None and c.block_friction == 0.0 < c.friction:
            raise UnsupportedScenario(
                "rapier multiplies the two colliders' friction coefficients here: frictionless "
                "block-block joints with friction on the base cannot both hold in a geometry "
                "whose blocks touch each other and the base (not a column)")

    def _build(self, scenario: Scenario, settings: EngineSettings) -> float:
        assert isinstance(settings, RapierSettings)  # resolve_settings made it one
        s = settings
        if s.planar and "y" in self.drive.axes:
            # settings are not visible to _check_supported, hence here
            raise UnsupportedScenario(
                "rapier: planar=True joins each block to the base along y, so a base motion "
                "along y would carry the blocks rigidly; run it with planar=false")
        r = _rapier()
        out_dt = 1.0 / scenario.output_rate
        # a whole number of steps per output interval lets samples be taken after
        # whole steps; a step longer than the interval is refused by the base loop
        dt = out_dt / max(1, round(out_dt / s.timestep)) if s.timestep <= out_dt * (1 + 1e-9) \
            else s.timestep
        self._dt = dt

        world = r.PhysicsWorld(gravity=(0.0, 0.0, -scenario.g))
        # one thread: bit-identical runs, and no oversubscription of shared cores
        world.set_num_threads(1)
        world.integration_parameters = self._parameters(r, s, dt)

        geo = scenario.geometry
        c = scenario.contact
        mus = product_frictions(geo, c.friction, c.block_friction)
        rest = math.sqrt(c.restitution)
        multiply = r.CoefficientCombineRule.MULTIPLY

        def material(builder: Any, mu: float) -> Any:
            return builder.friction(mu).restitution(rest).friction_combine_rule(multiply) \
                .restitution_combine_rule(multiply)

        drive = self.drive
        blocks = scenario.blocks
        depth = max(b.depth for b in blocks)
        # wide enough for any toppled block, the base's travel and an assembly's spread
        reach = max(0.5 * b.width for b in blocks) + geo.total_height + drive.travel + geo.room
        half_x = max(1.0, 2.0 * reach)
        half_y = max(1.0, 2.0 * reach, depth)
        half_z = max(0.5, 0.5 * geo.total_height)
        if scenario.has_cylinders:
            # the half-space z ≤ 0: parry's cylinder–cuboid manifold drops the contact
            # of a cylinder rolling on its rim for steps at a time, the half-space's
            # (the cylinder's support feature clipped against the plane) holds it
            ground = material(r.Collider.halfspace((0.0, 0.0, 1.0)), mus[0])
        else:
            ground = material(r.Collider.cuboid(half_x, half_y, half_z)
                              .translation((0.0, 0.0, -half_z)), mus[0])
        # the supports are more colliders of the base (at rest the base frame is the world's)
        colliders = [ground] + [
            material(self._support_collider(r, sup, depth, s.hull_radius), mus[0])
            for sup in geo.supports]
        base_builder = r.RigidBody.kinematic_velocity_based().can_sleep(False)
        base_handle = world.add_body(base_builder, colliders)
        self._base = world.rigid_bodies[base_handle]
        # the planar joint: y, and rotations about x and z, of each block relative to the
        # base (which never turns); contacts between the joined bodies stay on
        axes = r.JointAxesMask
        planar = r.GenericJoint.builder(axes.LIN_Y | axes.ANG_X | axes.ANG_Z) \
            .contacts_enabled(True).build()

        self._bodies = []
        # a start in the x–z plane at rest is placed from its (x, z, angle) poses, as
        # always; any other from its 3D states (position, quaternion, velocities)
        in_plane = scenario.initial_azimuth == 0.0 and not scenario.moving_start
        states = scenario.initial_states()
        for i, (blk, (cx, cz, th), mu) in enumerate(zip(blocks, scenario.initial_poses(),
                                                        mus[1:], strict=True)):
            shape = self._cylinder_collider(r, blk) if isinstance(blk, Cylinder) \
                else self._block_collider(r, blk, s.hull_radius)
            collider = material(shape, mu)
            if in_plane:
                builder = r.RigidBody.dynamic().translation((float(cx), 0.0, float(cz))) \
                    .rotation((0.0, float(th), 0.0))
            else:
                builder = self._start_3d(r, states[i])
            builder = builder.linear_damping(0.0).angular_damping(0.0).can_sleep(False) \
                .ccd_enabled(s.ccd)
            handle = world.add_body(builder, [collider])
            self._bodies.append(world.rigid_bodies[handle])
            if s.planar:
                world.impulse_joints.insert(base_handle, handle, planar)
        self._world = world
        self._poses = np.zeros((len(blocks), 7))

        if drive.moving:
            n = drive.steps_until_stop(dt) + int(math.ceil(out_dt / dt)) + 2
            u = drive.displacement(drive.grid(dt, n + 1))
            self._u = [tuple(p) for p in u[:-1].tolist()]
            self._v = [tuple(p) for p in (np.diff(u, axis=0) / dt).tolist()]
            self._u_end = tuple(drive.final_displacement().tolist())
        return dt

    @staticmethod
    def _parameters(r: Any, s: RapierSettings, dt: float) -> Any:
        """Rapier's IntegrationParameters from the settings.

        Built whole and assigned at once: a chained assignment to a nested struct of a
        world's parameters (``world.integration_parameters.contact_softness.x = …``)
        changes a copy and is silently lost.
        """
        p = r.IntegrationParameters()
        p.dt = dt
        p.length_unit = 1.0
        p.num_solver_iterations = s.solver_iterations
        p.num_internal_pgs_iterations = s.pgs_iterations
        p.num_internal_stabilization_iterations = s.stabilization_iterations
        p.friction_model = (r.FrictionModel.COULOMB if s.friction_model == "coulomb"
                            else r.FrictionModel.SIMPLIFIED)
        # the base is kinematic: contact_softness acts on every contact of the scene
        p.contact_softness = r.SpringCoefficients(s.contact_frequency, s.contact_damping_ratio)
        p.normalized_allowed_linear_error = s.allowed_linear_error
        p.normalized_prediction_distance = s.prediction_distance
        p.normalized_max_corrective_velocity = s.max_corrective_velocity
        p.friction_in_bias_pass = s.friction_in_bias_pass
        p.contact_clustering = s.contact_clustering
        p.contact_recycling = s.contact_recycling
        return p

    @staticmethod
    def _hull(r: Any, profile: np.ndarray, half_depth: float, radius: float) -> Any:
        """A convex prism's collider: ``profile`` (x, z) extruded over ±``half_depth``.

        With a ``radius``, the prism shrunk by it and rounded by it (Rapier's
        ``round_convex_hull``): the swept shape has the prism's faces exactly, and
        its contacts are computed on a smooth shape.
        """
        if radius > 0.0:
            profile = _inset(profile, radius)
            half_depth -= radius
        points = [(float(x), y, float(z)) for x, z in profile for y in (-half_depth, half_depth)]
        if radius > 0.0:
            return r.Collider.round_convex_hull(points, radius)
        return r.Collider.convex_hull(points)

    @staticmethod
    def _block_collider(r: Any, blk: Any, radius: float) -> Any:
        """A block's collider in its body frame (origin at the centre of gravity), with
        the block's mass and inertia."""
        hy = 0.5 * blk.depth
        if isinstance(blk, Block):
            # a chamfered block as the box spanning its flat faces: its rocking pivots
            # exactly, collided by the box-box routine (its hull did not hold the paper's
            # stack: the two hulls' first contacts threw the blocks 0.1 mm apart)
            builder = r.Collider.cuboid(blk.pivot_half_width, hy, blk.h)
        else:
            builder = RapierEngine._hull(r, blk.profile(), hy, radius)
        # the block's own inertia (a chamfered block's cut corners neglected, as the
        # analytic models do; a prism's principal frame turned by φ about y)
        phi, moments = principal_frame(blk.inertia_tensor)
        props = r.MassProperties(local_com=(0.0, 0.0, 0.0), mass=float(blk.m),
                                 principal_inertia=moments,
                                 principal_inertia_local_frame=(
                                     0.0, math.sin(0.5 * phi), 0.0, math.cos(0.5 * phi)))
        return builder.mass_properties(props)

    @staticmethod
    def _cylinder_collider(r: Any, blk: Cylinder) -> Any:
        """A cylinder's collider in its body frame (origin at the centre of gravity), with
        the cylinder's mass and inertia.

        Rapier's cylinder has its axis along its local y: the collider is turned by
        +90° about x (its y onto the body's z). Its mass properties are given in the
        collider's frame, the axial moment I3 about its y, so that the body gets
        (I1, I1, I3) about its x, y and z.
        """
        i1, _, i3 = (float(j) for j in blk.inertia)
        props = r.MassProperties(local_com=(0.0, 0.0, 0.0), mass=float(blk.m),
                                 principal_inertia=(i1, i3, i1),
                                 principal_inertia_local_frame=(0.0, 0.0, 0.0, 1.0))
        return r.Collider.cylinder(float(blk.h), float(blk.radius)) \
            .rotation((0.5 * math.pi, 0.0, 0.0)).mass_properties(props)

    @staticmethod
    def _start_3d(r: Any, state: np.ndarray) -> Any:
        """A dynamic body's builder at a 3D state of :meth:`Scenario.initial_states`.

        ``state`` is (x, y, z, w, qx, qy, qz, vx, vy, vz, ωx, ωy, ωz) in world axes. The
        body's origin is its centre of gravity, so Rapier's linear velocity (that of the
        centre of mass) is the state's; its angular velocity is in world axes, as the
        state's. ``Rotation3`` takes (w, x, y, z), unlike Rapier's (x, y, z, w) tuples.
        """
        x, y, z, qw, qx, qy, qz, vx, vy, vz, wx, wy, wz = (float(v) for v in state)
        pose = r.Isometry3((x, y, z), r.Rotation3(qw, qx, qy, qz))
        return r.RigidBody.dynamic().position(pose).linvel((vx, vy, vz)).angvel((wx, wy, wz))

    @staticmethod
    def _support_collider(r: Any, sup: Support, depth: float, radius: float) -> Any:
        """A fixed support's collider in the base's frame (the world's at rest)."""
        v = sup.array
        lo, hi = v.min(axis=0), v.max(axis=0)
        if len(v) == 4 and all(len(set(col)) == 2 for col in v.T.tolist()):
            # an axis-aligned rectangle: a box, collided with box blocks exactly
            half = 0.5 * (hi - lo)
            centre = 0.5 * (hi + lo)
            return r.Collider.cuboid(float(half[0]), depth, float(half[1])) \
                .translation((float(centre[0]), 0.0, float(centre[1])))
        return RapierEngine._hull(r, v, depth, radius)

    def _drive_base(self, t: float, dt: float) -> None:
        i = int(round(t / self._dt))
        if i < len(self._v):
            self._base.translation = self._u[i]
            self._base.linvel = self._v[i]
        else:  # beyond the precomputed window (should not happen): hold still
            self._base.translation = self._u_end
            self._base.linvel = (0.0, 0.0, 0.0)

    def _advance_driven(self, t0: float, n: int, dt: float) -> None:
        # _drive_base + _advance(1) per step in one loop, except that the base position
        # is reset at the first step of the call only: in between Rapier integrates it
        # from the secant velocity, which lands on u(t_{i+1}) up to float32 rounding
        i0 = int(round(t0 / self._dt))
        if i0 + n > len(self._v):  # past the precomputed window (should not happen)
            super()._advance_driven(t0, n, dt)
            return
        base, step = self._base, self._world.step
        base.translation = self._u[i0]
        for v in self._v[i0:i0 + n]:
            base.linvel = v
            step()

    def _fix_base(self) -> bool:
        self._base.translation = self._u_end
        self._base.linvel = (0.0, 0.0, 0.0)
        return True

    def _advance(self, n: int) -> None:
        step = self._world.step
        for _ in itertools.repeat(None, n):
            step()

    def _read_poses(self) -> np.ndarray:
        out = self._poses
        for i, body in enumerate(self._bodies):
            p, q = body.translation, body.rotation
            out[i] = (p.x, p.y, p.z, q.w, q.i, q.j, q.k)
        return out

    def _teardown(self) -> None:
        self._world = self._base = None
        self._bodies = []
        self._u, self._v = [], []


def _inset(poly: np.ndarray, m: float) -> np.ndarray:
    """Move every edge of a convex counter-clockwise polygon inward by ``m``."""
    out = np.empty_like(poly, dtype=float)
    k = len(poly)
    for j in range(k):
        p0, p1, p2 = poly[j - 1], poly[j], poly[(j + 1) % k]
        d1, d2 = (p1 - p0) / np.linalg.norm(p1 - p0), (p2 - p1) / np.linalg.norm(p2 - p1)
        # inward normals of the edges before and after vertex j (counter-clockwise: +90°)
        n1, n2 = np.array([-d1[1], d1[0]]), np.array([-d2[1], d2[0]])
        # the vertex moves along n1 + n2 so that it lies m from both edges
        bis = n1 + n2
        out[j] = p1 + bis * (m / float(bis @ n1))
    return out
