"""The wobbling study: planar rocking stays planar in the reference; who keeps it planar."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from rockbench.analytic import critical_angle
from rockbench.cli import main
from rockbench.engines import engine_class
from rockbench.errors import RockbenchError
from rockbench.report.wobbling_report import write_report
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import get_scenario
from rockbench.studies.wobbling import (
    DEFAULT_SCENARIO,
    THRESHOLD,
    Convergence,
    Verdict,
    WobblingOptions,
    asymmetric_scenario,
    out_of_plane_uplift,
    run_wobbling,
)
from rockbench.trajectory import Status

IN_PROCESS = ExecutionOptions(isolate=False)


def _engine_applying_y(name: str) -> None:
    cls = engine_class(name)
    for module in cls.requires:
        pytest.importorskip(module)
    if "y" not in cls.capabilities.base_axes:
        pytest.skip(f"{name} does not apply a y base motion here")


def test_the_reference_and_a_2d_engine_are_planar_exactly_and_the_report_is_written(tmp_path):
    pytest.importorskip("pymunk")
    res = run_wobbling(WobblingOptions(engines=["pymunk"], duration=1.0, converge=False,
                                       execution=IN_PROCESS))
    ref = res.row("analytic", "symmetric")
    eng = res.row("pymunk[accurate]", "symmetric")
    for r in (ref, eng):
        assert r.status is Status.OK
        assert r.max_roll == 0.0 and r.max_twist == 0.0 and r.max_drift == 0.0
    assert eng.peak is not None and eng.peak > 0.05  # it rocks in its plane
    # the y component is one a 2D engine cannot apply: unsupported, and said so
    asym = res.verdict("pymunk[accurate]", "asymmetric")
    assert asym.row.status is Status.UNSUPPORTED
    assert asym.verdict is Verdict.PLANAR_BY_CONSTRUCTION
    assert asym.convergence is Convergence.NOT_APPLICABLE
    assert res.verdict("analytic", "symmetric").verdict is Verdict.PLANAR_BY_CONSTRUCTION
    # the reference's stability: a y acceleration lifts one end of the rocking edge only
    # past g (d/2) / h_c, 4.9 m/s² for Single #2, 830 times ε = 1e-3 of 5.9 m/s²
    sc = get_scenario(DEFAULT_SCENARIO)
    assert out_of_plane_uplift(sc) == pytest.approx(9.81 * 0.251 / 0.5)
    nominal = 9.81 * 0.251 / 0.5 / (1e-3 * 0.006 * (10 * math.pi) ** 2)  # A ω² = 5.9 m/s²
    # (the sin² ramp's first cycle peaks 5 % above A ω²)
    assert 0.94 * nominal < res.uplift_ratio < nominal
    files = write_report(res, tmp_path, embed_figures=False)
    assert [f.name for f in files] == ["index.html", "report.md", "wobbling.csv"]
    with (tmp_path / "wobbling.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert [(r["method"], r["variant"], r["status"]) for r in rows] == [
        ("analytic", "symmetric", "ok"), ("pymunk[accurate]", "symmetric", "ok"),
        ("pymunk[accurate]", "asymmetric", "unsupported")]
    assert {r["verdict"] for r in rows} == {"planar by construction"}
    for fig in ("wobbling-angles.png", "wobbling-path.png"):
        assert (tmp_path / "figures" / fig).stat().st_size > 10_000
    md = (tmp_path / "report.md").read_text()
    assert "Vortex" in md and "107 %" in md


@pytest.mark.slow
def test_mujoco_keeps_the_paper_case_planar_and_converges(tmp_path):
    _engine_applying_y("mujoco")
    res = run_wobbling(WobblingOptions(engines=["mujoco"], duration=2.0,
                                       execution=IN_PROCESS))
    lam = critical_angle(get_scenario(DEFAULT_SCENARIO).geometry)
    for variant in ("symmetric", "asymmetric"):
        v = res.verdict("mujoco[accurate]", variant)
        assert v.verdict is Verdict.STAYS_PLANAR, v
        assert v.row.max_roll < THRESHOLD * lam and v.row.max_twist < THRESHOLD * lam
        assert v.convergence is Convergence.CONVERGED
        assert v.refined is not None and v.refined.timestep == pytest.approx(
            0.5 * v.row.timestep)
    # in its plane it rocks as the reference does (within 2 % of the peak over 2 s)
    sym = res.row("mujoco[accurate]", "symmetric")
    assert sym.peak_error is not None and abs(sym.peak_error) < 0.02


@pytest.mark.slow
@pytest.mark.parametrize("engine", ["mujoco", "rapier"])
def test_the_block_leaves_the_plane_only_past_the_out_of_plane_uplift(engine):
    """Below ε* = g (d/2) / (h_c A ω²) ≈ 0.83 the line contact holds the block in its plane,
    whatever ε (the roll does not grow with ε: there is nothing to scale); past it the block
    rocks about a second axis."""
    _engine_applying_y(engine)
    sc = get_scenario(DEFAULT_SCENARIO).replace(duration=2.0)
    lam = critical_angle(sc.geometry)
    star = out_of_plane_uplift(sc) / (0.006 * (10 * math.pi) ** 2)
    assert star == pytest.approx(0.832, abs=1e-3)
    cls = engine_class(engine)
    roll = {}
    for eps in (1e-3, 1e-2, 0.5, 1.0):
        tr = cls().simulate(asymmetric_scenario(sc, eps), "accurate")
        assert tr.status is Status.OK
        roll[eps] = float(np.max(np.abs(tr.roll)))
    assert max(roll[1e-3], roll[1e-2], roll[0.5]) < THRESHOLD * lam
    assert roll[1.0] > 0.05 * lam > 50 * roll[0.5]


def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    for args, what in ((["--asymmetry", "-0.001"], "--asymmetry"),
                       (["--scenario", "no-such-case"], "unknown scenario"),
                       (["--scenario", "free-b0"], "base motion along x")):
        code = main(["wobbling", "--engine", "analytic", "--out", str(tmp_path / "w"),
                     "--no-db", *args])
        err = capsys.readouterr().err.strip().splitlines()
        assert code == 2 and len(err) == 1 and what in err[0], err
    with pytest.raises(RockbenchError, match="ε must be a finite number > 0"):
        asymmetric_scenario(get_scenario(DEFAULT_SCENARIO), 0.0)
