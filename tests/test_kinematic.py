"""Kinematic analysis of local mechanisms (rockbench.analytic.kinematic) against hand geometry.

Every expected value is derived here from the geometry, not taken from the code
under test: a block of half-width b and half-height h rocking on its corner
(R = √(b² + h²), tan λ = b/h) has α(θ) = tan(λ − θ) after a rotation θ, its
centre of gravity moves R[sin λ − sin(λ − θ)] sideways, e* = 1, M* = m and
d_0 = b; a parapet turns about its wall's edge or its own corner; a monolithic
two-block stack has e* = (Σ m z)² / (Σ m Σ m z²) with z the heights of the
centres of gravity above the pivot.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rockbench.analytic.kinematic import (
    KinematicAnalysis,
    NoFiniteKinematics,
    kinematic_analysis,
)
from rockbench.analytic.static_collapse import LimitResult, limit_analysis
from rockbench.errors import ScenarioError
from rockbench.geometry import Block, Geometry, drum_column, parapet, single, voussoir_arch

G = 9.81
RHO = 2000.0
FC = 1.35


def block(width: float, height: float, depth: float = 1.0) -> Geometry:
    return single(Block(width, depth, height, density=RHO))


def analyse(geo: Geometry, direction: int, *, friction: float = math.inf,
            fc: float = FC) -> KinematicAnalysis:
    lim = limit_analysis(geo, friction=friction, direction=direction, g=G)
    return kinematic_analysis(geo, lim, confidence_factor=fc, g=G)


# ------------------------------------------------------------------ a single block
@pytest.mark.parametrize("width,height", [(0.25, 1.25), (0.4, 2.0), (1.0, 1.5)])
@pytest.mark.parametrize("direction", [1, -1])
def test_single_block_linear_quantities(width, height, direction):
    b, h = width / 2, height / 2
    mass = RHO * width * height * 1.0
    k = analyse(block(width, height), direction)
    assert k.load_factor == pytest.approx(b / h, rel=1e-9)
    assert k.moving_blocks == (0,)
    np.testing.assert_allclose(k.delta_x, [1.0])
    assert k.control_block == 0
    np.testing.assert_allclose(k.control_point, [0.0, h], atol=1e-12)
    assert k.mass_fraction == pytest.approx(1.0, rel=1e-12)
    assert k.participating_mass == pytest.approx(mass, rel=1e-12)
    assert k.total_weight == pytest.approx(mass * G, rel=1e-12)
    assert k.spectral_acceleration == pytest.approx(b / h * G / FC, rel=1e-9)
    assert k.direction_label == ("+x" if direction > 0 else "−x")


@pytest.mark.parametrize("width,height", [(0.25, 1.25), (0.4, 2.0), (1.0, 1.5)])
def test_single_block_capacity_curve_is_tan_lambda_minus_theta(width, height):
    b, h = width / 2, height / 2
    radius, lam = math.hypot(b, h), math.atan2(b, h)
    k = analyse(block(width, height), 1)
    curve = k.curve
    assert curve is not None and k.no_curve_reason == ""
    assert curve.rotation0 == pytest.approx(lam, rel=1e-9)
    theta = curve.rotation
    np.testing.assert_allclose(curve.load_factor[:-1], np.tan(lam - theta[:-1]), rtol=1e-9,
                               atol=1e-12)
    assert curve.load_factor[-1] == 0.0
    d_hand = radius * (math.sin(lam) - np.sin(lam - theta))
    np.testing.assert_allclose(curve.control_displacement, d_hand, rtol=1e-9, atol=1e-14)
    np.testing.assert_allclose(curve.displacement, d_hand, rtol=1e-9, atol=1e-14)  # e* = 1
    np.testing.assert_allclose(curve.acceleration, curve.load_factor * G / FC, rtol=1e-12)
    assert k.d0 == pytest.approx(b, rel=1e-9)
    assert curve.a0 == pytest.approx(b / h * G / FC, rel=1e-9)


def test_single_block_code_periods_by_hand():
    b, h = 0.125, 0.625
    radius = math.hypot(b, h)
    k = analyse(block(2 * b, 2 * h, 0.25), 1)
    a0 = b / h * G / FC
    # Circolare 2019: d_SLV = 0.4 d0 = 0.4 b; on the exact curve α = (b − d)/√(R² − (b − d)²)
    d_slv = 0.4 * b
    a_slv = (b - d_slv) / math.sqrt(radius ** 2 - (b - d_slv) ** 2) * G / FC
    assert k.d_slv == pytest.approx(d_slv, rel=1e-9)
    assert k.a_slv == pytest.approx(a_slv, rel=1e-4)  # interpolated between curve points
    assert k.period_slv == pytest.approx(1.68 * math.pi * math.sqrt(d_slv / a_slv), rel=1e-4)
    d_slc = 0.6 * b
    a_slc = (b - d_slc) / math.sqrt(radius ** 2 - (b - d_slc) ** 2) * G / FC
    assert k.d_slc == pytest.approx(d_slc, rel=1e-9)
    assert k.period_slc == pytest.approx(1.56 * math.pi * math.sqrt(d_slc / a_slc), rel=1e-4)
    # Circolare 2009 on the linear curve: du = 0.4 d0, ds = 0.4 du, as = a0 (1 − ds/d0)
    ds = 0.16 * b
    as_ = a0 * (1 - 0.16)
    assert k.du_2009 == pytest.approx(0.4 * b, rel=1e-9)
    assert k.ds_2009 == pytest.approx(ds, rel=1e-9)
    assert k.as_2009 == pytest.approx(as_, rel=1e-9)
    assert k.secant_period_2009 == pytest.approx(2 * math.pi * math.sqrt(ds / as_), rel=1e-9)
    assert k.linear_acceleration_at(0.0) == pytest.approx(a0, rel=1e-9)
    assert k.linear_acceleration_at(2 * b) == 0.0
    # the exact curve lies below the linear one between the ends (√(R² − u²) > h)
    assert k.acceleration_at(0.5 * b) < k.linear_acceleration_at(0.5 * b)


def test_confidence_factor_divides_the_capacity_only():
    geo = block(0.3, 1.2)
    k1, k2 = analyse(geo, 1, fc=1.0), analyse(geo, 1, fc=1.2)
    assert k2.spectral_acceleration == pytest.approx(k1.spectral_acceleration / 1.2, rel=1e-12)
    assert k2.d0 == pytest.approx(k1.d0, rel=1e-12)
    assert k2.participating_mass == pytest.approx(k1.participating_mass, rel=1e-12)


# ------------------------------------------------------------------ a parapet on its wall
def test_parapet_on_its_wall_turns_about_the_walls_edge_or_its_own_corner():
    # parapet 0.3 × 0.8 m, 0.4 m deep, centred 0.25 m from the wall's axis on a wall
    # 0.6 × 1.2 m: it overhangs the wall's edge x = 0.3 and sits from x = 0.1 to 0.4
    geo = parapet(0.25)
    mass = 2000.0 * 0.3 * 0.8 * 0.4
    cx, cz = 0.25, 1.2 + 0.4
    for direction, pivot_x in ((1, 0.3), (-1, 0.1)):
        arm_x, arm_z = abs(pivot_x - cx), cz - 1.2
        k = analyse(geo, direction, friction=1.0)
        assert k.moving_blocks == (1,)
        assert k.load_factor == pytest.approx(arm_x / arm_z, rel=1e-9)
        assert k.mass_fraction == pytest.approx(1.0, rel=1e-12)
        assert k.participating_mass == pytest.approx(mass, rel=1e-12)
        assert k.d0 == pytest.approx(arm_x, rel=1e-9)
        lam = math.atan2(arm_x, arm_z)
        assert k.curve is not None
        assert k.curve.rotation0 == pytest.approx(lam, rel=1e-9)
        mid = len(k.curve.rotation) // 2
        assert k.curve.load_factor[mid] == pytest.approx(
            math.tan(lam - k.curve.rotation[mid]), rel=1e-9)


def test_monolithic_wall_and_parapet_participating_mass_by_hand():
    # parapet-offset0.00: wall and parapet turn together about the wall's base corner
    geo = parapet(0.0)
    m = np.array([2000.0 * 0.6 * 1.2 * 0.4, 2000.0 * 0.3 * 0.8 * 0.4])
    z = np.array([0.6, 1.6])  # heights of the centres of gravity above the pivot (0.3, 0)
    k = analyse(geo, 1, friction=1.0)
    assert k.moving_blocks == (0, 1)
    assert k.control_block == 1  # the higher centre of gravity
    np.testing.assert_allclose(k.delta_x, z / 1.6, rtol=1e-9)
    e_star = (m @ z) ** 2 / (m.sum() * (m @ z ** 2))
    assert k.mass_fraction == pytest.approx(e_star, rel=1e-9)
    assert k.participating_mass == pytest.approx((m @ z) ** 2 / (m @ z ** 2), rel=1e-9)
    z_g = (m @ z) / m.sum()
    assert k.load_factor == pytest.approx(0.3 / z_g, rel=1e-9)
    # α = 0 when the common centre of gravity is over the pivot; the parapet's centre
    # (−0.3, 1.6) from the pivot has then moved sideways by Δx, and d = Δx Σ m z²/(1.6 Σ m z)
    phi0 = math.atan2(0.3, z_g)
    dx = -0.3 * math.cos(phi0) + 1.6 * math.sin(phi0) + 0.3
    assert k.curve is not None
    assert k.curve.rotation0 == pytest.approx(phi0, rel=1e-9)
    assert k.d0 == pytest.approx(dx * (m @ z ** 2) / (1.6 * (m @ z)), rel=1e-9)


def test_column_of_drums_turns_as_one_body():
    geo = drum_column(5)
    z = 0.25 + 0.5 * np.arange(5)
    k = analyse(geo, -1)
    assert k.load_factor == pytest.approx(0.3 / 1.25, rel=1e-9)
    assert k.control_block == 4
    assert k.mass_fraction == pytest.approx(z.sum() ** 2 / (5 * (z ** 2).sum()), rel=1e-9)
    assert k.has_curve


# ------------------------------------------------------------------ no finite kinematics
def test_four_hinge_arch_has_linear_quantities_but_no_curve():
    geo = voussoir_arch(9, 0.2)
    k = analyse(geo, 1, friction=1.0)
    assert k.load_factor > 0 and 0 < k.mass_fraction <= 1
    assert math.isfinite(k.spectral_acceleration)
    assert k.curve is None and not k.has_curve
    assert "hinge" in k.no_curve_reason
    with pytest.raises(NoFiniteKinematics, match="no finite kinematics for this mechanism"):
        _ = k.d0
    with pytest.raises(NoFiniteKinematics):
        _ = k.period_slv


def test_sliding_block_has_no_curve():
    k = analyse(block(1.0, 3.0), 1, friction=0.1)  # b/h = 1/3 > μ: it slides
    assert k.governing_mode == "sliding"
    assert k.load_factor == pytest.approx(0.1, rel=1e-9)
    assert k.mass_fraction == pytest.approx(1.0, rel=1e-12)
    assert k.curve is None and "translates" in k.no_curve_reason


# ------------------------------------------------------------------ refusals
def test_no_collapse_is_refused():
    geo = block(0.3, 1.2)
    none = LimitResult("no_mechanism", math.inf, math.nan, 1, math.inf, (), (), None, ())
    with pytest.raises(ScenarioError, match="no mechanism"):
        kinematic_analysis(geo, none)
    unstable = LimitResult("unstable", math.nan, math.nan, 1, math.inf, (), (), None, ())
    with pytest.raises(ScenarioError, match="cannot stand"):
        kinematic_analysis(geo, unstable)


@pytest.mark.parametrize("kw", [{"confidence_factor": 0.9}, {"confidence_factor": math.nan},
                                {"g": 0.0}, {"samples": 1}])
def test_bad_arguments_are_refused(kw):
    geo = block(0.3, 1.2)
    with pytest.raises(ScenarioError):
        kinematic_analysis(geo, limit_analysis(geo), **kw)
