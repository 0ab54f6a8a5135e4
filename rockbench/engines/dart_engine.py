"""``--engine dart``: DART (Dynamic Animation and Robotics Toolkit) through ``dartpy``.

DART steps velocity-based (semi-implicit Euler), with a linear complementarity problem
(``lcp_solver``, Dantzig by default) for contacts and friction. Each block is a
``Skeleton`` on a ``FreeJoint`` with the block's mass and full inertia tensor and one
shape: a box, a triangle mesh of the prism for a convex prism (a chamfered block: by
default the box spanned by its flat faces, or its prism mesh, ``chamfer_shape``), or
DART's ``CylinderShape`` (axis along body z; FCL's primitive cylinder) for a cylinder.
Bodies start at ``Scenario.initial_states()`` when the start leaves the x–z plane or
moves (rotation vector and translation, velocities in world axes). The
base is a box skeleton (top face z = 0) on a ``PrismaticJoint`` along x (a base that
moves along x only: the planar benchmark's model) or a ``TranslationalJoint`` (x, y and
z: a base that also moves along y or z) whose ``VELOCITY`` actuator is commanded every
step with the secant velocity of the base motion, so that its position follows u_g(t)
exactly at the step nodes; fixed supports are more shapes of the base body. The base
motion is applied along x, y and z. Sleeping
is switched off. DART multiplies the restitutions of a pair, so each body gets sqrt(e)
(``restitution_mode``), and gives a pair the smaller of its two friction coefficients:
a column's bottom block gets max(μ, μ_if) and the others μ_if (exact for any μ, μ_if);
any other geometry gives every block μ_if and the base μ, exact when μ_if ≥ μ.

Presets and knobs:

* ``accurate``: Δt 0.025 ms with the FCL collision detector (the step at which the
  paper's stack converges).
* ``single``: Δt 0.1 ms with FCL, enough for single blocks and stack pulses.
* ``fast``: Δt 1 ms with ODE's detector; the assembly studies' preset.
* ``timestep``, ``collision_detector``, ``lcp_solver``, ``split_impulse``,
  ``restitution_mode``, ``chamfer_shape``, ``base_drive``.

Known limits: arches are unstable with ODE's meshes (``fast``), and ODE's cylinder
contact does not hold a rolling rim (a precessing cylinder needs FCL); DART's own
detector has no cylinders; walls are costly (the
contact LCP grows with the bricks); an interface friction below the base's is
unsupported on assemblies.

See :doc:`the engine's page </engines/dart>` in the documentation for its
calibration, measured accuracy and cost.
"""

from __future__ import annotations

import math
import os
import tempfile
from dataclasses import dataclass
from typing import Any, ClassVar, Literal

import numpy as np
from scipy.spatial.transform import Rotation

from rockbench.engines.base import Capabilities, Engine
from rockbench.engines.settings import EngineSettings, KnobRole
from rockbench.errors import UnsupportedScenario
from rockbench.geometry import Block, Cylinder, Support
from rockbench.scenarios import Scenario

__all__ = ["DartEngine", "DartSettings"]

_DETECTORS = ("fcl", "ode", "bullet", "dart")


@dataclass(frozen=True)
class DartSettings(EngineSettings):
    """Knobs of the DART engine (defaults = the ``accurate`` preset).

    Parameters
    ----------
    timestep : float
        Physics time step in s. The main lever on accuracy: each impact
        resolves within one step, and the ~step-long contact transition
        advances impacts slightly. 0.1 ms gives ~1e-3 λ on B0.
    collision_detector : {"fcl", "ode", "bullet", "dart"}
        Narrow-phase library. FCL is the most accurate with the box ground and
        with meshes (chamfers); ODE is the cheapest and the most accurate at a
        coarse (1 ms) step; DART's own detector handles boxes only, so it
        cannot model chamfered blocks nor cylinders. FCL collides a cylinder as its
        primitive; ODE's cylinder–box contact does not hold a rolling rim and
        Bullet's rounds it (its collision margin), so rolling cylinders need FCL.
    lcp_solver : {"dantzig", "pgs"}
        Boxed-LCP solver of the contact problem. Dantzig (pivoting, exact) is
        DART's default; PGS (projected Gauss-Seidel, iterative; DART's fallback
        solver, set as primary here) was less accurate in calibration.
    split_impulse : bool
        Resolve penetration with a separate position-correction impulse
        instead of the velocity bias (Bullet-style). Off: less accurate here.
    restitution_mode : {"sqrt", "raw"}
        DART multiplies the restitution coefficients of the two bodies in a
        contact. ``"sqrt"`` gives every body sqrt(e) so every contact pair gets
        the scenario's e; ``"raw"`` gives every body e (pairs get e²).
    chamfer_shape : {"narrow_box", "mesh"}
        Collision shape of a chamfered block. ``"narrow_box"`` (default): a box
        of width w − 2c with the block's full height and depth. Its bottom and
        top faces are exactly those of the chamfered prism (pivots at ±(b − c)
        on the faces), so every flat-face contact of rocking is identical as
        long as the relative tilt stays below 45° (the chamfer faces never
        touch); mass and inertia stay those of the block. ``"mesh"``: the
        convex prism extruded along y from ``Block.profile()`` as a triangle
        mesh (FCL, ODE and Bullet collide meshes; DART's own detector cannot).
        In calibration the mesh was 2–3× slower and less accurate on a single
        block (0.0005 vs 0.0002 λ), and FCL's mesh–mesh contact made the paper
        stack rock monolithically where every other detector/shape combination
        agreed on the top block rocking on the bottom one.
    base_drive : {"velocity", "acceleration"}
        Base actuator. ``"velocity"`` commands the secant velocity
        (u(t+dt) − u(t))/dt, so the base displacement is exact at every step;
        ``"acceleration"`` commands the secant acceleration
        (u̇(t+dt) − u̇(t))/dt, exact in velocity but with an O(dt) drift in
        displacement.
    """

    timestep: float = 2.5e-5
    collision_detector: Literal["fcl", "ode", "bullet", "dart"] = "fcl"
    lcp_solver: Literal["dantzig", "pgs"] = "dantzig"
    split_impulse: bool = False
    restitution_mode: Literal["sqrt", "raw"] = "sqrt"
    chamfer_shape: Literal["narrow_box", "mesh"] = "narrow_box"
    base_drive: Literal["velocity", "acceleration"] = "velocity"

    def __post_init__(self) -> None:
        if not (math.isfinite(self.timestep) and 0.0 < self.timestep <= 0.05):
            raise ValueError(f"timestep must be in (0, 0.05] s, got {self.timestep!r}")


def _prism_obj(profile: np.ndarray, depth: float, path: str) -> None:
    """Write a convex prism (a counter-clockwise x–z ``profile`` extruded over ``depth``
    along y, centred on y = 0) as a Wavefront OBJ.

    Triangles are wound counter-clockwise seen from outside (outward normals),
    which ODE's trimesh collider relies on.
    """
    prof = np.asarray(profile, float)
    k, y = len(prof), 0.5 * depth
    lines = [f"v {x:.17g} {-y:.17g} {z:.17g}" for x, z in prof]
    lines += [f"v {x:.17g} {y:.17g} {z:.17g}" for x, z in prof]
    faces = []
    for i in range(k):  # side faces; the profile is counter-clockwise in (x, z)
        j = (i + 1) % k
        faces += [(i, k + j, j), (i, k + i, k + j)]
    for i in range(1, k - 1):  # end caps at y = −d/2 (normal −y) and y = +d/2 (normal +y)
        faces += [(0, i, i + 1), (k, k + i + 1, k + i)]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces]
    with open(path, "w", encoding="ascii") as fh:
        fh.write("\n".join(lines) + "\n")


def _prism_shape(profile: np.ndarray, depth: float) -> Any:
    """A ``MeshShape`` of a convex prism (:func:`_prism_obj`): a chamfered block's, an
    assembly's polygonal block or support.

    dartpy cannot build an Assimp scene from Python, so the prism goes through
    a temporary OBJ file read by DART's URDF loader; the shape keeps the mesh
    in memory, so the file is deleted right away.
    """
    with tempfile.TemporaryDirectory(prefix="rockbench-dart-") as tmp:
        path = os.path.join(tmp, "prism.obj")
        _prism_obj(profile, depth, path)
        urdf = (
            '<robot name="prism"><link name="prism"><collision><geometry>'
            f'<mesh filename="file://{path}"/></geometry></collision></link></robot>'
        )
        dart = DartEngine.library("dartpy")
        skel = dart.utils.DartLoader().parseSkeletonString(
            urdf, dart.common.Uri(f"file://{tmp}/"))
        if skel is None or skel.getNumBodyNodes() == 0:
            raise UnsupportedScenario("DART could not load a prism mesh")
        return skel.getBodyNode(0).getShapeNode(0).getShape()


def _add_shape(body: Any, shape: Any, friction: float, restitution: float,
               offset: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> None:
    node = body.createShapeNode(shape)
    node.setRelativeTranslation(np.asarray(offset, float))
    node.createCollisionAspect()
    dyn = node.createDynamicsAspect()
    dyn.setFrictionCoeff(friction)
    dyn.setRestitutionCoeff(restitution)


def _place(joint: Any, skel: Any, state: np.ndarray) -> None:
    """Put a body on a ``FreeJoint`` at a state of :meth:`Scenario.initial_states`.

    ``state`` is the centre of mass (x, y, z), the quaternion (w, x, y, z) and
    the velocity and angular velocity (world axes). The joint's positions are
    the rotation vector then the translation; the velocities are set in the
    world frame through the joint's helpers (the body origin is its centre of
    mass, so the origin's velocity is the centre of mass's).
    """
    w, x, y, z = state[3:7]
    rotvec = Rotation.from_quat([x, y, z, w]).as_rotvec()
    skel.setPositions(np.concatenate([rotvec, state[:3]]))
    skel.setVelocities(np.zeros(6))
    joint.setLinearVelocity(np.asarray(state[7:10], float))
    joint.setAngularVelocity(np.asarray(state[10:13], float))


def _rectangle(support: Support) -> bool:
    """True if a support is an axis-aligned rectangle (a box)."""
    v = support.array
    return len(v) == 4 and all(len(set(col)) == 2 for col in v.T.tolist())


class DartEngine(Engine):
    """DART 6 (dartpy): free-joint blocks on a prismatic, velocity-driven box base."""

    name: ClassVar[str] = "dart"
    capabilities: ClassVar[Capabilities] = Capabilities(dimensions=3, max_blocks=None,
                                                        chamfer=True, assemblies=True,
                                                        base_axes="xyz", cylinders=True,
                                                        start3d=True, moving_start=True)
    Settings: ClassVar[type[EngineSettings]] = DartSettings
    presets: ClassVar[dict[str, dict[str, Any]]] = {
        "accurate": {"timestep": 2.5e-5, "collision_detector": "fcl"},
        # the former accurate: single blocks and stack pulses as accurate, stack sines not
        "single": {"timestep": 1e-4, "collision_detector": "fcl"},
        "fast": {"timestep": 1e-3, "collision_detector": "ode"},
    }
    requires: ClassVar[tuple[str, ...]] = ("dartpy",)
    extra: ClassVar[str] = "dart"
    knob_roles: ClassVar[dict[str, KnobRole]] = {"timestep": KnobRole.TIME_STEP}
    contact_model: ClassVar[str] = "impulse"
    # the parapet and the column within 3.2 % of the limit analysis on the tilting
    # table; the finer presets cost 11-43 CPU s per simulated s on the arches
    assembly_preset: ClassVar[str] = "fast"

    @classmethod
    def version(cls) -> str:
        """dartpy's version string."""
        return str(getattr(cls.library("dartpy"), "__version__", "unknown"))

    # ------------------------------------------------------------------ hooks
    def _check_supported(self, scenario: Scenario) -> None:
        c = scenario.contact
        if scenario.geometry.column is None and c.block_friction < c.friction:
            raise UnsupportedScenario(
                "dart gives a contact the smaller of the two bodies' friction coefficients: "
                f"block-block joints at μ_if = {c.block_friction:g} below the base's "
                f"μ = {c.friction:g} cannot both hold in a geometry other than a column, "
                "whose blocks may touch each other and the base")

    def _build(self, scenario: Scenario, settings: EngineSettings) -> float:
        assert isinstance(settings, DartSettings)  # resolve_settings made it one
        s = settings
        chamfered = any(b.chamfer > 0 for b in scenario.blocks)
        use_mesh = chamfered and s.chamfer_shape == "mesh"
        if use_mesh and s.collision_detector == "dart":
            raise UnsupportedScenario(
                "DART's own collision detector has no mesh support, so chamfered blocks "
                "need collision_detector fcl/ode/bullet or chamfer_shape=narrow_box"
            )
        geo = scenario.geometry
        column = geo.column
        supports = geo.supports
        if s.collision_detector == "dart" and (
                not all(isinstance(b, Block) for b in scenario.blocks)
                or not all(_rectangle(sup) for sup in supports)):
            raise UnsupportedScenario(
                "DART's own collision detector has no mesh or cylinder support, so an "
                "assembly's polygonal blocks and supports, and cylinders, need "
                "collision_detector fcl/ode/bullet")
        dt = float(s.timestep)
        dart = self.library("dartpy")
        world = dart.simulation.World()
        world.setGravity(np.array([0.0, 0.0, -scenario.g]))
        world.setTimeStep(dt)
        opts = world.getDeactivationOptions()
        opts.mEnabled = False  # sleeping would freeze slow rocking near rest
        world.setDeactivationOptions(opts)
        world.setCollisionDetector(
            getattr(dart.simulation.CollisionDetectorType, s.collision_detector.upper()))
        solver = world.getConstraintSolver()
        if s.lcp_solver == "pgs":
            # PgsBoxedLcpSolver has no Python constructor: promote DART's fallback solver
            solver.setBoxedLcpSolver(solver.getSecondaryBoxedLcpSolver())
        solver.setSplitImpulseEnabled(bool(s.split_impulse))

        mu = float(scenario.contact.friction)
        # DART takes the smaller coefficient of a pair: the ground carries μ, the blocks
        # μ_if, the bottom block at least μ (so that the ground's rules its contact)
        mu_if = float(scenario.contact.block_friction)
        e = float(scenario.contact.restitution)
        e_body = math.sqrt(e) if s.restitution_mode == "sqrt" else e

        # base: a box (top face z = 0) on a prismatic joint along x, or a translational
        # joint if it also moves along y or z, driven kinematically
        drive = self.drive
        planar = set(drive.axes) <= {"x"}
        t_move = drive.stop
        u_max = drive.travel
        span = 4.0 * (geo.total_height + max(b.width for b in scenario.blocks))
        if column is None:  # wide scenes: the blocks' spread along x too
            span += 2.0 * u_max + geo.reach + geo.size
        else:  # a column: its blocks' offsets from x = 0
            span += 2.0 * u_max + float(np.max(np.abs(column.offsets)))
        depth = 4.0 * max(b.depth for b in scenario.blocks) + span
        thick = max(0.5, 0.25 * geo.total_height)
        base = dart.dynamics.Skeleton("base")
        if planar:
            joint, body = base.createPrismaticJointAndBodyNodePair()
            joint.setAxis(np.array([1.0, 0.0, 0.0]))
        else:
            joint, body = base.createTranslationalJointAndBodyNodePair()
        joint.setActuatorType(dart.dynamics.ActuatorType.VELOCITY
                              if s.base_drive == "velocity"
                              else dart.dynamics.ActuatorType.ACCELERATION)
        body.setMass(max(1.0, 100.0 * sum(b.m for b in scenario.blocks)))
        _add_shape(body, dart.dynamics.BoxShape(np.array([2.0 * span, depth, thick])),
                   mu, e_body, (0.0, 0.0, -0.5 * thick))
        # an assembly's fixed supports: more shapes of the base body (the base is at
        # x = 0 now, so base coordinates are world coordinates), deeper than any block
        sup_depth = 2.0 * max(b.depth for b in scenario.blocks)
        for sup in supports:
            v = sup.array
            lo, hi = v.min(axis=0), v.max(axis=0)
            if _rectangle(sup):
                _add_shape(body, dart.dynamics.BoxShape(np.array(
                    [float(hi[0] - lo[0]), sup_depth, float(hi[1] - lo[1])])), mu, e_body,
                    (0.5 * float(lo[0] + hi[0]), 0.0, 0.5 * float(lo[1] + hi[1])))
            else:
                _add_shape(body, _prism_shape(v, sup_depth), mu, e_body)
        world.addSkeleton(base)

        # blocks: one skeleton each, free joint at the centroid
        poses = scenario.initial_poses()
        # a 3D or moving start: each body's pose and velocities from initial_states()
        states = (None if scenario.planar_start and not scenario.moving_start
                  else scenario.initial_states())
        self._skels = []
        for i, (blk, (cx, cz, th)) in enumerate(zip(scenario.blocks, poses, strict=True)):
            skel = dart.dynamics.Skeleton(f"block{i}")
            free, bn = skel.createFreeJointAndBodyNodePair()
            if isinstance(blk, Cylinder):  # the native cylinder, its axis along body z
                shape = dart.dynamics.CylinderShape(blk.radius, blk.height)
                tensor = np.diag(blk.inertia)
            elif not isinstance(blk, Block):  # an assembly's convex prism
                shape = _prism_shape(blk.profile(), blk.depth)
                tensor = blk.inertia_tensor  # the x–z product of inertia is not zero
            else:
                if use_mesh and blk.chamfer > 0:
                    shape = _prism_shape(blk.profile(), blk.depth)
                else:  # plain box, or the chamfered prism's flat faces (narrow_box)
                    w = blk.width - 2.0 * blk.chamfer
                    shape = dart.dynamics.BoxShape(np.array([w, blk.depth, blk.height]))
                tensor = np.diag(blk.inertia)
            # a column's bottom block touches the base and the block above only
            block_mu = mu_if if column is None or i > 0 else max(mu, mu_if)
            _add_shape(bn, shape, block_mu, e_body)
            bn.setInertia(dart.dynamics.Inertia(blk.m, np.zeros(3), tensor))
            if states is None:
                # FreeJoint coordinates: rotation vector (about +y by θ), then translation
                skel.setPositions(np.array([0.0, th, 0.0, cx, 0.0, cz]))
                skel.setVelocities(np.zeros(6))
            else:
                _place(free, skel, states[i])
            world.addSkeleton(skel)
            self._skels.append(skel)

        self._world = world
        self._step = world.step
        self._base_joint = joint
        self._set_command = joint.setCommand
        self._set_commands = joint.setCommands
        self._dt = dt
        # base commands for every step while it moves, computed once (vectorised): floats
        # for the prismatic joint, (x, y, z) arrays for the translational one
        self._planar = planar
        self._cmd: list[Any] = []
        if t_move > 0:
            # one output interval of margin: the loop fixes the base at a sample boundary
            n = int(math.ceil((t_move + 1.0 / scenario.output_rate) / dt)) + 2
            t = drive.grid(dt, n + 1)
            f = drive.displacement if s.base_drive == "velocity" else drive.velocity
            if planar:
                self._cmd = (np.diff(f(t)[:, 0]) / dt).tolist()
                # the base stands still at the start, the excitation starts from rest
                joint.setPosition(0, 0.0)
            else:
                self._cmd = list(np.diff(f(t), axis=0) / dt)
                joint.setPositions(np.zeros(3))
        self._base_fn = drive.displacement if s.base_drive == "velocity" else drive.velocity
        self._poses = np.empty((len(self._skels), 7))
        self._get_positions = [sk.getPositions for sk in self._skels]
        return dt

    def _drive_base(self, t: float, dt: float) -> None:
        command = self._command(int(round(t / dt)), t, dt)
        if self._planar:
            self._set_command(0, command)
        else:
            self._set_commands(command)

    def _command(self, i: int, t: float, dt: float) -> Any:
        """Base command for step ``i`` (starting at time ``t``): a float along x for the
        prismatic joint, an (x, y, z) array for the translational one."""
        if i < len(self._cmd):
            return self._cmd[i]
        f = self._base_fn  # past the precomputed span (not expected): evaluate directly
        if not self._planar:
            return (f(t + dt) - f(t)) / dt
        return (float(f(t + dt)[0]) - float(f(t)[0])) / dt

    def _advance_driven(self, t0: float, n: int, dt: float) -> None:
        # one Python loop over precomputed commands: no per-step method dispatch
        i0 = int(round(t0 / dt))
        if i0 + n > len(self._cmd):
            super()._advance_driven(t0, n, dt)
            return
        step, setc = self._step, self._set_command
        if not self._planar:
            sets = self._set_commands
            for c in self._cmd[i0:i0 + n]:
                sets(c)
                step()
            return
        for v in self._cmd[i0:i0 + n]:
            setc(0, v)
            step()

    def _fix_base(self) -> bool:
        # World.step() resets commands to 0 after each step: with a zero velocity
        # (or acceleration, the base ends at rest) command the base stays put
        return True

    def _advance(self, n: int) -> None:
        step = self._step
        if n == 1:  # the fast preset samples every step
            step()
            return
        for _ in range(n):
            step()

    def _read_poses(self) -> np.ndarray:
        out = self._poses
        # plain floats and math: for a few blocks this beats vectorised numpy
        for i, get in enumerate(self._get_positions):
            rx, ry, rz, x, y, z = get().tolist()
            a = math.sqrt(rx * rx + ry * ry + rz * rz)
            k = math.sin(0.5 * a) / a if a > 1e-12 else 0.5
            out[i] = (x, y, z, math.cos(0.5 * a), rx * k, ry * k, rz * k)
        return out

    def _teardown(self) -> None:
        self._world = None
        self._step = None
        self._skels = []
        self._get_positions = []
        self._base_joint = None
        self._set_command = None
        self._set_commands = None
