"""Intensity measures of a base excitation, and scaling a record to a target intensity.

Six measures are offered. All but the Arias intensity are homogeneous of degree
one in the acceleration, so that a record scaled by a factor k > 0 has k times the
intensity and scaling to a target is one division (the Arias intensity: k²):

``pga``
    Peak ground acceleration max |ü_g| (m/s²).
``pgv``
    Peak ground velocity max |u̇_g| (m/s), of the exact (piecewise quadratic)
    velocity of the record, including the peaks between samples.
``pga-uplift``
    PGA / (g tan λ): the peak acceleration over Housner's (1963) static uplift
    threshold; a block at rest starts rocking only where this exceeds 1.
``pgv-rocking``
    PGV · p / (g tan λ): the peak velocity over the block's velocity scale
    g tan λ / p. For a pulse of acceleration amplitude a_p and circular
    frequency ω_p, PGV = c a_p / ω_p (c = 2 for a one-sine, 1 for a one-cosine
    pulse), so this is c · (a_p / (g tan λ)) / (ω_p / p), the ratio of the two
    groups of Dimitrakopoulos & DeJong (2012); it is the velocity analogue of
    ``pga-uplift``.
``sa``
    Sa(T, ζ) = ω² max |q|, the pseudo-spectral acceleration of a linear oscillator of
    period T and damping ratio ζ (m/s²), its response exact for the record
    (:mod:`rockbench.scenarios.oscillator`); records only.
``arias``
    The Arias intensity π/(2g) ∫ ü_g² dt (m/s), exact for the piecewise-linear record;
    records only.

For the analytic pulses, :func:`pulse_ratios` gives the two dimensionless
groups of Dimitrakopoulos & DeJong (2012) themselves, ω_p / p and
a_p / (g tan λ) (α there, λ here), which with η govern the whole rocking
response to the pulse (similarity law). They are not amplitude measures of a
record: ω_p / p does not change with scaling, and a record's pulse (a_p, ω_p)
needs a pulse-extraction method (e.g. Baker 2007) that rockbench does not
implement.

References
----------
G. W. Housner (1963), The behavior of inverted pendulum structures during
earthquakes, Bull. Seismol. Soc. Am. 53(2), 403–417.
E. G. Dimitrakopoulos, M. J. DeJong (2012), Revisiting the rocking block:
closed-form solutions and similarity laws, Proc. R. Soc. A 468, 2294–2318.
J. W. Baker (2007), Quantitative classification of near-fault ground motions
using wavelet analysis, Bull. Seismol. Soc. Am. 97(5), 1486–1501.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from enum import Enum

import numpy as np

from rockbench.errors import ScenarioError
from rockbench.geometry import RockingProperties
from rockbench.scenarios.excitation import (
    STANDARD_GRAVITY,
    CosinePulse,
    Excitation,
    Record,
    SinePulse,
)
from rockbench.scenarios.motion import Motion
from rockbench.scenarios.oscillator import Oscillator, response

__all__ = ["IntensityMeasure", "PulseRatios", "peak_ground_acceleration",
           "peak_ground_velocity", "spectral_acceleration", "arias_intensity", "intensity",
           "scale_factor", "scale_record", "pulse_ratios", "SPECTRAL_SAMPLES"]

#: Samples per period of the oscillator of Sa(T, ζ).
SPECTRAL_SAMPLES = 200


class IntensityMeasure(Enum):
    """The intensity measures of a base excitation (values are the CLI names)."""

    PGA = "pga"
    PGV = "pgv"
    PGA_UPLIFT = "pga-uplift"
    PGV_ROCKING = "pgv-rocking"
    SA = "sa"
    ARIAS = "arias"

    @property
    def units(self) -> str:
        """Units of the measure (``"1"`` for the dimensionless ones)."""
        return {"pga": "m/s2", "pgv": "m/s", "sa": "m/s2", "arias": "m/s"}.get(self.value, "1")

    @property
    def degree(self) -> int:
        """The power of a record's scale factor in the measure (Arias: 2, others 1)."""
        return 2 if self is IntensityMeasure.ARIAS else 1

    @property
    def needs_block(self) -> bool:
        """True when the measure is normalised by the block's rocking constants."""
        return self in (IntensityMeasure.PGA_UPLIFT, IntensityMeasure.PGV_ROCKING)

    @property
    def label(self) -> str:
        """Formula of the measure, for axis labels and tables."""
        return {"pga": "PGA (m/s²)", "pgv": "PGV (m/s)", "pga-uplift": "PGA / (g tan λ)",
                "pgv-rocking": "PGV p / (g tan λ)", "sa": "Sa(T, ζ) (m/s²)",
                "arias": "Arias intensity (m/s)"}[self.value]

    @classmethod
    def parse(cls, name: str | IntensityMeasure) -> IntensityMeasure:
        """The measure named ``name`` (case-insensitive), or a ScenarioError listing them."""
        if isinstance(name, IntensityMeasure):
            return name
        try:
            return cls(str(name).strip().lower())
        except ValueError:
            names = ", ".join(m.value for m in cls)
            raise ScenarioError(f"unknown intensity measure {name!r}; valid: {names}") from None


@dataclass(frozen=True)
class PulseRatios:
    """The dimensionless groups of a pulse on a block (Dimitrakopoulos & DeJong 2012).

    Attributes
    ----------
    frequency_ratio : float
        ω_p / p, the pulse's circular frequency over the block's frequency parameter.
    acceleration_ratio : float
        |a_p| / (g tan λ), the pulse's acceleration amplitude over the uplift threshold.
    """

    frequency_ratio: float
    acceleration_ratio: float


def peak_ground_acceleration(excitation: Excitation) -> float:
    """PGA = max |ü_g| over the whole motion (m/s²).

    Exact for records (the acceleration is linear between samples, so its peak
    is a sample) and for the analytic pulses.

    Raises
    ------
    ScenarioError
        For an excitation of several components.
    """
    return float(_axial(excitation, "PGA").peak_acceleration())


def peak_ground_velocity(excitation: Excitation) -> float:
    """PGV = max |u̇_g| over the whole motion (m/s): :meth:`Excitation.peak_velocity`.

    Exact for records (the exact integral of the piecewise-linear,
    baseline-corrected acceleration, including the extrema between samples)
    and for the one-sine and one-cosine pulses (2|A|ω resp. |A|ω).

    Raises
    ------
    ScenarioError
        For a motion that never ends, or one of several components.
    """
    return float(_axial(excitation, "PGV").peak_velocity())


def _axial(excitation: Excitation, measure: str) -> Motion:
    """The excitation as one motion along x; a multi-component one has no PGA or PGV here."""
    if not isinstance(excitation, Motion):
        raise ScenarioError(f"the {measure} is defined for a motion along x (a record or a "
                            f"pulse), not for a {excitation.kind!r} excitation")
    return excitation


def _record(excitation: Excitation, measure: str) -> Record:
    """The excitation as a record; the measures computed from samples refuse the others."""
    if not isinstance(excitation, Record):
        raise ScenarioError(f"{measure} is computed for records, not for a "
                            f"{excitation.kind!r} excitation")
    return excitation


def _velocity_scale(rocking: RockingProperties, g: float) -> float:
    return g * math.tan(rocking.lam) / rocking.p


def spectral_acceleration(excitation: Excitation, oscillator: Oscillator) -> float:
    """Sa(T, ζ) = ω² max |q|: the pseudo-spectral acceleration of a record (m/s²).

    The oscillator's response is exact at its samples (at least
    :data:`SPECTRAL_SAMPLES` a period, :func:`rockbench.scenarios.oscillator.response`),
    its free vibration after the record included; between samples the peak of a
    near-sinusoidal q can exceed the sampled one by at most 1 − cos(π/200) = 0.012 %.

    Raises
    ------
    ScenarioError
        For an excitation that is not a record.
    """
    r = response(_record(excitation, "Sa(T)"), oscillator,
                 samples_per_period=SPECTRAL_SAMPLES)
    return oscillator.omega ** 2 * float(np.max(np.abs(r.q)))


def arias_intensity(excitation: Excitation, g: float = STANDARD_GRAVITY) -> float:
    """I_a = π/(2g) ∫ ü_g² dt of a record (m/s), exact for its piecewise-linear ü_g.

    Raises
    ------
    ScenarioError
        For an excitation that is not a record.
    """
    record = _record(excitation, "the Arias intensity")
    t = np.asarray(record.times, float)
    a = np.asarray(record.acceleration(t), float)
    # ∫ over a step of (linear a)² = h (a_k² + a_k a_{k+1} + a_{k+1}²) / 3
    integral = float(np.sum(np.diff(t) * (a[:-1] ** 2 + a[:-1] * a[1:] + a[1:] ** 2)) / 3.0)
    return math.pi / (2.0 * g) * integral


def intensity(excitation: Excitation, measure: IntensityMeasure | str,
              rocking: RockingProperties | None = None, g: float = 9.81,
              oscillator: Oscillator | None = None) -> float:
    """The value of an intensity measure of an excitation.

    Parameters
    ----------
    excitation : Excitation
        A record or an analytic pulse.
    measure : IntensityMeasure or str
        Which measure (see the module docstring).
    rocking : RockingProperties, optional
        The block's rocking constants (λ, p); required by the normalised measures.
        For a stack, pass the constants of the mode the study is about (e.g.
        ``stack.monolithic(g)``).
    g : float
        Gravity (m/s²); use the scenario's.
    oscillator : Oscillator, optional
        The period and damping of ``sa``.

    Returns
    -------
    float
        The intensity, in ``measure.units``.
    """
    m = IntensityMeasure.parse(measure)
    if m.needs_block and rocking is None:
        raise ScenarioError(f"intensity measure {m.value!r} needs the block's rocking constants")
    if m is IntensityMeasure.SA:
        if oscillator is None:
            raise ScenarioError("intensity measure 'sa' needs a period (and damping)")
        return spectral_acceleration(excitation, oscillator)
    if m is IntensityMeasure.ARIAS:
        return arias_intensity(excitation)
    if m is IntensityMeasure.PGA:
        return peak_ground_acceleration(excitation)
    if m is IntensityMeasure.PGV:
        return peak_ground_velocity(excitation)
    assert rocking is not None
    if m is IntensityMeasure.PGA_UPLIFT:
        return peak_ground_acceleration(excitation) / (g * math.tan(rocking.lam))
    return peak_ground_velocity(excitation) / _velocity_scale(rocking, g)


def scale_factor(excitation: Excitation, measure: IntensityMeasure | str, target: float,
                 rocking: RockingProperties | None = None, g: float = 9.81,
                 oscillator: Oscillator | None = None) -> float:
    """The factor k ≥ 0 by which to scale the excitation to reach ``target``.

    A measure homogeneous of degree d in the acceleration gives
    k = (target / intensity)^(1/d) (d = 2 for the Arias intensity, 1 for the others).
    A target of 0 gives k = 0 (no motion at all).

    Raises
    ------
    ScenarioError
        If the target is negative or not finite, or the excitation has zero
        intensity and the target is not zero.
    """
    target = float(target)
    if not (math.isfinite(target) and target >= 0.0):
        raise ScenarioError(f"target intensity must be finite and >= 0, got {target!r}")
    current = intensity(excitation, measure, rocking, g, oscillator)
    if target == 0.0:
        return 0.0
    if current == 0.0:
        raise ScenarioError("cannot scale an excitation of zero intensity to a non-zero target")
    return float((target / current) ** (1.0 / IntensityMeasure.parse(measure).degree))


def scale_record(record: Record, measure: IntensityMeasure | str, target: float,
                 rocking: RockingProperties | None = None, g: float = 9.81,
                 oscillator: Oscillator | None = None) -> Record:
    """The record scaled so that its ``measure`` equals ``target``.

    The scale multiplies the record's existing ``scale``; the baseline correction
    is linear in it, so acceleration, velocity and displacement are all scaled by
    the same factor and stay exact integrals of each other. Subclasses of
    :class:`Record` keep their type and extra fields.
    """
    k = scale_factor(record, measure, target, rocking, g, oscillator)
    return dataclasses.replace(record, scale=record.scale * k)


def pulse_ratios(pulse: SinePulse | CosinePulse, rocking: RockingProperties,
                 g: float = 9.81) -> PulseRatios:
    """ω_p / p and a_p / (g tan λ) of an analytic pulse on a block.

    Dimitrakopoulos & DeJong (2012) show that the rocking response to a pulse of
    acceleration amplitude a_p and circular frequency ω_p depends only on these
    two groups and the restitution (similarity law), so overturning spectra are
    drawn in them.
    """
    if not isinstance(pulse, (SinePulse, CosinePulse)):
        raise ScenarioError(f"pulse ratios need a sine or cosine pulse, got {pulse.kind!r}")
    return PulseRatios(frequency_ratio=pulse.omega / rocking.p,
                       acceleration_ratio=abs(pulse.acceleration_amplitude)
                       / (g * math.tan(rocking.lam)))
