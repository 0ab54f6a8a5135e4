"""The three-component base motion that every excitation produces.

A :class:`BaseMotion` holds one one-dimensional :class:`Motion` per axis (x and
y horizontal, z vertical; :class:`Still` where the base does not move along it).
Each component gives acceleration, velocity and displacement as exact
integrals of each other, starting from rest, so the vector motion is exactly
consistent too. Engines receive it through their base class
(:class:`rockbench.engines.drive.BaseDrive`) and only apply it; the analytic
models read the components their model covers.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from rockbench.errors import ScenarioError

__all__ = ["Motion", "Still", "BaseMotion", "AXES"]

#: The axes of the base motion, in the order of every (..., 3) array.
AXES = ("x", "y", "z")

ArrayLike = float | np.ndarray


class Motion(ABC):
    """A base motion u(t) along one axis, at rest at t = 0 (one component).

    Subclasses implement :meth:`acceleration`, :meth:`velocity` and
    :meth:`displacement` as exact integrals of each other; times are scalars
    or arrays and the results have their shape.
    """

    def scalar_acceleration(self) -> Callable[[float], float]:
        """ü_g(t) for one float time, returning a float: what ODE right-hand sides call.

        This default wraps :meth:`acceleration`; the built-in excitations return
        plain-``math`` formulas instead, since a vectorised call on one float
        costs tens of µs and dominates long forced integrations.
        """
        return lambda t: float(self.acceleration(t))

    @abstractmethod
    def acceleration(self, t: ArrayLike) -> ArrayLike:
        """Base acceleration ü_g(t) in m/s²."""

    @abstractmethod
    def velocity(self, t: ArrayLike) -> ArrayLike:
        """Base velocity u̇_g(t) in m/s (exact integral of the acceleration)."""

    @abstractmethod
    def displacement(self, t: ArrayLike) -> ArrayLike:
        """Base displacement u_g(t) in m (exact integral of the velocity)."""

    @property
    def end_time(self) -> float:
        """Time after which the base stands still (``inf`` if never)."""
        return math.inf

    @property
    def breakpoints(self) -> tuple[float, ...]:
        """Times where ü_g is not smooth; ODE integrators restart there."""
        return ()

    @property
    def is_free(self) -> bool:
        """True when the base never moves."""
        return False

    def peak_acceleration(self, t_end: float = math.inf) -> float:
        """Largest |ü_g| over [0, t_end] (sampled finely)."""
        t_end = min(t_end, self.end_time if math.isfinite(self.end_time) else t_end)
        if not math.isfinite(t_end) or t_end <= 0:
            return 0.0
        t = np.linspace(0.0, t_end, 20001)
        return float(np.max(np.abs(self.acceleration(t))))

    def peak_velocity(self) -> float:
        """PGV: the largest |u̇_g| over the whole motion (m/s).

        Records and pulses give it exactly; this default samples the velocity
        finely over the motion.

        Raises
        ------
        ScenarioError
            For a motion that never ends (no peak over a finite time).
        """
        if not math.isfinite(self.end_time):
            raise ScenarioError(f"the PGV of a {type(self).__name__} motion, which never "
                                "ends, is not defined")
        if self.end_time <= 0:
            return 0.0
        t = np.linspace(0.0, self.end_time, 20001)
        return float(np.max(np.abs(self.velocity(t))))

    def motion_bounds(self, t_end: float = math.inf) -> tuple[float, float]:
        """Upper bounds on |u_g| and |u̇_g| over [0, t_end] (m, m/s).

        What a scene needs to size its ground and what the engine watchdog
        needs to bound speeds. Built-in excitations give them in closed form
        (exact for pulses); this default samples the motion finely.
        """
        t_end = min(t_end, self.end_time)
        if t_end <= 0:
            return 0.0, 0.0
        if not math.isfinite(t_end):
            raise ValueError(f"{type(self).__name__} never ends: give a finite t_end")
        t = np.linspace(0.0, t_end, 20001)
        return (float(np.max(np.abs(self.displacement(t)))),
                float(np.max(np.abs(self.velocity(t)))))




class Still(Motion):
    """No motion along an axis (a :class:`BaseMotion` component the base does not move along)."""

    def acceleration(self, t: ArrayLike) -> ArrayLike:
        return np.zeros_like(np.asarray(t, float)) + 0.0

    velocity = acceleration
    displacement = acceleration

    @property
    def end_time(self) -> float:
        return 0.0

    @property
    def is_free(self) -> bool:
        return True

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Still)

    def __hash__(self) -> int:
        return hash(Still)


@dataclass(frozen=True)
class BaseMotion:
    """Ground motion along x, y (horizontal) and z (vertical), at rest at t = 0.

    Parameters
    ----------
    x, y, z : Motion
        The motion along each axis (m, m/s, m/s²); default :class:`Still`.
    """

    x: Motion = field(default_factory=Still)
    y: Motion = field(default_factory=Still)
    z: Motion = field(default_factory=Still)

    @property
    def components(self) -> tuple[Motion, Motion, Motion]:
        """(x, y, z)."""
        return (self.x, self.y, self.z)

    @property
    def moving(self) -> tuple[Motion, ...]:
        """The components along which the base moves, in x, y, z order."""
        return tuple(c for c in self.components if not c.is_free)

    @property
    def axes(self) -> tuple[str, ...]:
        """The axes along which the base moves, e.g. ``("x",)`` or ``("x", "z")``."""
        return tuple(a for a, c in zip(AXES, self.components, strict=True) if not c.is_free)

    @property
    def is_free(self) -> bool:
        """True when the base never moves."""
        return not self.axes

    @property
    def end_time(self) -> float:
        """Time after which the base stands still (``inf`` if never; 0 if it never moves)."""
        return max((c.end_time for c in self.moving), default=0.0)

    @property
    def breakpoints(self) -> tuple[float, ...]:
        """Times where any component's acceleration is not smooth, sorted."""
        return tuple(sorted({b for c in self.moving for b in c.breakpoints}))

    def _stack(self, fn: Callable[[Motion], ArrayLike], t: ArrayLike) -> np.ndarray:
        t = np.asarray(t, float)
        return np.stack([np.asarray(fn(c), float) * np.ones_like(t) for c in self.components],
                        axis=-1)

    def acceleration(self, t: np.ndarray | float) -> np.ndarray:
        """Base acceleration (m/s²), shape ``t.shape + (3,)``."""
        return self._stack(lambda c: c.acceleration(t), t)

    def velocity(self, t: np.ndarray | float) -> np.ndarray:
        """Base velocity (m/s), the exact integral of the acceleration, ``t.shape + (3,)``."""
        return self._stack(lambda c: c.velocity(t), t)

    def displacement(self, t: np.ndarray | float) -> np.ndarray:
        """Base displacement (m), the exact integral of the velocity, ``t.shape + (3,)``."""
        return self._stack(lambda c: c.displacement(t), t)

    def motion_bounds(self, t_end: float = math.inf) -> tuple[float, float]:
        """Upper bounds on the base's travel |u| and speed |u̇| over [0, t_end] (m, m/s).

        The norms of the components' bounds (a single moving component's own).
        """
        moving = [c.motion_bounds(t_end) for c in self.moving]
        if len(moving) == 1:
            return moving[0]
        return (math.hypot(*(u for u, _ in moving)) if moving else 0.0,
                math.hypot(*(v for _, v in moving)) if moving else 0.0)

    def horizontal_bounds(self, t_end: float = math.inf) -> tuple[float, float]:
        """:meth:`motion_bounds` of the horizontal components only (m, m/s)."""
        return BaseMotion(self.x, self.y).motion_bounds(t_end)

    def peak_acceleration(self, t_end: float = math.inf) -> float:
        """Largest horizontal |ü| over [0, t_end] (m/s²): PGA (of one component alone
        where the other is still)."""
        moving = [c for c in (self.x, self.y) if not c.is_free]
        if len(moving) < 2:
            return moving[0].peak_acceleration(t_end) if moving else 0.0
        stop = min(t_end, self.end_time)
        if not math.isfinite(stop) or stop <= 0:
            return 0.0
        t = np.linspace(0.0, stop, 20001)
        return float(np.max(np.hypot(self.x.acceleration(t), self.y.acceleration(t))))
