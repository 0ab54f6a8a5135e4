"""Cylinders as bodies, 3D starts (a tilt toward any azimuth, initial velocities), and the
analytic references that cover them."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rockbench.analytic import (
    quarter_period,
    reference,
    rolling_reference,
    rolling_start,
    steady_precession,
)
from rockbench.bounds import SpeedBound
from rockbench.engines import get_engine
from rockbench.errors import ScenarioError, UnsupportedScenario
from rockbench.geometry import Block, Cylinder, footprint_pivot, stack
from rockbench.scenarios import Scenario, scenario_from_dict, scenario_to_dict
from rockbench.studies.references_3d import (
    DRUM,
    PILLAR,
    corner_landing_time,
    corner_release,
    first_zero,
    precession,
)
from rockbench.trajectory import Status

pytestmark = pytest.mark.fast


def _corners(state: np.ndarray, block: Block) -> np.ndarray:
    """World positions of a block's four bottom corners from its state row."""
    rot = Rotation.from_quat(np.roll(state[3:7], -1))
    local = [(sx * block.b, sy * 0.5 * block.depth, -block.h) for sx in (-1, 1) for sy in (-1, 1)]
    return state[:3] + rot.apply(local)


# ---------------------------------------------------------------- the body
def test_cylinder_mass_inertia_and_rocking_constants() -> None:
    c = Cylinder(0.3, 1.5, density=2000.0)
    m = 2000.0 * math.pi * 0.09 * 1.5
    assert c.m == pytest.approx(m)
    np.testing.assert_allclose(c.inertia, [m * (3 * 0.09 + 2.25) / 12] * 2 + [m * 0.045])
    rock = c.rocking()
    assert rock.lam == pytest.approx(math.atan(0.3 / 0.75))
    i_o = c.i_transverse + m * (0.09 + 0.75 ** 2)
    assert rock.p == pytest.approx(math.sqrt(m * 9.81 * math.hypot(0.3, 0.75) / i_o))
    assert (c.width, c.depth, c.chamfer) == (0.6, 0.6, 0.0)
    np.testing.assert_array_equal(c.profile(), [[-0.3, -0.75], [0.3, -0.75], [0.3, 0.75],
                                                [-0.3, 0.75]])


def test_drums_stack_into_a_column() -> None:
    col = stack((Cylinder(0.3, 0.6, mass=300.0), Cylinder(0.25, 0.5, mass=200.0))).column
    assert col is not None and col.blocks[1].pivot_half_width == 0.25
    assert col.interface(1).lam == pytest.approx(math.atan(0.25 / 0.25))


@pytest.mark.parametrize("kw, field", [({"radius": 0.0, "height": 1.0, "mass": 1.0}, "radius"),
                                       ({"radius": 0.1, "height": 1.0}, "density"),
                                       ({"radius": 0.1, "height": -1.0, "mass": 1.0}, "height")])
def test_bad_cylinders_are_refused_with_the_field(kw: dict, field: str) -> None:
    with pytest.raises(ScenarioError, match=f"cylinder.*{field}|{field}.*cylinder"):
        Cylinder(**kw)


def test_footprint_pivot_is_an_edge_a_corner_or_a_rim_point() -> None:
    np.testing.assert_allclose(footprint_pivot(PILLAR, 0.0), [0.15, 0.0])
    np.testing.assert_allclose(footprint_pivot(PILLAR, 0.5 * math.pi), [0.0, 0.15], atol=1e-15)
    np.testing.assert_allclose(footprint_pivot(PILLAR, 2.0), [-0.15, 0.15])
    np.testing.assert_allclose(footprint_pivot(DRUM, 2.0), 0.15 * np.array([math.cos(2.0),
                                                                            math.sin(2.0)]))


# ---------------------------------------------------------------- the start
def test_a_planar_start_keeps_its_poses_bit_for_bit() -> None:
    sc = Scenario("s", Block(0.5, 0.2, 1.0, mass=1.0), initial_tilt=-0.4)
    st, p = sc.initial_states(), sc.initial_poses()
    assert st[0, 0] == p[0, 0] and st[0, 2] == p[0, 1] and st[0, 1] == 0.0
    th = 2.0 * math.atan2(st[0, 5], st[0, 3])
    assert th == pytest.approx(p[0, 2], abs=1e-15) and not st[:, 7:].any()
    assert sc.planar_start and not sc.moving_start


def test_a_corner_start_stands_on_its_corner_tilted_by_theta0() -> None:
    sc = corner_release()
    assert sc.tilt_lambda() == pytest.approx(math.atan(0.15 * math.sqrt(2) / 0.6))
    assert sc.theta0 == pytest.approx(0.5 * sc.tilt_lambda())
    st = sc.initial_states()[0]
    z = _corners(st, PILLAR)[:, 2]
    assert z.min() == pytest.approx(0.0, abs=1e-15)
    assert np.sum(z < 1e-12) == 1  # one corner touches, the (+x, +y) one
    np.testing.assert_allclose(_corners(st, PILLAR)[np.argmin(z), :2], [0.15, 0.15])
    axis = Rotation.from_quat(np.roll(st[3:7], -1)).apply([0.0, 0.0, 1.0])
    assert math.acos(axis[2]) == pytest.approx(sc.theta0)
    assert math.atan2(axis[1], axis[0]) == pytest.approx(0.25 * math.pi)
    assert not sc.planar_start


def test_a_rolling_start_keeps_the_contact_point_at_rest() -> None:
    sc, sp = precession(1.0)
    st = sc.initial_states()[0]
    rot = Rotation.from_quat(np.roll(st[3:7], -1))
    contact = st[:3] + rot.apply([0.3, 0.0, -0.75])  # the rim point on the lean side
    assert contact[2] == pytest.approx(0.0, abs=1e-15)
    np.testing.assert_allclose(st[7:10] + np.cross(st[10:13], contact - st[:3]), 0.0,
                               atol=1e-14)
    assert sc.moving_start and not sc.planar_start
    assert sc.initial_kinetic_energy() > 0.0


def test_a_moving_start_widens_the_speed_bound() -> None:
    sc, _ = precession(1.0)
    still = Scenario("still", sc.geometry, initial_tilt=sc.initial_tilt)
    assert SpeedBound.for_scenario(sc).v_max > SpeedBound.for_scenario(still).v_max
    # the spin about its own axis is bounded through the smallest moment, not I_yy's
    assert SpeedBound.for_scenario(sc).omega_max > SpeedBound.for_scenario(still).omega_max


@pytest.mark.parametrize("kw, match", [
    ({"initial_azimuth": 0.3}, "needs an initial tilt"),
    ({"initial_velocity": (0.0, 1.0)}, "initial velocity must be three numbers"),
    ({"initial_angular_velocity": (0.0, math.nan, 0.0)}, "initial angular velocity y"),
])
def test_bad_starts_are_refused(kw: dict, match: str) -> None:
    with pytest.raises(ScenarioError, match=match):
        Scenario("s", DRUM, **kw)


def test_velocities_are_for_one_body() -> None:
    with pytest.raises(ScenarioError, match="single body"):
        Scenario("s", stack((DRUM, DRUM)), initial_velocity=(0.1, 0.0, 0.0))


# ---------------------------------------------------------------- scenario files
def test_a_scenario_file_with_a_cylinder_and_a_3d_start_round_trips() -> None:
    data = {"name": "drum", "blocks": [{"radius": 0.3, "height": 1.5, "density": 2000.0}],
            "initial": {"tilt": 0.5, "azimuth": 30.0, "angular_velocity": [0.0, 0.0, 1.0]}}
    sc = scenario_from_dict(data)
    assert isinstance(sc.blocks[0], Cylinder)
    assert sc.initial_azimuth == pytest.approx(math.radians(30.0))
    assert sc.initial_angular_velocity == (0.0, 0.0, 1.0)
    assert scenario_from_dict(scenario_to_dict(sc)) == sc


@pytest.mark.parametrize("block, initial, match", [
    ({"radius": 0.3, "height": 1.5, "mass": 1.0, "width": 1.0}, {},
     r"\[\[blocks\]\] #1 is a cylinder .*width"),
    ({"radius": 0.3, "mass": 1.0}, {}, r"\[\[blocks\]\] #1 is missing height"),
    ({"radius": 0.3, "height": 1.5, "mass": 1.0}, {"azimuth": 10.0},
     r"\[initial\] azimuth points the tilt"),
    ({"radius": 0.3, "height": 1.5, "mass": 1.0}, {"spin": 1.0}, r"'spin' in \[initial\]"),
])
def test_bad_scenario_files_name_the_field(block: dict, initial: dict, match: str) -> None:
    with pytest.raises(ScenarioError, match=match):
        scenario_from_dict({"blocks": [block], "initial": initial})


# ---------------------------------------------------------------- references
def test_a_drum_in_plane_gets_housner_with_the_cylinder_constants() -> None:
    sc = Scenario("drum", DRUM, initial_tilt=0.5, duration=0.8)
    ref = reference(sc)
    rock = DRUM.rocking()
    assert first_zero(ref.t, ref.theta[:, 0]) == pytest.approx(
        quarter_period(rock.p, rock.lam, sc.theta0), rel=1e-4)


def test_a_tilt_toward_any_azimuth_rolls_as_the_planar_release() -> None:
    """A drum released from rest toward 50° stays in that vertical plane and its tilt
    follows Housner's θ in the x–z plane until it lands (the reference stops there)."""
    planar = reference(Scenario("p", DRUM, initial_tilt=0.5, duration=0.8))
    sc = Scenario("a", DRUM, initial_tilt=0.5, initial_azimuth=math.radians(50.0),
                  duration=0.8)
    ref = reference(sc)
    assert ref.status is Status.UNSUPPORTED and "landed" in ref.message
    n = ref.t.size
    assert 0.3 < ref.t[-1] < 0.4
    np.testing.assert_allclose(ref.tilt[:, 0], planar.theta[:n, 0], atol=1e-7)
    np.testing.assert_allclose(ref.azimuth[:-1, 0], math.radians(50.0), atol=1e-9)


def test_the_rolling_reference_holds_a_steady_precession() -> None:
    sc, sp = precession(3.0)
    ref = reference(sc)
    assert ref.status is Status.OK
    np.testing.assert_allclose(ref.tilt[:, 0], sp.theta, atol=1e-9)
    np.testing.assert_allclose(np.hypot(ref.x[:, 0], ref.y[:, 0]), sp.com_radius, atol=1e-9)
    az = np.unwrap(ref.azimuth[:, 0])
    assert (az[-1] - az[0]) / 3.0 == pytest.approx(sp.psi_dot, rel=1e-9)


def test_a_start_that_slips_has_no_rolling_reference() -> None:
    start = rolling_start(DRUM, 0.1, psi_dot=2.0)
    sc = Scenario("slip", DRUM, **{**start._asdict(), "initial_velocity": (0.0, 0.0, 0.0)})
    with pytest.raises(UnsupportedScenario, match="without slipping"):
        rolling_reference(sc)


def test_a_corner_release_has_no_analytic_engine_reference_but_a_closed_form() -> None:
    tr = get_engine("analytic").simulate(corner_release())
    assert tr.status is Status.UNSUPPORTED and "rolling reference" in tr.message
    tilt = corner_release().theta0
    # the closed form is the planar quarter period with the diagonal's constants
    assert corner_landing_time(PILLAR, tilt) > quarter_period(
        PILLAR.rocking().p, PILLAR.rocking().lam, 0.5 * PILLAR.rocking().lam)


# ---------------------------------------------------------------- engines that cannot
def test_an_engine_without_cylinders_or_3d_starts_says_so() -> None:
    engine = get_engine("dem2d")
    tr = engine.simulate(Scenario("drum", DRUM, initial_tilt=0.5, duration=0.1))
    assert tr.status is Status.UNSUPPORTED and "does not build cylinders" in tr.message
    tr = engine.simulate(corner_release(0.1))
    assert tr.status is Status.UNSUPPORTED and "x–z plane only" in tr.message
    sc, _ = precession(0.1)
    assert get_engine("dem2d").simulate(sc).status is Status.UNSUPPORTED


def test_steady_precession_needs_a_wide_enough_contact_circle() -> None:
    with pytest.raises(ScenarioError, match="no steady precession"):
        steady_precession(Cylinder(0.3, 1.5, density=2000.0), 0.2, contact_radius=0.0)
