"""LMGC90 engine plugin: non-smooth contact dynamics through ``compas_lmgc90``.

LMGC90 (CNRS / Université de Montpellier, CeCILL licence) is a discrete element code of
the *non-smooth contact dynamics* family (Moreau–Jean): rigid bodies, unilateral
contact and Coulomb friction solved at the velocity level by nonlinear Gauss–Seidel
(NLGS) once per time step, impacts as velocity jumps. Its ``IQS_CLB`` law ("inelastic
quasi-shock, Coulomb") is a perfectly plastic impact with friction: Housner's
assumptions, with no contact stiffness or damping to calibrate. ``compas_lmgc90`` (MIT
licence) is the Block Research Group's binding; its wheel carries LMGC90's Fortran core.

Each block is a convex polyhedron (its x–z profile, chamfers included, extruded over
its depth) at its pose; a cylinder is a right prism on a regular ``cylinder_facets``-gon
inscribed in its circle, axis along body z, its density set so that its mass is the
cylinder's. A planar start at rest builds the blocks turned about y from
``initial_poses()``, as the planar benchmark always did; cylinders and 3D starts take
position and orientation from ``initial_states()``, and a moving start its velocities
(centre of inertia, world axes; the angular velocity turned into the principal frame
where LMGC90 keeps it) through LMGC90's exported ``put_vector_RBDY3``. The base is a box
whose top face is z = 0 and each fixed support one more body, all with their six
velocities driven. LMGC90 takes a driven velocity as a table fixed before
pre-processing, so the whole base velocity along each moving axis (x, y and z) is handed
over at build, every other component held at 0; the θ-method with θ = 1/2 then moves
the base by the trapezoidal rule of the exact velocities. Poses are read from each
body's centre of inertia and principal frame. The binding fixes gravity (9.81 m/s²),
one contact law for every pair, a restitution of 0 and the NLGS parameters; other
values are unsupported. Its face-to-face tolerance (2.56°, under which a tilted block
loses its contact) is reset through LMGC90's own exported setter, called via ctypes
after ``Solver()`` and before ``preprocess()``; a build without that symbol lists the
engine as unavailable. Creating a ``Solver`` resets LMGC90's Fortran state, so runs in
one process repeat to the bit.

Presets and knobs:

* ``accurate`` (the defaults): Δt 0.1 ms.
* ``fast``: Δt 1 ms.
* ``timestep``, ``theta`` (θ-method), ``alert`` (contact detection distance),
  ``f2f_tol`` (face-to-face tolerance), ``cylinder_facets`` (a cylinder's side faces).

Known limits: its impacts keep more energy than Housner's η, the more the larger the
amplitude, whatever the step, θ or contact law; stacks converge slowly on pulses; a
cylinder is a faceted prism with the prism's inertia (the binding takes a density only).

See :doc:`the engine's page </engines/lmgc90>` in the documentation for its measured
accuracy and cost.
"""

from __future__ import annotations

import ctypes
import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from rockbench.engines.base import Capabilities, Engine, install_hint
from rockbench.engines.drive import AXIS, BaseDrive
from rockbench.engines.settings import EngineSettings, KnobRole
from rockbench.errors import EngineUnavailable, UnsupportedScenario
from rockbench.geometry import Cylinder
from rockbench.scenarios import Scenario

__all__ = ["Lmgc90Engine", "Lmgc90Settings", "LMGC90_GRAVITY"]

#: gfortran's exported name of LMGC90's ``PRPRx.set_f2f_tol_PRPRx`` in the binding's module.
_F2F_SYMBOL = "__prprx_MOD_set_f2f_tol_prprx"
#: gfortran's exported name of LMGC90's ``RBDY3.put_vector_RBDY3`` (a body's velocities).
_PUT_VECTOR_SYMBOL = "__rbdy3_MOD_put_vector_rbdy3"
#: gfortran's exported name of LMGC90's ``PRPRx.set_size_factor_polyr_PRPRx``, and the factor
#: set for scenes with cylinders (LMGC90's default is 4).
_SIZE_FACTOR_SYMBOL = "__prprx_MOD_set_size_factor_polyr_prprx"
_SIZE_FACTOR = 32
#: LMGC90's inelastic quasi-shock law with Coulomb friction: a perfectly plastic impact.
#: (Its ``IQS_CLB_g0`` variant measures gaps from the initial ones: the lifted edge of a
#: tilted block then counts as closed and the block stays at its release tilt.)
_LAW = "IQS_CLB"
#: Gravity the binding imposes (``set_gravity`` in its Fortran wrapper), m/s² along −z.
LMGC90_GRAVITY = 9.81


def _solver_module() -> Any:
    """``compas_lmgc90.solver``, imported on first use (rule 2 of the engine contract)."""
    return Lmgc90Engine.library("compas_lmgc90.solver")


@dataclass(frozen=True)
class Lmgc90Settings(EngineSettings):
    """Knobs of the LMGC90 engine (defaults = the ``accurate`` preset).

    Parameters
    ----------
    timestep : float
        Time step in s (one contact detection and one NLGS solve per step).
    theta : float
        Parameter of LMGC90's θ-method, in [0.5, 1] (0.5, the LMGC90 default for
        rigid bodies; 1 changes B0's impact times by < 0.02 %).
    alert : float
        Contact detection distance in m: points of two facing faces farther apart
        than this carry no contact. It must exceed the gap under the lifted edge
        while that edge may come back within one step (0.2 m: B0's lifted edge at
        0.5 λ is 0.099 m up).
    f2f_tol : float
        Face-to-face tolerance of LMGC90's STO detection, on 1 − cos of the angle
        between two faces' normals: faces further from parallel get no contact at
        all. The binding's own 1e-3 (2.56°) loses the contact under any block
        tilted more than that (B0 at 0.5 λ falls through the ground); 0.5 (60°)
        keeps it up to overturning and changes nothing else measured.
    cylinder_facets : int
        Number of side faces of a :class:`~rockbench.geometry.Cylinder`'s polyhedron
        (even, ≥ 8): LMGC90 has no cylinder, so each is a right prism on the regular
        n-gon inscribed in its circle, a vertex at azimuth 0. Its mass is the
        cylinder's (the density is set on the prism's volume); its inertia, computed by
        LMGC90 from the prism, has the axial moment low by (1 − cos(2π/n))/3 (0.16 %
        at 64) of the disc's.
    """

    timestep: float = 1e-4
    theta: float = 0.5
    alert: float = 0.2
    f2f_tol: float = 0.5
    cylinder_facets: int = 64

    def __post_init__(self) -> None:
        if not (math.isfinite(self.timestep) and self.timestep > 0):
            raise ValueError(f"timestep must be finite and > 0, got {self.timestep!r}")
        if not 0.5 <= self.theta <= 1.0:
            raise ValueError(f"theta must be in [0.5, 1], got {self.theta!r}")
        if not (math.isfinite(self.alert) and self.alert > 0):
            raise ValueError(f"alert must be finite and > 0, got {self.alert!r}")
        if not 0.0 < self.f2f_tol <= 1.0:
            raise ValueError(f"f2f_tol must be in (0, 1], got {self.f2f_tol!r}")
        if not (isinstance(self.cylinder_facets, int) and self.cylinder_facets >= 8
                and self.cylinder_facets % 2 == 0):
            raise ValueError(
                f"cylinder_facets must be an even integer >= 8, got {self.cylinder_facets!r}")


class Lmgc90Engine(Engine):
    """Rocking blocks in LMGC90 (non-smooth contact dynamics) via compas_lmgc90."""

    name: ClassVar[str] = "lmgc90"
    capabilities: ClassVar[Capabilities] = Capabilities(
        dimensions=3, max_blocks=None, chamfer=True, assemblies=True, base_axes="xyz",
        cylinders=True, start3d=True, moving_start=True)
    Settings: ClassVar[type[EngineSettings]] = Lmgc90Settings
    presets: ClassVar[dict[str, dict[str, Any]]] = {"accurate": {}, "fast": {"timestep": 1e-3}}
    requires: ClassVar[tuple[str, ...]] = ("compas_lmgc90",)
    extra: ClassVar[str] = "lmgc90"
    knob_roles: ClassVar[dict[str, KnobRole]] = {"timestep": KnobRole.TIME_STEP}
    contact_model: ClassVar[str] = "non-smooth"
    known_failures: ClassVar[dict[str, str]] = {
        "free_rocking": "B2 from 0.5 lambda: 2nd and 3rd impacts 2.3 % and 2.2 % late at "
                        "the accurate step (0.1 ms; 0.05 ms alike): LMGC90's impact keeps "
                        "more energy than Housner's eta (effective 0.716 against 0.700)",
    }
    #: LMGC90 keeps one model per process in Fortran module state, but every new
    #: Solver resets it (compas_lmgc90 >= 0.1.11; tested): warm workers may be reused
    fresh_process: ClassVar[bool] = False

    def __init__(self) -> None:
        self._solver: Any = None
        self._step: Any = None
        self._m0 = np.zeros((0, 3, 3))
        self._poses = np.zeros((0, 7))
        self._first = 1  # index of the first block among LMGC90's bodies
        # the last state LMGC90 reported: every body's centre of inertia and frame
        self._coor: Any = ()
        self._frames: Any = ()
        #: Where the base ended (m along x), recorded at teardown.
        self.base_end = math.nan

    @classmethod
    def check_available(cls) -> None:
        """The binding and its compiled solver import, and export LMGC90's face-to-face
        tolerance setter."""
        super().check_available()
        cls.library("compas_lmgc90.solver")
        _f2f_tol_setter()

    @classmethod
    def version(cls) -> str:
        """Version of compas_lmgc90 (the binding; LMGC90's core is compiled into it)."""
        return str(cls.library("compas_lmgc90").__version__)

    # ------------------------------------------------------------------ hooks
    def _check_supported(self, scenario: Scenario) -> None:
        if not math.isclose(scenario.g, LMGC90_GRAVITY, rel_tol=1e-12):
            raise UnsupportedScenario(
                f"lmgc90: compas_lmgc90 fixes gravity at {LMGC90_GRAVITY} m/s², scenario has "
                f"g = {scenario.g:g}")
        c = scenario.contact
        if c.restitution != 0.0:
            raise UnsupportedScenario(
                "lmgc90: the IQS_CLB law is a perfectly plastic impact; scenario has "
                f"restitution {c.restitution:g}")
        if scenario.has_cylinders or scenario.moving_start:
            for name in (_SIZE_FACTOR_SYMBOL, _PUT_VECTOR_SYMBOL):
                try:
                    _symbol(name)
                except (OSError, AttributeError) as exc:
                    raise UnsupportedScenario(
                        f"lmgc90: this build of compas_lmgc90 does not export {name}, "
                        "which cylinders and moving starts need") from exc
        if c.block_friction != c.friction:
            raise UnsupportedScenario(
                "lmgc90: compas_lmgc90 gives every contact pair one law (one friction "
                "coefficient); scenario has a different interface friction")

    def _build(self, scenario: Scenario, settings: EngineSettings) -> float:
        assert isinstance(settings, Lmgc90Settings)  # resolve_settings made it one
        s = settings
        mod = _solver_module()
        dt = float(s.timestep)
        drive = self.drive
        geo = scenario.geometry
        blocks = scenario.blocks
        # wide scenes (not a column) need the blocks' spread along x too (geo.room)
        reach = max(0.5 * b.width for b in blocks) + geo.total_height + drive.travel + geo.room
        half = (max(1.0, 2.0 * reach), max(1.0, 2.0 * reach, max(b.depth for b in blocks)))
        thick = 0.5
        base = _box_polyhedron(half[0], half[1], thick, centre=(0.0, 0.0, -thick))

        bodies = [base]
        # the geometry's supports: driven bodies with the base's velocity, twice the
        # deepest block in depth
        depth = max(b.depth for b in blocks)
        supports = geo.supports
        for sup in supports:
            v, f = _prism(sup.array - sup.array.mean(axis=0), depth)
            c = sup.array.mean(axis=0)
            bodies.append({"vertices": (v + (c[0], 0.0, c[1])).tolist(), "faces": f})
        self._first = first = 1 + len(supports)
        rot0 = []
        # a planar start at rest of blocks and prisms builds the planar benchmark's bodies,
        # bit for bit; cylinders and 3D starts take their poses from initial_states()
        planar = scenario.planar_start and not scenario.moving_start and not scenario.has_cylinders
        states = scenario.initial_states()
        volumes = []
        if planar:
            for blk, (cx, cz, th) in zip(blocks, scenario.initial_poses(), strict=True):
                r = _rot_y(float(th))
                v, f = _prism(blk.profile(), 0.5 * blk.depth)
                bodies.append({"vertices": (v @ r.T + (cx, 0.0, cz)).tolist(), "faces": f})
                rot0.append(r)
                volumes.append(blk.volume)
        else:
            for blk, state in zip(blocks, states, strict=True):
                r = _rot_quaternion(state[3:7])
                if isinstance(blk, Cylinder):
                    v, f = _cylinder(blk.radius, blk.h, int(s.cylinder_facets))
                    volumes.append(_polyhedron_volume(v, f))
                else:
                    v, f = _prism(blk.profile(), 0.5 * blk.depth)
                    volumes.append(blk.volume)
                bodies.append({"vertices": (v @ r.T + state[:3]).tolist(), "faces": f})
                rot0.append(r)
        # each body's mass is the block's: its density over its polyhedron's volume (a
        # faceted cylinder's, below the cylinder's); the base's is irrelevant (driven)
        dens = [b.m / vol for b, vol in zip(blocks, volumes, strict=True)]
        densities = [dens[0]] * first + dens

        solver = mod.Solver(dt=dt, theta=float(s.theta), density=densities[0])
        self._solver = solver
        solver.geometry_from_v_f(bodies, density=densities)
        # each moving axis gets its velocity table, every other component is held at 0
        # (a motion along x alone hands LMGC90 the same calls as before y and z were applied)
        vel = {f"V{a}": _velocity_table(drive, scenario.duration, dt, axis=AXIS[a])
               for a in drive.axes}
        for body in range(first):
            for comp in ("Vy", "Vz", "Rx", "Ry", "Rz"):
                solver.apply_velocity(body, comp, vel.get(comp, 0.0))
            solver.apply_velocity(body, "Vx", vel.get("Vx", 0.0))
        _f2f_tol_setter()(ctypes.byref(ctypes.c_double(float(s.f2f_tol))))
        if scenario.has_cylinders:
            # a faceted rim gives STO many more contact points than a box's face: LMGC90's
            # array of them, 4 × its default size, overflows (a Fortran STOP)
            _symbol(_SIZE_FACTOR_SYMBOL)(ctypes.byref(ctypes.c_int(_SIZE_FACTOR)))
        solver.contact_law(_LAW, float(scenario.contact.friction), alert=float(s.alert))
        solver.preprocess()
        init = solver.lmgc90.get_initial_state()
        if scenario.moving_start:
            _set_velocities(first, states, init.init_body_frames)
        # the frame's rows are the principal axes (world components): the rotation since
        # the build is Fᵀ F0, applied to the block's initial orientation R0
        frame0 = np.reshape(init.init_body_frames[first:], (-1, 3, 3))
        self._m0 = frame0 @ np.array(rot0)
        self._coor, self._frames = init.init_bodies, init.init_body_frames
        self._step = solver.lmgc90.compute_one_step
        self._poses = np.zeros((len(blocks), 7))
        return dt

    def _drive_base(self, t: float, dt: float) -> None:
        # the base's velocity history is LMGC90's evolution table, set at build
        return None

    def _advance_driven(self, t0: float, n: int, dt: float) -> None:
        self._advance(n)

    def _fix_base(self) -> bool:
        # the evolution table holds the base still once the base motion has stopped
        return True

    def _advance(self, n: int) -> None:
        step = self._step
        for _ in range(n):
            last = step()
        self._coor, self._frames = last.bodies, last.body_frames

    def _sample_free(self, out: np.ndarray, k: int) -> None:
        # LMGC90 reports every state as Python lists: keep them, convert once per chunk
        step = self._step
        coor, frames = [], []
        for _ in range(out.shape[0]):
            for _ in range(k):
                last = step()
            coor.append(last.bodies)
            frames.append(last.body_frames)
        self._coor, self._frames = coor[-1], frames[-1]
        self._poses_into(out, np.asarray(coor), np.asarray(frames))

    def _sample_driven(self, out: np.ndarray, step0: int, k: int, dt: float) -> None:
        # the base follows its evolution table: driven steps are plain steps
        self._sample_free(out, k)

    def _read_poses(self) -> np.ndarray:
        out = self._poses
        self._poses_into(out[None], np.asarray(self._coor)[None], np.asarray(self._frames)[None])
        return out

    def _poses_into(self, out: np.ndarray, coor: np.ndarray, frames: np.ndarray) -> None:
        """Fill ``out`` (m, n_blocks, 7) from LMGC90's (m, n_bodies, 3) and (m, n_bodies, 9)."""
        first = self._first
        out[..., :3] = coor[:, first:]
        f = frames[:, first:].reshape(frames.shape[0], -1, 3, 3)
        out[..., 3:] = _quaternions(np.matmul(np.swapaxes(f, -1, -2), self._m0))

    def _teardown(self) -> None:
        if len(self._coor):
            self.base_end = float(self._coor[0][0])
        if self._solver is not None:
            self._solver.finalize()
        self._solver = self._step = None
        self._coor, self._frames = (), ()


def _f2f_tol_setter() -> Any:
    """LMGC90's ``set_f2f_tol_PRPRx``, exported by the binding's extension module.

    The binding sets the face-to-face tolerance of its STO detection to 1e-3 in
    ``Solver()`` and exposes no way to change it; LMGC90's own setter is an
    exported symbol of the same shared object (gfortran's name for the module
    procedure), called through ctypes between ``Solver()`` and ``preprocess()``.
    """
    binary = Lmgc90Engine.library("compas_lmgc90._lmgc90").__file__
    try:
        fn = getattr(ctypes.CDLL(binary), _F2F_SYMBOL)
    except (OSError, AttributeError) as exc:
        raise EngineUnavailable(
            f"engine 'lmgc90' is unavailable: {binary} does not export LMGC90's "
            f"{_F2F_SYMBOL} ({exc}), which the plugin needs to detect contact under a "
            f"tilted block; install it with: {install_hint(Lmgc90Engine.extra, 'compas_lmgc90')}"
        ) from exc
    fn.argtypes, fn.restype = [ctypes.POINTER(ctypes.c_double)], None
    return fn


def _symbol(name: str) -> Any:
    """An exported procedure of the binding's extension module (see :func:`_f2f_tol_setter`)."""
    binary = Lmgc90Engine.library("compas_lmgc90._lmgc90").__file__
    fn = getattr(ctypes.CDLL(binary), name)
    fn.restype = None
    return fn


def _set_velocities(first: int, states: np.ndarray, frames: Any) -> None:
    """Give each block its initial velocity (the centre of inertia's, world axes) and
    angular velocity (world axes, turned into the principal frame where LMGC90's RBDY3
    keeps it) as LMGC90's velocities at the beginning of the first step.

    The binding has no setter: ``put_vector_RBDY3('Vbeg_' and 'V____', body, v, 6)`` is
    an exported symbol of its extension module, called through ctypes after
    ``preprocess()`` (gfortran passes the string's length as a trailing size_t).
    """
    fn = _symbol(_PUT_VECTOR_SYMBOL)
    frames = np.reshape(np.asarray(frames, float), (-1, 3, 3))
    for i, st in enumerate(states):
        body = first + i
        v = np.empty(6)
        v[:3] = st[7:10]
        v[3:] = frames[body] @ st[10:13]  # rows: the principal axes in world components
        buf = (ctypes.c_double * 6)(*v.tolist())
        for name in (b"Vbeg_", b"V____"):
            fn(ctypes.c_char_p(name), ctypes.byref(ctypes.c_int(body + 1)), buf,
               ctypes.byref(ctypes.c_int(6)), ctypes.c_size_t(5))


def _rot_quaternion(q: np.ndarray) -> np.ndarray:
    """Rotation matrix of a unit quaternion (w, x, y, z)."""
    w, x, y, z = (float(c) for c in q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _cylinder(radius: float, half_height: float, n: int) -> tuple[np.ndarray, list[list[int]]]:
    """A cylinder of axis z as a right prism on a regular ``n``-gon inscribed in its circle
    (a vertex at azimuth 0 and, n even, at π): vertices and outward faces."""
    a = 2.0 * math.pi * np.arange(n) / n
    ring = np.column_stack([radius * np.cos(a), radius * np.sin(a)])
    v = np.array([(x, y, z) for x, y in ring for z in (-half_height, half_height)], float)
    faces = [[2 * j, 2 * ((j + 1) % n), 2 * ((j + 1) % n) + 1, 2 * j + 1] for j in range(n)]
    # each cap as a zigzag strip of triangles: every vertex is in at most four of them
    # (LMGC90's half-edge structure caps the faces around a vertex; a fan reaches n − 2)
    lo, hi = 1, n - 1
    strip = [[0, 1, n - 1]]
    while hi - lo > 1:
        strip.append([lo, lo + 1, hi])
        lo += 1
        if hi - lo > 1:
            strip.append([lo, hi - 1, hi])
            hi -= 1
    faces += [[2 * c for c in tri[::-1]] for tri in strip]
    faces += [[2 * c + 1 for c in tri] for tri in strip]
    return v, faces


def _polyhedron_volume(v: np.ndarray, faces: list[list[int]]) -> float:
    """Volume of a closed polyhedron with outward faces (divergence theorem, fans)."""
    vol = 0.0
    for f in faces:
        p0 = v[f[0]]
        for j in range(1, len(f) - 1):
            vol += float(np.dot(p0, np.cross(v[f[j]], v[f[j + 1]])))
    return vol / 6.0


def _rot_y(th: float) -> np.ndarray:
    """Rotation by ``th`` about +y (the top of an upright block moves toward +x)."""
    c, s = math.cos(th), math.sin(th)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _quaternions(r: np.ndarray) -> np.ndarray:
    """Unit quaternions (w, x, y, z) of rotation matrices, shape (..., 3, 3) -> (..., 4).

    Shepperd's method, vectorised: of the four algebraically equal forms, each
    matrix uses the one dividing by the largest of 4w², 4x², 4y², 4z².
    """
    r00, r01, r02 = r[..., 0, 0], r[..., 0, 1], r[..., 0, 2]
    r10, r11, r12 = r[..., 1, 0], r[..., 1, 1], r[..., 1, 2]
    r20, r21, r22 = r[..., 2, 0], r[..., 2, 1], r[..., 2, 2]
    big = np.stack([1.0 + r00 + r11 + r22, 1.0 + r00 - r11 - r22,
                    1.0 - r00 + r11 - r22, 1.0 - r00 - r11 + r22], axis=-1)
    s = 2.0 * np.sqrt(np.maximum(big, 1e-300))  # 4|q_i| for each form
    a, b, c = r21 - r12, r02 - r20, r10 - r01   # 4w·(x, y, z)
    d, e, f = r01 + r10, r02 + r20, r12 + r21   # 4xy, 4xz, 4yz
    forms = np.stack([
        np.stack([s[..., 0] / 4, a / s[..., 0], b / s[..., 0], c / s[..., 0]], axis=-1),
        np.stack([a / s[..., 1], s[..., 1] / 4, d / s[..., 1], e / s[..., 1]], axis=-1),
        np.stack([b / s[..., 2], d / s[..., 2], s[..., 2] / 4, f / s[..., 2]], axis=-1),
        np.stack([c / s[..., 3], e / s[..., 3], f / s[..., 3], s[..., 3] / 4], axis=-1),
    ], axis=-2)
    pick = np.argmax(big, axis=-1)[..., None, None]
    q = np.take_along_axis(forms, pick, axis=-2)[..., 0, :]
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def _prism(profile: np.ndarray, half_depth: float) -> tuple[np.ndarray, list[list[int]]]:
    """Vertices and outward faces of a convex x–z profile extruded over ±half_depth in y."""
    k = len(profile)
    v = np.array([(x, y, z) for x, z in profile for y in (-half_depth, half_depth)], float)
    faces = [[2 * j, 2 * ((j + 1) % k), 2 * ((j + 1) % k) + 1, 2 * j + 1] for j in range(k)]
    faces += [[2 * j for j in range(k)], [2 * j + 1 for j in range(k)]]
    centre = v.mean(axis=0)
    out = []
    for f in faces:
        p = v[f]
        n = np.cross(p[1] - p[0], p[2] - p[1])
        # LMGC90 wants every face wound outward: reverse those that face the centre
        out.append(f if n @ (p.mean(axis=0) - centre) > 0.0 else f[::-1])
    return v, out


def _box_polyhedron(hx: float, hy: float, hz: float,
                    centre: tuple[float, float, float]) -> dict[str, Any]:
    """A box of half-sizes (hx, hy, hz) as LMGC90 vertices and outward faces."""
    v, f = _prism(np.array([[-hx, -hz], [hx, -hz], [hx, hz], [-hx, hz]]), hy)
    return {"vertices": (v + centre).tolist(), "faces": f}


def _velocity_table(drive: BaseDrive, duration: float, dt: float, *, axis: int = 0
                    ) -> np.ndarray:
    """The base velocity along one axis as an LMGC90 evolution table, shape (2, n): times,
    values.

    The exact u̇_g along ``axis`` (0, 1, 2: x, y, z) at every step time up to when the
    base stops (``drive.stop``), then 0 until past the end of the run (``duration``;
    LMGC90 interpolates linearly between rows). ``drive`` must move.
    """
    t_end = drive.stop
    n = int(math.ceil(t_end / dt - 1e-9)) + 1
    t = drive.grid(dt, n + 1)
    v = drive.velocity(t)[:, axis]
    v[t > t_end + 1e-12] = 0.0
    tail = max(duration, t[-1]) + 1.0
    return np.vstack([np.append(t, tail), np.append(v, 0.0)])
