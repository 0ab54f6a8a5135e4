"""What is simulated: the contact and the scenario that ties geometry, contact and motion.

Axes (DESIGN.md): z up, rocking in the x–z plane, θ = rotation about +y, positive
when a block's top moves toward +x (pivoting on its +x bottom edge).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from rockbench import checks
from rockbench.errors import ScenarioError
from rockbench.geometry import Block, Body, Column, Geometry, single
from rockbench.scenarios.excitation import Excitation, Free
from rockbench.scenarios.motion import BaseMotion

__all__ = ["Contact", "Scenario"]


def _check(value: Any, what: str, *, low: float | None = 0.0, strict: bool = True,
           high: float | None = None, unit: str = "") -> float:
    """Validate a finite number (never a string or boolean) in a range; return it as float."""
    return checks.number(value, what, low=low, strict=strict, high=high, unit=unit)


@dataclass(frozen=True)
class Contact:
    """Contact properties shared by every contact in the scene.

    Parameters
    ----------
    friction : float
        Coulomb coefficient (≥ 0); the paper uses 1.0 (45°).
    restitution : float
        Engines' bounce coefficient in [0, 1].
    eta : float, optional
        Override of the analytic impact ratio (θ̇⁺ = η θ̇⁻) for single blocks;
        default Housner's 1 − 2mb²/I_O.
    interface_friction : float, optional
        Coulomb coefficient (≥ 0) of the block–block contacts of a stack; None
        (default): the same as ``friction``, which then holds for every contact.
    """

    friction: float = 1.0
    restitution: float = 0.0
    eta: float | None = None
    interface_friction: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "friction", _check(self.friction, "contact friction",
                                                    strict=False))
        object.__setattr__(self, "restitution", _check(self.restitution, "contact restitution",
                                                       strict=False, high=1.0))
        if self.eta is not None:
            object.__setattr__(self, "eta", _check(self.eta, "contact eta", strict=False,
                                                   high=1.0))
        if self.interface_friction is not None:
            object.__setattr__(self, "interface_friction", _check(
                self.interface_friction, "contact interface_friction", strict=False))

    @property
    def block_friction(self) -> float:
        """Coulomb coefficient between two blocks (``interface_friction`` or ``friction``)."""
        return self.friction if self.interface_friction is None else self.interface_friction

    def to_dict(self) -> dict[str, Any]:
        """Scenario-file representation."""
        d: dict[str, Any] = {"friction": self.friction, "restitution": self.restitution}
        if self.eta is not None:
            d["eta"] = self.eta
        if self.interface_friction is not None:
            d["interface_friction"] = self.interface_friction
        return d


@dataclass(frozen=True)
class Scenario:
    """A complete rocking problem: geometry, contact, base motion, initial state, output.

    Parameters
    ----------
    name : str
        Identifier (catalog name or file stem).
    geometry : Geometry or Block
        What rocks (:mod:`rockbench.geometry`); a single Block stands alone on
        the base.
    contact : Contact
        Friction, restitution, optional analytic η.
    excitation : Excitation
        Base motion (default: none); :attr:`motion` is its three-component form.
    initial_tilt : float
        Initial rotation as a fraction of the bottom block's λ; positive tilts
        toward +x. The whole column is rotated rigidly about the bottom pivot and
        released from rest. Columns only (:attr:`Geometry.column`): other
        geometries' blocks have their own angles.
    duration : float
        Simulated time (s).
    output_rate : float
        Samples per second in the returned trajectories.
    g : float
        Gravity (m/s², acting along −z).
    description : str
        Free text (e.g. the paper case it reproduces).
    """

    name: str
    geometry: Geometry
    contact: Contact = field(default_factory=Contact)
    excitation: Excitation = field(default_factory=Free)
    initial_tilt: float = 0.0
    duration: float = 10.0
    output_rate: float = 1000.0
    g: float = 9.81
    description: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip():
            raise ScenarioError("scenario name must be a non-empty string")
        if isinstance(self.geometry, Block):
            object.__setattr__(self, "geometry", single(self.geometry))
        if not isinstance(self.geometry, Geometry):
            raise ScenarioError("scenario geometry must be a Geometry or a Block")
        if not self.geometry.base:
            raise ScenarioError("a scenario's geometry stands on the base (z = 0)")
        if not isinstance(self.contact, Contact):
            raise ScenarioError("scenario contact must be a Contact")
        if not isinstance(self.excitation, Excitation):
            raise ScenarioError("scenario excitation must be an Excitation")
        tilt = self.initial_tilt
        if not (checks.is_number(tilt) and math.isfinite(tilt) and abs(tilt) < 1.0):
            raise ScenarioError(
                f"initial tilt must be a fraction of λ with |tilt| < 1, got "
                f"{checks.describe(tilt)}"
            )
        if tilt != 0 and self.geometry.column is None:
            raise ScenarioError(f"initial tilt is for a column of blocks on the base (got "
                                f"{tilt!r}); this geometry's blocks take their own angle")
        if not isinstance(self.description, str):
            raise ScenarioError(f"scenario description must be a string, got "
                                f"{checks.describe(self.description)}")
        object.__setattr__(self, "duration", _check(self.duration, "scenario duration",
                                                    unit="s"))
        object.__setattr__(self, "output_rate", _check(self.output_rate, "output_rate",
                                                       unit="samples/s"))
        object.__setattr__(self, "g", _check(self.g, "gravity", unit="m/s²"))
        if self.duration * self.output_rate < 1.0 - 1e-9:
            raise ScenarioError(
                f"output_rate {self.output_rate:g} samples/s gives a single sample over the "
                f"{self.duration:g} s run: a trajectory needs at least 2 (output_rate >= "
                f"1/duration = {1.0 / self.duration:.3g})")

    @property
    def blocks(self) -> tuple[Body, ...]:
        """The bodies of the geometry (bottom first for a column)."""
        return self.geometry.bodies

    @property
    def n_blocks(self) -> int:
        """Number of bodies."""
        return len(self.geometry.bodies)

    @functools.cached_property
    def motion(self) -> BaseMotion:
        """The three-component base motion of :attr:`excitation`."""
        return self.excitation.base_motion()

    @property
    def theta0(self) -> float:
        """Initial rotation in rad (fraction × bottom block's λ); 0 when not tilted."""
        if self.initial_tilt == 0:
            return 0.0
        return self.initial_tilt * self._tilted_column().blocks[0].rocking(self.g).lam

    def _tilted_column(self) -> Column:
        """The geometry as a column: a scenario with an initial tilt is one (__post_init__)."""
        column = self.geometry.column
        assert column is not None
        return column

    def output_times(self) -> np.ndarray:
        """Sample times 0, 1/rate, … up to the duration."""
        n = int(math.floor(self.duration * self.output_rate + 1e-9)) + 1
        return np.arange(n) / self.output_rate

    def initial_poses(self) -> np.ndarray:
        """Centre of gravity (x, z) and angle of each body at t = 0, shape (n, 3).

        A tilted column is rotated rigidly about the bottom pivot on the side it
        tilts to; otherwise the geometry's rest poses.
        """
        geo = self.geometry
        th = self.theta0
        c = geo.centroids
        if th == 0.0:
            return np.column_stack([c, geo.angles])
        px = math.copysign(self._tilted_column().blocks[0].pivot_half_width, th) + geo.poses[0][0]
        dx, dz = c[:, 0] - px, c[:, 1]
        # rotation about +y by θ maps (x, z) -> (x cos θ + z sin θ, −x sin θ + z cos θ)
        ct, st = math.cos(th), math.sin(th)
        return np.column_stack([px + dx * ct + dz * st, -dx * st + dz * ct,
                                np.full(len(c), th)])

    def replace(self, **changes: Any) -> Scenario:
        """A copy with some fields changed (validated again)."""
        kw = {f.name: getattr(self, f.name) for f in fields(self)}
        kw.update(changes)
        return Scenario(**kw)
