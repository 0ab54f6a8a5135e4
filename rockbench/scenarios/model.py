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
from scipy.spatial.transform import Rotation

from rockbench import checks
from rockbench.errors import ScenarioError
from rockbench.geometry import Block, Body, Column, Cylinder, Geometry, footprint_pivot, single
from rockbench.scenarios.excitation import Excitation, Free
from rockbench.scenarios.motion import BaseMotion

__all__ = ["Contact", "Scenario"]

Vector = tuple[float, float, float]
_ZERO: Vector = (0.0, 0.0, 0.0)


def _wxyz(r: Rotation) -> np.ndarray:
    """A rotation as the unit quaternion (w, x, y, z) the engines read."""
    return np.roll(r.as_quat(), 1)


def _about_y(angle: float) -> Rotation:
    return Rotation.from_rotvec([0.0, angle, 0.0])


def _vector(value: Any, what: str, unit: str) -> Vector:
    """Three finite numbers."""
    if not isinstance(value, (list, tuple, np.ndarray)) or len(value) != 3:
        raise ScenarioError(f"{what} must be three numbers [x, y, z] ({unit}), got "
                            f"{checks.describe(value)}")
    x, y, z = (checks.number(v, f"{what} {c}", unit=unit) for v, c in zip(value, "xyz",
                                                                           strict=True))
    return (x, y, z)


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
    geometry : Geometry, Block or Cylinder
        What rocks (:mod:`rockbench.geometry`); a single Block or Cylinder
        stands alone on the base.
    contact : Contact
        Friction, restitution, optional analytic η.
    excitation : Excitation
        Base motion (default: none); :attr:`motion` is its three-component form.
    initial_tilt : float
        Initial rotation as a fraction of the bottom block's λ toward
        ``initial_azimuth``; positive tilts toward +x. The whole column is
        rotated rigidly about the bottom pivot (an edge, or a corner where the
        azimuth is not along an axis) and released. Columns only
        (:attr:`Geometry.column`): other geometries' blocks have their own angles.
    initial_azimuth : float
        Horizontal direction of the tilt, from +x toward +y (rad); 0 keeps the
        start in the x–z plane. λ is then that of the pivot the body tips over
        toward this direction (:meth:`tilt_lambda`).
    initial_velocity : (float, float, float)
        Velocity of a single body's centre of mass at t = 0 (m/s, world axes).
    initial_angular_velocity : (float, float, float)
        Angular velocity of a single body at t = 0 (rad/s, world axes): a
        spinning, rolling or precessing start
        (:func:`rockbench.analytic.rolling_cylinder.rolling_start`).
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
    initial_azimuth: float = 0.0
    initial_velocity: Vector = _ZERO
    initial_angular_velocity: Vector = _ZERO
    duration: float = 10.0
    output_rate: float = 1000.0
    g: float = 9.81
    description: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip():
            raise ScenarioError("scenario name must be a non-empty string")
        if isinstance(self.geometry, (Block, Cylinder)):
            object.__setattr__(self, "geometry", single(self.geometry))
        if not isinstance(self.geometry, Geometry):
            raise ScenarioError("scenario geometry must be a Geometry, a Block or a Cylinder")
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
        self._check_start()
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

    def _check_start(self) -> None:
        """Validate the initial azimuth and velocities."""
        psi = checks.number(self.initial_azimuth, "initial azimuth", unit="rad")
        if psi != 0.0 and self.initial_tilt == 0.0:
            raise ScenarioError(f"initial azimuth {psi:g} rad needs an initial tilt to point")
        object.__setattr__(self, "initial_azimuth", psi)
        for name, unit in (("initial_velocity", "m/s"), ("initial_angular_velocity", "rad/s")):
            v = _vector(getattr(self, name), name.replace("_", " "), unit)
            object.__setattr__(self, name, v)
            if any(v) and self.n_blocks != 1:
                raise ScenarioError(f"{name.replace('_', ' ')} is for a single body; this "
                                    f"geometry has {self.n_blocks}")

    @property
    def moving_start(self) -> bool:
        """True when the body starts with a velocity or an angular velocity."""
        return any(self.initial_velocity) or any(self.initial_angular_velocity)

    @property
    def planar_start(self) -> bool:
        """True when the start lies in the x–z plane: no azimuth, no motion out of it."""
        v, w = self.initial_velocity, self.initial_angular_velocity
        return self.initial_azimuth == 0.0 and v[1] == 0.0 and w[0] == 0.0 and w[2] == 0.0

    @property
    def has_cylinders(self) -> bool:
        """True when a body is a :class:`~rockbench.geometry.Cylinder`."""
        return any(isinstance(b, Cylinder) for b in self.blocks)

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
        """Initial tilt in rad (fraction × the λ of :meth:`tilt_lambda`); 0 when not tilted."""
        if self.initial_tilt == 0:
            return 0.0
        return self.initial_tilt * self.tilt_lambda()

    def _lean(self) -> np.ndarray:
        """The horizontal unit vector (x, y) the start tilts toward (the tilt's sign taken in)."""
        u = np.array([math.cos(self.initial_azimuth), math.sin(self.initial_azimuth)])
        return u if self.initial_tilt >= 0 else -u

    def tilt_lambda(self) -> float:
        """λ toward the start's lean: atan of the pivot's lever over the centroid's height (rad).

        In the x–z plane it is the bottom block's λ; toward a corner of a block
        the lever is the corner's distance along the lean, b |cos ψ| + (d/2) |sin ψ|.
        """
        bottom = self._tilted_column().blocks[0]
        if self.initial_azimuth == 0.0:
            return bottom.rocking(self.g).lam
        lever = float(footprint_pivot(bottom, math.atan2(*self._lean()[::-1])) @ self._lean())
        return math.atan2(lever, bottom.h)

    def _tilted_column(self) -> Column:
        """The geometry as a column: a scenario with an initial tilt is one (__post_init__)."""
        column = self.geometry.column
        assert column is not None
        return column

    def output_times(self) -> np.ndarray:
        """Sample times 0, 1/rate, … up to the duration."""
        n = int(math.floor(self.duration * self.output_rate + 1e-9)) + 1
        return np.arange(n) / self.output_rate

    def initial_states(self) -> np.ndarray:
        """Each body's state at t = 0, shape (n, 13), world axes.

        Columns: centre of gravity (x, y, z), orientation quaternion (w, x, y, z),
        velocity (3) and angular velocity (3). The column tilted toward the
        azimuth turns rigidly about the pivot of its bottom block's footprint
        (:func:`~rockbench.geometry.footprint_pivot`).
        """
        n = self.n_blocks
        out = np.zeros((n, 13))
        if self.initial_azimuth == 0.0:
            p = self.initial_poses()
            out[:, 0], out[:, 2] = p[:, 0], p[:, 1]
            out[:, 3:7] = [_wxyz(_about_y(a)) for a in p[:, 2]]
        else:
            geo = self.geometry
            u = self._lean()
            axis = np.array([-u[1], u[0], 0.0])  # ẑ × u: turning about it leans the top to u
            bottom = self._tilted_column().blocks[0]
            pivot = np.append(footprint_pivot(bottom, math.atan2(u[1], u[0])), 0.0)
            pivot[0] += geo.poses[0][0]
            turn = Rotation.from_rotvec(abs(self.theta0) * axis)
            c = np.column_stack([geo.centroids[:, 0], np.zeros(n), geo.centroids[:, 1]])
            out[:, :3] = pivot + turn.apply(c - pivot)
            out[:, 3:7] = [_wxyz(turn * _about_y(a)) for a in geo.angles]
        out[:, 7:10] = self.initial_velocity
        out[:, 10:13] = self.initial_angular_velocity
        return out

    def initial_poses(self) -> np.ndarray:
        """Centre of gravity (x, z) and angle of each body at t = 0, shape (n, 3).

        A tilted column is rotated rigidly about the bottom pivot on the side it
        tilts to; otherwise the geometry's rest poses. A start out of the x–z
        plane gives the angle about +y, atan2(R₀₂, R₂₂), of :meth:`initial_states`.
        """
        geo = self.geometry
        th = self.theta0
        c = geo.centroids
        if th == 0.0:
            return np.column_stack([c, geo.angles])
        if self.initial_azimuth != 0.0:
            states = self.initial_states()
            r = Rotation.from_quat(np.roll(states[:, 3:7], -1, axis=1)).as_matrix()
            return np.column_stack([states[:, 0], states[:, 2],
                                    np.arctan2(r[:, 0, 2], r[:, 2, 2])])
        px = math.copysign(self._tilted_column().blocks[0].pivot_half_width, th) + geo.poses[0][0]
        dx, dz = c[:, 0] - px, c[:, 1]
        # rotation about +y by θ maps (x, z) -> (x cos θ + z sin θ, −x sin θ + z cos θ)
        ct, st = math.cos(th), math.sin(th)
        return np.column_stack([px + dx * ct + dz * st, -dx * st + dz * ct,
                                np.full(len(c), th)])

    def initial_kinetic_energy(self) -> float:
        """Kinetic energy at t = 0 (J): ½ m v² + ½ ωᵀ I ω of the single moving body."""
        if not self.moving_start:
            return 0.0
        body = self.blocks[0]
        st = self.initial_states()[0]
        rot = Rotation.from_quat(np.roll(st[3:7], -1)).as_matrix()
        inertia = rot @ body.inertia_tensor @ rot.T
        v, w = st[7:10], st[10:13]
        return float(0.5 * body.m * v @ v + 0.5 * w @ inertia @ w)

    def replace(self, **changes: Any) -> Scenario:
        """A copy with some fields changed (validated again)."""
        kw = {f.name: getattr(self, f.name) for f in fields(self)}
        kw.update(changes)
        return Scenario(**kw)

