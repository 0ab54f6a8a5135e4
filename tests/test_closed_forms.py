"""Closed forms of the single rocking block against the worked numbers of two-block-model.md §6.

The reference values below (T1, T2, T3, T12, T13) were computed independently in the
specification; the quadratures and ODE residuals re-derive the formulas from the
equation of motion.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate

from rockbench.analytic.closed_forms import (
    amplitude_after_impacts,
    free_impact_times,
    free_period,
    impact_velocity,
    quarter_period,
    rectangular_pulse_min_overturn,
    sine_pulse_linear_response,
)
from rockbench.scenarios import Block

G = 9.81
# T1: block 1 m x 5 m (b = 0.5, h = 2.5)
LAM = 0.197395559850
R = 2.549509756796
P = 1.698778657906
ETA = 49.0 / 52.0
# T3 table: impact time, post-impact rate, |theta_n| exact, |theta_n| Housner linear
T3 = np.array([
    [0.7761248546, -0.273096156019, 0.083339113164, 0.083308071011],
    [2.1263229608, +0.257340608556, 0.071253454725, 0.071206385983],
    [3.3271341884, -0.242494034986, 0.061415146055, 0.061360166072],
    [4.4096877965, +0.228503994506, 0.053237762768, 0.053179649296],
    [5.3946268903, -0.215321071746, 0.046344891970, 0.046286562025],
])


@pytest.fixture(scope="module")
def rock():
    return Block(1.0, 0.2, 5.0, mass=1.0).rocking(G)


def test_t1_constants(rock):
    assert rock.lam == pytest.approx(LAM, rel=1e-11)
    assert rock.R == pytest.approx(R, rel=1e-11)
    assert rock.p == pytest.approx(P, rel=1e-11)
    assert rock.p == pytest.approx(math.sqrt(3 * G / (4 * rock.R)), rel=1e-13)
    assert rock.eta == pytest.approx(ETA, rel=1e-13)
    assert rock.eta == pytest.approx(1 - 1.5 * math.sin(rock.lam) ** 2, rel=1e-13)
    assert G * math.tan(rock.lam) == pytest.approx(1.962, rel=1e-12)


def test_t2_period(rock):
    th0 = 0.5 * rock.lam
    assert free_period(rock.p, rock.lam, th0) == pytest.approx(3.104499418457, rel=1e-11)
    assert free_period(rock.p, rock.lam, th0, linear=True) == pytest.approx(
        3.100952300750, rel=1e-11)
    assert quarter_period(rock.p, rock.lam, th0) == pytest.approx(0.776124854614, rel=1e-11)
    # the Housner formula as printed in the literature (OpenSees example)
    ang = 1.0 / (1.0 - th0 / rock.lam)
    t_lin = 4 / rock.p * math.log(ang + math.sqrt(ang * ang - 1))
    assert free_period(rock.p, rock.lam, th0, linear=True) == pytest.approx(t_lin, rel=1e-13)


@pytest.mark.parametrize("lam", [0.05, 0.2, 0.6, 1.0])
@pytest.mark.parametrize("frac", [1e-4, 0.2, 0.5, 0.9, 0.999])
def test_exact_period_is_the_energy_quadrature(lam, frac):
    """T = 4 ∫ dθ / sqrt(2p²[cos(λ−θ0) − cos(λ−θ)]) from the energy integral of the EOM."""
    p = 2.3
    th0 = frac * lam

    def integrand(w):  # θ = θ0 (1 − w²) removes the singularity at the turning point
        th = th0 * (1 - w * w)
        e = 2 * math.sin(0.5 * (th0 - th)) * math.sin(lam - 0.5 * (th0 + th))
        return 2 * th0 * w / math.sqrt(2 * p * p * e)

    quad, _ = integrate.quad(integrand, 0, 1, epsabs=0, epsrel=1e-12, limit=200)
    assert free_period(p, lam, th0) == pytest.approx(4 * quad, rel=1e-9)
    assert free_period(p, lam, -th0) == pytest.approx(4 * quad, rel=1e-9)


def test_exact_period_tends_to_linear_for_slender_blocks():
    ratios = [free_period(1.0, lam, 0.5 * lam) / free_period(1.0, lam, 0.5 * lam, linear=True)
              for lam in (0.4, 0.1, 0.01, 0.001)]
    gaps = np.abs(np.array(ratios) - 1)
    assert np.all(np.diff(gaps) < 0) and gaps[-1] < 1e-6


def test_t3_amplitudes(rock):
    n = np.arange(1, 6)
    exact = amplitude_after_impacts(rock.lam, 0.5 * rock.lam, rock.eta, n)
    linear = amplitude_after_impacts(rock.lam, 0.5 * rock.lam, rock.eta, n, linear=True)
    np.testing.assert_allclose(exact, T3[:, 2], rtol=1e-10)
    np.testing.assert_allclose(linear, T3[:, 3], rtol=1e-10)
    assert amplitude_after_impacts(rock.lam, 0.5 * rock.lam, rock.eta, 0) == pytest.approx(
        0.5 * rock.lam, rel=1e-14)


def test_t3_impact_velocities_and_times(rock):
    amps = amplitude_after_impacts(rock.lam, 0.5 * rock.lam, rock.eta, np.arange(0, 5))
    # the post-impact rate is eta times the speed gained falling from the previous amplitude
    post = rock.eta * impact_velocity(rock.p, rock.lam, amps)
    np.testing.assert_allclose(post, np.abs(T3[:, 1]), rtol=1e-10)
    # ... which is also the speed needed to climb to the next amplitude (energy balance)
    np.testing.assert_allclose(post, impact_velocity(rock.p, rock.lam, T3[:, 2]), rtol=1e-9)
    times = free_impact_times(rock.p, rock.lam, 0.5 * rock.lam, rock.eta, 5)
    np.testing.assert_allclose(times, T3[:, 0], rtol=1e-9)
    # without loss the impacts are T/4 + k T/2
    t_nl = free_impact_times(rock.p, rock.lam, 0.5 * rock.lam, 1.0, 4)
    np.testing.assert_allclose(t_nl, 0.776124854614 + 1.552249709228 * np.arange(4), rtol=1e-11)


def test_impact_velocity_is_energy(rock):
    th = np.array([1e-6, 0.01, 0.1, 0.19])
    w = impact_velocity(rock.p, rock.lam, th)
    np.testing.assert_allclose(
        0.5 * w**2, rock.p**2 * (np.cos(rock.lam - th) - math.cos(rock.lam)), rtol=1e-8)
    wl = impact_velocity(rock.p, rock.lam, th, linear=True)
    np.testing.assert_allclose(wl**2, rock.p**2 * (rock.lam**2 - (rock.lam - th) ** 2),
                               rtol=1e-12)


def test_t12_rectangular_pulse(rock):
    a_nl = rectangular_pulse_min_overturn(rock.p, rock.lam, 0.5, G)
    assert a_nl == pytest.approx(3.4300270873, rel=1e-9)
    assert a_nl / (G * math.tan(rock.lam)) == pytest.approx(1.7482299120, rel=1e-9)
    a_lin = rectangular_pulse_min_overturn(rock.p, rock.lam, 0.5, G, linear=True)
    assert a_lin == pytest.approx(3.3834864782, rel=1e-10)
    assert a_lin / (G * rock.lam) == pytest.approx(1.7472621063, rel=1e-10)
    # long pulses need just the static threshold, short ones much more
    assert rectangular_pulse_min_overturn(rock.p, rock.lam, 20.0, G) == pytest.approx(
        G * math.tan(rock.lam), rel=1e-6)
    assert rectangular_pulse_min_overturn(rock.p, rock.lam, 0.05, G) > 10 * G * math.tan(rock.lam)


def test_sine_pulse_linear_response_solves_the_linear_eom(rock):
    p, lam = rock.p, rock.lam
    w = 2 * p
    a_p = 3.0 * G * lam
    ts = math.asin(G * lam / a_p) / w
    t = np.linspace(ts, 2 * math.pi / w, 2001)
    th, om = sine_pulse_linear_response(p, lam, a_p, w, G, t)
    assert abs(th[0]) < 1e-15 and abs(om[0]) < 1e-14
    h = 1e-4
    thp, _ = sine_pulse_linear_response(p, lam, a_p, w, G, t[1:-1] + h)
    thm, _ = sine_pulse_linear_response(p, lam, a_p, w, G, t[1:-1] - h)
    acc = (thp - 2 * th[1:-1] + thm) / h**2
    # linearised EOM on the negative side (s = -1): θ'' = -p² [-λ - θ + ü_g/g]
    rhs = -p * p * (-lam - th[1:-1] + a_p * np.sin(w * t[1:-1]) / G)
    np.testing.assert_allclose(acc, rhs, atol=1e-5 * p * p * lam)
    np.testing.assert_allclose(om[1:-1], (thp - thm) / (2 * h), rtol=1e-6, atol=1e-7)
    assert np.all(th[1:] < 0)


@pytest.mark.parametrize(("ratio", "boundary"), [(2.0, 2.34990313), (4.0, 5.23896436)])
def test_t13_linear_mode1_boundary(rock, ratio, boundary):
    """Mode 1 (overturning without impact): θ < 0 throughout and (θ + λ) + θ̇/p < 0 at the end."""
    p, lam = rock.p, rock.lam
    w = ratio * p
    t_end = 2 * math.pi / w

    def margin(factor):
        a_p = factor * boundary * G * lam
        th, om = sine_pulse_linear_response(p, lam, a_p, w, G, t_end)
        return float(th + lam + om / p)

    assert margin(1.001) < 0 < margin(0.999)


def test_invalid_amplitude():
    with pytest.raises(ValueError):
        free_period(1.0, 0.2, 0.2)
    with pytest.raises(ValueError):
        amplitude_after_impacts(0.2, 0.3, 0.9, 1)
