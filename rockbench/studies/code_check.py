"""The Italian code check of a local mechanism beside the dynamics (NTC 2018 §8.7.1).

An engineer assessing a masonry element files the kinematic analysis of its
local mechanism: NTC 2018 §8.7.1 and the Circolare of 21 January 2019 n. 7
§C8.7.1.2.1. :func:`code_check` does it for a rockbench scenario at a site
(:class:`SiteParameters`, read from a small TOML file by :func:`load_site`), for
each direction of the loads (+x, −x):

* the mechanism and α_0 from limit analysis (the scenario's friction, real
  Coulomb joints: :func:`rockbench.studies.tilting.reference`), its code
  quantities from :func:`rockbench.analytic.kinematic.kinematic_analysis`;
* the **linear check** (§C8.7.1.2.1.7 with §C8.7.1.2.1.5): the ground
  acceleration that activates the mechanism a_g,SLD is the one whose peak
  acceleration at the element's base equals a_0* = α_0 g/(e* FC) [C8.7.1.8];
  a_g,SLV = q a_g,SLD must reach the site's a_g. With the demand linear in a_g
  this is a_0* ≥ a_base/q, a_base the base's peak acceleration: a_g S g on the
  ground, the floor acceleration a_Z(z) [C7.2.7], [C7.2.8] at a height z
  (:class:`LinearCheck`);
* the **non-linear check** (§C8.7.1.2.1.8), where the mechanism has finite
  kinematics: the capacity d_SLV = 0.4 d_0 at T_SLV = 1.68 π √(d_SLV/a(d_SLV))
  against the displacement demand, S_De(T) (§3.2.3.2.3) on the ground (its
  largest value on [0, T_SLV]) or [C8.7.1.12] on the floor spectrum at a height,
  both for the mechanism's damping ξ = 8 %; a_g,SLV = a_g d_SLV/demand, not less
  than a_g,SLD (:class:`NonLinearCheck`).

For the comparison with dynamics each check carries ``design_pga``, the code's
peak acceleration at the element's base (m/s²: a_g S g on the ground, the peak
floor acceleration a_Z(z) g of [C7.2.7] at a height), and ``capacity_pga``, the
same acceleration at the hazard level a_g,SLV at which the check is exactly met:
the demand is scaled with a_g *holding the spectral shape fixed* (S, F_0, T_B,
T_C, T_D of the site, although S_S and T_D depend on a_g in the code).

The element is rigid until the mechanism opens (T_0 = 0): the Circolare's
hypothesis for walls restrained by the rest of the building; for an element
free to vibrate (a parapet, a pinnacle) it asks for an elastic period T_0 from
the masonry's modulus [C8.7.1.7], which rigid blocks do not have. At a height
the base's acceleration is not taken below the ground's a_g S (the first-mode
formula tends to 0 at the foot of the building, whose floor moves with the
ground); the 2009 Circolare (C8A.4.2.3) required both checks.

Beside it, :class:`Ec8Check` is Eurocode 8's force-based check of a non-structural element
(EN 1998-1 §4.3.5.2, :mod:`rockbench.analytic.ec8_elements`): the element's design
acceleration S_a γ_a / q_a against the collapse multiplier α_0 g of limit analysis (the
same load pattern: a horizontal force proportional to each block's weight), with the
site's a_g, its ground type's soil factor and topographic factor, and the building's
z/H and T_1 (T_a = 0: a rigid element).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, cast

import numpy as np

from rockbench import checks
from rockbench.analytic.code_spectra import (
    Building,
    FloorModel,
    SiteSpectrum,
    floor_acceleration,
    floor_displacement_demand,
    simplified_floor_spectrum,
)
from rockbench.analytic.ec8_elements import element_coefficient, soil_factor
from rockbench.analytic.kinematic import KinematicAnalysis, kinematic_analysis
from rockbench.analytic.static_collapse import Flow, LimitResult, limit_analysis
from rockbench.errors import ScenarioError
from rockbench.scenarios import Scenario
from rockbench.studies.tilting import reference
from rockbench.tomlfile import read_toml

__all__ = ["CODES", "SLV_DAMPING", "DEFAULT_Q", "DEFAULT_FC", "SiteParameters", "CodeCheckInput",
           "load_site", "site_from_dict", "LinearCheck", "NonLinearCheck", "DirectionCheck",
           "CodeCheckResult", "Ec8Check", "code_check", "Check"]

#: Codes the check implements.
CODES = ("ntc2018",)
#: Equivalent viscous damping of the mechanism at the SLV (%), Circolare 2019 §C8.7.1.2.1.8.
SLV_DAMPING = 8.0
#: Behaviour factor q of the linear check (Circolare 2019 §C8.7.1.2.1.7: "si può assumere q = 2").
DEFAULT_Q = 2.0
#: Confidence factor FC of knowledge level LC1 (Circolare 2019 Tab. C8.5.IV).
DEFAULT_FC = 1.35
#: Periods sampled for the largest ground displacement demand on [0, T_SLV].
_DEMAND_SAMPLES = 2001
_TOP_KEYS = ("code", "ag", "F0", "TC_star", "soil", "topography", "q", "confidence_factor",
             "building", "description", "ec8")
_EC8_KEYS = ("qa", "importance")
_BUILDING_KEYS = ("height", "element_height", "period", "storeys", "damping", "floor_model")
#: Which check: the linear (q) or the non-linear (displacement) one.
Check = Literal["linear", "nonlinear"]


@dataclass(frozen=True)
class SiteParameters:
    """Where the element stands and how the code is applied (the site file).

    Parameters
    ----------
    ag : float
        a_g (in g) of the SLV return period on rigid ground.
    F0, TC_star : float
        F_0 and T_C* (s) of the same return period.
    soil, topography : str
        Subsoil category A–E, topographic category T1–T4.
    q : float
        Behaviour factor of the linear check (≥ 1; default 2.0).
    confidence_factor : float
        FC (≥ 1; default 1.35, knowledge level LC1).
    building : Building or None
        The building the element stands on (None: on the ground).
    floor_model : {"modal", "simplified"}
        Floor demand: first mode [C7.2.5]–[C7.2.8] or the simplified [C7.2.11].
    ec8_qa, ec8_importance : float
        q_a and γ_a of Eurocode 8's element check (``[ec8]`` ``qa``, ``importance``;
        default 1.0 and 1.0: a cantilevering parapet of ordinary importance).
    code : str
        "ntc2018".
    description : str
        Free text.
    source : str
        The file it was read from ("" if built in code).

    Raises
    ------
    ScenarioError
        A value out of range or an unknown category (the message names the field).
    """

    ag: float
    F0: float
    TC_star: float
    soil: str = "A"
    topography: str = "T1"
    q: float = DEFAULT_Q
    confidence_factor: float = DEFAULT_FC
    building: Building | None = None
    floor_model: FloorModel = "modal"
    ec8_qa: float = 1.0
    ec8_importance: float = 1.0
    code: str = "ntc2018"
    description: str = ""
    source: str = ""

    def __post_init__(self) -> None:
        if self.code not in CODES:
            raise ScenarioError(f"code must be one of {', '.join(map(repr, CODES))}, got "
                                f"{checks.describe(self.code)}")
        spec = SiteSpectrum(self.ag, self.F0, self.TC_star, self.soil, self.topography)
        for name in ("ag", "F0", "TC_star"):
            object.__setattr__(self, name, getattr(spec, name))
        object.__setattr__(self, "q", checks.number(self.q, "q", low=1.0, strict=False,
                                                    high=10.0))
        object.__setattr__(self, "confidence_factor", checks.number(
            self.confidence_factor, "confidence_factor", low=1.0, strict=False, high=3.0))
        if self.floor_model not in ("modal", "simplified"):
            raise ScenarioError(f"building.floor_model must be 'modal' or 'simplified', got "
                                f"{checks.describe(self.floor_model)}")
        if self.building is not None and not isinstance(self.building, Building):
            raise ScenarioError("building must be a Building")
        object.__setattr__(self, "ec8_qa", checks.number(self.ec8_qa, "ec8.qa", low=1.0,
                                                         strict=False, high=5.0))
        object.__setattr__(self, "ec8_importance", checks.number(
            self.ec8_importance, "ec8.importance", low=0.5, high=3.0))

    @property
    def spectrum(self) -> SiteSpectrum:
        """The site's elastic spectrum at 5 % damping (NTC 2018 §3.2.3.2.1)."""
        return SiteSpectrum(self.ag, self.F0, self.TC_star, self.soil, self.topography)

    @property
    def element_height(self) -> float:
        """Height z of the element's base (m; 0 on the ground)."""
        return 0.0 if self.building is None else self.building.element_height

    def base_acceleration(self) -> float:
        """The code's peak acceleration at the element's base, in g (module docstring).

        a_g S on the ground; at a height the peak floor acceleration a_Z(z)
        ([C7.2.7], [C7.2.8], first mode; or α S (1 + z/H) of [C7.2.11] at T_a = 0),
        not below a_g S.
        """
        spec = self.spectrum
        if self.building is None:
            return spec.pga
        if self.floor_model == "simplified":
            floor = simplified_floor_spectrum(spec, self.building, 0.0)
        else:
            floor = floor_acceleration(spec, self.building)
        return max(floor, spec.pga)

    def displacement_demand(self, period: float, g: float = 9.81,
                            damping: float = SLV_DAMPING) -> float:
        """The displacement demand (m) on a mechanism of period T_SLV (module docstring).

        On the ground the largest S_De on [0, T] (§C8.7.1.2.1.8); at a height
        [C8.7.1.12] on the floor spectrum, not below the ground's.
        """
        spec = self.spectrum.with_damping(damping)
        periods = np.linspace(0.0, period, _DEMAND_SAMPLES)
        ground = float(np.max(spec.displacement(periods, g)))
        if self.building is None:
            return ground
        floor = floor_displacement_demand(self.spectrum, self.building, period, damping, g,
                                          self.floor_model)
        return max(floor, ground)

    def to_dict(self) -> dict[str, Any]:
        """The site file's content (TOML-able)."""
        d: dict[str, Any] = {"code": self.code, "ag": self.ag, "F0": self.F0,
                             "TC_star": self.TC_star, "soil": self.soil,
                             "topography": self.topography, "q": self.q,
                             "confidence_factor": self.confidence_factor}
        if self.description:
            d["description"] = self.description
        if self.building is not None:
            b = self.building
            d["building"] = {"height": b.height, "element_height": b.element_height,
                             "period": b.period, "storeys": b.storeys, "damping": b.damping,
                             "floor_model": self.floor_model}
        d["ec8"] = {"qa": self.ec8_qa, "importance": self.ec8_importance}
        return d

    def ec8_coefficient(self) -> float:
        """S_a of EN 1998-1 [4.25] (g) of a rigid element (T_a = 0) at the element's base:
        the site's a_g, the type 1 soil factor of its ground type times its S_T."""
        soil = soil_factor(self.soil) * self.spectrum.ST
        if self.building is None:
            return element_coefficient(self.ag, soil)
        b = self.building
        return element_coefficient(self.ag, soil, b.element_height, b.height, 0.0, b.period)


#: The brief's name for the same type.
CodeCheckInput = SiteParameters


def _text(data: Mapping[str, Any], key: str, default: str, where: str = "") -> str:
    return checks.text(data.get(key, default), f"{where}{key}")


def site_from_dict(data: Mapping[str, Any], source: str = "") -> SiteParameters:
    """A :class:`SiteParameters` from a site file's table (see :func:`load_site`).

    Raises
    ------
    ScenarioError
        Unknown keys, missing or invalid values (one line naming the field).
    """
    checks.no_unknown(data, _TOP_KEYS, "the site file")
    for key in ("ag", "F0", "TC_star"):
        if key not in data:
            raise ScenarioError(f"{key} is missing: a site needs ag (g), F0 and TC_star (s) "
                                f"of the SLV return period")
    building = None
    floor_model: str = "modal"
    if "building" in data:
        raw = checks.table(data["building"], "building")
        checks.no_unknown(raw, _BUILDING_KEYS, "[building]")
        for key in ("height", "element_height", "period", "storeys"):
            if key not in raw:
                raise ScenarioError(f"building.{key} is missing: [building] needs height (m), "
                                    f"element_height (m), period (s) and storeys")
        building = Building(raw["height"], raw["element_height"], raw["period"],
                            raw["storeys"], raw.get("damping", 5.0))
        floor_model = _text(raw, "floor_model", "modal", "building.")
    ec8 = checks.table(data.get("ec8", {}), "ec8")
    checks.no_unknown(ec8, _EC8_KEYS, "[ec8]")
    return SiteParameters(
        ag=data["ag"], F0=data["F0"], TC_star=data["TC_star"],
        soil=_text(data, "soil", "A"), topography=_text(data, "topography", "T1"),
        q=data.get("q", DEFAULT_Q), confidence_factor=data.get("confidence_factor", DEFAULT_FC),
        building=building, floor_model=cast(FloorModel, floor_model),
        ec8_qa=ec8.get("qa", 1.0), ec8_importance=ec8.get("importance", 1.0),
        code=_text(data, "code", "ntc2018"), description=_text(data, "description", ""),
        source=source)


def load_site(path: str | Path) -> SiteParameters:
    """Read a site file (TOML).

    A site file reads::

        code = "ntc2018"          # the only code implemented
        ag = 0.25                 # g, SLV return period, rigid ground
        F0 = 2.4
        TC_star = 0.3             # s
        soil = "C"                # A-E (NTC 2018 Tab. 3.2.II)
        topography = "T1"         # T1-T4 (Tab. 3.2.III)
        q = 2.0                   # behaviour factor of the linear check
        confidence_factor = 1.35  # FC

        [building]                # optional: the element stands on a building
        height = 12.0             # H (m)
        element_height = 12.0     # z of the element's base (m)
        period = 0.4              # T1 (s)
        storeys = 4               # N
        damping = 5.0             # xi_1 (%), optional
        floor_model = "modal"     # or "simplified" (Circolare [C7.2.11])

        [ec8]                     # optional: Eurocode 8's element check
        qa = 1.0                  # q_a (EN 1998-1 Tab. 4.4)
        importance = 1.0          # gamma_a

    Raises
    ------
    ScenarioError
        Unreadable or malformed file, unknown keys or invalid values; the message
        starts with the file name and names the field.
    """
    path = Path(path)
    data = read_toml(path, ScenarioError, "site file")
    try:
        return site_from_dict(data, str(path))
    except ScenarioError as exc:
        raise ScenarioError(f"{path}: {exc}") from None


# ---------------------------------------------------------------------- checks
@dataclass(frozen=True)
class LinearCheck:
    """The linear kinematic check at the SLV (Circolare 2019 §C8.7.1.2.1.7).

    Attributes
    ----------
    spectral_acceleration : float
        a_0* (m/s²): the capacity.
    design_pga : float
        The code's peak acceleration at the element's base (m/s²).
    q : float
        Behaviour factor.
    ag : float
        The site's a_g (g).
    """

    spectral_acceleration: float
    design_pga: float
    q: float
    ag: float

    @property
    def demand(self) -> float:
        """a_base / q (m/s²): what a_0* must reach."""
        return self.design_pga / self.q

    @property
    def ratio(self) -> float:
        """Capacity / demand = a_0* q / a_base = a_g,SLV / a_g."""
        return self.spectral_acceleration / self.demand

    @property
    def passed(self) -> bool:
        """True if a_0* ≥ a_base / q."""
        return self.ratio >= 1.0

    @property
    def capacity_ag(self) -> float:
        """a_g,SLV = q a_g,SLD (g): the site a_g at which the check is exactly met."""
        return self.ag * self.ratio

    @property
    def capacity_pga(self) -> float:
        """The base's peak acceleration (m/s²) at a_g,SLV: q a_0*."""
        return self.design_pga * self.ratio


@dataclass(frozen=True)
class NonLinearCheck:
    """The non-linear (displacement) kinematic check at the SLV (§C8.7.1.2.1.8).

    Attributes
    ----------
    capacity : float
        d_SLV = 0.4 d_0 (m).
    acceleration : float
        a(d_SLV) on the capacity curve (m/s²).
    period : float
        T_SLV (s) [C8.7.1.10].
    demand : float
        The displacement demand at the site's a_g (m), for ξ = :data:`SLV_DAMPING`.
    activation_ratio : float
        a_g,SLD / a_g: the activation check without q (the floor of a_g,SLV).
    design_pga : float
        The code's peak acceleration at the element's base (m/s²).
    ag : float
        The site's a_g (g).
    damping : float
        The mechanism's damping ξ (%).
    """

    capacity: float
    acceleration: float
    period: float
    demand: float
    activation_ratio: float
    design_pga: float
    ag: float
    damping: float = SLV_DAMPING

    @property
    def displacement_ratio(self) -> float:
        """d_SLV / demand."""
        return self.capacity / self.demand

    @property
    def ratio(self) -> float:
        """a_g,SLV / a_g, a_g,SLV not below a_g,SLD (§C8.7.1.2.1.8)."""
        return max(self.displacement_ratio, self.activation_ratio)

    @property
    def governed_by_activation(self) -> bool:
        """True if a_g,SLD (activation) rather than the displacement sets a_g,SLV."""
        return self.activation_ratio > self.displacement_ratio

    @property
    def passed(self) -> bool:
        """True if a_g,SLV ≥ a_g."""
        return self.ratio >= 1.0

    @property
    def capacity_ag(self) -> float:
        """a_g,SLV (g)."""
        return self.ag * self.ratio

    @property
    def capacity_pga(self) -> float:
        """The base's peak acceleration (m/s²) at a_g,SLV."""
        return self.design_pga * self.ratio


@dataclass(frozen=True, eq=False)
class DirectionCheck:
    """The check of the mechanism under loads toward one direction.

    Attributes
    ----------
    direction : int
        +1: loads toward +x (a base acceleration toward −x); −1 the reverse.
    limit : LimitResult
        The limit analysis.
    kinematics : KinematicAnalysis or None
        Its code quantities (None unless the limit analysis found a collapse).
    linear, nonlinear : LinearCheck or NonLinearCheck or None
        The checks (``nonlinear`` None without finite kinematics).
    note : str
        Why a check is missing ("" when both are there).
    """

    direction: int
    limit: LimitResult
    kinematics: KinematicAnalysis | None
    linear: LinearCheck | None
    nonlinear: NonLinearCheck | None
    note: str = ""

    @property
    def label(self) -> str:
        """"+x" or "−x"."""
        return "+x" if self.direction > 0 else "−x"

    @property
    def passed(self) -> bool:
        """True if every check done passes; an assembly that cannot stand fails, one with
        no mechanism passes."""
        if self.limit.status == "unstable":
            return False
        return all(c.passed for c in (self.linear, self.nonlinear) if c is not None)


@dataclass(frozen=True)
class Ec8Check:
    """Eurocode 8's check of a rigid non-structural element (EN 1998-1 §4.3.5.2).

    Attributes
    ----------
    alpha0 : float
        The smaller collapse multiplier of the two directions (limit analysis).
    coefficient : float
        S_a of [4.25] (g), T_a = 0.
    qa, importance : float
        q_a and γ_a.
    g : float
        Gravity (m/s²).
    """

    alpha0: float
    coefficient: float
    qa: float
    importance: float
    g: float

    @property
    def ratio(self) -> float:
        """α_0 / (S_a γ_a / q_a): the overturning resistance over the design force."""
        return self.alpha0 * self.qa / (self.coefficient * self.importance)

    @property
    def passed(self) -> bool:
        """True if the resistance reaches the design force."""
        return self.ratio >= 1.0

    @property
    def design_pga(self) -> float:
        """S_a g (m/s²): the design acceleration of a rigid element at its base."""
        return self.coefficient * self.g

    @property
    def capacity_pga(self) -> float:
        """α_0 g q_a / γ_a (m/s²): the base acceleration at which the check is exactly met."""
        return self.design_pga * self.ratio


@dataclass(frozen=True, eq=False)
class CodeCheckResult:
    """The code check of a scenario at a site (:func:`code_check`).

    Attributes
    ----------
    scenario : Scenario
        What was checked (at rest).
    site : SiteParameters
        Where.
    friction : float
        Coulomb μ of the joints in the limit analysis.
    design_pga : float
        The code's peak acceleration at the element's base (m/s²): a_g S g on the
        ground, a_Z(z) g ([C7.2.7], first mode; not below a_g S g) at a height.
    directions : tuple of DirectionCheck
        Loads toward +x, then −x.
    ec8 : Ec8Check or None
        Eurocode 8's element check (None when no direction has a collapse mechanism).
    """

    scenario: Scenario
    site: SiteParameters
    friction: float
    design_pga: float
    directions: tuple[DirectionCheck, ...]
    ec8: Ec8Check | None = None

    @property
    def passed(self) -> bool:
        """True if every direction passes every check done."""
        return all(d.passed for d in self.directions)

    def checks(self, check: Check) -> list[tuple[DirectionCheck, LinearCheck | NonLinearCheck]]:
        """The (direction, check) pairs of one kind that were done."""
        out: list[tuple[DirectionCheck, LinearCheck | NonLinearCheck]] = []
        for d in self.directions:
            c = d.linear if check == "linear" else d.nonlinear
            if c is not None:
                out.append((d, c))
        return out

    def capacity_pga(self, check: Check = "nonlinear") -> float:
        """The smallest capacity_pga (m/s²) of ``check`` over the directions; NaN if none
        (no mechanism, no finite kinematics, or an assembly that cannot stand)."""
        values = [c.capacity_pga for _, c in self.checks(check)]
        return min(values) if values else math.nan

    def capacity_ag(self, check: Check = "nonlinear") -> float:
        """The smallest a_g,SLV (g) of ``check`` over the directions; NaN if none."""
        values = [c.capacity_ag for _, c in self.checks(check)]
        return min(values) if values else math.nan

    def capacity_ground_pga(self, check: Check = "nonlinear") -> float:
        """a_g,SLV S g (m/s²): the ground's peak acceleration at the smallest a_g,SLV of
        ``check`` (equal to :meth:`capacity_pga` on the ground; at a height that one is the
        floor's); NaN if no such check was done."""
        return self.capacity_ag(check) * self.site.spectrum.S * self.scenario.g

    def to_dict(self) -> dict[str, Any]:
        """Every number of the check, JSON-able (NaN and inf become None)."""
        g = self.scenario.g
        out: dict[str, Any] = {
            "scenario": self.scenario.name, "code": self.site.code,
            "clauses": "NTC 2018 §8.7.1, §3.2.3.2; Circolare 2019 n. 7 §C8.7.1.2.1, §C7.2.3",
            "site": self.site.to_dict(), "site_file": self.site.source or None,
            "spectrum": _spectrum_dict(self.site.spectrum),
            "friction": _num(self.friction), "g": g,
            "element_height": self.site.element_height,
            "design_pga": self.design_pga, "design_pga_g": self.design_pga / g,
            "passed": self.passed,
            "capacity_pga": {"linear": _num(self.capacity_pga("linear")),
                             "nonlinear": _num(self.capacity_pga("nonlinear"))},
            "capacity_ground_pga": {"linear": _num(self.capacity_ground_pga("linear")),
                                    "nonlinear": _num(self.capacity_ground_pga("nonlinear"))},
            "directions": [_direction_dict(d) for d in self.directions],
            "ec8": None if self.ec8 is None else {
                "clause": "EN 1998-1 §4.3.5.2", **dataclasses.asdict(self.ec8),
                "ratio": self.ec8.ratio, "passed": self.ec8.passed,
                "design_pga": self.ec8.design_pga, "capacity_pga": self.ec8.capacity_pga},
        }
        return out


def _num(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def _spectrum_dict(s: SiteSpectrum) -> dict[str, Any]:
    return {"SS": s.SS, "ST": s.ST, "S": s.S, "CC": s.CC, "eta": s.eta, "TB": s.TB,
            "TC": s.TC, "TD": s.TD, "TE": s.TE, "TF": s.TF, "pga_g": s.pga,
            "plateau_g": s.plateau}


def _direction_dict(d: DirectionCheck) -> dict[str, Any]:
    out: dict[str, Any] = {"direction": d.label, "status": d.limit.status,
                           "load_factor": _num(d.limit.load_factor),
                           "governing_mode": d.limit.governing_mode, "passed": d.passed,
                           "note": d.note}
    k = d.kinematics
    if k is not None:
        out["mechanism"] = {
            "moving_blocks": list(k.moving_blocks), "weights": k.weights.tolist(),
            "delta_x": k.delta_x.tolist(), "control_block": k.control_block,
            "control_point": k.control_point.tolist(),
            "participating_mass": k.participating_mass, "mass_fraction": k.mass_fraction,
            "confidence_factor": k.confidence_factor,
            "spectral_acceleration": k.spectral_acceleration,
            "finite_kinematics": k.has_curve, "no_curve_reason": k.no_curve_reason or None}
        if k.curve is not None:
            out["mechanism"].update({
                "d0": k.d0, "rotation0": k.curve.rotation0, "d_slv": k.d_slv,
                "a_slv": k.a_slv, "period_slv": k.period_slv, "d_slc": k.d_slc,
                "a_slc": k.a_slc, "period_slc": k.period_slc,
                "circolare_2009": {"du": k.du_2009, "ds": k.ds_2009, "as": k.as_2009,
                                   "Ts": k.secant_period_2009},
                "curve": {"d": k.curve.displacement.tolist(),
                          "a": k.curve.acceleration.tolist(),
                          "alpha": k.curve.load_factor.tolist()}})
    for name, c in (("linear", d.linear), ("nonlinear", d.nonlinear)):
        if c is None:
            out[name] = None
            continue
        row = dataclasses.asdict(c)
        row.update({"ratio": c.ratio, "passed": c.passed, "capacity_ag": c.capacity_ag,
                    "capacity_pga": c.capacity_pga})
        if isinstance(c, NonLinearCheck):
            row.update({"displacement_ratio": c.displacement_ratio,
                        "governed_by_activation": c.governed_by_activation})
        else:
            row["demand"] = c.demand
        out[name] = row
    return out


def _limit(scenario: Scenario, direction: int, friction: float) -> LimitResult:
    """:func:`rockbench.studies.tilting.reference` with any μ (inf: the associative,
    no-sliding limit)."""
    if friction == scenario.contact.friction:
        return reference(scenario, direction)
    flow: Flow = "non-associative" if math.isfinite(friction) else "associative"
    return limit_analysis(scenario.geometry, friction=friction, direction=direction,
                          g=scenario.g, flow=flow)


def _direction(scenario: Scenario, site: SiteParameters, direction: int,
               design_pga: float, friction: float) -> DirectionCheck:
    limit = _limit(scenario, direction, friction)
    if limit.status != "collapse":
        note = ("no mechanism opens under horizontal loads: nothing to check"
                if limit.status == "no_mechanism"
                else "the assembly cannot stand under its own weight: it fails")
        return DirectionCheck(direction, limit, None, None, None, note)
    k = kinematic_analysis(scenario.geometry, limit, confidence_factor=site.confidence_factor,
                           g=scenario.g)
    linear = LinearCheck(k.spectral_acceleration, design_pga, site.q, site.ag)
    if k.curve is None:
        return DirectionCheck(direction, limit, k, linear, None,
                              f"no non-linear check: no finite kinematics for this "
                              f"mechanism ({k.no_curve_reason})")
    demand = site.displacement_demand(k.period_slv, scenario.g)
    nonlinear = NonLinearCheck(k.d_slv, k.a_slv, k.period_slv, demand,
                               k.spectral_acceleration / design_pga, design_pga, site.ag)
    return DirectionCheck(direction, limit, k, linear, nonlinear)


def code_check(scenario: Scenario, site: SiteParameters, *,
               friction: float | None = None) -> CodeCheckResult:
    """The NTC 2018 kinematic check of ``scenario``'s blocks at ``site`` (module docstring).

    Parameters
    ----------
    scenario : Scenario
        Its geometry, friction and gravity (the excitation is ignored).
    site : SiteParameters
        Hazard, soil, q, FC and, optionally, the building the element stands on.
    friction : float, optional
        Coulomb μ of every joint instead of the scenario's (``math.inf``: no sliding, the
        Circolare's traditional hypothesis).

    Returns
    -------
    CodeCheckResult

    Raises
    ------
    ScenarioError
        A negative friction.
    """
    mu = scenario.contact.friction
    if friction is not None:
        mu = math.inf if friction == math.inf else checks.number(friction, "friction",
                                                                 low=0.0, strict=False)
    design_pga = site.base_acceleration() * scenario.g
    dirs = tuple(_direction(scenario, site, d, design_pga, mu) for d in (1, -1))
    alphas = [d.limit.load_factor for d in dirs if d.limit.status == "collapse"]
    ec8 = (Ec8Check(min(alphas), site.ec8_coefficient(), site.ec8_qa, site.ec8_importance,
                    scenario.g) if alphas else None)
    return CodeCheckResult(scenario, site, mu, design_pga, dirs, ec8)
