"""pybullet (Bullet 3) engine plugin: rigid blocks in 3D, in maximal coordinates.

Each run owns a DIRECT-mode pybullet client, disconnected at teardown. Each block is
a rigid body with the block's mass and principal inertia (a convex prism's body frame
is its principal frame, turned back when its pose is read) and one collision shape: a
box, the convex hull of its prism or a concave triangle mesh (``collision_shape``); a
chamfered block is a box spanning its flat faces or its hull (``chamfer_shape``). The
ground is a box whose top face is z = 0: a static body in free rocking, and under a
moving base a fixed-base multibody whose velocity is prescribed every step (Bullet
ignores a static body's velocity, which would then not drag a block through
friction): the secant velocity (u_g(t_{i+1}) − u_g(t_i)) / dt of the step, along x, y
and z, its position reset to u_g once per output sample. Fixed supports are bodies of
the ground's kind, moved with it. No damping, no sleeping.
A :class:`~rockbench.geometry.Cylinder` is Bullet's own cylinder (``GEOM_CYLINDER``, its
axis along the body's z) with the cylinder's mass and inertia and the hulls' collision
margin. A start tilted toward an azimuth is placed from
:meth:`~rockbench.scenarios.Scenario.initial_states` (centre of mass, quaternion), one in
the x–z plane from the poses as before; a moving start gets the states' world-frame
velocity of the centre of mass (the body's origin) and angular velocity.
Bullet multiplies the friction and restitution of the two bodies in contact, so each
body gets coefficients whose products are the scenario's
(:func:`~rockbench.engines.friction.product_frictions`). The base motion is applied
along x, y and z.

Presets and knobs:

* ``accurate`` (the defaults): Δt = 1 / ((``substeps`` + 1) · ``fps``) = 0.1 ms, 50
  solver iterations all run (``solver_residual_threshold`` 1e-12), a contact breaking
  threshold of 1e-4 m (Bullet's 0.02 m keeps a lifted pivot in contact) and no contact
  slop.
* ``fast``: Δt 1 ms, hulls for chamfered blocks, breaking threshold 1e-3 m, Bullet's
  early exit of the solver.
* The paper's Table 2 knobs (``fps``, ``substeps``, ``solver_iterations``,
  ``collision_shape``, ``collision_margin``); an explicit ``timestep`` overrides
  ``fps`` and ``substeps``.

Known limits: the paper stack's 4 mm sinusoid does not converge as the step shrinks; a
concave mesh collides with convex shapes only, so ``"mesh"`` supports single blocks.

See :doc:`the engine's page </engines/bullet>` in the documentation for its
calibration, measured accuracy and cost.
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
from rockbench.geometry.polygon import rotate
from rockbench.scenarios import Scenario

__all__ = ["BulletEngine", "BulletSettings"]

#: A still base's velocity (m/s).
_ZERO = (0.0, 0.0, 0.0)

#: Collision margin of hull and mesh blocks when ``collision_margin`` is None (m).
_DEFAULT_HULL_MARGIN = 1e-4

#: pybullet's names of the constraint solvers (looked up once pybullet is imported)
_SOLVERS = {
    "si": "CONSTRAINT_SOLVER_LCP_SI",
    "pgs": "CONSTRAINT_SOLVER_LCP_PGS",
    "dantzig": "CONSTRAINT_SOLVER_LCP_DANTZIG",
}


@dataclass(frozen=True)
class BulletSettings(EngineSettings):
    """Knobs of the pybullet engine (defaults = the ``accurate`` preset).

    Parameters
    ----------
    fps : float
        Frame rate of the paper's Blender set-up (frames per second). With
        ``substeps`` it sets the time step Δt = 1 / ((substeps + 1) · fps).
    substeps : int
        Sub-steps per frame n_s (paper: 2, 20, 200).
    timestep : float or None
        Explicit physics time step in s; overrides ``fps``/``substeps``. In both
        cases the step is rounded so that a whole number of steps fits one output
        interval (the effective step is recorded in the trajectory's settings).
    solver_iterations : int
        ``numSolverIterations`` of the sequential-impulse solver (paper: 10, 100, 1000).
    solver : {"si", "pgs", "dantzig"}
        ``constraintSolverType``: Bullet's sequential impulse (default) or the
        MLCP solvers (projected Gauss–Seidel, Dantzig).
    solver_residual_threshold : float
        Early exit of the iterations once the largest velocity correction of a
        pass, squared (m²/s²), is below this value. Bullet's own 1e-7 stops after
        3–5 of 50 passes at 0.1 ms steps (3.2e-4 m/s, while gravity adds 9.8e-4 m/s
        per step): sticking contacts creep (stack interfaces slip 1e-4 m) and
        slipping ones carry less than μN. At 1e-12 all passes run in 92–99 % of
        the steps (counted with ``reportSolverAnalytics``).
    collision_shape : {"box", "convex", "mesh"}
        Block shape: ``btBoxShape`` (box–box contact is exact, no margin at the
        corners), convex hull of the block prism's vertices (``GEOM_MESH``, also
        used for chamfers whatever this knob says), or a concave triangle mesh
        (``GEOM_MESH`` + ``GEOM_FORCE_CONCAVE_TRIMESH``). Bullet collides a dynamic
        concave mesh only with convex shapes, so "mesh" supports single blocks
        only (a stack raises :class:`UnsupportedScenario`).
    chamfer_shape : {"hull", "narrow_box"}
        Collision shape of a chamfered block. ``"hull"``: the convex hull of the
        chamfered prism (Bullet's convex–convex collision keeps one new point per
        step in the manifold: the paper stack at rest is held at a single point,
        the face centre, at each contact, counted with ``getContactPoints``; its
        pulses are 20 % off). ``"narrow_box"`` (default): a box of width w − 2c
        (the chamfered prism's bottom and top faces, hence its rocking pivots,
        exactly), collided by Bullet's box–box routine, which gives the four
        corners of each face at once.
    collision_margin : float or None
        Collision margin of the block shapes in m (paper: 1e-3, 1e-5, 1e-6);
        None keeps pybullet's default (1e-3 m). Convex hulls are inflated by it.
    enable_sat : bool
        Separating-axis test for convex hulls (full contact manifolds).
    contact_breaking_threshold : float
        Distance (m) beyond which manifold points are dropped (Bullet default
        0.02; 1e-3 is far more accurate for rocking, see the engine's page;
        1e-4 for the paper stack, whose lifted upper block otherwise keeps stale
        points on the lower one: stack pulses 7.7 % off at 1e-3 with the narrow
        box, 0.85 % at 1e-4).
    contact_slop : float
        Penetration (m) tolerated without correction (Bullet default 1e-3).
    erp, contact_erp, friction_erp : float
        Error-reduction parameters of joints, contacts and friction.
    split_impulse : bool
        Solve penetrations deeper than ``split_impulse_threshold`` with a split
        (position-only) impulse instead of Baumgarte velocity terms.
    split_impulse_threshold : float
        ``splitImpulsePenetrationThreshold`` (m, negative: penetration depth).
    warm_starting_factor : float
        Fraction of last step's impulses used to start the iterations.
    cone_friction : bool
        Friction cone instead of Bullet's two-direction friction pyramid.
    maximal_coordinates : bool
        Blocks as ``btRigidBody`` (True, ~2× faster) or free-floating ``btMultiBody``.
    friction_anchor : bool
        Bullet's friction anchors (``changeDynamics(frictionAnchor=1)``): a
        sticking contact point keeps its first position and the friction
        constraint pulls the bodies back to it, instead of letting them creep.
    restitution : float or None
        Restitution of every contact; None uses the scenario's. Bullet multiplies
        the bodies' coefficients, so each body gets its square root.
    restitution_velocity_threshold : float
        Approach speed (m/s) below which Bullet applies no restitution.
    """

    fps: float = 1000.0
    substeps: int = 9
    timestep: float | None = None
    solver_iterations: int = 50
    solver: Literal["si", "pgs", "dantzig"] = "si"
    solver_residual_threshold: float = 1e-12
    collision_shape: Literal["box", "convex", "mesh"] = "box"
    chamfer_shape: Literal["hull", "narrow_box"] = "narrow_box"
    collision_margin: float | None = None
    enable_sat: bool = False
    contact_breaking_threshold: float = 1e-4
    contact_slop: float = 0.0
    erp: float = 0.2
    contact_erp: float = 0.2
    friction_erp: float = 0.2
    split_impulse: bool = True
    split_impulse_threshold: float = -0.04
    warm_starting_factor: float = 0.85
    cone_friction: bool = True
    maximal_coordinates: bool = True
    friction_anchor: bool = False
    restitution: float | None = None
    restitution_velocity_threshold: float = 0.2

    def __post_init__(self) -> None:
        if not (self.fps > 0 and math.isfinite(self.fps)):
            raise ValueError(f"fps must be positive, got {self.fps!r}")
        if self.substeps < 0:
            raise ValueError(f"substeps must be >= 0, got {self.substeps!r}")
        if self.timestep is not None and not (0 < self.timestep < math.inf):
            raise ValueError(f"timestep must be positive, got {self.timestep!r}")
        if self.solver_iterations < 1:
            raise ValueError("solver_iterations must be >= 1")
        if self.collision_margin is not None and self.collision_margin < 0:
            raise ValueError("collision_margin must be >= 0")
        if self.contact_breaking_threshold <= 0:
            raise ValueError("contact_breaking_threshold must be > 0")
        if self.restitution is not None and not 0 <= self.restitution <= 1:
            raise ValueError("restitution must be in [0, 1]")

    @property
    def dt(self) -> float:
        """Requested physics time step (s) before rounding to the output interval."""
        if self.timestep is not None:
            return self.timestep
        return 1.0 / ((self.substeps + 1) * self.fps)


class BulletEngine(Engine):
    """Bullet 3 through pybullet, one DIRECT client per simulation."""

    name: ClassVar[str] = "bullet"
    capabilities: ClassVar[Capabilities] = Capabilities(dimensions=3, max_blocks=None,
                                                         chamfer=True, assemblies=True,
                                                         base_axes="xyz", cylinders=True,
                                                         start3d=True, moving_start=True)
    Settings: ClassVar[type[EngineSettings]] = BulletSettings
    presets: ClassVar[dict[str, dict[str, Any]]] = {
        # 0.1 ms steps (fps 1000 × 10 sub-steps), every solver pass run: ≤ 5e-3 λ on the
        # free-rocking catalog; the paper stack within 0.38 % on its pulses, interface slip
        # 9e-6 m, Coulomb sliding within 0.4 % (1e-7: 0.85 %, 1e-4 m, 2.5 %) at 3.5× the
        # cost on stacks (docs/engines/stack-convergence.md, tests/test_sliding_engines.py)
        "accurate": {},
        # 1 ms steps, no sub-steps: ≤ 0.05 λ at ~10× less cost (calibrated with the hull,
        # the 1 mm breaking threshold and Bullet's early exit, kept: running every pass
        # there makes B0 worse, 0.013 -> 0.020 λ, and gains nothing on stacks)
        "fast": {"substeps": 0, "chamfer_shape": "hull", "contact_breaking_threshold": 1e-3,
                 "solver_residual_threshold": 1e-7},
    }
    requires: ClassVar[tuple[str, ...]] = ("pybullet",)
    extra: ClassVar[str] = "bullet"
    knob_roles: ClassVar[dict[str, KnobRole]] = {
        "timestep": KnobRole.TIME_STEP, "fps": KnobRole.FRAME_RATE,
        "substeps": KnobRole.SUBSTEPS, "solver_iterations": KnobRole.ITERATIONS,
        "solver_residual_threshold": KnobRole.TOLERANCE,
        "collision_shape": KnobRole.COLLISION_SHAPE,
        "collision_margin": KnobRole.COLLISION_MARGIN}
    # the step is 1 / ((substeps + 1) · fps): a finer rung doubles substeps + 1
    refinement: ClassVar[str] = "substeps"
    contact_model: ClassVar[str] = "impulse"
    known_failures: ClassVar[dict[str, str]] = {
        "assembly_rest": (
            "arch-rest (9 voussoirs, t/R = 0.2, accurate preset): Bullet's convex-hull "
            "contacts (GJK) add one manifold point per step, so every voussoir joint is a "
            "hinge for the first steps (4 points after ~100) and the arch settles by up to "
            "6.1e-4 rad = 2.09e-3 λ (limit 2e-3 λ), then holds; the box assemblies turn by "
            "< 3e-7 λ"),
        "assembly_penetration": (
            "arch-rest: the settled voussoirs' x–z sections overlap by 4.65e-5 m (limit "
            "2.2e-5 m; 3.0–5.0e-5 m with collision margins 0 to 1e-3 m or the Dantzig "
            "solver) while Bullet's own closest-point distances stay above -1.3e-7 m: its "
            "hull manifolds, not symmetric in depth, also twist the voussoirs out of plane "
            "by up to 2.7e-4 rad; the box assemblies overlap by < 2e-8 m"),
    }

    def __init__(self) -> None:
        self._cid: int | None = None

    @classmethod
    def version(cls) -> str:
        from importlib.metadata import PackageNotFoundError, version

        pb = cls.library("pybullet")
        try:
            return version("pybullet")
        except PackageNotFoundError:  # pragma: no cover - e.g. a source build
            return str(pb.getAPIVersion())

    # ------------------------------------------------------------------ hooks
    def _check_supported(self, scenario: Scenario) -> None:
        c = scenario.contact
        if scenario.geometry.column is None and c.block_friction == 0.0 < c.friction:
            raise UnsupportedScenario(
                "bullet multiplies the two bodies' friction coefficients: frictionless "
                "block-block joints with friction on the base cannot both hold in a "
                "geometry whose blocks touch each other and the base (not a column)")

    def _build(self, scenario: Scenario, settings: EngineSettings) -> float:
        assert isinstance(settings, BulletSettings)  # resolve_settings made it one
        s = settings
        if s.collision_shape == "mesh" and scenario.n_blocks > 1:
            # settings are not visible to _check_supported, hence here
            raise UnsupportedScenario(
                "bullet: collision_shape='mesh' cannot model stacks or assemblies of several "
                "blocks (Bullet does not collide two concave triangle meshes)")
        out_dt = 1.0 / scenario.output_rate
        if s.dt <= out_dt * (1.0 + 1e-9):
            # a whole number of steps per output interval lets steps be batched
            dt = out_dt / max(1, round(out_dt / s.dt))
        else:  # coarser than the output (the paper's low frame rates): interpolated
            dt = s.dt
        self._dt = dt
        self._pb = pb = self.library("pybullet")
        cid = pb.connect(pb.DIRECT)
        self._cid = cid
        kw = {"physicsClientId": cid}
        self._kw = kw
        pb.setGravity(0.0, 0.0, -scenario.g, **kw)
        # contactBreakingThreshold is process-global in Bullet: always set it
        pb.setPhysicsEngineParameter(
            fixedTimeStep=dt, numSubSteps=0, numSolverIterations=s.solver_iterations,
            constraintSolverType=getattr(pb, _SOLVERS[s.solver]),
            solverResidualThreshold=s.solver_residual_threshold,
            contactBreakingThreshold=s.contact_breaking_threshold,
            contactSlop=s.contact_slop, erp=s.erp, contactERP=s.contact_erp,
            frictionERP=s.friction_erp, useSplitImpulse=int(s.split_impulse),
            splitImpulsePenetrationThreshold=s.split_impulse_threshold,
            warmStartingFactor=s.warm_starting_factor, enableConeFriction=int(s.cone_friction),
            enableSAT=int(s.enable_sat),
            restitutionVelocityThreshold=s.restitution_velocity_threshold,
            deterministicOverlappingPairs=1, **kw)
        self._substeps = 0
        self._margin = s.collision_margin
        self._shape = s.collision_shape
        self._chamfer_shape = s.chamfer_shape
        self._anchor = s.friction_anchor
        # hulls/meshes: the margin actually applied (pybullet's default is 1e-3 m)
        self._hull_margin = _DEFAULT_HULL_MARGIN if s.collision_margin is None \
            else s.collision_margin

        blocks = scenario.blocks
        geo = scenario.geometry
        drive = self.drive
        # (a geometry that is not a column spreads along x too: its room)
        reach = max(0.5 * b.width for b in blocks) + geo.total_height + drive.travel \
            + geo.room
        ground_half = (max(1.0, 2.0 * reach), max(1.0, 2.0 * reach, max(b.depth for b in blocks)),
                       0.5)
        self._ground_z = -ground_half[2]
        gshape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=ground_half, **kw)
        # a moving base must be a fixed-base multibody: Bullet ignores the velocity
        # of a static (mass 0) btRigidBody in contacts
        moving = drive.moving
        ground_maximal = s.maximal_coordinates and not moving
        self._ground = pb.createMultiBody(0.0, gshape, basePosition=(0.0, 0.0, self._ground_z),
                                          useMaximalCoordinates=ground_maximal, **kw)

        c = scenario.contact
        mus = product_frictions(geo, c.friction, c.block_friction)
        e = c.restitution if s.restitution is None else s.restitution
        rest = math.sqrt(e)
        self._set_dynamics(self._ground, mus[0], rest, None)
        # the supports: bodies of the ground's kind at their place on the base
        depth = max(b.depth for b in blocks)
        self._supports: list[tuple[int, float, float]] = []
        for sup in geo.supports:
            shape, (px, pz) = self._support_shape(sup, depth)
            body = pb.createMultiBody(0.0, shape, basePosition=(px, 0.0, pz),
                                      useMaximalCoordinates=ground_maximal, **kw)
            self._set_dynamics(body, mus[0], rest, None, margin=self._hull_margin)
            self._supports.append((body, px, pz))

        poses = scenario.initial_poses()
        # a start in the x–z plane is placed from its (x, z, angle) poses, as always; one
        # tilted toward an azimuth from the 3D states (position, quaternion)
        states = scenario.initial_states()
        planar = scenario.initial_azimuth == 0.0
        self._bodies: list[int] = []
        # (block index, cos φ/2, sin φ/2) of the bodies whose frame is turned by φ from
        # the block's (prisms: their principal frame)
        self._turns: list[tuple[int, float, float]] = []
        for i, (blk, (cx, cz, th), mu) in enumerate(zip(blocks, poses, mus[1:], strict=True)):
            if isinstance(blk, (Block, Cylinder)):
                phi, inertia = 0.0, tuple(float(j) for j in blk.inertia)
            else:
                phi, inertia = principal_frame(blk.inertia_tensor)
                if phi != 0.0:
                    self._turns.append((i, math.cos(0.5 * phi), math.sin(0.5 * phi)))
            pos: tuple[float, ...]
            if planar:
                a = th + phi
                pos = (float(cx), 0.0, float(cz))
                orn = (0.0, math.sin(0.5 * a), 0.0, math.cos(0.5 * a))
            else:  # a tilted column: blocks and cylinders, whose frames are principal
                pos = tuple(float(v) for v in states[i, :3])
                w, x, y, z = (float(v) for v in states[i, 3:7])
                orn = (x, y, z, w)  # pybullet's order
            shape = self._cylinder_shape(blk) if isinstance(blk, Cylinder) \
                else self._block_shape(blk, s, phi)
            body = pb.createMultiBody(blk.m, shape, basePosition=pos, baseOrientation=orn,
                                      useMaximalCoordinates=s.maximal_coordinates, **kw)
            self._set_dynamics(body, mu, rest, blk, inertia=inertia)
            if scenario.moving_start:
                # world-frame velocity of the centre of mass (the body's origin: no
                # inertial offset) and world-frame angular velocity
                pb.resetBaseVelocity(body, tuple(float(v) for v in states[i, 7:10]),
                                     tuple(float(v) for v in states[i, 10:13]), **kw)
            self._bodies.append(body)
        self._poses = np.empty((len(blocks), 7))

        # base kinematics per step, precomputed: position u(t_i) and the secant
        # velocity (u(t_{i+1}) − u(t_i)) / dt, so that Bullet's integration of the
        # base lands exactly on u(t_{i+1}) and the block feels ü_g at mid-step; both as
        # (x, y, z) tuples, a base moving along x only with exact zeros along y and z
        if moving:
            n = drive.steps_until_stop(dt) + int(math.ceil(out_dt / dt)) + 2
            grid = drive.grid(dt, n + 1)
            if drive.axes == ("x",):  # the planar benchmark's values, bit for bit
                u = drive.displacement(grid)[:, 0]
                self._u = [(x, 0.0, 0.0) for x in u.tolist()]
                self._v = [(v, 0.0, 0.0) for v in (np.diff(u) / dt).tolist()]
                self._u_end = (float(drive.final_displacement()[0]), 0.0, 0.0)
            else:
                u3 = drive.displacement(grid)
                self._u = [tuple(p) for p in u3.tolist()]
                self._v = [tuple(p) for p in (np.diff(u3, axis=0) / dt).tolist()]
                self._u_end = tuple(drive.final_displacement().tolist())
        return dt

    def _block_shape(self, blk: Any, s: BulletSettings, phi: float = 0.0) -> int:
        """Collision shape of a block in its body frame (turned by ``phi`` from the block's)."""
        pb, kw = self._pb, self._kw
        hy = 0.5 * blk.depth
        if self._is_box(blk):
            shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=(blk.b, hy, blk.h), **kw)
        elif self._narrow(blk):
            shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=(blk.pivot_half_width, hy,
                                                                      blk.h), **kw)
        else:
            # Bullet inflates hulls and triangles by the collision margin: shrink the
            # prism by it so that the swept shape has the block's faces exactly
            m = self._hull_margin
            prof = _offset_polygon(blk.profile(), m)
            if phi != 0.0:
                prof = rotate(prof, -phi)
            yy = hy - m
            verts = [(float(x), y, float(z)) for x, z in prof for y in (-yy, yy)]
            if s.collision_shape == "mesh":
                indices = _prism_triangles(len(prof))
                shape = pb.createCollisionShape(pb.GEOM_MESH, vertices=verts, indices=indices,
                                                flags=pb.GEOM_FORCE_CONCAVE_TRIMESH, **kw)
            else:
                shape = pb.createCollisionShape(pb.GEOM_MESH, vertices=verts, **kw)
        if shape < 0:  # pragma: no cover - pybullet signals failure by -1
            raise RuntimeError("pybullet could not create the block collision shape")
        return shape

    def _cylinder_shape(self, blk: Cylinder) -> int:
        """Collision shape of a cylinder: Bullet's own, its axis along the body's z."""
        pb, kw = self._pb, self._kw
        shape = pb.createCollisionShape(pb.GEOM_CYLINDER, radius=blk.radius, height=blk.height,
                                        **kw)
        if shape < 0:  # pragma: no cover - pybullet signals failure by -1
            raise RuntimeError("pybullet could not create the cylinder collision shape")
        return shape

    def _support_shape(self, sup: Support, depth: float) -> tuple[int, tuple[float, float]]:
        """Collision shape of a fixed support and its body's position (x, z) on the base."""
        pb, kw = self._pb, self._kw
        v = sup.array
        lo, hi = v.min(axis=0), v.max(axis=0)
        if len(v) == 4 and all(len(set(col)) == 2 for col in v.T.tolist()):
            # an axis-aligned rectangle: a box, which Bullet's box-box routine collides
            # with box blocks exactly (four corner points per face)
            half = (0.5 * float(hi[0] - lo[0]), depth, 0.5 * float(hi[1] - lo[1]))
            shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=half, **kw)
            pos = (0.5 * float(lo[0] + hi[0]), 0.5 * float(lo[1] + hi[1]))
        else:  # a hull in world coordinates, shrunk by the margin Bullet inflates it by
            prof = _offset_polygon(v, self._hull_margin)
            verts = [(float(x), y, float(z)) for x, z in prof for y in (-depth, depth)]
            shape = pb.createCollisionShape(pb.GEOM_MESH, vertices=verts, **kw)
            pos = (0.0, 0.0)
        if shape < 0:  # pragma: no cover - pybullet signals failure by -1
            raise RuntimeError("pybullet could not create a support's collision shape")
        return shape, pos

    def _is_box(self, blk: Any) -> bool:
        return self._shape == "box" and isinstance(blk, Block) and blk.chamfer == 0.0

    def _narrow(self, blk: Any) -> bool:
        return self._chamfer_shape == "narrow_box" and isinstance(blk, Block) \
            and blk.chamfer > 0.0 and self._shape != "mesh"

    def _set_dynamics(self, body: int, mu: float, rest: float, blk: Any,
                      inertia: tuple[float, ...] = (), margin: float | None = None) -> None:
        """Contact coefficients, no damping, no sleeping; a block's mass, ``inertia``
        (principal moments in its body frame) and margin; a support's ``margin``."""
        pb, kw = self._pb, self._kw
        extra: dict[str, Any] = {} if margin is None else {"collisionMargin": margin}
        if blk is not None:
            # box inertia (chamfer corners neglected, as the analytic models do);
            # the mass must be repeated or maximal-coordinate bodies lose it
            extra = {"mass": blk.m, "localInertiaDiagonal": inertia}
            if self._anchor:
                extra["frictionAnchor"] = 1
            boxed = self._is_box(blk) or self._narrow(blk)
            if self._margin is not None or not boxed:
                extra["collisionMargin"] = self._hull_margin if not boxed else self._margin
        pb.changeDynamics(body, -1, lateralFriction=mu, restitution=rest, rollingFriction=0.0,
                          spinningFriction=0.0, linearDamping=0.0, angularDamping=0.0,
                          activationState=pb.ACTIVATION_STATE_DISABLE_SLEEPING, **extra, **kw)

    # pybullet parses keyword arguments on every call: the per-step calls below pass
    # the client id positionally (``physicsClientId=cid`` costs ~0.5 µs more per call)
    def _drive_base(self, t: float, dt: float) -> None:
        i = int(round(t / self._dt))
        if i < len(self._v):
            u, v = self._u[i], self._v[i]
        else:  # beyond the precomputed window (should not happen): hold still
            u, v = self._u_end, _ZERO
        self._place_base(u, v)

    def _ground_at(self, u: tuple[float, ...]) -> tuple[float, float, float]:
        """The ground body's position at base displacement ``u`` (x, y, z)."""
        z = self._ground_z if u[2] == 0.0 else self._ground_z + u[2]
        return (u[0], u[1], z)

    def _place_base(self, u: tuple[float, ...], v: tuple[float, ...]) -> None:
        """Put the ground (and the supports) at displacement ``u`` with velocity ``v``."""
        pb, g, cid = self._pb, self._ground, self._cid
        pb.resetBasePositionAndOrientation(g, self._ground_at(u), (0.0, 0.0, 0.0, 1.0), cid)
        pb.resetBaseVelocity(g, v, (0.0, 0.0, 0.0), cid)
        for body, px, pz in self._supports:
            z = pz if u[2] == 0.0 else pz + u[2]
            pb.resetBasePositionAndOrientation(body, (u[0] + px, u[1], z), (0.0, 0.0, 0.0, 1.0),
                                               cid)
            pb.resetBaseVelocity(body, v, (0.0, 0.0, 0.0), cid)

    def _advance_driven(self, t0: float, n: int, dt: float) -> None:
        # _drive_base + _advance(1) per step in one loop over local names, except that the
        # base position is reset at the first step of the call only (once per output
        # sample): in between Bullet integrates the fixed-base multibody's position from
        # the secant velocity, which lands on u(t_{i+1}) (to rounding, which does not
        # reach the blocks' trajectories; resetting every step is kept in _drive_base)
        i0 = int(round(t0 / self._dt))
        if i0 + n > len(self._v):  # past the precomputed window (should not happen)
            super()._advance_driven(t0, n, dt)
            return
        pb, g, cid = self._pb, self._ground, self._cid
        if self._substeps != 0:
            pb.setPhysicsEngineParameter(fixedTimeStep=self._dt, numSubSteps=0, **self._kw)
            self._substeps = 0
        reset_vel, step, zero = pb.resetBaseVelocity, pb.stepSimulation, (0.0, 0.0, 0.0)
        if self._supports:  # the supports move with the ground
            self._place_base(self._u[i0], self._v[i0])
            bases = [g] + [body for body, _, _ in self._supports]
            for vel in self._v[i0:i0 + n]:
                for body in bases:
                    reset_vel(body, vel, zero, cid)
                step(cid)
            return
        pb.resetBasePositionAndOrientation(g, self._ground_at(self._u[i0]),
                                           (0.0, 0.0, 0.0, 1.0), cid)
        for vel in self._v[i0:i0 + n]:
            reset_vel(g, vel, zero, cid)
            step(cid)

    def _fix_base(self) -> bool:
        self._place_base(self._u_end, _ZERO)
        return True

    def _advance(self, n: int) -> None:
        pb, cid = self._pb, self._cid
        if n == 1:
            if self._substeps != 0:
                pb.setPhysicsEngineParameter(fixedTimeStep=self._dt, numSubSteps=0, **self._kw)
                self._substeps = 0
            pb.stepSimulation(cid)
            return
        if self._substeps != n:
            if _substeps_exact(n, self._dt):
                pb.setPhysicsEngineParameter(fixedTimeStep=n * self._dt, numSubSteps=n,
                                             **self._kw)
                self._substeps = n
            else:  # Bullet's accumulator would take n − 1 steps: step one by one
                if self._substeps != 0:
                    pb.setPhysicsEngineParameter(fixedTimeStep=self._dt, numSubSteps=0,
                                                 **self._kw)
                    self._substeps = 0
                step = pb.stepSimulation
                for _ in range(n):
                    step(cid)
                return
        pb.stepSimulation(cid)

    def _read_poses(self) -> np.ndarray:
        get, cid, out = self._pb.getBasePositionAndOrientation, self._cid, self._poses
        for i, body in enumerate(self._bodies):
            (x, y, z), (qx, qy, qz, qw) = get(body, cid)
            out[i] = (x, y, z, qw, qx, qy, qz)
        for i, c, s in self._turns:  # the block's orientation: q_body · rot_y(−φ)
            w, qx, qy, qz = out[i, 3:].tolist()
            out[i, 3:] = (w * c + qy * s, qx * c + qz * s, qy * c - w * s, qz * c - qx * s)
        return out

    def _teardown(self) -> None:
        if self._cid is not None:
            try:
                self._pb.disconnect(physicsClientId=self._cid)
            finally:
                self._cid = None


def principal_frame(tensor: np.ndarray) -> tuple[float, tuple[float, float, float]]:
    """Angle φ about y of the principal frame of an x–z-symmetric inertia tensor, and its
    principal moments.

    ``tensor`` is a centroidal inertia tensor whose y axis is principal (a prism
    centred in depth). With R the rotation by φ about y (θ > 0: +z toward +x),
    Rᵀ · tensor · R is diagonal; its diagonal is returned.
    """
    t = np.asarray(tensor, float)
    # a product of inertia at rounding level (a symmetric section) is no turn
    product = t[0, 2] if abs(t[0, 2]) > 1e-12 * (t[0, 0] + t[2, 2]) else 0.0
    phi = 0.5 * math.atan2(-2.0 * product, t[0, 0] - t[2, 2])
    c, s = math.cos(phi), math.sin(phi)
    r = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    d = np.diag(r.T @ t @ r)
    return phi, (float(d[0]), float(d[1]), float(d[2]))


def _substeps_exact(n: int, dt: float) -> bool:
    """True if Bullet's fixed-step accumulator takes exactly n steps of dt per call.

    Bullet computes ``int(local_time / (frame / n))`` in double precision; emulate it
    over a few calls so that a rounding down to n − 1 steps is caught.
    """
    frame = n * dt
    fixed = frame / n
    local = 0.0
    for _ in range(4):
        local += frame
        steps = int(local / fixed)
        if steps != n:
            return False
        local -= steps * fixed
    return True


def _offset_polygon(poly: np.ndarray, m: float) -> np.ndarray:
    """Move every edge of a convex counter-clockwise polygon inward by ``m``."""
    if m == 0.0:
        return poly
    out = np.empty_like(poly)
    k = len(poly)
    for j in range(k):
        p0, p1, p2 = poly[j - 1], poly[j], poly[(j + 1) % k]
        # inward normals of the edges before and after vertex j (CCW: rotate by +90°)
        d1, d2 = (p1 - p0) / np.linalg.norm(p1 - p0), (p2 - p1) / np.linalg.norm(p2 - p1)
        n1, n2 = np.array([-d1[1], d1[0]]), np.array([-d2[1], d2[0]])
        # the vertex moves along n1 + n2 so that it is m from both edges
        bis = n1 + n2
        out[j] = p1 + bis * (m / float(bis @ n1))
    return out


def _prism_triangles(k: int) -> list[int]:
    """Triangle indices of a prism whose vertex 2j is (profile j, y−) and 2j+1 is (j, y+).

    Outward normals for a counter-clockwise profile in the x–z plane.
    """
    tri: list[int] = []
    for j in range(k):
        a0, a1 = 2 * j, 2 * j + 1
        b0, b1 = 2 * ((j + 1) % k), 2 * ((j + 1) % k) + 1
        tri += [a0, b1, b0, a0, a1, b1]
    for j in range(1, k - 1):  # caps: fans from vertex 0
        tri += [0, 2 * j, 2 * (j + 1)]
        tri += [1, 2 * (j + 1) + 1, 2 * j + 1]
    return tri
