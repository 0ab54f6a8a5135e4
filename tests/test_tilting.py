"""Tilting table (issue 18 item 4a): the TiltTable excitation and engines against limit analysis."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rockbench.errors import ScenarioError
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Block, Scenario, excitation_from_table, get_scenario
from rockbench.scenarios.excitation import TiltTable
from rockbench.studies.tilting import quasi_static, reference, tilting_table

#: Rate of the first run (1/s); the second runs at half of it.
RATE = 0.05
#: The onset lags the threshold (the mechanism needs time to turn by the onset angle):
#: at RATE/2 it may overshoot the LP factor by this much, and never undershoot by more
#: than the detection resolution.
OVERSHOOT = 0.04
UNDERSHOOT = 0.005
#: Halving the rate changes the onset factor by less than this (quasi-static).
HALVING = 0.035
#: The rate-0 extrapolation (lag ∝ rate^(2/3)) agrees with the LP within this.
EXTRAPOLATED = 0.01


# ---------------------------------------------------------------- the excitation
def test_tilt_table_motion_is_the_exact_ramp_and_its_integrals():
    exc = TiltTable(0.05, direction=1, gravity=9.81)
    t = np.linspace(0.0, 4.0, 4001)
    a, v, u = exc.acceleration(t), exc.velocity(t), exc.displacement(t)
    assert a == pytest.approx(-0.05 * 9.81 * t, abs=1e-15)  # loads toward +x: base toward −x
    assert np.gradient(v, t, edge_order=2) == pytest.approx(a, abs=1e-9)
    assert np.gradient(u, t, edge_order=2) == pytest.approx(v, abs=1e-6)  # O(h²) of a cubic
    assert exc.load_factor(t) == pytest.approx(-a / 9.81)
    assert exc.motion_bounds(4.0) == pytest.approx((abs(u[-1]), abs(v[-1])))
    assert exc.scalar_acceleration()(2.0) == pytest.approx(float(exc.acceleration(2.0)))
    assert TiltTable(0.05, direction=-1).acceleration(1.0) > 0
    late = TiltTable(0.05, gravity=9.81, delay=0.5)
    assert late.displacement(t + 0.5) == pytest.approx(u, rel=1e-12, abs=1e-15)
    assert late.acceleration(0.4) == 0.0 and late.breakpoints == (0.5,)


def test_tilt_table_reads_back_its_table_and_refuses_bad_fields():
    exc = TiltTable(0.02, direction=-1, gravity=9.80665, delay=0.25)
    assert excitation_from_table(exc.to_table()) == exc
    for bad in ({"rate": 0.0}, {"rate": 0.1, "direction": 0}, {"rate": 0.1, "direction": True},
                {"rate": 0.1, "gravity": -1.0}, {"rate": 0.1, "delay": -0.1},
                {"direction": 1}):
        with pytest.raises(ScenarioError, match=r"^\[excitation\]"):
            excitation_from_table({"type": "tilt-table", **bad})


# ---------------------------------------------------------------- engines against the LP
CASES = {
    "single block b/h = 0.5": Scenario(name="b2", geometry=Block(0.5, 0.2, 1.0, mass=1.0)),
    "parapet": get_scenario("parapet-offset0.25"),
    "5-drum column": get_scenario("column-5drums"),
}


#: Engine settings: pymunk at dt 0.1 ms (its fast preset, dt 1 ms, moves early: the
#: parapet's onset at 0.1065 against 0.125); MuJoCo's fast preset, whose onsets at
#: RATE / 2 are those of its accurate preset within 0.1 % (b2 0.50452 against 0.50453,
#: parapet 0.12891 against 0.12894, column 0.24550 against 0.24564) at a tenth of the
#: cost; on the wall its softer contacts creep, 0.58039 against 0.58304 (dt 0.1 ms).
SETTINGS = {"pymunk": {"timestep": 1e-4}, "mujoco": {"preset": "fast"}}


@pytest.fixture(scope="module", params=list(SETTINGS))
def comparisons(request):
    engine = request.param
    return engine, tilting_table(list(CASES.values()), engine, rate=RATE,
                                 settings=SETTINGS[engine],
                                 execution=ExecutionOptions(isolate=False))


#: The 6 x 3 running-bond wall of 0.24 x 0.12 m bricks (mu = 1).
WALL = get_scenario("wall-6x3")
#: Its rate (1/s): twice RATE halves the cost and is quasi-static (halving it moves the
#: onset by -0.5 % in pymunk, -0.6 % in MuJoCo; their onsets +1.1 % and +0.8 % at 0.05/s).
WALL_RATE = 0.1
#: Its runs stop at this multiple of the LP factor: the onset needs the developed motion
#: (100 times the thresholds), reached by +4.3 % at 0.05/s.
WALL_OVERSHOOT = 1.15


def test_limit_analysis_reference_of_the_cases():
    # closed forms: b/h for the block, the parapet's lever 0.05 over 0.4 on the wall
    # edge, the column's width over its height
    alphas = [reference(sc).load_factor for sc in CASES.values()]
    assert alphas == pytest.approx([0.5, 0.125, 0.6 / 2.5], rel=1e-7)


@pytest.mark.slow
def test_tilting_table_onset_matches_the_collapse_factor(comparisons):
    engine, cmps = comparisons
    for name, c in zip(CASES, cmps, strict=True):
        what = (f"{engine} {name}: onset α {c.run.onset_factor:.5f} at {RATE}/s, "
                f"{c.half.onset_factor:.5f} at {RATE / 2}/s, LP {c.limit.load_factor:.5f}")
        assert c.half.status.completed, f"{what}: {c.half.message}"
        assert -UNDERSHOOT <= c.error <= OVERSHOOT, what
        assert quasi_static(c, HALVING), what
        # the lag shrinks with the rate: the slower run is closer
        assert c.half.onset_factor <= c.run.onset_factor, what
        assert abs(c.extrapolated_error) <= EXTRAPOLATED, what
        assert abs(c.angle_error) <= OVERSHOOT * c.limit.tilt_angle, what


def test_tilting_table_moves_the_mechanisms_blocks_the_mechanisms_way(comparisons):
    engine, cmps = comparisons
    for name, c in zip(CASES, cmps, strict=True):
        assert c.mechanism_matches, f"{engine} {name}: moved {c.half.moved}, LP " \
                                    f"{c.limit.moving_blocks}"
        signs = tuple(c.limit.mechanism[i].rotation_sign for i in c.half.moved)
        assert c.half.rotation_sign == signs, f"{engine} {name}"


def test_parapet_tilted_the_other_way_holds_to_its_longer_lever():
    (c,) = tilting_table([CASES["parapet"]], "pymunk", rate=RATE, direction=-1,
                         settings=SETTINGS["pymunk"], execution=ExecutionOptions(isolate=False))
    assert c.limit.load_factor == pytest.approx(0.375, rel=1e-7)
    assert -UNDERSHOOT <= c.error <= OVERSHOOT and c.mechanism_matches
    assert c.half.rotation_sign == (-1,)
    assert math.isfinite(c.half.cpu_time) and c.half.cpu_time > 0


@pytest.mark.slow
def test_thin_arch_opens_its_four_hinge_mechanism_at_the_lp_factor():
    # t/R = 0.15, not far above the minimum 0.1075: the contacts settle first (SETTLE)
    sc = get_scenario("arch-9v-t0.15")
    (c,) = tilting_table([sc], "pymunk", rate=RATE, settings=SETTINGS["pymunk"],
                         execution=ExecutionOptions(isolate=False))
    assert c.limit.load_factor == pytest.approx(0.1464, abs=1e-4)
    assert -UNDERSHOOT <= c.error <= OVERSHOOT and quasi_static(c, HALVING)
    assert c.mechanism_matches
    signs = tuple(c.limit.mechanism[i].rotation_sign for i in c.half.moved)
    assert c.half.rotation_sign == signs and len(set(signs)) == 2  # alternating hinges


@pytest.mark.parametrize("engine", list(SETTINGS))
@pytest.mark.slow
def test_running_bond_wall_turns_its_stepped_wedge_out_at_the_coulomb_lp_factor(engine):
    # Coulomb joints: the nine-brick wedge above the first course turns about that
    # course's leeward corner at 11/19 (its head joints open); the associative LP's 0.992
    # leans on friction at head joints that nothing presses. MuJoCo's soft contacts turn
    # single leeward half bricks by the onset angle first (4 % below), so the onset is
    # taken on the developed motion (rockbench.studies.tilting).
    (c,) = tilting_table([WALL], engine, rate=WALL_RATE, settings=SETTINGS[engine],
                         overshoot=WALL_OVERSHOOT, execution=ExecutionOptions(isolate=False))
    assert c.limit.load_factor == pytest.approx(11 / 19, rel=1e-8)
    assert c.limit.moving_blocks == (6, 9, 12, 13, 15, 16, 18, 19, 20)
    what = (f"{engine} wall: onset α {c.run.onset_factor:.5f} at {WALL_RATE}/s, "
            f"{c.half.onset_factor:.5f} at {WALL_RATE / 2}/s, LP {c.limit.load_factor:.5f}")
    assert c.half.status.completed, f"{what}: {c.half.message}"
    assert -UNDERSHOOT <= c.error <= OVERSHOOT and quasi_static(c, HALVING), what
    assert abs(c.extrapolated_error) <= EXTRAPOLATED, what
    assert c.mechanism_matches, f"{what}: moved {c.half.moved}"
    assert c.half.rotation_sign == (1,) * 9, what  # one rigid rotation toward +x
