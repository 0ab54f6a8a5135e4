"""The analytic adapter behind the engine interface (``--engine analytic``)."""

import numpy as np
import pytest

from rockbench.analytic import quarter_period
from rockbench.engines import get_engine
from rockbench.scenarios import Block, Scenario, get_scenario, stack
from rockbench.trajectory import Status


def test_exact_and_linearised_first_impact_match_closed_forms():
    sc = get_scenario("free-b0").replace(duration=2.0)
    rock = sc.blocks[0].rocking()
    engine = get_engine("analytic")
    exact = engine.simulate(sc)
    linear = engine.simulate(sc, {"linear": True})
    assert exact.impacts[0] == pytest.approx(quarter_period(rock.p, rock.lam, sc.theta0), rel=1e-8)
    assert linear.impacts[0] == pytest.approx(
        quarter_period(rock.p, rock.lam, sc.theta0, linear=True), rel=1e-8)
    assert linear.settings["linear"] is True and exact.settings["linear"] is False
    assert linear.impacts[0] != pytest.approx(exact.impacts[0], rel=1e-6)


def test_unsupported_cases_are_statuses():
    b = Block(0.5, 0.2, 1.0, mass=1.0)
    three = Scenario("three", stack((b, b, b)), duration=0.1)
    assert get_engine("analytic").simulate(three).status is Status.UNSUPPORTED
    two = Scenario("two", stack((b, b)), duration=0.1)
    traj = get_engine("analytic").simulate(two, {"linear": True})
    assert traj.status is Status.UNSUPPORTED and "single blocks" in traj.message
    assert np.all(get_engine("analytic").simulate(two).theta == 0.0)
