"""Housner single-block solver: physics checks against §6 of two-block-model.md.

Reference numbers (T2, T3, T12, T13) come from the specification, computed there
independently; the other tests check laws the solution must obey (energy between
impacts, the uplift threshold, mirror symmetry, geometry of the centroid).
Most free-rocking checks run twice: with the closed-form free phases (default) and
with the ODE integrated through every half-cycle (``free_closed_form=False``).
"""

from __future__ import annotations

import math
import re
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest
from scipy.optimize import brentq

from rockbench.analytic.closed_forms import (
    amplitude_after_impacts,
    free_impact_times,
    impact_velocity,
    quarter_period,
    sine_pulse_linear_response,
)
from rockbench.analytic.housner import scalar_acceleration, single_block_reference, solve_single
from rockbench.errors import UnsupportedScenario
from rockbench.scenarios import (
    AxialExcitation,
    Block,
    Components,
    Contact,
    Free,
    Record,
    Scenario,
    SinePulse,
    Sinusoid,
    stack,
)
from rockbench.trajectory import Status, Trajectory

G = 9.81
B0 = Block(1.0, 0.2, 5.0, mass=1.0)  # the 1 m x 5 m block of T1-T3, T12, T13
SINGLE2 = Block(0.17, 0.502, 1.0, density=2670.0)
T3 = np.array([
    [0.7761248546, -0.273096156019, 0.083339113164],
    [2.1263229608, +0.257340608556, 0.071253454725],
    [3.3271341884, -0.242494034986, 0.061415146055],
    [4.4096877965, +0.228503994506, 0.053237762768],
    [5.3946268903, -0.215321071746, 0.046344891970],
])
BOTH = pytest.mark.parametrize("closed", [True, False], ids=["closed-form", "ode"])


@pytest.fixture(scope="module")
def rock():
    return B0.rocking(G)


def free(rock, t_out, *, theta0=None, eta=None, closed=True, linear=False, omega0=0.0):
    return solve_single(rock, g=G, accel=Free().acceleration, end_time=0.0,
                        theta0=0.5 * rock.lam if theta0 is None else theta0, omega0=omega0,
                        t_out=t_out, eta=eta, linear=linear, free_closed_form=closed)


def pulse(a, t1):
    """Rectangular acceleration pulse a on [0, t1]."""
    return lambda t: np.where((np.asarray(t) >= 0) & (np.asarray(t) <= t1), a, 0.0)


def sine(a, w):
    t_end = 2 * math.pi / w
    return (lambda t: np.where((np.asarray(t) >= 0) & (np.asarray(t) <= t_end),
                               a * np.sin(w * np.asarray(t)), 0.0)), t_end


def energy(rock, th, om, *, linear=False):
    """Mechanical energy per unit I_O, (½θ̇² + p² cos(sλ − θ)) for the pivot on side sgn θ."""
    s = np.sign(th)
    if linear:
        return 0.5 * om**2 - 0.5 * rock.p**2 * (s * rock.lam - th) ** 2
    return 0.5 * om**2 + rock.p**2 * np.cos(s * rock.lam - th)


# ---------------------------------------------------------------- free rocking


@BOTH
@pytest.mark.parametrize("linear", [False, True], ids=["exact", "linear"])
def test_t2_lossless_impacts_at_quarter_and_half_periods(rock, closed, linear):
    sol = free(rock, np.linspace(0, 20, 201), eta=1.0, closed=closed, linear=linear)
    period = 3.100952300750 if linear else 3.104499418457
    k = np.arange(sol.impacts.size)
    assert sol.impacts.size == 13 and sol.status == "ok" and sol.rest_time is None
    np.testing.assert_allclose(sol.impacts, period / 4 + k * period / 2, rtol=0, atol=1e-8)
    # the amplitude never decays
    np.testing.assert_allclose(np.abs(sol.impact_rates),
                               impact_velocity(rock.p, rock.lam, 0.5 * rock.lam, linear=linear),
                               rtol=1e-8)


@BOTH
def test_t3_impacts_rates_and_amplitudes(rock, closed):
    times = free_impact_times(rock.p, rock.lam, 0.5 * rock.lam, rock.eta, 40)
    # sample at every apex: midway between impacts in free motion (symmetric swings)
    apexes = 0.5 * (times[:-1] + times[1:])
    sol = free(rock, np.concatenate([[0.0], apexes]), closed=closed)
    np.testing.assert_allclose(sol.impacts[:5], T3[:, 0], rtol=1e-9)
    np.testing.assert_allclose(sol.impact_rates[:5], T3[:, 1], rtol=1e-8)
    # the swing after each impact goes the way of the post-impact rate
    np.testing.assert_allclose(sol.theta[1:6], np.sign(T3[:, 1]) * T3[:, 2], rtol=1e-8)
    # 39 later swings against the exact amplitude decay law
    amps = amplitude_after_impacts(rock.lam, 0.5 * rock.lam, rock.eta, np.arange(1, 40))
    signs = np.where(np.arange(1, 40) % 2 == 1, -1.0, 1.0)  # first swing after impact 1 is < 0
    np.testing.assert_allclose(sol.theta[1:], signs * amps, rtol=1e-8)
    np.testing.assert_allclose(sol.theta_dot[1:], 0.0, atol=1e-8)
    np.testing.assert_allclose(sol.impacts, times[:-1], rtol=1e-9)


def test_closed_form_and_ode_free_phases_agree(rock):
    t = np.linspace(0, 20, 20001)
    a = free(rock, t, closed=True)
    b = free(rock, t, closed=False)
    assert np.max(np.abs(a.theta - b.theta)) < 1e-8 * rock.lam
    assert np.max(np.abs(a.theta_dot - b.theta_dot)) < 1e-7 * rock.p * rock.lam
    np.testing.assert_allclose(a.impacts, b.impacts, atol=1e-8)


@BOTH
def test_energy_conserved_between_impacts_and_lost_at_impacts(rock, closed):
    t = np.linspace(0, 8, 8001)
    sol = free(rock, t, closed=closed)
    e = energy(rock, sol.theta, sol.theta_dot)
    seg = np.searchsorted(sol.impacts, t)  # half-cycle index of each sample
    interior = np.ones(t.size, bool)
    for ti in sol.impacts:  # drop samples within 1 µs of an impact
        interior &= np.abs(t - ti) > 1e-6
    e_floor = rock.p**2 * math.cos(rock.lam)  # energy of the block standing on θ = 0
    excess = []
    for k in range(seg.max() + 1):
        ek = e[(seg == k) & interior]
        assert np.ptp(ek) < 1e-10 * rock.p**2
        excess.append(ek.mean() - e_floor)
    # each impact keeps eta² of the kinetic energy at θ = 0
    np.testing.assert_allclose(np.array(excess[1:]) / np.array(excess[:-1]), rock.eta**2,
                               rtol=1e-7)


@BOTH
def test_b0_comes_to_rest_just_before_the_zeno_limit(rock, closed):
    """The impacts accumulate at t∞ = T(θ0)/4 + Σ T(θ_k)/2 (a finite sum of infinitely
    many half-cycles). The arrest rule stops the sequence once |θ̇⁺| < 1e-3 p λ, which
    drops a geometric tail of about 2e-3/p · η/(1 − η) ≈ 19 ms, so the block is at rest
    slightly before t∞ ≈ 19.35 s (engine-notes.md: "comes to rest near 19.35 s")."""
    amps = amplitude_after_impacts(rock.lam, 0.5 * rock.lam, rock.eta, np.arange(0, 400))
    amps = amps[amps > 0]
    q = quarter_period(rock.p, rock.lam, amps)
    t_inf = q[0] + 2 * np.sum(q[1:])
    assert t_inf == pytest.approx(19.35, abs=0.01)
    t = np.linspace(0, 20, 20001)
    sol = free(rock, t, closed=closed)
    assert sol.status == "ok"
    assert t_inf - 0.03 < sol.rest_time < t_inf
    assert sol.impacts[-1] == pytest.approx(sol.rest_time, abs=1e-12)
    after = t >= sol.rest_time
    assert np.all(sol.theta[after] == 0) and np.all(sol.theta_dot[after] == 0)
    # just before the arrest the swings are tiny: amplitude ~ 5e-7 λ (§5.5)
    before = (t > sol.rest_time - 0.05) & ~after
    assert np.max(np.abs(sol.theta[before])) < 1e-3 * rock.lam


def test_release_from_upright_with_speed_reaches_the_energy_amplitude(rock):
    """A start on θ = 0 with a (small) velocity: the excursion must not be lost to the
    event-at-t0 trap, and its duration is twice the quarter period of the amplitude."""
    for frac in (0.3, 0.01, 3e-6):
        amp = frac * rock.lam
        w0 = impact_velocity(rock.p, rock.lam, amp)
        for closed in (True, False):
            sol = free(rock, np.array([0.0, 2.0]), theta0=0.0, omega0=-w0, eta=1.0,
                       closed=closed)
            assert sol.impacts[0] == pytest.approx(2 * quarter_period(rock.p, rock.lam, amp),
                                                   rel=1e-6)
            # it swings out to θ < 0, comes back at the same speed and crosses to θ > 0 (η = 1)
            assert sol.impact_rates[0] == pytest.approx(w0, rel=1e-6)


def test_linear_option_reproduces_housner_decay(rock):
    times = free_impact_times(rock.p, rock.lam, 0.5 * rock.lam, rock.eta, 10, linear=True)
    apexes = 0.5 * (times[:-1] + times[1:])
    for closed in (True, False):
        sol = free(rock, apexes, closed=closed, linear=True)
        np.testing.assert_allclose(sol.impacts, times[:-1], rtol=1e-9)
        amps = amplitude_after_impacts(rock.lam, 0.5 * rock.lam, rock.eta, np.arange(1, 10),
                                       linear=True)
        np.testing.assert_allclose(np.abs(sol.theta), amps, rtol=1e-8)


# ---------------------------------------------------------------- forced rocking


@pytest.mark.parametrize(("linear", "a_min", "margin"),
                         [(False, 3.4300270873, 5e-4), (True, 3.3834864782, 1e-3)],
                         ids=["exact", "linear"])
def test_t12_rectangular_pulse_boundary(rock, linear, a_min, margin):
    t_out = np.linspace(0, 10, 101)
    runs = {f: solve_single(rock, g=G, accel=pulse(f * a_min, 0.5), breakpoints=(0.5,),
                            end_time=0.5, t_out=t_out, linear=linear)
            for f in (1 + margin, 1 - margin)}
    over, safe = runs[1 + margin], runs[1 - margin]
    assert over.status == "overturned" and over.impacts.size == 0  # no impact before
    assert over.theta[-1] < -0.5 and over.t[-1] <= over.overturn_time
    assert safe.status == "ok" and safe.impacts.size > 0
    assert np.max(np.abs(safe.theta)) < math.pi / 2
    # a positive pulse tips the block to θ < 0 from t = 0
    assert over.uplift_times.tolist() == [0.0] and np.all(over.theta[1:] <= 0)


@pytest.mark.parametrize(("ratio", "a_min"), [(2.0, 1.219869), (4.0, 1.725529)])
def test_t13_sine_pulse_minimum_overturning(rock, ratio, a_min):
    """Nonlinear minimum a_p/(g tan λ); the block overturns after one impact (mode 2)."""
    t_out = np.linspace(0, 12, 121)
    res = {}
    for f in (1.001, 0.999):
        acc, t_end = sine(f * a_min * G * math.tan(rock.lam), ratio * rock.p)
        res[f] = solve_single(rock, g=G, accel=acc, breakpoints=(t_end,), end_time=t_end,
                              t_out=t_out)
    assert res[1.001].status == "overturned"
    assert res[1.001].impacts.size == 1 and res[1.001].impacts[0] < res[1.001].overturn_time
    assert res[0.999].status == "ok"


@pytest.mark.parametrize(("ratio", "boundary"), [(2.0, 2.34990313), (4.0, 5.23896436)])
def test_t13_linear_mode1(rock, ratio, boundary):
    """Linearised model: just above the mode-1 boundary the block overturns without any
    impact; just below it, it comes back to θ = 0 first. Before that the solver follows
    the closed-form response."""
    w = ratio * rock.p
    t_out = np.linspace(0, 12, 1201)
    for f, overturns in ((1.001, True), (0.999, False)):
        a_p = f * boundary * G * rock.lam
        acc, t_end = sine(a_p, w)
        sol = solve_single(rock, g=G, accel=acc, breakpoints=(t_end,), end_time=t_end,
                           t_out=t_out, linear=True)
        first = sol.impacts[0] if sol.impacts.size else math.inf
        assert (sol.status == "overturned" and first > sol.overturn_time) == overturns
        if not overturns:
            assert first < math.inf
        ts = math.asin(G * rock.lam / a_p) / w
        assert sol.uplift_times[0] == pytest.approx(ts, abs=1e-12)
        m = (sol.t <= min(t_end, first)) & (sol.t < (sol.overturn_time or math.inf))
        th, om = sine_pulse_linear_response(rock.p, rock.lam, a_p, w, G, sol.t[m])
        np.testing.assert_allclose(sol.theta[m], th, atol=1e-9 * rock.lam)
        np.testing.assert_allclose(sol.theta_dot[m], om, atol=1e-8 * rock.p * rock.lam)


def test_uplift_time_and_direction():
    rock = SINGLE2.rocking(G)
    exc = SinePulse(5.0, 0.006)
    sol = solve_single(rock, g=G, accel=exc.acceleration, breakpoints=exc.breakpoints,
                       end_time=exc.end_time, t_out=np.linspace(0, 1, 1001))
    a_p = exc.peak_acceleration()
    assert sol.uplift_times[0] == pytest.approx(
        math.asin(G * math.tan(rock.lam) / a_p) / exc.omega, abs=1e-12)
    # positive base acceleration: the block first rotates to θ < 0
    assert np.all(sol.theta[sol.t <= sol.impacts[0]] <= 0)
    assert np.min(sol.theta) < -0.01 * rock.lam


@pytest.mark.parametrize("linear", [False, True])
def test_sub_threshold_motion_leaves_the_block_at_rest(linear):
    rock = SINGLE2.rocking(G)
    thr = G * (rock.lam if linear else math.tan(rock.lam))
    for sign in (1, -1):
        f = 5.0
        amp = sign * 0.99 * thr / (2 * math.pi * f) ** 2
        exc = SinePulse(f, amp)
        sol = solve_single(rock, g=G, accel=exc.acceleration, breakpoints=exc.breakpoints,
                           end_time=exc.end_time, t_out=np.linspace(0, 1, 1001), linear=linear)
        assert sol.status == "ok" and sol.rest_time == 0.0
        assert sol.uplift_times.size == 0 and sol.impacts.size == 0
        assert np.all(sol.theta == 0) and np.all(sol.theta_dot == 0)
        # just above the threshold it rocks (a short exceedance between scan samples is found)
        exc = SinePulse(f, amp / 0.99 * 1.0001)
        sol = solve_single(rock, g=G, accel=exc.acceleration, breakpoints=exc.breakpoints,
                           end_time=exc.end_time, t_out=np.linspace(0, 1, 1001), linear=linear)
        # a barely exceeding peak in each half cycle (0.01 % over for ~0.9 ms): two uplifts
        np.testing.assert_allclose(sol.uplift_times, [0.25 / f, 0.75 / f], atol=1e-3)
        assert sol.impacts.size == 2 and np.all(sol.impacts > sol.uplift_times)
        assert 0 < np.max(np.abs(sol.theta)) < 1e-6 * rock.lam


def test_mirror_symmetry():
    base = Scenario("single", SINGLE2, excitation=SinePulse(5.0, 0.006), duration=4.0)
    a = single_block_reference(base)
    b = single_block_reference(base.replace(excitation=SinePulse(5.0, -0.006)))
    assert a.impacts.size > 3
    np.testing.assert_allclose(b.theta, -a.theta, atol=1e-12)
    np.testing.assert_allclose(b.impacts, a.impacts, atol=1e-12)


def test_mirror_symmetry_of_the_initial_tilt(rock):
    t = np.linspace(0, 10, 1001)
    a = free(rock, t, theta0=0.3 * rock.lam)
    b = free(rock, t, theta0=-0.3 * rock.lam)
    np.testing.assert_allclose(b.theta, -a.theta, atol=1e-14)


def test_forced_energy_balance_before_the_first_impact(rock):
    """d/dt(½θ̇² + p² cos(sλ−θ)) = −p² (ü_g/g) cos(sλ−θ) θ̇ : the work of the base."""
    acc, t_end = sine(1.5 * G * math.tan(rock.lam), 2 * rock.p)
    t = np.linspace(0, t_end, 4001)
    sol = solve_single(rock, g=G, accel=acc, breakpoints=(t_end,), end_time=t_end, t_out=t)
    m = sol.t <= (sol.impacts[0] if sol.impacts.size else t_end)
    m &= sol.t >= sol.uplift_times[0]
    th, om, tt = sol.theta[m], sol.theta_dot[m], sol.t[m]
    e = energy(rock, th, om)
    power = -rock.p**2 * acc(tt) / G * np.cos(-rock.lam - th) * om
    work = np.concatenate([[0.0], np.cumsum(0.5 * (power[1:] + power[:-1]) * np.diff(tt))])
    np.testing.assert_allclose(e - e[0], work, atol=1e-7 * rock.p**2)


# ---------------------------------------------------------------- Trajectory adapter


def test_reference_trajectory_geometry():
    sc = Scenario("single", SINGLE2, excitation=SinePulse(5.0, 0.006), duration=4.0,
                  output_rate=500.0)
    tr = single_block_reference(sc)
    assert isinstance(tr, Trajectory) and tr.status is Status.OK
    n = sc.output_times().size
    assert tr.theta.shape == tr.x.shape == tr.z.shape == tr.wobble.shape == (n, 1)
    assert np.all(tr.wobble == 0)
    assert tr.engine == "analytic" and tr.engine_version.startswith("housner-")
    assert tr.settings["rtol"] == 1e-10 and tr.settings["linear"] is False
    assert tr.scenario == "single" and tr.impacts.size > 3 and "rest_time" in tr.extra
    rock, blk = SINGLE2.rocking(G), SINGLE2
    th = tr.theta[:, 0]
    ug = sc.excitation.displacement(tr.t)
    # centroid height: R cos(λ − |θ|); horizontal: pivot at u_g ± b, centroid R sin(|θ| − λ)
    np.testing.assert_allclose(tr.z[:, 0], rock.R * np.cos(rock.lam - np.abs(th)), atol=1e-12)
    side = np.where(th >= 0, 1.0, -1.0)
    pivot = ug + side * blk.pivot_half_width
    np.testing.assert_allclose(tr.x[:, 0] - pivot, side * rock.R * np.sin(np.abs(th) - rock.lam),
                               atol=1e-12)
    at_rest = th == 0
    assert at_rest[0]
    np.testing.assert_allclose(tr.x[at_rest, 0], ug[at_rest], atol=1e-15)
    np.testing.assert_allclose(tr.z[at_rest, 0], blk.h, atol=1e-15)


def test_reference_eta_override_and_overturning():
    sc = Scenario("free", B0, contact=Contact(eta=1.0), initial_tilt=0.5, duration=20.0)
    tr = single_block_reference(sc)
    assert tr.impacts.size == 13 and tr.extra["rest_time"] is None
    np.testing.assert_allclose(np.diff(tr.impacts), 1.552249709228, atol=1e-8)
    rock = B0.rocking(G)
    big = Scenario("over", B0, excitation=SinePulse(0.5, 2.0), duration=10.0)
    assert big.excitation.peak_acceleration() > 5 * G * math.tan(rock.lam)
    tr = single_block_reference(big)
    assert tr.status is Status.OVERTURNED
    assert tr.t[-1] <= tr.extra["overturn_time"] < tr.t[-1] + 1 / big.output_rate
    assert tr.t.size < big.output_times().size and abs(tr.theta[-1, 0]) <= math.pi / 2


def test_unsupported_scenarios():
    two = Scenario("two", stack((B0, B0)))
    with pytest.raises(UnsupportedScenario):
        single_block_reference(two)
    off = Scenario("off", stack((B0,), offsets=(0.1,)))
    with pytest.raises(UnsupportedScenario):
        single_block_reference(off)


def test_free_rocking_is_fast():
    sc = Scenario("b0", B0, initial_tilt=0.5, duration=20.0, output_rate=1000.0)
    single_block_reference(sc)
    start = time.perf_counter()
    tr = single_block_reference(sc)
    assert time.perf_counter() - start < 0.5  # ~0.02 s measured; an ODE sweep takes ~0.2 s
    assert tr.extra["rest_time"] == pytest.approx(19.33, abs=0.01)


def test_fast_scalar_excitations_match_the_excitation_objects():
    """The ODE uses plain-float copies of the built-in excitations; they must be the same
    functions, and the solution must not depend on which one is used."""
    rng = np.random.default_rng(1)
    t_rec = np.arange(0, 3, 0.01)
    excs = [SinePulse(5.0, 0.006), SinePulse(2.0, -0.01, cycles=2), Free(),
            Sinusoid(2.0, 0.01, duration=5.0), Sinusoid(3.0, 0.006, ramp_cycles=0.5),
            Record(t_rec, 2.5 * np.sin(2 * np.pi * t_rec) + rng.standard_normal(t_rec.size))]
    for exc in excs:
        fast = scalar_acceleration(exc)
        assert fast is not None, exc
        tt = rng.uniform(-0.5, 6.0, 2000)
        ref = np.asarray(exc.acceleration(tt)) * np.ones_like(tt)
        np.testing.assert_allclose([fast(float(x)) for x in tt], ref, rtol=0,
                                   atol=1e-12 * (1 + np.max(np.abs(ref))))
    rock = SINGLE2.rocking(G)
    exc = Sinusoid(2.0, 0.012, duration=3.0)
    t_out = np.linspace(0, 4, 4001)
    kw = dict(g=G, accel=exc.acceleration, breakpoints=exc.breakpoints, end_time=exc.end_time,
              t_out=t_out)
    a = solve_single(rock, accel_scalar=scalar_acceleration(exc), **kw)
    b = solve_single(rock, **kw)
    assert a.impacts.size > 5
    np.testing.assert_allclose(a.theta, b.theta, atol=1e-12)
    np.testing.assert_allclose(a.impacts, b.impacts, atol=1e-12)


# ---------------------------------------------------------------- built-in DOP853


@pytest.mark.parametrize("name", ["single-pulse-3.0hz-8mm", "single-sine-5.0hz-5mm"])
def test_builtin_integrator_matches_solve_ivp(name):
    """The scalar DOP853 of the forced phases is SciPy's algorithm: same answer to rounding."""
    from rockbench.scenarios import get_scenario

    sc = get_scenario(name)
    a = single_block_reference(sc)  # integrator="builtin" (default)
    b = single_block_reference(sc, integrator="scipy")
    assert a.settings == b.settings and a.status is b.status is Status.OK
    assert a.impacts.size == b.impacts.size > 5
    np.testing.assert_allclose(a.theta, b.theta, rtol=0, atol=1e-8)
    np.testing.assert_allclose(a.impacts, b.impacts, rtol=0, atol=1e-8)
    assert a.extra["uplift_times"] == pytest.approx(b.extra["uplift_times"], abs=1e-8)


@pytest.mark.parametrize("case", ["overturn", "linear", "free-ode", "tilted"])
def test_builtin_integrator_matches_solve_ivp_on_every_path(rock, case):
    """Overturning event, linear model, ODE free phases, a start off θ = 0."""
    exc, end = sine(1.3 * G * math.tan(rock.lam), 2 * math.pi)
    kw = dict(g=G, accel=exc, end_time=end, breakpoints=(end,), t_out=np.linspace(0, 6, 3001))
    if case == "overturn":
        exc, end = sine(5.0 * G * math.tan(rock.lam), 2 * math.pi)
        kw.update(accel=exc, end_time=end, breakpoints=(end,))
    elif case == "linear":
        kw.update(linear=True)
    elif case == "free-ode":
        kw.update(free_closed_form=False)
    else:
        kw.update(theta0=0.3 * rock.lam)
    a = solve_single(rock, **kw)
    b = solve_single(rock, integrator="scipy", **kw)
    assert a.status == b.status == ("overturned" if case == "overturn" else "ok")
    assert a.t.size == b.t.size and a.impacts.size == b.impacts.size
    assert case == "overturn" or a.impacts.size > 3
    np.testing.assert_allclose(a.theta, b.theta, rtol=0, atol=1e-8)
    np.testing.assert_allclose(a.theta_dot, b.theta_dot, rtol=0, atol=1e-7)
    np.testing.assert_allclose(a.impacts, b.impacts, rtol=0, atol=1e-8)
    if case == "overturn":
        assert a.overturn_time == pytest.approx(b.overturn_time, abs=1e-8)


def test_builtin_integrator_tables_and_steps_are_scipys():
    """The copied DOP853 coefficients, and step sequence / dense output against solve_ivp."""
    from scipy.integrate import solve_ivp
    from scipy.integrate._ivp import dop853_coefficients as ref

    from rockbench.analytic import _integrate as ig

    a = np.zeros((16, 16))
    for i, row in enumerate(ig.A):
        for j, v in row:
            a[i, j] = v
    np.testing.assert_array_equal(a[1:], ref.A[1:])
    np.testing.assert_array_equal(ig.C, ref.C)
    for mine, theirs in ((ig.E3, ref.E3), (ig.E5, ref.E5)):
        v = np.zeros(13)
        for j, x in mine:
            v[j] = x
        np.testing.assert_array_equal(v, theirs)
    d = np.zeros((4, 16))
    for i, row in enumerate(ig.D):
        for j, x in row:
            d[i, j] = x
    np.testing.assert_array_equal(d, ref.D)

    def alpha(t, th):
        return -4.0 * (math.sin(-0.2 - th) + 0.3 * math.sin(20 * t) * math.cos(-0.2 - th))

    res = ig.integrate_phase(alpha, 0.1, 0.01, 0.0, 3.0, rtol=1e-10, atol=1e-12,
                             events=[lambda t, th, w: math.pi / 2 - abs(th)])
    over = lambda t, y: math.pi / 2 - abs(y[0])  # noqa: E731
    over.terminal, over.direction = True, -1
    sol = solve_ivp(lambda t, y: [y[1], alpha(t, y[0])], (0.1, 3.0), [0.01, 0.0],
                    method="DOP853", rtol=1e-10, atol=1e-12, dense_output=True, events=[over])
    assert res.status == sol.status == 1 and res.event == 0 and res.nfev == sol.nfev
    assert len(res.ts) == sol.t.size
    assert res.t == pytest.approx(sol.t_events[0][0], abs=1e-12)
    tt = np.linspace(0.1, res.t, 2001)
    th, om = res.dense(tt)
    np.testing.assert_allclose(th, sol.sol(tt)[0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(om, sol.sol(tt)[1], rtol=0, atol=1e-11)
    with pytest.raises(ValueError, match="integrator"):
        solve_single(B0.rocking(G), g=G, accel=Free().acceleration, t_out=[0, 1],
                     integrator="rk4")


def test_squat_block_stops_at_its_first_impact() -> None:
    """Past λ ≈ 54.7° Housner's η = 1 − 1.5 sin²λ is negative: no rebound is possible, so
    the block released from a tilt stops at the first impact (η clipped at 0), which comes
    after the closed-form quarter period."""
    block = Block(2.0, 0.5, 1.0, mass=10.0)  # λ = atan(2) = 63.4°
    rock = block.rocking()
    assert rock.eta < 0.0
    sc = Scenario("squat", block, initial_tilt=0.5, duration=2.0)
    ref = single_block_reference(sc)
    assert ref.status is Status.OK
    t1 = quarter_period(rock.p, rock.lam, 0.5 * rock.lam)
    assert ref.impacts is not None and ref.impacts.size == 1
    assert ref.impacts[0] == pytest.approx(t1, rel=1e-9)
    after = ref.t > t1 + 1e-9
    assert np.all(ref.theta[after, 0] == 0.0)


# ---------------------------------------------------------------- vertical base motion


@dataclass(frozen=True)
class Steady(AxialExcitation):
    """ü = a on [0, until], then 0 (test-only: no ``kind``, so never registered).

    A Record cannot hold a constant acceleration: its baseline correction removes the
    mean acceleration so that the base ends at rest.
    """

    a: float
    until: float

    def acceleration(self, t: Any) -> Any:
        t = np.asarray(t, float)
        return np.where((t >= 0) & (t <= self.until), self.a, 0.0)

    def velocity(self, t: Any) -> Any:
        return self.a * np.clip(np.asarray(t, float), 0.0, self.until)

    def displacement(self, t: Any) -> Any:
        t = np.asarray(t, float)
        tc = np.clip(t, 0.0, self.until)
        return 0.5 * self.a * tc * tc + self.a * self.until * np.maximum(t - self.until, 0.0)

    @property
    def end_time(self) -> float:
        return self.until

    @property
    def breakpoints(self) -> tuple[float, ...]:
        return (self.until,)

    @classmethod
    def from_table(cls, table: Any, *, source: Any = None) -> Steady:
        raise NotImplementedError

    def to_table(self) -> dict[str, Any]:
        raise NotImplementedError


@pytest.mark.parametrize("z", [Free(), SinePulse(5.0, 0.0)], ids=["still", "zero-pulse"])
def test_components_without_vertical_acceleration_are_the_horizontal_reference(z):
    """ü_z ≡ 0 as a Components excitation: bit for bit the reference of the x motion alone,
    whether z stands still or takes the vertical path with a zero pulse (the same timing)."""
    x = SinePulse(5.0, 0.006)
    alone = single_block_reference(Scenario("x", SINGLE2, excitation=x, duration=4.0))
    both = single_block_reference(Scenario("x", SINGLE2, excitation=Components(x=x, z=z),
                                           duration=4.0))
    assert alone.status is both.status is Status.OK and alone.impacts.size > 3
    for f in ("t", "theta", "x", "z", "impacts"):
        np.testing.assert_array_equal(getattr(both, f), getattr(alone, f), err_msg=f)
    assert both.extra == alone.extra and both.message == alone.message


@pytest.mark.parametrize("a_z", [0.5 * G, -0.4 * G])
def test_constant_vertical_acceleration_is_a_gravity_g_plus_a_z(a_z):
    """Free rocking on a base accelerating steadily upward (a_z > 0) or downward (> −g) is
    free rocking under gravity g + a_z: impact times scale by √(g / (g + a_z))."""
    dur = 8.0
    lift = Scenario("lift", B0, excitation=Components(z=Steady(a_z, 2 * dur)), initial_tilt=0.5,
                    duration=dur)
    heavy = Scenario("heavy", B0, initial_tilt=0.5, duration=dur, g=G + a_z)
    a, b = single_block_reference(lift), single_block_reference(heavy)
    assert a.status is b.status is Status.OK
    assert a.impacts.size == b.impacts.size >= 5
    np.testing.assert_allclose(a.impacts, b.impacts, rtol=0, atol=1e-8)
    scale = math.sqrt(G / (G + a_z))
    # the closed form of free rocking with p² ∝ g + a_z, and the g-only run's times, scaled
    rock = B0.rocking(G)
    times = free_impact_times(rock.p / scale, rock.lam, 0.5 * rock.lam, rock.eta, a.impacts.size)
    np.testing.assert_allclose(a.impacts, times, rtol=1e-9)
    still = single_block_reference(Scenario("still", B0, initial_tilt=0.5,
                                            duration=dur / scale + 0.1))
    np.testing.assert_allclose(a.impacts, scale * still.impacts[:a.impacts.size], rtol=0,
                               atol=1e-8)
    # the same rotation, and the centroid rides on the base: z = z_g+a + ½ a_z t²
    np.testing.assert_allclose(a.theta, b.theta, rtol=0, atol=1e-8 * rock.lam)
    np.testing.assert_allclose(a.z[:, 0] - 0.5 * a_z * a.t**2, b.z[:, 0], rtol=0, atol=1e-9)


def test_base_falling_faster_than_gravity_stops_the_reference():
    """Where ü_z < −g the block leaves the ground: the reference stops there, unsupported."""
    z = SinePulse(2.0, 1.5 * G / (4 * math.pi) ** 2)  # peak 1.5 g, below −g in its 2nd half
    w = z.omega
    t_flight = (math.pi + math.asin(G / z.peak_acceleration())) / w  # g + ü_z = 0
    sc = Scenario("fall", SINGLE2, excitation=Components(x=SinePulse(5.0, 0.006), z=z),
                  duration=2.0)
    tr = single_block_reference(sc)
    assert tr.status is Status.UNSUPPORTED and "leaves the ground" in tr.message
    said = float(re.search(r"at t = ([0-9.]+) s", tr.message).group(1))
    assert said == pytest.approx(t_flight, abs=5e-7)
    assert tr.t[-1] <= t_flight < tr.t[-1] + 1 / sc.output_rate
    assert np.all(np.isfinite(tr.theta))
    # the solver's own time, against a root of g + ü_z on the inputs
    rock = SINGLE2.rocking(G)
    sol = solve_single(rock, g=G, accel=Free().acceleration, end_time=z.end_time,
                       breakpoints=z.breakpoints, t_out=sc.output_times(),
                       vertical=(z.acceleration, lambda t: float(z.acceleration(t))))
    assert sol.status == "flight" and sol.t[-1] <= t_flight
    root = brentq(lambda t: G + float(z.acceleration(t)), 0.5 / z.frequency, 0.75 / z.frequency,
                  xtol=1e-14)
    assert t_flight == pytest.approx(root, abs=1e-12)
    # a base falling at 1.2 g from the start: the block is never on the ground
    tr = single_block_reference(sc.replace(excitation=Components(z=Steady(-1.2 * G, 5.0))))
    assert tr.status is Status.UNSUPPORTED and "at t = 0.000000 s" in tr.message
    assert tr.t.tolist() == [0.0]


@pytest.mark.parametrize("linear", [False, True], ids=["exact", "linear"])
def test_uplift_under_vertical_motion_at_g_plus_uz_tan_lambda(linear):
    """The block lifts off when |ü_x| = (g + ü_z) tan λ ((g + ü_z) λ linearised)."""
    rock = SINGLE2.rocking(G)
    x, z = SinePulse(5.0, 0.006), SinePulse(3.0, 0.02)  # ü_z ≈ 1.4 m/s² at the uplift
    sc = Scenario("up", SINGLE2, excitation=Components(x=x, z=z), duration=1.0)
    tr = single_block_reference(sc, linear=linear)
    assert tr.status is Status.OK
    slope = rock.lam if linear else math.tan(rock.lam)

    def excess(t: float) -> float:
        return abs(float(x.acceleration(t))) - (G + float(z.acceleration(t))) * slope

    tt = np.linspace(0.0, 0.05, 50001)
    first = int(np.argmax([excess(float(t)) > 0 for t in tt]))
    assert first > 0
    root = brentq(excess, float(tt[first - 1]), float(tt[first]), xtol=1e-15)
    assert tr.extra["uplift_times"][0] == pytest.approx(root, abs=1e-12)
    # later than on a base that does not move vertically (the upward ü_z adds weight)
    flat = single_block_reference(sc.replace(excitation=x), linear=linear)
    assert tr.extra["uplift_times"][0] - flat.extra["uplift_times"][0] > 1e-3
    # a positive ü_x tips the block to θ < 0 first
    assert np.all(tr.theta[tr.t <= tr.impacts[0], 0] <= 0)
    assert np.min(tr.theta) < -0.01 * rock.lam
