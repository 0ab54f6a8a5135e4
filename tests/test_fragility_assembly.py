"""Fragility of structures no closed form covers: assemblies against the engines' consensus."""

from __future__ import annotations

import math

import numpy as np
import pytest
from fragility_helpers import noise_records, pymunk_missing, study

from rockbench.analytic import limit_analysis
from rockbench.cli import main
from rockbench.errors import RockbenchError
from rockbench.scenarios import get_scenario
from rockbench.studies.consensus import outcome_consensus
from rockbench.studies.fragility import LimitState, uplift_acceleration


@pytest.mark.fast
@pytest.mark.parametrize(("by_family", "expected"), [
    ({"impulse": [True], "penalty": [True]}, True),
    ({"impulse": [False], "penalty": [False], "soft": [True]}, False),
    # one family alone is no consensus, whatever it says
    ({"impulse": [True, True]}, None),
    # two families that disagree: none
    ({"impulse": [True], "penalty": [False]}, None),
    # a family split evenly abstains; one without an outcome too
    ({"impulse": [True, False], "penalty": [True], "soft": [True]}, True),
    ({"impulse": [None], "penalty": [True], "soft": [True]}, True),
    ({"impulse": [None], "penalty": [True]}, None),
    # the family's majority is its vote: two impulse engines count once
    ({"impulse": [True, True, False], "penalty": [True]}, True),
])
def test_the_outcome_consensus_counts_families_not_engines(by_family, expected):
    assert outcome_consensus(by_family) is expected


def _alpha0(scenario) -> float:
    return min(limit_analysis(scenario.geometry, direction=d).load_factor for d in (1, -1))


@pytest.mark.slow
def test_a_parapet_is_studied_against_the_consensus_of_two_contact_families():
    if pymunk_missing():
        pytest.skip(f"needs pymunk: {pymunk_missing()}")
    sc = get_scenario("parapet-offset0.25")
    recs = noise_records(3)
    res = study(sc, recs, (0.6, 4.0, 12.0), measure="pga-uplift",
                engines=["pymunk", "dem2d"], presets=["fast"], settle=1.5)
    assert [m.label for m in res.methods] == ["consensus", "pymunk[fast]", "dem2d[fast]"]
    assert res.reference.label == "consensus"
    # no run of the consensus: it is read off the engines' runs
    assert {r.method for r in res.runs} == {"pymunk[fast]", "dem2d[fast]"}
    # pga-uplift of an assembly is the PGA over α0 g, α0 the collapse factor of limit analysis
    alpha0 = _alpha0(sc)
    assert uplift_acceleration(sc) == pytest.approx(alpha0 * sc.g, rel=1e-12)
    for r in res.runs:
        rec = next(x.record for x in recs if x.name == r.record)
        pga = float(np.max(np.abs(rec.acceleration(rec.times))))
        assert r.scale * pga / (alpha0 * sc.g) == pytest.approx(r.level, rel=1e-9)
        assert r.metrics.status.completed
    # below α0 g no mechanism can form: nothing overturns, nothing rocks beyond contact noise
    for r in res.runs:
        if r.level < 1.0:
            assert r.overturned is False
            assert max(p for p in r.metrics.peaks if p is not None) < 0.02
    for state in LimitState:
        by_engine = {m: {(r.record, r.level): r.outcome(state) for r in res.runs
                         if r.method == m} for m in ("pymunk[fast]", "dem2d[fast]")}
        # two families: the consensus is their outcome where they agree, none elsewhere
        agree = [k for k, v in by_engine["pymunk[fast]"].items()
                 if v is not None and v == by_engine["dem2d[fast]"][k]]
        cons = res.curve("consensus", state)
        assert sum(cons.runs) == len(agree)
        assert sum(cons.exceeded) == sum(by_engine["pymunk[fast]"][k] for k in agree)
        for m in ("pymunk[fast]", "dem2d[fast]"):
            c = res.curve(m, state)
            assert (c.agreed, c.compared) == (len(agree), len(agree))
        assert cons.exceeded[0] == 0


@pytest.mark.fast
def test_an_assembly_needs_two_contact_families_and_has_no_rocking_frequency():
    for name in ("parapet-offset0.25", "arch-9v-t0.20"):
        sc = get_scenario(name)
        with pytest.raises(RockbenchError, match="at least 2 families, got impulse"):
            study(sc, noise_records(1), (5.0,), measure="pga", engines=["pymunk"])
        with pytest.raises(RockbenchError, match="assembly.*pgv-rocking"):
            study(sc, noise_records(1), (5.0,), measure="pgv-rocking",
                  engines=["pymunk", "dem2d"])


@pytest.mark.fast
def test_the_command_refuses_an_assembly_without_engines_in_one_line(tmp_path, capsys):
    t = np.linspace(0.0, 1.0, 101)
    (tmp_path / "recs").mkdir()
    (tmp_path / "recs" / "r1.csv").write_text(
        "\n".join(f"{a},{b}" for a, b in zip(t, np.sin(2 * math.pi * t), strict=True)))
    code = main(["fragility", "--scenario", "parapet-offset0.25", "--record-set",
                 str(tmp_path / "recs"), "--levels", "1,2", "--out", str(tmp_path / "out"),
                 "--no-db"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and "consensus" in err[0] and "--engine" in err[0]
