"""The exact Coulomb sliding reference and the regime criteria of a block at rest.

Expected values are closed forms derived here (constant-acceleration step, onset
times of sine pulses, hand-computed thresholds), invariants (energy balance,
mirror symmetry) and an independent first-order integrator that converges to
the reference as its step shrinks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
import pytest

from rockbench.analytic import critical_angle, reference, slides, sliding_reference, slip_of
from rockbench.analytic.sliding import (
    Regime,
    onset_regime,
    regime_thresholds,
    solve_sliding,
)
from rockbench.analytic.twoblock_model import BlockParams
from rockbench.errors import UnsupportedScenario
from rockbench.scenarios import (
    AxialExcitation,
    Block,
    Contact,
    CosinePulse,
    Excitation,
    Geometry,
    Scenario,
    SinePulse,
    Sinusoid,
    catalog,
    get_scenario,
    get_suite,
    stack,
)
from rockbench.trajectory import Status

G = 9.81
SINGLE2 = Block(width=0.17, depth=0.502, height=1.0, density=2670.0)


@dataclass(frozen=True)
class Step(AxialExcitation):
    """ü_g = a on [0, T], then 0 (test-only: no ``kind``, so never registered)."""

    a: float
    duration: float
    report_group: ClassVar[str] = "pulse"

    def acceleration(self, t: Any) -> Any:
        t = np.asarray(t, float)
        return np.where((t >= 0) & (t <= self.duration), self.a, 0.0)

    def velocity(self, t: Any) -> Any:
        return self.a * np.clip(np.asarray(t, float), 0.0, self.duration)

    def displacement(self, t: Any) -> Any:
        t = np.asarray(t, float)
        tc = np.clip(t, 0.0, self.duration)
        return 0.5 * self.a * tc * tc + self.a * self.duration * np.maximum(t - self.duration, 0)

    @property
    def end_time(self) -> float:
        return self.duration

    @property
    def breakpoints(self) -> tuple[float, ...]:
        return (self.duration,)

    @classmethod
    def from_table(cls, table: Any, *, source: Any = None) -> Excitation:
        raise NotImplementedError

    def to_table(self) -> dict[str, Any]:
        raise NotImplementedError


def slider_scenario(exc: Excitation, mu: float, duration: float = 1.5,
                    geometry: Geometry | None = None) -> Scenario:
    return Scenario("slide", geometry or stack((SINGLE2,)), contact=Contact(friction=mu),
                    excitation=exc, duration=duration, output_rate=1000.0)


# ----------------------------------------------------------------------- closed forms
@pytest.mark.parametrize("a, mu", [(3.0, 0.1), (-2.0, 0.15)])
def test_constant_acceleration_step_closed_form(a, mu):
    """Slip ½(|a| − μg)t² behind the base during the step, then a stop at μg."""
    T = 0.3
    t = np.linspace(0.0, 1.5, 1501)
    sol = solve_sliding(Step(a, T), mu, g=G, t_out=t)
    sgn, k = math.copysign(1.0, a), abs(a) - mu * G
    during = t <= T
    np.testing.assert_allclose(sol.slip[during], -sgn * 0.5 * k * t[during] ** 2,
                               rtol=1e-12, atol=1e-15)
    t_stop = T + k * T / (mu * G)
    after = (t > T) & (t <= t_stop)
    tau = t[after] - T
    expected = -sgn * (0.5 * k * T * T + k * T * tau - 0.5 * mu * G * tau * tau)
    np.testing.assert_allclose(sol.slip[after], expected, rtol=1e-12, atol=1e-15)
    final = -sgn * 0.5 * k * abs(a) * T * T / (mu * G)
    assert sol.slip[-1] == pytest.approx(final, rel=1e-12)
    assert sol.path == pytest.approx(abs(final), rel=1e-12)
    # one slip from t = 0 (the base jumps to |a| > μg at once), then stuck
    assert [p.direction for p in sol.phases] == [-int(sgn), 0]
    assert sol.phases[0].start == 0.0
    assert sol.phases[0].end == pytest.approx(t_stop, abs=1e-12)
    assert np.all(sol.slip_rate[t > t_stop] == 0.0)


@pytest.mark.parametrize("f, amp, mu", [(3.0, 0.008, 0.10), (5.0, 0.006, 0.15)])
def test_sine_pulse_slip_starts_when_the_base_exceeds_mu_g(f, amp, mu):
    exc = SinePulse(f, amp)
    sol = solve_sliding(exc, mu, g=G, t_out=np.linspace(0, 1.5, 1501))
    w = 2 * math.pi * f
    onset = math.asin(mu * G / (amp * w * w)) / w
    assert sol.phases[0].direction == 0 and sol.phases[1].direction == -1
    assert sol.slip_times[0] == pytest.approx(onset, abs=1e-13)
    # slip phases alternate direction or end in stick; the block ends at rest on the base
    assert sol.phases[-1].direction == 0 and sol.slip_rate[-1] == 0.0
    starts = [p.start for p in sol.phases]
    assert starts == sorted(starts) and sol.phases[-1].end == 1.5


def test_a_cosine_pulse_above_mu_g_slips_from_the_start():
    """ü_g jumps to A ω² > μ g at t = 0: the slip starts at once, s̈ = −(A ω² − μ g)."""
    f, amp, mu = 3.0, 0.008, 0.10
    exc = CosinePulse(f, amp)
    t = np.linspace(0.0, 0.01, 11)
    sol = solve_sliding(exc, mu, g=G, t_out=t)
    assert sol.phases[0].start == 0.0 and sol.phases[0].direction == -1
    w = 2 * math.pi * f
    # s = −(u_g − ½ μ g t²) while it slips (u_g = A (1 − cos ωt))
    np.testing.assert_allclose(sol.slip, -(amp * (1 - np.cos(w * t)) - 0.5 * mu * G * t * t),
                               rtol=1e-12, atol=1e-16)


def test_a_slip_shorter_than_the_scan_step_is_located():
    """Peak of a sine pulse 1e-8 above μ g: near the peak the excess is Δ − ½ k u²
    (half-width d), σ ṡ ∝ Δ(u + d) − k (u³ + d³)/6 vanishes again at u = 2d: the
    block slips from t_m − d to t_m + 2d, 27 µs here, within one 0.1 ms scan cell."""
    f, mu = 2.5, 0.1
    w = 2 * math.pi * f
    amp = mu * G * (1 + 1e-8) / w**2
    sol = solve_sliding(SinePulse(f, amp), mu, g=G, t_out=np.linspace(0, 0.5, 501))
    t_m = 0.25 / f
    d = (0.5 * math.pi - math.asin(mu * G / (amp * w * w))) / w
    assert 3 * d < 1e-4
    (slip,) = [p for p in sol.phases if p.direction != 0]
    assert slip.direction == -1
    assert slip.start == pytest.approx(t_m - d, abs=1e-12)
    assert slip.end - slip.start == pytest.approx(3 * d, rel=1e-5)


def test_a_frictionless_block_stays_where_it_is():
    exc = SinePulse(3.0, 0.008)
    t = np.linspace(0.0, 1.0, 1001)
    sol = solve_sliding(exc, 0.0, g=G, t_out=t)
    np.testing.assert_allclose(sol.slip, -exc.displacement(t), rtol=0, atol=1e-15)
    assert sol.path == pytest.approx(2 * math.pi * 0.008, rel=1e-12)
    assert sol.dissipated(1.0) == 0.0


def test_stick_while_the_base_acceleration_stays_below_mu_g():
    mu = 0.15
    f = 3.0
    amp = 0.99 * mu * G / (2 * math.pi * f) ** 2
    sc = slider_scenario(SinePulse(f, amp), mu)
    assert not slides(sc)  # the dispatch keeps Housner's (at rest) reference
    tr = sliding_reference(sc)
    assert tr.status is Status.OK and tr.extra["slip_path"] == 0.0
    assert [p[2] for p in tr.extra["phases"]] == [0]
    np.testing.assert_array_equal(slip_of(tr, sc), 0.0)
    np.testing.assert_array_equal(tr.theta, 0.0)


@pytest.mark.parametrize("exc", [SinePulse(3.0, 0.008), Sinusoid(3.0, 0.008)])
def test_mirror_symmetry(exc):
    mu = 0.15
    t = np.linspace(0, 2.0, 2001)
    a = solve_sliding(exc, mu, g=G, t_out=t)
    mirrored = type(exc)(exc.frequency, -exc.amplitude)
    b = solve_sliding(mirrored, mu, g=G, t_out=t)
    np.testing.assert_allclose(b.slip, -a.slip, rtol=0, atol=1e-15)
    assert [p.direction for p in b.phases] == [-p.direction for p in a.phases]
    np.testing.assert_allclose([p.start for p in b.phases], [p.start for p in a.phases],
                               atol=1e-13)
    assert b.path == pytest.approx(a.path, rel=1e-13)


@pytest.mark.parametrize("exc, mu", [(SinePulse(3.0, 0.008), 0.10),
                                     (SinePulse(5.0, 0.006), 0.15),
                                     (Sinusoid(3.0, 0.008), 0.15)])
def test_friction_dissipates_mu_m_g_times_the_slip_path(exc, mu):
    """Energy in the base frame: ½ m ṡ² = −∫ m ü_g ṡ dt − μ m g × path (trapezoid check)."""
    m = SINGLE2.m
    t = np.linspace(0.0, 2.0, 400001)
    sol = solve_sliding(exc, mu, g=G, t_out=t)
    work_in = -m * np.trapezoid(np.asarray(exc.acceleration(t)) * sol.slip_rate, t)
    kinetic = 0.5 * m * sol.slip_rate[-1] ** 2
    assert work_in - kinetic == pytest.approx(sol.dissipated(m), rel=2e-6)
    assert sol.dissipated(m) == pytest.approx(mu * m * G * sol.path)
    # the path is the total variation of the sampled slip
    assert sol.path == pytest.approx(np.sum(np.abs(np.diff(sol.slip))), rel=1e-8)


def implicit_coulomb(exc: Excitation, mu: float, h: float, t_end: float) -> tuple:
    """Independent first-order scheme: backward Euler with set-valued Coulomb friction."""
    n = int(round(t_end / h))
    t = np.arange(n + 1) * h
    a = np.asarray(exc.acceleration(t[1:]))
    s = np.zeros(n + 1)
    v = 0.0
    cap = mu * G * h
    for i in range(n):
        trial = v - a[i] * h
        v = 0.0 if abs(trial) <= cap else trial - math.copysign(cap, trial)
        s[i + 1] = s[i] + v * h
    return t, s


def test_independent_integrator_converges_to_the_reference():
    exc, mu = SinePulse(3.0, 0.008), 0.10
    errors = []
    for h in (1e-3, 1e-4, 1e-5):
        t, s = implicit_coulomb(exc, mu, h, 1.0)
        ref = solve_sliding(exc, mu, g=G, t_out=t).slip
        errors.append(np.max(np.abs(s - ref)) / np.max(np.abs(ref)))
    # measured 8.6e-3, 8.6e-4, 9.0e-5 of the peak slip: first order down to 1e-5 s
    assert errors[2] < 1e-4
    assert errors[0] / errors[1] == pytest.approx(10.0, rel=0.1)
    assert errors[1] / errors[2] == pytest.approx(10.0, rel=0.1)


# ------------------------------------------------------------ trajectories and dispatch
def test_sliding_trajectory_moves_with_the_base_plus_the_slip():
    sc = get_scenario("slide-single-pulse-3.0hz-8mm-mu0.10")
    tr = reference(sc)
    assert tr.engine_version.startswith("sliding-") and tr.status is Status.OK
    sol = solve_sliding(sc.excitation, 0.10, g=G, t_out=sc.output_times())
    x0, z0 = sc.geometry.centroids[0]
    np.testing.assert_allclose(tr.x[:, 0], x0 + sc.excitation.displacement(tr.t) + sol.slip,
                               atol=1e-15)
    np.testing.assert_array_equal(tr.z[:, 0], z0)
    np.testing.assert_array_equal(tr.theta, 0.0)
    assert tr.extra["final_slip"] == sol.slip[-1] and tr.extra["slip_path"] == sol.path
    assert reference(sc, linear=True).extra == tr.extra  # nothing to linearise


def test_a_stack_below_every_uplift_ratio_slides_as_one_body():
    sc = get_scenario("slide-stack-pulse-5.0hz-4mm-mu0.10")
    assert sc.contact.friction < math.tan(critical_angle(sc.geometry))
    tr = reference(sc)
    assert tr.engine_version.startswith("sliding-") and tr.n_blocks == 2
    s1, s2 = slip_of(tr, sc, 0), slip_of(tr, sc, 1)
    np.testing.assert_allclose(s2, s1, atol=1e-15)
    ref = solve_sliding(sc.excitation, 0.10, g=G, t_out=tr.t).slip
    np.testing.assert_allclose(s1, ref, atol=1e-15)
    assert np.max(np.abs(s1)) > 0.01  # it does slide, by centimetres


def test_reference_picks_sliding_only_for_low_friction_cases():
    names = get_suite("sliding")
    assert len(names) >= 5 and all(n.startswith("slide-") for n in names)
    for name in names:
        sc = get_scenario(name)
        assert slides(sc), name
        b = sc.blocks[0]
        assert sc.contact.friction < b.pivot_half_width / b.h
    # every other catalog scenario keeps its rocking reference
    for name in catalog():
        if not name.startswith("slide-"):
            assert not slides(get_scenario(name)), name
    # friction at the uplift ratio: the block could rock, so no sliding reference
    b = SINGLE2
    sc = slider_scenario(SinePulse(3.0, 0.008), b.pivot_half_width / b.h)
    assert not slides(sc)
    with pytest.raises(UnsupportedScenario, match="uplift ratio"):
        sliding_reference(sc)
    with pytest.raises(UnsupportedScenario, match="upright"):
        sliding_reference(slider_scenario(SinePulse(3.0, 0.008), 0.1).replace(initial_tilt=0.2))


# ------------------------------------------------------------------ regime criteria
def pivot_friction_demand(a: float, blk: BlockParams) -> float:
    """H/V at the pivot of a block starting to rock from rest under a > g b/h."""
    b, h, m = blk.b, blk.h, blk.m
    phi_dd = m * (a * h - G * b) / (blk.I + m * (b * b + h * h))
    return (a - h * phi_dd) / (G + b * phi_dd)


S2 = BlockParams.uniform(0.085, 0.5, 1.0)  # Single #2: b/h = 0.17
SQUARE = BlockParams.uniform(0.5, 0.5, 1.0)  # b/h = 1
SQUAT = BlockParams.uniform(1.0, 0.5, 1.0)  # b/h = 2

#: (block, μ, |ü_g|/g, regime entered from rest)
TABLE = [
    (S2, 0.10, 0.05, Regime.REST), (S2, 0.10, 0.10, Regime.REST),
    (S2, 0.10, 0.11, Regime.SLIDE), (S2, 0.10, 2.00, Regime.SLIDE),
    (S2, 0.50, 0.169, Regime.REST), (S2, 0.50, 0.171, Regime.ROCK),
    (S2, 0.50, 1.70, Regime.ROCK), (S2, 0.50, 1.80, Regime.SLIDE_ROCK),
    (S2, 1.00, 3.00, Regime.ROCK), (S2, 1.00, 6.00, Regime.SLIDE_ROCK),
    (SQUARE, 0.50, 0.49, Regime.REST), (SQUARE, 0.50, 0.51, Regime.SLIDE),
    (SQUARE, 1.20, 0.99, Regime.REST), (SQUARE, 1.20, 1.01, Regime.ROCK),
    (SQUAT, 1.50, 1.49, Regime.REST), (SQUAT, 1.50, 1.51, Regime.SLIDE),
    (SQUAT, 3.00, 1.99, Regime.REST), (SQUAT, 3.00, 2.01, Regime.ROCK),
    (SQUAT, 3.00, 50.0, Regime.ROCK),
]


@pytest.mark.parametrize("blk, mu, a_g, regime", TABLE)
def test_regime_table(blk, mu, a_g, regime):
    assert onset_regime(a_g * G, mu, blk, G) is regime
    assert onset_regime(-a_g * G, mu, blk, G) is regime  # either direction


@pytest.mark.parametrize("blk, mu, a_sr_g", [(S2, 0.50, 1.7481), (S2, 1.00, 5.8107),
                                             (SQUARE, 1.20, 2.1429)])
def test_slide_rock_threshold_is_where_rocking_needs_more_friction_than_mu(blk, mu, a_sr_g):
    thr = regime_thresholds(mu, blk, G)
    assert thr.rock == pytest.approx(G * blk.b / blk.h)
    assert thr.slide == math.inf and thr.slide_rock / G == pytest.approx(a_sr_g, abs=1e-4)
    # the defining property: the pivot's friction demand reaches μ there, not before
    assert pivot_friction_demand(thr.slide_rock, blk) == pytest.approx(mu, rel=1e-12)
    a = np.linspace(thr.rock, thr.slide_rock, 50)[1:-1]
    assert all(pivot_friction_demand(x, blk) < mu for x in a)


def test_squat_blocks_never_slide_rock_from_rest():
    # c h (h + μ b) ≥ 1: incipient rocking never needs more than μ V at the pivot
    thr = regime_thresholds(3.0, SQUAT, G)
    assert thr.slide_rock == math.inf
    assert all(pivot_friction_demand(a * G, SQUAT) < 3.0 for a in (2.01, 10.0, 1e3))


def test_below_the_uplift_ratio_a_block_only_slides():
    thr = regime_thresholds(0.1, S2, G)
    assert (thr.slide, thr.rock, thr.slide_rock) == (pytest.approx(0.1 * G), math.inf, math.inf)
