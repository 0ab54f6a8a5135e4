"""Incidence angles: a horizontal pair turned about the vertical, exactly."""

from __future__ import annotations

import numpy as np
import pytest

from rockbench.errors import ScenarioError
from rockbench.scenarios.excitation import Free, Record, SinePulse, Sinusoid, TiltTable
from rockbench.scenarios.incidence import along, horizontal_pair, rotate_pair, scaled

pytestmark = pytest.mark.fast


def _pair() -> tuple[Record, Record]:
    t1 = np.linspace(0.0, 4.0, 401)
    t2 = np.linspace(0.0, 3.5, 176)  # another step and length: combined on both grids
    h1 = Record(t1, 2.0 * np.sin(7.0 * t1) * np.exp(-t1), scale=1.5)
    h2 = Record(t2, -1.0 * np.cos(5.0 * t2) * t2 * np.exp(-t2))
    return h1, h2


def test_zero_and_ninety_degrees_give_the_pair_and_its_quarter_turn():
    h1, h2 = _pair()
    t = np.linspace(0.0, 4.5, 2001)
    c0 = rotate_pair(h1, h2, 0.0)
    assert c0.x is h1 and c0.y is h2 and c0.z.is_free
    c90 = rotate_pair(h1, h2, 90.0)
    np.testing.assert_allclose(c90.x.acceleration(t), -np.asarray(h2.acceleration(t)),
                               atol=1e-12)
    np.testing.assert_allclose(c90.y.acceleration(t), h1.acceleration(t), atol=1e-12)


@pytest.mark.parametrize("angle", [17.0, 30.0, 45.0, 120.0, 163.0])
def test_the_resultant_and_its_peak_do_not_depend_on_the_angle(angle):
    h1, h2 = _pair()
    grid = np.union1d(h1.times, h2.times)
    c = rotate_pair(h1, h2, angle, z=SinePulse(2.0, 0.001))
    r0 = np.hypot(h1.acceleration(grid), h2.acceleration(grid))
    r = np.hypot(c.x.acceleration(grid), c.y.acceleration(grid))
    # the combined records are baseline-corrected again: a constant of the size of the
    # end-of-record mismatch of the two grids (here 1e-4 of the peak)
    np.testing.assert_allclose(r, r0, atol=2e-4 * r0.max())
    assert r.max() == pytest.approx(r0.max(), rel=2e-4)
    # the components are what the rotation says, the vertical untouched, the base at rest
    a = np.radians(angle)
    np.testing.assert_allclose(
        c.x.acceleration(grid),
        np.cos(a) * h1.acceleration(grid) - np.sin(a) * h2.acceleration(grid),
        atol=2e-4 * r0.max())
    assert c.z == SinePulse(2.0, 0.001)
    assert abs(float(c.x.velocity(5.0))) < 1e-9 and abs(float(c.y.velocity(5.0))) < 1e-9


def test_one_motion_along_a_direction_is_scaled_exactly():
    p = SinePulse(3.0, 0.008)
    c = along(p, 30.0)
    assert c.x == SinePulse(3.0, 0.008 * np.cos(np.radians(30.0)))
    assert c.y.amplitude == pytest.approx(0.004, rel=1e-14)
    assert along(p, 90.0).x.is_free and along(p, 0.0).y.is_free
    assert scaled(Sinusoid(2.0, 0.01, 3.0), -0.5).amplitude == pytest.approx(-0.005)
    h1, _ = _pair()
    assert scaled(h1, 0.5).scale == pytest.approx(0.75)
    # a pair with one still component is the other turned exactly (no resampling)
    assert rotate_pair(p, Free(), 60.0) == along(p, 60.0)


def test_what_cannot_be_turned_is_refused():
    with pytest.raises(ScenarioError, match="cannot be turned"):
        scaled(TiltTable(0.5), 0.5)
    with pytest.raises(ScenarioError, match="must be records"):
        rotate_pair(SinePulse(3.0, 0.008), SinePulse(2.0, 0.004), 30.0)
    from rockbench.scenarios.excitation import Components
    with pytest.raises(ScenarioError, match="no horizontal component along x"):
        horizontal_pair(Components(y=SinePulse(3.0, 0.008)))
