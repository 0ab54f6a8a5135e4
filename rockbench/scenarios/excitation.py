"""Base excitations: a three-component base motion (x, y horizontal, z vertical), from rest.

An excitation gives its :class:`~rockbench.scenarios.motion.BaseMotion` (x, y, z) through
:meth:`Excitation.base_motion`. The one-dimensional motions (pulses, sinusoids, records,
the tilting table: :class:`AxialExcitation`) move the base along +x and keep it still
along y and z; the ``components`` excitation (:class:`Components`) takes one such 1-D
motion per axis, ``[excitation.x]``, ``[excitation.y]`` and ``[excitation.z]``.

Every 1-D motion returns acceleration, velocity and displacement that are exact
integrals of each other (closed forms for pulses and sinusoids, exact piecewise
polynomial integration for records), so that an engine driven by displacement or
velocity and an analytic model driven by acceleration see the same motion.
Functions accept scalars or arrays of times and return the same shape.

Excitations are registered by kind: a subclass that declares ``kind`` (its
``type`` in scenario files) and ``report_group`` is found by
:func:`excitation_from_table`, reads and writes its own ``[excitation]`` table
(:meth:`Excitation.from_table`, :meth:`Excitation.to_table`) and gives the plain-float
ü_g(t) the analytic solvers use (:meth:`Excitation.scalar_acceleration`). Adding an
excitation is writing one such class; nothing else dispatches on the classes.
"""

from __future__ import annotations

import math
import re
from abc import ABC, abstractmethod
from bisect import bisect_right
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar, TypeVar

import numpy as np

from rockbench import checks
from rockbench.errors import ScenarioError
from rockbench.scenarios.motion import BaseMotion, Motion, Still

__all__ = ["Excitation", "AxialExcitation", "Components", "Free", "SinePulse", "CosinePulse",
           "Sinusoid", "Record", "TiltTable", "register_set_reader",
           "STANDARD_GRAVITY", "MAX_BASE_ACCELERATION", "MIN_RECORD_STEP", "MAX_RECORD_SPAN",
           "REPORT_GROUPS", "excitation_kinds",
           "excitation_class", "excitation_from_table"]

#: Conversion factor for records given in units of g.
STANDARD_GRAVITY = 9.80665

#: Largest base acceleration accepted (m/s², about 10⁵ g): far beyond any ground motion,
#: and a bound under which the solvers' squared accelerations cannot overflow.
MAX_BASE_ACCELERATION = 1e6
#: Shortest interval between a record's samples (s): 1 MHz, beyond any accelerograph or
#: shake-table controller (they sample at 10 kHz at most).
MIN_RECORD_STEP = 1e-6
#: Longest record (s): a day; ground motions last minutes.
MAX_RECORD_SPAN = 86400.0

#: How reports group scenarios by their base motion (an excitation's ``report_group``).
REPORT_GROUPS = ("free", "pulse", "sine", "record", "tilt")

ArrayLike = float | np.ndarray

#: kind → class, filled by :meth:`Excitation.__init_subclass__`.
_REGISTRY: dict[str, type[Excitation]] = {}


def _finite_positive(value: Any, what: str, allow_zero: bool = False) -> float:
    return checks.number(value, what, low=0.0, strict=not allow_zero)


def _finite(value: Any, what: str) -> float:
    return checks.number(value, what)


def _plausible(peak: float, what: str) -> None:
    """Refuse a base acceleration above :data:`MAX_BASE_ACCELERATION`, saying why."""
    if not peak <= MAX_BASE_ACCELERATION:
        raise ScenarioError(
            f"{what} reaches {peak:.3g} m/s² ({peak / STANDARD_GRAVITY:.3g} g): base "
            f"accelerations above {MAX_BASE_ACCELERATION:g} m/s² are refused (no ground motion "
            f"comes near, and the solvers' arithmetic would overflow)")


class Excitation(ABC):
    """What a scenario's ``[excitation]`` table describes: a base motion, at rest at t = 0.

    A concrete subclass declares the class variables ``kind`` and
    ``report_group`` and implements :meth:`base_motion`, :meth:`from_table` and
    :meth:`to_table`; defining it registers it under its kind (a subclass
    without its own ``kind``, such as a shared base, is not registered). The
    one-dimensional motions along x are :class:`Motion` s; :class:`Components`
    combines three of them.
    """

    #: Name used in scenario files (``type = "..."`` of the ``[excitation]`` table).
    kind: ClassVar[str]
    #: How reports group scenarios driven by it: one of :data:`REPORT_GROUPS`.
    report_group: ClassVar[str]
    #: Keys its ``[excitation]`` table may hold besides ``type``.
    table_keys: ClassVar[frozenset[str]] = frozenset()

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "kind" not in cls.__dict__:
            return
        kind, group = cls.kind, getattr(cls, "report_group", None)
        if not isinstance(kind, str) or not kind:
            raise TypeError(f"{cls.__qualname__}.kind must be a non-empty string")
        if group not in REPORT_GROUPS:
            raise TypeError(f"{cls.__qualname__}.report_group must be one of "
                            f"{', '.join(REPORT_GROUPS)}, got {group!r}")
        old = _REGISTRY.get(kind)
        # the same class defined again (a module reloaded) replaces itself
        if old is not None and (old.__module__, old.__qualname__) != (cls.__module__,
                                                                       cls.__qualname__):
            raise TypeError(f"excitation kind {kind!r} is already registered by "
                            f"{old.__module__}.{old.__qualname__}")
        _REGISTRY[kind] = cls

    @abstractmethod
    def base_motion(self) -> BaseMotion:
        """The three-component ground motion this excitation produces."""

    @classmethod
    @abstractmethod
    def from_table(cls, table: Mapping[str, Any], *, source: Path | None = None) -> Excitation:
        """The excitation of an ``[excitation]`` table of this kind.

        Parameters
        ----------
        table : mapping
            The parsed table; its ``type`` key (this class's kind) is ignored.
        source : Path, optional
            Scenario file the table was read from: relative file names in the
            table are resolved against its folder (else the working directory).

        Raises
        ------
        ScenarioError
            Unknown or missing keys, wrong types or invalid values; the message
            names the field.
        """

    @abstractmethod
    def to_table(self) -> dict[str, Any]:
        """The ``[excitation]`` table (``type`` plus fields) that :meth:`from_table` reads back."""

    @classmethod
    def read_fields(cls, table: Mapping[str, Any],
                    required: tuple[str, ...] = ()) -> dict[str, Any]:
        """The fields of an ``[excitation]`` table of this kind, for :meth:`from_table`.

        Returns a copy without ``type``; refuses keys outside ``table_keys`` and
        missing ``required`` ones with a message naming them.
        """
        data = checks.table(table, "[excitation]")
        data.pop("type", None)
        where = f"[excitation] of type {cls.kind!r}"
        checks.no_unknown(data, cls.table_keys, where)
        missing = [k for k in required if k not in data]
        if missing:
            raise ScenarioError(f"{where} needs {' and '.join(map(repr, missing))}")
        return data

    @property
    def end_time(self) -> float:
        """Time after which the base stands still (``inf`` if never)."""
        return self.base_motion().end_time

    @property
    def is_free(self) -> bool:
        """True when the base never moves."""
        return self.base_motion().is_free


class AxialExcitation(Motion, Excitation):
    """An excitation that is one motion along x (every kind but :class:`Components`)."""

    def base_motion(self) -> BaseMotion:
        """The motion along x, the base still along y and z."""
        return BaseMotion(x=self)


def excitation_kinds() -> tuple[str, ...]:
    """Kinds of every registered excitation (their ``type`` in scenario files)."""
    return tuple(_REGISTRY)


def excitation_class(kind: Any) -> type[Excitation]:
    """The excitation class registered under ``kind``.

    Raises
    ------
    ScenarioError
        ``kind`` is not a string or no class has it.
    """
    types = ", ".join(_REGISTRY)
    if not isinstance(kind, str):
        raise ScenarioError(f"[excitation] type must be a string, one of {types}; "
                            f"got {checks.describe(kind)}")
    if kind not in _REGISTRY:
        raise ScenarioError(f"unknown excitation type {kind!r}; types: {types}")
    return _REGISTRY[kind]


def excitation_from_table(table: Any, *, source: Path | None = None) -> Excitation:
    """The excitation of an ``[excitation]`` table, by its ``type`` (default ``"free"``).

    Parameters
    ----------
    table : mapping
        The parsed table.
    source : Path, optional
        Scenario file it was read from (see :meth:`Excitation.from_table`).

    Raises
    ------
    ScenarioError
        Not a table, unknown type, or invalid fields; messages start with
        ``[excitation]``.
    """
    data = checks.table(table, "[excitation]")
    cls = excitation_class(data.get("type", "free"))
    try:
        return cls.from_table(data, source=source)
    except ScenarioError as exc:
        msg = str(exc)
        raise ScenarioError(msg if msg.startswith("[excitation]") else
                            f"[excitation] {msg}") from None


@dataclass(frozen=True)
class Free(AxialExcitation):
    """No base motion (free rocking from an initial tilt)."""

    kind: ClassVar[str] = "free"
    report_group: ClassVar[str] = "free"

    # the motion of an axis that does not move
    acceleration = Still.acceleration
    velocity = Still.velocity
    displacement = Still.displacement
    end_time = Still.end_time
    is_free = Still.is_free

    def scalar_acceleration(self) -> Callable[[float], float]:
        return lambda t: 0.0

    @classmethod
    def from_table(cls, table: Mapping[str, Any], *, source: Path | None = None) -> Free:
        cls.read_fields(table)
        return cls()

    def to_table(self) -> dict[str, Any]:
        return {"type": self.kind}


_PulseT = TypeVar("_PulseT", bound="_Pulse")


@dataclass(frozen=True)
class _Pulse(AxialExcitation):
    """Shared part of the one-sine and one-cosine acceleration pulses.

    Subclasses give the shape through :meth:`acceleration`, :meth:`velocity`
    and :meth:`displacement`; this class holds the fields, validation, timing and
    the (a_p, ω_p) form used by overturning studies.
    """

    frequency: float
    amplitude: float
    cycles: int = 1
    report_group: ClassVar[str] = "pulse"
    table_keys: ClassVar[frozenset[str]] = frozenset(
        {"frequency", "amplitude", "peak_acceleration", "cycles"})

    def __post_init__(self) -> None:
        checks.number(self.frequency, f"{self.kind} frequency", low=0.0, unit="Hz")
        checks.number(self.amplitude, f"{self.kind} amplitude", unit="m")
        checks.integer(self.cycles, f"{self.kind} cycles")
        _plausible(abs(self.acceleration_amplitude), f"{self.kind} peak acceleration A ω²")

    @classmethod
    def from_table(cls, table: Mapping[str, Any], *, source: Path | None = None) -> _Pulse:
        """A pulse from ``frequency`` and one of ``amplitude`` (m) and ``peak_acceleration``."""
        data = cls.read_fields(table, required=("frequency",))
        if ("amplitude" in data) == ("peak_acceleration" in data):
            raise ScenarioError(f"[excitation] of type {cls.kind!r} needs exactly one of "
                                f"'amplitude' (displacement, m) and 'peak_acceleration' "
                                f"(m/s², signed)")
        if "peak_acceleration" in data:
            f = checks.number(data.pop("frequency"), f"{cls.kind} frequency", low=0.0,
                              unit="Hz")
            a = checks.number(data.pop("peak_acceleration"), f"{cls.kind} peak_acceleration",
                              unit="m/s²")
            return cls.from_acceleration(a, 2.0 * math.pi * f, **data)
        return cls(**data)

    def to_table(self) -> dict[str, Any]:
        return {"type": self.kind, "frequency": self.frequency, "amplitude": self.amplitude,
                "cycles": self.cycles}

    @property
    def omega(self) -> float:
        """Circular frequency ω = 2πf."""
        return 2.0 * math.pi * self.frequency

    @property
    def end_time(self) -> float:
        return self.cycles / self.frequency

    @property
    def breakpoints(self) -> tuple[float, ...]:
        return (self.end_time,)

    def _inside(self, t: np.ndarray) -> np.ndarray:
        return (t >= 0) & (t <= self.end_time)

    def peak_acceleration(self, t_end: float = math.inf) -> float:
        return abs(self.amplitude) * self.omega**2 if t_end >= 0 else 0.0

    def _phase(self, t_end: float) -> float:
        """ω · min(t_end, end of the pulse), at least 0: the pulse phase reached by t_end."""
        return self.omega * min(max(t_end, 0.0), self.end_time)

    def peak_velocity(self) -> float:
        """PGV in closed form: the velocity bound of :meth:`motion_bounds` is exact for a pulse."""
        return self.motion_bounds()[1]

    @property
    def acceleration_amplitude(self) -> float:
        """Signed acceleration amplitude a_p = A ω² (m/s²)."""
        return self.amplitude * self.omega**2

    @classmethod
    def from_acceleration(cls: type[_PulseT], a_p: float, omega_p: float,
                          cycles: int = 1) -> _PulseT:
        """The pulse given by its acceleration amplitude a_p and circular frequency ω_p.

        Parameters
        ----------
        a_p : float
            Acceleration amplitude in m/s² (negative reverses the pulse).
        omega_p : float
            Circular frequency ω_p in rad/s (> 0).
        cycles : int
            Number of full cycles.
        """
        w = _finite_positive(omega_p, "pulse circular frequency omega_p")
        a = _finite(a_p, "pulse acceleration amplitude a_p")
        return cls(frequency=w / (2.0 * math.pi), amplitude=a / (w * w), cycles=cycles)


@dataclass(frozen=True)
class SinePulse(_Pulse):
    """One-sine acceleration pulse ü_g = A ω² sin(ωt) for 0 ≤ t ≤ cycles/f, then 0.

    u̇_g = Aω(1 − cos ωt), u_g = A(ωt − sin ωt); after the pulse the base stands
    still, displaced by 2π·cycles·A.

    Parameters
    ----------
    frequency : float
        f in Hz (ω = 2πf).
    amplitude : float
        Displacement amplitude A in m; the peak acceleration is A ω².
        A negative value reverses the pulse.
    cycles : int
        Number of full cycles (default 1).
    """

    kind: ClassVar[str] = "sine-pulse"

    def acceleration(self, t: ArrayLike) -> ArrayLike:
        t = np.asarray(t, float)
        w = self.omega
        return np.where(self._inside(t), self.amplitude * w * w * np.sin(w * t), 0.0)

    def scalar_acceleration(self) -> Callable[[float], float]:
        amp, w, t_end = self.amplitude * self.omega**2, self.omega, self.end_time

        def pulse(t: float) -> float:
            return amp * math.sin(w * t) if 0.0 <= t <= t_end else 0.0
        return pulse

    def velocity(self, t: ArrayLike) -> ArrayLike:
        tc = np.clip(np.asarray(t, float), 0.0, self.end_time)
        w = self.omega
        return self.amplitude * w * (1.0 - np.cos(w * tc))

    def displacement(self, t: ArrayLike) -> ArrayLike:
        t = np.asarray(t, float)
        tc = np.clip(t, 0.0, self.end_time)
        w = self.omega
        # after the pulse the base is at rest (velocity 0), so u stays constant
        return np.where(t < 0, 0.0, self.amplitude * (w * tc - np.sin(w * tc)))

    def motion_bounds(self, t_end: float = math.inf) -> tuple[float, float]:
        """Exact peaks: u_g grows monotonically; u̇_g peaks at 2Aω each half cycle."""
        ph, a = self._phase(t_end), abs(self.amplitude)
        return a * (ph - math.sin(ph)), a * self.omega * (2.0 if ph >= math.pi else
                                                           1.0 - math.cos(ph))


@dataclass(frozen=True)
class CosinePulse(_Pulse):
    """One-cosine acceleration pulse ü_g = A ω² cos(ωt) for 0 ≤ t ≤ cycles/f, then 0.

    The acceleration jumps to its peak at t = 0, but the base still starts from
    rest: u̇_g = A ω sin(ωt) and u_g = A (1 − cos ωt) are the exact integrals from
    u̇_g(0) = u_g(0) = 0. After the pulse the base stands still at its start
    position (u̇_g = u_g = 0), unlike the one-sine pulse which displaces it.

    Parameters
    ----------
    frequency : float
        f in Hz (ω = 2πf).
    amplitude : float
        Displacement amplitude A in m; the peak acceleration is A ω² and the peak
        displacement 2A. A negative value reverses the pulse.
    cycles : int
        Number of full cycles (default 1).
    """

    kind: ClassVar[str] = "cosine-pulse"

    def acceleration(self, t: ArrayLike) -> ArrayLike:
        t = np.asarray(t, float)
        w = self.omega
        return np.where(self._inside(t), self.amplitude * w * w * np.cos(w * t), 0.0)

    def scalar_acceleration(self) -> Callable[[float], float]:
        amp, w, t_end = self.amplitude * self.omega**2, self.omega, self.end_time

        def cos_pulse(t: float) -> float:
            return amp * math.cos(w * t) if 0.0 <= t <= t_end else 0.0
        return cos_pulse

    def velocity(self, t: ArrayLike) -> ArrayLike:
        t = np.asarray(t, float)
        w = self.omega
        return np.where(self._inside(t), self.amplitude * w * np.sin(w * t), 0.0)

    def displacement(self, t: ArrayLike) -> ArrayLike:
        t = np.asarray(t, float)
        w = self.omega
        return np.where(self._inside(t), self.amplitude * (1.0 - np.cos(w * t)), 0.0)

    def motion_bounds(self, t_end: float = math.inf) -> tuple[float, float]:
        """Exact peaks: 2A at each half cycle, Aω at each quarter cycle."""
        ph, a = self._phase(t_end), abs(self.amplitude)
        return (a * (2.0 if ph >= math.pi else 1.0 - math.cos(ph)),
                a * self.omega * (1.0 if ph >= 0.5 * math.pi else math.sin(ph)))


@dataclass(frozen=True)
class Sinusoid(AxialExcitation):
    """Harmonic displacement u_g = A sin(ωt)·w(t) with smooth sin² ramps.

    Parameters
    ----------
    frequency : float
        f in Hz.
    amplitude : float
        Displacement amplitude A in m (peak acceleration ≈ A ω²).
    duration : float or None
        Length of the motion in s. ``None`` means it lasts the whole scenario
        with no ramp-down. With a duration, the window also ramps down over the
        last ``ramp_cycles`` cycles so that the base ends at rest.
    ramp_cycles : float
        Length of the sin² ramp in cycles (default 1). ``0`` gives an impulsive
        start (u̇_g(0) = Aω); use it only when a study asks for it.
    """

    frequency: float
    amplitude: float
    duration: float | None = None
    ramp_cycles: float = 1.0
    kind: ClassVar[str] = "sinusoid"
    report_group: ClassVar[str] = "sine"
    table_keys: ClassVar[frozenset[str]] = frozenset(
        {"frequency", "amplitude", "duration", "ramp_cycles"})

    def __post_init__(self) -> None:
        checks.number(self.frequency, "sinusoid frequency", low=0.0, unit="Hz")
        checks.number(self.amplitude, "sinusoid amplitude", unit="m")
        checks.number(self.ramp_cycles, "sinusoid ramp_cycles", low=0.0, strict=False)
        if self.duration is not None:
            checks.number(self.duration, "sinusoid duration", low=0.0, unit="s")
            if 2 * self.ramp_time > self.duration + 1e-12:
                raise ScenarioError(
                    f"sinusoid duration {self.duration} s is shorter than its two ramps "
                    f"({2 * self.ramp_time:g} s)"
                )
        _plausible(abs(self.amplitude) * self.omega**2, "sinusoid acceleration A ω²")

    @property
    def omega(self) -> float:
        """Circular frequency ω = 2πf."""
        return 2.0 * math.pi * self.frequency

    @property
    def ramp_time(self) -> float:
        """Length of each ramp in s."""
        return self.ramp_cycles / self.frequency

    @property
    def end_time(self) -> float:
        return math.inf if self.duration is None else float(self.duration)

    @property
    def breakpoints(self) -> tuple[float, ...]:
        pts = [self.ramp_time] if self.ramp_time > 0 else []
        if self.duration is not None:
            pts += [self.duration - self.ramp_time, self.duration]
        return tuple(sorted(set(pts)))

    def _window(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Window w and its first two derivatives."""
        w = np.ones_like(t)
        dw = np.zeros_like(t)
        ddw = np.zeros_like(t)
        tr = self.ramp_time
        if tr > 0:
            k = math.pi / tr
            ramps = [(t < tr, t, 1.0)]
            if self.duration is not None:
                ramps.append((t > self.duration - tr, self.duration - t, -1.0))
            for mask, s, sign in ramps:
                # w = sin²(πs/(2 tr)) = (1 - cos(ks))/2 on a ramp, s measured from its foot
                w = np.where(mask, 0.5 * (1 - np.cos(k * s)), w)
                dw = np.where(mask, sign * 0.5 * k * np.sin(k * s), dw)
                ddw = np.where(mask, 0.5 * k * k * np.cos(k * s), ddw)
        outside = (t < 0) | (t > self.end_time)
        return (np.where(outside, 0.0, w), np.where(outside, 0.0, dw), np.where(outside, 0.0, ddw))

    def displacement(self, t: ArrayLike) -> ArrayLike:
        t = np.asarray(t, float)
        w, _, _ = self._window(t)
        return self.amplitude * np.sin(self.omega * t) * w

    def velocity(self, t: ArrayLike) -> ArrayLike:
        t = np.asarray(t, float)
        w, dw, _ = self._window(t)
        om = self.omega
        return self.amplitude * (om * np.cos(om * t) * w + np.sin(om * t) * dw)

    def acceleration(self, t: ArrayLike) -> ArrayLike:
        t = np.asarray(t, float)
        w, dw, ddw = self._window(t)
        om = self.omega
        s, c = np.sin(om * t), np.cos(om * t)
        return self.amplitude * (-om * om * s * w + 2 * om * c * dw + s * ddw)

    def peak_acceleration(self, t_end: float = math.inf) -> float:
        if self.duration is None:  # periodic after the ramp: one more cycle holds every peak
            t_end = min(t_end, self.ramp_time + 1.0 / self.frequency)
        return super().peak_acceleration(t_end)

    def motion_bounds(self, t_end: float = math.inf) -> tuple[float, float]:
        """|u_g| ≤ A, and |u̇_g| ≤ A ω unless the ramps are shorter than 0.35 cycles.

        u̇_g = A (ω cos ωt · w + sin ωt · w'), so |u̇_g| ≤ A sqrt(ω² w² + w'²).
        On a ramp w = (1 − cos ks)/2 and |w'| = (k/2) sin ks with k = π/t_ramp;
        in y = 1 − cos ks ∈ [0, 2] the square root's argument is
        (ω² − k²) y²/4 + k² y/2, largest at y = 2 (i.e. ω², the steady
        amplitude) when k² ≤ 2ω², and k⁴ / (4 (k² − ω²)) otherwise. Both
        bounds are reached once the full amplitude has lasted a quarter cycle.
        """
        if t_end <= 0:
            return 0.0, 0.0
        a, om = abs(self.amplitude), self.omega
        k2 = (math.pi / self.ramp_time) ** 2 if self.ramp_time > 0 else 0.0
        return a, a * (om if k2 <= 2.0 * om * om else 0.5 * k2 / math.sqrt(k2 - om * om))

    def scalar_acceleration(self) -> Callable[[float], float]:
        amp, w, tr, t_end = self.amplitude, self.omega, self.ramp_time, self.end_time
        has_end = self.duration is not None
        k = math.pi / tr if tr > 0 else 0.0

        def sinusoid(t: float) -> float:
            if t < 0.0 or t > t_end:
                return 0.0
            win, dwin, ddwin = 1.0, 0.0, 0.0
            if tr > 0:
                if has_end and t > t_end - tr:  # ramp down (takes precedence, as in _window)
                    x, sign = t_end - t, -1.0
                elif t < tr:
                    x, sign = t, 1.0
                else:
                    x = -1.0
                if x >= 0.0:
                    cx, sx = math.cos(k * x), math.sin(k * x)
                    win, dwin, ddwin = 0.5 * (1.0 - cx), sign * 0.5 * k * sx, 0.5 * k * k * cx
            s, c = math.sin(w * t), math.cos(w * t)
            return amp * (-w * w * s * win + 2.0 * w * c * dwin + s * ddwin)
        return sinusoid

    @classmethod
    def from_table(cls, table: Mapping[str, Any], *, source: Path | None = None) -> Sinusoid:
        return cls(**cls.read_fields(table, required=("frequency", "amplitude")))

    def to_table(self) -> dict[str, Any]:
        d: dict[str, Any] = {"type": self.kind, "frequency": self.frequency,
                             "amplitude": self.amplitude, "ramp_cycles": self.ramp_cycles}
        if self.duration is not None:
            d["duration"] = self.duration
        return d


@dataclass(frozen=True)
class Record(AxialExcitation):
    """A recorded accelerogram, linearly interpolated and integrated exactly.

    The acceleration between samples is linear; velocity and displacement are its
    exact integrals from rest. A constant acceleration offset (a linear baseline
    correction of the velocity) is removed so that the base ends at rest at the
    last sample; after it the base stands still.

    Parameters
    ----------
    times : array_like
        Sample times in s, strictly increasing, starting at 0 or later
        (a sample ``(0, 0)`` is prepended when the first time is > 0).
    accelerations : array_like
        Accelerations in m/s² (before ``scale``).
    scale : float
        Factor applied to the accelerations.
    source : str
        File the record came from (kept for scenario files); empty if inline.
    units : str
        Units of the source file (``"g"`` or ``"m/s2"``), kept for round trips.
    """

    times: np.ndarray
    accelerations: np.ndarray
    scale: float = 1.0
    source: str = ""
    units: str = "m/s2"
    kind: ClassVar[str] = "record"
    report_group: ClassVar[str] = "record"
    table_keys: ClassVar[frozenset[str]] = frozenset(
        {"file", "units", "scale", "times", "accelerations"})
    _tab: tuple[np.ndarray, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        t = checks.number_array(self.times, "record times")
        a = checks.number_array(self.accelerations, "record accelerations")
        if t.size != a.size or t.size < 2:
            raise ScenarioError(
                f"record needs matching time and acceleration arrays of at least 2 samples, "
                f"got {t.size} and {a.size}"
            )
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(a))):
            raise ScenarioError("record contains NaN or infinite values")
        if np.any(np.diff(t) <= 0) or t[0] < 0:
            raise ScenarioError("record times must be >= 0 and strictly increasing")
        steps = np.diff(t)
        k = int(np.argmin(steps))
        if steps[k] < MIN_RECORD_STEP:
            raise ScenarioError(
                f"record times: samples {k + 1} and {k + 2} are {steps[k]:.3g} s apart; the "
                f"shortest interval accepted is {MIN_RECORD_STEP:g} s (1 MHz; times are in s)")
        if t[-1] > MAX_RECORD_SPAN:
            raise ScenarioError(
                f"record times reach {t[-1]:.3g} s; a record may last at most "
                f"{MAX_RECORD_SPAN:g} s (a day; times are in s)")
        scale = checks.number(self.scale, "record scale")
        checks.text(self.source, "record source")
        if self.units not in _UNITS:
            raise ScenarioError(f"record units must be 'g' or 'm/s2', got "
                                f"{checks.describe(self.units)}")
        if t[0] > 0:
            t = np.concatenate([[0.0], t])
            a = np.concatenate([[0.0], a])
        object.__setattr__(self, "times", t)
        object.__setattr__(self, "accelerations", a)
        # finite samples can overflow once scaled and integrated (1e308, -1e308, ...) and
        # would stall the solvers: refused before anything is computed from them
        with np.errstate(over="ignore"):
            _plausible(float(np.max(np.abs(a))) * abs(scale), "record acceleration (× scale)")
        with np.errstate(over="ignore", invalid="ignore"):
            a = a * scale
            dt = np.diff(t)
            # exact velocity of the piecewise-linear acceleration, then the constant
            # offset c that brings the velocity back to zero at the last sample
            v_raw = np.concatenate([[0.0], np.cumsum(0.5 * (a[:-1] + a[1:]) * dt)])
            c = v_raw[-1] / t[-1]
            a = a - c
            v = np.concatenate([[0.0], np.cumsum(0.5 * (a[:-1] + a[1:]) * dt)])
            u = np.concatenate([[0.0], np.cumsum(v[:-1] * dt
                                                 + dt * dt * (2 * a[:-1] + a[1:]) / 6)])
        if not all(np.all(np.isfinite(x)) for x in (v, u)):
            raise ScenarioError(
                "record velocity or displacement overflows: the record is too long for its "
                "accelerations")
        object.__setattr__(self, "_tab", (t, a, v, u))

    def __eq__(self, other: object) -> bool:
        # the generated __eq__ compares the arrays element-wise and cannot tell a bool
        if not isinstance(other, Record):
            return NotImplemented
        return ((self.scale, self.source, self.units) == (other.scale, other.source, other.units)
                and np.array_equal(self.times, other.times)
                and np.array_equal(self.accelerations, other.accelerations))

    def __hash__(self) -> int:
        return hash((self.times.tobytes(), self.accelerations.tobytes(), self.scale,
                     self.source, self.units))

    @property
    def end_time(self) -> float:
        return float(self.times[-1])

    @property
    def breakpoints(self) -> tuple[float, ...]:
        return tuple(float(x) for x in self.times[1:])

    def _locate(self, t: ArrayLike) -> tuple[np.ndarray, ...]:
        tt, a, v, u = self._tab
        t = np.asarray(t, float)
        tc = np.clip(t, 0.0, tt[-1])
        k = np.clip(np.searchsorted(tt, tc, side="right") - 1, 0, tt.size - 2)
        tau = tc - tt[k]
        slope = (a[k + 1] - a[k]) / (tt[k + 1] - tt[k])
        return t, k, tau, slope

    def acceleration(self, t: ArrayLike) -> ArrayLike:
        t, k, tau, slope = self._locate(t)
        a = self._tab[1]
        return np.where((t < 0) | (t > self.end_time), 0.0, a[k] + slope * tau)

    def velocity(self, t: ArrayLike) -> ArrayLike:
        t, k, tau, slope = self._locate(t)
        _, a, v, _ = self._tab
        return np.where(t < 0, 0.0, v[k] + a[k] * tau + 0.5 * slope * tau**2)

    def displacement(self, t: ArrayLike) -> ArrayLike:
        t, k, tau, slope = self._locate(t)
        _, a, v, u = self._tab
        return np.where(
            t < 0, 0.0, u[k] + v[k] * tau + 0.5 * a[k] * tau**2 + slope * tau**3 / 6
        )

    def peak_acceleration(self, t_end: float = math.inf) -> float:
        tt, a, _, _ = self._tab
        return float(np.max(np.abs(a[tt <= t_end]))) if np.any(tt <= t_end) else 0.0

    def peak_velocity(self) -> float:
        """PGV, exact: the velocity is quadratic between samples, with an extremum inside an
        interval where the acceleration changes sign, at v_k − a_k² Δt / (2 Δa)."""
        t, a, v, _ = self._tab
        da, dt = np.diff(a), np.diff(t)
        inner = a[:-1] * a[1:] < 0.0
        # a changes sign strictly inside the interval, so da != 0 there
        v_inner = v[:-1][inner] - a[:-1][inner] ** 2 * dt[inner] / (2.0 * da[inner])
        return float(max(np.max(np.abs(v)), np.max(np.abs(v_inner), initial=0.0)))

    def motion_bounds(self, t_end: float = math.inf) -> tuple[float, float]:
        """Bounds from the tabulated samples, valid between them too.

        Over a sample interval Δt the velocity moves from v_k by at most
        max |a| Δt, and the displacement from u_k by at most that velocity
        bound times Δt (the cubic between samples never leaves these bounds).
        """
        tt, a, v, u = self._tab
        # the intervals that start before t_end
        n = min(int(np.searchsorted(tt, t_end, side="left")), tt.size - 1)
        if n == 0:
            return 0.0, 0.0
        dt = np.diff(tt[:n + 1])
        vb = np.abs(v[:n]) + np.maximum(np.abs(a[:n]), np.abs(a[1:n + 1])) * dt
        ub = np.abs(u[:n]) + vb * dt
        return float(ub.max()), float(vb.max())

    def scalar_acceleration(self) -> Callable[[float], float]:
        times = np.asarray(self.times, dtype=float)
        acc = np.asarray(self.acceleration(times), dtype=float)
        tl, al = times.tolist(), acc.tolist()
        slopes = (np.diff(acc) / np.diff(times)).tolist()
        last, t_end = len(tl) - 2, float(times[-1])

        def record(t: float) -> float:
            if t < 0.0 or t > t_end:
                return 0.0
            i = min(max(bisect_right(tl, t) - 1, 0), last)
            return al[i] + slopes[i] * (t - tl[i])
        return record

    @classmethod
    def from_table(cls, table: Mapping[str, Any], *, source: Path | None = None) -> Record:
        """A record from ``file`` (CSV or PEER AT2), or inline ``times`` and ``accelerations``.

        ``units`` (``"g"`` or ``"m/s2"``) applies to a file; inline accelerations
        are in m/s². ``scale`` multiplies the accelerations. A table with ``set``
        names a record of an installed record set instead, read by the reader
        that :mod:`rockbench.scenarios.record_sets` registers
        (:func:`register_set_reader`).
        """
        if isinstance(table, Mapping) and ("set" in table or "record" in table):
            if _SET_READER is None:
                raise ScenarioError("[excitation] names a record set, but no record-set reader "
                                    "is registered (import rockbench.scenarios)")
            return _SET_READER(table, source=source)
        data = cls.read_fields(table)
        scale = data.get("scale", 1.0)
        checks.number(scale, "record scale")
        if "file" in data:
            if "times" in data or "accelerations" in data:
                raise ScenarioError("[excitation] of type 'record' takes either 'file' or "
                                    "'times'/'accelerations'")
            src = checks.text(data["file"], "record file")
            units = data.get("units")
            if units is not None and units not in _UNITS:
                raise ScenarioError(f"record units must be 'g' or 'm/s2', got "
                                    f"{checks.describe(units)}")
            path = Path(src)
            if not path.is_absolute() and source is not None:
                path = source.parent / path
            return cls.from_file(path, units=units, scale=scale, source=src)
        if "times" not in data or "accelerations" not in data:
            raise ScenarioError("[excitation] of type 'record' needs 'file' or both 'times' "
                                "and 'accelerations'")
        if data.get("units", "m/s2") != "m/s2":
            raise ScenarioError(f"record units apply to a 'file' only: inline accelerations are "
                                f"in m/s², got units = {checks.describe(data['units'])}")
        return cls(data["times"], data["accelerations"], scale=scale)

    def to_table(self) -> dict[str, Any]:
        if self.source:
            return {"type": self.kind, "file": self.source, "units": self.units,
                    "scale": self.scale}
        return {"type": self.kind, "times": self.times.tolist(),
                "accelerations": self.accelerations.tolist(), "scale": self.scale}

    @classmethod
    def from_file(
        cls, path: str | Path, *, units: str | None = None, scale: float = 1.0,
        source: str | None = None,
    ) -> Record:
        """Read a PEER NGA ``.AT2`` file or a two-column CSV ``t,acc``.

        Parameters
        ----------
        path : str or Path
            The file. ``.at2`` (any case) selects the PEER reader.
        units : {"g", "m/s2"}, optional
            Units of the file's accelerations; default ``"g"`` for AT2 and
            ``"m/s2"`` for CSV.
        scale : float
            Extra factor on the accelerations.
        source : str, optional
            Path to store in scenario files (default: ``path`` as given).
        """
        path = Path(path)
        is_at2 = path.suffix.lower() == ".at2"
        units = units or ("g" if is_at2 else "m/s2")
        if units not in _UNITS:
            raise ScenarioError(f"record units must be 'g' or 'm/s2', got "
                                f"{checks.describe(units)}")
        checks.number(scale, "record scale")
        try:
            raw = path.read_bytes()
        except OSError as exc:
            raise ScenarioError(f"cannot read record file {str(path)!r}: "
                                f"{exc.strerror or exc}") from None
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise ScenarioError(f"{path}: not a text record file (byte 0x{raw[exc.start]:02x} "
                                f"at offset {exc.start} is not UTF-8)") from None
        t, a = _parse_at2(text, path) if is_at2 else _parse_csv(text, path)
        if units == "g":
            with np.errstate(over="ignore"):  # an overflow is refused by the checks below
                a = a * STANDARD_GRAVITY
        try:
            return cls(t, a, scale=scale, source=str(source if source is not None else path),
                       units=units)
        except ScenarioError as exc:
            raise ScenarioError(f"{path}: {exc}") from None


#: Units a record file may give its accelerations in.
_UNITS = ("g", "m/s2")

#: Reads a ``type = "record"`` table that names a record of a set (``set``,
#: ``record``): registered by :mod:`rockbench.scenarios.record_sets`, which builds
#: on this module (so this module cannot import it).
_SET_READER: Callable[..., Record] | None = None


def register_set_reader(reader: Callable[..., Record]) -> None:
    """Register the reader of record-set tables (:mod:`rockbench.scenarios.record_sets`)."""
    global _SET_READER
    _SET_READER = reader


def _short(line: str, limit: int = 60) -> str:
    """repr of a file line, cut to ``limit`` characters for a one-line message."""
    r = repr(line)
    return r if len(r) <= limit else r[:limit - 4] + "..." + r[0]


def _parse_csv(text: str, path: Path) -> tuple[np.ndarray, np.ndarray]:
    rows: list[list[float]] = []
    for ln, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        parts = [p for p in s.replace(";", ",").replace("\t", ",").split(",") if p.strip()]
        try:
            vals = [float(p) for p in parts]
        except ValueError:
            if not rows:  # a header line
                continue
            raise ScenarioError(f"{path}: line {ln} is not two numbers: {_short(s)}") from None
        if len(vals) != 2:
            raise ScenarioError(f"{path}: line {ln} must have 2 columns (t, acc), has {len(vals)}")
        rows.append(vals)
    if len(rows) < 2:
        raise ScenarioError(f"{path}: no record data found (expected CSV rows 't,acc')")
    arr = np.asarray(rows)
    return arr[:, 0], arr[:, 1]


def _parse_at2(text: str, path: Path) -> tuple[np.ndarray, np.ndarray]:
    lines = text.splitlines()
    if len(lines) < 5:
        raise ScenarioError(f"{path}: too short for a PEER AT2 file (4 header lines + data)")
    header = lines[3].upper()
    m_n = re.search(r"NPTS\s*=?\s*(\d+)", header)
    m_dt = re.search(r"DT\s*=?\s*([0-9.Ee+-]+)", header)
    if not (m_n and m_dt):
        raise ScenarioError(f"{path}: line 4 must give NPTS and DT, got {_short(lines[3].strip())}")
    n = int(m_n.group(1))
    try:
        dt = float(m_dt.group(1))
    except ValueError:
        dt = math.nan
    if not (math.isfinite(dt) and dt > 0):
        raise ScenarioError(f"{path}: line 4 must give DT as a finite number of seconds > 0, "
                            f"got DT={m_dt.group(1)}")
    try:
        vals = np.array([float(x) for ln in lines[4:] for x in ln.split()])
    except ValueError as exc:
        raise ScenarioError(f"{path}: non-numeric data ({_short(str(exc), 80)})") from None
    if vals.size < n:
        raise ScenarioError(f"{path}: header says NPTS={n} but {vals.size} values found")
    return dt * np.arange(n), vals[:n]


@dataclass(frozen=True)
class TiltTable(AxialExcitation):
    """A tilting table, as the base acceleration ramp that loads the blocks alike.

    ü_g(t) = −direction · rate · g · (t − delay) for t ≥ delay (the base is
    still before, so that a scene can settle on its contacts): in the base's frame every
    block then feels its weight plus a horizontal inertial force α(t) · m g
    toward ``direction`` · x̂, with α(t) = rate · (t − delay); that is gravity tilted by
    φ = atan(α) (and scaled by sqrt(1 + α²), which changes no static
    threshold of rigid blocks). A table tilted at φ is thus the moment α(t) =
    tan φ; the limit-analysis collapse factor α is the tilting-table
    collapse angle atan(α). Velocity and displacement are the exact
    integrals rate · g · s²/2 and rate · g · s³/6 (times −direction, s = t − delay).

    Parameters
    ----------
    rate : float
        dα/dt in 1/s (the tilt angle grows at rate · cos²φ rad/s); slow
        enough to be quasi-static (see :mod:`rockbench.studies.tilting`).
    direction : {+1, -1}
        +1 leans the blocks toward +x (the base accelerates toward −x).
    gravity : float
        The g that α is a fraction of (m/s²): the scenario's.
    delay : float
        Time before the ramp starts (s).
    """

    rate: float
    direction: int = 1
    gravity: float = STANDARD_GRAVITY
    delay: float = 0.0
    kind: ClassVar[str] = "tilt-table"
    report_group: ClassVar[str] = "tilt"
    table_keys: ClassVar[frozenset[str]] = frozenset({"rate", "direction", "gravity",
                                                                    "delay"})

    def __post_init__(self) -> None:
        checks.number(self.rate, "tilt-table rate", low=0.0, unit="1/s")
        if self.direction not in (1, -1) or isinstance(self.direction, bool):
            raise ScenarioError(f"tilt-table direction must be 1 or -1, got "
                                f"{checks.describe(self.direction)}")
        checks.number(self.gravity, "tilt-table gravity", low=0.0, unit="m/s²")
        checks.number(self.delay, "tilt-table delay", low=0.0, strict=False, unit="s")

    @property
    def _k(self) -> float:
        """−direction · rate · g: ü_g = k t."""
        return -self.direction * self.rate * self.gravity

    def load_factor(self, t: ArrayLike) -> ArrayLike:
        """α(t) = rate · (t − delay), 0 before: the tangent of the equivalent tilt angle."""
        return self.rate * self._ramp(t)

    def _ramp(self, t: ArrayLike) -> np.ndarray:
        return np.maximum(np.asarray(t, float) - self.delay, 0.0)

    def acceleration(self, t: ArrayLike) -> ArrayLike:
        return self._k * self._ramp(t)

    def velocity(self, t: ArrayLike) -> ArrayLike:
        return 0.5 * self._k * self._ramp(t) ** 2

    def displacement(self, t: ArrayLike) -> ArrayLike:
        return self._k / 6.0 * self._ramp(t) ** 3

    @property
    def breakpoints(self) -> tuple[float, ...]:
        return (self.delay,) if self.delay > 0 else ()

    def scalar_acceleration(self) -> Callable[[float], float]:
        k, t0 = self._k, self.delay
        return lambda t: k * (t - t0) if t > t0 else 0.0

    def peak_acceleration(self, t_end: float = math.inf) -> float:
        return abs(self._k) * max(t_end - self.delay, 0.0)

    def motion_bounds(self, t_end: float = math.inf) -> tuple[float, float]:
        """|u_g| and |u̇_g| at ``t_end`` (both grow monotonically)."""
        t = max(t_end - self.delay, 0.0)
        return abs(self._k) * t**3 / 6.0, 0.5 * abs(self._k) * t * t

    @classmethod
    def from_table(cls, table: Mapping[str, Any], *, source: Path | None = None) -> TiltTable:
        return cls(**cls.read_fields(table, required=("rate",)))

    def to_table(self) -> dict[str, Any]:
        return {"type": self.kind, "rate": self.rate, "direction": self.direction,
                "gravity": self.gravity, "delay": self.delay}


@dataclass(frozen=True)
class Components(Excitation):
    """Three one-dimensional motions at once: x and y horizontal, z vertical.

    Each component is any :class:`Motion` (a pulse, a sinusoid, a record, ...)
    given as its own table, ``[excitation.x]``, ``[excitation.y]``,
    ``[excitation.z]``; a component left out stands still::

        [excitation]
        type = "components"
        [excitation.x]
        type = "record"
        file = "RSN6_IMPVALL.I_I-ELC180.AT2"
        [excitation.z]
        type = "record"
        file = "RSN6_IMPVALL.I_I-ELC-UP.AT2"

    Parameters
    ----------
    x, y, z : Motion
        The motion along each axis (default: none).
    """

    x: AxialExcitation = field(default_factory=Free)
    y: AxialExcitation = field(default_factory=Free)
    z: AxialExcitation = field(default_factory=Free)
    kind: ClassVar[str] = "components"
    report_group: ClassVar[str] = "record"
    table_keys: ClassVar[frozenset[str]] = frozenset({"x", "y", "z"})

    def __post_init__(self) -> None:
        for axis in ("x", "y", "z"):
            if not isinstance(getattr(self, axis), AxialExcitation):
                raise ScenarioError(f"[excitation.{axis}] must be a one-dimensional motion "
                                    f"(a pulse, a sinusoid, a record, ...), got "
                                    f"{checks.describe(getattr(self, axis))}")

    def base_motion(self) -> BaseMotion:
        return BaseMotion(self.x, self.y, self.z)

    @property
    def group(self) -> str:
        """The report group of its first moving component (x, then y, then z)."""
        moving = [c for c in (self.x, self.y, self.z) if not c.is_free]
        return moving[0].report_group if moving else Free.report_group

    @classmethod
    def from_table(cls, table: Mapping[str, Any], *, source: Path | None = None) -> Components:
        data = cls.read_fields(table)
        parts = {}
        for axis, sub in data.items():
            try:
                motion = excitation_from_table(sub, source=source)
            except ScenarioError as exc:
                raise ScenarioError(str(exc).replace("[excitation]", f"[excitation.{axis}]", 1)
                                    ) from None
            if not isinstance(motion, AxialExcitation):
                raise ScenarioError(f"[excitation.{axis}] must be a one-dimensional motion, "
                                    f"not {motion.kind!r}")
            parts[axis] = motion
        return cls(**parts)

    def to_table(self) -> dict[str, Any]:
        out: dict[str, Any] = {"type": self.kind}
        for axis in ("x", "y", "z"):
            c = getattr(self, axis)
            if not c.is_free:
                out[axis] = c.to_table()
        return out
