"""A cylinder rolling on its bottom rim without slipping: physics checks.

Every expected value here is computed independently of the module under test: the
kinematics from the test's own rotation matrices (ZYZ Euler angles), the energy and the
Newton–Euler balance from world-frame vectors, the planar case from Housner's solver
(:func:`rockbench.analytic.housner.solve_single`), the thin-disk limit from the classical
rolling-coin result. The module's outputs are only the trajectories being judged.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import pytest
from scipy.optimize import brentq

from rockbench.analytic.housner import SingleBlockSolution, solve_single
from rockbench.analytic.rolling_cylinder import (
    Cylinder,
    EventKind,
    RollingOutcome,
    RollingSolution,
    solve_rolling,
    steady_precession,
)
from rockbench.errors import ScenarioError
from rockbench.geometry.rocking import rocking_about


@dataclass(frozen=True)
class Motion:
    """Initial tilt, azimuth and rates."""

    theta0: float
    psi0: float
    theta_dot0: float
    psi_dot0: float
    phi_dot0: float


def roll(cyl: Cylinder, m: Motion, duration: float, **kw: Any) -> RollingSolution:
    return solve_rolling(cyl, m.theta0, m.psi0, m.theta_dot0, m.psi_dot0, m.phi_dot0,
                         duration, **kw)


G = 9.81
Z = np.array([0.0, 0.0, 1.0])
#: The issue's slender drum: R 0.3 m, H 1.5 m (α = atan(0.4) = 0.38 rad).
SLENDER = Cylinder(0.3, 1.5, density=2400.0)
#: A squat drum, α = atan(2.5) = 1.19 rad.
SQUAT = Cylinder(0.5, 0.4, mass=300.0)
#: A general 3D motion: tilt, tilt rate, precession and spin all non-zero (θ in 0.14–0.28).
WOBBLE = Motion(theta0=0.2, psi0=0.3, theta_dot0=0.3, psi_dot0=3.5, phi_dot0=-2.5)
#: A wilder one that nearly lands flat (θ down to 0.014 rad, ψ̇ up to 40 rad/s).
NEAR_LANDING = Motion(theta0=0.15, psi0=0.3, theta_dot0=0.5, psi_dot0=2.0, phi_dot0=3.0)


# ---------------------------------------------------------------- the test's own model
def rot(axis: str, a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    if axis == "y":
        return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def orientation(psi: float, theta: float, phi: float) -> np.ndarray:
    """Body → world rotation: ZYZ Euler angles (rockbench: θ about +y when ψ = φ = 0)."""
    return rot("z", psi) @ rot("y", theta) @ rot("z", phi)


def omega_world(psi: float, theta: float, phi: float, td: float, pd: float,
                fd: float) -> np.ndarray:
    """ψ̇ ẑ + θ̇ (Rz(ψ) ŷ) + φ̇ e₃."""
    return pd * Z + td * (rot("z", psi) @ [0, 1, 0]) + fd * (orientation(psi, theta, phi) @ Z)


def inertia_world(cyl: Cylinder, rmat: np.ndarray) -> np.ndarray:
    i_body = np.diag([cyl.i_transverse, cyl.i_transverse, cyl.i_axial])
    return rmat @ i_body @ rmat.T


def contact_offset(cyl: Cylinder, psi: float, theta: float) -> np.ndarray:
    """P − G in the world: the lowest rim point, found by scanning the rim itself."""
    rmat = orientation(psi, theta, 0.0)
    chi = np.linspace(-math.pi, math.pi, 4001)
    rim = rmat @ np.vstack([cyl.radius * np.cos(chi), cyl.radius * np.sin(chi),
                            np.full_like(chi, -cyl.h)])
    k = int(np.argmin(rim[2]))
    # refine the minimum on the circle analytically: the lowest point is where the rim's
    # tangent is horizontal, i.e. along the steepest descent of the rim's plane
    e3 = rmat @ Z
    down = -Z + e3 * e3[2]
    down /= np.linalg.norm(down)
    p = rmat @ [0, 0, -cyl.h] + cyl.radius * down
    assert np.linalg.norm(p - rim[:, k]) < 1e-3 * cyl.radius
    return p


def energy_of(cyl: Cylinder, sol: RollingSolution, i: int, g: float = G) -> float:
    """Energy at sample i from world vectors: ½ m |ω × (G − P)|² + ½ ω·Iω + m g z_G."""
    ps, th, ph = sol.psi[i], sol.theta[i], sol.phi[i]
    w = omega_world(ps, th, ph, sol.theta_dot[i], sol.psi_dot[i], sol.phi_dot[i])
    v = np.cross(w, -contact_offset(cyl, ps, th))
    z_g = -contact_offset(cyl, ps, th)[2]
    return float(0.5 * cyl.m * v @ v + 0.5 * w @ inertia_world(
        cyl, orientation(ps, th, ph)) @ w + cyl.m * g * z_g)


def triples(centres: np.ndarray, delta: float) -> np.ndarray:
    return np.sort(np.concatenate([centres - delta, centres, centres + delta]))


# ---------------------------------------------------------------- energy, constraint, laws
@pytest.mark.parametrize("motion", [WOBBLE, NEAR_LANDING], ids=["wobble", "near-landing"])
def test_energy_is_conserved_on_a_fixed_base(motion: Motion) -> None:
    sol = roll(SLENDER, motion, 4.0, output_rate=50.0)
    assert sol.outcome is RollingOutcome.OK, sol.message
    e = np.array([energy_of(SLENDER, sol, i) for i in range(sol.t.size)])
    drift = np.max(np.abs(e - e[0])) / abs(e[0])
    assert drift < 1e-8, drift
    # the module's own energy column is the same quantity
    np.testing.assert_allclose(sol.energy, e, rtol=1e-10)
    # and the motion is genuinely 3D: the azimuth turns, the tilt varies
    assert np.ptp(sol.psi) > 1.0 and np.ptp(sol.theta) > 0.02


def test_the_contact_material_point_is_at_rest_and_the_path_rolls_off_the_rim() -> None:
    centres = np.linspace(0.1, 2.9, 15)
    delta = 1e-4
    sol = roll(SLENDER, WOBBLE, 3.0, t_eval=triples(centres, delta))
    assert sol.outcome is RollingOutcome.OK
    speeds = []
    for k in range(centres.size):
        i = 3 * k + 1
        frames = {j: (orientation(sol.psi[j], sol.theta[j], sol.phi[j]), sol.com[j])
                  for j in (i - 1, i, i + 1)}
        r_i, g_i = frames[i]
        p_world = g_i + contact_offset(SLENDER, sol.psi[i], sol.theta[i])
        body = r_i.T @ (p_world - g_i)            # the material point touching now
        assert abs(p_world[2]) < 1e-12 and abs(body[2] + SLENDER.h) < 1e-12
        pos = {j: frames[j][1] + frames[j][0] @ body for j in (i - 1, i + 1)}
        v = (pos[i + 1] - pos[i - 1]) / (2 * delta)
        w = omega_world(sol.psi[i], sol.theta[i], sol.phi[i], sol.theta_dot[i],
                        sol.psi_dot[i], sol.phi_dot[i])
        speeds.append(np.linalg.norm(v) / (np.linalg.norm(w) * SLENDER.r))
    assert max(speeds) < 1e-7, max(speeds)
    # the contact point's path on the ground is as long as the arc rolled off the rim
    fine = roll(SLENDER, WOBBLE, 3.0, output_rate=4000.0)
    path = np.sum(np.hypot(np.diff(fine.contact_x), np.diff(fine.contact_y)))
    rim = SLENDER.radius * np.trapezoid(np.abs(fine.phi_dot), fine.t)
    assert path == pytest.approx(rim, rel=1e-6)


def test_the_trajectory_obeys_newton_euler_with_the_force_at_the_contact() -> None:
    """m a_G = F − m g ẑ and dH_G/dt = (P − G) × F, by finite differences of the output."""
    centres = np.linspace(0.2, 2.8, 9)
    delta = 1e-3
    sol = roll(SLENDER, WOBBLE, 3.0, t_eval=triples(centres, delta))
    assert sol.outcome is RollingOutcome.OK
    m = SLENDER.m
    for k in range(centres.size):
        i = 3 * k + 1

        def h_g(j: int) -> np.ndarray:
            w = omega_world(sol.psi[j], sol.theta[j], sol.phi[j], sol.theta_dot[j],
                            sol.psi_dot[j], sol.phi_dot[j])
            return inertia_world(SLENDER, orientation(sol.psi[j], sol.theta[j], sol.phi[j])) @ w

        a_g = (sol.com[i + 1] - 2 * sol.com[i] + sol.com[i - 1]) / delta ** 2
        force = m * a_g + m * G * Z
        dh = (h_g(i + 1) - h_g(i - 1)) / (2 * delta)
        torque = np.cross(contact_offset(SLENDER, sol.psi[i], sol.theta[i]), force)
        scale = m * G * SLENDER.r
        assert np.linalg.norm(dh - torque) < 1e-5 * scale, (k, dh, torque)
        # the normal force reported is the vertical component of F
        assert sol.normal_force[i] == pytest.approx(force[2], rel=1e-5)


def test_a_constant_base_acceleration_is_a_tilted_gravity() -> None:
    """In the base frame a constant acceleration a adds the potential m a·x_G: conserved."""
    a = (0.1, 0.05)
    sol = roll(SLENDER, WOBBLE, 2.0, output_rate=50.0, base_acceleration=lambda t: a)
    assert sol.outcome is RollingOutcome.OK, sol.message
    e = np.array([energy_of(SLENDER, sol, i) for i in range(sol.t.size)])
    e += SLENDER.m * (a[0] * sol.com[:, 0] + a[1] * sol.com[:, 1])
    drift = np.max(np.abs(e - e[0])) / abs(e[0])
    assert drift < 1e-8, drift
    assert np.max(np.abs(sol.energy - sol.energy[0])) / abs(e[0]) > 1e-3  # it does work


# ---------------------------------------------------------------- steady precession
def steady_residual(cyl: Cylinder, theta: float, psi_dot: float, phi_dot: float) -> float:
    """Newton–Euler in the world for a motion that turns rigidly about ẑ at rate Ω.

    v_G = ω × (G − P); every vector turns at Ω so a_G = Ω ẑ × v_G and
    dH_G/dt = Ω ẑ × H_G; the contact force F = m (a_G + g ẑ) must give the torque.
    """
    rmat = orientation(0.0, theta, 0.0)
    w = psi_dot * Z + phi_dot * (rmat @ Z)
    gp = contact_offset(cyl, 0.0, theta)
    v = np.cross(w, -gp)
    force = cyl.m * (psi_dot * np.cross(Z, v) + G * Z)
    lhs = psi_dot * np.cross(Z, inertia_world(cyl, rmat) @ w)
    return float(np.linalg.norm(lhs - np.cross(gp, force)) / (cyl.m * G * cyl.r))


@pytest.mark.parametrize("cyl,theta,rho", [
    (SLENDER, 0.2, 0.3), (SLENDER, 0.1, 1.0), (SLENDER, 0.3, 0.6), (SLENDER, 0.5, -0.5),
    (SQUAT, 0.4, 0.5), (SQUAT, 1.0, 2.0),
])
def test_steady_precession_is_a_solution_of_newton_euler(cyl: Cylinder, theta: float,
                                                         rho: float) -> None:
    sp = steady_precession(cyl, theta, contact_radius=rho)
    assert steady_residual(cyl, theta, sp.psi_dot, sp.phi_dot) < 1e-12
    assert sp.contact_radius == pytest.approx(rho, rel=1e-12)
    # the other parametrisation of the family gives the same member
    sp2 = steady_precession(cyl, theta, psi_dot=sp.psi_dot)
    assert sp2.phi_dot == pytest.approx(sp.phi_dot, rel=1e-10)
    # and a member chosen by Ω alone is a solution too
    sp3 = steady_precession(cyl, theta, psi_dot=1.7 * sp.psi_dot)
    assert steady_residual(cyl, theta, sp3.psi_dot, sp3.phi_dot) < 1e-12


@pytest.mark.parametrize("cyl,theta,rho", [(SLENDER, 0.2, 0.3), (SQUAT, 0.4, 0.5)])
def test_started_on_the_steady_precession_it_stays_there(cyl: Cylinder, theta: float,
                                                          rho: float) -> None:
    sp = steady_precession(cyl, theta, contact_radius=rho)
    turns = 10.0
    duration = turns * 2 * math.pi / sp.psi_dot
    sol = solve_rolling(cyl, theta, 0.0, 0.0, sp.psi_dot, sp.phi_dot, duration,
                        output_rate=200.0)
    assert sol.outcome is RollingOutcome.OK
    assert np.max(np.abs(sol.theta - theta)) < 1e-8
    assert np.max(np.abs(sol.psi_dot - sp.psi_dot)) < 1e-8 * abs(sp.psi_dot)
    assert sol.psi[-1] == pytest.approx(turns * 2 * math.pi, rel=1e-9)
    # the contact point runs on a circle of radius |ρ| centred at P(0) − ρ u(0)
    centre = np.array([-rho, 0.0])
    dist = np.hypot(sol.contact_x - centre[0], sol.contact_y - centre[1])
    assert np.max(np.abs(dist - abs(rho))) < 1e-8
    # the centre of mass on a horizontal circle about the same vertical axis
    dist_g = np.hypot(sol.com[:, 0] - centre[0], sol.com[:, 1] - centre[1])
    assert np.max(np.abs(dist_g - sp.com_radius)) < 1e-8
    assert np.ptp(sol.com[:, 2]) < 1e-8


def test_small_perturbations_of_a_fast_steady_roll_stay_small() -> None:
    sp = steady_precession(SLENDER, 0.2, contact_radius=0.3)
    sol = solve_rolling(SLENDER, 0.2 + 1e-4, 0.0, 0.0, sp.psi_dot, sp.phi_dot, 5.0,
                        output_rate=100.0)
    assert sol.outcome is RollingOutcome.OK
    assert np.max(np.abs(sol.theta - 0.2)) < 1e-2


def test_thin_disk_limit_is_the_rolling_coin() -> None:
    """A coin on edge rolling on a wide circle: tan β → 3 v² / (2 g ρ) (Routh; Goldstein)."""
    coin = Cylinder(0.05, 1e-9, mass=0.01)        # thin: h sin θ ≪ R cos θ at this lean
    beta = 0.05                                     # lean of the coin's plane from vertical
    theta = 0.5 * math.pi - beta                    # tilt of its axis
    for rho in (5.0, 20.0, 50.0):                   # ρ/R = 100, 400, 1000
        sp = steady_precession(coin, theta, contact_radius=rho)
        v = coin.radius * abs(sp.phi_dot)
        ratio = math.tan(beta) / (1.5 * v * v / (G * rho))
        # the limit holds up to terms of order R sin β / ρ (contact vs centre circle, ...)
        assert ratio == pytest.approx(1.0, abs=2 * coin.radius * math.sin(beta) / rho)


# ---------------------------------------------------------------- reduction to planar rocking
def housner(cyl: Cylinder, t: np.ndarray, theta0: float, omega0: float,
            accel: Callable[[Any], Any] | None = None) -> SingleBlockSolution:
    rock = rocking_about(cyl.m, cyl.radius, cyl.h, cyl.i_transverse, G)
    assert rock.I_O == pytest.approx(cyl.i_transverse + cyl.m * (cyl.radius ** 2 + cyl.h ** 2))
    if accel is None:
        return solve_single(rock, g=G, accel=np.zeros_like, theta0=theta0, omega0=omega0,
                            t_out=t, free_closed_form=False)
    return solve_single(rock, g=G, accel=accel, theta0=theta0, omega0=omega0, t_out=t,
                        breakpoints=[0.5], end_time=0.5)


@pytest.mark.parametrize("psi0", [0.0, 0.7, -2.5])
def test_free_planar_rocking_is_housner(psi0: float) -> None:
    theta0, omega0 = 0.25, 0.25
    sol = solve_rolling(SLENDER, theta0, psi0, omega0, 0.0, 0.0, 2.0, output_rate=500.0)
    assert sol.outcome is RollingOutcome.LANDED
    ref = housner(SLENDER, np.append(sol.t, sol.t[-1] + 0.5), theta0, omega0)
    landing = sol.first(EventKind.LANDING)
    assert landing is not None
    assert landing.t == pytest.approx(ref.impacts[0], abs=1e-8)
    assert np.max(np.abs(sol.theta - ref.theta[:-1])) < 1e-8
    assert np.all(sol.psi == psi0) and np.all(sol.phi == 0.0)
    assert np.max(np.abs(sol.psi_dot)) == 0.0 and np.max(np.abs(sol.phi_dot)) == 0.0
    # the contact point stays put: rocking about a fixed rim point
    assert np.max(np.hypot(sol.contact_x, sol.contact_y)) < 1e-9
    # landing speed from energy: ½ I₀ θ̇² = m g r [cos(α − θ_max) − cos α] ...
    e0 = 0.5 * SLENDER.i_pivot * omega0 ** 2 + SLENDER.m * G * SLENDER.r * math.cos(
        SLENDER.alpha - theta0)
    speed = math.sqrt(2 * (e0 - SLENDER.m * G * SLENDER.r * math.cos(SLENDER.alpha))
                      / SLENDER.i_pivot)
    assert landing.state.theta_dot == pytest.approx(-speed, rel=1e-9)


def test_forced_planar_rocking_is_housner() -> None:
    """A sine pulse along x, tilted in the x–z plane: Housner's forced equation."""
    amp, f = 8.0, 2.0

    def ax(t: Any) -> Any:
        return np.where(np.asarray(t) < 0.5, -amp * np.sin(2 * math.pi * f * np.asarray(t)), 0.0)

    theta0 = 0.05
    sol = solve_rolling(SLENDER, theta0, 0.0, 0.0, 0.0, 0.0, 3.0, output_rate=500.0,
                        base_acceleration=lambda t: (float(ax(t)), 0.0),
                        breakpoints=[0.5])
    ref = housner(SLENDER, sol.t, theta0, 0.0, ax)
    assert np.max(np.abs(sol.theta - ref.theta)) < 1e-8
    assert np.max(np.abs(sol.theta)) > 2 * theta0     # the pulse did rock it
    assert np.all(sol.psi == 0.0) and np.all(sol.phi == 0.0)
    # the same pulse along y acting on a cylinder leaning toward +y
    sol_y = solve_rolling(SLENDER, theta0, 0.5 * math.pi, 0.0, 0.0, 0.0, 3.0,
                          output_rate=500.0, breakpoints=[0.5],
                          base_acceleration=lambda t: (0.0, float(ax(t))))
    np.testing.assert_allclose(sol_y.theta, sol.theta, atol=1e-9)


# ---------------------------------------------------------------- symmetry
def test_turning_everything_by_half_a_turn_turns_the_motion() -> None:
    a = (0.6, 0.3)
    one = roll(SLENDER, WOBBLE, 2.0, output_rate=100.0, base_acceleration=lambda t: a)
    turned = replace(WOBBLE, psi0=WOBBLE.psi0 + math.pi)
    two = roll(SLENDER, turned, 2.0, output_rate=100.0,
               base_acceleration=lambda t: (-a[0], -a[1]))
    np.testing.assert_allclose(two.theta, one.theta, atol=1e-9)
    np.testing.assert_allclose(two.psi, one.psi + math.pi, atol=1e-9)
    np.testing.assert_allclose(two.contact_x, -one.contact_x, atol=1e-9)
    np.testing.assert_allclose(two.contact_y, -one.contact_y, atol=1e-9)


def test_mirror_image_in_the_x_z_plane() -> None:
    one = roll(SLENDER, WOBBLE, 2.0, output_rate=100.0)
    mirror = replace(WOBBLE, psi0=-WOBBLE.psi0, psi_dot0=-WOBBLE.psi_dot0,
                     phi_dot0=-WOBBLE.phi_dot0)
    two = roll(SLENDER, mirror, 2.0, output_rate=100.0)
    np.testing.assert_allclose(two.theta, one.theta, atol=1e-9)
    np.testing.assert_allclose(two.psi, -one.psi, atol=1e-9)
    np.testing.assert_allclose(two.contact_y, -one.contact_y, atol=1e-9)
    np.testing.assert_allclose(two.contact_x, one.contact_x, atol=1e-9)


# ---------------------------------------------------------------- events
def test_overturning_and_the_balance_crossing_match_housner() -> None:
    theta0, omega0, tip = 0.3, 0.5, 1.2
    sol = solve_rolling(SLENDER, theta0, 0.0, omega0, 0.0, 0.0, 3.0, output_rate=500.0,
                        overturn_angle=tip)
    assert sol.outcome is RollingOutcome.OVERTURNED, sol.message
    ref = housner(SLENDER, sol.t, theta0, omega0)
    assert np.max(np.abs(sol.theta - ref.theta)) < 1e-8
    bal, over = sol.first(EventKind.BALANCE), sol.first(EventKind.OVERTURN)
    assert bal is not None and over is not None
    assert bal.state.theta == pytest.approx(SLENDER.alpha, abs=1e-12)
    assert over.state.theta == pytest.approx(tip, abs=1e-12)
    # at the balance crossing the centre of mass is right above the contact point
    t_fine = np.array([0.0, bal.t])
    at = solve_rolling(SLENDER, theta0, 0.0, omega0, 0.0, 0.0, 3.0, t_eval=t_fine)
    assert np.hypot(at.com[1, 0] - at.contact_x[1], at.com[1, 1] - at.contact_y[1]) < 1e-12


def test_the_rim_lifts_off_while_falling_over() -> None:
    """Housner's overturning ignores it: N = m (g + z̈_G) vanishes before θ = π/2."""
    theta0, omega0 = 0.3, 0.5
    sol = solve_rolling(SLENDER, theta0, 0.0, omega0, 0.0, 0.0, 3.0, output_rate=500.0)
    assert sol.outcome is RollingOutcome.FLIGHT
    flight = sol.first(EventKind.FLIGHT)
    assert flight is not None
    # planar: z_G = r cos(α − θ), θ̈ = −p² sin(α − θ), θ̇² from energy
    r, al = SLENDER.r, SLENDER.alpha
    p2 = SLENDER.m * G * r / SLENDER.i_pivot

    def n_over_m(th: float) -> float:
        w2 = omega0 ** 2 + 2 * p2 * (math.cos(al - theta0) - math.cos(al - th))
        return G + r * (-p2 * math.sin(al - th) ** 2 - math.cos(al - th) * w2)

    th_lift = brentq(n_over_m, al, 0.5 * math.pi)
    assert flight.state.theta == pytest.approx(th_lift, abs=1e-9)
    assert np.all(sol.normal_force[sol.t < flight.t] > 0)


def test_a_precessing_landing_is_turned_back_unless_a_landing_angle_stops_it() -> None:
    """Near upright a precession acts as a barrier (as in a spherical pendulum): ψ̇ grows
    like 1/sin²θ and the rim model turns back at a tiny tilt instead of landing."""
    sol = solve_rolling(SLENDER, 0.1, 0.0, -0.5, 1e-3, 0.0, 1.0, output_rate=200.0)
    assert sol.outcome is RollingOutcome.OK and sol.first(EventKind.LANDING) is None
    assert sol.theta[-1] > 0.05                     # back up: no landing without an angle
    stop = solve_rolling(SLENDER, 0.1, 0.0, -0.5, 1e-3, 0.0, 1.0, landing_angle=1e-3)
    landing = stop.first(EventKind.LANDING)
    assert stop.outcome is RollingOutcome.LANDED and landing is not None
    assert landing.state.theta == pytest.approx(1e-3, abs=1e-12)
    # the planar landing (ψ̇ = 0) reaches θ = 0 at the time energy gives (Housner's)
    flat = solve_rolling(SLENDER, 0.1, 0.0, -0.5, 0.0, 0.0, 1.0)
    ref = housner(SLENDER, np.array([0.0, 1.0]), 0.1, -0.5)
    assert flat.outcome is RollingOutcome.LANDED
    assert flat.end_time == pytest.approx(ref.impacts[0], abs=1e-9)


def test_it_leaves_the_ground_when_the_base_falls_faster_than_gravity() -> None:
    sol = solve_rolling(SLENDER, 0.1, duration=1.0, breakpoints=[0.2],
                        base_acceleration=lambda t: (0.0, 0.0, -1.2 * G if t >= 0.2 else 0.0))
    assert sol.outcome is RollingOutcome.FLIGHT
    assert 0.2 <= sol.end_time < 0.2 + 1e-9
    assert np.all(sol.normal_force[sol.t < 0.2] > 0) and sol.t[-1] <= 0.2
    at_once = solve_rolling(SLENDER, 0.1, duration=1.0,
                            base_acceleration=lambda t: (0.0, 0.0, -1.2 * G))
    assert at_once.outcome is RollingOutcome.FLIGHT and at_once.end_time == 0.0


def test_it_slips_where_friction_falls_short() -> None:
    sp = steady_precession(SLENDER, 0.2, contact_radius=0.3)
    # the friction needed: m Ω² times G's distance from the axis, over m g
    gp = contact_offset(SLENDER, 0.0, 0.2)
    d_axis = abs(0.3 - gp[0])           # G at P − gp, the axis at P − ρ u: G − axis = ρ u − gp
    demand = sp.psi_dot ** 2 * d_axis / G
    assert sp.friction_demand == pytest.approx(demand, rel=1e-9)
    args = (SLENDER, 0.2, 0.0, 0.0, sp.psi_dot, sp.phi_dot, 2.0)
    assert solve_rolling(*args, friction=0.9 * demand).outcome is RollingOutcome.SLIPPED
    ok = solve_rolling(*args, friction=1.1 * demand, output_rate=100.0)
    assert ok.outcome is RollingOutcome.OK
    np.testing.assert_allclose(ok.friction_demand, demand, rtol=1e-7)


# ---------------------------------------------------------------- bad input
@pytest.mark.parametrize("make", [
    lambda: Cylinder(-0.3, 1.5, density=2400.0),
    lambda: Cylinder(0.3, 1.5),
    lambda: Cylinder(0.3, 1.5, density=2400.0, mass=1.0),
    lambda: solve_rolling(SLENDER, 0.0),
    lambda: solve_rolling(SLENDER, 1.6),
    lambda: solve_rolling(SLENDER, 0.1, duration=-1.0),
    lambda: solve_rolling(SLENDER, 0.1, t_eval=[0.0, 2.0, 1.0]),
    lambda: solve_rolling(SLENDER, 0.1, landing_angle=0.2),
    lambda: solve_rolling(SLENDER, 0.1, overturn_angle=0.05),
    lambda: solve_rolling(SLENDER, 0.1, contact0=(0.0,)),  # type: ignore[arg-type]
    lambda: solve_rolling(SLENDER, 0.1, psi_dot0=math.nan),
    lambda: steady_precession(SLENDER, 0.2, contact_radius=0.0),   # centrifugal and gravity agree
    lambda: steady_precession(SLENDER, 0.2),
    lambda: steady_precession(SLENDER, 0.2, psi_dot=0.0),
])
def test_bad_input_is_a_scenario_error(make: Callable[[], object]) -> None:
    with pytest.raises(ScenarioError):
        make()
