"""Newton engine plugin: rigid blocks in 3D through Newton (NVIDIA Warp) on the CPU.

Newton (NVIDIA, Google DeepMind, Disney Research; Apache-2.0) is a GPU-first
simulator built on NVIDIA Warp: every step is a sequence of Warp kernels, which run
here on the CPU device in float32. Its kernels are compiled by Warp the first time a
machine uses them (XPBD and the collision pipeline: about 35 s of CPU on 2 cores) and
cached on disk (``~/.cache/warp``): later processes load them in about a second. The
compilation is charged to the run that triggers it; :meth:`NewtonEngine.warm_up`
compiles them beforehand.

Scene: one :class:`newton.ModelBuilder` per run. Each block is a free body whose
frame is the block's (origin at its centre of gravity) with the block's mass and full
inertia tensor (``lock_inertia``: its shapes have no density), and one collision
shape: a box, or the convex hull of its prism (a chamfered block, a polygonal prism); a
cylinder is Newton's cylinder shape (its axis along the body's z). A start in the x–z
plane at rest is placed from ``initial_poses`` as it always was (bit-identical planar
runs); any other from ``initial_states``: position, quaternion and the velocities of
the centre of gravity (``body_qd``: linear, angular, world axes), written to the free
joint's coordinates too for the joint-space solvers. The base is a box whose top face is
z = 0 (the plane z = 0 in a scene with a cylinder: Newton's cylinder–plane routine,
rather than the generic convex one of a cylinder against a box) and the fixed supports
are more shapes of it: static shapes in free rocking, otherwise shapes of a KINEMATIC
body whose pose and velocity the plugin writes before every step (the base motion along
x, y and z). No damping, no sleeping. Newton gives a contact the *mean* of its two shapes' friction
coefficients (:func:`~rockbench.engines.friction.mean_frictions` chooses them so that
each pair gets the scenario's μ or μ_if) and its torsional and rolling friction, which
Newton enables by default (0.005 m and 1e-4 m: resistances Housner's block does not have),
are off except in the ``game`` preset.

Solvers (the ``solver`` knob; what each does on this problem is measured on the
engine's page):

* ``xpbd`` (:class:`newton.solvers.SolverXPBD`, the default): position-based
  dynamics; contacts are hard position constraints relaxed by ``relaxation``. Newton
  divides a body's contact corrections by its number of contacts by default, which
  leaves a stack's interface under-corrected (the upper block rocks on the lower one):
  here every contact is corrected in full, at relaxation 0.5.
* ``steel`` (:class:`newton.solvers.SolverSteel`, experimental in Newton 1.8):
  reduced coordinates, projected Gauss–Seidel on impulses, Coulomb friction patches.
* ``semi_implicit`` and ``featherstone`` (penalty contacts: ``contact_ke``,
  ``contact_kd``, ``contact_kf``), ``vbd`` (:class:`newton.solvers.SolverVBD`,
  augmented VBD for rigid bodies) and ``kamino`` (Disney's beta P-ADMM solver):
  offered for measurement; see the engine's page for why they are not trusted here.

``SolverMuJoCo`` is not offered: it needs ``mujoco-warp`` and pins an older
``mujoco`` (``newton[sim]``) than ``rockbench[mujoco]``.

Stepping: collision detection and the solver step are recorded once into Warp CPU
graphs (``wp.capture_begin`` on the CPU records the kernel launches, which
``wp.capture_launch`` replays in C++), bit-identical to launching them from Python
and about 20 times cheaper, since a step of these small scenes is almost all launch
overhead. A driven base writes its pose and velocity into the state arrays between
one-step graphs.

Presets: ``accurate`` (the defaults: XPBD, 0.25 ms, 8 iterations), ``fast`` (1 ms,
relaxation 0.3) and ``game`` (Newton's own defaults with XPBD at 60 Hz: what a game or
robotics user runs; its step is longer than the 1 ms output interval of the catalog's
scenarios, so it runs scenarios whose ``output_rate`` is at most 60 per second).

Known limits (float32 XPBD): the error does not converge below about 0.25 ms; a block
released within about 1 % of its tipping point may stand still (its turn per step is
below float32's resolution); a voussoir arch sags slowly at rest.

See :doc:`the engine's page </engines/newton>` in the documentation for its
calibration, measured accuracy, cost and known limits.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Literal

import numpy as np

from rockbench.engines.base import Capabilities
from rockbench.engines.batch import BatchEngine
from rockbench.engines.drive import BaseDrive
from rockbench.engines.friction import mean_frictions
from rockbench.engines.settings import EngineSettings, KnobRole
from rockbench.errors import UnsupportedScenario
from rockbench.geometry import Block, Cylinder, Support, stack
from rockbench.scenarios import Scenario, SinePulse

__all__ = ["NewtonEngine", "NewtonSettings", "prism_mesh"]

Solver = Literal["xpbd", "steel", "semi_implicit", "featherstone", "vbd", "kamino"]
#: Solvers that step joint coordinates (joint_q, joint_qd) rather than body poses.
_JOINT_SPACE = ("featherstone", "steel")
#: Base mass per kg of blocks (a kinematic body needs a mass; it never responds).
_BASE_MASS_RATIO = 1.0e6


def _libs() -> tuple[Any, Any]:
    """Warp and Newton, imported on first use (rule 2), Warp's info banner silenced."""
    wp = NewtonEngine.library("warp")
    # the module-load lines and the init banner go to stdout: keep the CLI's clean
    wp.config.log_level = wp.LOG_WARNING
    return wp, NewtonEngine.library("newton")


def _pose_3d(wp: Any, state: np.ndarray) -> Any:
    """A body's transform at a 3D state of :meth:`Scenario.initial_states`.

    ``state`` is (x, y, z, w, qx, qy, qz, vx, vy, vz, ωx, ωy, ωz) in world axes; Warp's
    quaternions are (x, y, z, w).
    """
    x, y, z, qw, qx, qy, qz = (float(v) for v in state[:7])
    return wp.transform(wp.vec3(x, y, z), wp.quat(qx, qy, qz, qw))


def _set_velocity(wp: Any, builder: Any, body: int, state: np.ndarray) -> None:
    """Give a free body (just added by ``add_body``) the velocities of a 3D state.

    Newton's ``body_qd`` is (linear, angular) in world axes, the linear part the
    velocity of the centre of mass, which is the body's origin here, as the state's.
    The body's free joint (the builder's last) gets the same: a FREE joint's
    ``joint_qd`` is the child's centre-of-mass velocity and angular velocity in the
    parent's frame, the world's (the joint-space solvers start from it).
    """
    v = [float(c) for c in state[7:13]]
    builder.body_qd[body] = wp.spatial_vector(*v)
    joint = builder.joint_count - 1
    assert builder.joint_child[joint] == body
    start = builder.joint_qd_start[joint]
    builder.joint_qd[start:start + 6] = v


@dataclass(frozen=True)
class NewtonSettings(EngineSettings):
    """Knobs of the Newton engine (defaults = the ``accurate`` preset).

    Newton's own default is given with each knob; the ``game`` preset is all of them
    at 60 Hz with XPBD.

    Parameters
    ----------
    timestep : float
        Physics time step in s (Newton's examples: 1/60 to 1/600). Rounded so that a
        whole number of steps fits one output interval (the effective step is
        recorded in the trajectory's settings).
    solver : {"xpbd", "steel", "semi_implicit", "featherstone", "vbd", "kamino"}
        Newton's solver (see the module docstring; Newton's examples default to XPBD).
    iterations : int
        Solver iterations per step: XPBD's constraint iterations (Newton: 2), Steel's
        PGS sweeps (12), VBD's iterations (10), Kamino's P-ADMM iteration cap (200);
        unused by the penalty solvers.
    relaxation : float
        XPBD's ``rigid_contact_relaxation``, the fraction of a contact's position
        error corrected per iteration (Newton: 0.8). Without contact weighting the
        contacts of a body overshoot together; 0.5 at 0.25 ms, 0.3 at 1 ms.
    contact_weighting : bool
        XPBD's ``rigid_contact_con_weighting``: divide a body's contact corrections
        by its number of active contacts (Newton: on). Off here: with it the lower
        block of a stack (four contacts) under-corrects its interface and the upper
        block rocks on it instead of with it (a stack pulse's peaks 69 % low).
    velocity_pass : bool
        XPBD's ``enable_restitution`` (Newton: off), always on when the scenario's
        restitution is > 0: after the position projection, a velocity-level solve
        drives each penetrating contact's normal velocity to −e times its approach
        velocity. With e = 0 it should remove a landing corner's push-out velocity,
        but it made rocking far worse (B0 0.47 λ off, a 0.1 rad wobble): off.
    restitution_iterations : int
        XPBD's ``rigid_contact_restitution_iterations``, outer iterations of that
        velocity solve (Newton: 2).
    contact_ke : float
        Normal contact stiffness in N/m of the penalty solvers (``semi_implicit``,
        ``featherstone``) and VBD (Newton's ShapeConfig: 2.5e3, far too soft for
        these masses).
    contact_kd : float
        Normal contact damping in N·s/m of those solvers (Newton: 100).
    contact_kf : float
        Friction gain in N·s/m of the penalty solvers: the slope of their viscous
        regularisation of Coulomb friction (Newton: 1000).
    mu_torsional : float
        Torsional friction coefficient in m (Newton: 0.005).
    mu_rolling : float
        Rolling friction coefficient in m (Newton: 1e-4): a resisting torque up to
        ``mu_rolling`` × the normal force against any relative rotation, a resistance
        Housner's block does not have; off except in ``game``.
    gap : float
        Contact detection gap in m (``ModelBuilder.rigid_gap``; Newton: 0.1):
        contacts are made while shapes are closer than this (speculative contacts;
        XPBD acts on penetrating ones only: no measurable effect). The shapes' margin
        (an outward offset of their surfaces) is 0, as Newton's: a margin would lift
        the blocks off their rest poses.
    angular_damping : float
        Angular velocity damping in 1/s of the semi-implicit and Featherstone solvers
        (Newton: 0.05); XPBD's default is 0. Off: Housner's block has no damping.
    chamfer_shape : {"hull", "box"}
        A chamfered block's collision shape: the convex hull of its prism, or the box
        spanning its flat faces (its rocking pivots exactly, collided by the box–box
        routine).
    planar : bool
        Join each block to the base by a D6 joint that frees only x, z and the rotation
        about y (not in Newton's defaults): the blocks stay in the x–z plane. A base
        motion along y is then unsupported. XPBD only (Steel carried a planar block
        rigidly with a moving base).
    graph : bool
        Replay each step's kernels from a recorded Warp CPU graph (Newton: launched
        from Python). Bit-identical; off only to measure the launch overhead.
    """

    timestep: float = 2.5e-4
    solver: Solver = "xpbd"
    iterations: int = 8
    relaxation: float = 0.5
    contact_weighting: bool = False
    velocity_pass: bool = False
    restitution_iterations: int = 2
    contact_ke: float = 1.0e7
    contact_kd: float = 1.0e3
    contact_kf: float = 1.0e3
    mu_torsional: float = 0.0
    mu_rolling: float = 0.0
    gap: float = 0.01
    angular_damping: float = 0.0
    chamfer_shape: Literal["hull", "box"] = "hull"
    planar: bool = False
    graph: bool = True

    def __post_init__(self) -> None:
        if not (math.isfinite(self.timestep) and self.timestep > 0):
            raise ValueError(f"timestep must be finite and > 0, got {self.timestep!r}")
        for name in ("iterations", "restitution_iterations"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} must be >= 1, got {getattr(self, name)!r}")
        if self.planar and self.solver != "xpbd":
            # measured: Steel carried a planar block rigidly with a moving base (no rocking)
            raise ValueError(f"planar is offered with solver 'xpbd' only, not {self.solver!r}")
        if not 0 < self.relaxation <= 1:
            raise ValueError(f"relaxation must be in (0, 1], got {self.relaxation!r}")
        for name in ("contact_ke", "contact_kd", "contact_kf", "mu_torsional", "mu_rolling",
                     "gap", "angular_damping"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be finite and >= 0, got {value!r}")


def prism_mesh(profile: np.ndarray, half_depth: float) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and outward triangles of a convex profile (x, z) extruded over ±half_depth.

    Parameters
    ----------
    profile : ndarray, shape (k, 2)
        Convex polygon in the x–z plane, counter-clockwise seen from −y (the
        geometry's convention: x to the right, z up).
    half_depth : float
        Half the extrusion along y (m).

    Returns
    -------
    vertices : ndarray, shape (2k, 3)
        The profile at y = −half_depth (first k), then at y = +half_depth.
    indices : ndarray, shape (4k − 4) × 3
        Triangle vertex indices, flattened, counter-clockwise seen from outside.
    """
    p = np.asarray(profile, dtype=float)
    k = len(p)
    front = np.column_stack([p[:, 0], np.full(k, -half_depth), p[:, 1]])
    back = np.column_stack([p[:, 0], np.full(k, half_depth), p[:, 1]])
    tris: list[tuple[int, int, int]] = []
    # seen from −y (x right, z up, y away from the viewer) the profile is
    # counter-clockwise: the front cap's fan faces −y, outward; the back cap's is reversed
    for j in range(1, k - 1):
        tris.append((0, j, j + 1))
        tris.append((k, k + j + 1, k + j))
    for j in range(k):
        a, b = j, (j + 1) % k
        tris.append((a, k + b, b))
        tris.append((a, k + a, k + b))
    return np.vstack([front, back]), np.asarray(tris, dtype=np.int32).ravel()


class NewtonEngine(BatchEngine):
    """Newton (NVIDIA Warp, float32) on the CPU device, one model per simulation."""

    name: ClassVar[str] = "newton"
    capabilities: ClassVar[Capabilities] = Capabilities(dimensions=3, max_blocks=None,
                                                        chamfer=True, assemblies=True,
                                                        base_axes="xyz", cylinders=True,
                                                        start3d=True, moving_start=True)
    Settings: ClassVar[type[EngineSettings]] = NewtonSettings
    presets: ClassVar[dict[str, dict[str, Any]]] = {
        # calibration: docs/engines/newton.md
        "accurate": {},
        # the same at 1 ms, its relaxation lowered to the overshoot of a longer step
        "fast": {"timestep": 1.0e-3, "relaxation": 0.3},
        # Newton's defaults (ShapeConfig, ModelBuilder.rigid_gap, SolverXPBD) at 60 Hz:
        # what a user of its examples runs; longer than a 1 ms output interval
        "game": {"timestep": 1.0 / 60.0, "solver": "xpbd", "iterations": 2,
                 "relaxation": 0.8, "contact_weighting": True, "velocity_pass": False,
                 "restitution_iterations": 2, "contact_ke": 2.5e3,
                 "contact_kd": 100.0, "contact_kf": 1000.0, "mu_torsional": 0.005,
                 "mu_rolling": 1.0e-4, "gap": 0.1},
    }
    requires: ClassVar[tuple[str, ...]] = ("newton", "warp")
    extra: ClassVar[str] = "newton"
    knob_roles: ClassVar[dict[str, KnobRole]] = {
        "timestep": KnobRole.TIME_STEP, "iterations": KnobRole.ITERATIONS}
    contact_model: ClassVar[str] = "impulse"
    known_failures: ClassVar[dict[str, str]] = {
        "mirror_symmetry": "Single #2 under the 3 Hz / 8 mm pulse and under its mirror image "
                           "rotate 1.71e-2 λ apart (limit 1e-2 λ), from the first impact on: "
                           "float32 rounding of the contact corrections differs between the "
                           "mirrored runs and the block's out-of-plane wobble amplifies it "
                           "(4.6e-3 λ with planar=true, 4.7e-3 λ with 16 iterations)",
        "assembly_rest": "the 9-voussoir arch sags at rest: a voussoir drifts 3.3e-3 m in 2 s "
                         "(limit 1e-3 of the scene's size), steadily: XPBD's few Jacobi-style "
                         "iterations leave the arch's thrust unbalanced every step (the steel "
                         "solver holds it to 1.2e-5 m)",
    }

    def __init__(self) -> None:
        self._model: Any = None
        self._solver: Any = None
        self._pipeline: Any = None
        self._contacts: Any = None
        self._control: Any = None
        self._states: list[Any] = []
        self._graphs: dict[tuple[int, int], Any] = {}
        self._cur = 0
        super().__init__()
        # per world: the base's body, its free joint's first coordinates (-1: none)
        self._bases = np.zeros(0, int)
        self._base_q = np.zeros(0, int)
        self._base_qd = np.zeros(0, int)
        self._rows = np.zeros(0, int)  # the blocks' bodies, world after world
        self._splits = np.zeros(0, int)
        self._dt = 0.0
        self._s: NewtonSettings = NewtonSettings()
        self._poses = np.zeros((0, 7))
        self._views: list[dict[str, np.ndarray]] = []

    @classmethod
    def version(cls) -> str:
        """Newton's version and the Warp that compiles its kernels."""
        wp, newton = _libs()
        return f"{newton.__version__} (warp {wp.__version__})"

    @classmethod
    def warm_up(cls, solvers: Sequence[str] = ("xpbd",)) -> float:
        """Compile (or load from Warp's disk cache) the kernels of ``solvers``.

        The first run of a solver on a machine compiles its kernels (XPBD and the
        collision pipeline: about 35 s of CPU on 2 cores) and that time is the run's CPU
        time. Call this once beforehand (a test session, a benchmark) to keep it out of
        the measurements; later processes load the cached kernels in about a second.

        Returns
        -------
        float
            Wall-clock seconds it took.
        """
        # a box on a chamfered block (a convex hull) on a moving base: every kernel a run
        # of the catalog uses
        geo = stack((Block(0.3, 0.2, 0.4, mass=1.0, chamfer=0.01),
                     Block(0.2, 0.2, 0.3, mass=1.0)))
        sc = Scenario("newton-warm-up", geo, excitation=SinePulse(5.0, 1e-4), duration=0.004,
                      output_rate=500.0)
        start = time.perf_counter()
        for solver in solvers:
            cls().simulate(sc, {"solver": solver, "timestep": 1e-3})
        return time.perf_counter() - start

    # ------------------------------------------------------------------ hooks
    def _check_supported(self, scenario: Scenario) -> None:
        c = scenario.contact
        if mean_frictions(scenario.geometry, c.friction, c.block_friction) is None:
            raise UnsupportedScenario(
                "newton gives a contact the mean of its two shapes' friction coefficients: "
                f"block-block friction {c.block_friction} above twice the base's "
                f"{c.friction} cannot both hold in a geometry whose blocks touch each other "
                "and the base (not a column)")

    def _build(self, scenario: Scenario, settings: EngineSettings) -> float:
        # one run is a batch of one world: both paths build and step the same model
        self.drives = [self.drive]
        return self._build_batch([scenario], settings)

    def _build_batch(self, scenarios: list[Scenario], settings: EngineSettings) -> float:
        assert isinstance(settings, NewtonSettings)  # resolve_settings made it one
        s = self._s = settings
        if s.planar and any("y" in d.axes for d in self.drives):
            # settings are not visible to _check_supported, hence here
            raise UnsupportedScenario(
                "newton: planar=True joins each block to the base along y, so a base motion "
                "along y would carry the blocks rigidly; run it with planar=false")
        if s.planar and any(not sc.planar_start or sc.moving_start for sc in scenarios):
            raise UnsupportedScenario(
                "newton: planar=True joins each block to the base in the x–z plane at rest: "
                "a 3D or moving start needs planar=false")
        wp, newton = _libs()
        out_dt = 1.0 / scenarios[0].output_rate
        # a whole number of steps per output interval lets samples be taken after whole
        # steps; a step longer than the interval is refused by the base loop
        dt = out_dt / max(1, round(out_dt / s.timestep)) if s.timestep <= out_dt * (1 + 1e-9) \
            else s.timestep
        self._dt = dt
        builder = newton.ModelBuilder(up_axis="Z", gravity=(0.0, 0.0, -scenarios[0].g))
        builder.rigid_gap = s.gap
        bases, base_joints, firsts = [], [], []
        for sc, drive in zip(scenarios, self.drives, strict=True):
            # a world per scenario: Newton collides no shape with another world's
            builder.begin_world(gravity=(0.0, 0.0, -sc.g))
            base, joint, first = self._add_world(newton, wp, builder, sc, drive, s)
            builder.end_world()
            bases.append(base)
            base_joints.append(joint)
            firsts.append(first)
        if s.solver == "vbd":
            builder.color()
        self._model = model = builder.finalize(device="cpu")
        self._solver = self._make_solver(newton, model, s,
                                         max(sc.contact.restitution for sc in scenarios))
        self._states = [model.state(), model.state()]
        if s.solver in _JOINT_SPACE:
            for st in self._states:
                newton.eval_fk(model, st.joint_q, st.joint_qd, st)
        self._pipeline = newton.CollisionPipeline(model, broad_phase="explicit")
        self._contacts = self._pipeline.contacts()
        self._control = model.control()
        self._cur = 0
        self._graphs = {}
        # CPU arrays: numpy() is a view of the same memory, written and read in place
        self._views = [{"body_q": st.body_q.numpy(), "body_qd": st.body_qd.numpy(),
                        "joint_q": st.joint_q.numpy(), "joint_qd": st.joint_qd.numpy()}
                       for st in self._states]
        self._bases = np.asarray(bases, int)
        q_start, qd_start = model.joint_q_start.numpy(), model.joint_qd_start.numpy()
        self._base_q = np.asarray([q_start[j] if j >= 0 else -1 for j in base_joints], int)
        self._base_qd = np.asarray([qd_start[j] if j >= 0 else -1 for j in base_joints], int)
        self._rows = np.concatenate([np.arange(f, f + sc.n_blocks)
                                     for f, sc in zip(firsts, scenarios, strict=True)])
        self._splits = np.cumsum([sc.n_blocks for sc in scenarios])[:-1]
        self._poses = np.zeros((len(self._rows), 7))
        return dt

    def _add_world(self, newton: Any, wp: Any, builder: Any, scenario: Scenario,
                   drive: BaseDrive, s: NewtonSettings) -> tuple[int, int, int]:
        """Add ``scenario``'s base, supports and blocks to the builder's current world.

        Returns the base's body (-1: static shapes) and free joint (-1: none), and the
        first block's body.
        """
        geo = scenario.geometry
        blocks = scenario.blocks
        c = scenario.contact
        mus = mean_frictions(geo, c.friction, c.block_friction)
        assert mus is not None  # _check_supported refused the others

        def shape_cfg(mu: float) -> Any:
            # no density: the bodies' mass and inertia are set explicitly
            return newton.ModelBuilder.ShapeConfig(
                density=0.0, ke=s.contact_ke, kd=s.contact_kd, kf=s.contact_kf, mu=mu,
                restitution=c.restitution, mu_torsional=s.mu_torsional,
                mu_rolling=s.mu_rolling, margin=0.0, gap=s.gap)

        # the base first (a planar joint's parent): wide enough for any toppled block, the
        # base's travel and an assembly's spread
        depth = max(b.depth for b in blocks)
        reach = max(0.5 * b.width for b in blocks) + geo.total_height + drive.travel + geo.room
        hx = max(1.0, 2.0 * reach)
        hy = max(1.0, 2.0 * reach, depth)
        hz = max(0.5, 0.5 * geo.total_height)
        base = base_joint = -1  # static shapes in free rocking
        joints = []
        if drive.moving:
            mass = _BASE_MASS_RATIO * float(sum(b.m for b in blocks))
            inertia = mass * (hx * hx + hz * hz) / 3.0
            base = builder.add_link(xform=wp.transform_identity(), mass=mass,
                                    inertia=wp.mat33(inertia, 0.0, 0.0, 0.0, inertia, 0.0,
                                                     0.0, 0.0, inertia),
                                    lock_inertia=True, is_kinematic=True, label="base")
            base_joint = builder.add_joint_free(child=base, label="base_free")
            joints.append(base_joint)
        base_cfg = shape_cfg(mus[0])
        if scenario.has_cylinders:
            # the plane z = 0 (infinite): Newton collides a cylinder with a plane by its own
            # routine (the rim point, the cap's tripod), with a box by GJK and a clipped
            # manifold, which launched a drum landing on its cap at an oblique azimuth
            builder.add_shape_plane(body=base, width=0.0, length=0.0, cfg=base_cfg)
        else:
            builder.add_shape_box(base, xform=wp.transform(wp.vec3(0.0, 0.0, -hz),
                                                           wp.quat_identity()),
                                  hx=hx, hy=hy, hz=hz, cfg=base_cfg)
        for sup in geo.supports:
            self._add_support(newton, wp, builder, base, sup, depth, base_cfg)
        if drive.moving and not s.planar:
            builder.add_articulation(joints, label="base")
            joints = []

        first = builder.body_count
        dof = newton.ModelBuilder.JointDofConfig
        # a start in the x–z plane at rest is placed from its (x, z, angle) poses, as
        # always (bit-identical planar runs); any other from its 3D states
        in_plane = scenario.initial_azimuth == 0.0 and not scenario.moving_start
        states = scenario.initial_states()
        for i, (blk, (cx, cz, th)) in enumerate(zip(blocks, scenario.initial_poses(),
                                                   strict=True)):
            if in_plane:
                q = wp.quat_from_axis_angle(wp.vec3(0.0, 1.0, 0.0), float(th))
                pose = wp.transform(wp.vec3(float(cx), 0.0, float(cz)), q)
            else:
                pose = _pose_3d(wp, states[i])
            inertia = wp.mat33(*np.asarray(blk.inertia_tensor, float).ravel().tolist())
            if s.planar:
                # x, z and the rotation about y relative to the base, from the block's pose
                body = builder.add_link(xform=pose, mass=float(blk.m), inertia=inertia,
                                        lock_inertia=True, label=f"block{i}")
                joints.append(builder.add_joint_d6(
                    base, body, linear_axes=[dof(axis=(1.0, 0.0, 0.0)),
                                             dof(axis=(0.0, 0.0, 1.0))],
                    angular_axes=[dof(axis=(0.0, 1.0, 0.0))], parent_xform=pose,
                    collision_filter_parent=False, label=f"planar{i}"))
            else:
                body = builder.add_body(xform=pose, mass=float(blk.m), inertia=inertia,
                                        lock_inertia=True, label=f"block{i}")
                if not in_plane:
                    _set_velocity(wp, builder, body, states[i])
            cfg = shape_cfg(mus[i + 1])
            if isinstance(blk, Cylinder):
                # Newton's cylinder: its axis along the body's z, as the Cylinder's
                builder.add_shape_cylinder(body, radius=float(blk.radius),
                                           half_height=float(blk.h), cfg=cfg)
            elif isinstance(blk, Block) and (blk.chamfer == 0 or s.chamfer_shape == "box"):
                # a chamfered block as the box spanning its flat faces: its pivots exactly
                builder.add_shape_box(body, hx=blk.pivot_half_width, hy=0.5 * blk.depth,
                                      hz=blk.h, cfg=cfg)
            else:  # a chamfered block or a convex prism: the hull of its prism
                verts, tris = prism_mesh(blk.profile(), 0.5 * blk.depth)
                mesh = newton.Mesh(verts, tris, compute_inertia=False)
                builder.add_shape_convex_hull(body, mesh=mesh, cfg=cfg)
        if joints:
            builder.add_articulation(joints, label="blocks")
        return base, base_joint, first

    @staticmethod
    def _add_support(newton: Any, wp: Any, builder: Any, base: int, sup: Support, depth: float,
                     cfg: Any) -> None:
        """A fixed support as a shape of the base (the world's frame at rest)."""
        v = sup.array
        lo, hi = v.min(axis=0), v.max(axis=0)
        if len(v) == 4 and all(len(set(col)) == 2 for col in v.T.tolist()):
            # an axis-aligned rectangle: a box, collided with box blocks exactly
            half, centre = 0.5 * (hi - lo), 0.5 * (hi + lo)
            builder.add_shape_box(base, xform=wp.transform(
                wp.vec3(float(centre[0]), 0.0, float(centre[1])), wp.quat_identity()),
                hx=float(half[0]), hy=depth, hz=float(half[1]), cfg=cfg)
            return
        verts, tris = prism_mesh(v, depth)
        builder.add_shape_convex_hull(base, mesh=newton.Mesh(verts, tris, compute_inertia=False),
                                      cfg=cfg)

    @staticmethod
    def _make_solver(newton: Any, model: Any, s: NewtonSettings, restitution: float) -> Any:
        """The Newton solver that ``s.solver`` names, with rockbench's choices."""
        solvers = newton.solvers
        if s.solver == "xpbd":
            return solvers.SolverXPBD(model, iterations=s.iterations,
                                      rigid_contact_relaxation=s.relaxation,
                                      rigid_contact_con_weighting=s.contact_weighting,
                                      angular_damping=0.0,
                                      enable_restitution=s.velocity_pass or restitution > 0,
                                      rigid_contact_restitution_iterations=(
                                          s.restitution_iterations))
        if s.solver == "semi_implicit":
            return solvers.SolverSemiImplicit(model, angular_damping=s.angular_damping)
        if s.solver == "featherstone":
            return solvers.SolverFeatherstone(model, angular_damping=s.angular_damping)
        if s.solver == "steel":
            return solvers.SolverSteel(model, iterations=s.iterations,
                                       enable_restitution=restitution > 0)
        if s.solver == "vbd":
            return solvers.SolverVBD(model, iterations=s.iterations)
        padmm = solvers.SolverKamino.Config.from_model(model).padmm
        padmm.max_iterations = s.iterations
        config = solvers.SolverKamino.Config.from_model(model, padmm=padmm)
        return solvers.SolverKamino(model, config=config)

    # ------------------------------------------------------------------ stepping
    def _graph(self, start: int, steps: int) -> Any:
        """The recorded graph of ``steps`` steps from state ``start`` (built on first use)."""
        key = (start, steps)
        g = self._graphs.get(key)
        if g is None:
            wp = self.library("warp")
            wp.capture_begin(device="cpu")
            try:
                self._eager(start, steps)
            finally:
                g = wp.capture_end(device="cpu")
            self._graphs[key] = g
        return g

    def _eager(self, start: int, steps: int) -> None:
        """Launch ``steps`` steps from state ``start`` kernel by kernel."""
        states, pipe, contacts = self._states, self._pipeline, self._contacts
        solver, control, dt = self._solver, self._control, self._dt
        a = start
        for _ in range(steps):
            src, dst = states[a], states[1 - a]
            src.clear_forces()
            pipe.collide(src, contacts)
            solver.step(src, dst, control, contacts, dt)
            a = 1 - a

    def _steps(self, n: int) -> None:
        """Take ``n`` steps from the current state."""
        if n <= 0:
            return
        if self._s.graph:
            self.library("warp").capture_launch(self._graph(self._cur, n))
        else:
            self._eager(self._cur, n)
        self._cur = (self._cur + n) % 2

    def _drive_worlds(self, worlds: list[int], u: np.ndarray, v: np.ndarray) -> None:
        # the base bodies' poses and velocities in the current state, and their free
        # joints' coordinates for the joint-space solvers
        view = self._views[self._cur]
        bodies = self._bases[worlds]
        view["body_q"][bodies, :3] = u
        view["body_qd"][bodies, :3] = v
        if self._s.solver in _JOINT_SPACE:
            q0, qd0 = self._base_q[worlds], self._base_qd[worlds]
            for a in range(3):
                view["joint_q"][q0 + a] = u[:, a]
                view["joint_qd"][qd0 + a] = v[:, a]

    def _advance(self, n: int) -> None:
        self._steps(n)

    def _sample_free(self, out: np.ndarray, k: int) -> None:
        for row in out:
            self._steps(k)
            row[...] = self._read_poses()

    def _read_poses(self) -> np.ndarray:
        return self._read_all()

    def _read_all(self) -> np.ndarray:
        """Every world's block poses, world after world, (x, y, z, qw, qx, qy, qz)."""
        q = self._views[self._cur]["body_q"][self._rows]
        out = self._poses
        out[:, :3] = q[:, :3]
        # Warp's quaternions are (x, y, z, w)
        out[:, 3] = q[:, 6]
        out[:, 4:] = q[:, 3:6]
        return out

    def _read_batch(self) -> list[np.ndarray]:
        return np.split(self._read_all(), self._splits)

    def _advance_batch(self, n: int) -> None:
        self._steps(n)

    def _teardown(self) -> None:
        self._model = self._solver = None
        self._states, self._views, self._graphs, self.drives = [], [], {}, []
        self._pipeline = self._contacts = self._control = None
