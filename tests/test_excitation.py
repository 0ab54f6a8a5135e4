"""Excitations: exact consistency of acceleration, velocity, displacement; start from rest."""

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

from rockbench import checks
from rockbench.analytic.housner import scalar_acceleration, single_block_reference
from rockbench.errors import ScenarioError
from rockbench.scenarios import (
    REPORT_GROUPS,
    AxialExcitation,
    Block,
    CosinePulse,
    Free,
    Record,
    Scenario,
    SinePulse,
    Sinusoid,
    excitation_class,
    excitation_from_table,
    excitation_kinds,
    load_scenario,
    save_scenario,
)
from rockbench.scenarios.excitation import TiltTable
from rockbench.store import scenario_hash

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


# ---------------------------------------------------------------- registry by kind
BUILT_IN = {"free": (Free, "free"), "sine-pulse": (SinePulse, "pulse"),
            "cosine-pulse": (CosinePulse, "pulse"), "sinusoid": (Sinusoid, "sine"),
            "record": (Record, "record"), "tilt-table": (TiltTable, "tilt")}


def test_built_in_kinds_are_registered_with_their_report_groups():
    assert set(BUILT_IN) <= set(excitation_kinds())
    for kind, (cls, group) in BUILT_IN.items():
        assert excitation_class(kind) is cls
        assert cls.kind == kind and cls.report_group == group
    assert set(REPORT_GROUPS) == {g for _, g in BUILT_IN.values()}


@pytest.mark.parametrize("exc", BOUNDED, ids=lambda e: type(e).__name__)
def test_every_excitation_reads_back_its_own_table(exc):
    table = exc.to_table()
    assert table["type"] == exc.kind
    back = excitation_from_table(table)
    t = np.linspace(-0.1, 4.0, 2001)
    assert type(back) is type(exc)
    for f in ("acceleration", "velocity", "displacement"):
        np.testing.assert_array_equal(getattr(back, f)(t), getattr(exc, f)(t))


@pytest.mark.parametrize("exc", BOUNDED, ids=lambda e: type(e).__name__)
def test_scalar_acceleration_is_the_vectorised_one(exc):
    fast = exc.scalar_acceleration()
    t = np.concatenate([np.linspace(-0.1, 6.0, 1501), exc.breakpoints])
    got = np.array([fast(float(x)) for x in t])
    assert all(type(fast(float(x))) is float for x in t[:5])
    np.testing.assert_allclose(got, exc.acceleration(t), rtol=0, atol=1e-12)
    assert scalar_acceleration(exc) is not None  # the solvers' check accepts it


@pytest.mark.parametrize("table, match", [
    ({"type": ["sine-pulse"]}, "type must be a string"),
    ({"type": "quake"}, "unknown excitation type 'quake'; types: free, sine-pulse"),
    ("sine-pulse", "must be a table"),
    ({"type": "free", "frequency": 2.0}, "unknown key 'frequency'"),
    ({"type": "sinusoid", "frequency": 2.0}, "needs 'amplitude'"),
    ({"type": "sine-pulse", "frequency": True, "amplitude": 0.01}, "frequency .*boolean"),
    ({"type": "sine-pulse", "frequency": 3.0, "amplitude": 0.01, "cycles": math.inf},
     "cycles must be an integer"),
    ({"type": "sine-pulse", "frequency": 3.0, "amplitude": 0.01, "cycles": 1.5},
     "cycles must be an integer"),
    ({"type": "sinusoid", "frequency": 3.0, "amplitude": "0.01"}, "amplitude .*string"),
    ({"type": "record", "times": [0.0, "0.1"], "accelerations": [0.0, 1.0]}, "item 2"),
    ({"type": "record", "times": [0.0, 0.1], "accelerations": [0.0, 1.0], "units": "g"},
     "inline accelerations are in m/s²"),
    ({"type": "record", "file": 3}, "record file must be a string, got 3"),
])
def test_bad_excitation_tables(table, match):
    with pytest.raises(ScenarioError, match=match):
        excitation_from_table(table)


@pytest.mark.parametrize("make", [
    lambda: SinePulse(3.0, 1e6),  # A ω² = 3.6e8 m/s²
    lambda: Sinusoid(1e4, 1.0),
    lambda: Record([0.0, 0.1, 0.2], [1e308, -1e308, 1e308]),
    lambda: Record([0.0, 0.1], [0.0, 1.0e5], scale=100.0),
])
def test_implausible_base_accelerations_are_refused(make):
    with pytest.raises(ScenarioError, match=r"above 1e\+06 m/s² are refused"):
        make()


def test_registry_refuses_a_taken_kind_and_an_unknown_group():
    with pytest.raises(TypeError, match="already registered"):
        class Again(Free):  # noqa: F841 - defining it is the test
            kind: ClassVar[str] = "free"
    with pytest.raises(TypeError, match="report_group"):
        class Odd(Free):  # noqa: F841
            kind: ClassVar[str] = "odd"
            report_group: ClassVar[str] = "quake"
    assert excitation_class("free") is Free and "odd" not in excitation_kinds()


@dataclass(frozen=True)
class BangBang(AxialExcitation):
    """A new excitation in one class: ü_g = +level for T/2, then −level for T/2.

    The base ends at rest, displaced by level·T²/4. Defined here only: nothing
    else in rockbench knows it.
    """

    level: float
    period: float
    kind: ClassVar[str] = "bang-bang"
    report_group: ClassVar[str] = "pulse"
    table_keys: ClassVar[frozenset[str]] = frozenset({"level", "period"})

    def __post_init__(self) -> None:
        checks.number(self.level, "bang-bang level", unit="m/s²")
        checks.number(self.period, "bang-bang period", low=0.0, unit="s")

    @property
    def end_time(self) -> float:
        return self.period

    @property
    def breakpoints(self) -> tuple[float, ...]:
        return (0.5 * self.period, self.period)

    def acceleration(self, t):
        t = np.asarray(t, float)
        h = 0.5 * self.period
        return np.where((t >= 0) & (t < h), self.level,
                        np.where((t >= h) & (t <= self.period), -self.level, 0.0))

    def velocity(self, t):
        tc = np.clip(np.asarray(t, float), 0.0, self.period)
        h = 0.5 * self.period
        return self.level * np.where(tc < h, tc, self.period - tc)

    def displacement(self, t):
        tc = np.clip(np.asarray(t, float), 0.0, self.period)
        h = 0.5 * self.period
        return self.level * np.where(tc < h, 0.5 * tc**2,
                                     0.5 * h * h + h * (tc - h) - 0.5 * (tc - h) ** 2)

    def scalar_acceleration(self):
        a, h, end = self.level, 0.5 * self.period, self.period
        return lambda t: (a if 0.0 <= t < h else -a if h <= t <= end else 0.0)

    @classmethod
    def from_table(cls, table, *, source=None):
        return cls(**cls.read_fields(table, required=("level", "period")))

    def to_table(self):
        return {"type": self.kind, "level": self.level, "period": self.period}


B0 = Block(1.0, 0.2, 5.0, mass=1.0)


def test_a_new_excitation_class_round_trips_through_toml(tmp_path):
    sc = Scenario("bang", B0, excitation=BangBang(1.2, 0.8), duration=2.0)
    back = load_scenario(save_scenario(sc, tmp_path / "bang.toml"))
    assert back == sc and back.excitation.report_group == "pulse"
    assert scenario_hash(back) == scenario_hash(sc)
    assert 'type = "bang-bang"' in (tmp_path / "bang.toml").read_text()
    (tmp_path / "bad.toml").write_text((tmp_path / "bang.toml").read_text()
                                       .replace("period = 0.8", "period = -0.8"))
    with pytest.raises(ScenarioError, match=r"bad\.toml: \[excitation\] bang-bang period"):
        load_scenario(tmp_path / "bad.toml")


def test_a_new_excitation_class_drives_the_analytic_reference():
    lam, p = B0.rocking().lam, B0.rocking().p
    g = 9.81
    # below g tan λ the block stays at rest and its centroid follows the base exactly
    calm = Scenario("calm", B0, excitation=BangBang(0.5 * g * math.tan(lam), 0.8), duration=1.5)
    tr = single_block_reference(calm)
    assert str(tr.status) == "ok" and np.all(tr.theta == 0.0)
    np.testing.assert_allclose(tr.x[:, 0], calm.excitation.displacement(tr.t), atol=1e-15)
    # linearised model above g λ: θ = −(a/g − λ)(cosh pt − 1) while +a lasts
    # (a positive base acceleration tips the block to θ < 0)
    a = 1.5 * g * lam
    strong = Scenario("strong", B0, excitation=BangBang(a, 1.0), duration=1.5)
    tr = single_block_reference(strong, linear=True)
    first = tr.t < 0.5
    expected = -(a / g - lam) * (np.cosh(p * tr.t[first]) - 1.0)
    assert np.max(np.abs(tr.theta[first, 0] - expected)) < 1e-7 * lam
    assert tr.theta[first, 0][-1] < -0.1 * lam
