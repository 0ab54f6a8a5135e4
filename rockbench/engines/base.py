"""The :class:`Engine` base class: one simulation loop shared by every physics engine.

Contract for implementers (the numbered rules that every plugin follows)
------------------------------------------------------------------------
1. Subclass :class:`Engine`; set the class attributes ``name`` (the flag used on
   the command line), ``capabilities`` (:class:`Capabilities`), ``Settings`` (a
   frozen :class:`~rockbench.engines.settings.EngineSettings` dataclass whose
   defaults are calibrated), ``presets`` (at least ``"accurate"`` and
   ``"fast"``, each a mapping of knob overrides, possibly empty),
   ``knob_roles`` (what each knob does:
   :class:`~rockbench.engines.settings.KnobRole`, at least the time step) and,
   if not ``accurate``, ``assembly_preset`` (the preset the assembly studies
   run).
2. Declare ``requires`` (import names of the libraries the engine cannot run
   without) and ``extra`` (the rockbench extra that installs them; a
   third-party plugin leaves it empty and the hint names the library). Never
   import a library at module level, nor catch its ImportError yourself: get it
   through :meth:`library` (``self.library("mujoco")``, or a module-level
   function that calls it), which raises
   :class:`~rockbench.errors.EngineUnavailable` with the ``pip install`` hint.
   Submodules of a library may then be imported inside methods. Implement
   :meth:`version` (the library's version string) through :meth:`library`
   too: :meth:`simulate` calls it first. The registry calls
   :meth:`check_available` and :meth:`version` and lists the engine as
   unavailable, with the reason and the hint, when either raises anything, so
   a missing or broken library is never a crash nor a wrong "available". An
   optional library (one the engine runs without, more slowly) is not in
   ``requires``; :meth:`version` says whether it is used (the one import that
   may be tried at module level, catching ImportError, is such an optional
   accelerator that decorates code at definition, like the numba of
   ``dem2d_kernels``). Declare the checks
   of the conformance kit the engine is known to fail in ``known_failures``
   (check name -> measured reason): the test suites, yours through
   :func:`rockbench.engines.testing.parametrize_with_checks`, mark them as
   strict expected failures.
3. Implement :meth:`_build`: create the minimal scene for ``scenario.geometry``
   (:mod:`rockbench.geometry`): one collision shape per body (box, or convex
   prism if chamfered or polygonal), the fixed supports, a ground/base body whose
   top face is the plane z = 0, friction and restitution from
   ``scenario.contact``, no hidden damping, no sleeping. Place body ``i``'s
   centre of gravity and angle at ``scenario.initial_poses()[i]``, at rest.
   Declare ``Capabilities.cylinders`` only where a
   :class:`~rockbench.geometry.Cylinder` is built as a cylinder, and
   ``Capabilities.start3d`` and ``moving_start`` only where the 3D pose and the
   velocities of ``scenario.initial_states()[i]`` are applied (world axes). Return the
   physics time step actually used.
4. Apply the base motion: :attr:`drive` (a :class:`~rockbench.engines.drive.BaseDrive`,
   set before :meth:`_build`) samples the scenario's three-component motion on
   the engine's step grid; the engine applies it (velocity and/or displacement,
   not tilted gravity; the one exception is an engine whose number format cannot
   follow a base that travels far and fast, which may run a uniformly
   accelerating base in the base's frame and add u_g to the poses it reads:
   Blender, see ``blender_engine``) and never reads the excitation itself.
   Declare the axes it applies in ``Capabilities.base_axes``: a motion along any
   other axis is ``unsupported``. :meth:`_drive_base` imposes the motion for
   the step starting at time ``t``; it is called before every step while the
   base moves, by :meth:`_advance_driven`, which an engine may override to take
   many driven steps in one call (e.g. a compiled loop over precomputed base
   velocities).
5. Optionally implement :meth:`_fix_base` (called once when the excitation has
   ended): make the base still and return True so that steps can be batched.
6. Implement :meth:`_advance`: take ``n`` physics steps. Optionally override
   :meth:`_sample_free` / :meth:`_sample_driven` to take many output samples
   in one call (they fill an array of poses; the defaults loop in Python).
7. Implement :meth:`_read_poses`: return an array (n_blocks, 7) with each block
   centroid's world position (x, y, z) and orientation quaternion (w, x, y, z),
   bottom block first. 2D engines map their plane to x–z and set y = 0.
8. Optionally override :meth:`_check_supported` to raise
   :class:`~rockbench.errors.UnsupportedScenario` for what the engine cannot
   model, :meth:`unmodelled_pairs` to name an assembly's body pairs it builds no
   contact between (the run is then watched for their overlap), and
   :meth:`_teardown` to free native resources.
9. Do not override :meth:`simulate`: it owns timing, sampling at the output
   rate, NaN/explosion/energy-gain/overturning detection and the Trajectory.
10. Register the class under the entry-point group ``rockbench.engines`` and run
    the conformance kit on it: :func:`rockbench.engines.testing.check_engine`
    (one call) or, in a pytest suite, one test decorated with
    :func:`rockbench.engines.testing.parametrize_with_checks`.
"""

from __future__ import annotations

import importlib
import importlib.metadata
import math
import operator
import re
import sys
import time
from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import ModuleType
from typing import Any, ClassVar

import numpy as np

from rockbench.bounds import SpeedBound
from rockbench.engines.drive import BaseDrive
from rockbench.engines.overlap import OverlapWatch
from rockbench.engines.settings import EngineSettings, KnobRole, SettingsError
from rockbench.errors import EngineUnavailable, UnsupportedScenario
from rockbench.geometry import Block, Cylinder
from rockbench.limits import check_memory
from rockbench.scenarios import Scenario
from rockbench.trajectory import (
    Orientation,
    Status,
    Trajectory,
    angles_from_quaternions,
    orientation_from_quaternions,
)

__all__ = ["Engine", "Capabilities", "angles_from_quaternions", "install_hint", "OVERTURN_MARGIN",
           "require_library", "trajectory_from_poses", "Watchdog", "Orientation",
           "orientation_from_quaternions"]


def install_hint(extra: str, module: str) -> str:
    """The command that installs an engine's library: its rockbench extra, or else the module.

    An extra whose packages exist for other Pythons only (Blender's bpy: 3.11; Box2D's and
    Jolt's wheels: ≥ 3.12) installs nothing here, so the hint says which Python it needs.
    """
    if not extra:
        return f"pip install {module}"
    hint = f"pip install 'rockbench[{extra}]'"
    need = _python_of_extra(extra)
    here = f"{sys.version_info.major}.{sys.version_info.minor}"
    return hint if need is None else f"{hint} under Python {need} (this is Python {here})"


#: A requirement's Python condition in rockbench's metadata: python_version >= "3.12".
_PYTHON_MARKER = re.compile(r'python_version\s*(==|>=|<=|<|>)\s*"(\d+)\.(\d+)"')
_COMPARE = {"==": operator.eq, ">=": operator.ge, "<=": operator.le, "<": operator.lt,
            ">": operator.gt}


def _python_of_extra(extra: str) -> str | None:
    """The Python an extra's packages need (e.g. ``">= 3.12"``) when it is not this one;
    None when they install here, or when rockbench's metadata cannot tell."""
    try:
        requires = importlib.metadata.requires("rockbench") or []
    except importlib.metadata.PackageNotFoundError:  # a source tree never installed
        return None
    for req in requires:
        if f'extra == "{extra}"' not in req:
            continue
        found = _PYTHON_MARKER.search(req)
        if found is None:
            return None
        op, major, minor = found.group(1), int(found.group(2)), int(found.group(3))
        if not _COMPARE[op](sys.version_info[:2], (major, minor)):
            sign = {">=": "≥ ", "<=": "≤ ", "==": ""}.get(op, f"{op} ")
            return f"{sign}{major}.{minor}"
        return None
    return None


def require_library(module: str, *, engine: str, extra: str = "") -> ModuleType:
    """Import an engine's library, or raise :class:`EngineUnavailable` with the install hint.

    Any failure of the import counts (a missing package, a broken binary wheel, a
    missing shared library), since each leaves the engine unusable.

    Parameters
    ----------
    module : str
        Import name of the library (``"mujoco"``, ``"pydrake.all"``).
    engine : str
        Engine name, for the message.
    extra : str
        rockbench extra that installs it (hint ``pip install 'rockbench[extra]'``);
        empty: the hint names the module.
    """
    try:
        return importlib.import_module(module)
    except Exception as exc:  # an engine library can fail in many ways on import
        raise EngineUnavailable(
            f"engine {engine!r} is unavailable: cannot import {module} "
            f"({type(exc).__name__}: {exc}); install it with: {install_hint(extra, module)}"
        ) from exc


@dataclass(frozen=True)
class Capabilities:
    """What an engine can model.

    Attributes
    ----------
    dimensions : int
        2 for planar engines (x–z plane), 3 otherwise.
    max_blocks : int or None
        Largest stack it builds (None: no limit).
    chamfer : bool
        Whether chamfered (convex prism) blocks are modelled.
    analytic : bool
        True for reference solutions (not physics engines).
    assemblies : bool
        Whether it builds any :class:`~rockbench.geometry.Geometry` (bodies at
        any pose, convex prisms, fixed supports); without it only columns
        (:attr:`~rockbench.geometry.Geometry.column`) are built and others are
        ``unsupported``.
    no_assemblies : str
        Why not, when ``assemblies`` is False (the unsupported status says it).
    prisms : bool
        Whether an assembly's blocks may be convex polygonal prisms
        (:class:`~rockbench.geometry.Prism`) besides rectangular blocks (and
        cylinders, which ``cylinders`` declares).
    no_prisms : str
        Why not, when ``prisms`` is False (the unsupported status says it).
    base_axes : str
        The axes of the base motion it applies (``"x"``, ``"xz"``, ``"xyz"``).
    cylinders : bool
        Whether it builds :class:`~rockbench.geometry.Cylinder` bodies as
        cylinders (without it they are ``unsupported``: a box in their place
        would be another body).
    start3d : bool
        Whether it places bodies at the 3D pose of
        :meth:`~rockbench.scenarios.Scenario.initial_states` (a tilt toward any
        azimuth); without it a start out of the x–z plane is ``unsupported``.
    moving_start : bool
        Whether it gives bodies the initial velocities of
        :meth:`~rockbench.scenarios.Scenario.initial_states`; without it a
        moving start is ``unsupported``.
    """

    dimensions: int = 3
    max_blocks: int | None = None
    chamfer: bool = True
    analytic: bool = False
    assemblies: bool = False
    no_assemblies: str = "only single blocks and stacks are built"
    prisms: bool = True
    no_prisms: str = ""
    base_axes: str = "x"
    cylinders: bool = False
    start3d: bool = False
    moving_start: bool = False


class Engine(ABC):
    """A physics engine behind one simulation loop (template method).

    See the module docstring for the numbered contract. Users call
    :meth:`simulate` only.
    """

    name: ClassVar[str]
    capabilities: ClassVar[Capabilities] = Capabilities()
    Settings: ClassVar[type[EngineSettings]]
    presets: ClassVar[Mapping[str, Mapping[str, Any]]] = {"accurate": {}, "fast": {}}
    #: The rockbench extra that installs the library (``pip install 'rockbench[extra]'``).
    extra: ClassVar[str] = ""
    #: Import names of the libraries the engine needs (checked by :meth:`check_available`).
    requires: ClassVar[tuple[str, ...]] = ()
    #: Conformance checks this engine is known to fail: check name -> measured reason.
    #: The test suites mark them as strict expected failures.
    known_failures: ClassVar[Mapping[str, str]] = {}
    #: True if the engine keeps global state between runs (one model per process, a
    #: global session): the runner then starts a fresh worker process for every run
    #: instead of reusing a warm one (:mod:`rockbench.runner`).
    fresh_process: ClassVar[bool] = False
    #: The preset the sensitivity study (the paper's Table 2) varies the knobs from.
    sensitivity_preset: ClassVar[str] = "accurate"
    #: The preset the assembly studies (tilting table, pulse to collapse) run by default.
    assembly_preset: ClassVar[str] = "accurate"
    #: What each knob does (knob → role): studies ask the engine instead of guessing
    #: from names. A role appears at most once.
    knob_roles: ClassVar[Mapping[str, KnobRole]] = {}
    #: The knob a convergence ladder refines (by its role's :meth:`KnobRole.refine`):
    #: the time step, or the knob that sets it; '' for the knob of the time-step role.
    refinement: ClassVar[str] = ""
    #: The family of its contact model (independent families make a consensus):
    #: ``soft-constraint``, ``impulse``, ``compliant-point``, ``penalty``,
    #: ``non-smooth``, ``analytic``.
    contact_model: ClassVar[str] = ""

    # ------------------------------------------------------------------ public API
    @classmethod
    def library(cls, module: str) -> ModuleType:
        """Import one of the engine's libraries (rule 2): :func:`require_library`."""
        return require_library(module, engine=cls.name, extra=cls.extra)

    @classmethod
    def check_available(cls) -> None:
        """Raise :class:`EngineUnavailable` if a library in ``requires`` cannot be imported."""
        for module in cls.requires:
            cls.library(module)

    @classmethod
    @abstractmethod
    def version(cls) -> str:
        """Version of the underlying library (may raise :class:`EngineUnavailable`)."""

    @classmethod
    def settings(cls, preset: str | None = None, **overrides: Any) -> EngineSettings:
        """Build settings from a preset name (or the defaults) plus knob overrides.

        Raises
        ------
        SettingsError
            Unknown preset or knob, or a value of the wrong type.
        """
        base = cls.Settings()
        if preset is not None and not isinstance(preset, str):
            raise SettingsError(f"preset of {cls.name!r} must be a preset name, got {preset!r}")
        if preset not in (None, "default"):
            if preset not in cls.presets:
                raise SettingsError(
                    f"engine {cls.name!r} has no preset {preset!r}; presets: "
                    f"{', '.join(sorted(cls.presets))}"
                )
            base = base.replace(**cls.presets[preset])
        if not overrides:
            return base
        try:
            return base.replace(**overrides)
        except SettingsError as exc:
            text = str(exc)
            if text.split(" ", 1)[0] in overrides:  # a knob's value: name its engine too
                raise SettingsError(f"{cls.name}.{text}") from None
            if text.startswith("no knob"):
                raise SettingsError(f"engine {cls.name!r} has {text}") from None
            raise

    @classmethod
    def knob(cls, role: KnobRole) -> str | None:
        """The knob that plays ``role`` (None if the engine has none)."""
        return next((k for k, r in cls.knob_roles.items() if r is role), None)

    @classmethod
    def refined(cls, settings: Mapping[str, Any], level: int) -> dict[str, Any]:
        """``settings`` (a preset and overrides) one convergence-ladder rung ``level`` finer.

        The :attr:`refinement` knob (default: the time step's) is refined ``level``
        times by a factor of 2 (:meth:`KnobRole.refine`); level 0 is ``settings``.

        Raises
        ------
        SettingsError
            The engine declares no knob to refine, or its value is not a number.
        """
        knob = cls.refinement or cls.knob(KnobRole.TIME_STEP)
        if knob is None or knob not in cls.knob_roles:
            raise SettingsError(f"engine {cls.name!r} declares no knob a convergence ladder "
                                "refines (knob_roles, refinement)")
        value = getattr(cls.resolve_settings(dict(settings)), knob)
        try:
            refined = cls.knob_roles[knob].refine(value, level)
        except ValueError as exc:
            raise SettingsError(f"engine {cls.name!r}: {knob} {exc}") from None
        return {**settings, knob: refined}

    @classmethod
    def resolve_settings(cls, settings: Any = None) -> EngineSettings:
        """Accept None, a preset name, a mapping of overrides or a Settings instance."""
        if settings is None or isinstance(settings, str):
            return cls.settings(settings)
        if isinstance(settings, cls.Settings):
            return settings
        if isinstance(settings, Mapping):
            s = dict(settings)
            return cls.settings(s.pop("preset", None), **s)
        raise SettingsError(
            f"settings for {cls.name!r} must be a preset name, a mapping or "
            f"{cls.Settings.__qualname__}, got {type(settings).__name__}"
        )

    def check_supported(self, scenario: Scenario) -> None:
        """Raise :class:`UnsupportedScenario` if the engine cannot model ``scenario``."""
        cap = self.capabilities
        if cap.max_blocks is not None and scenario.n_blocks > cap.max_blocks:
            raise UnsupportedScenario(
                f"{self.name} models at most {cap.max_blocks} block(s), scenario has "
                f"{scenario.n_blocks}"
            )
        if scenario.geometry.column is None and not cap.assemblies:
            raise UnsupportedScenario(
                f"{self.name} builds only blocks standing on each other: {cap.no_assemblies}")
        if scenario.has_cylinders and not cap.cylinders:
            why = " (a planar engine: a box of the cylinder's silhouette would be another body)" \
                if cap.dimensions == 2 else ""
            raise UnsupportedScenario(f"{self.name} does not build cylinders{why}")
        if not cap.start3d and not scenario.planar_start:
            raise UnsupportedScenario(f"{self.name} starts bodies in the x–z plane only; this "
                                      "scenario starts them out of it")
        if not cap.moving_start and scenario.moving_start:
            raise UnsupportedScenario(f"{self.name} starts bodies at rest only; this scenario "
                                      "starts them moving")
        if not cap.prisms and not all(isinstance(b, (Block, Cylinder)) for b in scenario.blocks):
            raise UnsupportedScenario(
                f"{self.name} builds rectangular blocks only: {cap.no_prisms}")
        other = tuple(a for a in scenario.motion.axes if a not in cap.base_axes)
        if other:
            raise UnsupportedScenario(
                f"{self.name} applies the base motion along {', '.join(cap.base_axes)} only; "
                f"this scenario's base also moves along {', '.join(other)}")
        if not cap.chamfer and any(b.chamfer > 0 for b in scenario.blocks):
            raise UnsupportedScenario(f"{self.name} does not model chamfered blocks")
        self._check_supported(scenario)

    def simulate(self, scenario: Scenario, settings: Any = None) -> Trajectory:
        """Run ``scenario`` and return its sampled :class:`Trajectory`.

        Never raises for physics failures: NaN, explosions, energy gain and
        overturning become the trajectory's ``status``; an unsupported scenario
        returns status ``unsupported``. Bad settings raise :class:`SettingsError`,
        a scenario over the memory budget :class:`~rockbench.errors.ScenarioError`
        (:mod:`rockbench.limits`).
        """
        s = self.resolve_settings(settings)
        check_memory(scenario)
        self.drive = BaseDrive(scenario.motion, scenario.duration)
        meta = dict(engine=self.name, engine_version=self.version(), settings=s.to_dict(),
                    scenario=scenario.name)
        try:
            self.check_supported(scenario)
        except UnsupportedScenario as exc:
            return Trajectory.failed(Status.UNSUPPORTED, str(exc), n_blocks=scenario.n_blocks,
                                     **meta)
        start, cpu = time.perf_counter(), time.process_time()
        try:
            traj = self._run(scenario, s, meta)
        except UnsupportedScenario as exc:  # raised by _build when it depends on settings
            traj = Trajectory.failed(Status.UNSUPPORTED, str(exc), n_blocks=scenario.n_blocks,
                                     **meta)
        finally:
            self._teardown()
        traj.wall_time = time.perf_counter() - start
        traj.cpu_time = time.process_time() - cpu
        return traj

    # ------------------------------------------------------------------ the loop
    def _run(self, scenario: Scenario, settings: EngineSettings, meta: dict) -> Trajectory:
        t_out = scenario.output_times()
        n_out, nb = t_out.size, scenario.n_blocks
        dt = float(self._build(scenario, settings))
        interval = 1.0 / scenario.output_rate
        if not dt <= interval * (1.0 + 1e-9):
            # a step longer than the output interval only repeats or interpolates samples:
            # the output would claim a resolution the physics never had
            raise SettingsError(
                f"{self.name}: physics time step {dt:.4g} s is longer than the output interval "
                f"{interval:.4g} s of scenario {scenario.name!r}: lower the engine's step or the "
                "scenario's output_rate")
        ratio = 1.0 / (scenario.output_rate * dt)
        k = int(round(ratio))
        # when the step divides the output interval, sample right after whole
        # steps; otherwise read every step and interpolate onto the output times
        aligned = k >= 1 and abs(ratio - k) <= 1e-6 * ratio
        drive = self.drive
        watch = Watchdog(scenario, drive, self.unmodelled_pairs(scenario))
        poses = np.full((n_out, nb, 7), np.nan)
        poses[0] = self._read_poses()
        sampler = self._sample_aligned if aligned else self._sample_interpolated
        with np.errstate(invalid="ignore", over="ignore"):
            last, verdict = sampler(poses, t_out, dt, k, drive, watch)
        return trajectory_from_poses(poses[:last], t_out[:last], verdict, meta,
                                     effective_timestep=dt, steps_per_sample=ratio)

    def _sample_aligned(self, poses: np.ndarray, t_out: np.ndarray, dt: float, k: int,
                        drive: BaseDrive, watch: Watchdog
                        ) -> tuple[int, tuple[Status, str] | None]:
        """Advance k steps per output sample, a watchdog chunk of samples per hook call."""
        n_out = t_out.size
        batched = not drive.moving
        # the base is driven up to the first sample that ends past the motion,
        # then the engine holds it still (n_out: the motion outlasts the run)
        ends_past = (np.arange(1, n_out) * k) * dt > drive.end_time
        last_driven = int(np.argmax(ends_past)) + 1 if ends_past.any() else n_out
        i = 1
        while i < n_out:
            m = min(watch.chunk, n_out - i)
            if batched:
                self._sample_free(poses[i:i + m], k)
            else:  # an engine that cannot hold the base still goes on driving it
                if i <= last_driven:
                    m = min(m, last_driven - i + 1)
                self._sample_driven(poses[i:i + m], (i - 1) * k, k, dt)
                if i + m - 1 == last_driven:
                    batched = self._fix_base()
            bad = watch.check(poses[i - 1:i + m], t_out[i:i + m])
            if bad is not None:
                return i + bad[0] + 1, bad[1]
            i += m
        return n_out, None

    def _sample_interpolated(self, poses: np.ndarray, t_out: np.ndarray, dt: float, k: int,
                             drive: BaseDrive, watch: Watchdog
                             ) -> tuple[int, tuple[Status, str] | None]:
        """Step one at a time and interpolate poses linearly onto the output times."""
        n_out = t_out.size
        prev = poses[0].copy()
        step, i, checked = 0, 1, 1
        moving = drive.moving
        while i < n_out:
            if moving:
                self._advance_driven(step * dt, 1, dt)
            else:
                self._advance(1)
            step += 1
            if moving and step * dt > drive.end_time and self._fix_base():
                moving = False
            cur = np.array(self._read_poses(), dtype=float)
            # keep quaternions on one hemisphere so that interpolation is short-way
            flip = np.sum(cur[:, 3:] * prev[:, 3:], axis=1) < 0
            cur[flip, 3:] *= -1.0
            t0, t1 = (step - 1) * dt, step * dt
            while i < n_out and t_out[i] <= t1 + 1e-12:
                w = (t_out[i] - t0) / dt
                q = prev + w * (cur - prev)
                q[:, 3:] /= np.linalg.norm(q[:, 3:], axis=1, keepdims=True)
                poses[i] = q
                i += 1
            prev = cur
            if i - checked >= watch.chunk or i == n_out:
                bad = watch.check(poses[checked - 1:i], t_out[checked:i])
                if bad is not None:
                    return checked + bad[0] + 1, bad[1]
                checked = i
        return n_out, None

    # ------------------------------------------------------------------ hooks
    def unmodelled_pairs(self, scenario: Scenario) -> tuple[tuple[int, int], ...]:
        """Body pairs of an assembly between which this engine builds no contact (rule 8).

        Bodies are numbered as in the limit analysis: blocks, then supports, then the
        base (:mod:`rockbench.engines.overlap`). The default is none: every body
        collides with every other. An engine that lays its contacts once, at rest,
        names the other pairs; a run in which any of them overlap stops as
        ``unstable``, naming them.
        """
        return ()

    @abstractmethod
    def _build(self, scenario: Scenario, settings: EngineSettings) -> float:
        """Create the scene (rule 3); return the physics time step in s."""

    @abstractmethod
    def _drive_base(self, t: float, dt: float) -> None:
        """Impose the base motion for the step [t, t + dt] (rule 4)."""

    def _advance_driven(self, t0: float, n: int, dt: float) -> None:
        """Take ``n`` steps from ``t0`` while driving the base (rule 4).

        The default calls :meth:`_drive_base` then ``_advance(1)`` per step; an
        engine that can drive the base inside a compiled loop overrides this.
        """
        for j in range(n):
            self._drive_base(t0 + j * dt, dt)
            self._advance(1)

    def _sample_free(self, out: np.ndarray, k: int) -> None:
        """Fill ``out`` (m, n_blocks, 7) with the poses after each of m runs of k steps.

        The base is still. The default calls :meth:`_advance` and
        :meth:`_read_poses` per sample; a compiled engine may override it to
        take many samples per call (rule 6).
        """
        for j in range(out.shape[0]):
            self._advance(k)
            out[j] = self._read_poses()

    def _sample_driven(self, out: np.ndarray, step0: int, k: int, dt: float) -> None:
        """Like :meth:`_sample_free` while driving the base, starting at step ``step0``."""
        for j in range(out.shape[0]):
            self._advance_driven((step0 + j * k) * dt, k, dt)
            out[j] = self._read_poses()

    def _fix_base(self) -> bool:
        """Hold the base still after the excitation (rule 5); True if steps may be batched."""
        return False

    @abstractmethod
    def _advance(self, n: int) -> None:
        """Take ``n`` physics steps (rule 6)."""

    @abstractmethod
    def _read_poses(self) -> np.ndarray:
        """Block centroid poses, shape (n_blocks, 7): x, y, z, qw, qx, qy, qz (rule 7)."""

    def _check_supported(self, scenario: Scenario) -> None:  # noqa: B027 - optional hook
        """Engine-specific support check (rule 8); raise UnsupportedScenario."""

    def _teardown(self) -> None:  # noqa: B027 - optional hook
        """Free native resources after a run (rule 8)."""


def trajectory_from_poses(poses: np.ndarray, t: np.ndarray,
                          verdict: tuple[Status, str] | None, meta: dict,
                          **effective: Any) -> Trajectory:
    """The :class:`Trajectory` of sampled poses (n, n_blocks, 7) at times ``t``.

    ``verdict`` is the watchdog's (None: ``ok``); ``meta`` the run's engine, version,
    settings and scenario; ``effective`` is added to its settings (the effective step).
    """
    status, message = verdict if verdict is not None else (Status.OK, "")
    meta = {**meta, "settings": {**meta["settings"], **effective}}
    o = orientation_from_quaternions(poses[..., 3:])
    return Trajectory(t=t, theta=o.theta, x=poses[..., 0], z=poses[..., 2], wobble=o.wobble,
                      y=poses[..., 1], roll=o.roll, twist=o.twist, status=status,
                      message=message, **meta)


#: A block counts as overturned once |θ| ≥ π/2 − this (rad): a toppled block may settle on
#: its side a hair short of π/2 (a float32 engine at π/2 − 2e-7), and no block that rocks
#: comes back from there (it falls past its λ < π/2 long before).
OVERTURN_MARGIN = 1e-3
_R22_OVER = 0.5 * math.sin(OVERTURN_MARGIN)


class Watchdog:
    """Detects NaN, explosions, energy gain in free motion and overturning from poses.

    Poses are checked in chunks of samples (vectorised, a fixed handful of NumPy
    calls per chunk) so that the check costs far less than the physics; a run
    may go on a few samples past a failure, but the trajectory is cut at the
    first failing sample. The samplers call it with floating-point warnings
    silenced: NaN and infinities are what it looks for.
    """

    #: Seconds of output per check: each check has a fixed cost (a few dozen
    #: NumPy calls), and a failed run goes on for at most this long before it
    #: is stopped.
    PERIOD = 1.0

    def __init__(self, scenario: Scenario, drive: BaseDrive,
                 unmodelled: Sequence[tuple[int, int]] = ()) -> None:
        geo = scenario.geometry
        self.masses = geo.masses
        # body pairs the engine has no contact between: any overlap is a missed contact
        self.overlaps = OverlapWatch(scenario, drive, unmodelled) if unmodelled else None
        height = geo.total_height
        u_base, v_base = drive.motion.motion_bounds(scenario.duration)
        # a falling block cannot leave a ball of a few heights (or, for a wide
        # geometry, of its size) around its start
        self.reach2 = (3.0 * max(height, geo.size) + 2.0 * u_base + 1.0) ** 2
        p0 = scenario.initial_poses()
        self.x0, self.z0 = p0[:, 0], p0[:, 1]
        # overturning is measured from each block's own orientation at rest (a
        # geometry's blocks need not stand upright); None: all upright
        angles = geo.angles
        self.half_turn0 = None if not angles.any() else 0.5 * angles
        self.free = not drive.moving
        mgz0 = float(self.masses @ p0[:, 1])
        mgz_up = mgz0 if scenario.theta0 == 0.0 else float(self.masses @ geo.centroids[:, 1])
        # potential energy may not rise above its start (and the kinetic energy it starts
        # with) in free motion, beyond the contact penetration noise of a soft engine
        self.z_limit = (mgz0 + 0.02 * abs(mgz0 - mgz_up) + 1e-4 * self.masses.sum() * height
                        + scenario.initial_kinetic_energy() / scenario.g)
        self.chunk = max(1, int(self.PERIOD * scenario.output_rate))
        # the speed bound as the largest move per (uniform) output interval
        self.bound = SpeedBound.for_scenario(scenario, v_base=v_base)
        self.h = 1.0 / scenario.output_rate
        self.move2 = (self.bound.v_max * self.h) ** 2
        self.turn = self.bound.omega_max * self.h
        # the rotation between two samples is 2 acos |q0 · q1| (any axis): within the bound
        # when |q0 · q1| ≥ cos(bound / 2)
        self.cos_half_turn = math.cos(0.5 * min(self.turn, math.pi))

    def check(self, poses: np.ndarray, t: np.ndarray) -> tuple[int, tuple[Status, str]] | None:
        """First failing sample of a chunk (index within the chunk, verdict), or None.

        The common case, a chunk that passes, costs a fixed two dozen NumPy
        calls whatever the chunk's length, ending in six reductions that NaN
        makes fail, so it is caught too. Only a failing chunk is searched
        sample by sample for the first offence and its reason.

        Parameters
        ----------
        poses : ndarray, shape (m + 1, n_blocks, 7)
            The last sample already checked (to bound the speed across chunks),
            then the chunk's m new samples.
        t : ndarray, shape (m,)
            Times of the new samples (s).
        """
        x, z = poses[..., 0], poses[..., 2]
        w, qx, qy, qz = (poses[..., i] for i in range(3, 7))
        if self.half_turn0 is not None:
            # the orientation relative to the block's own at rest: q · rot_y(−θ_rest)
            c, s = np.cos(self.half_turn0), np.sin(self.half_turn0)
            w, qx, qy, qz = w * c + qy * s, qx * c + qz * s, qy * c - w * s, qz * c - qx * s
        # R22/2 (R22 = cos of the tilt, about any axis): overturned when the tilt reaches
        # π/2 − OVERTURN_MARGIN, i.e. R22 ≤ sin(margin), as |θ| does in a planar run
        r22 = 0.5 - (qx * qx + qy * qy)
        dx, dz = x[1:] - x[:-1], z[1:] - z[:-1]
        move2 = dx * dx + dz * dz
        # the rotation per sample about any axis (θ alone is ill-defined for a block falling
        # about x, whose R02 and R22 both vanish): cos of its half, |q0 · q1|
        cos_half = np.abs(w[1:] * w[:-1] + qx[1:] * qx[:-1] + qy[1:] * qy[:-1]
                          + qz[1:] * qz[:-1])
        r22, x, z = r22[1:], x[1:], z[1:]
        far2 = (x - self.x0) ** 2 + (z - self.z0) ** 2
        height = z @ self.masses if self.free else None
        # (array methods: np.max's Python wrapper costs as much as the reduction)
        # (y enters no bound: a sum that NaN or infinity makes non-finite covers it)
        overlap = self.overlaps.first(poses[1:], t) if self.overlaps is not None else None
        if (move2.max() <= self.move2 and cos_half.min() >= self.cos_half_turn
                and r22.min() > _R22_OVER and far2.max() <= self.reach2
                and (height is None or height.max() <= self.z_limit)
                and math.isfinite(poses[1:, :, 1].sum())) and overlap is None:
            return None
        # the same quantities sample by sample, for the first offence and its reason
        finite = np.isfinite(poses[1:]).all(axis=(1, 2))
        far = (far2 > self.reach2).any(axis=1)
        fast = ((move2 > self.move2) | (cos_half < self.cos_half_turn)).any(axis=1)
        over = r22 <= _R22_OVER
        gain = height > self.z_limit if height is not None else np.zeros(len(t), bool)
        bad = ~finite | far | fast | over.any(axis=1) | gain
        if overlap is not None and not bad[:overlap[0] + 1].any():
            j = overlap[0]
            return j, (Status.UNSTABLE, f"{overlap[1]} at t = {t[j]:.4g} s")
        if not bad.any():
            return None
        j = int(np.argmax(bad))
        if not finite[j]:
            status, what = Status.UNSTABLE, "NaN or infinite pose"
        elif far[j]:
            status, what = Status.UNSTABLE, "explosion: a block left the scene"
        elif fast[j]:
            dxz = np.column_stack([dx[j], dz[j]])
            turn = 2.0 * np.arccos(np.clip(cos_half[j], 0.0, 1.0))
            status = Status.UNSTABLE
            what = self.bound.violation(self.h, dxz, turn) or "explosion: non-physical speed"
        elif over[j].any():
            status, what = Status.OVERTURNED, f"block {int(np.argmax(over[j])) + 1} overturned"
        else:
            status, what = Status.UNSTABLE, "energy gain in free motion"
        return j, (status, f"{what} at t = {t[j]:.4g} s")
