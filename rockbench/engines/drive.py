"""The base motion as an engine applies it: :class:`BaseDrive`, sampled on the step grid.

The :class:`~rockbench.engines.base.Engine` base class builds one
:class:`BaseDrive` per run from the scenario's three-component
:class:`~rockbench.scenarios.motion.BaseMotion` and hands it to the engine
(``self.drive``) before :meth:`~rockbench.engines.base.Engine._build`. An
engine only applies what it samples: the displacement, velocity or
acceleration (arrays of shape (n, 3): x, y, z) at the times of its own step
grid, t_i = (start + i) · dt (+ phase · dt). It never reads the excitation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rockbench.scenarios.motion import AXES, BaseMotion

__all__ = ["BaseDrive"]


@dataclass(frozen=True)
class BaseDrive:
    """A scenario's base motion over one run.

    Parameters
    ----------
    motion : BaseMotion
        The three-component motion.
    duration : float
        Length of the run (s).
    """

    motion: BaseMotion
    duration: float

    @property
    def moving(self) -> bool:
        """True when the base moves at some time."""
        return not self.motion.is_free

    @property
    def axes(self) -> tuple[str, ...]:
        """The axes along which the base moves (``"x"``, ``"y"``, ``"z"``)."""
        return self.motion.axes

    @property
    def end_time(self) -> float:
        """Time after which the base stands still (``inf`` if never, 0 if it never moves)."""
        return self.motion.end_time

    @property
    def stop(self) -> float:
        """Time within the run when the base stops: min(duration, end_time), 0 if still."""
        return min(self.duration, self.end_time) if self.moving else 0.0

    @property
    def travel(self) -> float:
        """Bound on the base's horizontal travel over the run (m): what a scene must hold."""
        return self.motion.horizontal_bounds(self.duration)[0]

    @property
    def speed(self) -> float:
        """Bound on the base's speed over the run (m/s)."""
        return self.motion.motion_bounds(self.duration)[1]

    def steps_until_stop(self, dt: float) -> int:
        """Number of whole steps of length ``dt`` that cover [0, :attr:`stop`]."""
        return int(math.ceil(self.stop / dt))

    @staticmethod
    def grid(dt: float, n: int, *, start: int = 0, phase: float = 0.0) -> np.ndarray:
        """Times (start + i) · dt for i < n, plus phase · dt when ``phase`` is not 0 (s)."""
        t = (start + np.arange(n)) * dt
        return t + phase * dt if phase else t

    def displacement(self, t: np.ndarray | float) -> np.ndarray:
        """Base displacement (m), shape ``t.shape + (3,)``."""
        return self.motion.displacement(t)

    def velocity(self, t: np.ndarray | float) -> np.ndarray:
        """Base velocity (m/s), shape ``t.shape + (3,)``."""
        return self.motion.velocity(t)

    def acceleration(self, t: np.ndarray | float) -> np.ndarray:
        """Base acceleration (m/s²), shape ``t.shape + (3,)``."""
        return self.motion.acceleration(t)

    def final_displacement(self) -> np.ndarray:
        """Where the base stands after it stopped, (3,) (m)."""
        return self.displacement(self.stop)

    def unsupported_axes(self, applies: str) -> tuple[str, ...]:
        """The moving axes outside ``applies`` (e.g. ``"x"`` or ``"xz"``)."""
        return tuple(a for a in self.axes if a not in applies)


#: Index of each axis in the (..., 3) arrays.
AXIS = {a: i for i, a in enumerate(AXES)}
