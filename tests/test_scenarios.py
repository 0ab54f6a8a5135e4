"""Scenario model: geometry (λ, R, p, η), validation, TOML round trip, catalog."""

import math

import numpy as np
import pytest

from rockbench.analytic import critical_angle
from rockbench.errors import ScenarioError, UnknownScenario
from rockbench.scenarios import (
    Block,
    Contact,
    Record,
    Scenario,
    SinePulse,
    Sinusoid,
    catalog,
    get_scenario,
    get_suite,
    load_scenario,
    resolve_scenarios,
    save_scenario,
    stack,
    suites,
)


def test_single_block_constants_match_housner_closed_forms():
    # two-block-model.md T1: a 1 m x 5 m block
    r = Block(1.0, 0.2, 5.0, mass=1.0).rocking()
    assert r.lam == pytest.approx(0.197395559850, abs=1e-12)
    assert r.R == pytest.approx(2.549509756796, abs=1e-12)
    assert r.p == pytest.approx(1.698778657906, abs=1e-12)
    assert r.eta == pytest.approx(49 / 52, abs=1e-12)
    # uniform block: p = sqrt(3g/4R), η = 1 - 1.5 sin²λ
    assert r.p == pytest.approx(math.sqrt(3 * 9.81 / (4 * r.R)))
    assert r.eta == pytest.approx(1 - 1.5 * math.sin(r.lam) ** 2)


def test_reference_geometry_composite_constants():
    # two-block-model.md T6 (G_ref): lower 1 x 3 m (6000 kg), upper 0.6 x 2 m (2400 kg)
    lower = Block(1.0, 1.0, 3.0, density=2000.0)
    upper = Block(0.6, 1.0, 2.0, density=2000.0)
    assert lower.m == pytest.approx(6000) and upper.m == pytest.approx(2400)
    assert lower.inertia[1] == pytest.approx(5000)
    st = stack((lower, upper)).column
    mono = st.monolithic()
    assert mono.lam == pytest.approx(0.222081901905, abs=1e-11)
    assert mono.R == pytest.approx(2.270035511724, abs=1e-11)
    assert mono.I_O == pytest.approx(59872, rel=1e-12)
    assert mono.p == pytest.approx(1.767578007736, abs=1e-11)
    assert mono.eta == pytest.approx(0.929850347408, abs=1e-11)
    up = st.interface(1)
    assert up.lam == pytest.approx(0.291456794478, abs=1e-11)
    assert up.p == pytest.approx(2.654657584984, abs=1e-11)
    assert up.eta == pytest.approx(0.876146788991, abs=1e-11)
    assert st.critical_angle() == pytest.approx(mono.lam)


def test_chamfer_moves_pivots_inward():
    b = Block(0.2, 0.4, 0.6, density=2670.0, chamfer=0.005)
    assert b.pivot_half_width == pytest.approx(0.095)
    assert b.rocking().lam == pytest.approx(math.atan(0.095 / 0.3))
    prof = b.profile()
    assert prof.shape == (8, 2)
    assert np.min(prof[:, 1]) == pytest.approx(-0.3)
    assert np.max(prof[prof[:, 1] == -0.3][:, 0]) == pytest.approx(0.095)


def test_initial_pose_rotates_about_the_pivot():
    sc = Scenario("t", Block(0.5, 0.2, 1.0, mass=1.0), initial_tilt=0.5)
    poses = sc.initial_poses()
    c, th = poses[:, :2], poses[0, 2]
    lam = critical_angle(sc.geometry)
    assert th == pytest.approx(0.5 * lam)
    # the centroid stays at distance R from the +x pivot (0.25, 0), moved toward +x
    assert math.hypot(c[0, 0] - 0.25, c[0, 1]) == pytest.approx(math.hypot(0.25, 0.5))
    assert c[0, 0] > 0
    neg = sc.replace(initial_tilt=-0.5).initial_poses()
    th_neg = neg[0, 2]
    assert neg[0, 0] == pytest.approx(-c[0, 0]) and th_neg == pytest.approx(-th)


@pytest.mark.parametrize("make, match", [
    (lambda: Block(-0.5, 0.2, 1.0, mass=1.0), "width"),
    (lambda: Block(0.5, 0.0, 1.0, mass=1.0), "depth"),
    (lambda: Block(0.5, 0.2, float("nan"), mass=1.0), "height"),
    (lambda: Block(0.5, 0.2, 1.0), "exactly one"),
    (lambda: Block(0.5, 0.2, 1.0, mass=1.0, density=2.0), "exactly one"),
    (lambda: Block(0.5, 0.2, 1.0, mass=1.0, chamfer=0.3), "chamfer"),
    (lambda: Contact(friction=-0.1), "friction"),
    (lambda: Contact(restitution=1.5), "restitution"),
    (lambda: Scenario("x", Block(0.5, 0.2, 1.0, mass=1.0), duration=0.0), "duration"),
    (lambda: Scenario("x", Block(0.5, 0.2, 1.0, mass=1.0), initial_tilt=1.2), "tilt"),
    (lambda: Scenario("", Block(0.5, 0.2, 1.0, mass=1.0)), "name"),
])
def test_validation_messages(make, match):
    with pytest.raises(ScenarioError, match=match):
        make()


@pytest.mark.parametrize("name", ["free-b1-0.99", "single-sine-5.0hz-6mm", "stack-pulse-6.5hz-2mm"])
def test_toml_round_trip_catalog(tmp_path, name):
    sc = get_scenario(name)
    back = load_scenario(save_scenario(sc, tmp_path / "s.toml"))
    assert back == sc


def test_toml_round_trip_records_and_overrides(tmp_path):
    rec = tmp_path / "r.csv"
    rec.write_text("0,0\n0.1,1\n0.2,0\n")
    sc = Scenario("rec", stack((Block(0.5, 0.2, 1.0, mass=3.0),), (0.0,)),
                  contact=Contact(0.8, 0.1, eta=0.9),
                  excitation=Record.from_file(rec, scale=2.0, source="r.csv"),
                  duration=1.0, output_rate=500.0, g=9.80665)
    back = load_scenario(save_scenario(sc, tmp_path / "s.toml"))
    assert back.contact == sc.contact and back.g == sc.g
    assert np.array_equal(back.excitation.accelerations, sc.excitation.accelerations)
    assert back.excitation.scale == 2.0
    sc2 = sc.replace(excitation=Sinusoid(2.0, 0.003, duration=0.9, ramp_cycles=0.5))
    assert load_scenario(save_scenario(sc2, tmp_path / "t.toml")) == sc2


def test_tilt_in_radians(tmp_path):
    f = tmp_path / "s.toml"
    f.write_text('[[blocks]]\nwidth=0.5\ndepth=0.2\nheight=1.0\nmass=1.0\n'
                 '[initial]\ntilt_rad=0.2318\n')
    sc = load_scenario(f)
    assert sc.theta0 == pytest.approx(0.2318)
    assert sc.name == "s"


@pytest.mark.parametrize("text, match", [
    ("[[blocks]]\nwidth=0.5\ndepth=0.2\nheight=1\nmass=1\ncolour='red'\n", "unknown key 'colour'"),
    ("name='x'\nspeed=3\n[[blocks]]\nwidth=0.5\ndepth=0.2\nheight=1\nmass=1\n", "'speed'"),
    ("[[blocks]]\nwidth=0.5\ndepth=0.2\nheight=-1\nmass=1\n", "height"),
    ("[[blocks]]\nwidth=0.5\ndepth=0.2\nmass=1\n", "missing height"),
    ("name = \n", "malformed TOML"),
    ("name='x'\n", "at least one"),
    ("[[blocks]]\nwidth=0.5\ndepth=0.2\nheight=1\nmass=1\n[excitation]\ntype='quake'\n",
     "unknown excitation type"),
    ("[[blocks]]\nwidth=0.5\ndepth=0.2\nheight=1\nmass=1\n[excitation]\ntype='sine-pulse'\n"
     "frequency=3\namplitude=0.01\nphase=1\n", "'phase'"),
    ("[[blocks]]\nwidth=0.5\ndepth=0.2\nheight=1\nmass=1\n[excitation]\ntype='record'\n"
     "file='missing.csv'\n", "cannot read record file"),
    ("[[blocks]]\nwidth=0.5\ndepth=0.2\nheight=1\nmass=1\n[contact]\nfriction=-1\n", "friction"),
])
def test_bad_files(tmp_path, text, match):
    f = tmp_path / "bad.toml"
    f.write_text(text)
    with pytest.raises(ScenarioError, match=match):
        load_scenario(f)


def test_catalog_holds_every_paper_case():
    names = set(catalog())
    assert len(get_suite("paper-free")) == 10
    assert len(get_suite("paper-single-pulse")) == len(get_suite("paper-single-sine")) == 6
    assert len(get_suite("paper-stack-pulse")) == len(get_suite("paper-stack-sine")) == 8
    assert len(get_suite("paper")) == 38
    assert set(get_suite("smoke")) <= names
    assert {"free-b0", "free-b3-0.2", "single-pulse-3.3hz-6mm", "stack-sine-6.5hz-2mm"} <= names
    for suite in suites().values():
        assert set(suite) <= names


def test_paper_inputs_and_normalisation():
    sc = get_scenario("single-pulse-5.0hz-6mm")
    assert sc.excitation.peak_acceleration() == pytest.approx(5.92, abs=0.01)  # paper: 5.92 m/s²
    assert sc.blocks[0].m == pytest.approx(228, abs=0.5)  # paper: 228 kg
    # λ from the modelled geometry: tan λ = 0.17 / 1.0
    assert math.tan(critical_angle(sc.geometry)) == pytest.approx(0.17)
    two = get_scenario("stack-pulse-4.0hz-4mm")
    assert two.excitation.peak_acceleration() == pytest.approx(2.53, abs=0.01)
    assert critical_angle(two.geometry) == pytest.approx(two.geometry.column.monolithic().lam)
    b0 = get_scenario("free-b0")
    assert b0.theta0 == pytest.approx(0.5 * 0.197395559850)


def test_unknown_names():
    with pytest.raises(UnknownScenario, match="did you mean 'free-b1-0.5'"):
        get_scenario("free-b1-05")
    with pytest.raises(UnknownScenario, match="suite"):
        get_suite("papr")
    assert len(resolve_scenarios("smoke,free-b0")) == 4


def test_sine_pulse_catalog_consistency():
    sc = get_scenario("single-pulse-3.0hz-8mm")
    assert isinstance(sc.excitation, SinePulse)
    assert sc.output_times()[-1] == pytest.approx(sc.duration)


BLOCK = "[[blocks]]\nwidth=0.5\ndepth=0.2\nheight=1.0\nmass=1.0\n"


@pytest.mark.parametrize("text, match", [
    (BLOCK.replace("width=0.5", "width='0.5'"),
     r"\[\[blocks\]\] #1: block width .*'0.5' \(a string\)"),
    (BLOCK.replace("width=0.5", "width=true"), r"block width .*true \(a boolean\)"),
    (BLOCK.replace("width=0.5", "width=[0.5]"), r"block width .*a list"),
    (BLOCK.replace("width=0.5", "width=0"), r"block width must be a finite number > 0 \(m\)"),
    (BLOCK.replace("mass=1.0", "mass=-1"), r"block mass must be a finite number > 0 \(kg\)"),
    (BLOCK.replace("mass=1.0", "mass=nan"), "block mass"),
    (BLOCK.replace("width=0.5", "width=1979-05-27"), "block width .*a date"),
    ("name = {a = 1}\n" + BLOCK, "name must be a string, got a table"),
    ("name = 3\n" + BLOCK, "name must be a string, got 3"),
    ("description = [1]\n" + BLOCK, "description must be a string"),
    ("excitation = 'sine'\n" + BLOCK, r"\[excitation\] must be a table, got 'sine'"),
    ("contact = [1]\n" + BLOCK, r"\[contact\] must be a table"),
    ("blocks = 'x'\n", r"at least one \[\[blocks\]\] table, got 'x'"),
    (BLOCK + "[excitation]\ntype=['sine-pulse']\n", "type must be a string"),
    (BLOCK + "[excitation]\ntype='sine-pulse'\nfrequency=3\namplitude=0.01\ncycles=inf\n",
     "cycles must be an integer >= 1, got inf"),
    (BLOCK + "[excitation]\ntype='sinusoid'\nfrequency=inf\namplitude=0.01\n",
     r"sinusoid frequency must be a finite number > 0 \(Hz\), got inf"),
    (BLOCK + "[contact]\nfriction='high'\n", "contact friction .*'high'"),
    ("gravity=-9.81\n" + BLOCK + "[initial]\ntilt_rad=0.1\n", "gravity must be .* > 0"),
    ("gravity='earth'\n" + BLOCK, "gravity must be a finite number"),
    (BLOCK + "[initial]\ntilt=true\n", r"\[initial\] tilt must be a number"),
    (BLOCK + "[initial]\ntilt_rad='0.1'\n", r"\[initial\] tilt_rad must be a finite number"),
    (BLOCK + "[initial]\ntilt_rad=-0.5\n", r"tilt_rad must be smaller .* λ = 0.463648 rad, "
                                          r"got -0.5"),
    (BLOCK + "offset='0.1'\n", r"\[\[blocks\]\] #1 offset must be a finite number"),
    (BLOCK + BLOCK + "offset=0.3\n", "block #2 is off its support"),
    ("duration=-1\n" + BLOCK, "duration must be a finite number > 0"),
    ("duration=inf\n" + BLOCK, "duration must be a finite number"),
    ("output_rate=1e-6\n" + BLOCK, "a single sample over the 10 s run: a trajectory needs at "
                                   "least 2"),
])
def test_wrong_types_and_values_are_named(tmp_path, text, match):
    f = tmp_path / "bad.toml"
    f.write_text(text)
    with pytest.raises(ScenarioError, match=match) as info:
        load_scenario(f)
    msg = str(info.value)
    assert msg.startswith(f"{f}: ") and "\n" not in msg


@pytest.mark.parametrize("data, match", [
    (b"\x00\x01\xff\xfe[[blocks]]", "must be UTF-8 TOML text; byte 0xff at offset 2"),
    (("a = " + "[" * 5000 + "]" * 5000).encode(), "nested too deeply"),
    (("a = " + "{b = " * 5000 + "1" + "}" * 5000).encode(), "nested too deeply"),
])
def test_undecodable_toml_is_a_typed_error(tmp_path, data, match):
    f = tmp_path / "bad.toml"
    f.write_bytes(data)
    with pytest.raises(ScenarioError, match=match) as info:
        load_scenario(f)
    assert str(info.value).startswith(f"{f}: ") and "\n" not in str(info.value)


def test_windows_line_endings_read_as_before(tmp_path):
    f = tmp_path / "crlf.toml"
    f.write_bytes(b'description = """two\r\nlines"""\r\n' + BLOCK.replace("\n", "\r\n").encode())
    assert load_scenario(f).description == "two\nlines"


@pytest.mark.parametrize("offsets, ok", [
    ((0.0, 0.0), True),
    ((0.0, 0.249), True),     # centre of the upper block just inside the lower's face
    ((0.0, 0.25), False),     # on the edge: no rest position
    ((0.0, -0.3), False),
    ((0.5, 0.5), True),       # the bottom block's own position is free
    ((0.0, 0.15, 0.3), True),  # the top pair's centre of mass (x = 0.225) is on block #1
    ((0.0, 0.2, 0.4), False),  # each block's centre is over the one below, but the top
                               # pair's centre of mass (x = 0.3) is off block #1
])
def test_stack_offsets_must_keep_each_centre_of_mass_on_its_support(offsets, ok):
    blk = Block(0.5, 0.2, 1.0, mass=1.0)
    make = lambda: stack((blk,) * len(offsets), offsets)  # noqa: E731
    if ok:
        assert make().column.offsets == offsets
    else:
        with pytest.raises(ScenarioError, match="off its support"):
            make()


def test_output_rate_gives_at_least_two_samples():
    blk = Block(0.5, 0.2, 1.0, mass=1.0)
    sc = Scenario("x", blk, duration=2.0, output_rate=0.5)
    assert sc.output_times().tolist() == [0.0, 2.0]
    with pytest.raises(ScenarioError, match=r"output_rate >= 1/duration = 0.5"):
        Scenario("x", blk, duration=2.0, output_rate=0.4)


@pytest.mark.parametrize("make", [
    lambda: Block(True, 0.2, 1.0, mass=1.0),
    lambda: Block("0.5", 0.2, 1.0, mass=1.0),
    lambda: Contact(friction="1"),
    lambda: Scenario("x", Block(0.5, 0.2, 1.0, mass=1.0), initial_tilt=True),
    lambda: Scenario("x", Block(0.5, 0.2, 1.0, mass=1.0), duration="10"),
    lambda: stack((Block(0.5, 0.2, 1.0, mass=1.0),), ("0",)),
])
def test_the_api_never_coerces_strings_or_booleans(make):
    with pytest.raises(ScenarioError, match="boolean|string"):
        make()
