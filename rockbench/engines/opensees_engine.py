"""OpenSees engine plugin (OpenSeesPy): rigid blocks on compression-only interface springs.

The structural engineer's model of a rocking block, in OpenSees's planar
``basic`` model (``-ndm 2 -ndf 3``), whose (X, Y) plane is our (x, z) plane.
OpenSees's rotation is counter-clockwise positive while our θ (about +y) is
positive when the top moves toward +x, so θ = −r_z.

Model (one per scenario, built from the same :class:`Scenario` as every engine).
A column (:attr:`rockbench.geometry.Geometry.column`: upright rectangular
blocks each on the one below, the bottom one on the base: a single block, the
paper's stacks, the catalog's drum columns and parapets) gets the model of this
list; any other geometry the one of the paragraph after it:

* **Blocks.** Each block is a node at its centroid carrying the block's mass
  ``m`` (both translations) and centroidal inertia ``Block.inertia[1]``, joined
  to massless interface nodes on its faces by ``elasticBeamColumn`` elements
  with a ``Corotational`` transformation, ``body_stiffness`` times stiffer than
  the interface they serve (axially and in bending). The corotational beams keep
  the rigid-body kinematics exact at large rotations, which OpenSees's
  ``rigidLink`` (a constant, small-rotation constraint matrix) would not.
* **Interfaces.** The base and every block-to-block interface carry ``springs``
  contact points spread evenly between the interface's pivots (the pivots
  included; end points get half the tributary length). The base interface spans
  the bottom block's pivots (b − chamfer); a block-to-block interface spans the
  overlap of the two facing pivot spans. At each point a ``flatSliderBearing``
  joins the two sides: its axial material is an elastic no-tension (``ENT``)
  spring and its shear obeys Coulomb friction (``frictionModel Coulomb`` with
  the scenario's μ, normal force from the spring; ``friction`` on every
  interface of a column, ``interface_friction`` is not applied there), so the
  point carries no force at all once it lifts off. With μ = 0 a ``zeroLength``
  element with the same spring carries the normal force alone. The contact
  elements keep their global orientation (normal along z), exact on the base;
  on a block-to-block interface the normal is off by the lower block's tilt, a
  second-order error in the gap while that tilt stays small. The interface's vertical stiffness is
  K = M ω_c² (M: the mass it carries, ω_c = 2π ``contact_frequency``), shared
  by the points in proportion to their tributary lengths; the shear stiffness
  before slip equals the normal one.
* **Impact damping.** Energy at impact is lost in dashpots c = β k at the
  contact points, which act only while a point is compressed by more than
  d_0 = ``damping_onset`` · g/ω_c²: a parallel ``zeroLength`` element with a
  gate spring of stiffness ε k (ε = 1e-3, which shifts the stiffness by
  0.1 %) and stiffness-proportional Rayleigh damping β/ε on its *current*
  tangent, which is zero in tension and, with ``ElasticBilin`` as the gate
  (``ENT`` when d_0 = 0), below d_0. β = 2ζ/ω_c, ζ = ``damping_ratio`` of the
  interface's vertical mode. The onset is what lets a pivot lift off freely:
  a corner carrying the block's weight is compressed by about 2 g/ω_c² (two
  points share K), and a dashpot acting there pulls the separating corner down
  (module docstring, calibration).
* **Base motion.** Uniform excitation: the base nodes are fixed and every
  block's mass gets the inertial load −m ü_g(t) (a ``Path`` series of the
  scenario's acceleration at every step time), so the model moves relative to
  the base; the reported positions add the scenario's exact u_g(t). Chosen over
  an imposed base displacement because the ground is rigid: the relative
  equations of motion are then exactly the absolute ones with the base moving
  by the scenario's consistent (ü_g, u̇_g, u_g) from rest, with no numerical
  differentiation of u_g and nothing for the base's own (massless) nodes to
  get wrong. Rayleigh damping acts on relative velocities, which is what the
  contact dashpots should see.
* **Integration.** ``Newmark`` (average acceleration, γ = 1/2, β = 1/4) or
  ``HHT`` (``integrator = "hht"`` with ``alpha`` in [2/3, 1]) at ``timestep``,
  Newton–Raphson on the displacement increment; a step that fails to converge
  is retried with Krylov–Newton, then taken with a fixed number of Newton
  iterations (counted in ``unconverged_steps``).

Any other geometry (:class:`~rockbench.geometry.Geometry` whose ``column`` is
None: blocks and convex prisms at given poses, fixed supports, e.g. a
running-bond wall or an arch) gets the same model on every interface that
exists at rest (:attr:`~rockbench.geometry.Geometry.interfaces`: face-to-face
contacts, bed and head joints, an arch's radial joints): ``springs`` points
spread along the interface, each a
pair of nodes, one on each body (a fixed node on a support or the base, which
move with the base), joined by the same ``flatSliderBearing`` (or, with μ = 0,
``zeroLength``) and gated dashpot, oriented once along the interface's normal
and tangent at rest (μ: ``friction`` against a support or the base,
``interface_friction`` between blocks). The contact nodes do not turn: the beams
from the centroid are pinned at them (``-release``), because the slider adds a
small-rotation P-Δ term −V r_i (r_i: its first node's rotation) to its normal
force, and with nodes that turned with the bodies its friction iteration failed
on a tilting 5-drum column at 0.5 rad (a column keeps its nodes turning with the
blocks, unchanged). An interface carries K = M ω_c² as a column's does, M the
mass it carries (:meth:`OpenseesEngine.assembly_interfaces`), and the slider's
shear iteration converges to 1e-12 of the weight the joint carries (OpenSees's
default, 1e-12 N, is below the round-off of a heavy joint). Gravity is applied
by a static analysis before the run, so the scene starts in exact equilibrium on
its springs (as does an upright column whose blocks are not all centred, whose
interfaces a uniform settlement would not balance). Measured (``accurate``): at
rest for 0.5 s the 9-voussoir arch t/R = 0.2 keeps its poses to 1.3e-14 λ and
6e-16 m (under 1.5 s of CPU), the 6 × 3 running-bond wall to 9e-11 λ and 7e-12
m, but at 10 s of CPU (its head joints sit at zero compression, where Newton
cycles between the no-tension springs' two tangents); the arch under a pulse at
half its collapse acceleration rides with its supports (displacement within 4e-7
of the base's, 4e-6 λ of turn). The four assembly checks of the conformance kit pass.

The catalog's drum columns and parapets are columns (issue 25): they get the
column model, with one μ (``friction``) on every joint and contact nodes that
turn with the blocks. Measured (``accurate``): at rest for 0.5 s the 5-drum
column keeps its poses to 1.0e-15 λ and 1.4e-10 m (its closed-form
settlement), the parapet 0.25 m off-centre to 1.5e-14 λ and 6e-16 m (settled
statically); on the tilting table at 0.05 and 0.025 /s the parapet's onsets are
0.1310 / 0.1289 (LP 0.125, +3.1 %), the LP's mechanism (the parapet alone), at
17 s of CPU. The drum columns' joints are heavy (4.6 to 46 kN): under the
catalog's 2 Hz, 30 mm pulse the slider's shear iteration fails on them (its
1e-12 N tolerance, with the nodes' P-Δ term) and the run stops as ``unstable``
(NaN) at 0.4 s on the 5- and 10-drum columns (at 0.88 s on the 3-drum one with
``fast``), and on the tilting table the 5-drum column ends ``unstable`` (NaN) with
no onset found. Built with the model of the paragraph above (before issue
25) they ran: onsets 0.2487 / 0.2456 on the tilting table (LP 0.24, +2.3 %), the
column as one body, with about 1100 of its steps taken with fixed Newton
iterations (Newton stagnates at an increment of 1e-7 m, a contact switching
state between iterations, see ``_retry_step``).

What the model cannot represent, by construction: the interface springs are
laid once, on the joints that exist at rest, and carry their contact points
with the bodies. A mechanism that brings bodies into contact that were not
touching at rest finds nothing there: they pass through each other (measured: a
0.2 × 0.8 m block 1 cm from a 0.4 × 0.4 m block, pushed toward it by a 2 Hz
pulse at twice its uplift acceleration, overlaps it by 1.2 cm at 0.08 rad, by
its whole width at 0.66 rad; the same holds for a block tipping onto the base
beyond its own face). The engine names those pairs (:meth:`OpenseesEngine.unmodelled_pairs`)
and the run stops as ``unstable`` where one of them overlaps (the example: at
0.241 s, by 3.2 mm, at the first checked sample past 1e-3 of the smaller block's
size; samples are checked every 0.02 s). Large sliding is not followed either: a contact
point stays at its place on both bodies, so a block that slides along a joint
keeps being carried by springs that have left the face, and a joint's normal
stays that at rest (second order in the rotation, as on a stack). Results are
meaningful up to the onset of a mechanism of the joints at rest and through
its rocking while no new contact forms; the tilting table's onset is that.

The initial state is set as displacements of the upright model: the rigid
rotation θ0 about the pivot for a tilted start (the lifted points start open),
or the static settlement under gravity for an upright one (every interface
compressed uniformly by its load, exact static equilibrium), so nothing rings
at t = 0.

Calibration (``benchmarks/calibrate_opensees.py``, OpenSees 3.7.1). Two
knobs set the energy an impact removes: the dashpots' damping ratio ζ and
their onset d_0. ``--search`` runs B0–B3 from 0.5 λ for a grid of one knob
(``--knob``), up to their third impact or over ``--search-duration`` s. With
one contact point at each pivot (``springs = 2``: Housner's own assumption of
an impact at the corner) the result barely depends on ζ once the contact does
not bounce: at f_c = 1 kHz, Δt = 50 µs every ζ in 1.45–1.7 keeps
max |θ − θ_ref| ≤ 0.004 λ and the three impact times within 0.4 % on all four
blocks, and ``accurate`` takes ζ = 1.6.

The onset is what makes the late, small impacts right. With the dashpots
acting from first contact (d_0 = 0, the model before issue 16) the energy kept
per impact on B0 is Housner's η² = 0.888 down to 0.09 λ, then drops in steps:
0.873 from 0.055 to 0.006 λ, 0.841 at 0.003 λ, 0.72 at 1e-4 λ. Each step is
one more time step during which the corner that lifts off is still compressed
after the impact (it leaves its static compression, ≈ 2 g/ω_c², at a speed
that falls with the amplitude), and in that step its dashpot pulls it down
harder than its spring pushes: a sticky contact that Housner's impact does not
have (the share of the impact loss spent with a point in tension grows from
6 % at large amplitude to 20–30 % at the end). B0 then comes to rest 2 s early
(0.038 λ over 20 s); a stiffer contact only delays it (2 kHz, Δt = 25 µs:
0.009 λ at four times the cost). With d_0 = 2.5 g/ω_c² the lifting corner's
dashpot never acts (its dissipation is zero at every impact), while the
impacting corner, compressed 10–30 times further, is damped as before: the
energy kept per impact stays within 0.003 of η² down to 0.003 λ, and over 20 s
B0, B1, B2 and B3 from 0.5 λ stay within 0.0022, 0.0036, 0.0021 and 0.0007 λ
of Housner (impact times within 0.36 %). d_0 = 3 gives 0.0028 λ on B0, d_0 = 5
0.015 λ (the impacting corner's dashpot then misses the start of the smallest
impacts). What is left: below ~5e-4 λ the contact, undamped under the onset,
keeps the block rocking at ~1e-4 λ instead of bringing it to rest. All ten
free cases stay within 0.0074 λ over 20 s (the 0.99 λ releases are the worst),
the six Single #2 pulse peaks within −0.04 to +0.23 % of Housner (before:
0.8–1.7 % low) and the paper's eight two-block pulse peaks within −3.4 to
+4.9 % of the two-block model (before: −18 to +16 %), at 15–25 s of CPU per
20 s case. ``fast`` (f_c = 200 Hz, Δt = 0.5 ms, the same ζ and onset) keeps the
first three impact times within 1.7 % and max |θ − θ_ref| ≤ 0.053 λ over 20 s
(before: 0.20 λ, B0 at rest early) and the pulse peaks within −0.3 to +2.2 %
(before: 2.4–6.3 % low), at a tenth of the cost.

A Winkler bed of 10 points per interface (the ``winkler`` preset, no onset)
spreads each impact over the whole face, and no single ζ matches Housner's η
on all blocks (B0 and B1 need ζ ≈ 3.5, B3 ≈ 5 at f_c = 500 Hz, with impact
times moving by several per cent between neighbouring ζ). Alternatives tried:
plastic impacts by numerical damping alone (``integrator = "generalized-alpha"``,
ρ∞ = 0, no dashpots, f_c = 20 kHz, Δt = 0.1 ms) did not converge (16808 of
36000 steps of B0 taken with fixed iterations, 0.9 λ off).

Alternative element: ``element = "rockingbc"`` (preset ``rockingbc``) replaces
the springs of a single block by OpenSees's ``RockingBC`` macroelement
(Avgenakis & Psycharis 2020), a deformable rocking body whose base uplifts
and impacts without contact springs; its knobs, cost and accuracy are in
:class:`OpenseesSettings`.

Library notes: the ``openseespy`` 3.8.0.0 wheel needs ``openseespylinux`` 3.8,
which the package index does not offer for Python 3.11, so pip installs
3.7.1.2. Its Linux binary bundles ``libblas.so.3`` but does not find it
(OpenSeesPyDoc issue #319); :meth:`OpenseesEngine.library` loads the bundled
copy first. OpenSees keeps one global model per process: every build and
teardown calls ``wipe()``. At interpreter exit OpenSees writes "Process 0 Terminating" to the
C stderr; :func:`_filter_exit_stderr` drops that one line.
Licence: OpenSeesPy is free for research, education and internal use;
commercial redistribution needs a licence from its authors.
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
#: Stiffness fraction of the contact dashpots' gating springs (see the module docstring).
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
        Calibrated against Housner's η (module docstring).
    damping_onset : float
        Compression beyond which a point's dashpot acts, as a multiple of the
        static settlement g/ω_c² (0: as soon as the point is in contact). Above
        the compression of a pivot under the weight it carries, a pivot lifts
        off without its dashpot holding it back (module docstring).
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


def _column(scenario: Scenario) -> Column:
    """The scenario's geometry as a column (the column model is built only for one)."""
    column = scenario.geometry.column
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
        # calibrated with benchmarks/calibrate_opensees.py (figures in the module docstring)
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
        if scenario.geometry.column is None:  # its interfaces are the geometry's at rest
            return
        for i in range(1, scenario.n_blocks):
            lo, hi = self._span(scenario, i)
            if hi <= lo:
                raise UnsupportedScenario(f"blocks {i} and {i + 1} do not overlap")

    @staticmethod
    def _span(scenario: Scenario, i: int) -> tuple[float, float]:
        """x range of interface ``i`` (0: the base), between the facing pivots."""
        blocks, off = scenario.blocks, _column(scenario).offsets
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
        s: OpenseesSettings = settings  # type: ignore[assignment]
        dt = float(s.timestep)
        ops.wipe()
        ops.logFile(os.devnull, "-noEcho")  # convergence retries are expected, not news
        if s.element == "rockingbc":
            return self._build_rockingbc(ops, scenario, s)
        if scenario.geometry.column is None:
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
        self._add_excitation(ops, scenario, dt, 2)
        ops.constraints("Plain")
        ops.numberer("RCM")
        ops.system("BandGeneral")
        self._start_transient(ops, s, scenario, cnodes)
        # a scene that does not stand on its springs has no initial state: the poses read
        # NaN, which the base class's watchdog reports as unstable
        self._failed = not settled
        return dt

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
        self._a0 = geo.angles if geo.column is None else None
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
        blk, g = scenario.blocks[0], scenario.g
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
        """Displace the upright model to the initial state (module docstring)."""
        th = scenario.theta0
        if th != 0.0:
            px = math.copysign(scenario.blocks[0].pivot_half_width, th) + \
                _column(scenario).offsets[0]
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
