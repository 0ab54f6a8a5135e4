"""Pulse to collapse (issue 18 item 4b) and the report of the assembly studies."""

from __future__ import annotations

import csv
import math
import struct

import numpy as np
import pytest
from matplotlib.figure import Figure
from matplotlib.patches import FancyArrow

from rockbench.analytic import critical_angle
from rockbench.cli import main
from rockbench.engines import get_engine
from rockbench.report.assembly_report import _MOVING, draw_assembly, write_assembly_report
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Block, Contact, Scenario, get_scenario
from rockbench.studies.collapse import (
    RESIDUAL_DISPLACEMENT,
    RESIDUAL_DROP,
    collapsed,
    outcome,
    pulse_scenario,
    pulse_to_collapse,
    static_factor,
)
from rockbench.studies.tilting import reference, tilting_table
from rockbench.trajectory import Status, Trajectory

HERE = ExecutionOptions(isolate=False)
#: A slender block: b/h = 0.2, the static factor tan λ = 0.2.
SLENDER = Scenario(name="slender", geometry=Block(0.2, 0.2, 1.0, mass=1.0))
PARAPET = get_scenario("parapet-offset0.25")
PYMUNK = {"timestep": 1e-4}


def test_static_factor_is_tan_lambda_and_the_parapets_lever():
    assert static_factor(SLENDER) == pytest.approx(0.2, rel=1e-7)
    # the parapet's short lever (0.05 over 0.4) governs, not its long one (0.375)
    assert static_factor(PARAPET) == pytest.approx(0.125, rel=1e-7)


@pytest.mark.parametrize("engine,settings", [("analytic", {}), ("pymunk", PYMUNK)])
def test_a_slow_pulse_collapses_a_block_just_above_g_tan_lambda(engine, settings):
    # at f_p = 0.05 Hz (ω_p/p = 0.12) the pulse is a slow tilt: 2 % below the static
    # factor nothing moves, 2 % above it the block goes over
    eng = get_engine(engine)
    below = pulse_scenario(SLENDER, 0.05, 0.98, 0.2)
    above = pulse_scenario(SLENDER, 0.05, 1.02, 0.2)
    rest = eng.simulate(below, settings)
    assert collapsed(rest, below) is False
    assert float(np.max(np.abs(rest.theta))) < 1e-3 * critical_angle(SLENDER.geometry)
    over = eng.simulate(above, settings)
    assert over.status is Status.OVERTURNED and collapsed(over, above) is True


#: A squat block on a low-friction base: b/h = 2 > μ = 0.3, so it slides at α = μ.
SQUAT = Scenario(name="squat", geometry=Block(1.0, 0.2, 0.5, mass=1.0),
                 contact=Contact(friction=0.3))


def _end_state(scenario: Scenario, dtheta, dx, dz) -> Trajectory:
    """Rest, then every block moved by (dθ, dx, dz) relative to the base at the end."""
    t = np.array([0.0, scenario.duration])
    x0, z0 = (np.array([p[i] for p in scenario.geometry.poses]) for i in (0, 1))
    u = float(np.asarray(scenario.excitation.displacement(t[-1])))
    return Trajectory(t, np.vstack([np.zeros(2), dtheta]),
                      np.vstack([x0, x0 + u + np.asarray(dx)]),
                      np.vstack([z0, z0 + np.asarray(dz)]))


def test_outcome_tells_sliding_from_collapse():
    sc = pulse_scenario(PARAPET, 1.0, 2.0, 0.125)
    lam, (wall, top) = critical_angle(sc.geometry), sc.blocks
    far = 2 * RESIDUAL_DISPLACEMENT * wall.height
    cases = {
        "rest": ([0.0, 0.0], [0.0, 0.0], [0.0, 0.0]),
        # the whole assembly (or a block on another) translated: slid, not collapsed
        "sliding": ([0.0, 0.0], [far, far], [0.0, 0.0]),
        # the parapet turned past λ, or fallen off the wall by half its height
        "collapse": ([0.0, 1.5 * lam], [0.0, 0.0], [0.0, 0.0]),
    }
    for expected, state in cases.items():
        assert outcome(_end_state(sc, *state), sc) == expected
        assert collapsed(_end_state(sc, *state), sc) is (expected == "collapse")
    fell = _end_state(sc, [0.0, 0.0], [0.0, far], [0.0, -2 * RESIDUAL_DROP * top.height])
    assert outcome(fell, sc) == "collapse"
    assert outcome(Trajectory(np.array([0.0, 1.0]), np.zeros((2, 2)), status=Status.CRASHED),
                   sc) is None


def test_a_squat_block_sliding_on_the_base_has_not_collapsed():
    # 3 and 6 times the sliding factor μ = 0.3 at 0.5 Hz: the block slides more than a
    # quarter of its width on the base without rocking (1.5 times: less); the bisection
    # finds no collapse up to 6, and says where it slid
    assert static_factor(SQUAT) == pytest.approx(0.3, rel=1e-7)
    study = pulse_to_collapse([SQUAT], ["pymunk"], [0.5], settings={"pymunk": PYMUNK},
                              rtol=0.05, max_factor=6.0, execution=HERE)
    (p,) = study.points
    assert math.isinf(p.upper) and p.lower == 6.0 and p.sliding_factor == 3.0
    assert [(q.factor, q.slid, q.collapsed) for q in p.probes] == [
        (1.5, False, False), (3.0, True, False), (6.0, True, False)]
    sc = pulse_scenario(SQUAT, 0.5, 3.0, 0.3)
    run = get_engine("pymunk").simulate(sc, PYMUNK)
    assert float(np.max(np.abs(run.theta))) < 0.01 * critical_angle(sc.geometry)
    assert abs(run.x[-1, 0] - run.x[0, 0] - float(sc.excitation.displacement(run.t[-1]))) > 0.25


@pytest.fixture(scope="module")
def block_study():
    return pulse_to_collapse([SLENDER], ["analytic", "pymunk"], [0.05, 1.0],
                             settings={"pymunk": PYMUNK}, rtol=0.02, execution=HERE)


@pytest.mark.slow
def test_collapse_amplitude_tends_to_the_static_factor_at_low_frequency(block_study):
    for e in ("analytic", "pymunk"):
        slow, fast = block_study.curve("slender", e)
        # a_p ≥ g tan λ, and the slow pulse needs no more than the bisection tolerance above it
        assert 1.0 <= slow.lower < slow.upper <= 1.03, (slow.lower, slow.upper)
        assert slow.acceleration_ratio == pytest.approx(0.2, rel=0.03)
        # a shorter pulse needs more (1 Hz: ω_p/p = 2.3)
        assert fast.lower > slow.upper
        assert fast.cpu_time > 0 and fast.failed == 0


def test_bisection_brackets_hold(block_study):
    for p in block_study.points:
        assert p.upper / p.lower - 1.0 <= block_study.rtol
        verdicts = {q.factor: q.collapsed for q in p.probes}
        assert verdicts[p.upper] is True
        assert p.lower == 1.0 or verdicts[p.lower] is False
        # every probe that collapsed is at or above the bracket, every one that did not at or
        # below it
        assert all(q.factor >= p.upper for q in p.probes if q.collapsed)
        assert all(q.factor <= p.lower for q in p.probes if q.collapsed is False)
    # engines agree on the block within the tolerance: the same bracket at 0.05 Hz
    a, b = (block_study.curve("slender", e)[0] for e in ("analytic", "pymunk"))
    assert a.upper == b.upper


def test_bad_study_arguments_are_refused():
    with pytest.raises(ValueError, match="frequencies"):
        pulse_to_collapse([SLENDER], ["analytic"], [0.0], execution=HERE)
    with pytest.raises(ValueError, match="rtol"):
        pulse_to_collapse([SLENDER], ["analytic"], [1.0], rtol=0.0, execution=HERE)


def test_mechanism_drawing_of_the_parapet_shows_the_moving_block():
    fig = Figure()
    ax = fig.add_subplot()
    drawing = draw_assembly(ax, PARAPET, reference(PARAPET, 1))
    assert drawing.blocks == 2 and drawing.supports == 1
    assert drawing.moving == (1,) and drawing.centres == 1
    arrows = [p for p in ax.patches if isinstance(p, FancyArrow)]
    assert len(arrows) == 1
    filled = [p for p in ax.patches if tuple(p.get_facecolor()[:3]) == tuple(
        int(_MOVING[k:k + 2], 16) / 255 for k in (1, 3, 5))]
    assert len(filled) == 1
    # the parapet's rotation centre is its corner on the wall's edge (0.3, 1.2)
    line = [ln for ln in ax.lines if ln.get_marker() == "x"][0]
    assert (line.get_xdata()[0], line.get_ydata()[0]) == pytest.approx((0.3, 1.2), abs=1e-6)


def _png_size(path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return struct.unpack(">II", data[16:24])


@pytest.mark.slow
def test_report_files_exist_and_figures_are_real_pngs(tmp_path, block_study):
    cmps = tilting_table([PARAPET], "pymunk", settings=PYMUNK, execution=HERE)
    study = pulse_to_collapse([PARAPET], ["pymunk"], [0.5], settings={"pymunk": PYMUNK},
                              rtol=0.05, execution=HERE)
    (p,) = study.points
    assert 1.0 < p.factor < 2.0 and math.isfinite(p.cpu_time)
    files = write_assembly_report(tmp_path, [PARAPET], cmps, study, command="test")
    for name in ("index.html", "report.md", "results.csv"):
        assert (tmp_path / name) in files and (tmp_path / name).stat().st_size > 300
    pngs = sorted((tmp_path / "figures").glob("*.png"))
    assert [x.name for x in pngs] == ["assembly-parapet-offset0.25.png",
                                      "collapse-parapet-offset0.25.png"]
    for png in pngs:
        w, h = _png_size(png)
        assert 400 <= w <= 2000 and 300 <= h <= 2000 and png.stat().st_size > 10_000
    rows = list(csv.DictReader((tmp_path / "results.csv").open()))
    assert [r["study"] for r in rows] == ["tilting", "collapse"]
    assert float(rows[0]["error"]) == pytest.approx(cmps[0].error)
    md = (tmp_path / "report.md").read_text()
    assert "Tilting table" in md and "Pulse to collapse" in md and "CPU s" in md


def test_collapse_command_writes_the_report(tmp_path, capsys):
    out = tmp_path / "r"
    assert main(["collapse", "--scenarios", "parapet-offset0.25", "--engine", "pymunk",
                 "--set", "pymunk.timestep=1e-4", "--frequencies", "1", "--rtol", "0.1",
                 "--no-db", "--no-isolate", "--out", str(out)]) == 0
    assert (out / "index.html").exists() and (out / "figures" / "collapse-parapet-offset0.25.png"
                                              ).exists()
    assert "collapse" in capsys.readouterr().out
