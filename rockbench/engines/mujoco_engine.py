"""MuJoCo engine plugin: rigid blocks as free bodies on a box base driven along x, y and z.

The scene is an MJCF string built from the scenario. Each block is a body with a free
joint, its frame at the centroid, with the block's mass and inertia; its collision
shape is a ``box`` geom, or a ``mesh`` geom of its prism for a chamfered block or a
convex prism (MuJoCo collides with the convex hull; ``multiccd`` gives a flat face
several contact points). The ground is a box whose top face is z = 0: a static world
geom in free rocking, otherwise a heavy body on one slide joint per axis along which the
base moves (x, y and z; a scenario moving along x only gets the x joint only, the model
of the planar benchmark) whose positions and velocities are overwritten with the base
motion's before every step, and a force gives each exactly the acceleration to the next
step's velocity (plus the base's weight along z; a mocap body would not drag the blocks
through friction). Once the motion ends a huge damping holds it still, so that steps
are batched in C. The base motion is applied along x, y and z. Contacts are
condim 3 with Coulomb friction (an interface friction on the blocks' geoms, the base's
on the base geom, whose ``priority`` rules its contacts) and a tight ``solimp``. No
damping, no sleeping.

MuJoCo's contacts are soft: ``solref`` has the time constant ``timeconst_factor`` × Δt
and the damping ratio ``dampratio``. A contact is found only once a corner has
penetrated, and at τ = 2 Δt the spring pushes a landing corner out with e ≈ 1/(4ζ²),
so a plastic impact needs ζ ≈ 3, not critical damping. MuJoCo has no restitution
coefficient: a scenario restitution e > 0 is mapped onto ζ = −ln e / sqrt(π² + ln² e).
The pyramidal cone (with ``impratio`` 10) is the default because the elliptic cone
lets a sliding block hop.

Presets and knobs:

* ``accurate`` (the defaults): Δt 0.1 ms, τ = 2 Δt, ζ = 3, pyramidal cone, Newton
  solver.
* ``fast``: the same contact at Δt 1 ms; the assembly studies' preset.
* ``timestep``, ``timeconst_factor``, ``dampratio``, ``solimp_*``, ``cone``,
  ``impratio``, the solver's ``iterations`` and ``tolerance``, ``noslip_iterations``.

Known limits: sliding contacts chatter with either cone, so a slide follows the Coulomb
slider on average but not through a near-stick, and a stack interface that must carry
exactly μN carries less.

See :doc:`the engine's page </engines/mujoco>` in the documentation for its
calibration, measured accuracy and cost.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar, Literal

import numpy as np

from rockbench.engines.base import Capabilities, Engine
from rockbench.engines.drive import AXIS, BaseDrive
from rockbench.engines.settings import EngineSettings, KnobRole
from rockbench.errors import UnsupportedScenario
from rockbench.geometry import Block, Cylinder
from rockbench.scenarios import Scenario

__all__ = ["MujocoEngine", "MujocoSettings"]

#: Base mass per kg of blocks: the contact reaction barely moves a driven base.
_BASE_MASS_RATIO = 1.0e6
#: Excitation samples precomputed per chunk (bounded memory for long records).
_CHUNK = 20000
#: The base's slide joint along each axis: name, axis.
_SLIDES = {"x": ("slide", "1 0 0"), "y": ("slide_y", "0 1 0"), "z": ("slide_z", "0 0 1")}


@dataclass(frozen=True)
class MujocoSettings(EngineSettings):
    """Knobs of the MuJoCo engine (defaults = the ``accurate`` preset).

    Parameters
    ----------
    timestep : float
        Physics time step in s (``opt.timestep``), the main accuracy lever.
    timeconst_factor : float
        Contact ``solref`` time constant as a multiple of the time step. MuJoCo
        clamps it to ≥ 2 steps (``refsafe``); 2–5 works, larger makes contacts
        softer (more penetration, impacts smeared and early).
    dampratio : float
        Contact ``solref`` damping ratio used when the scenario restitution is 0.
        It lowers the contact stiffness at a fixed time constant (K ∝ 1/ζ²); at
        τ = 2 dt a corner that lands inside the contact rebounds with e ≈ 1/(4ζ²),
        so Housner's plastic impact needs ζ ≈ 3 (see the module docstring), not 1.
    solimp_dmin : float
        ``solimp`` d0: constraint impedance at zero penetration (0–1, 1 = hard).
    solimp_dmax : float
        ``solimp`` d_width: impedance at ``solimp_width`` penetration.
    solimp_width : float
        ``solimp`` width in m over which the impedance rises from dmin to dmax.
    integrator : {"Euler", "implicitfast", "implicit"}
        Time integrator. Euler is semi-implicit (symplectic) and the cheapest.
        RK4 is not offered: it integrates the base's holding damping explicitly.
    cone : {"elliptic", "pyramidal"}
        Friction cone. Elliptic is isotropic Coulomb; the pyramid is exact along its
        edges, the contact frame's tangents, which for these faces are y and the
        in-plane direction: Coulomb in the x–z plane. Pyramidal is the default (see
        the module docstring: elliptic cones lift sliding blocks).
    solver : {"Newton", "CG", "PGS"}
        Constraint solver.
    iterations : int
        Maximum constraint-solver iterations per step.
    tolerance : float
        Solver tolerance (relative cost improvement at which it stops).
    ls_iterations : int
        Maximum line-search iterations of the Newton/CG solvers.
    noslip_iterations : int
        Extra no-slip iterations after the main solver (0 = off); they remove the
        creep that soft friction allows (the normal forces stay the main solver's).
    noslip_tolerance : float
        The no-slip pass stops once an iteration improves its cost by less than this.
        MuJoCo's default 1e-6 ends it after about 2 iterations on the sliding cases
        (20 and 100 iterations gave the same trajectories); 0 runs them all.
    impratio : float
        Ratio of frictional to normal constraint impedance; > 1 makes friction
        harder. Both cones: a pyramid facet's regulariser is 2 μ² / impratio times
        the normal one.
    multiccd : bool
        Several contact points between convex meshes (chamfered blocks) instead
        of one. Boxes use MuJoCo's box–box routine either way.

    Notes
    -----
    The presets' calibration and their measured accuracy are on
    :doc:`the engine's page </engines/mujoco>` in the documentation.
    """

    timestep: float = 1.0e-4
    timeconst_factor: float = 2.0
    dampratio: float = 3.0
    solimp_dmin: float = 0.99
    solimp_dmax: float = 0.999
    solimp_width: float = 0.001
    integrator: Literal["Euler", "implicitfast", "implicit"] = "Euler"
    cone: Literal["elliptic", "pyramidal"] = "pyramidal"
    solver: Literal["Newton", "CG", "PGS"] = "Newton"
    iterations: int = 100
    tolerance: float = 1.0e-10
    ls_iterations: int = 50
    noslip_iterations: int = 0
    noslip_tolerance: float = 1.0e-6
    impratio: float = 10.0
    multiccd: bool = True

    def __post_init__(self) -> None:
        if not (math.isfinite(self.timestep) and self.timestep > 0):
            raise ValueError(f"timestep must be finite and > 0, got {self.timestep!r}")
        if not self.timeconst_factor > 0:
            raise ValueError(f"timeconst_factor must be > 0, got {self.timeconst_factor!r}")
        if not self.dampratio > 0:
            raise ValueError(f"dampratio must be > 0, got {self.dampratio!r}")
        if not 0 < self.solimp_dmin <= self.solimp_dmax < 1:
            raise ValueError("solimp must satisfy 0 < solimp_dmin <= solimp_dmax < 1")
        if not self.solimp_width > 0:
            raise ValueError(f"solimp_width must be > 0, got {self.solimp_width!r}")
        for name in ("iterations", "ls_iterations"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} must be >= 1, got {getattr(self, name)!r}")
        if self.noslip_iterations < 0:
            raise ValueError(f"noslip_iterations must be >= 0, got {self.noslip_iterations!r}")
        if not (self.tolerance >= 0 and self.noslip_tolerance >= 0 and self.impratio >= 1):
            raise ValueError("tolerance and noslip_tolerance must be >= 0 and impratio >= 1")


def restitution_dampratio(e: float) -> float:
    """Damping ratio of the linear spring–damper whose coefficient of restitution is ``e``."""
    if e <= 0:
        return 1.0
    le = math.log(e)
    return -le / math.sqrt(math.pi**2 + le * le)


def _fmt(values: Any) -> str:
    """Numbers for MJCF attributes (shortest text that round-trips)."""
    return " ".join(repr(float(v)) for v in np.ravel(values))


class MujocoEngine(Engine):
    """MuJoCo (DeepMind) rigid-body engine with soft, convex contacts."""

    name: ClassVar[str] = "mujoco"
    capabilities: ClassVar[Capabilities] = Capabilities(dimensions=3, max_blocks=None,
                                                        chamfer=True, assemblies=True,
                                                        base_axes="xyz", cylinders=True,
                                                        start3d=True, moving_start=True)
    Settings: ClassVar[type[EngineSettings]] = MujocoSettings
    presets: ClassVar[dict[str, dict[str, Any]]] = {
        "accurate": {},
        # accurate's contact at 1 ms (dt ≤ 1/output_rate: the base loop takes whole steps
        # per output sample): the cheapest of benchmarks/preset_pareto.py's grid meeting the
        # former fast's worst errors (τ = 4 dt, ζ = 1, elliptic cone: 1.24× its cost)
        "fast": {"timestep": 1.0e-3},
    }
    requires: ClassVar[tuple[str, ...]] = ("mujoco",)
    extra: ClassVar[str] = "mujoco"
    knob_roles: ClassVar[dict[str, KnobRole]] = {
        "timestep": KnobRole.TIME_STEP, "iterations": KnobRole.ITERATIONS,
        "tolerance": KnobRole.TOLERANCE, "timeconst_factor": KnobRole.CONTACT_SOFTNESS}
    contact_model: ClassVar[str] = "soft-constraint"
    # onsets within 0.1 % of the limit analysis on the tilting table at a fraction of the
    # accurate cost
    assembly_preset: ClassVar[str] = "fast"

    @classmethod
    def version(cls) -> str:
        return str(cls.library("mujoco").__version__)

    # ------------------------------------------------------------------ build
    def _check_supported(self, scenario: Scenario) -> None:
        if scenario.contact.restitution >= 0.99:
            raise UnsupportedScenario(
                "mujoco models restitution through the contact damping ratio and cannot "
                f"represent near-elastic impacts (restitution {scenario.contact.restitution})"
            )

    def mjcf(self, scenario: Scenario, settings: MujocoSettings) -> str:
        """The MJCF model of ``scenario`` (public for inspection and tests)."""
        s = settings
        blocks = scenario.blocks
        drive = BaseDrive(scenario.motion, scenario.duration)
        e = scenario.contact.restitution
        zeta = restitution_dampratio(e) if e > 0 else s.dampratio
        tau = s.timeconst_factor * s.timestep
        mu = scenario.contact.friction
        mu_if = scenario.contact.block_friction
        contact_common = (
            f'condim="3" solref="{_fmt(tau)} {_fmt(zeta)}" '
            f'solimp="{_fmt(s.solimp_dmin)} {_fmt(s.solimp_dmax)} {_fmt(s.solimp_width)} 0.5 2" '
            'margin="0" gap="0"'
        )
        geom_common = f'friction="{_fmt(mu_if)} 0 0" {contact_common}'
        base_common = f'friction="{_fmt(mu)} 0 0" {contact_common}'
        if mu_if != mu:  # equal priorities take the larger friction
            base_common += ' priority="1"'
        geo = scenario.geometry
        poses = scenario.initial_poses()
        mass_total = sum(b.m for b in blocks)
        # a base large enough for the stack, its tilt and the base travel
        ext = geo.total_height + max(b.width for b in blocks) + geo.room
        hx = 2.0 * ext + 2.0 * drive.travel + 1.0
        hy = 2.0 * max(b.depth for b in blocks) + 0.5
        if "y" in drive.axes:  # as wide as long: the base travels, the blocks rock along y
            hy = max(hy, hx)
        hz = 0.25 * ext + 0.1
        flags = "" if s.multiccd else ' multiccd="disable"'
        assets, bodies = [], []
        states = scenario.initial_states()
        for i, (blk, (cx, cz, th_i)) in enumerate(zip(blocks, poses, strict=True)):
            pos: tuple[float, ...] = (cx, 0.0, cz)
            quat: tuple[float, ...] = (math.cos(0.5 * th_i), 0.0, math.sin(0.5 * th_i), 0.0)
            if scenario.initial_azimuth != 0.0:  # a start out of the x–z plane
                pos, quat = tuple(states[i, :3]), tuple(states[i, 3:7])
            if isinstance(blk, Cylinder):
                shape = f'type="cylinder" size="{_fmt((blk.radius, blk.h))}"'
            elif blk.chamfer > 0 or not isinstance(blk, Block):  # a convex prism
                prof = blk.profile()
                hd = 0.5 * blk.depth
                verts = [(x, y, z) for y in (-hd, hd) for x, z in prof]
                assets.append(f'<mesh name="prism{i}" vertex="{_fmt(verts)}"/>')
                shape = f'type="mesh" mesh="prism{i}"'
            else:
                shape = f'type="box" size="{_fmt((blk.b, 0.5 * blk.depth, blk.h))}"'
            if isinstance(blk, (Block, Cylinder)):
                inertia = f'diaginertia="{_fmt(blk.inertia)}"'
            else:  # a polygon's x–z product of inertia is not zero
                t = blk.inertia_tensor
                inertia = f'fullinertia="{_fmt((t[0, 0], t[1, 1], t[2, 2], 0.0, t[0, 2], 0.0))}"'
            bodies.append(
                f'<body name="block{i}" pos="{_fmt(pos)}" quat="{_fmt(quat)}">'
                f'<freejoint name="free{i}"/>'
                f'<inertial pos="0 0 0" mass="{_fmt(blk.m)}" {inertia}/>'
                f'<geom name="geom{i}" {shape} {geom_common}/></body>'
            )
        base_geom = (f'<geom name="base" type="box" size="{_fmt((hx, hy, hz))}" '
                     f'pos="0 0 {_fmt(-hz)}" {base_common}/>')
        # an assembly's fixed supports: prisms (world coordinates) on the base, wider than
        # any block in depth
        for j, sup in enumerate(geo.supports):
            hd = max(b.depth for b in blocks)
            verts = [(x, y, z) for y in (-hd, hd) for x, z in sup.vertices]
            assets.append(f'<mesh name="support{j}" vertex="{_fmt(verts)}"/>')
            base_geom += f'<geom name="support{j}" type="mesh" mesh="support{j}" {base_common}/>'
        if not drive.moving:
            base = base_geom
        else:
            mb = _BASE_MASS_RATIO * mass_total
            ib = mb * (hx * hx + hz * hz) / 3.0  # irrelevant (no rotation), but positive
            # one slide joint per moving axis, in x, y, z order ("slide" along x)
            joints = "".join(
                f'<joint name="{_SLIDES[a][0]}" type="slide" axis="{_SLIDES[a][1]}" '
                'damping="0" armature="0"/>' for a in drive.axes)
            base = (f'<body name="base" pos="0 0 0">{joints}'
                    f'<inertial pos="0 0 {_fmt(-hz)}" mass="{_fmt(mb)}" '
                    f'diaginertia="{_fmt(ib)} {_fmt(ib)} {_fmt(ib)}"/>{base_geom}</body>')
        return (
            '<mujoco model="rockbench">'
            '<compiler angle="radian" inertiafromgeom="false" boundmass="0" boundinertia="0"/>'
            f'<option timestep="{_fmt(s.timestep)}" gravity="0 0 {_fmt(-scenario.g)}" '
            f'integrator="{s.integrator}" cone="{s.cone}" solver="{s.solver}" '
            f'iterations="{s.iterations}" tolerance="{_fmt(s.tolerance)}" '
            f'ls_iterations="{s.ls_iterations}" noslip_iterations="{s.noslip_iterations}" '
            f'noslip_tolerance="{_fmt(s.noslip_tolerance)}" '
            f'impratio="{_fmt(s.impratio)}"><flag{flags}/></option>'
            f'<asset>{"".join(assets)}</asset>'
            f'<worldbody>{"".join(bodies)}{base}</worldbody></mujoco>'
        )

    def _build(self, scenario: Scenario, settings: EngineSettings) -> float:
        mujoco = self.library("mujoco")
        assert isinstance(settings, MujocoSettings)
        self._model = mujoco.MjModel.from_xml_string(self.mjcf(scenario, settings))
        self._data = mujoco.MjData(self._model)
        self._step = mujoco.mj_step
        n = scenario.n_blocks
        self._n = n
        # blocks come first in the body tree: their free-joint qpos is (x, y, z, qw, qx, qy, qz)
        self._pose_view = self._data.qpos[: 7 * n].reshape(n, 7)
        self._poses = np.empty((n, 7))
        self._dt = float(self._model.opt.timestep)
        drive = self.drive
        self._chunk_start = self._chunk_end = -1
        # per step: plain floats for a base moving along x only (one slide joint: the
        # planar benchmark's model and loops), else tuples, one value per slide joint
        self._ul: list[Any] = []
        self._vl: list[Any] = []
        self._fl: list[Any] = []
        self._axes = drive.axes
        self._cols = [AXIS[a] for a in self._axes]
        self._na = len(self._axes)
        self._planar = self._axes == ("x",)
        if drive.moving:
            self._jq = 7 * n  # slide joints: after the n free joints
            self._jv = 6 * n
            self._mbase = float(self._model.body_mass[n + 1])
            # the force that holds the base's weight along z (gravity acts on its joint)
            self._hold = [self._mbase * scenario.g if a == "z" else 0.0 for a in self._axes]
            # steps the base loop drives at most: to the end of the motion (or of the run),
            # then up to one output interval more (the base is fixed after the first sample
            # past the end); short runs thus precompute only what they use
            per_sample = max(1, math.ceil(1.0 / (scenario.output_rate * self._dt) - 1e-9))
            self._n_drive = drive.steps_until_stop(self._dt) + per_sample + 2
        if scenario.moving_start:
            # a free joint's velocity: the centre of mass's in world axes, ω in the body's
            states = scenario.initial_states()
            for i, st in enumerate(states):
                rot = np.empty(9)
                mujoco.mju_quat2Mat(rot, st[3:7])
                self._data.qvel[6 * i:6 * i + 3] = st[7:10]
                self._data.qvel[6 * i + 3:6 * i + 6] = rot.reshape(3, 3).T @ st[10:13]
        mujoco.mj_forward(self._model, self._data)
        return self._dt

    # ------------------------------------------------------------------ drive
    def _load_chunk(self, i0: int, n: int = 1) -> None:
        """Precompute base displacement, velocity and step force for steps i0, i0 + 1, …

        At least ``n`` steps, at most ``_CHUNK`` (unless ``n`` is larger), and no more
        than the motion needs. Every value depends on its step index only, so where a
        chunk starts does not change the trajectory.
        """
        dt = self._dt
        size = max(n, min(_CHUNK, self._n_drive - i0))
        t = self.drive.grid(dt, size + 1, start=i0)
        if self._planar:
            self._u = self.drive.displacement(t)[:, 0]
            self._v = self.drive.velocity(t)[:, 0]
            # the force that takes the base from v(t) to v(t + dt) in one (semi-implicit) step
            self._f = self._mbase * np.diff(self._v) / dt
            # plain floats for the stepping loops (cheaper to index and assign than NumPy
            # scalars)
            self._ul, self._vl, self._fl = self._u.tolist(), self._v.tolist(), self._f.tolist()
        else:  # one column per slide joint; along z the force also holds the base's weight
            self._u = self.drive.displacement(t)[:, self._cols]
            self._v = self.drive.velocity(t)[:, self._cols]
            self._f = self._mbase * np.diff(self._v, axis=0) / dt + np.asarray(self._hold)
            self._ul = [tuple(r) for r in self._u.tolist()]
            self._vl = [tuple(r) for r in self._v.tolist()]
            self._fl = [tuple(r) for r in self._f.tolist()]
        self._chunk_start, self._chunk_end = i0, i0 + size

    def _drive_base(self, t: float, dt: float) -> None:
        i = int(round(t / self._dt))
        if not self._chunk_start <= i < self._chunk_end:
            self._load_chunk(i)
        j = i - self._chunk_start
        d = self._data
        jq, jv, na = self._jq, self._jv, self._na
        if self._planar:
            d.qpos[jq] = self._ul[j]
            d.qvel[jv] = self._vl[j]
            d.qfrc_applied[jv] = self._fl[j]
        else:
            d.qpos[jq:jq + na] = self._ul[j]
            d.qvel[jv:jv + na] = self._vl[j]
            d.qfrc_applied[jv:jv + na] = self._fl[j]

    def _advance_driven(self, t0: float, n: int, dt: float) -> None:
        # the same as _drive_base + _advance(1) per step, in one loop over local names
        i0 = int(round(t0 / self._dt))
        if not (0 <= self._chunk_start <= i0 and i0 + n <= self._chunk_end):
            self._load_chunk(i0, n)
        a = i0 - self._chunk_start
        m, d, step = self._model, self._data, self._step
        qpos, qvel, qfrc, jq, jv = d.qpos, d.qvel, d.qfrc_applied, self._jq, self._jv
        if not self._planar:
            self._drive_steps(self._ul[a:a + n], self._vl[a:a + n], self._fl[a:a + n])
            return
        for u, v, f in zip(self._ul[a:a + n], self._vl[a:a + n], self._fl[a:a + n],
                           strict=True):
            qpos[jq] = u
            qvel[jv] = v
            qfrc[jv] = f
            step(m, d)

    def _drive_steps(self, ul: list[Any], vl: list[Any], fl: list[Any]) -> None:
        """Steps of a base on slide joints other than x alone: (u, v, f) tuples, one per step."""
        m, d, step, na = self._model, self._data, self._step, self._na
        qpos = d.qpos[self._jq:self._jq + na]  # views of the slide joints' entries
        qvel = d.qvel[self._jv:self._jv + na]
        qfrc = d.qfrc_applied[self._jv:self._jv + na]
        for u, v, f in zip(ul, vl, fl, strict=True):
            qpos[:] = u
            qvel[:] = v
            qfrc[:] = f
            step(m, d)

    def _sample_free(self, out: np.ndarray, k: int) -> None:
        # mj_step(m, d, k) per sample, the block poses copied straight from qpos
        m, d, step, view = self._model, self._data, self._step, self._pose_view
        for row in out:
            step(m, d, k)
            row[...] = view

    def _sample_driven(self, out: np.ndarray, step0: int, k: int, dt: float) -> None:
        # _advance_driven for all the samples at once: one chunk lookup, one loop
        n = out.shape[0] * k
        if not (0 <= self._chunk_start <= step0 and step0 + n <= self._chunk_end):
            self._load_chunk(step0, n)
        a = step0 - self._chunk_start
        m, d, step, view = self._model, self._data, self._step, self._pose_view
        qpos, qvel, qfrc, jq, jv = d.qpos, d.qvel, d.qfrc_applied, self._jq, self._jv
        ul, vl, fl = self._ul, self._vl, self._fl
        if not self._planar:
            for row in out:
                self._drive_steps(ul[a:a + k], vl[a:a + k], fl[a:a + k])
                a += k
                row[...] = view
            return
        for row in out:
            b = a + k
            for u, v, f in zip(ul[a:b], vl[a:b], fl[a:b], strict=True):
                qpos[jq] = u
                qvel[jv] = v
                qfrc[jv] = f
                step(m, d)
            a = b
            row[...] = view

    def _fix_base(self) -> bool:
        m, d = self._model, self._data
        jv = slice(self._jv, self._jv + self._na)
        d.qvel[jv] = 0.0
        d.qfrc_applied[jv] = self._hold  # 0, and the base's weight along z
        # implicit damping ≫ mass/dt: any contact push is absorbed within the step
        m.dof_damping[jv] = 1.0e6 * self._mbase / self._dt
        return True

    # ------------------------------------------------------------------ step/read
    def _advance(self, n: int) -> None:
        self._step(self._model, self._data, n)

    def _read_poses(self) -> np.ndarray:
        np.copyto(self._poses, self._pose_view)
        return self._poses

    def _teardown(self) -> None:
        self._model = None
        self._data = None
        self._pose_view = None
        self._ul, self._vl, self._fl = [], [], []
