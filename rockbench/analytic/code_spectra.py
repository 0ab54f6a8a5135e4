"""The Italian code's seismic demand: NTC 2018 elastic spectra and the Circolare's floor demand.

The demand side of the code check of local mechanisms
(:mod:`rockbench.studies.code_check`). Everything here is a closed form of the
code; accelerations are in units of g, periods in s, displacements in m.

Ground (NTC 2018 §3.2.3.2)
--------------------------
:class:`SiteSpectrum` is the horizontal elastic spectrum of §3.2.3.2.1
[3.2.2] at a site given by the hazard parameters of the chosen return period
(a_g in g, F_0, T_C* in s), the subsoil category A–E and the topographic
category T1–T4:

* S = S_S S_T [3.2.3]; S_S and C_C from Tab. 3.2.IV (B: 1.00 ≤ 1.40 − 0.40 F_0 a_g/g
  ≤ 1.20, C_C = 1.10 T_C*^−0.20; C: 1.00 ≤ 1.70 − 0.60 F_0 a_g/g ≤ 1.50,
  C_C = 1.05 T_C*^−0.33; D: 0.90 ≤ 2.40 − 1.50 F_0 a_g/g ≤ 1.80, C_C = 1.25 T_C*^−0.50;
  E: 1.00 ≤ 2.00 − 1.10 F_0 a_g/g ≤ 1.60, C_C = 1.15 T_C*^−0.40; A: 1, 1); S_T from
  Tab. 3.2.V at the crest (T1 1.0, T2 1.2, T3 1.2, T4 1.4);
* η = √(10/(5 + ξ)) ≥ 0.55, ξ in percent [3.2.4];
* T_C = C_C T_C* [3.2.5], T_B = T_C/3 [3.2.6], T_D = 4 a_g/g + 1.6 [3.2.7];
* S_e(T) = a_g S η F_0 [T/T_B + (1 − T/T_B)/(η F_0)] below T_B, a_g S η F_0 on the
  plateau, × T_C/T up to T_D, × T_C T_D/T² beyond;
* the displacement spectrum of §3.2.3.2.3: S_De = S_e (T/2π)² [3.2.10] up to T_E,
  then 0.025 a_g S T_C T_D [F_0 η + (1 − F_0 η)(T − T_E)/(T_F − T_E)] up to T_F and
  d_g = 0.025 a_g S T_C T_D beyond [3.2.11], [3.2.12] (T_E, T_F of Tab. 3.2.VII:
  A 4.5, 10; B 5.0, 10; C, D, E 6.0, 10 s).

At a height of a building (Circolare 2019 §C7.2.3)
----------------------------------------------------
A part on a floor at height z of a building of height H feels the floor's
motion. :class:`Building` idealises the building by its first mode (the
Circolare's simplification for local mechanisms, §C8.7.1.2.1.8: "è sufficiente
considerare il solo primo modo"): period T_1, damping ξ_1 (percent), the linear
mode shape ψ_1(z) = z/H and the participation factor γ_1 = 3N/(2N + 1) of N
equal storeys [C7.2.10]. Then

* the peak floor acceleration [C7.2.7], [C7.2.8] (one mode)
  a_Z(z) = S_e(T_1, ξ_1) |γ_1 ψ_1(z)| √(1 + 0.0004 ξ_1²)   (:func:`floor_acceleration`);
* the floor spectrum [C7.2.6] (one mode; [C7.2.5] keeps it ≥ S_e(T, ξ) for T > T_1),
  with A = 1.1 ξ_1^−0.5 η(ξ), a = 0.8, b = 1.1:
  A a_Z / (1 + (A − 1)(1 − T/(a T_1))^1.6) for T < a T_1, A a_Z up to b T_1,
  A a_Z / (1 + (A − 1)(T/(b T_1) − 1)^1.2) beyond (:func:`floor_spectrum`).
  The Circolare says ξ_k is "in percentuale"; that is how it enters √(1 + 0.0004 ξ_k²)
  (1.005 at 5 %). In the amplification 1.1 ξ_k^−0.5 a percentage would give 0.49 at
  5 %, a floor spectrum below the floor acceleration and negative ordinates beyond
  b T_1, so there ξ_k is read as a ratio (0.05 → 4.92, close to the a_p = 5 of
  Tab. C7.2.II for T_1 < 0.5 s). :data:`FLOOR_AMPLIFICATION_DAMPING_AS_RATIO` names
  that reading.
* the simplified floor spectrum [C7.2.11] with a, b, a_p of Tab. C7.2.II:
  α S (1 + z/H) a_p / (1 + (a_p − 1)(1 − T_a/(a T_1))²) ≥ α S below a T_1,
  α S (1 + z/H) a_p up to b T_1, and the same fraction with b T_1 beyond
  (:func:`simplified_floor_spectrum`); at T_a = 0 it is the floor acceleration
  α S (1 + z/H).

:func:`floor_displacement_demand` is [C8.7.1.12]: S_eZ(T, ξ, z) T²/4π², not below
S_eZ(T_1, ξ, z) b² T_1²/4π² when T > b T_1 (a displacement spectrum that does not
decrease with the period).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, get_args, overload

import numpy as np

from rockbench import checks
from rockbench.errors import ScenarioError

__all__ = ["SoilCategory", "TopographyCategory", "FloorModel", "SiteSpectrum", "Building",
           "damping_factor", "floor_acceleration", "floor_spectrum",
           "simplified_floor_spectrum", "floor_displacement_demand",
           "simplified_floor_parameters", "FLOOR_A", "FLOOR_B",
           "FLOOR_AMPLIFICATION_DAMPING_AS_RATIO", "SOILS", "TOPOGRAPHIES"]

SoilCategory = Literal["A", "B", "C", "D", "E"]
TopographyCategory = Literal["T1", "T2", "T3", "T4"]
#: How the floor demand is computed: "modal" ([C7.2.5]–[C7.2.8], first mode) or
#: "simplified" ([C7.2.11], Tab. C7.2.II).
FloorModel = Literal["modal", "simplified"]

#: Subsoil categories of NTC 2018 Tab. 3.2.II.
SOILS: tuple[str, ...] = get_args(SoilCategory)
#: Topographic categories of NTC 2018 Tab. 3.2.III.
TOPOGRAPHIES: tuple[str, ...] = get_args(TopographyCategory)

#: Tab. 3.2.IV: soil → (intercept, slope, lower, upper) of S_S = intercept − slope F_0 a_g/g
#: clamped to [lower, upper], and (coefficient, exponent) of C_C = coefficient T_C*^exponent.
_SOIL_TABLE: dict[str, tuple[tuple[float, float, float, float], tuple[float, float]]] = {
    "A": ((1.00, 0.00, 1.00, 1.00), (1.00, 0.00)),
    "B": ((1.40, 0.40, 1.00, 1.20), (1.10, -0.20)),
    "C": ((1.70, 0.60, 1.00, 1.50), (1.05, -0.33)),
    "D": ((2.40, 1.50, 0.90, 1.80), (1.25, -0.50)),
    "E": ((2.00, 1.10, 1.00, 1.60), (1.15, -0.40)),
}
#: Tab. 3.2.V: S_T at the crest or top of the slope.
_TOPOGRAPHY_TABLE = {"T1": 1.0, "T2": 1.2, "T3": 1.2, "T4": 1.4}
#: Tab. 3.2.VII: soil → (T_E, T_F) (s).
_DISPLACEMENT_CORNERS = {"A": (4.5, 10.0), "B": (5.0, 10.0), "C": (6.0, 10.0),
                         "D": (6.0, 10.0), "E": (6.0, 10.0)}
#: [C7.2.6]: the floor spectrum's plateau runs from a T_1 to b T_1.
FLOOR_A = 0.8
FLOOR_B = 1.1
#: [C7.2.6]: ξ_1 enters the amplification 1.1 ξ_1^−0.5 as a ratio (module docstring).
FLOOR_AMPLIFICATION_DAMPING_AS_RATIO = True


def damping_factor(damping: float) -> float:
    """η = √(10/(5 + ξ)) ≥ 0.55, ξ in percent (NTC 2018 [3.2.4])."""
    xi = checks.number(damping, "damping", low=0.0, strict=False, unit="%")
    return max(math.sqrt(10.0 / (5.0 + xi)), 0.55)


@dataclass(frozen=True)
class SiteSpectrum:
    """The NTC 2018 horizontal elastic spectrum at a site (§3.2.3.2.1, §3.2.3.2.3).

    Parameters
    ----------
    ag : float
        Peak acceleration on rigid horizontal ground a_g (in g) for the limit
        state's return period.
    F0 : float
        Maximum spectral amplification on rigid ground (≥ 2.2, §3.2.3.2.1).
    TC_star : float
        Start of the constant-velocity branch on rigid ground T_C* (s).
    soil : {"A", "B", "C", "D", "E"}
        Subsoil category (Tab. 3.2.II).
    topography : {"T1", "T2", "T3", "T4"}
        Topographic category (Tab. 3.2.III); S_T is the crest value of Tab. 3.2.V.
    damping : float
        Viscous damping ratio ξ in percent (5: η = 1).

    Raises
    ------
    ScenarioError
        A value out of range or an unknown category.
    """

    ag: float
    F0: float
    TC_star: float
    soil: str = "A"
    topography: str = "T1"
    damping: float = 5.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "ag", checks.number(self.ag, "ag", low=0.0, high=2.0,
                                                     unit="g"))
        object.__setattr__(self, "F0", checks.number(self.F0, "F0", low=2.2, strict=False,
                                                     high=5.0))
        object.__setattr__(self, "TC_star", checks.number(self.TC_star, "TC_star", low=0.0,
                                                          high=2.0, unit="s"))
        if self.soil not in _SOIL_TABLE:
            raise ScenarioError(f"soil must be one of {', '.join(SOILS)} (NTC 2018 Tab. 3.2.II), "
                                f"got {checks.describe(self.soil)}")
        if self.topography not in _TOPOGRAPHY_TABLE:
            raise ScenarioError(f"topography must be one of {', '.join(TOPOGRAPHIES)} (NTC 2018 "
                                f"Tab. 3.2.III), got {checks.describe(self.topography)}")
        object.__setattr__(self, "damping", checks.number(self.damping, "damping", low=0.0,
                                                          strict=False, high=100.0, unit="%"))

    # ---------------------------------------------------------------- coefficients
    @property
    def SS(self) -> float:
        """Stratigraphic amplification S_S (Tab. 3.2.IV)."""
        (c0, c1, lo, hi), _ = _SOIL_TABLE[self.soil]
        return min(max(c0 - c1 * self.F0 * self.ag, lo), hi)

    @property
    def CC(self) -> float:
        """C_C of Tab. 3.2.IV (T_C = C_C T_C*)."""
        _, (k, e) = _SOIL_TABLE[self.soil]
        return k * self.TC_star ** e

    @property
    def ST(self) -> float:
        """Topographic amplification S_T (Tab. 3.2.V, crest value)."""
        return _TOPOGRAPHY_TABLE[self.topography]

    @property
    def S(self) -> float:
        """S = S_S S_T [3.2.3]."""
        return self.SS * self.ST

    @property
    def eta(self) -> float:
        """η of the spectrum's damping [3.2.4]."""
        return damping_factor(self.damping)

    @property
    def TC(self) -> float:
        """T_C = C_C T_C* (s) [3.2.5]."""
        return self.CC * self.TC_star

    @property
    def TB(self) -> float:
        """T_B = T_C/3 (s) [3.2.6]."""
        return self.TC / 3.0

    @property
    def TD(self) -> float:
        """T_D = 4 a_g/g + 1.6 (s) [3.2.7]."""
        return 4.0 * self.ag + 1.6

    @property
    def TE(self) -> float:
        """T_E (s) of Tab. 3.2.VII."""
        return _DISPLACEMENT_CORNERS[self.soil][0]

    @property
    def TF(self) -> float:
        """T_F (s) of Tab. 3.2.VII."""
        return _DISPLACEMENT_CORNERS[self.soil][1]

    @property
    def pga(self) -> float:
        """Peak ground acceleration at the surface a_g S (g): S_e(0)."""
        return self.ag * self.S

    @property
    def plateau(self) -> float:
        """a_g S η F_0 (g): the constant-acceleration branch."""
        return self.ag * self.S * self.eta * self.F0

    def with_damping(self, damping: float) -> SiteSpectrum:
        """The same site at another damping ratio ξ (percent)."""
        return SiteSpectrum(self.ag, self.F0, self.TC_star, self.soil, self.topography,
                            damping)

    # ---------------------------------------------------------------- ordinates
    @overload
    def acceleration(self, period: float) -> float: ...
    @overload
    def acceleration(self, period: np.ndarray) -> np.ndarray: ...

    def acceleration(self, period: float | np.ndarray) -> float | np.ndarray:
        """S_e(T) in g [3.2.2]; ``period`` ≥ 0 (s), a number or an array."""
        t = np.asarray(period, dtype=float)
        if np.any(~np.isfinite(t)) or np.any(t < 0):
            raise ScenarioError(f"spectral periods must be finite and >= 0 s, got {period!r}")
        top = self.plateau
        tb, tc, td = self.TB, self.TC, self.TD
        with np.errstate(divide="ignore", invalid="ignore"):
            rising = top * (t / tb + (1.0 - t / tb) / (self.eta * self.F0))
            out = np.where(t < tb, rising,
                           np.where(t < tc, top,
                                    np.where(t < td, top * tc / t, top * tc * td / t ** 2)))
        return float(out) if out.ndim == 0 else out

    @overload
    def displacement(self, period: float, g: float = ...) -> float: ...
    @overload
    def displacement(self, period: np.ndarray, g: float = ...) -> np.ndarray: ...

    def displacement(self, period: float | np.ndarray, g: float = 9.81) -> float | np.ndarray:
        """S_De(T) in m (§3.2.3.2.3 [3.2.10], [3.2.11]); ``g`` converts g to m/s²."""
        t = np.asarray(period, dtype=float)
        se = np.asarray(self.acceleration(t)) * g
        elastic = se * (t / (2.0 * math.pi)) ** 2
        dg = 0.025 * self.ag * g * self.S * self.TC * self.TD
        fe = self.F0 * self.eta
        te, tf = self.TE, self.TF
        middle = dg * (fe + (1.0 - fe) * (t - te) / (tf - te))
        out = np.where(t <= te, elastic, np.where(t <= tf, middle, dg))
        return float(out) if out.ndim == 0 else out


@dataclass(frozen=True)
class Building:
    """The building an element stands on, by its first mode (Circolare 2019 §C7.2.3).

    Parameters
    ----------
    height : float
        Height H of the building above the foundation (m).
    element_height : float
        Height z of the element's base (the floor or roof it stands on), 0 ≤ z ≤ H (m).
    period : float
        First-mode period T_1 (s).
    storeys : int
        Number of storeys N (γ_1 = 3N/(2N + 1) [C7.2.10]).
    damping : float
        First-mode damping ratio ξ_1 in percent (default 5).

    Raises
    ------
    ScenarioError
        A value out of range.
    """

    height: float
    element_height: float
    period: float
    storeys: int
    damping: float = 5.0

    def __post_init__(self) -> None:
        h = checks.length(self.height, "building.height")
        object.__setattr__(self, "height", h)
        z = checks.number(self.element_height, "building.element_height", low=0.0,
                          strict=False, high=h, unit="m")
        object.__setattr__(self, "element_height", z)
        object.__setattr__(self, "period", checks.number(self.period, "building.period",
                                                         low=0.0, high=10.0, unit="s"))
        object.__setattr__(self, "storeys", int(checks.integer(self.storeys,
                                                               "building.storeys")))
        object.__setattr__(self, "damping", checks.number(
            self.damping, "building.damping", low=0.0, high=100.0, unit="%"))

    @property
    def participation(self) -> float:
        """γ_1 = 3N/(2N + 1) [C7.2.10]."""
        n = self.storeys
        return 3.0 * n / (2.0 * n + 1.0)

    @property
    def mode_shape(self) -> float:
        """ψ_1(z) = z/H: the linear first mode at the element's height."""
        return self.element_height / self.height


def floor_acceleration(site: SiteSpectrum, building: Building) -> float:
    """Peak floor acceleration a_Z(z) in g, first mode ([C7.2.7], [C7.2.8]).

    a_Z = S_e(T_1, ξ_1) |γ_1 ψ_1(z)| √(1 + 0.0004 ξ_1²), ξ_1 in percent.
    """
    xi = building.damping
    se = site.with_damping(xi).acceleration(building.period)
    return se * abs(building.participation * building.mode_shape) * math.sqrt(
        1.0 + 0.0004 * xi ** 2)


def _amplification(building: Building, damping: float) -> float:
    """A = 1.1 ξ_1^−0.5 η(ξ) of [C7.2.6] (ξ_1 as a ratio: module docstring)."""
    xi1 = building.damping / 100.0 if FLOOR_AMPLIFICATION_DAMPING_AS_RATIO else building.damping
    return 1.1 * xi1 ** -0.5 * damping_factor(damping)


def floor_spectrum(site: SiteSpectrum, building: Building, period: float,
                   damping: float = 5.0) -> float:
    """Floor spectrum S_eZ(T, ξ, z) in g of the first mode ([C7.2.5], [C7.2.6]).

    Parameters
    ----------
    site, building : SiteSpectrum, Building
        The ground spectrum and the building.
    period : float
        The element's period T (s), ≥ 0.
    damping : float
        The element's damping ratio ξ in percent.
    """
    t = checks.number(period, "period", low=0.0, strict=False, unit="s")
    az = floor_acceleration(site, building)
    amp = _amplification(building, damping)
    t1 = building.period
    if t < FLOOR_A * t1:
        out = amp * az / (1.0 + (amp - 1.0) * (1.0 - t / (FLOOR_A * t1)) ** 1.6)
    elif t < FLOOR_B * t1:
        out = amp * az
    else:
        out = amp * az / (1.0 + (amp - 1.0) * (t / (FLOOR_B * t1) - 1.0) ** 1.2)
    if t > t1:
        out = max(out, site.with_damping(damping).acceleration(t))
    return out


def simplified_floor_parameters(period: float) -> tuple[float, float, float]:
    """(a, b, a_p) of Tab. C7.2.II for a building of first period T_1 (s)."""
    if period < 0.5:
        return 0.8, 1.4, 5.0
    if period <= 1.0:
        return 0.3, 1.2, 4.0
    return 0.3, 1.0, 2.5


def simplified_floor_spectrum(site: SiteSpectrum, building: Building, period: float) -> float:
    """The simplified floor spectrum S_a(T_a) in g of [C7.2.11] (Tab. C7.2.II).

    ``period`` is the element's T_a (s); at T_a = 0 it is the floor acceleration
    α S (1 + z/H) with α = a_g/g.
    """
    ta = checks.number(period, "period", low=0.0, strict=False, unit="s")
    a, b, ap = simplified_floor_parameters(building.period)
    t1 = building.period
    base = site.pga
    top = base * (1.0 + building.mode_shape) * ap
    if ta < a * t1:
        return max(top / (1.0 + (ap - 1.0) * (1.0 - ta / (a * t1)) ** 2), base)
    if ta < b * t1:
        return top
    return max(top / (1.0 + (ap - 1.0) * (1.0 - ta / (b * t1)) ** 2), base)


def floor_displacement_demand(site: SiteSpectrum, building: Building, period: float,
                              damping: float, g: float = 9.81,
                              model: FloorModel = "modal") -> float:
    """Displacement demand (m) on a mechanism at the floor of ``building`` [C8.7.1.12].

    S_eZ(T, ξ, z) T²/4π², and for T > b T_1 not less than S_eZ(T_1, ξ, z) b² T_1²/4π²
    (the end of the floor spectrum's plateau), so that the displacement spectrum does
    not decrease with the period. ``model`` picks the floor spectrum: [C7.2.6]
    ("modal", b = 1.1) or [C7.2.11] ("simplified", b of Tab. C7.2.II, whose damping
    is the spectrum's own 5 %).
    """
    t = checks.number(period, "period", low=0.0, strict=False, unit="s")
    t1 = building.period
    if model == "modal":
        b = FLOOR_B

        def spectrum(x: float) -> float:
            return floor_spectrum(site, building, x, damping)
    elif model == "simplified":
        b = simplified_floor_parameters(t1)[1]

        def spectrum(x: float) -> float:
            return simplified_floor_spectrum(site, building, x)
    else:
        raise ScenarioError(f"floor model must be 'modal' or 'simplified', got {model!r}")
    demand = spectrum(t) * g * t ** 2 / (4.0 * math.pi ** 2)
    if t > b * t1:
        demand = max(demand, spectrum(t1) * g * (b * t1) ** 2 / (4.0 * math.pi ** 2))
    return demand
