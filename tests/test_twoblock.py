"""Tests of the two-stacked-block analytic reference against two-block-model.md §6.

Every number asserted here is either printed in the specification (T0–T13) or
computed in this file independently of the implementation (closed forms of the
Housner single block, a minimal single-block integrator, explicit geometry).
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.special import ellipkinc

from rockbench.analytic.overturning import pulse_outcome
from rockbench.analytic.twoblock import (
    BlockParams,
    Pattern,
    TwoBlockModel,
    parse_pattern,
    solve_two_blocks,
    two_block_reference,
)
from rockbench.bounds import check_trajectory
from rockbench.engines import engine_class
from rockbench.errors import UnsupportedScenario
from rockbench.runner import Job, run_job
from rockbench.scenarios import Block, Free, Record, Scenario, SinePulse, get_scenario, stack
from rockbench.trajectory import Status, Trajectory

G = 9.81
RHO = 2000.0


def uniform(b: float, h: float, rho: float = RHO) -> BlockParams:
    """Uniform rectangle per unit thickness (spec §6: m = ρ·4bh, I = m(b²+h²)/3)."""
    m = rho * 4 * b * h
    return BlockParams(b, h, m, m * (b * b + h * h) / 3)


G_REF = (BlockParams(0.5, 1.5, 6000.0, 5000.0), BlockParams(0.3, 1.0, 2400.0, 872.0))
G_U = (uniform(0.6, 1.0), uniform(0.2, 1.0))


def zero_accel(t):
    return np.zeros_like(np.asarray(t, float))


def sine_pulse(ap: float, wp: float = 2 * math.pi, sign: float = 1.0):
    t_end = 2 * math.pi / wp

    def acc(t):
        t = np.asarray(t, float)
        return np.where((t >= 0) & (t <= t_end), sign * ap * np.sin(wp * t), 0.0)

    return acc, t_end


def run_pulse(blocks, ap, t_end_run, sign=1.0, n=None, **kw):
    acc, te = sine_pulse(ap, sign=sign)
    n = n or int(round(t_end_run * 1000)) + 1
    return solve_two_blocks(*blocks, g=G, accel=acc, breakpoints=(te,), end_time=te,
                            t_out=np.linspace(0, t_end_run, n), **kw)


# --------------------------------------------------------------- single-block closed forms
def housner_constants(b: float, h: float):
    r = math.hypot(b, h)
    alpha = math.atan2(b, h)
    return alpha, r, math.sqrt(3 * G / (4 * r)), 1 - 1.5 * math.sin(alpha) ** 2


def exact_period(p: float, alpha: float, th0: float) -> float:
    """Free-rocking period without loss (elliptic integral, §4)."""
    mpar = math.cos((alpha - th0) / 2) ** 2
    s2 = (math.sin(alpha / 2) ** 2 - math.sin((alpha - th0) / 2) ** 2) / (
        math.sin(alpha / 2) ** 2 * math.cos((alpha - th0) / 2) ** 2)
    return 4 / p * ellipkinc(math.asin(math.sqrt(s2)), mpar)


def free_impact_times(p: float, alpha: float, eta: float, th0: float, n: int) -> list[float]:
    """Impact times of a single block released from rest at th0 (exact, §4)."""
    times = [exact_period(p, alpha, th0) / 4]
    for k in range(1, n):
        c = math.cos(alpha) + eta ** (2 * k) * (math.cos(alpha - th0) - math.cos(alpha))
        thn = alpha - math.acos(c)
        times.append(times[-1] + exact_period(p, alpha, thn) / 2)
    return times


T3_TIMES = [0.7761248546, 2.1263229608, 3.3271341884, 4.4096877965, 5.3946268903]


def test_closed_form_helper_reproduces_T2_T3():
    alpha, r, p, eta = housner_constants(0.5, 2.5)
    assert exact_period(p, alpha, 0.5 * alpha) == pytest.approx(3.104499418457, abs=1e-11)
    assert free_impact_times(p, alpha, eta, 0.5 * alpha, 5) == pytest.approx(T3_TIMES, abs=1e-9)


# ------------------------------------------------------------------------ constants
def test_T1_constants_as_upper_block():
    m = TwoBlockModel(uniform(2.0, 0.5), uniform(0.5, 2.5), G)
    assert m.alpha2 == pytest.approx(0.197395559850, abs=1e-12)
    assert m.R2 == pytest.approx(2.549509756796, abs=1e-12)
    assert m.p2 == pytest.approx(1.698778657906, abs=1e-12)
    assert m.eta2 == pytest.approx(49 / 52, abs=1e-12)
    assert m.thr_upper == pytest.approx(1.962, abs=1e-12)


def test_T6_constants():
    m = TwoBlockModel(*G_REF, G)
    expected = dict(alpha1=0.321750554397, R1=1.581138830084, alpha2=0.291456794478,
                    R2=1.044030650891, p2=2.654657584984, eta2=0.876146788991,
                    ybar=2.214285714286, alphaM=0.222081901905, RM=2.270035511724,
                    IOM=59872.0, pM=1.767578007736, etaM=0.929850347408,
                    thr_upper=2.943, thr_stack=2.215161290323)
    for k, v in expected.items():
        assert getattr(m, k) == pytest.approx(v, rel=1e-11, abs=1e-12), k


@pytest.mark.parametrize("a, expected", [
    (2.0, "R"), (-2.0, "R"), (2.3, "M(-1)"), (-2.3, "M(+1)"), (3.0, "M(-1)"), (-3.0, "M(+1)"),
    (10.0, "M(-1)"), (30.0, "B(-1,+1)"), (-30.0, "B(+1,-1)"),
])
def test_T6_start_pattern(a, expected):
    assert TwoBlockModel(*G_REF, G).start_pattern(a).name == expected


def test_pattern_names_roundtrip():
    for name in ("R", "M(+1)", "M(-1)", "U(+1)", "U(-1)", "B(+1,+1)", "B(+1,-1)",
                 "B(-1,+1)", "B(-1,-1)"):
        assert parse_pattern(name).name == name
    assert parse_pattern("B(1,-1)") == Pattern(1, -1)
    with pytest.raises(ValueError):
        parse_pattern("B(+1)")
    with pytest.raises(ValueError):
        parse_pattern("X")


# ---------------------------------------------------------------------------- T0
def test_T0_matrices_and_accelerations():
    m = TwoBlockModel(*G_REF, G)
    mm, cc, gg, bb = m.matrices_B(1, -1, 0.05, 0.02, 0.3, -0.4)
    npt = np.testing
    npt.assert_allclose(mm, [[43136, 6743.401064], [6743.401064, 3488]], rtol=1e-9)
    npt.assert_allclose(cc, [-620.715831, 349.152655], rtol=1e-8)
    npt.assert_allclose(gg, [40262.091529, -7532.636016], rtol=1e-10)
    npt.assert_allclose(bb, [16425.651731, 2385.120976], rtol=1e-10)
    # L, γ, Δ from the Cartesian forms: c = C − O1 in the upright frame
    s1, s2 = 1, -1
    vx, vy = s2 * m.bc - s1 * m.b1, 2 * m.h1
    assert math.hypot(vx, vy) == pytest.approx(3.104834939252, abs=1e-12)
    gam = math.atan2(vx, vy)
    assert gam == pytest.approx(-0.260602391747, abs=1e-12)
    assert 0.05 - 0.02 + gam + s2 * m.alpha2 == pytest.approx(-0.522059186225, abs=1e-12)
    qdd = m.accel_B(1, -1, 0.05, 0.02, 0.3, -0.4, 1.5)
    npt.assert_allclose(qdd, [-2.367230647148, 5.610374874530], rtol=1e-11)
    npt.assert_allclose(m.matrices_B(1, 1, 0.05, 0.12)[0],
                        [[41696, 7443.518529], [7443.518529, 3488]], rtol=1e-9)
    qdd2 = m.accel_B(1, 1, 0.05, 0.12, -0.2, 0.6, -2.0)
    npt.assert_allclose(qdd2, [0.172357260399, -0.141195574206], rtol=1e-10)
    # mirror symmetry
    npt.assert_allclose(m.accel_B(-1, 1, -0.05, -0.02, -0.3, 0.4, -1.5), -qdd, rtol=1e-13)
    npt.assert_allclose(m.accel_B(-1, -1, -0.05, -0.12, 0.2, -0.6, 2.0), -qdd2, rtol=1e-13)


def test_T0_indicators():
    m = TwoBlockModel(*G_REF, G)
    assert m.lambda_if(1, 1, 0.05, 0.2, -1.0) == pytest.approx(981.320681, rel=1e-9)
    assert m.lambda_if(1, -1, 0.05, 0.2, -1.0) == pytest.approx(12665.783112, rel=1e-9)
    assert m.lambda_b(1, 1, 0.1, 0.5, -1.0) == pytest.approx(13421.050938, rel=1e-9)
    assert m.lambda_b(1, -1, 0.1, 0.5, -1.0) == pytest.approx(68064.842415, rel=1e-9)
    # at θ = θ̇ = 0: λ_if(σ) = σ (M12 + M22) θ̈_M + m2 (g bc + σ ü_g h2), which is the
    # static formula m2 (g bc + σ ü_g h2) of §3.2 plus the inertia of the accelerating stack
    for a in (-1.7, 0.4, 2.2):
        for s in (1, -1):
            ddm = -m.pM**2 * (math.sin(s * m.alphaM) + a / G * math.cos(s * m.alphaM))
            for sg in (1, -1):
                c = np.array([sg * m.bc - s * m.b1, 2 * m.h1])
                d = np.array([-sg * m.bc, m.h2])
                expect = sg * (m.m2 * c @ d + m.IC2) * ddm + m.m2 * (G * m.bc + sg * a * m.h2)
                assert m.lambda_if(s, sg, 0.0, 0.0, a) == pytest.approx(expect, rel=1e-12)


def test_M_and_U_are_constrained_B():
    """M: B with θ1 = θ2 and λ_if(σ) = 0 ⇒ same accelerations; U likewise at λ_b = 0."""
    m = TwoBlockModel(*G_REF, G)
    # find the ü_g where λ_if(+1) = 0 in M(+1) at a given state and compare accelerations
    th, w = 0.04, 0.3
    from scipy.optimize import brentq
    a0 = brentq(lambda a: m.lambda_if(1, 1, th, w, a), -20, 20)
    dd = m.accel_M(1, th, a0)
    np.testing.assert_allclose(m.accel_B(1, 1, th, th, w, w, a0), [dd, dd], rtol=1e-8)


# ---------------------------------------------------------------------------- T7
@pytest.mark.parametrize("pre, post, th1, th2, expected", [
    ("M(+1)", "M(-1)", 0, 0, [[0.929850347408]]),
    ("U(+1)", "U(-1)", 0, 0, [[0.876146788991]]),
    ("B(+1,+1)", "B(+1,-1)", 0.07, 0.07,
     [[0.935450553885, 0.064549446115], [0.246437938953, 0.753562061047]]),
    ("B(+1,+1)", "B(+1,-1)", 0.3, 0.3,
     [[0.935450553885, 0.064549446115], [0.246437938953, 0.753562061047]]),
    ("B(+1,-1)", "B(+1,+1)", 0.07, 0.07,
     [[0.976305651224, 0.023694348776], [0.173741771047, 0.826258228953]]),
    ("B(+1,+1)", "B(-1,+1)", 0, 0.0, [[0.794238732550, 0], [0.597179654699, 1]]),
    ("B(+1,+1)", "B(-1,+1)", 0, 0.05, [[0.795605983915, 0], [0.571399977592, 1]]),
    ("B(+1,+1)", "U(+1)", 0, 0.05, [[2.126945790343, 1.0]]),
    ("B(+1,+1)", "M(+1)", 0.07, 0.07, [[0.819080705505, 0.180919294495]]),
    ("M(+1)", "B(-1,+1)", 0, 0, [[0.794238732550], [1.597179654699]]),
    ("M(+1)", "B(-1,-1)", 0, 0, [[0.925131565327], [0.951213814289]]),
])
def test_T7_impact_maps(pre, post, th1, th2, expected):
    m = TwoBlockModel(*G_REF, G)
    np.testing.assert_allclose(m.impact_map(pre, post, th1, th2), expected, rtol=1e-10,
                               atol=1e-12)


def test_closed_form_maps_3_and_4():
    """§3.4 closed forms 3 (base) and 4 (interface) vs the general law, all signs."""
    m = TwoBlockModel(*G_REF, G)
    b1, h1, m1, i1, bc, h2, m2, i2 = m.b1, m.h1, m.m1, m.I1, m.bc, m.h2, m.m2, m.I2
    r1s, r2s = b1**2 + h1**2, bc**2 + h2**2
    for s1 in (1, -1):
        for s2 in (1, -1):
            th2 = 0.037 * s2  # consistent with the sign of φ = θ2 − θ1
            cm = np.array([s2 * bc - s1 * b1, 2 * h1])
            cp = np.array([s2 * bc + s1 * b1, 2 * h1])
            d = np.array([-s2 * bc * math.cos(th2) + h2 * math.sin(th2),
                          s2 * bc * math.sin(th2) + h2 * math.cos(th2)])
            nn = np.array([[i1 + m1 * (h1**2 - b1**2) + m2 * (bc**2 - b1**2 + 4 * h1**2),
                            m2 * cp @ d], [m2 * d @ cm, i2 + m2 * r2s]])
            mp = np.array([[i1 + m1 * r1s + m2 * cp @ cp, m2 * cp @ d],
                           [m2 * cp @ d, i2 + m2 * r2s]])
            pre, post = Pattern(s1, s2), Pattern(-s1, s2)
            np.testing.assert_allclose(m.impact_map(pre, post, 0.0, th2),
                                       np.linalg.solve(mp, nn), rtol=1e-12, atol=1e-14)
            k = s1 * s2
            nn4 = np.array([[i1 + m1 * r1s + m2 * (b1**2 - bc**2 + 4 * h1**2),
                             m2 * (bc**2 + k * b1 * bc + 2 * h1 * h2)],
                            [m2 * (bc**2 - k * b1 * bc + 2 * h1 * h2), i2 + m2 * (h2**2 - bc**2)]])
            off = m2 * (2 * h1 * h2 - bc**2 - k * b1 * bc)
            mp4 = np.array([[i1 + m1 * r1s + m2 * ((b1 + k * bc) ** 2 + 4 * h1**2), off],
                            [off, i2 + m2 * r2s]])
            th = 0.03 * s1
            pm = m.impact_map(Pattern(s1, s2), Pattern(s1, -s2), th, th)
            np.testing.assert_allclose(pm, np.linalg.solve(mp4, nn4), rtol=1e-12, atol=1e-14)
            np.testing.assert_allclose(pm @ [1, 1], [1, 1], rtol=1e-12)


@pytest.mark.parametrize("pre, kind, th1, th2, w1, w2, post, expected", [
    ("M(+1)", "base", 0, 0, -0.3, -0.3, "B(-1,-1)", (-0.2775394696, -0.2853641443)),
    ("U(+1)", "interface", 0, 0, 0, -0.5, "B(-1,-1)", (-0.0118471744, -0.4131291145)),
    ("B(+1,+1)", "base", 0, 0.05, -0.2, 0.1, "B(-1,+1)", (-0.1591211968, -0.0142799955)),
    ("B(+1,+1)", "interface", 0.07, 0.07, 0.1, -0.2, "B(+1,-1)", (0.0806351662, -0.1260686183)),
])
def test_T7_selected_outcomes(pre, kind, th1, th2, w1, w2, post, expected):
    m = TwoBlockModel(*G_REF, G)
    p, a1, a2 = m.impact_outcome(pre, kind, th1, th2, w1, w2)
    assert p.name == post
    assert (a1, a2) == pytest.approx(expected, abs=1e-10)


def test_legacy_rule_keeps_monolithic():
    m = TwoBlockModel(*G_REF, G)
    p, a1, a2 = m.impact_outcome("M(+1)", "base", 0, 0, -0.3, -0.3, legacy=True)
    assert p.name == "M(-1)"
    assert a1 == a2 == pytest.approx(0.929850347408 * -0.3, rel=1e-11)


def test_random_impacts_never_gain_energy():
    rng = np.random.default_rng(1)
    for _ in range(200):
        lo = uniform(rng.uniform(0.2, 1.0), rng.uniform(0.3, 2.0))
        up = uniform(rng.uniform(0.1, 1.0), rng.uniform(0.3, 2.0))
        m = TwoBlockModel(lo, up, G)
        s1, s2 = rng.choice([-1, 1], 2)
        w = rng.normal(size=2)
        case = rng.integers(4)
        # pre-impact rates with the closing gap approaching (s·gap rate < 0)
        if case == 0:
            w1, w2 = -s1 * abs(w[0]), w[1]
            pre, kind, th1, th2 = Pattern(s1, s2), "base", 0.0, s2 * 0.05
        elif case == 1:
            w1 = w[0]
            w2 = w1 - s2 * abs(w[1])
            pre, kind, th1, th2 = Pattern(s1, s2), "interface", s1 * 0.04, s1 * 0.04
        elif case == 2:
            w1 = w2 = -s1 * abs(w[0])
            pre, kind, th1, th2 = Pattern(s1, 0), "base", 0.0, 0.0
        else:
            w1, w2 = 0.0, -s2 * abs(w[1])
            pre, kind, th1, th2 = Pattern(0, s2), "interface", 0.0, 0.0
        post, a1, a2 = m.impact_outcome(pre, kind, th1, th2, w1, w2)
        t_pre = m.kinetic_energy(pre, th1, th2, w1, w2)
        t_post = m.kinetic_energy(post, th1, th2, a1, a2)
        assert t_post <= t_pre * (1 + 1e-12)
        # the selected outcome is kinematically admissible for the impacting contact
        st = post.base if kind == "base" else post.iface
        rate = a1 if kind == "base" else a2 - a1
        assert st * rate >= -1e-12


# ----------------------------------------------------------------- T4, T5: limits
def test_T4_monolithic_limit_free_rocking():
    lo, up = uniform(0.5, 1.5), uniform(0.5, 1.0)
    m = TwoBlockModel(lo, up, G)
    alpha, r, p, eta = housner_constants(0.5, 2.5)
    assert (m.alphaM, m.RM, m.pM, m.etaM) == pytest.approx((alpha, r, p, eta), rel=1e-13)
    th0 = 0.5 * m.alphaM
    sol = solve_two_blocks(lo, up, g=G, accel=zero_accel, theta0=(th0, th0),
                           t_out=np.linspace(0, 6, 601))
    times = sol.impact_times[:5]
    ref = free_impact_times(p, alpha, eta, th0, 5)
    np.testing.assert_allclose(times, ref, atol=1e-8)
    np.testing.assert_allclose(times, T3_TIMES, atol=2e-9)
    assert all(name.startswith("M") for _, name in sol.patterns)
    np.testing.assert_array_equal(sol.theta[:, 0], sol.theta[:, 1])


def test_T5_upper_block_on_heavy_wide_base():
    lo, up = uniform(2.0, 0.5), uniform(0.5, 2.5)
    m = TwoBlockModel(lo, up, G)
    alpha, r, p, eta = housner_constants(0.5, 2.5)
    th0 = 0.5 * m.alpha2
    sol = solve_two_blocks(lo, up, g=G, accel=zero_accel, theta0=(0.0, th0),
                           t_out=np.linspace(0, 5.6, 5601))
    np.testing.assert_allclose(sol.impact_times[:5], free_impact_times(p, alpha, eta, th0, 5),
                               atol=1e-8)
    assert all(name.startswith("U") for _, name in sol.patterns)
    assert np.all(sol.theta[:, 0] == 0.0)
    s2 = np.where(sol.theta[:, 1] < 0, -1, 1)
    lam = [min(m.lambda_b(int(s), sg, th, w, 0.0) for sg in (1, -1))
           for s, th, w in zip(s2, sol.theta[:, 1], sol.theta_dot[:, 1], strict=True)]
    assert min(lam) > 0


# ----------------------------------------------------------------------- T8, T9
def test_T8_energy_conservation_free_motion():
    sol = solve_two_blocks(*G_REF, g=G, accel=zero_accel, theta0=(0.02, 0.10),
                           pattern="B(+1,+1)", t_out=np.linspace(0, 3, 3001))
    e = sol.energy()
    assert e[0] == pytest.approx(183704.468597742, abs=1e-6)
    t_imp, kind, pre, post = sol.impacts[0]
    assert t_imp == pytest.approx(0.2184666635, abs=1e-9)
    assert (kind, pre, post) == ("base", "B(+1,+1)", "B(-1,+1)")
    # conservation between impacts, non-increase across impacts
    edges = np.concatenate([[0.0], sol.impact_times, [np.inf]])
    ok = ~np.isnan(e)
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        seg = ok & (sol.t > a) & (sol.t < b)
        if seg.sum() > 1:
            assert np.ptp(e[seg]) < 1e-8 * e[0]
    assert np.all(np.diff(e[ok]) < 1e-8 * e[0])
    assert sum(sol.impact_losses) > 0 and min(sol.impact_losses) >= -1e-9


@pytest.mark.parametrize("ap, de, w, dt", [
    (3.0, 1208.616000, 2698.112970, 1489.496979),
    (4.0, 4798.715391, 6227.581632, 1428.866241),
])
def test_T9_energy_balance(ap, de, w, dt):
    sol = run_pulse(G_REF, ap, 5.0)
    e = sol.energy()
    last = np.flatnonzero(~np.isnan(e))[-1]
    assert sol.status == "overturned"
    assert e[last] - e[0] == pytest.approx(de, rel=1e-6)
    assert sol.work[last] == pytest.approx(w, rel=1e-6)
    assert sum(sol.impact_losses) == pytest.approx(dt, rel=1e-6)
    # the balance holds sample by sample
    ok = ~np.isnan(e)
    t_imp, losses = sol.impact_times, np.array(sol.impact_losses)
    cum = np.array([losses[t_imp <= t].sum() for t in sol.t[ok]])
    np.testing.assert_allclose(e[ok] - e[0], sol.work[ok] - cum, atol=1e-7 * w)


# -------------------------------------------------------------------- T10, T11
T11 = {
    3.0: dict(init=0.132206115584, uplift=0.4826074905,
              impacts=[(0.623745395, "base", "B(+1,-1)"), (0.664275039, "interface", "B(+1,+1)"),
                       (0.994762049, "interface", None), (1.021497930, "interface", None),
                       (1.774522763, "base", None)],
              over=3.69272, over_tol=1e-5),
    4.0: dict(init=0.093409543237, uplift=0.4942018618,
              impacts=[(0.773257301, "base", None), (0.954925181, "interface", None),
                       (1.650978036, "base", None)],
              over=1.8191538, over_tol=2e-7),
}


@pytest.fixture(scope="module")
def t11_runs():
    return {(ap, sg): run_pulse(G_REF, ap, 4.0, sign=sg) for ap in (3.0, 4.0) for sg in (1, -1)}


@pytest.mark.parametrize("ap", [3.0, 4.0])
def test_T11_event_times(t11_runs, ap):
    sol = t11_runs[(ap, 1.0)]
    ref = T11[ap]
    m = sol.model
    # initiation: closed form arcsin(g tan αM / a_p) / ω_p
    t_init = math.asin(G * math.tan(m.alphaM) / ap) / (2 * math.pi)
    assert t_init == pytest.approx(ref["init"], abs=1e-12)
    assert sol.patterns[0] == (0.0, "R")
    assert sol.patterns[1][1] == "M(-1)"
    assert sol.patterns[1][0] == pytest.approx(t_init, abs=1e-11)
    assert sol.patterns[2][1] == "B(-1,-1)"
    assert sol.patterns[2][0] == pytest.approx(ref["uplift"], abs=2e-10)
    assert len(sol.impacts) >= len(ref["impacts"])
    for (t, kind, post), got in zip(ref["impacts"], sol.impacts[: len(ref["impacts"])],
                                    strict=True):
        assert got[0] == pytest.approx(t, abs=2e-9)
        assert got[1] == kind
        if post:
            assert got[3] == post
    assert sol.status == "overturned" and sol.overturned_block == "upper"
    assert sol.overturn_time == pytest.approx(ref["over"], abs=ref["over_tol"])


def test_T11_post_impact_state():
    """State right after the first base impact, a_p = 3: [0, −0.0056071, 0.117667, 0.1170335]."""
    acc, te = sine_pulse(3.0)
    t_imp = 0.623745395
    t_after = 0.6237454  # 5e-9 s after the impact
    sol = solve_two_blocks(*G_REF, g=G, accel=acc, breakpoints=(te,), end_time=te,
                           t_out=np.array([0.0, t_after]))
    assert sol.impacts[0][0] == pytest.approx(t_imp, abs=2e-9) and t_after > sol.impacts[0][0]
    # extrapolate back to the impact instant with the post-impact rates (1e-7 s later)
    th = sol.theta[1] - sol.theta_dot[1] * (sol.t[1] - sol.impacts[0][0])
    np.testing.assert_allclose(th, [0.0, -0.0056071], atol=5e-8)
    np.testing.assert_allclose(sol.theta_dot[1], [0.117667, 0.1170335], atol=2e-6)


@pytest.mark.parametrize("ap", [3.0, 4.0])
def test_T10_mirror_symmetry(t11_runs, ap):
    a, b = t11_runs[(ap, 1.0)], t11_runs[(ap, -1.0)]
    np.testing.assert_allclose(b.impact_times, a.impact_times, atol=1e-9)
    assert [x[1] for x in b.impacts] == [x[1] for x in a.impacts]
    flip = {"+": "-", "-": "+"}
    mirrored = ["".join(flip.get(ch, ch) for ch in n) for _, n in a.patterns]
    assert [n for _, n in b.patterns] == mirrored
    ok = ~np.isnan(a.theta[:, 0])
    np.testing.assert_allclose(b.theta[ok], -a.theta[ok], atol=1e-8)
    assert b.overturn_time == pytest.approx(a.overturn_time, abs=1e-8)


def test_T11b_upper_block_first():
    sol = run_pulse(G_U, 3.0, 2.5)
    m = sol.model
    assert m.thr_upper == pytest.approx(1.962) and m.thr_stack == pytest.approx(3.924)
    assert [n for _, n in sol.patterns[:4]] == ["R", "U(-1)", "U(+1)", "B(+1,+1)"]
    assert sol.patterns[1][0] == pytest.approx(0.113455189122, abs=1e-11)
    t_imp, kind, pre, post = sol.impacts[0]
    assert t_imp == pytest.approx(0.727579655, abs=2e-9)
    assert (kind, pre, post) == ("interface", "U(-1)", "U(+1)")
    assert sol.patterns[3][0] == pytest.approx(2.0095749602, abs=2e-9)
    assert sol.overturn_time == pytest.approx(2.0313602, abs=2e-7)
    # post-impact rate: sample 1e-7 s after the impact
    s2 = solve_two_blocks(*G_U, g=G, accel=sine_pulse(3.0)[0], breakpoints=(1.0,),
                          end_time=1.0, t_out=[0.0, t_imp + 1e-7])
    assert s2.theta_dot[1, 1] == pytest.approx(0.454801064, abs=1e-6)
    assert s2.theta_dot[1, 0] == 0.0


# ------------------------------------------------------------------- T12, T13, thresholds
def heavy_base_with(b2: float, h2: float) -> tuple[BlockParams, BlockParams]:
    """A single block (b2, h2) on a very heavy wide base: pattern U only."""
    return uniform(4.0, 0.5, rho=1e4 * RHO), uniform(b2, h2)


@pytest.mark.parametrize("factor, overturns", [(1.0005, True), (0.9995, False)])
def test_T12_rectangular_pulse_in_U(factor, overturns):
    ap = 3.4300270873 * factor
    t1 = 0.5

    def acc(t):
        t = np.asarray(t, float)
        return np.where((t >= 0) & (t <= t1), ap, 0.0)

    sol = solve_two_blocks(*heavy_base_with(0.5, 2.5), g=G, accel=acc, breakpoints=(t1,),
                           end_time=t1, t_out=np.linspace(0, 7.0, 71))
    assert sol.patterns[1] == (0.0, "U(-1)")
    assert (sol.status == "overturned") is overturns
    if overturns:  # mode 1: over the top without any impact (after ~6 s)
        assert sol.overturned_block == "upper" and not sol.impacts
    else:  # it falls back onto the lower block
        assert sol.impacts[0][1:3] == ("interface", "U(-1)")


@pytest.mark.parametrize("ratio_wp, amin", [(2.0, 1.219869), (4.0, 1.725529)])
@pytest.mark.parametrize("factor", [1.0005, 0.9995])
def test_T13_sine_pulse_minimum_overturning_in_U(ratio_wp, amin, factor):
    alpha, r, p, eta = housner_constants(0.5, 2.5)
    wp = ratio_wp * p
    ap = factor * amin * G * math.tan(alpha)
    te = 2 * math.pi / wp

    def acc(t):
        t = np.asarray(t, float)
        return np.where((t >= 0) & (t <= te), ap * np.sin(wp * t), 0.0)

    sol = solve_two_blocks(*heavy_base_with(0.5, 2.5), g=G, accel=acc, breakpoints=(te,),
                           end_time=te, t_out=np.linspace(0, te + 8.0, 201))
    assert all(n[0] in "RU" for _, n in sol.patterns)
    assert (sol.status == "overturned") is (factor > 1)
    if factor > 1:
        assert len(sol.impacts) == 1  # mode 2: overturning after one impact


@pytest.mark.parametrize("blocks, pattern", [(G_REF, "M(-1)"), (G_U, "U(-1)")])
def test_initiation_threshold(blocks, pattern):
    thr = TwoBlockModel(*blocks, G).threshold
    t_out = np.linspace(0, 0.3, 31)
    for factor, moves in ((1 - 1e-6, False), (1 + 1e-6, True)):
        a = factor * thr
        sol = solve_two_blocks(*blocks, g=G, accel=lambda t, a=a: np.full_like(
            np.asarray(t, float), a), t_out=t_out)
        if moves:
            assert sol.patterns[:2] == [(0.0, "R"), (0.0, pattern)]
            assert np.all(sol.theta[1:, 0 if pattern[0] == "M" else 1] < 0)
        else:
            assert sol.patterns == [(0.0, "R")] and np.all(sol.theta == 0)


def test_initiation_from_sine_just_below_and_above():
    m = TwoBlockModel(*G_REF, G)
    for factor, moves in ((0.999999, False), (1.000001, True)):
        sol = run_pulse(G_REF, factor * m.threshold, 1.2)
        assert (len(sol.patterns) > 1) is moves
        if moves:
            assert sol.patterns[1][1] == "M(-1)"
            assert sol.patterns[1][0] == pytest.approx(0.25, abs=2e-3)


def test_zeno_free_rocking_comes_to_rest():
    lo, up = uniform(0.5, 1.5), uniform(0.5, 1.0)
    th0 = 0.5 * TwoBlockModel(lo, up, G).alphaM
    sol = solve_two_blocks(lo, up, g=G, accel=zero_accel, theta0=(th0, th0),
                           t_out=np.linspace(0, 25, 251))
    assert sol.status == "ok" and sol.patterns[-1][1] == "R"
    assert np.all(sol.theta[-10:] == 0) and len(sol.impacts) < 1000


# ------------------------------------------------------------ reference (Scenario)
def _housner_single(p, alpha, eta, theta0, t_out, acc, t_break, thr):
    """Minimal independent Housner integrator (nonlinear, impacts θ̇⁺ = η θ̇⁻)."""
    out = np.zeros_like(t_out)
    t, y = 0.0, np.array([theta0, 0.0])
    impacts = []
    if theta0 == 0.0:  # wait for |ü_g| > g tan α on a fine grid + bisection
        ts = np.linspace(0, t_break, 200001)
        i = int(np.argmax(np.abs(acc(ts)) > thr))
        lo_, hi_ = ts[i - 1], ts[i]
        for _ in range(80):
            mid = 0.5 * (lo_ + hi_)
            lo_, hi_ = (mid, hi_) if abs(acc(mid)) <= thr else (lo_, mid)
        t = hi_
        s = -np.sign(acc(hi_))
    else:
        s = np.sign(theta0)
    armed = theta0 != 0.0
    while t < t_out[-1]:
        def f(tt, yy, s=s):
            arg = s * alpha - yy[0]
            return [yy[1], -p * p * (math.sin(arg) + float(acc(tt)) / G * math.cos(arg))]

        def hit(tt, yy, s=s, armed=armed):
            return s * yy[0] if armed else s * yy[0] - 1e-11
        hit.terminal, hit.direction = True, (-1 if armed else 1)
        t_stop = t_break if t < t_break else t_out[-1]
        sol = solve_ivp(f, (t, t_stop), y, method="DOP853", rtol=1e-11, atol=1e-13,
                        events=hit, dense_output=True)
        mask = (t_out >= t) & (t_out <= sol.t[-1])
        if mask.any():
            out[mask] = sol.sol(t_out[mask])[0]
        t, y = sol.t[-1], sol.y[:, -1].copy()
        if sol.status == 1 and armed:
            impacts.append(t)
            y = np.array([0.0, eta * y[1]])
            s = -s
            armed = False
        elif sol.status == 1:
            armed = True
        if len(impacts) >= 6:
            out[t_out > t] = np.nan
            break
    return out, impacts


@pytest.mark.parametrize("kind", ["free", "pulse"])
def test_reference_monolithic_limit(kind):
    """Wide squat upper block: the stack rocks as the equivalent single (chamfered) block."""
    lower = Block(width=0.30, depth=0.3, height=1.2, density=2500.0, chamfer=0.01)
    upper = Block(width=0.50, depth=0.3, height=0.15, density=2500.0, chamfer=0.01)
    if kind == "free":
        sc = Scenario("mono-free", stack((lower, upper)), excitation=Free(), initial_tilt=0.5,
                      duration=2.5, output_rate=200.0)
    else:
        sc = Scenario("mono-pulse", stack((lower, upper)), excitation=SinePulse(2.0, 0.02),
                      duration=2.5, output_rate=200.0)
    tr = two_block_reference(sc)
    assert tr.status == Status.OK and tr.engine == "analytic"
    assert all(n[0] in "MR" for _, n in tr.extra["patterns"])
    # equivalent single block from first principles (pivots at b − c on the face)
    m1, m2 = lower.m, upper.m
    b = lower.b - lower.chamfer
    z1, z2 = lower.h, lower.height + upper.h
    mt = m1 + m2
    zbar = (m1 * z1 + m2 * z2) / mt
    i1 = m1 * (lower.width**2 + lower.height**2) / 12
    i2 = m2 * (upper.width**2 + upper.height**2) / 12
    i_o = i1 + m1 * (b * b + z1 * z1) + i2 + m2 * (b * b + z2 * z2)
    rr = math.hypot(b, zbar)
    alpha = math.atan2(b, zbar)
    p = math.sqrt(mt * G * rr / i_o)
    eta = 1 - 2 * mt * b * b / i_o
    exc = sc.excitation
    theta0 = 0.5 * math.atan2(b, lower.h) if kind == "free" else 0.0
    t_break = exc.end_time if kind == "pulse" else 0.0
    ref, imp = _housner_single(p, alpha, eta, theta0, tr.t, exc.acceleration, t_break,
                               G * math.tan(alpha))
    ok = ~np.isnan(ref)
    assert ok.sum() > 100 and len(imp) >= 2
    np.testing.assert_allclose(tr.theta[ok, 0], ref[ok], atol=1e-6 * alpha)
    np.testing.assert_allclose(tr.theta[ok, 1], ref[ok], atol=1e-6 * alpha)
    np.testing.assert_allclose(tr.impacts[: len(imp)], imp, atol=1e-8)
    # centroids in the ground frame: rotation about the active pivot + base displacement
    th = tr.theta[ok, 0]
    s = np.where(th < 0, -1.0, 1.0)
    ug = exc.displacement(tr.t[ok])
    for j, zc in enumerate((z1, z2)):
        dx, dz = -s * b, zc
        x = s * b + dx * np.cos(th) + dz * np.sin(th) + ug
        z = -dx * np.sin(th) + dz * np.cos(th)
        np.testing.assert_allclose(tr.x[ok, j], x, atol=1e-12)
        np.testing.assert_allclose(tr.z[ok, j], z, atol=1e-12)
    assert tr.scenario == sc.name and tr.engine_version.startswith("twoblock-")


def test_reference_rejects_unsupported():
    blk = Block(width=0.2, depth=0.2, height=0.6, density=2000.0)
    with pytest.raises(UnsupportedScenario):
        two_block_reference(Scenario("one", stack((blk,))))
    with pytest.raises(UnsupportedScenario):
        two_block_reference(Scenario("three", stack((blk, blk, blk))))
    with pytest.raises(UnsupportedScenario):
        two_block_reference(Scenario("off", stack((blk, blk), offsets=(0.0, 0.01))))


def test_reference_paper_case_completes():
    bottom = Block(width=0.20, depth=0.40, height=0.60, density=2670, chamfer=0.005)
    top = Block(width=0.15, depth=0.55, height=0.60, density=2670, chamfer=0.005)
    sc = Scenario("stack-pulse-5.0hz-4mm", stack((bottom, top)),
                  excitation=SinePulse(5.0, 0.004), duration=4.0, output_rate=1000.0)
    tr = two_block_reference(sc)
    assert tr.status.completed and tr.theta.shape == (4001, 2)
    assert tr.wall_time < 5.0
    assert np.nanmax(np.abs(tr.theta[:, 1])) > np.nanmax(np.abs(tr.theta[:, 0]))
    assert tr.extra["patterns"][0] == [0.0, "R"]


def test_reference_overturn_and_record_input():
    lower = Block(width=0.30, depth=0.3, height=1.2, density=2500.0, chamfer=0.01)
    upper = Block(width=0.50, depth=0.3, height=0.15, density=2500.0, chamfer=0.01)
    sc = Scenario("mono-over", stack((lower, upper)), excitation=SinePulse(2.0, 0.03),
                  duration=2.5, output_rate=200.0)
    tr = two_block_reference(sc)
    assert tr.status == Status.OVERTURNED
    t_over = tr.extra["overturn_time"]
    assert tr.extra["overturned_block"] in ("stack", "lower", "upper") and 0 < t_over < 2.5
    # the samples end at the last output time before the overturn, with no NaN
    assert tr.t[-1] < t_over <= tr.t[-1] + 1 / sc.output_rate
    assert np.all(np.isfinite(tr.theta)) and np.all(np.isfinite(tr.x))
    assert np.max(np.abs(tr.theta)) <= math.pi / 2
    # a recorded accelerogram (piecewise linear, restarts at every sample) runs too
    t = np.linspace(0, 0.5, 101)
    rec = Record(t, 4.0 * np.sin(2 * np.pi * 2.0 * t))
    tr2 = two_block_reference(sc.replace(name="rec", excitation=rec, duration=1.5))
    assert tr2.status.completed and tr2.extra["patterns"][1][1] == "M(-1)"


def test_max_phases_cap_reports_incomplete():
    lo, up = uniform(0.5, 1.5), uniform(0.5, 1.0)
    th0 = 0.5 * TwoBlockModel(lo, up, G).alphaM
    sol = solve_two_blocks(lo, up, g=G, accel=zero_accel, theta0=(th0, th0),
                           t_out=np.linspace(0, 25, 251), max_phases=5)
    assert sol.status == "incomplete" and "max_phases" in sol.message
    assert np.isnan(sol.theta[-1, 0]) and np.isfinite(sol.theta[0, 0])


def test_kick_of_lower_block_and_legacy_rule():
    """bc = b1: the upper block's impact always kicks the (heavy) lower block (§3.5
    criterion b1 ≥ bc + 2 h1 h2 (1 − η2) / ((1 + η2) bc) violated); legacy keeps U."""
    lo, up = uniform(0.3, 0.3, rho=100 * RHO), uniform(0.5, 2.0)
    m = TwoBlockModel(lo, up, G)
    assert m.thr_upper < m.thr_stack
    assert lo.b < m.bc + 2 * lo.h * up.h * (1 - m.eta2) / ((1 + m.eta2) * m.bc)
    th0 = 0.5 * m.alpha2
    kw = dict(g=G, accel=zero_accel, theta0=(0.0, th0), t_out=np.linspace(0, 2.5, 251))
    new = solve_two_blocks(lo, up, **kw)
    old = solve_two_blocks(lo, up, **kw, legacy=True)
    assert new.patterns[0] == (0.0, "U(+1)") and old.patterns[0] == (0.0, "U(+1)")
    assert new.impacts[0][1:3] == ("interface", "U(+1)") and new.impacts[0][3].startswith("B(")
    assert old.impacts[0][1:] == ("interface", "U(+1)", "U(-1)")
    assert old.impacts[0][0] == pytest.approx(new.impacts[0][0], abs=1e-12)
    # legacy: single-block Housner on the resting lower block, pivots at ±bc (= b1)
    bc = lo.b
    r = math.hypot(bc, up.h)
    i_c = up.I + up.m * r * r
    alpha, p, eta = math.atan2(bc, up.h), math.sqrt(up.m * G * r / i_c), 1 - 2 * up.m * bc**2 / i_c
    np.testing.assert_allclose(old.impact_times[:2], free_impact_times(p, alpha, eta, th0, 2),
                               atol=1e-8)


# --------------------------------------------------------- statuses of overturning runs
#: A slender lower block under a squat, wide top (which cannot lift first: its uplift
#: threshold g bc/h2 is 10× the stack's), 1 Hz sine pulse of 10 m/s²: the whole stack
#: goes over during the first excursion (mode 1 of the monolithic block).
WHOLE = Scenario("whole-stack-over",
                 stack((Block(0.30, 0.3, 1.2, density=2500.0),
                        Block(0.50, 0.3, 0.15, density=2500.0))),
                 excitation=SinePulse.from_acceleration(10.0, 2 * math.pi), duration=1.5)
#: The paper's stack under the 5 Hz pulse at 20 mm (issue 15): the top block alone goes.
TOP = get_scenario("stack-pulse-5.0hz-4mm").replace(excitation=SinePulse(5.0, 0.02),
                                                      duration=1.5)


def test_whole_stack_overturn_is_reported_with_time_and_block():
    tr = two_block_reference(WHOLE)
    mono = WHOLE.geometry.column.monolithic(G)
    housner = pulse_outcome(mono, WHOLE.excitation, g=G)
    assert housner.overturned and housner.impacts == 0  # mode 1 of the monolithic stack
    assert tr.status is Status.OVERTURNED
    # the stack rocks in M, the top tips on the falling lower block only at the end:
    # the lower block (carrying the top) is the one that passes 90°, near Housner's time
    assert [n for _, n in tr.extra["patterns"]] == ["R", "M(-1)", "B(-1,+1)"]
    assert tr.extra["overturned_block"] == "lower"
    assert tr.extra["overturn_time"] == pytest.approx(housner.overturn_time, abs=5e-3)
    assert "lower block overturned" in tr.message
    assert tr.t[-1] < tr.extra["overturn_time"] and np.all(np.isfinite(tr.theta))
    # the runner's check keeps the reference's status (the NaN tail made it "unstable")
    assert check_trajectory(tr, WHOLE) is tr


def test_top_block_alone_overturn_is_reported_with_time_and_block():
    tr = two_block_reference(TOP)
    assert tr.status is Status.OVERTURNED and tr.extra["overturned_block"] == "upper"
    assert tr.extra["overturn_time"] == pytest.approx(0.669871, abs=1e-6)
    assert "upper block overturned" in tr.message
    # the upper block reaches 90° while the lower one stays below its own critical angle
    assert abs(tr.theta[-1, 1]) > 1.5
    assert np.max(np.abs(tr.theta[:, 0])) < TOP.blocks[0].rocking(G).lam
    assert tr.t.size == 670 and np.all(np.isfinite(tr.theta))
    assert check_trajectory(tr, TOP) is tr
    # the reference row of a study (issue 15: it said "unstable")
    row = run_job(Job(TOP, "analytic", {}))
    assert row.status is Status.OVERTURNED and row.extra["overturned_block"] == "upper"


@pytest.mark.parametrize("sc, block, t_over", [(WHOLE, 1, 0.754069), (TOP, 2, 0.669871)])
def test_an_engine_overturns_the_same_block_at_the_same_time(sc, block, t_over):
    pytest.importorskip("pymunk")
    tr = run_job(Job(sc, "pymunk", dict(engine_class("pymunk").presets["accurate"])))
    assert tr.status is Status.OVERTURNED and f"block {block} overturned" in tr.message
    assert tr.t[-1] == pytest.approx(t_over, abs=0.01)
    assert two_block_reference(sc).status is tr.status


def _engine_like(theta: np.ndarray, status: Status = Status.OK, message: str = "") -> Trajectory:
    n = theta.shape[0]
    t = np.arange(n) / 100.0
    x = np.zeros(theta.shape)
    return Trajectory(t=t, theta=theta, x=x, z=np.full(theta.shape, 0.5), status=status,
                      message=message, engine="fake")


def test_a_block_past_90_degrees_is_overturned_whatever_the_engine_reported():
    sc = Scenario("b", Block(0.2, 0.2, 1.0, mass=1.0), duration=1.0, output_rate=100.0)
    n = 60
    fall = np.linspace(0.0, 2.5, n)  # 0.0424 rad per 10 ms: within the speed bound
    theta = np.column_stack([np.zeros(n), fall])
    i = int(np.argmax(fall >= math.pi / 2))
    ok = check_trajectory(_engine_like(theta), sc)
    assert ok.status is Status.OVERTURNED and ok.t.size == i + 1
    assert ok.message.startswith(f"block 2 past 90° at t = {ok.t[-1]:.4g} s")
    assert "reported ok" in ok.message
    # an unwrapped angle (3.5 rad is −2.78 rad wrapped) counts the same
    spun = np.concatenate([np.linspace(0.0, 1.2, 30), np.linspace(1.24, 3.5, n - 30)])
    k = int(np.argmax(spun >= math.pi / 2))
    over = check_trajectory(_engine_like(spun[:, None] + 2 * math.pi), sc)
    assert over.status is Status.OVERTURNED and over.t.size == k + 1
    # "unstable" after the block fell over: it fell over
    late_nan = theta.copy()
    late_nan[-1] = np.nan
    fell = check_trajectory(_engine_like(late_nan, Status.UNSTABLE, "NaN at the end"), sc)
    assert fell.status is Status.OVERTURNED and fell.t.size == i + 1
    # but a NaN before the fall is a failure, not an overturn
    early_nan = theta.copy()
    early_nan[5, 0] = np.nan
    bad = check_trajectory(_engine_like(early_nan), sc)
    assert bad.status is Status.UNSTABLE and bad.t.size == 6 and "NaN" in bad.message
    verdict = _engine_like(early_nan, Status.UNSTABLE, "engine's reason")
    assert check_trajectory(verdict, sc) is verdict
    # an engine that stopped at the first sample past 90° keeps its own message
    own = _engine_like(theta[:i + 1], Status.OVERTURNED, "block 2 overturned")
    assert check_trajectory(own, sc) is own
    # upright runs and failed runs are untouched
    calm = _engine_like(np.zeros((n, 2)))
    assert check_trajectory(calm, sc) is calm
    crashed = Trajectory.failed(Status.CRASHED, "boom", n_blocks=2)
    assert check_trajectory(crashed, sc) is crashed


# ------------------------------------------------- vertical base motion (g → g + ü_z, §0)
def static_threshold(blocks) -> float:
    """min(b_c/h2, b1/ȳ): |ü_g| / (g + ü_z) at which a resting stack starts (§3.1),
    from the block parameters alone."""
    lo, up = blocks
    ybar = (lo.m * lo.h + up.m * (2 * lo.h + up.h)) / (lo.m + up.m)
    return min(min(lo.b, up.b) / up.h, lo.b / ybar)


def constant(c: float):
    return lambda t: c * np.ones_like(np.asarray(t, float))


@pytest.mark.parametrize("blocks, c, ap", [(G_REF, 2.0, 3.6), (G_U, -2.0, 2.5)])
def test_a_constant_vertical_acceleration_is_a_change_of_gravity(blocks, c, ap):
    """In a base accelerating up at c the blocks weigh m (g + c): the motion is that of
    the model with gravity g + c (the same w_rest: it is a numerical setting), and the
    vertical inertial force −m c does the work of a uniform field, −c Σ m Δz_G."""
    acc, te = sine_pulse(ap)
    m0 = TwoBlockModel(*blocks, G)
    kw = dict(accel=acc, breakpoints=(te,), end_time=te, t_out=np.linspace(0, 4, 4001),
              w_rest=1e-3 * min(m0.pM * m0.alphaM, m0.p2 * m0.alpha2))
    moving = solve_two_blocks(*blocks, g=G, vertical=constant(c), **kw)
    heavy = solve_two_blocks(*blocks, g=G + c, **kw)
    assert [n for _, n in moving.patterns] == [n for _, n in heavy.patterns]
    assert len(moving.patterns) >= 4 and moving.status == heavy.status
    np.testing.assert_allclose([t for t, _ in moving.patterns], [t for t, _ in heavy.patterns],
                               rtol=0, atol=1e-9)
    np.testing.assert_allclose(moving.impact_times, heavy.impact_times, rtol=0, atol=1e-9)
    np.testing.assert_allclose(moving.theta, heavy.theta, rtol=0, atol=1e-9)
    # the work of −m c on the centroids' heights (the horizontal work is the same in both)
    g1, g2 = m0.positions(moving.theta[:, 0], moving.theta[:, 1])
    lo, up = blocks
    w_z = -c * (lo.m * (g1[:, 1] - g1[0, 1]) + up.m * (g2[:, 1] - g2[0, 1]))
    ok = np.isfinite(w_z)
    np.testing.assert_allclose(moving.work[ok] - heavy.work[ok], w_z[ok], rtol=0,
                               atol=1e-7 * np.max(np.abs(w_z[ok])))


@pytest.mark.parametrize("ap, az", [(3.0, 4.0), (3.0, -4.0), (3.5, 6.0)])
def test_energy_balance_with_horizontal_and_vertical_motion(ap, az):
    """T + V(g) − W_base + Σ impact losses is constant, with W_base the work of both
    inertial forces of the accelerating base frame, −m ü_g along x and −m ü_z along z."""
    acc, te = sine_pulse(ap)

    def vert(t):
        t = np.asarray(t, float)
        return np.where((t >= 0) & (t <= te), az * np.sin(3 * math.pi * t), 0.0)

    sol = solve_two_blocks(*G_REF, g=G, accel=acc, vertical=vert, breakpoints=(te,),
                           end_time=te, t_out=np.linspace(0, 4, 4001))
    e = sol.energy()
    ok = ~np.isnan(e)
    assert len(sol.impacts) >= 3 and ok.sum() > 1000
    t_imp, losses = sol.impact_times, np.array(sol.impact_losses)
    cum = np.array([losses[t_imp <= t].sum() for t in sol.t[ok]])
    scale = np.max(np.abs(e[ok] - e[0]))
    np.testing.assert_allclose(e[ok] - e[0], sol.work[ok] - cum, rtol=0, atol=1e-8 * scale)
    # W_base split by axis, as Stieltjes sums −Σ ü(t_mid) Σ m Δx_G on the samples: the
    # vertical part matters (the balance above would fail without it)
    lo, up = G_REF
    g1, g2 = sol.model.positions(sol.theta[ok, 0], sol.theta[ok, 1])
    t = sol.t[ok]
    tm = 0.5 * (t[1:] + t[:-1])
    w_x = -np.cumsum(acc(tm) * np.diff(lo.m * g1[:, 0] + up.m * g2[:, 0]))
    w_z = -np.cumsum(vert(tm) * np.diff(lo.m * g1[:, 1] + up.m * g2[:, 1]))
    assert np.max(np.abs(w_z)) > 0.05 * scale
    np.testing.assert_allclose(sol.work[ok][1:], w_x + w_z, rtol=0, atol=2e-3 * scale)


@pytest.mark.parametrize("blocks, pattern", [(G_REF, "M(-1)"), (G_U, "U(-1)")])
def test_a_vertical_motion_moves_the_uplift_threshold(blocks, pattern):
    """Uplift from rest when |ü_g| > (g + ü_z) min(tan α2, tan αM). At 0.9 of the static
    threshold along x alone the stack stays put; with the ground pulled down by 0.4 g as x
    peaks it starts when 0.9 sin ωt = (1 − 0.4 sin ωt), i.e. sin ωt = 1/1.3. Pushed up by
    0.4 g while x peaks, 1.2 times the static threshold does not start it in the first
    half-cycle; in the second the ground is pulled down as x peaks the other way, and it
    starts toward +x when −1.2 sin ωt = 1 + 0.4 sin ωt, i.e. sin ωt = −1/1.6."""
    tan_min = static_threshold(blocks)
    w = 2 * math.pi
    t_out = np.linspace(0, 1.0, 101)

    def run(kx: float, kz: float | None):
        acc, te = sine_pulse(kx * G * tan_min)
        vert = None if kz is None else sine_pulse(kz * G)[0]
        return solve_two_blocks(*blocks, g=G, accel=acc, vertical=vert, breakpoints=(te,),
                                end_time=te, t_out=t_out)

    alone = run(0.9, None)
    assert alone.patterns == [(0.0, "R")] and np.all(alone.theta == 0)
    down = run(0.9, -0.4)
    assert down.patterns[1][1] == pattern
    assert down.patterns[1][0] == pytest.approx(math.asin(1 / 1.3) / w, abs=1e-9)
    assert down.status in ("ok", "overturned") and len(down.patterns) >= 2
    assert run(1.2, None).patterns[1][1] == pattern
    up = run(1.2, 0.4)
    assert up.patterns[1][1] == pattern.replace("-1", "+1")
    assert up.patterns[1][0] == pytest.approx(0.5 + math.asin(1 / 1.6) / w, abs=1e-9)
    assert np.all(up.theta[t_out <= 0.5] == 0)


def paper_stack_with(x, z, duration: float) -> Scenario:
    from rockbench.scenarios import Components

    base = get_scenario("stack-pulse-4.0hz-4mm")
    return base.replace(name="stack-xz", excitation=Components(x=x, z=z), duration=duration)


def test_where_the_base_falls_faster_than_gravity_the_reference_stops():
    """g + ü_z < 0 at t_f = (π + asin(1/1.5))/ω for a vertical pulse of peak 1.5 g: the
    stack leaves the ground, which the model does not follow: it stops there."""
    z = SinePulse(2.0, 1.5 * G / (4 * math.pi) ** 2)
    t_flight = (math.pi + math.asin(1 / 1.5)) / z.omega
    root = brentq(lambda t: G + float(z.acceleration(t)), 0.26, 0.37, xtol=1e-14)
    assert t_flight == pytest.approx(root, abs=1e-12)
    sc = paper_stack_with(SinePulse(1.0, 3.0 / (2 * math.pi) ** 2), z, 2.0)
    tr = two_block_reference(sc)
    assert tr.status is Status.UNSUPPORTED and "leaves the ground" in tr.message
    said = float(re.search(r"at t = ([0-9.]+) s", tr.message).group(1))
    assert said == pytest.approx(t_flight, abs=5e-7)
    assert tr.t[-1] <= t_flight < tr.t[-1] + 1 / sc.output_rate
    assert np.all(np.isfinite(tr.theta)) and np.all(np.isfinite(tr.z))
    assert np.max(np.abs(tr.theta)) > 0  # it rocked before it flew
    # the solver: status "flight" at the root, nothing computed after it
    lo, up = (BlockParams.from_block(b) for b in sc.geometry.column.blocks)
    sol = solve_two_blocks(lo, up, g=G, accel=zero_accel, vertical=z.acceleration,
                           breakpoints=z.breakpoints, end_time=z.end_time,
                           t_out=np.linspace(0, 1, 1001))
    assert sol.status == "flight" and sol.flight_time == pytest.approx(root, abs=1e-12)
    after = sol.t > sol.flight_time
    assert np.all(np.isnan(sol.theta[after])) and np.all(sol.theta[~after] == 0)
    # a stack that overturns before the base falls: overturned, at T11's time
    acc, te = sine_pulse(4.0)
    sol = solve_two_blocks(*G_REF, g=G, accel=acc, breakpoints=(te, 2.5), end_time=3.0,
                           vertical=lambda t: np.where(np.asarray(t) > 2.5, -1.5 * G, 0.0),
                           t_out=np.linspace(0, 3.0, 3001))
    assert sol.status == "overturned" and sol.overturn_time == pytest.approx(1.8191538,
                                                                            abs=2e-7)
    assert sol.flight_time == pytest.approx(2.5, abs=1e-9)


def test_a_stack_under_vertical_motion_is_covered_and_rides_on_the_base():
    """coverage() takes a two-block column whose base moves along x and z; the start time
    is the root of |ü_x| = (g + ü_z) min(tan α2, tan αM) (both pulses in phase:
    sin ωt = g T / (A_x − A_z T)) and at rest the centroids ride on the base's z."""
    from rockbench import analytic

    x, z = SinePulse(4.0, 0.004), SinePulse(4.0, 0.002)
    sc = paper_stack_with(x, z, 1.0)
    assert analytic.coverage(sc) == "" and analytic.has_reference(sc)
    tr = analytic.reference(sc)
    assert tr.status is Status.OK and tr.theta.shape == (1001, 2)
    blocks = tuple(BlockParams.from_block(b) for b in sc.geometry.column.blocks)
    tan_min = static_threshold(blocks)
    ax, az = x.peak_acceleration(), z.peak_acceleration()
    t_start = math.asin(G * tan_min / (ax - az * tan_min)) / x.omega
    (t0, p0), (t1, p1) = tr.extra["patterns"][:2]
    assert (t0, p0) == (0.0, "R") and p1 == "M(-1)"
    assert t1 == pytest.approx(t_start, abs=1e-9)
    # heavier while x peaks: later than along x alone (at sin ωt = g T / A_x)
    assert t1 > math.asin(G * tan_min / ax) / x.omega + 1e-3
    rest = tr.t <= t_start
    lo, up = blocks
    heights = np.array([lo.h, 2 * lo.h + up.h])
    np.testing.assert_allclose(tr.z[rest], heights + z.displacement(tr.t[rest])[:, None],
                               rtol=0, atol=1e-12)
    assert np.ptp(z.displacement(tr.t)) > 1e-3
    # the Coulomb slider still takes no vertical motion
    slide = get_scenario("slide-stack-pulse-5.0hz-4mm-mu0.10")
    slide = slide.replace(excitation=paper_stack_with(slide.motion.x, z, 1.0).excitation)
    assert "sliding" in analytic.coverage(slide) and not analytic.has_reference(slide)
