"""Excitations: exact consistency of acceleration, velocity, displacement; start from rest."""

import math

import numpy as np
import pytest

from rockbench.errors import ScenarioError
from rockbench.scenarios import CosinePulse, Free, Record, SinePulse, Sinusoid

EXCITATIONS = [
    SinePulse(3.0, 0.008),
    SinePulse(5.0, -0.006, cycles=2),
    Sinusoid(3.3, 0.006),
    Sinusoid(2.0, 0.01, duration=3.2, ramp_cycles=1.5),
    Record(np.linspace(0.0, 2.0, 401), 3.0 * np.sin(9.0 * np.linspace(0.0, 2.0, 401)) + 0.4),
]


BOUNDED = [*EXCITATIONS, CosinePulse(2.0, 0.01), CosinePulse(4.0, -0.003, cycles=3),
           Sinusoid(2.0, 0.01, duration=5.0, ramp_cycles=0.1),
           Sinusoid(2.0, 0.01, duration=5.0, ramp_cycles=0.3), Free()]


def _rel_max(a, b):
    return np.max(np.abs(a - b)) / np.max(np.abs(b))


@pytest.mark.parametrize("exc", EXCITATIONS, ids=lambda e: type(e).__name__)
def test_derivatives_are_consistent(exc):
    # central differences of u and v reproduce v and a (h small, away from kinks)
    t = np.linspace(0.0101, 3.9, 997)
    h = 1e-6
    du = (exc.displacement(t + h) - exc.displacement(t - h)) / (2 * h)
    dv = (exc.velocity(t + h) - exc.velocity(t - h)) / (2 * h)
    assert _rel_max(du, exc.velocity(t)) < 1e-6
    assert _rel_max(dv, exc.acceleration(t)) < 1e-6


@pytest.mark.parametrize("exc", EXCITATIONS, ids=lambda e: type(e).__name__)
def test_starts_from_rest(exc):
    assert exc.velocity(0.0) == 0.0
    assert exc.displacement(0.0) == 0.0


def test_sine_pulse_closed_form_and_end_state():
    f, amp = 3.0, 0.008
    w = 2 * math.pi * f
    p = SinePulse(f, amp)
    assert p.peak_acceleration() == pytest.approx(amp * w * w)
    assert p.acceleration(0.25 / f) == pytest.approx(amp * w * w)
    # after one cycle the base stands still, displaced by 2π A
    assert p.velocity(5.0) == pytest.approx(0.0, abs=1e-15)
    assert p.displacement(5.0) == pytest.approx(2 * math.pi * amp)
    assert p.acceleration(p.end_time + 1e-9) == 0.0


def test_sinusoid_reaches_full_amplitude_after_ramp_and_ends_at_rest():
    s = Sinusoid(2.0, 0.01, duration=3.0)
    t = np.linspace(0.6, 2.4, 2001)  # between the ramps
    assert np.max(np.abs(s.displacement(t))) == pytest.approx(0.01, rel=1e-4)
    assert s.displacement(3.0) == pytest.approx(0.0, abs=1e-15)
    assert s.velocity(3.0) == pytest.approx(0.0, abs=1e-15)


def test_sinusoid_peak_acceleration_without_an_end():
    s = Sinusoid(3.3, 0.006)  # lasts forever: periodic after its ramp
    assert s.peak_acceleration() == pytest.approx(s.peak_acceleration(20.0), rel=1e-6)
    # the ramp's w' and w'' terms add to the steady amplitude A ω²
    assert s.peak_acceleration() > 0.006 * (2 * math.pi * 3.3) ** 2
    assert s.peak_acceleration(0.0) == 0.0


def test_impulsive_sinusoid_only_when_asked():
    s = Sinusoid(2.0, 0.01, ramp_cycles=0)
    assert s.velocity(0.0) == pytest.approx(0.01 * 4 * math.pi)


def test_record_baseline_brings_velocity_back_to_zero():
    t = np.linspace(0, 5, 1001)
    r = Record(t, np.where(t < 1, 2.0, 0.0))  # a one-sided pulse would leave the base moving
    assert r.velocity(5.0) == pytest.approx(0.0, abs=1e-12)
    assert r.velocity(7.0) == pytest.approx(0.0, abs=1e-12)
    assert r.displacement(7.0) == pytest.approx(r.displacement(5.0))


def test_record_readers(tmp_path):
    csv = tmp_path / "rec.csv"
    csv.write_text("t,acc\n0,0\n0.01,0.5\n0.02,-0.25\n0.03,0\n")
    r = Record.from_file(csv, scale=2.0)
    assert r.accelerations[1] == pytest.approx(0.5)
    at2 = tmp_path / "rec.AT2"
    at2.write_text("PEER NGA\nsynthetic\nACCELERATION TIME SERIES IN UNITS OF G\n"
                   "NPTS=    5, DT=   .0100 SEC\n 0.0 0.1 -0.1\n 0.05 0.0\n")
    r2 = Record.from_file(at2)
    assert r2.times[-1] == pytest.approx(0.04)
    assert r2.accelerations[1] == pytest.approx(0.1 * 9.80665)
    assert r2.units == "g"


@pytest.mark.parametrize("content, match", [
    ("t,acc\n0,1,2\n0.1,2,3\n", "2 columns"),
    ("nothing here", "no record data"),
    ("t,acc\n0,0\n0.1,x\n", "not two numbers"),
])
def test_bad_csv_records(tmp_path, content, match):
    f = tmp_path / "bad.csv"
    f.write_text(content)
    with pytest.raises(ScenarioError, match=match):
        Record.from_file(f)


def test_unreadable_record():
    with pytest.raises(ScenarioError, match="cannot read record file"):
        Record.from_file("/nonexistent/record.csv")


@pytest.mark.parametrize("make", [
    lambda: SinePulse(0.0, 0.01),
    lambda: SinePulse(3.0, float("nan")),
    lambda: SinePulse(3.0, 0.01, cycles=0),
    lambda: Sinusoid(-1.0, 0.01),
    lambda: Sinusoid(2.0, 0.01, duration=0.5),
    lambda: Record([0, 0.1, 0.1], [0, 1, 2]),
    lambda: Record([0, 0.1], [0, float("inf")]),
])
def test_invalid_excitations(make):
    with pytest.raises(ScenarioError):
        make()


def test_free_is_still():
    assert Free().is_free
    assert np.all(Free().displacement(np.linspace(0, 3, 5)) == 0)


@pytest.mark.parametrize("exc", BOUNDED, ids=lambda e: type(e).__name__)
@pytest.mark.parametrize("t_end", [0.02, 0.13, 0.3, 1.0, 20.0])
def test_motion_bounds_hold_between_samples_too(exc, t_end):
    t = np.linspace(0.0, t_end, 400_001)
    u, v = np.max(np.abs(exc.displacement(t))), np.max(np.abs(exc.velocity(t)))
    ub, vb = exc.motion_bounds(t_end)
    assert ub >= u * (1 - 1e-12) and vb >= v * (1 - 1e-12)
    if isinstance(exc, SinePulse | CosinePulse):  # closed forms: the peaks themselves
        assert (ub, vb) == pytest.approx((u, v), rel=1e-7, abs=1e-15)  # sampling error


def test_motion_bounds_are_the_peaks_over_a_whole_motion():
    a, f = 0.006, 5.0
    w = 2 * math.pi * f
    assert SinePulse(f, a).motion_bounds() == pytest.approx((2 * math.pi * a, 2 * a * w))
    # a sinusoid whose ramps last ≥ 0.35 cycles never outpaces its steady amplitude A ω
    for rc in (0.36, 1.0, 3.0):
        assert Sinusoid(f, a, duration=10.0, ramp_cycles=rc).motion_bounds(10.0) == \
            pytest.approx((a, a * w), rel=1e-12)
    rec = EXCITATIONS[-1]
    t = np.linspace(0.0, 2.0, 400_001)
    assert rec.motion_bounds() == pytest.approx(
        (np.max(np.abs(rec.displacement(t))), np.max(np.abs(rec.velocity(t)))), rel=0.01)
    assert Free().motion_bounds() == (0.0, 0.0)
