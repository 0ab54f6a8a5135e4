"""Restitution fidelity: the effective η of each impact, from successive peaks."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from rockbench.analytic import critical_angle, reference
from rockbench.analytic.overturning import housner_eta
from rockbench.analytic.restitution import effective_restitution, half_cycle_peaks
from rockbench.cli import main
from rockbench.errors import RockbenchError
from rockbench.method import Method
from rockbench.report.restitution_report import write_report
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import get_scenario
from rockbench.studies.restitution import RestitutionOptions, run_restitution, sampled_for


@pytest.mark.fast
@pytest.mark.parametrize("eta", [0.5, 0.8, 0.95])
@pytest.mark.parametrize("rate", [200.0, 1000.0])
def test_the_analytic_model_shows_the_eta_it_was_given_at_every_impact(eta, rate):
    sc = get_scenario("free-b3-0.5")
    sc = sc.replace(contact=dataclasses.replace(sc.contact, eta=eta), output_rate=rate)
    lam = critical_angle(sc.geometry)
    tr = reference(sc)
    found = effective_restitution(tr.t, tr.theta[:, 0], lam, impacts=4)
    n = len(found.eta)
    # every impact until the peaks fall below 2 % of λ: 2 at η = 0.5, 4 above
    assert n == (2 if eta == 0.5 else 4)
    # the parabola through the sampled peak errs by O(Δt²): 200 samples/s are enough
    assert found.eta == pytest.approx([eta] * n, abs=2e-4)
    # energy is conserved between impacts: each peak's potential is η² the last one's
    v = np.cos(lam - np.array(found.peaks)) - math.cos(lam)
    assert v[1:] / v[:-1] == pytest.approx([eta**2] * n, abs=4e-4)


@pytest.mark.fast
def test_peaks_are_refined_between_samples():
    t = np.linspace(0.0, 2.0, 41)  # 20 samples a half-cycle, peaks between samples
    theta = 0.3 * np.sin(2 * np.pi * (t - 0.013))
    times, peaks = half_cycle_peaks(t, theta)
    # the first stretch, before θ turns positive at t = 0.013, is cut by the window
    assert peaks[1:] == pytest.approx(0.3, rel=1e-3)
    assert times[1:] == pytest.approx(0.013 + 0.25 + 0.5 * np.arange(4), abs=2e-3)


@pytest.mark.fast
def test_an_overturned_block_or_a_bad_angle_has_no_restitution():
    t = np.linspace(0.0, 1.0, 11)
    with pytest.raises(RockbenchError, match="overturned"):
        effective_restitution(t, np.linspace(0.1, 1.0, 11), 0.3)
    with pytest.raises(RockbenchError, match="λ must be in"):
        effective_restitution(t, np.zeros(11), 2.0)


@pytest.mark.slow
def test_the_study_reads_housners_eta_off_the_analytic_model_and_an_engine(tmp_path):
    pytest.importorskip("pymunk")
    sc = get_scenario("free-b2-0.5")
    res = run_restitution(RestitutionOptions(
        scenarios=[sc], engines=["pymunk"], presets=["accurate"], restitution=(0.0,),
        impacts=3, execution=ExecutionOptions(isolate=False)))
    h = housner_eta(critical_angle(sc.geometry))
    assert h == pytest.approx(0.7, abs=1e-12)  # λ = atan(1/2): 1 − 1.5 · 1/5
    ref = res.row("analytic", "free-b2-0.5")
    assert ref.ratio == pytest.approx(1.0, abs=2e-4) and len(ref.impacts.eta) == 3
    # pymunk's calibrated accurate preset dissipates as a plastic impact does
    eng = res.row("pymunk[accurate]", "free-b2-0.5")
    assert eng.ratio == pytest.approx(1.0, abs=0.01)
    files = write_report(res, tmp_path)
    rows = (tmp_path / "restitution.csv").read_text().splitlines()
    assert len(rows) == 1 + 3 + 3
    assert (tmp_path / "figures" / "restitution.png").stat().st_size > 20_000
    assert "η measured" in (tmp_path / "report.md").read_text()
    assert files[0].name == "index.html"


def test_a_step_longer_than_the_output_interval_is_sampled_once_per_step():
    pytest.importorskip("pymunk")
    sc = get_scenario("free-b2-0.5")
    assert sc.output_rate == 1000.0
    sixty = {"timestep": 1.0 / 60.0}
    assert sampled_for(sc, Method.of("pymunk", sixty)).output_rate == pytest.approx(60.0)
    assert sampled_for(sc, Method.of("pymunk", {"preset": "fast"})) is sc
    assert sampled_for(sc, Method.reference()) is sc
    # a game-like 60 Hz step runs, and its η is read off one sample per step
    res = run_restitution(RestitutionOptions(
        scenarios=[sc], engines=["pymunk"], presets=["accurate"], overrides={"pymunk": sixty},
        impacts=3, execution=ExecutionOptions(isolate=False)))
    row = res.row("pymunk[accurate]", "free-b2-0.5")
    assert row.status == "ok" and row.impacts is not None and len(row.impacts.eta) >= 2
    assert 0.5 < row.ratio < 1.05


@pytest.mark.fast
def test_the_study_refuses_what_is_not_free_rocking_and_bad_coefficients(tmp_path, capsys):
    with pytest.raises(RockbenchError, match="free rocking of one block"):
        run_restitution(RestitutionOptions(scenarios=[get_scenario("parapet-offset0.25")]))
    code = main(["restitution", "--engine", "pymunk", "--restitution", "0,2",
                 "--out", str(tmp_path / "r"), "--no-db"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "[0, 1]" in err[0]
