"""Values no physics can use are refused; values that are merely implausible warn and run."""

import math
import warnings
from pathlib import Path

import pytest

from rockbench.campaign.standing import warn_cannot_stand
from rockbench.checks import MAX_LENGTH
from rockbench.cli import main
from rockbench.engines import engine_class
from rockbench.engines.settings import SettingsError
from rockbench.errors import PlausibilityWarning, ScenarioError
from rockbench.geometry import Block, stack
from rockbench.geometry.builders import parapet
from rockbench.scenarios import (
    Record,
    Scenario,
    SinePulse,
    get_scenario,
    load_scenario,
)
from rockbench.scenarios.catalog import catalog
from rockbench.scenarios.excitation import MAX_RECORD_SPAN, MIN_RECORD_STEP, STANDARD_GRAVITY
from rockbench.scenarios.intensity import IntensityMeasure
from rockbench.scenarios.plausibility import review
from rockbench.studies.fragility import _warn_below_uplift, uplift_acceleration

BLOCK = """name = "{name}"
duration = 1.0
blocks = [ {{ width = {w}, depth = {d}, height = {h}, mass = 1.0 }} ]
[initial]
tilt = 0.5
[excitation]
type = "free"
"""


def _file(tmp_path: Path, name: str, w: float, d: float, h: float) -> Path:
    path = tmp_path / f"{name}.toml"
    path.write_text(BLOCK.format(name=name, w=w, d=d, h=h))
    return path


# ----------------------------------------------------------------- refused values
def test_a_block_larger_than_any_structure_is_refused() -> None:
    Block(0.5, 0.2, MAX_LENGTH, mass=1.0)  # the limit itself is a (huge) length
    with pytest.raises(ScenarioError, match=r"block width must be at most 500 m .*1e\+29"):
        Block(1e29, 0.2, 2e29, mass=1.0)


def test_an_offset_of_a_kilometre_is_refused_and_blocks_that_miss_say_so() -> None:
    wall, parapet = Block(0.6, 0.4, 1.2, density=2000.0), Block(0.3, 0.4, 0.8, density=2000.0)
    with pytest.raises(ScenarioError, match="stack offset must be within 500 m"):
        stack((wall, parapet), (0.0, 1000.0))
    # beyond the wall's edge but within the limit: the faces do not meet at all
    with pytest.raises(ScenarioError, match=r"block #2 does not touch block #1: .* 0\.65 to "
                                            r"0\.95 m and from -0\.3 to 0\.3 m"):
        stack((wall, parapet), (0.0, 0.8))


def test_a_file_with_a_huge_block_names_the_file_and_the_field(tmp_path: Path) -> None:
    path = _file(tmp_path, "huge", 1e29, 0.2, 2e29)
    with pytest.raises(ScenarioError, match=r"^.*huge\.toml: \[\[blocks\]\] #1: block width "
                                            r"must be at most 500 m"):
        load_scenario(path)


def test_record_samples_closer_than_a_microsecond_are_refused() -> None:
    Record([0.0, MIN_RECORD_STEP, 1.0], [0.0, 1.0, 0.0])  # the limit itself is accepted
    with pytest.raises(ScenarioError, match=r"samples 1 and 2 are 1e-300 s apart"):
        Record([0.0, 1e-300, 1.0], [0.0, 1.0, 0.0])


def test_a_record_longer_than_a_day_is_refused() -> None:
    Record([0.0, 0.5, MAX_RECORD_SPAN], [0.0, 1.0, 0.0])
    with pytest.raises(ScenarioError, match=r"record times reach 1e\+12 s"):
        Record([0.0, 0.5, 1e12], [0.0, 1.0, 0.0])


def test_an_integer_knob_beyond_a_c_int_is_refused() -> None:
    pymunk = engine_class("pymunk")
    assert pymunk.settings(None, iterations="2147483647").iterations == 2**31 - 1
    with pytest.raises(SettingsError, match=r"iterations must be an integer of at most "
                                            r"2147483647 .* got 1e\+30"):
        pymunk.settings(None, iterations="1e30")


def test_the_cli_refuses_a_huge_iteration_count_in_one_line(capsys) -> None:
    code = main(["run", "free-b1-0.5", "--engine", "pymunk", "--preset", "fast",
                 "--set", "pymunk.iterations=1e30"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert err == ["rockbench: error: pymunk.iterations must be an integer of at most "
                   "2147483647 in size (the engines pass it to C as an int), got 1e+30"]


# ----------------------------------------------------------------- warnings
def test_every_catalog_scenario_is_plausible() -> None:
    found = {name: review(get_scenario(name)) for name in catalog()}
    assert {k: v for k, v in found.items() if v} == {}


def test_sizes_typed_in_millimetres_warn_and_run(tmp_path: Path) -> None:
    path = _file(tmp_path, "mm", 250, 200, 400)
    with pytest.warns(PlausibilityWarning, match=r"mm\.toml: every block size is 10 m or more "
                                                 r"\(200 to 400 m\).*did you mean millimetres"):
        sc = load_scenario(path)
    assert sc.geometry.bodies[0].height == 400.0


def test_a_size_far_outside_the_structural_range_warns() -> None:
    sc = Scenario("tower", Block(2.0, 2.0, 80.0, mass=1.0), duration=1.0)
    assert review(sc) == ["a block size of 80 m is far outside the structural range "
                          "(0.01 to 50 m; lengths are in metres)"]


def test_a_pulse_of_hundreds_of_g_warns_with_its_peak() -> None:
    # amplitude 20 (m, meant in mm) at 2 Hz: A ω² = 20 (4π)² = 3158 m/s², 322 g
    pulse = SinePulse(frequency=2.0, amplitude=20.0)
    sc = Scenario("pulse", Block(0.2, 0.2, 0.8, mass=1.0), excitation=pulse, duration=1.0)
    peak = 20.0 * (4.0 * math.pi) ** 2
    (msg,) = review(sc)
    assert f"{peak:.3g} m/s² ({peak / STANDARD_GRAVITY:.3g} g)" in msg
    assert review(sc.replace(excitation=SinePulse(frequency=2.0, amplitude=0.02))) == []


def test_the_cli_prints_a_warning_as_one_line_and_runs(tmp_path: Path, capsys) -> None:
    path = _file(tmp_path, "mm", 250, 200, 400)
    code = main(["run", str(path), "--engine", "analytic"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 0
    assert len(err) == 1 and err[0].startswith(f"rockbench: warning: {path}: every block size")


def test_pga_levels_all_below_uplift_warn_that_they_are_in_m_per_s2() -> None:
    sc = Scenario("b", Block(0.25, 0.25, 1.25, mass=1.0))
    uplift = uplift_acceleration(sc)  # tan λ = 0.2: uplift 1.962
    assert uplift == pytest.approx(0.2 * sc.g, rel=1e-12)
    with pytest.warns(PlausibilityWarning, match=r"at most 0\.6 m/s².*g tan λ = 1\.96 m/s² "
                                                 r"\(0\.2 g\).*did you mean g\?"):
        _warn_below_uplift((0.2, 0.4, 0.6), IntensityMeasure.PGA, uplift, 9.81)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _warn_below_uplift((0.2, 2.0), IntensityMeasure.PGA, uplift, 9.81)  # one rocks
        _warn_below_uplift((0.2, 0.6), IntensityMeasure.PGA_UPLIFT, uplift, 9.81)


# a parapet 0.3 m wide on a wall 0.6 m wide, its centre `x` from the wall's: beyond
# x = 0.3 m its centre of mass overhangs the wall's edge and nothing holds it up
PARAPET = """name = "parapet-{x}"
duration = 1.0
[[blocks]]
width = 0.6
depth = 0.4
height = 1.2
density = 2000.0
z = 0.6
[[blocks]]
width = 0.3
depth = 0.4
height = 0.8
density = 2000.0
x = {x}
z = 1.6
[excitation]
type = "free"
"""


@pytest.mark.parametrize(("x", "falls"), [(0.25, False), (0.29, False), (0.31, True),
                                          (0.4, True)])
def test_a_parapet_that_cannot_stand_is_warned_of_once(x: float, falls: bool) -> None:
    sc = get_scenario("parapet-offset0.25")
    geo = parapet(x)
    sc = sc.replace(name=f"parapet-{x}", geometry=geo)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        warned = warn_cannot_stand([sc, sc.replace(name="again")])
    assert warned == ([sc.name] if falls else [])
    msgs = [str(w.message) for w in caught if w.category is PlausibilityWarning]
    assert len(msgs) == int(falls)
    if falls:
        assert "cannot stand at rest under its own weight" in msgs[0]


def test_the_cli_warns_of_a_parapet_that_cannot_stand_and_runs(tmp_path: Path,
                                                               capsys) -> None:
    path = tmp_path / "overhang.toml"
    path.write_text(PARAPET.format(x=0.4))
    code = main(["run", str(path), "--engine", "pymunk"])
    out = capsys.readouterr()
    err = [ln for ln in out.err.strip().splitlines() if ln]
    assert code == 0
    assert len(err) == 1 and err[0].startswith("rockbench: warning: scenario 'parapet-0.4' "
                                               "cannot stand at rest")
    # and it does fall, with no base motion at all
    assert "overturned" in out.out
