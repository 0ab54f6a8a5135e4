"""Kinematic analysis of a local mechanism: the Italian code's quantities of a collapse mechanism.

NTC 2018 §8.7.1 and the Circolare of 21 January 2019 n. 7 §C8.7.1.2.1 check a
masonry element (a free-standing block, a parapet, a column of drums, ...) by
the kinematic analysis of its local mechanism. This module turns the mechanism
that :func:`rockbench.analytic.static_collapse.limit_analysis` finds into the
code's quantities (:func:`kinematic_analysis`); the demand and the checks are in
:mod:`rockbench.analytic.code_spectra` and :mod:`rockbench.studies.code_check`.

Linear quantities (Circolare 2019 §C8.7.1.2.1.3)
-------------------------------------------------
* α_0, the activation multiplier: the limit-analysis load factor (the virtual
  work equation [C8.7.1.1] with the weights P_k of the blocks as the only loads);
* δ_x,k, the virtual horizontal displacements of the centres of gravity of the
  moving blocks, normalised so that the control point's is 1; the control point
  is the centre of gravity of the highest moving block that moves along the loads
  (any point of the chain will do: the spectral displacement d below does not
  depend on it for small displacements);
* the participating mass M* = (Σ P_k δ_x,k)² / (g Σ P_k δ_x,k²) and its fraction
  e* = g M* / Σ P_k [C8.7.1.5], the sums running over the blocks of the mechanism
  (the blocks at rest do no virtual work and carry no inertia of the oscillator);
* the spectral acceleration of activation a_0* = α_0 g / (e* FC) [C8.7.1.3] at d = 0,
  [C8.7.1.8], with FC the confidence factor.

Capacity curve (Circolare 2019 [C8.7.1.3], [C8.7.1.4])
-------------------------------------------------------
a(d) = α(d_C) g / (e* FC) against the spectral displacement
d = d_C Σ P_k δ_x,k² / (δ_C,x Σ P_k δ_x,k), where d_C is the horizontal
displacement of the control point after a *finite* motion of the mechanism and
α(d_C) the multiplier that balances the weights in that displaced configuration:
α = Σ P_k δ_z,k / (± Σ P_k δ_x,k) by virtual work, the virtual displacements
being those of the same mechanism at the displaced configuration (the kinematic
chain is kept: a change of mechanism at large displacement, such as an upper drum
starting to turn on its own, is not followed). d_0 is the displacement at which
α falls to 0.

That is done exactly where every moving block turns about a *fixed* centre: a
point of contact with a body at rest (a block rocking on its corner, a parapet
on its wall's edge, the upper drums of a column turning together about one
joint, a wedge of a wall turning about a brick's corner); the groups of blocks
that share a centre turn as rigid bodies by angles in the ratio of their
angular velocities. Any other mechanism (a translation, a four-hinge arch whose
hinges move with the voussoirs, blocks of different centres hinged to each
other) has no finite kinematics here: :attr:`KinematicAnalysis.curve` is None
with the reason, and the quantities of the curve raise :class:`NoFiniteKinematics`.

From the curve (:class:`KinematicAnalysis`):

* Circolare 2019 §C8.7.1.2.1.6, §C8.7.1.2.1.8: d_SLV = 0.4 d_0 and d_SLC = 0.6 d_0
  (the mechanism's own limits; ruptures of ties are not modelled), and the
  equivalent periods T_SLV = 1.68 π √(d_SLV / a(d_SLV)) [C8.7.1.10],
  T_SLC = 1.56 π √(d_SLC / a(d_SLC)) [C8.7.1.11], with a(d) on the curve above;
* the Circolare 2009 (C8A.4.2.3) quantities, for reference: the linear curve
  a*(d*) = a_0*(1 − d*/d_0*), d_u* = 0.4 d_0*, the secant point d_s* = 0.4 d_u*,
  a_s* = a*(d_s*) and the secant period T_s = 2π √(d_s*/a_s*).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from rockbench.analytic.static_collapse import LimitResult, Mode
from rockbench.errors import ScenarioError
from rockbench.geometry import Geometry

__all__ = ["CapacityCurve", "KinematicAnalysis", "NoFiniteKinematics", "kinematic_analysis",
           "SLV_FRACTION", "SLC_FRACTION", "SLV_PERIOD_FACTOR", "SLC_PERIOD_FACTOR",
           "ULTIMATE_FRACTION_2009", "SECANT_FRACTION_2009", "DEFAULT_SAMPLES"]

#: d_SLV = 0.4 d_0 (Circolare 2019 §C8.7.1.2.1.6).
SLV_FRACTION = 0.4
#: d_SLC = 0.6 d_0 (Circolare 2019 §C8.7.1.2.1.6).
SLC_FRACTION = 0.6
#: T_SLV = 1.68 π √(d_SLV/a(d_SLV)) [C8.7.1.10].
SLV_PERIOD_FACTOR = 1.68
#: T_SLC = 1.56 π √(d_SLC/a(d_SLC)) [C8.7.1.11].
SLC_PERIOD_FACTOR = 1.56
#: d_u* = 0.4 d_0* (Circolare 2009 C8A.4.2.3).
ULTIMATE_FRACTION_2009 = 0.4
#: d_s* = 0.4 d_u* (Circolare 2009 C8A.4.2.3).
SECANT_FRACTION_2009 = 0.4
#: Points of the capacity curve from d = 0 to d_0.
DEFAULT_SAMPLES = 201
#: Relative tolerance of "the same centre" and "on a contact" (of the geometry's size).
_TOL = 1e-6
#: Grid of the search for the rotation at which α falls to 0, over a quarter turn.
_SCAN = 4000


class NoFiniteKinematics(ScenarioError):
    """The mechanism has no finite kinematics here (see :mod:`rockbench.analytic.kinematic`)."""


@dataclass(frozen=True, eq=False)
class CapacityCurve:
    """The capacity curve a(d) of a mechanism moved through finite rotations.

    Attributes
    ----------
    rotation : ndarray
        Rotation of the control point's block (rad, ≥ 0), from 0 to
        :attr:`rotation0`.
    control_displacement : ndarray
        d_C: horizontal displacement of the control point along the loads (m).
    displacement : ndarray
        d: spectral displacement of the equivalent oscillator (m) [C8.7.1.4].
    load_factor : ndarray
        α(d_C) of the displaced configuration.
    acceleration : ndarray
        a = α g / (e* FC) (m/s²) [C8.7.1.3].
    rotation0 : float
        Rotation at which α = 0 (rad).
    """

    rotation: np.ndarray
    control_displacement: np.ndarray
    displacement: np.ndarray
    load_factor: np.ndarray
    acceleration: np.ndarray
    rotation0: float

    @property
    def d0(self) -> float:
        """d_0: the spectral displacement at which α = 0 (m)."""
        return float(self.displacement[-1])

    @property
    def a0(self) -> float:
        """a(0) (m/s²)."""
        return float(self.acceleration[0])

    def acceleration_at(self, d: float) -> float:
        """a(d) on the curve (m/s², linear between its points; 0 beyond d_0)."""
        return float(np.interp(d, self.displacement, self.acceleration, right=0.0))

    def load_factor_at(self, d: float) -> float:
        """α(d) on the curve (linear between its points; 0 beyond d_0)."""
        return float(np.interp(d, self.displacement, self.load_factor, right=0.0))


@dataclass(frozen=True, eq=False)
class KinematicAnalysis:
    """The code's quantities of one limit-analysis mechanism (module docstring).

    Attributes
    ----------
    direction : int
        +1: the horizontal loads act toward +x; −1 toward −x.
    load_factor : float
        α_0.
    governing_mode : {"rocking", "sliding", "mixed"}
        From the limit analysis.
    moving_blocks : tuple of int
        Indices of the blocks of the mechanism.
    weights : ndarray
        P_k = m_k g of the moving blocks (N).
    centroids : ndarray (n, 2)
        Their centres of gravity at rest (m).
    delta_x, delta_z : ndarray
        Their virtual displacements, normalised so that the control point's δ_x is 1.
    control_block : int
        The block whose centre of gravity is the control point.
    control_point : ndarray (2,)
        The control point at rest (x, z) (m).
    participating_mass : float
        M* (kg).
    mass_fraction : float
        e*.
    confidence_factor : float
        FC.
    g : float
        Gravity (m/s²).
    curve : CapacityCurve or None
        The capacity curve from finite kinematics; None where the mechanism has none.
    no_curve_reason : str
        Why :attr:`curve` is None ("" when there is a curve).
    """

    direction: int
    load_factor: float
    governing_mode: Mode | None
    moving_blocks: tuple[int, ...]
    weights: np.ndarray
    centroids: np.ndarray
    delta_x: np.ndarray
    delta_z: np.ndarray
    control_block: int
    control_point: np.ndarray
    participating_mass: float
    mass_fraction: float
    confidence_factor: float
    g: float
    curve: CapacityCurve | None
    no_curve_reason: str = ""

    # ------------------------------------------------------------ linear quantities
    @property
    def total_weight(self) -> float:
        """Σ P_k over the moving blocks (N)."""
        return float(self.weights.sum())

    @property
    def spectral_acceleration(self) -> float:
        """a_0* = α_0 g / (e* FC) (m/s²) [C8.7.1.3] at d = 0, [C8.7.1.8]."""
        return self.load_factor * self.g / (self.mass_fraction * self.confidence_factor)

    @property
    def displacement_factor(self) -> float:
        """Σ P δ_x² / (δ_C,x Σ P δ_x): d = d_C × this [C8.7.1.4]."""
        p, dx = self.weights, self.delta_x
        return float((p * dx ** 2).sum() / (p * dx).sum())

    @property
    def direction_label(self) -> str:
        """"+x" or "−x": where the loads (and the mechanism) go."""
        return "+x" if self.direction > 0 else "−x"

    # ------------------------------------------------------------ the curve
    @property
    def has_curve(self) -> bool:
        """True if finite kinematics gave a capacity curve."""
        return self.curve is not None

    def _curve(self) -> CapacityCurve:
        if self.curve is None:
            raise NoFiniteKinematics(f"no finite kinematics for this mechanism: "
                                     f"{self.no_curve_reason}")
        return self.curve

    @property
    def d0(self) -> float:
        """d_0 (m): where the capacity curve falls to 0."""
        return self._curve().d0

    def acceleration_at(self, d: float) -> float:
        """a(d) on the capacity curve (m/s²)."""
        return self._curve().acceleration_at(d)

    def linear_acceleration_at(self, d: float) -> float:
        """a_0* (1 − d/d_0) (m/s²): the linear curve of the Circolare 2009, ≥ 0."""
        return max(self.spectral_acceleration * (1.0 - d / self.d0), 0.0)

    @property
    def d_slv(self) -> float:
        """d_SLV = 0.4 d_0 (m) (Circolare 2019 §C8.7.1.2.1.6)."""
        return SLV_FRACTION * self.d0

    @property
    def d_slc(self) -> float:
        """d_SLC = 0.6 d_0 (m) (Circolare 2019 §C8.7.1.2.1.6)."""
        return SLC_FRACTION * self.d0

    @property
    def a_slv(self) -> float:
        """a(d_SLV) on the capacity curve (m/s²)."""
        return self.acceleration_at(self.d_slv)

    @property
    def a_slc(self) -> float:
        """a(d_SLC) on the capacity curve (m/s²)."""
        return self.acceleration_at(self.d_slc)

    @property
    def period_slv(self) -> float:
        """T_SLV = 1.68 π √(d_SLV / a(d_SLV)) (s) [C8.7.1.10]."""
        return SLV_PERIOD_FACTOR * math.pi * math.sqrt(self.d_slv / self.a_slv)

    @property
    def period_slc(self) -> float:
        """T_SLC = 1.56 π √(d_SLC / a(d_SLC)) (s) [C8.7.1.11]."""
        return SLC_PERIOD_FACTOR * math.pi * math.sqrt(self.d_slc / self.a_slc)

    @property
    def du_2009(self) -> float:
        """d_u* = 0.4 d_0* (m) (Circolare 2009 C8A.4.2.3)."""
        return ULTIMATE_FRACTION_2009 * self.d0

    @property
    def ds_2009(self) -> float:
        """d_s* = 0.4 d_u* (m) (Circolare 2009 C8A.4.2.3)."""
        return SECANT_FRACTION_2009 * self.du_2009

    @property
    def as_2009(self) -> float:
        """a_s* = a*(d_s*) on the linear curve (m/s²) (Circolare 2009 C8A.4.2.3)."""
        return self.linear_acceleration_at(self.ds_2009)

    @property
    def secant_period_2009(self) -> float:
        """T_s = 2π √(d_s*/a_s*) (s) (Circolare 2009 C8A.4.2.3)."""
        return 2.0 * math.pi * math.sqrt(self.ds_2009 / self.as_2009)


@dataclass(frozen=True)
class _Group:
    """Blocks turning together about one fixed centre."""

    blocks: tuple[int, ...]
    centre: np.ndarray
    omega: float  # angular velocity of the group (LP normalisation)


def _segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    ab = b - a
    t = float(np.clip(np.dot(p - a, ab) / max(float(np.dot(ab, ab)), 1e-300), 0.0, 1.0))
    return float(np.hypot(*(p - (a + t * ab))))


def _groups(assembly: Geometry, limit: LimitResult) -> list[_Group] | str:
    """The rigid groups of the mechanism, or why it has no finite kinematics."""
    tol = _TOL * assembly.size
    moving = [m for m in limit.mechanism if m.kind != "rest"]
    groups: list[_Group] = []
    for m in moving:
        if m.kind != "rotation" or m.centre is None:
            return (f"block {m.block} translates (a sliding mechanism): its capacity does not "
                    f"fall with the displacement as the Circolare's curve assumes")
        for k, grp in enumerate(groups):
            if float(np.hypot(*(grp.centre - m.centre))) <= tol:
                scale = max(abs(grp.omega), abs(m.velocity[2]))
                if abs(grp.omega - m.velocity[2]) > 1e-6 * scale:
                    return (f"blocks {grp.blocks[0]} and {m.block} turn about the same point "
                            f"at different rates: a hinge between moving blocks")
                groups[k] = _Group(grp.blocks + (m.block,), grp.centre, grp.omega)
                break
        else:
            groups.append(_Group((m.block,), np.asarray(m.centre, float),
                                 float(m.velocity[2])))
    group_of = {b: k for k, grp in enumerate(groups) for b in grp.blocks}
    for itf in assembly.interfaces:
        ga, gb = group_of.get(itf.a), group_of.get(itf.b)
        if ga is not None and gb is not None and ga != gb:
            c1, c2 = groups[ga].centre, groups[gb].centre
            return (f"blocks {itf.a} and {itf.b} touch but turn about different centres "
                    f"({c1[0]:.4g}, {c1[1]:.4g}) and ({c2[0]:.4g}, {c2[1]:.4g}) m: a chain "
                    f"of hinges that move with the blocks (e.g. a four-hinge arch)")
    for grp in groups:
        fixed = False
        for itf in assembly.interfaces:
            inside = [s for s in (itf.a, itf.b) if s in grp.blocks]
            other = [s for s in (itf.a, itf.b) if s not in grp.blocks]
            if len(inside) != 1 or other[0] in group_of:
                continue
            if _segment_distance(grp.centre, itf.p0, itf.p1) <= tol:
                fixed = True
                break
        if not fixed:
            c = grp.centre
            return (f"block {grp.blocks[0]} turns about ({c[0]:.4g}, {c[1]:.4g}) m, which is "
                    f"not a contact with a body at rest: the centre moves as the mechanism "
                    f"opens (e.g. a four-hinge arch)")
    return groups


def _rotate(r: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Rotate the points r (n, 2) about the origin by θ (n,) about +y (θ > 0: top to +x)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.column_stack([r[:, 0] * c + r[:, 1] * s, -r[:, 0] * s + r[:, 1] * c])


class _Chain:
    """The finite motion of the rigid groups, parametrised by the control block's rotation."""

    def __init__(self, groups: list[_Group], blocks: tuple[int, ...], centroids: np.ndarray,
                 weights: np.ndarray, control: int, direction: int) -> None:
        where = {b: (grp.centre, grp.omega) for grp in groups for b in grp.blocks}
        self.centres = np.array([where[b][0] for b in blocks])
        self.omegas = np.array([where[b][1] for b in blocks])
        self.arms = centroids - self.centres
        self.weights = weights
        self.direction = direction
        k = blocks.index(control)
        self.control = k
        self.rates = self.omegas / abs(self.omegas[k])  # θ_i per unit control rotation

    def arms_at(self, phi: float) -> np.ndarray:
        return _rotate(self.arms, self.rates * phi)

    def work(self, phi: float) -> tuple[float, float]:
        """(Σ P δ_z, dir Σ P δ_x) of the virtual motion at the rotated configuration."""
        r = self.arms_at(phi)
        vx, vz = self.omegas * r[:, 1], -self.omegas * r[:, 0]
        return (float((self.weights * vz).sum()),
                float(self.direction * (self.weights * vx).sum()))

    def load_factor(self, phi: float) -> float:
        up, side = self.work(phi)
        return up / side

    def control_displacement(self, phi: float) -> float:
        r = self.arms_at(phi)[self.control]
        return float(self.direction * (r[0] - self.arms[self.control, 0]))


def _curve(chain: _Chain, alpha0: float, factor: float, scale: float, samples: int
           ) -> CapacityCurve | str:
    """Sample the capacity curve from 0 to the rotation at which α = 0."""
    if abs(chain.load_factor(0.0) - alpha0) > 1e-6 * max(1.0, abs(alpha0)):
        return (f"the weights' virtual work gives α = {chain.load_factor(0.0):.6g}, not the "
                f"limit analysis's {alpha0:.6g} (work done at the joints)")
    top = 0.5 * math.pi / float(np.abs(chain.rates).max())
    grid = np.linspace(0.0, top, _SCAN + 1)
    ups = np.array([chain.work(p)[0] for p in grid])
    sides = np.array([chain.work(p)[1] for p in grid])
    crossing = np.nonzero(ups[1:] <= 0.0)[0]
    if crossing.size == 0:
        return "α does not fall to 0 within a quarter turn of the mechanism"
    k = int(crossing[0]) + 1
    if np.any(sides[: k + 1] <= 0.0):
        return "the loads' virtual work changes sign before α falls to 0"
    phi0 = float(brentq(lambda p: chain.work(p)[0], grid[k - 1], grid[k], xtol=1e-14))
    phis = np.linspace(0.0, phi0, samples)
    alphas = np.array([chain.load_factor(p) for p in phis])
    alphas[-1] = 0.0
    dc = np.array([chain.control_displacement(p) for p in phis])
    d = dc * factor
    if np.any(np.diff(d) <= 0.0):
        return "the control point does not move steadily along the loads"
    return CapacityCurve(phis, dc, d, alphas, alphas * scale, phi0)


def kinematic_analysis(assembly: Geometry, limit: LimitResult, *,
                       confidence_factor: float = 1.0, g: float = 9.81,
                       samples: int = DEFAULT_SAMPLES) -> KinematicAnalysis:
    """The code's quantities of the collapse mechanism ``limit`` of ``assembly``.

    Parameters
    ----------
    assembly : Geometry
        The geometry ``limit`` was computed for.
    limit : LimitResult
        Its limit analysis, of status "collapse".
    confidence_factor : float
        FC (≥ 1; the Circolare's 1.35, 1.20, 1.00 for the knowledge levels LC1–LC3).
    g : float
        Gravity (m/s²).
    samples : int
        Points of the capacity curve (≥ 2).

    Returns
    -------
    KinematicAnalysis

    Raises
    ------
    ScenarioError
        ``limit`` is not a collapse (the assembly does not stand, or no mechanism
        exists), or bad FC, g or samples.
    """
    if limit.status != "collapse":
        what = {"unstable": "the assembly cannot stand under its own weight",
                "no_mechanism": "no mechanism opens under horizontal loads"}[limit.status]
        raise ScenarioError(f"no kinematic analysis: {what} (limit analysis status "
                            f"{limit.status!r})")
    if not (math.isfinite(confidence_factor) and confidence_factor >= 1.0):
        raise ScenarioError(f"confidence factor FC must be >= 1, got {confidence_factor!r}")
    if not (math.isfinite(g) and g > 0):
        raise ScenarioError(f"g must be finite and > 0, got {g!r}")
    if int(samples) != samples or samples < 2:
        raise ScenarioError(f"samples must be an integer >= 2, got {samples!r}")
    moving = [m for m in limit.mechanism if m.kind != "rest"]
    blocks = tuple(m.block for m in moving)
    weights = assembly.masses[list(blocks)] * g
    centroids = assembly.centroids[list(blocks)]
    direction = limit.direction
    ux = np.array([direction * m.velocity[0] for m in moving])
    uz = np.array([m.velocity[1] for m in moving])
    along = ux > 1e-9 * float(np.abs(ux).max())
    control_pos = max(np.nonzero(along)[0], key=lambda i: (centroids[i, 1], -i))
    control = blocks[int(control_pos)]
    dx, dz = ux / ux[control_pos], uz / ux[control_pos]
    sum_pd = float((weights * dx).sum())
    sum_pd2 = float((weights * dx ** 2).sum())
    mstar = sum_pd ** 2 / (g * sum_pd2)
    estar = g * mstar / float(weights.sum())
    alpha0 = limit.load_factor
    groups = _groups(assembly, limit)
    curve: CapacityCurve | str
    if isinstance(groups, str):
        curve = groups
    else:
        chain = _Chain(groups, blocks, centroids, weights, control, direction)
        curve = _curve(chain, alpha0, sum_pd2 / sum_pd, g / (estar * confidence_factor),
                       int(samples))
    return KinematicAnalysis(
        direction=direction, load_factor=alpha0, governing_mode=limit.governing_mode,
        moving_blocks=blocks, weights=weights, centroids=centroids, delta_x=dx, delta_z=dz,
        control_block=control, control_point=centroids[control_pos].copy(),
        participating_mass=mstar, mass_fraction=estar,
        confidence_factor=float(confidence_factor), g=float(g),
        curve=None if isinstance(curve, str) else curve,
        no_curve_reason=curve if isinstance(curve, str) else "")
