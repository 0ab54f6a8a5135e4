"""The code's verdict beside the dynamics: design level, probabilities and margins."""

from __future__ import annotations

from pathlib import Path

import pytest
from fragility_helpers import noise_records, study

from rockbench.cli import main
from rockbench.errors import RockbenchError
from rockbench.report.fragility_report import write_report
from rockbench.scenarios import Block, Scenario
from rockbench.studies.code_check import code_check, load_site
from rockbench.studies.code_comparison import code_beside, design_level
from rockbench.studies.fragility import LimitState

G = 9.81
SITE = 'code = "ntc2018"\nag = 0.25\nF0 = 2.4\nTC_star = 0.3\nsoil = "C"\n'
ROOF = SITE + ("[building]\nheight = 12.0\nelement_height = 12.0\nperiod = 0.4\n"
               "storeys = 4\n")


def _site(tmp_path: Path, text: str = SITE) -> Path:
    path = tmp_path / "site.toml"
    path.write_text(text)
    return path


def _block() -> Scenario:
    return Scenario("b", Block(0.25, 0.25, 1.25, density=2000.0))


@pytest.mark.fast
def test_the_design_level_is_the_codes_pga_in_the_studys_measure(tmp_path):
    sc = _block()
    check = code_check(sc, load_site(_site(tmp_path)))
    # soil C: S_S = 1.70 − 0.60 F0 ag = 1.34 (within [1, 1.5]), S_T = 1: a_g S g
    s = 1.70 - 0.60 * 2.4 * 0.25
    assert check.design_pga == pytest.approx(0.25 * s * sc.g, rel=1e-9)
    assert design_level(check, "pga", sc) == pytest.approx(check.design_pga, rel=1e-12)
    # pga-uplift: the same PGA over g tan λ, tan λ = 0.2
    assert design_level(check, "pga-uplift", sc) == pytest.approx(
        check.design_pga / (0.2 * sc.g), rel=1e-9)
    with pytest.raises(RockbenchError, match="pga or pga-uplift, not 'pgv'"):
        design_level(check, "pgv", sc)


@pytest.mark.slow
def test_each_method_is_set_against_the_codes_capacities(tmp_path):
    sc = _block()
    check = code_check(sc, load_site(_site(tmp_path)))
    res = study(sc, noise_records(6), (1.0, 2.0, 3.0, 4.5, 6.0, 9.0), measure="pga",
                settle=1.0, design_level=check.design_pga)
    beside = code_beside(res, check)
    (ref,) = beside.methods
    boot = res.curve("analytic", LimitState.OVERTURNING).bootstrap
    assert boot is not None and boot.fit.ok
    assert ref.median_pga == pytest.approx(boot.fit.median, rel=1e-12)
    # the linear capacity of a block is q α0 g / FC = 2 · 0.2 · g / 1.35 (e* = 1)
    assert check.capacity_pga("linear") == pytest.approx(2 * 0.2 * sc.g / 1.35, rel=1e-9)
    assert ref.linear_margin == pytest.approx(boot.fit.median / (2 * 0.2 * sc.g / 1.35),
                                              rel=1e-9)
    assert ref.nonlinear_margin == pytest.approx(
        boot.fit.median / check.capacity_pga("nonlinear"), rel=1e-12)
    assert ref.probability is not None
    assert ref.probability.probability == pytest.approx(
        boot.probability_at(check.design_pga).probability, rel=1e-12)
    write_report(res, tmp_path / "out", code=beside)
    md = (tmp_path / "out" / "report.md").read_text()
    assert "The code check beside the dynamics" in md
    assert f"{ref.nonlinear_margin:.2f}" in md and "Overturning against the code" in md


@pytest.mark.slow
def test_the_command_takes_the_codes_design_level_and_says_where_the_element_is(
        tmp_path, capsys):
    recs = tmp_path / "recs"
    recs.mkdir()
    for i, r in enumerate(noise_records(2)):
        rec = r.record
        (recs / f"r{i}.csv").write_text("\n".join(
            f"{t},{a}" for t, a in zip(rec.times, rec.acceleration(rec.times), strict=True)))
    args = ["fragility", "--block", "0.25,1.25", "--record-set", str(recs), "--measure",
            "pga", "--levels", "2,4,8", "--out", str(tmp_path / "out"), "--no-db",
            "--jobs", "1", "--no-isolate"]
    assert main(args + ["--code-check", str(_site(tmp_path))]) == 0
    out = capsys.readouterr()
    assert "code check (NTC 2018): fails; design PGA 3.29 m/s² (0.335 g)" in out.out
    # the code's design PGA is the study's design level
    md = (tmp_path / "out" / "report.md").read_text()
    assert "probability at the design level 3.28635 = 0.335 g" in md
    # a site on a roof, records straight to the base: one warning line, the study runs
    assert main(args + ["--code-check", str(_site(tmp_path, ROOF))]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "add --floor" in err[0]
    assert main(args[:6] + ["pgv"] + args[7:] + ["--code-check", str(_site(tmp_path))]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "pga or pga-uplift" in err[0]
