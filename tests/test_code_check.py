"""The NTC 2018 code check (spectra, floor demand, linear and non-linear checks, site file, CLI).

Expected values are computed here by hand from the code's formulas (NTC 2018
§3.2.3.2, Circolare 2019 §C7.2.3 and §C8.7.1.2.1), never taken from the code
under test. The running example is the brief's: a_g = 0.25 g, F_0 = 2.4,
T_C* = 0.3 s, soil C, T1, on the ground and on the roof of a 4-storey building
(H = 12 m, T_1 = 0.4 s).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from rockbench.analytic.code_spectra import (
    Building,
    SiteSpectrum,
    damping_factor,
    floor_acceleration,
    floor_displacement_demand,
    floor_spectrum,
    simplified_floor_parameters,
    simplified_floor_spectrum,
)
from rockbench.cli import main
from rockbench.errors import ScenarioError
from rockbench.scenarios import Block, Scenario, get_scenario, single
from rockbench.studies.code_check import SiteParameters, code_check, load_site

G = 9.81
AG, F0, TCS = 0.25, 2.4, 0.3
# soil C by hand (Tab. 3.2.IV)
SS_C = 1.70 - 0.60 * F0 * AG  # 1.34, inside [1.00, 1.50]
CC_C = 1.05 * TCS ** -0.33
TC_C = CC_C * TCS
TB_C = TC_C / 3
TD_C = 4 * AG + 1.6
PLATEAU_C = AG * SS_C * F0  # η = 1 at 5 %
ETA8 = math.sqrt(10 / 13)

SITE_TOML = """\
code = "ntc2018"
ag = 0.25
F0 = 2.4
TC_star = 0.3
soil = "C"
topography = "T1"
"""
ROOF_TOML = SITE_TOML + """
[building]
height = 12.0
element_height = 12.0
period = 0.4
storeys = 4
"""


def block_scenario(width: float = 0.25, height: float = 1.25) -> Scenario:
    return Scenario(f"block-{width:g}x{height:g}",
                    single(Block(width, width, height, density=2000.0)))


@pytest.fixture()
def ground() -> SiteParameters:
    return SiteParameters(ag=AG, F0=F0, TC_star=TCS, soil="C")


@pytest.fixture()
def roof() -> SiteParameters:
    return SiteParameters(ag=AG, F0=F0, TC_star=TCS, soil="C",
                          building=Building(12.0, 12.0, 0.4, 4))


# ------------------------------------------------------------------ NTC 2018 spectra
def test_soil_c_spectrum_at_known_points():
    s = SiteSpectrum(AG, F0, TCS, "C", "T1")
    assert s.SS == pytest.approx(1.34, rel=1e-12)
    assert s.S == pytest.approx(1.34, rel=1e-12)
    assert s.CC == pytest.approx(CC_C, rel=1e-12)
    assert (s.TB, s.TC, s.TD) == pytest.approx((TB_C, TC_C, 2.6), rel=1e-12)
    assert (s.TE, s.TF) == (6.0, 10.0)
    assert s.eta == 1.0
    assert s.pga == pytest.approx(AG * 1.34, rel=1e-12)
    assert s.acceleration(0.0) == pytest.approx(AG * 1.34, rel=1e-12)
    for t in (TB_C, 0.3, TC_C * (1 - 1e-9)):
        assert s.acceleration(t) == pytest.approx(PLATEAU_C, rel=1e-9)
    assert s.acceleration(TB_C / 2) == pytest.approx(
        PLATEAU_C * (0.5 + 0.5 / F0), rel=1e-12)
    assert s.acceleration(1.0) == pytest.approx(PLATEAU_C * TC_C, rel=1e-12)
    assert s.acceleration(3.0) == pytest.approx(PLATEAU_C * TC_C * TD_C / 9, rel=1e-12)
    np.testing.assert_allclose(s.acceleration(np.array([1.0, 3.0])),
                               [PLATEAU_C * TC_C, PLATEAU_C * TC_C * TD_C / 9], rtol=1e-12)
    # displacement spectrum §3.2.3.2.3
    assert s.displacement(1.0) == pytest.approx(PLATEAU_C * TC_C * G / (4 * math.pi ** 2),
                                                rel=1e-12)
    dg = 0.025 * AG * G * 1.34 * TC_C * TD_C
    assert s.displacement(8.0) == pytest.approx(dg * (F0 + (1 - F0) * 2 / 4), rel=1e-12)
    assert s.displacement(12.0) == pytest.approx(dg, rel=1e-12)


@pytest.mark.parametrize("soil,ag,f0,expected", [
    ("A", 0.3, 2.5, 1.0),
    ("B", 0.05, 2.4, 1.20),              # 1.40 − 0.40·0.12 = 1.352 → capped at 1.20
    ("B", 0.30, 2.5, 1.40 - 0.40 * 0.75),
    ("C", 0.50, 2.5, 1.00),              # 1.70 − 0.60·1.25 = 0.95 → floor 1.00
    ("D", 0.05, 2.4, 1.80),              # 2.22 → capped at 1.80
    ("D", 0.35, 2.6, 2.40 - 1.50 * 0.91),
    ("E", 0.20, 2.5, 2.00 - 1.10 * 0.50),
])
def test_stratigraphic_amplification_and_its_limits(soil, ag, f0, expected):
    assert SiteSpectrum(ag, f0, 0.3, soil).SS == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("soil,cc", [("A", 1.0), ("B", 1.10 * 0.4 ** -0.20),
                                     ("D", 1.25 * 0.4 ** -0.50), ("E", 1.15 * 0.4 ** -0.40)])
def test_cc_of_each_soil(soil, cc):
    assert SiteSpectrum(0.2, 2.5, 0.4, soil).CC == pytest.approx(cc, rel=1e-12)


@pytest.mark.parametrize("topo,st", [("T1", 1.0), ("T2", 1.2), ("T3", 1.2), ("T4", 1.4)])
def test_topographic_amplification(topo, st):
    s = SiteSpectrum(0.2, 2.5, 0.4, "A", topo)
    assert s.S == pytest.approx(st, rel=1e-12)


def test_damping_factor():
    assert damping_factor(5.0) == 1.0
    assert damping_factor(8.0) == pytest.approx(math.sqrt(10 / 13), rel=1e-12)
    assert damping_factor(30.0) == 0.55  # √(10/35) = 0.53 → the 0.55 floor
    s = SiteSpectrum(AG, F0, TCS, "C", damping=8.0)
    assert s.plateau == pytest.approx(PLATEAU_C * ETA8, rel=1e-12)


@pytest.mark.parametrize("kw,field", [({"ag": 0.0}, "ag"), ({"F0": 2.0}, "F0"),
                                      ({"TC_star": -0.1}, "TC_star"), ({"soil": "S1"}, "soil"),
                                      ({"topography": "T5"}, "topography")])
def test_bad_site_values_name_the_field(kw, field):
    args = {"ag": AG, "F0": F0, "TC_star": TCS} | kw
    with pytest.raises(ScenarioError, match=field):
        SiteSpectrum(**args)


# ------------------------------------------------------------------ demand at a height
def test_roof_floor_acceleration_by_hand():
    b = Building(12.0, 12.0, 0.4, 4)
    assert b.participation == pytest.approx(12 / 9, rel=1e-12)
    assert b.mode_shape == 1.0
    s = SiteSpectrum(AG, F0, TCS, "C")
    # T1 = 0.4 s is on the plateau (T_B = 0.156 s, T_C = 0.469 s)
    a_z = PLATEAU_C * 12 / 9 * math.sqrt(1 + 0.0004 * 25)
    assert floor_acceleration(s, b) == pytest.approx(a_z, rel=1e-12)
    half = Building(12.0, 6.0, 0.4, 4)
    assert floor_acceleration(s, half) == pytest.approx(a_z / 2, rel=1e-12)
    # simplified floor spectrum [C7.2.11] at T_a = 0: α S (1 + z/H)
    assert simplified_floor_parameters(0.4) == (0.8, 1.4, 5.0)
    assert simplified_floor_parameters(0.7) == (0.3, 1.2, 4.0)
    assert simplified_floor_parameters(1.5) == (0.3, 1.0, 2.5)
    assert simplified_floor_spectrum(s, b, 0.0) == pytest.approx(AG * 1.34 * 2, rel=1e-12)
    assert simplified_floor_spectrum(s, b, 0.4) == pytest.approx(AG * 1.34 * 2 * 5, rel=1e-12)


def test_floor_spectrum_by_hand():
    b = Building(12.0, 12.0, 0.4, 4)
    s = SiteSpectrum(AG, F0, TCS, "C")
    a_z = PLATEAU_C * 12 / 9 * math.sqrt(1.01)
    amp = 1.1 / math.sqrt(0.05) * ETA8  # ξ_1 = 5 % read as 0.05; element ξ = 8 %
    assert floor_spectrum(s, b, 0.0, 8.0) == pytest.approx(a_z, rel=1e-12)
    assert floor_spectrum(s, b, 0.4, 8.0) == pytest.approx(amp * a_z, rel=1e-12)
    t = 0.16  # below a T1 = 0.32 s
    assert floor_spectrum(s, b, t, 8.0) == pytest.approx(
        amp * a_z / (1 + (amp - 1) * (1 - t / 0.32) ** 1.6), rel=1e-12)
    t = 1.0  # beyond b T1 = 0.44 s
    up = amp * a_z / (1 + (amp - 1) * (t / 0.44 - 1) ** 1.2)
    assert floor_spectrum(s, b, t, 8.0) == pytest.approx(
        max(up, PLATEAU_C * ETA8 * TC_C / t), rel=1e-12)
    # [C8.7.1.12]: beyond b T1 not below the displacement at the plateau's end
    floor_end = amp * a_z * G * 0.44 ** 2 / (4 * math.pi ** 2)
    assert floor_displacement_demand(s, b, 1.0, 8.0, G) == pytest.approx(
        max(up * G / (4 * math.pi ** 2), floor_end), rel=1e-12)


# ------------------------------------------------------------------ the check of a block
def hand_block() -> tuple[float, float, float, float]:
    """a0*, d_SLV, a(d_SLV), T_SLV of a 0.25 × 1.25 block (FC = 1.35) by hand."""
    b, h = 0.125, 0.625
    a0 = b / h * G / 1.35
    d_slv = 0.05
    a_slv = 0.075 / math.sqrt(b ** 2 + h ** 2 - 0.075 ** 2) * G / 1.35
    t_slv = 1.68 * math.pi * math.sqrt(d_slv / a_slv)
    return a0, d_slv, a_slv, t_slv


def test_block_on_the_ground_by_hand(ground):
    a0, d_slv, a_slv, t_slv = hand_block()
    r = code_check(block_scenario(), ground)
    pga = AG * 1.34 * G
    assert r.design_pga == pytest.approx(pga, rel=1e-12)
    assert r.friction == 1.0
    for d in r.directions:
        assert d.limit.load_factor == pytest.approx(0.2, rel=1e-9)
        lin = d.linear
        assert lin is not None
        assert lin.spectral_acceleration == pytest.approx(a0, rel=1e-9)
        assert lin.demand == pytest.approx(pga / 2, rel=1e-12)
        assert lin.ratio == pytest.approx(a0 / (pga / 2), rel=1e-9)
        assert not lin.passed  # α0 = 0.2 < a_g S = 0.335 and q = 2 is not enough
        assert lin.capacity_pga == pytest.approx(2 * a0, rel=1e-9)
        assert lin.capacity_ag == pytest.approx(AG * a0 / (pga / 2), rel=1e-9)
        nl = d.nonlinear
        assert nl is not None
        assert nl.capacity == pytest.approx(d_slv, rel=1e-9)
        assert nl.period == pytest.approx(t_slv, rel=1e-4)
        # T_C < T_SLV < T_D: S_De = a_g S η F0 T_C/T · g T²/4π², largest at T_SLV
        assert TC_C < t_slv < TD_C
        demand = PLATEAU_C * ETA8 * TC_C / t_slv * G * t_slv ** 2 / (4 * math.pi ** 2)
        assert nl.demand == pytest.approx(demand, rel=1e-4)
        assert nl.damping == 8.0
        ratio = max(d_slv / demand, a0 / pga)
        assert nl.ratio == pytest.approx(ratio, rel=1e-4)
        assert not nl.passed
        assert nl.capacity_pga == pytest.approx(pga * ratio, rel=1e-4)
    assert not r.passed
    assert r.capacity_pga("linear") == pytest.approx(2 * a0, rel=1e-9)


def test_block_on_a_roof_by_hand(roof):
    a0, d_slv, a_slv, t_slv = hand_block()
    r = code_check(block_scenario(), roof)
    a_z = PLATEAU_C * 12 / 9 * math.sqrt(1.01) * G  # m/s²
    assert r.design_pga == pytest.approx(a_z, rel=1e-12)
    (d, _) = r.directions
    assert d.linear is not None and d.nonlinear is not None
    assert d.linear.demand == pytest.approx(a_z / 2, rel=1e-12)
    assert d.linear.ratio == pytest.approx(2 * a0 / a_z, rel=1e-9)
    assert d.linear.capacity_pga == pytest.approx(2 * a0, rel=1e-9)
    # the ground's a_g S g at the same hazard: a_g,SLV = a_g · ratio
    assert r.capacity_ground_pga("linear") == pytest.approx(
        AG * 2 * a0 / a_z * 1.34 * G, rel=1e-9)
    # non-linear: T_SLV ≈ 1.27 s > b T1 = 0.44 s
    amp = 1.1 / math.sqrt(0.05) * ETA8
    t = t_slv
    floor_t = max(amp * a_z / (1 + (amp - 1) * (t / 0.44 - 1) ** 1.2),
                  PLATEAU_C * ETA8 * TC_C / t * G)
    floor = max(floor_t * t ** 2, amp * a_z * 0.44 ** 2) / (4 * math.pi ** 2)
    ground = PLATEAU_C * ETA8 * TC_C / t * G * t ** 2 / (4 * math.pi ** 2)
    demand = max(floor, ground)
    assert d.nonlinear.demand == pytest.approx(demand, rel=1e-3)
    assert d.nonlinear.ratio == pytest.approx(max(d_slv / demand, a0 / a_z), rel=1e-3)
    assert not r.passed


def test_parapet_by_hand(ground):
    r = code_check(get_scenario("parapet-offset0.25"), ground)
    pga = AG * 1.34 * G
    for d, alpha in zip(r.directions, (0.05 / 0.4, 0.15 / 0.4), strict=True):
        assert d.limit.load_factor == pytest.approx(alpha, rel=1e-6)
        assert d.kinematics is not None and d.kinematics.mass_fraction == pytest.approx(1.0)
        assert d.linear is not None
        assert d.linear.spectral_acceleration == pytest.approx(alpha * G / 1.35, rel=1e-6)
        assert d.linear.ratio == pytest.approx(alpha * G / 1.35 / (pga / 2), rel=1e-6)
        assert d.nonlinear is not None
        assert d.nonlinear.capacity == pytest.approx(0.4 * 0.4 * alpha, rel=1e-6)  # 0.4 d0


def test_the_site_parameters_change_the_check(ground):
    strong = SiteParameters(ag=AG, F0=F0, TC_star=TCS, soil="C", q=3.0, confidence_factor=1.0)
    r1, r2 = code_check(block_scenario(), ground), code_check(block_scenario(), strong)
    lin1, lin2 = r1.directions[0].linear, r2.directions[0].linear
    assert lin1 is not None and lin2 is not None
    assert lin2.ratio == pytest.approx(lin1.ratio * 1.35 * 3.0 / 2.0, rel=1e-9)


def test_arch_gets_the_linear_check_only(ground):
    r = code_check(get_scenario("arch-9v-t0.20"), ground)
    for d in r.directions:
        assert d.linear is not None and d.nonlinear is None
        assert "no finite kinematics" in d.note
    assert math.isnan(r.capacity_pga("nonlinear"))
    assert r.capacity_pga("linear") > 0
    json.dumps(r.to_dict())


def test_friction_override(ground):
    squat = block_scenario(1.0, 1.0)  # b/h = 1: slides at μ = 0.3
    r = code_check(squat, ground, friction=0.3)
    assert r.friction == 0.3
    d = r.directions[0]
    assert d.limit.governing_mode == "sliding"
    assert d.limit.load_factor == pytest.approx(0.3, rel=1e-9)
    assert d.nonlinear is None and "translates" in d.note
    rock = code_check(squat, ground, friction=math.inf)
    assert rock.directions[0].limit.load_factor == pytest.approx(1.0, rel=1e-9)
    with pytest.raises(ScenarioError, match="friction"):
        code_check(squat, ground, friction=-1.0)


def test_result_to_dict_is_json(roof):
    data = json.loads(json.dumps(code_check(get_scenario("parapet-offset0.25"), roof).to_dict()))
    assert data["design_pga"] == pytest.approx(PLATEAU_C * 12 / 9 * math.sqrt(1.01) * G)
    assert data["site"]["building"]["storeys"] == 4
    assert [d["direction"] for d in data["directions"]] == ["+x", "−x"]
    assert data["directions"][0]["nonlinear"]["capacity"] == pytest.approx(0.4 * 0.05)


# ------------------------------------------------------------------ the site file
def test_site_file(tmp_path):
    f = tmp_path / "roof.toml"
    f.write_text(ROOF_TOML)
    site = load_site(f)
    assert (site.ag, site.F0, site.TC_star, site.soil, site.topography) == (
        0.25, 2.4, 0.3, "C", "T1")
    assert (site.q, site.confidence_factor, site.code) == (2.0, 1.35, "ntc2018")
    assert site.building == Building(12.0, 12.0, 0.4, 4)
    assert site.floor_model == "modal"
    assert site.source == str(f)


@pytest.mark.parametrize("text,field", [
    ('ag = "0.25"\nF0 = 2.4\nTC_star = 0.3\n', "ag"),
    ("ag = 0.25\nF0 = 2.4\n", "TC_star"),
    ('ag = 0.25\nF0 = 2.4\nTC_star = 0.3\nsoil = "F"\n', "soil"),
    ("ag = 0.25\nF0 = 2.4\nTC_star = 0.3\nsoil = 3\n", "soil"),
    ('ag = 0.25\nF0 = 2.4\nTC_star = 0.3\ncode = "ec8"\n', "code"),
    ("ag = 0.25\nF0 = 2.4\nTC_star = 0.3\nq = 0.5\n", "q"),
    ("ag = 0.25\nF0 = 2.4\nTC_star = 0.3\nconfidence_factor = 0.9\n", "confidence_factor"),
    ("ag = 0.25\nF0 = 2.4\nTC_star = 0.3\nwind = 1\n", "wind"),
    ("ag = 0.25\nF0 = 2.4\nTC_star = 0.3\nbuilding = 3\n", "building"),
    ("ag = 0.25\nF0 = 2.4\nTC_star = 0.3\n[building]\nheight = 10\n", "building.element_height"),
    ("ag = 0.25\nF0 = 2.4\nTC_star = 0.3\n[building]\nheight = 10\nelement_height = 12\n"
     "period = 0.4\nstoreys = 3\n", "building.element_height"),
    ("ag = 0.25\nF0 = 2.4\nTC_star = 0.3\n[building]\nheight = 10\nelement_height = 10\n"
     "period = 0.4\nstoreys = 2.5\n", "building.storeys"),
    ("ag = 0.25\nF0 = 2.4\nTC_star = 0.3\n[building]\nheight = 10\nelement_height = 10\n"
     'period = 0.4\nstoreys = 3\nfloor_model = "exact"\n', "floor_model"),
    ("ag = 0.25\nF0 = [2.4\n", "malformed TOML"),
])
def test_bad_site_files_say_file_and_field(tmp_path, text, field):
    f = tmp_path / "site.toml"
    f.write_text(text)
    with pytest.raises(ScenarioError) as info:
        load_site(f)
    message = str(info.value)
    assert message.startswith(str(f)) and field in message and "\n" not in message


# ------------------------------------------------------------------ the command
def test_check_command_writes_the_report(tmp_path, capsys):
    site = tmp_path / "roof.toml"
    site.write_text(ROOF_TOML)
    out = tmp_path / "check"
    rc = main(["check", "--scenario", "parapet-offset0.25", "--site", str(site),
               "--out", str(out)])
    assert rc == 0
    printed = capsys.readouterr().out
    assert "parapet-offset0.25" in printed and "linear" in printed and "FAIL" in printed
    for name in ("report.md", "check.json", "figures/capacity.png"):
        assert (out / name).is_file(), name
    data = json.loads((out / "check.json").read_text())
    assert data["directions"][0]["load_factor"] == pytest.approx(0.125, rel=1e-6)
    assert data["command"].startswith("rockbench check")
    report = (out / "report.md").read_text()
    assert "C8.7.1.2.1.7" in report and "figures/capacity.png" in report


@pytest.mark.parametrize("argv,needle", [
    (["--block", "0.25"], "--block"),
    (["--block", "0.25,1.25", "--friction", "-1"], "--friction"),
    (["--block", "0.25,1.25", "--friction", "x"], "--friction"),
])
def test_check_command_bad_input_is_one_line(tmp_path, capsys, argv, needle):
    site = tmp_path / "site.toml"
    site.write_text(SITE_TOML)
    rc = main(["check", *argv, "--site", str(site), "--out", str(tmp_path / "o")])
    assert rc == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and needle in err


def test_check_command_bad_site_is_one_line(tmp_path, capsys):
    site = tmp_path / "site.toml"
    site.write_text("ag = 0.25\n")
    rc = main(["check", "--block", "0.25,1.25", "--site", str(site), "--out",
               str(tmp_path / "o")])
    assert rc == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and str(site) in err and "F0" in err


# ------------------------------------------------------------- Eurocode 8, beside it
@pytest.mark.fast
@pytest.mark.parametrize(("z", "period", "expected"), [
    # [4.25] with T_a = 0: α S (3 (1 + z/H) / 2 − 0.5); never below α S
    (0.0, 0.4, 0.25 * 1.15 * 1.0),
    (6.0, 0.4, 0.25 * 1.15 * (3 * 1.5 / 2 - 0.5)),
    (12.0, 0.4, 0.25 * 1.15 * 2.5),
])
def test_ec8_element_coefficient_by_hand(z, period, expected):
    from rockbench.analytic.ec8_elements import element_coefficient, soil_factor

    assert soil_factor("C") == 1.15
    got = element_coefficient(0.25, soil_factor("C"), z, 12.0, 0.0, period)
    assert got == pytest.approx(expected, rel=1e-12)
    # an element in resonance with the building (T_a = T_1): 3 (1 + z/H) − 0.5
    assert element_coefficient(0.25, 1.15, z, 12.0, period, period) == pytest.approx(
        0.25 * 1.15 * (3 * (1 + z / 12.0) - 0.5), rel=1e-12)


@pytest.mark.fast
def test_ec8_check_of_a_block_on_a_roof_by_hand(roof):
    # α0 = b/h = 0.2 against S_a γ_a / q_a = 0.25 · 1.15 · 2.5 = 0.71875 (q_a = γ_a = 1)
    e = code_check(block_scenario(), roof).ec8
    assert e is not None
    assert e.alpha0 == pytest.approx(0.2, rel=1e-9)
    assert e.coefficient == pytest.approx(0.71875, rel=1e-12)
    assert e.ratio == pytest.approx(0.2 / 0.71875, rel=1e-9) and not e.passed
    assert e.capacity_pga == pytest.approx(0.2 * e.g, rel=1e-9)
    # a wall (q_a = 2) of ordinary importance on the ground passes: 0.2 · 2 / 0.2875 > 1
    site = SiteParameters(0.25, 2.4, 0.3, "C", ec8_qa=2.0)
    assert code_check(block_scenario(), site).ec8.ratio == pytest.approx(0.4 / 0.2875, rel=1e-9)


@pytest.mark.fast
def test_ec8_table_of_the_site_file(tmp_path):
    path = tmp_path / "site.toml"
    path.write_text('ag = 0.25\nF0 = 2.4\nTC_star = 0.3\n[ec8]\nqa = 2.0\nimportance = 1.4\n')
    site = load_site(path)
    assert (site.ec8_qa, site.ec8_importance) == (2.0, 1.4)
    path.write_text('ag = 0.25\nF0 = 2.4\nTC_star = 0.3\n[ec8]\nq = 2.0\n')
    with pytest.raises(ScenarioError, match=r"\[ec8\]"):
        load_site(path)
