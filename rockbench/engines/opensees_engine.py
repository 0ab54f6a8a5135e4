"""OpenSees engine plugin (OpenSeesPy): rigid blocks on compression-only interface springs.

The structural engineer's model of a rocking block, in OpenSees's planar ``basic``
model (``-ndm 2 -ndf 3``), whose (X, Y) plane is our (x, z) plane; OpenSees's rotation
is counter-clockwise positive, so θ = −r_z. Each block is a node at its centroid with
the block's mass and inertia, joined to massless interface nodes by stiff
``elasticBeamColumn`` elements with a ``Corotational`` transformation (exact rigid-body
kinematics at large rotations). Each interface that exists at rest (the base, and every
joint between blocks or with a fixed support) carries ``springs`` contact points
between its pivots; at each, a ``flatSliderBearing`` joins the two sides, with an
elastic no-tension spring normal to the interface and Coulomb friction along it. The
interface's stiffness is K = M (2π ``contact_frequency``)² for the mass M it carries.
Impacts lose energy in dashpots (ζ = ``damping_ratio``) that act only beyond a
compression ``damping_onset`` · g/ω_c², so that a pivot lifts off freely. A column of
one or two blocks (single blocks, the paper's stack, parapets) has contact nodes that
turn with the blocks; any other geometry (taller drum columns, walls, arches) has
fixed-orientation joints and starts from a static gravity analysis. The base motion
(along x only) is a uniform excitation: the base nodes are fixed, every block gets the
inertial load −m ü_g(t) and the reported
positions add u_g(t). Newmark (or HHT, generalized-α) integration, Newton–Raphson with
Krylov–Newton and fixed-iteration fallbacks (counted in ``unconverged_steps``).

Presets and knobs:

* ``accurate`` (the defaults): 2 points per interface, f_c = 1 kHz, ζ = 1.6, onset 2.5,
  Δt 0.05 ms.
* ``fast``: f_c = 200 Hz, Δt 0.5 ms.
* ``winkler``: the literature's bed of 10 points per interface (not calibrated to
  Housner's η).
* ``rockingbc``: OpenSees's ``RockingBC`` macroelement for a single block (``element``).

Known limits: the springs are laid on the joints at rest, so bodies that come into
contact later pass through each other (the run stops as ``unstable`` when a pair the
engine names, :meth:`OpenseesEngine.unmodelled_pairs`, overlaps), and large sliding
is not followed; heavy drum columns can fail the slider's friction iteration. OpenSees
keeps one global model per process (``wipe()`` at every build); OpenSeesPy is free for
research, education and internal use only.

See :doc:`the engine's page </engines/opensees>` in the documentation for its
calibration, measured accuracy and cost.
"""

from __future__ import annotations

import atexit
import ctypes
import importlib.util
import math
import os
import re
import sys
from collections.abc import Iterator
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass, fields
from typing import Any, ClassVar, Literal

import numpy as np

from rockbench.engines.base import Capabilities, Engine
from rockbench.engines.settings import EngineSettings, KnobRole
from rockbench.errors import UnsupportedScenario
from rockbench.geometry import Column
from rockbench.scenarios import Scenario

__all__ = ["OpenseesEngine", "OpenseesSettings"]

#: Import name of the OpenSeesPy interpreter module.
_MODULE = "openseespy.opensees"
#: Stiffness fraction of the contact dashpots' gating springs (see the engine's page).
_EPS_DAMP = 1e-3
#: The line OpenSees writes to the C stderr when the interpreter exits.
_EXIT_LINE = re.compile(rb"Process \d+ Terminating\n")
_exit_filter_registered = False


def _drop_exit_line(read_fd: int, write_fd: int) -> None:
    """Copy ``read_fd`` to ``write_fd`` until EOF, without OpenSees's exit line."""
    pending = b""
    while chunk := os.read(read_fd, 65536):
        lines = (pending + chunk).splitlines(keepends=True)
        # hold back an unfinished last line only while it may become the exit line
        last = lines[-1] if lines else b""
        pending = last if not last.endswith(b"\n") and b"Process ".startswith(
            last[:8]) else b""
        for line in lines[:-1] if pending else lines:
            if not _EXIT_LINE.fullmatch(line):
                os.write(write_fd, line)
    if pending:
        os.write(write_fd, pending)


def _filter_exit_stderr() -> None:
    """At interpreter exit, route fd 2 through a child that drops OpenSees's exit line.

    OpenSeesPy's exit hook (``Py_AtExit``) deletes its interpreter, whose
    destructor writes "Process 0 Terminating" after Python has released
    ``sys.stderr``, so the line reaches the C stderr whatever Python does with
    its own streams (``logFile -noEcho`` and ``wipe()`` do not stop it). This
    runs in Python's exit phase: fd 2 becomes a pipe to a forked child that
    copies everything to the original stderr except that one line, and exits
    when this process has exited (end of the pipe). Nothing else is lost.
    """
    if not hasattr(os, "fork"):
        return
    try:
        r, w = os.pipe()
        pid = os.fork()
    except OSError:  # no pipe or process to spare: the line stays
        return
    if pid == 0:  # the child: copy, then leave without Python's exit machinery
        code = 0
        try:
            os.close(w)
            _drop_exit_line(r, 2)
        except BaseException:  # noqa: BLE001 - a child that fails must still exit
            code = 1
        finally:
            os._exit(code)
    os.close(r)
    sys.stderr.flush()
    os.dup2(w, 2)
    os.close(w)


def _register_exit_filter() -> None:
    """Register :func:`_filter_exit_stderr` once, when OpenSeesPy is first imported."""
    global _exit_filter_registered
    if not _exit_filter_registered:
        _exit_filter_registered = True
        atexit.register(_filter_exit_stderr)


@contextmanager
def _c_stdout_muted() -> Iterator[None]:
    """Send the C stdout to /dev/null meanwhile (RockingBC prints its state changes there)."""
    sys.stdout.flush()
    saved, null = os.dup(1), os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 1)
        yield
    finally:
        ctypes.CDLL(None).fflush(None)  # what the element left in stdio's buffer goes too
        os.dup2(saved, 1)
        os.close(saved)
        os.close(null)


def _preload_bundled_blas() -> None:
    """Load the BLAS that the Linux wheel bundles but does not find (OpenSeesPyDoc #319)."""
    try:
        spec = importlib.util.find_spec("openseespylinux")
    except (ImportError, ValueError):
        return
    if spec is None or not spec.origin:
        return
    path = os.path.join(os.path.dirname(spec.origin), "lib", "libblas.so.3")
    if os.path.exists(path):
        try:
            ctypes.CDLL(path, mode=ctypes.RTLD_GLOBAL)
        except OSError:  # the import then fails and says why
            pass


#: Knobs of the interface-spring model only (``element = "springs"``).
_SPRING_KNOBS = frozenset({"springs", "contact_frequency", "damping_ratio", "damping_onset",
                           "body_stiffness", "tolerance", "iterations"})
#: Knobs of the RockingBC model only (``element = "rockingbc"``).
_ROCKINGBC_KNOBS = frozenset({"rockingbc_strain", "rockingbc_segments", "rockingbc_damping"})
#: Newton test of the RockingBC model: relative unbalance, iterations (as in its examples).
_RBC_TEST = ("RelativeNormUnbalance", 1e-10, 100)


@dataclass(frozen=True)
class OpenseesSettings(EngineSettings):
    """Knobs of the opensees engine (defaults = the ``accurate`` preset).

    Presets: ``accurate`` (the defaults), ``fast``, ``winkler`` and
    ``rockingbc`` (the RockingBC element, see ``element``; all in
    :attr:`OpenseesEngine.presets`).

    Parameters
    ----------
    timestep : float
        Integration step (s); best chosen to divide the output interval.
    springs : int
        Contact points per interface (≥ 2; the literature asks for ≥ 10 to
        resolve the contact pressure under a rocking block).
    contact_frequency : float
        Vertical frequency f_c (Hz) of each interface under the mass it
        carries: K = M (2π f_c)². Higher is closer to a rigid contact (static
        settlement g/(2π f_c)²) and needs a smaller step (≳ 20 steps per
        contact period).
    damping_ratio : float
        ζ of each interface's vertical mode given by the contact dashpots
        (β = 2ζ/ω_c): the knob that sets the energy an impact removes.
        Calibrated against Housner's η (see the engine's documentation page).
    damping_onset : float
        Compression beyond which a point's dashpot acts, as a multiple of the
        static settlement g/ω_c² (0: as soon as the point is in contact). Above
        the compression of a pivot under the weight it carries, a pivot lifts
        off without its dashpot holding it back (see the engine's page).
    body_stiffness : float
        Stiffness of the beams that make a block rigid, as a multiple of the
        interface stiffness they connect to.
    integrator : {"newmark", "hht", "generalized-alpha"}
        Newmark average acceleration, Hilber–Hughes–Taylor with ``alpha``, or the
        generalized-α method (Chung & Hulbert) with spectral radius ``rho_inf``.
    alpha : float
        HHT α in [2/3, 1] (1: no numerical damping, the same as Newmark).
    rho_inf : float
        Generalized-α spectral radius at infinite frequency, in [0, 1] (1: no
        numerical damping; 0: modes far above 1/Δt are removed within a step).
    tolerance : float
        Newton convergence: norm of the displacement increment as a fraction of
        the static settlement g/ω_c² (a contact force within that fraction of
        the weight it carries).
    iterations : int
        Newton iterations per step before the fallbacks are tried.
    element : {"springs", "rockingbc"}
        ``springs``: the interface-spring model above (all knobs up to
        ``iterations``). ``rockingbc``: one ``RockingBC`` macroelement
        (Avgenakis & Psycharis 2020, EESD 49(11)) from the base to the
        centroid of a single block, which carries the block's mass and
        inertia. The element is a deformable body of width 2 × pivot
        half-width and the block's depth whose base is a no-tension elastic
        half-plane interface discretised in ``rockingbc_segments`` intervals;
        it uplifts and impacts without springs or dashpots, sliding with the
        scenario's μ (ν = 0, an elastic material). Its impacts lose energy
        through Rayleigh damping only. A static gravity stage and, for a
        tilted start, a pushover of the centroid's rotation to θ0 precede
        the dynamic run (Newton, relative unbalance 1e-10, ≤ 100 iterations).
        Stacks, frictionless bases and restitution > 0 are unsupported; the
        spring knobs must keep their defaults (and the ``rockingbc_*`` knobs
        theirs with ``springs``). Preset ``rockingbc``: Δt = 10 µs, at which
        the result no longer depends on the step. Measured (OpenSees 3.7.1,
        defaults below): B0 from 0.5 λ (θ0 = 0.099 rad) stays within
        1.8e-3 λ of Housner over 0.3 s, 3.2e-3 λ over 0.4 s and 0.011 λ up
        to its first impact, but its first two impacts are −0.97 % and
        +2.1 % off and it is 0.17 λ off by 3.4 s. B2 from 0.1 λ (0.046 rad)
        stays within 1.8e-3 λ up to its first impact (−0.9 %); from 0.5 λ
        (0.23 rad) it is 0.058 λ off there (first impact 5.3 % early, the
        same with ε0 ten times smaller or no sliding): the element departs
        from Housner as the rotation grows. Cost at 10 µs: 34 µs of CPU per
        step on B0 (44 on B2), about 700 s per 20 s case (the springs'
        ``accurate``: 15–25 s). Δt = 0.1 ms gives the same to 0.006 λ and
        0.1 % in impact time on B0 over 3.4 s at a seventh of the cost.
        Energy per impact comes from the Rayleigh damping, not calibrated
        against Housner's η.
    rockingbc_strain : float
        Self-weight strain ε0 at the base that sets the body's stiffness:
        E = m g / (B w ε0) (B: pivot width, w: depth). Smaller is closer to a
        rigid block but harder for Newton (ε0 = 5e-7 on B0 at Δt = 0.1 ms
        did not converge; on B2 at 10 µs it did, with the same result).
    rockingbc_segments : int
        Nw, intervals of the element's base interface.
    rockingbc_damping : float
        ζ of the model's first (elastic) mode after gravity, given as
        stiffness-proportional Rayleigh damping on the current tangent,
        β = 2ζ/ω_1.
    """

    timestep: float = 5e-5
    springs: int = 2
    contact_frequency: float = 1000.0
    damping_ratio: float = 1.6
    damping_onset: float = 2.5
    body_stiffness: float = 1e4
    integrator: Literal["newmark", "hht", "generalized-alpha"] = "newmark"
    alpha: float = 1.0
    rho_inf: float = 1.0
    tolerance: float = 1e-4
    iterations: int = 25
    element: Literal["springs", "rockingbc"] = "springs"
    rockingbc_strain: float = 5e-6
    rockingbc_segments: int = 15
    rockingbc_damping: float = 0.05

    def __post_init__(self) -> None:
        for name in ("timestep", "contact_frequency", "body_stiffness", "tolerance"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v!r}")
        if not (math.isfinite(self.damping_ratio) and self.damping_ratio >= 0):
            raise ValueError(f"damping_ratio must be finite and >= 0, got {self.damping_ratio!r}")
        if not (math.isfinite(self.damping_onset) and self.damping_onset >= 0):
            raise ValueError(f"damping_onset must be finite and >= 0, got {self.damping_onset!r}")
        if self.springs < 2:
            raise ValueError(f"springs must be >= 2, got {self.springs!r}")
        if self.iterations < 1:
            raise ValueError(f"iterations must be >= 1, got {self.iterations!r}")
        if not (2.0 / 3.0 <= self.alpha <= 1.0):
            raise ValueError(f"alpha must be in [2/3, 1], got {self.alpha!r}")
        if not (0.0 <= self.rho_inf <= 1.0):
            raise ValueError(f"rho_inf must be in [0, 1], got {self.rho_inf!r}")
        if not (math.isfinite(self.rockingbc_strain) and 0 < self.rockingbc_strain < 1e-2):
            raise ValueError(f"rockingbc_strain must be in (0, 0.01), got "
                             f"{self.rockingbc_strain!r}")
        if self.rockingbc_segments < 2:
            raise ValueError(f"rockingbc_segments must be >= 2, got {self.rockingbc_segments!r}")
        if not (math.isfinite(self.rockingbc_damping) and self.rockingbc_damping >= 0):
            raise ValueError(f"rockingbc_damping must be finite and >= 0, got "
                             f"{self.rockingbc_damping!r}")
        # a knob of the other model would be silently ignored: refuse it instead
        unused = _SPRING_KNOBS if self.element == "rockingbc" else _ROCKINGBC_KNOBS
        changed = [f.name for f in fields(self)
                   if f.name in unused and getattr(self, f.name) != f.default]
        if changed:
            raise ValueError(f"element={self.element!r} does not use {', '.join(changed)}")


#: The most blocks the column model is built for: on taller drum columns its turning
#: contact nodes fail the sliders' friction iteration (a 5-drum column on the tilting
#: table: NaN at 11.35 s), while the fixed-orientation model holds (onset +2.3 %).
COLUMN_MODEL_BLOCKS = 2


def _column_model(scenario: Scenario) -> Column | None:
    """The scenario's geometry as a column where the column model is built, else None."""
    column = scenario.geometry.column
    if column is None or scenario.n_blocks > COLUMN_MODEL_BLOCKS:
        return None
    return column


def _column(scenario: Scenario) -> Column:
    """The scenario's geometry as a column (the column model is built only for one)."""
    column = _column_model(scenario)
    if column is None:  # pragma: no cover - the callers are the column model's
        raise UnsupportedScenario("opensees: the column model needs blocks each on the one below")
    return column


def _base_z(column: Column) -> list[float]:
    """Height of each block's bottom face above the base, bottom first (m).

    A running sum of the heights in Python floats (the contact heights of the
    column model, unchanged from the stack's).
    """
    out, z = [], 0.0
    for b in column.blocks:
        out.append(z)
        z += b.height
    return out


@dataclass(frozen=True)
class _Interface:
    """One interface: contact points x (m) at height z (m) and spring stiffnesses k (N/m)."""

    x: np.ndarray
    z: float
    k: np.ndarray


@dataclass(frozen=True)
class _Joint:
    """One interface of an assembly: bodies a (a block) and b (a block, or −1: fixed),
    contact points (n, 2) in m, unit normal out of a, spring stiffnesses k (N/m)."""

    a: int
    b: int
    points: np.ndarray
    normal: np.ndarray
    k: np.ndarray


class OpenseesEngine(Engine):
    """Rigid blocks on compression-only friction springs in OpenSees (planar, implicit)."""

    name: ClassVar[str] = "opensees"
    capabilities: ClassVar[Capabilities] = Capabilities(
        dimensions=2, max_blocks=None, chamfer=True, assemblies=True)
    Settings: ClassVar[type[EngineSettings]] = OpenseesSettings
    presets: ClassVar[dict[str, dict[str, Any]]] = {
        "accurate": {},
        # its calibration: the engine's page; reproduce with `rockbench calibrate opensees`
        "fast": {"timestep": 5e-4, "contact_frequency": 200.0},
        # the literature's Winkler bed: 10 points per interface (not Housner-calibrated)
        "winkler": {"timestep": 1e-4, "springs": 10, "contact_frequency": 500.0,
                    "damping_ratio": 3.6, "damping_onset": 0.0},
        # the RockingBC macroelement at the step it needs (figures in the Settings docstring)
        "rockingbc": {"element": "rockingbc", "timestep": 1e-5},
    }
    extra: ClassVar[str] = "opensees"
    knob_roles: ClassVar[dict[str, KnobRole]] = {
        "timestep": KnobRole.TIME_STEP, "iterations": KnobRole.ITERATIONS,
        "tolerance": KnobRole.TOLERANCE, "contact_frequency": KnobRole.CONTACT_STIFFNESS,
        "springs": KnobRole.CONTACT_POINTS}
    contact_model: ClassVar[str] = "penalty"
    requires: ClassVar[tuple[str, ...]] = (_MODULE,)
    known_failures: ClassVar[dict[str, str]] = {}

    def __init__(self) -> None:
        self._ops: Any = None
        self._centroids: list[int] = []
        self._x0 = np.zeros(0)
        self._z0 = np.zeros(0)
        self._a0: np.ndarray | None = None
        self._u = np.zeros(1)
        self._step = 0
        self._dt = 0.0
        self._poses = np.zeros((0, 7))
        self._algorithm: tuple[Any, ...] = ("Newton",)
        self._test: tuple[Any, ...] = ()
        self._failed = False
        self._mute = False
        #: Where the base ended (m) at teardown, for the benchmarks and tests.
        self.base_end = math.nan
        #: Steps of the last run taken with fixed Newton iterations (see _retry_step).
        self.unconverged_steps = 0

    # ------------------------------------------------------------------ library
    @classmethod
    def library(cls, module: str) -> Any:
        """Import OpenSeesPy (rule 2), loading the BLAS its Linux wheel bundles first.

        Its exit message is filtered out of stderr (:func:`_filter_exit_stderr`).
        """
        _preload_bundled_blas()
        lib = super().library(module)
        _register_exit_filter()
        return lib

    @classmethod
    def version(cls) -> str:
        """Version of OpenSees (as reported by the interpreter)."""
        return str(cls.library(_MODULE).version())

    # ------------------------------------------------------------------ hooks
    def _check_supported(self, scenario: Scenario) -> None:
        """Refuse restitution > 0 and columns whose blocks do not overlap.

        Impacts follow from the springs and dashpots; a coefficient of
        restitution cannot be honoured, so it is refused rather than ignored.
        """
        if scenario.contact.restitution > 0.0:
            raise UnsupportedScenario(
                "opensees has no restitution coefficient (impacts follow from the interface "
                "springs and their damping); use restitution = 0"
            )
        if _column_model(scenario) is None:  # its interfaces are the geometry's at rest
            return
        for i in range(1, scenario.n_blocks):
            lo, hi = self._span(scenario, i)
            if hi <= lo:
                raise UnsupportedScenario(f"blocks {i} and {i + 1} do not overlap")

    @staticmethod
    def _span(scenario: Scenario, i: int) -> tuple[float, float]:
        """x range of interface ``i`` (0: the base), between the facing pivots."""
        column = _column(scenario)
        blocks, off = column.blocks, column.offsets
        up = (off[i] - blocks[i].pivot_half_width, off[i] + blocks[i].pivot_half_width)
        if i == 0:
            return up
        lo = (off[i - 1] - blocks[i - 1].pivot_half_width,
              off[i - 1] + blocks[i - 1].pivot_half_width)
        return max(up[0], lo[0]), min(up[1], lo[1])

    @staticmethod
    def interfaces(scenario: Scenario, s: OpenseesSettings) -> list[_Interface]:
        """Contact points and spring stiffnesses of every interface, base first."""
        omega = 2.0 * math.pi * s.contact_frequency
        masses = np.array([b.m for b in scenario.blocks])
        base_z = _base_z(_column(scenario))
        out = []
        for i in range(scenario.n_blocks):
            lo, hi = OpenseesEngine._span(scenario, i)
            x = np.linspace(lo, hi, s.springs)
            trib = np.full(s.springs, 1.0)
            trib[[0, -1]] = 0.5
            stiffness = float(masses[i:].sum()) * omega * omega
            out.append(_Interface(x=x, z=float(base_z[i]), k=stiffness * trib / trib.sum()))
        return out

    def _build(self, scenario: Scenario, settings: EngineSettings) -> float:
        ops = self.library(_MODULE)
        assert isinstance(settings, OpenseesSettings)  # resolve_settings made it one
        s = settings
        dt = float(s.timestep)
        ops.wipe()
        ops.logFile(os.devnull, "-noEcho")  # convergence retries are expected, not news
        if s.element == "rockingbc":
            return self._build_rockingbc(ops, scenario, s)
        if _column_model(scenario) is None:
            return self._build_assembly(ops, scenario, s)
        ops.model("basic", "-ndm", 2, "-ndf", 3)
        ops.geomTransf("Corotational", 1)
        frictionless = scenario.contact.friction == 0.0
        if not frictionless:
            ops.frictionModel("Coulomb", 1, float(scenario.contact.friction))
        ops.uniaxialMaterial("Elastic", 1, 0.0)  # no moment at a contact point
        blocks, g = scenario.blocks, scenario.g
        centres = scenario.geometry.centroids
        ifaces = self.interfaces(scenario, s)
        omega = 2.0 * math.pi * s.contact_frequency
        onset = s.damping_onset * g / omega**2
        tags = iter(range(2, 10**9))
        ops.timeSeries("Constant", 1)
        ops.pattern("Plain", 1, 1)
        cnodes = []
        for blk, (cx, cz) in zip(blocks, centres, strict=True):
            tag = next(tags)
            ops.node(tag, float(cx), float(cz))
            ops.mass(tag, blk.m, blk.m, float(blk.inertia[1]))
            ops.load(tag, 0.0, -blk.m * g, 0.0)
            cnodes.append(tag)
        # node tag -> (x, z) of every block node, for the initial displacements
        block_nodes: list[list[tuple[int, float, float]]] = [
            [(c, float(x), float(z))] for c, (x, z) in zip(cnodes, centres, strict=True)]
        for i, face in enumerate(ifaces):
            dampers = []
            k_face = float(face.k.sum())
            for x, k in zip(face.x.tolist(), face.k.tolist(), strict=True):
                lower, upper = next(tags), next(tags)
                ops.node(lower, x, face.z)
                ops.node(upper, x, face.z)
                if i == 0:
                    ops.fix(lower, 1, 1, 1)
                sides = ((upper, i),) if i == 0 else ((upper, i), (lower, i - 1))
                for node, b in sides:
                    self._beam(ops, next(tags), cnodes[b], node, centres[b], (x, face.z),
                               s.body_stiffness * k_face)
                    block_nodes[b].append((node, x, face.z))
                mat, mat_d = next(tags), next(tags)
                ops.uniaxialMaterial("ENT", mat, k)
                if onset > 0:  # no tangent (so no dashpot) until the onset compression
                    ops.uniaxialMaterial("ElasticBilin", mat_d, 0.0, 0.0, 1.0, 0.0,
                                         _EPS_DAMP * k, -onset)
                else:
                    ops.uniaxialMaterial("ENT", mat_d, _EPS_DAMP * k)
                if frictionless:  # (OpenSees exits the process on a zero friction model)
                    ops.element("zeroLength", next(tags), lower, upper, "-mat", mat, "-dir", 2)
                else:  # local x along +Y (normal), local y along −X (shear)
                    ops.element("flatSliderBearing", next(tags), lower, upper, 1, k, "-P", mat,
                                "-Mz", 1, "-orient", 0.0, 1.0, 0.0, -1.0, 0.0, 0.0)
                tag = next(tags)
                ops.element("zeroLength", tag, lower, upper, "-mat", mat_d, "-dir", 2,
                            "-doRayleigh", 1)
                dampers.append(tag)
            beta = 2.0 * s.damping_ratio / omega
            if beta > 0:
                ops.region(i + 1, "-ele", *dampers, "-rayleigh", 0.0, beta / _EPS_DAMP, 0.0, 0.0)
        self._test = ("NormDispIncr", float(s.tolerance) * g / omega**2, int(s.iterations))
        # an upright column whose blocks are not all centred loads its interfaces off
        # their middles, where a uniform settlement is not in equilibrium: settled
        # statically instead, as any other geometry
        settled = True
        if scenario.theta0 == 0.0 and not _column(scenario).centred:
            settled = self._settle(ops)
        else:
            self._set_initial_state(ops, scenario, block_nodes, ifaces)
        return self._finish_build(ops, s, scenario, cnodes, dt, settled)

    def unmodelled_pairs(self, scenario: Scenario) -> tuple[tuple[int, int], ...]:
        """Every pair of a block and another body that shares no joint at rest: the
        model has no contact between them (module docstring). Bodies are numbered
        blocks, then supports, then the base, as in :class:`~rockbench.geometry.Interface`."""
        geo = scenario.geometry
        joined = {(f.a, f.b) for f in geo.interfaces}
        nb, n_bodies = geo.n_bodies, geo.all_bodies
        return tuple((a, b) for a in range(nb) for b in range(a + 1, n_bodies)
                     if (a, b) not in joined)

    @staticmethod
    def assembly_interfaces(scenario: Scenario, s: OpenseesSettings) -> list[_Joint]:
        """Contact points, frame and spring stiffnesses of every interface of an assembly at rest.

        The interfaces are the geometry's (face-to-face contacts at rest,
        :attr:`~rockbench.geometry.Geometry.interfaces`).
        Each carries K = M ω_c² as a stack's does, M the mass it carries: on a
        bed joint the upper body and every block whose centroid is higher (a
        load estimate that errs on the heavy side: it only stiffens the
        contact), on a joint within 45° of vertical (a head joint) the lighter
        block alone, as in :func:`rockbench.engines.dem2d_engine.assembly_contacts`.
        """
        geo = scenario.geometry
        nb = geo.n_bodies
        cents = geo.centroids
        masses = geo.masses
        omega = 2.0 * math.pi * s.contact_frequency
        trib = np.full(s.springs, 1.0)
        trib[[0, -1]] = 0.5
        out = []
        for f in geo.interfaces:
            on = [k for k in (f.a, f.b) if k < nb]
            if abs(f.normal[1]) < math.sqrt(0.5):
                carried = float(min(masses[k] for k in on))
            else:  # the normal points from a into b
                up = f.a if f.b >= nb or f.normal[1] < 0 else f.b
                carried = float(masses[cents[:, 1] > cents[up, 1]].sum() + masses[up])
            x = np.linspace(f.p0, f.p1, s.springs)
            out.append(_Joint(a=f.a, b=f.b if f.b < nb else -1, points=x,
                              normal=np.array(f.normal, float),
                              k=carried * omega * omega * trib / trib.sum()))
        return out

    def _build_assembly(self, ops: Any, scenario: Scenario, s: OpenseesSettings) -> float:
        """A geometry that is not a column: the column's model on every interface at rest
        (module docstring).

        Each interface point is a pair of nodes, one on each body (a fixed node
        on a support or the base), joined by the contact elements in the
        interface's own frame (local x along the normal out of body ``a``).
        Gravity is applied by a static analysis first (exact equilibrium on
        the springs, nothing rings at t = 0).
        """
        dt = float(s.timestep)
        ops.model("basic", "-ndm", 2, "-ndf", 3)
        ops.geomTransf("Corotational", 1)
        mu = {False: float(scenario.contact.friction), True: float(scenario.contact.block_friction)}
        friction_tag = {False: 1, True: 2}  # block on a support or the base / on a block
        for between_blocks, value in mu.items():
            if value > 0.0:  # (OpenSees exits the process on a zero friction model)
                ops.frictionModel("Coulomb", friction_tag[between_blocks], value)
        ops.uniaxialMaterial("Elastic", 1, 0.0)  # no moment at a contact point
        g = scenario.g
        centres = scenario.geometry.centroids
        omega = 2.0 * math.pi * s.contact_frequency
        onset = s.damping_onset * g / omega**2
        beta = 2.0 * s.damping_ratio / omega
        tags = iter(range(2, 10**9))
        ops.timeSeries("Constant", 1)
        ops.pattern("Plain", 1, 1)
        cnodes = []
        for blk, (cx, cz) in zip(scenario.blocks, centres, strict=True):
            tag = next(tags)
            ops.node(tag, float(cx), float(cz))
            ops.mass(tag, blk.m, blk.m, float(blk.inertia[1]))
            ops.load(tag, 0.0, -blk.m * g, 0.0)
            cnodes.append(tag)
        for region, joint in enumerate(self.assembly_interfaces(scenario, s), 1):
            nx, nz = (float(v) for v in joint.normal)
            k_face = float(joint.k.sum())
            between_blocks = joint.b >= 0
            dampers = []
            for (px, pz), k in zip(joint.points.tolist(), joint.k.tolist(), strict=True):
                side_a, side_b = next(tags), next(tags)
                ops.node(side_a, px, pz)
                ops.node(side_b, px, pz)
                # the contact nodes do not turn: the slider adds a P-Δ term −V r_i to its
                # normal force, whose friction iteration failed on a tilting 5-drum
                # column at 0.5 rad; the beams are pinned at them instead
                ops.fix(side_a, 0, 0, 1)
                self._beam(ops, next(tags), cnodes[joint.a], side_a, centres[joint.a],
                           (px, pz), s.body_stiffness * k_face, pinned=True)
                if between_blocks:
                    ops.fix(side_b, 0, 0, 1)
                    self._beam(ops, next(tags), cnodes[joint.b], side_b, centres[joint.b],
                               (px, pz), s.body_stiffness * k_face, pinned=True)
                else:  # a support or the base: it moves with the base, i.e. fixed here
                    ops.fix(side_b, 1, 1, 1)
                mat, mat_d = next(tags), next(tags)
                ops.uniaxialMaterial("ENT", mat, k)
                if onset > 0:
                    ops.uniaxialMaterial("ElasticBilin", mat_d, 0.0, 0.0, 1.0, 0.0,
                                         _EPS_DAMP * k, -onset)
                else:
                    ops.uniaxialMaterial("ENT", mat_d, _EPS_DAMP * k)
                # local x along the normal (out of body a), local y along the tangent
                frame = ("-orient", nx, nz, 0.0, -nz, nx, 0.0)
                if mu[between_blocks] == 0.0:
                    ops.element("zeroLength", next(tags), side_a, side_b, "-mat", mat,
                                "-dir", 1, *frame)
                else:
                    # its shear iteration's default tolerance, 1e-12 N, is below the
                    # round-off of a heavy joint (a 5-drum column failed a step at
                    # 3.6e-12 N): relative to the weight the joint carries instead
                    ops.element("flatSliderBearing", next(tags), side_a, side_b,
                                friction_tag[between_blocks], k, "-P", mat, "-Mz", 1, *frame,
                                "-iter", 100, 1e-12 * max(1.0, k_face * g / omega**2))
                tag = next(tags)
                ops.element("zeroLength", tag, side_a, side_b, "-mat", mat_d, "-dir", 1,
                            "-doRayleigh", 1, *frame)
                dampers.append(tag)
            if beta > 0:
                ops.region(region, "-ele", *dampers, "-rayleigh", 0.0, beta / _EPS_DAMP,
                           0.0, 0.0)
        self._test = ("NormDispIncr", float(s.tolerance) * g / omega**2, int(s.iterations))
        settled = self._settle(ops)
        return self._finish_build(ops, s, scenario, cnodes, dt, settled)

    def _finish_build(self, ops: Any, s: OpenseesSettings, scenario: Scenario,
                      cnodes: list[int], dt: float, settled: bool) -> float:
        """The excitation, the analysis and the transient's start, common to both models."""
        self._add_excitation(ops, scenario, dt, 2)
        ops.constraints("Plain")
        ops.numberer("RCM")
        ops.system("BandGeneral")
        self._start_transient(ops, s, scenario, cnodes)
        # a scene that does not stand on its springs has no initial state: the poses read
        # NaN, which the base class's watchdog reports as unstable
        self._failed = not settled
        return dt

    def _settle(self, ops: Any) -> bool:
        """The static settlement under gravity (load pattern 1); True if it converged.

        Newton with :attr:`_test` and twenty times its iterations: the head joints
        of a wall sit at zero compression, where the no-tension springs' tangent
        jumps, and Newton converges slowly there (43 iterations on wall-6x3).
        """
        ops.constraints("Plain")
        ops.numberer("RCM")
        ops.system("BandGeneral")
        ops.test(self._test[0], self._test[1], 20 * self._test[2])
        ops.algorithm("Newton")
        ops.integrator("LoadControl", 1.0)
        ops.analysis("Static")
        ok = ops.analyze(1)
        ops.loadConst("-time", 0.0)
        ops.wipeAnalysis()
        return ok == 0

    def _add_excitation(self, ops: Any, scenario: Scenario, dt: float, tag: int) -> None:
        """Uniform excitation −m ü_g(t) on every mass (series and pattern ``tag``)."""
        drive = self.drive
        t_end = drive.stop
        n_drive = int(math.ceil(t_end / dt - 1e-9)) + 1 if t_end > 0 else 0
        if n_drive:
            t = drive.grid(dt, n_drive + 1)
            acc = drive.acceleration(t)[:, 0]
            ops.timeSeries("Path", tag, "-dt", dt, "-values", *acc.tolist())
            ops.pattern("UniformExcitation", tag, 1, "-accel", tag)
            self._u = np.ascontiguousarray(drive.displacement(t)[:, 0])
        else:
            self._u = np.zeros(1)

    def _start_transient(self, ops: Any, s: OpenseesSettings, scenario: Scenario,
                         cnodes: list[int]) -> None:
        """Newton with :attr:`_test`, the chosen integrator, and the run's bookkeeping."""
        ops.test(*self._test)
        ops.algorithm("Newton")
        if s.integrator == "hht":
            ops.integrator("HHT", float(s.alpha))
        elif s.integrator == "generalized-alpha":
            # OpenSees's αM, αF are 1 − α_m, 1 − α_f of Chung & Hulbert (γ, β by default)
            rho = float(s.rho_inf)
            ops.integrator("GeneralizedAlpha", (2.0 - rho) / (1.0 + rho), 1.0 / (1.0 + rho))
        else:
            ops.integrator("Newmark", 0.5, 0.25)
        ops.analysis("Transient")
        geo = scenario.geometry
        centres = geo.centroids
        self._ops, self._centroids, self._dt, self._step = ops, cnodes, float(s.timestep), 0
        self._failed = False
        self._mute = s.element == "rockingbc"
        self.unconverged_steps = 0
        self._x0, self._z0 = centres[:, 0].copy(), centres[:, 1].copy()
        # a geometry that is not a column: its bodies' angles at rest (a column's are 0)
        self._a0 = geo.angles if _column_model(scenario) is None else None
        self._poses = np.zeros((scenario.n_blocks, 7))

    def _build_rockingbc(self, ops: Any, scenario: Scenario, s: OpenseesSettings) -> float:
        """One RockingBC element from the base to the block's centroid (Settings docstring).

        Gravity is applied statically first (the body is deformable), a tilted
        start is reached by a pushover of the centroid's rotation about the
        pivot, then the transient analysis starts from rest.
        """
        column = scenario.geometry.column
        if scenario.n_blocks > 1 or column is None:
            raise UnsupportedScenario(
                "opensees element='rockingbc' models a single block: a block-to-block "
                "interface would need the lower block's top face as the element's base, a "
                "stiff beam in series with the deformable RockingBC body, not measured here")
        mu = float(scenario.contact.friction)
        if mu == 0.0:  # RockingBC reads μ = 0 as "no sliding", the opposite of frictionless
            raise UnsupportedScenario("opensees element='rockingbc' cannot model a frictionless "
                                      "base (the element reads mu = 0 as no sliding)")
        blk, g = column.blocks[0], scenario.g
        (cx, cz), = column.centroids
        width = 2.0 * blk.pivot_half_width
        # E from the self-weight strain at the base: m g / (E B w) = ε0
        young = blk.m * g / (width * blk.depth * s.rockingbc_strain)
        ops.model("basic", "-ndm", 2, "-ndf", 3)
        ops.node(1, float(cx), float(_base_z(column)[0]))
        ops.node(2, float(cx), float(cz))
        ops.fix(1, 1, 1, 1)
        ops.mass(2, blk.m, blk.m, float(blk.inertia[1]))
        # nodes as (centroid, base), as in the probe that measured it; ν = 0; sy = −1e12:
        # an elastic material (no crushing)
        ops.element("RockingBC", 1, 2, 1, int(s.rockingbc_segments), young, 0.0, -1e12,
                    width, float(blk.depth), mu)
        ops.timeSeries("Linear", 1)
        ops.pattern("Plain", 1, 1)
        ops.load(2, 0.0, -blk.m * g, 0.0)
        ops.constraints("Transformation")
        ops.numberer("RCM")
        ops.system("UmfPack")
        ops.test("EnergyIncr", 1e-10, 100)
        ops.algorithm("Newton")
        ops.integrator("LoadControl", 0.1)
        ops.analysis("Static")
        with _c_stdout_muted():
            ok = ops.analyze(10)
        ops.loadConst("-time", 0.0)
        omega1 = math.sqrt(float(ops.eigen(1)[0]))
        th = scenario.theta0
        if th != 0.0 and ok == 0:  # push the centroid's rotation to −θ0 (θ = −r_z)
            ops.timeSeries("Linear", 2)
            ops.pattern("Plain", 2, 2)
            ops.load(2, math.copysign(1.0, th), 0.0, 0.0)
            n_push = 200
            ops.integrator("DisplacementControl", 2, 3, -th / n_push)
            ops.analysis("Static")
            with _c_stdout_muted():
                ok = ops.analyze(n_push)
            ops.remove("loadPattern", 2)
        ops.setTime(0.0)
        ops.wipeAnalysis()
        # stiffness-proportional damping on the current tangent: ζ of the first mode
        ops.rayleigh(0.0, 2.0 * s.rockingbc_damping / omega1, 0.0, 0.0)
        self._add_excitation(ops, scenario, float(s.timestep), 3)
        ops.constraints("Transformation")
        ops.numberer("RCM")
        ops.system("UmfPack")
        self._test = _RBC_TEST
        self._start_transient(ops, s, scenario, [2])
        # a static stage that did not converge leaves no valid initial state: the poses
        # read NaN, which the base class's watchdog reports as unstable
        self._failed = ok != 0
        return float(s.timestep)

    @staticmethod
    def _beam(ops: Any, tag: int, centre: int, node: int, c: np.ndarray,
              p: tuple[float, float], stiffness: float, pinned: bool = False) -> None:
        """A corotational beam from a block's centroid node to one of its face nodes.

        Axial stiffness EA/L and bending stiffness EI/L³ both equal ``stiffness``;
        ``pinned``: no moment at the face node (an assembly's contact nodes).
        """
        length = math.hypot(p[0] - float(c[0]), p[1] - float(c[1]))
        release = ("-release", 2) if pinned else ()
        ops.element("elasticBeamColumn", tag, centre, node, stiffness * length, 1.0,
                    stiffness * length**3, 1, *release)

    @staticmethod
    def _set_initial_state(ops: Any, scenario: Scenario,
                           block_nodes: list[list[tuple[int, float, float]]],
                           ifaces: list[_Interface]) -> None:
        """Displace the upright model to the initial state, so that nothing rings at t = 0.

        A tilted start is the rigid rotation θ0 about the pivot (the lifted points start
        open); an upright one is the static settlement under gravity (every interface
        compressed uniformly by its load: exact static equilibrium).
        """
        th = scenario.theta0
        if th != 0.0:
            column = _column(scenario)
            px = math.copysign(column.blocks[0].pivot_half_width, th) + column.offsets[0]
            ct, st = math.cos(th), math.sin(th)
            for nodes in block_nodes:
                for tag, x, z in nodes:
                    dx = x - px
                    # rotation about +y by θ: (x, z) -> (x cos θ + z sin θ, −x sin θ + z cos θ)
                    ops.setNodeDisp(tag, 1, px + dx * ct + z * st - x, "-commit")
                    ops.setNodeDisp(tag, 2, -dx * st + z * ct - z, "-commit")
                    ops.setNodeDisp(tag, 3, -th, "-commit")
            return
        # upright: each interface compressed uniformly by the weight it carries
        masses = np.array([b.m for b in scenario.blocks])
        sink = np.cumsum([float(masses[i:].sum()) * scenario.g / float(f.k.sum())
                          for i, f in enumerate(ifaces)])
        for b, nodes in enumerate(block_nodes):
            for tag, _, _ in nodes:
                ops.setNodeDisp(tag, 2, -float(sink[b]), "-commit")

    def _drive_base(self, t: float, dt: float) -> None:
        # the UniformExcitation pattern carries ü_g at every step time: nothing to set
        pass

    def _advance_driven(self, t0: float, n: int, dt: float) -> None:
        self._advance(n)

    def _fix_base(self) -> bool:
        # the acceleration series is zero after the excitation: the base is still
        return True

    def _advance(self, n: int) -> None:
        with _c_stdout_muted() if self._mute else nullcontext():
            self._advance_steps(n)

    def _advance_steps(self, n: int) -> None:
        ops, dt = self._ops, self._dt
        target = self._step + n
        while self._step < target and not self._failed:
            if ops.analyze(target - self._step, dt) == 0:
                self._step = target
                return
            # analyze stops at the first step that fails, after the last committed one
            self._step = int(round(ops.getTime() / dt))
            self._retry_step(ops, dt)
            self._step += 1

    def _retry_step(self, ops: Any, dt: float) -> None:
        """One step that Newton did not converge: Krylov–Newton, else accept fixed iterations.

        A contact point whose dashpot switches on and off between iterations can
        make Newton cycle between two states that differ by micrometres; the step
        is then taken with a fixed number of Newton iterations and counted in
        :attr:`unconverged_steps`.
        """
        ops.algorithm("KrylovNewton")
        ok = ops.analyze(1, dt)
        ops.algorithm("Newton")
        if ok == 0:
            return
        ops.test("FixedNumIter", self._test[2])
        ok = ops.analyze(1, dt)
        ops.test(*self._test)
        self.unconverged_steps += 1
        # a step that even this cannot take ends the run: the poses read NaN from
        # now on, which the base class's watchdog reports as unstable
        self._failed = ok != 0

    def _read_poses(self) -> np.ndarray:
        ops, p = self._ops, self._poses
        if self._failed:
            p[:] = math.nan
            return p
        u = float(self._u[min(self._step, self._u.size - 1)])
        for i, tag in enumerate(self._centroids):
            ux, uz, rz = ops.nodeDisp(tag)
            half = -0.5 * rz  # θ/2 with θ = −r_z
            if self._a0 is not None:  # an assembly's blocks: from their angle at rest
                half += 0.5 * float(self._a0[i])
            p[i, 0] = self._x0[i] + ux + u
            p[i, 2] = self._z0[i] + uz
            p[i, 3] = math.cos(half)
            p[i, 5] = math.sin(half)
        return p

    def _teardown(self) -> None:
        if self._ops is not None:
            self.base_end = float(self._u[min(self._step, self._u.size - 1)])
            self._ops.wipe()
        self._ops = None
        self._centroids = []
