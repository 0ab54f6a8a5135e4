"""Lognormal fragility fits (Baker 2015), bootstrap intervals, degenerate data, safe islands."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import norm

from rockbench.analytic.housner import single_block_reference
from rockbench.errors import ScenarioError
from rockbench.fragility import (
    ExceedanceData,
    FitStatus,
    FragilityError,
    IntensityMeasure,
    Island,
    PulseRatios,
    bootstrap_fragility,
    compare_medians,
    find_non_monotone,
    fit_fragility,
    intensity,
    pulse_ratios,
)
from rockbench.fragility.fit import _centre, _fit_batch
from rockbench.scenarios import Block, Contact, CosinePulse, Scenario, SinePulse, Sinusoid, stack
from rockbench.scenarios.excitation import TiltTable

THETA, BETA = 0.8, 0.35
LEVELS = np.geomspace(0.3, 2.5, 12)
B_ROCK = Block(0.5, 0.2, 1.0, mass=1.0).rocking()


def draw(n_per_level: int, seed: int, levels: np.ndarray = LEVELS) -> ExceedanceData:
    rng = np.random.default_rng(seed)
    n = np.full(levels.size, n_per_level)
    z = rng.binomial(n, norm.cdf(np.log(levels / THETA) / BETA))
    return ExceedanceData(tuple(levels), tuple(n), tuple(z))


def log_likelihood(data: ExceedanceData, theta: float, beta: float) -> float:
    """Baker's (2015) binomial log-likelihood, written independently of the module."""
    u = np.log(np.asarray(data.levels) / theta) / beta
    n, z = np.asarray(data.runs), np.asarray(data.exceeded)
    return float(np.sum(z * norm.logcdf(u) + (n - z) * norm.logsf(u)))


def asymptotic_se(levels: np.ndarray, n: int) -> tuple[float, float]:
    """Standard errors of ln θ̂ and β̂ from the expected Fisher information (delta method)."""
    lx = np.log(levels)
    b = 1.0 / BETA
    a = -math.log(THETA) * b
    u = a + b * lx
    w = n * norm.pdf(u) ** 2 / (norm.cdf(u) * norm.sf(u))
    info = np.array([[w.sum(), (w * lx).sum()], [(w * lx).sum(), (w * lx * lx).sum()]])
    cov = np.linalg.inv(info)
    g_ln_theta = np.array([-1.0 / b, a / b**2])
    g_beta = np.array([0.0, -1.0 / b**2])
    return math.sqrt(g_ln_theta @ cov @ g_ln_theta), math.sqrt(g_beta @ cov @ g_beta)


@pytest.mark.parametrize("n", [20, 80, 320, 1280])
def test_fit_recovers_the_median_and_dispersion(n):
    data = draw(n, seed=n)
    fit = fit_fragility(data)
    assert fit.status is FitStatus.OK and fit.ok
    assert (fit.n_levels, fit.n_runs) == (LEVELS.size, LEVELS.size * n)
    se_theta, se_beta = asymptotic_se(LEVELS, n)
    # four standard errors: the tolerance shrinks as 1/sqrt(n)
    assert abs(math.log(fit.median / THETA)) < 4 * se_theta
    assert abs(fit.dispersion - BETA) < 4 * se_beta
    boot = bootstrap_fragility(data, n_resamples=400, confidence=0.99, seed=1)
    assert boot.fit == fit
    assert boot.median_interval[0] < THETA < boot.median_interval[1]
    assert boot.dispersion_interval[0] < BETA < boot.dispersion_interval[1]
    assert boot.median_interval[0] < fit.median < boot.median_interval[1]


def test_the_fit_maximises_bakers_likelihood():
    data = draw(30, seed=7)
    fit = fit_fragility(data)
    assert fit.log_likelihood == pytest.approx(log_likelihood(data, fit.median, fit.dispersion),
                                               rel=1e-12)
    for dt, db in [(1.01, 1.0), (0.99, 1.0), (1.0, 1.01), (1.0, 0.99), (1.005, 1.005)]:
        assert log_likelihood(data, fit.median * dt, fit.dispersion * db) < fit.log_likelihood
    p = fit.probability(np.array([fit.median, fit.median * math.exp(fit.dispersion)]))
    assert p == pytest.approx([0.5, norm.cdf(1.0)], rel=1e-12)


def test_a_nearly_flat_fit_is_flagged_as_extrapolated():
    flat = fit_fragility(ExceedanceData((1.0, 2.0, 3.0), (50, 50, 50), (20, 21, 22)))
    assert flat.ok and flat.extrapolated and flat.median > 3.0 and flat.dispersion > 3.0
    assert flat.to_dict()["extrapolated"] is True
    assert flat.level_range == (1.0, 3.0)
    fit = fit_fragility(draw(20, seed=0))
    assert not fit.extrapolated and fit.to_dict()["extrapolated"] is False


def test_scaling_the_levels_scales_the_median_only():
    data = draw(40, seed=3)
    fit = fit_fragility(data)
    k = 9.80665
    scaled = fit_fragility(ExceedanceData(tuple(k * np.asarray(data.levels)), data.runs,
                                          data.exceeded))
    assert scaled.median == pytest.approx(k * fit.median, rel=1e-7)
    assert scaled.dispersion == pytest.approx(fit.dispersion, rel=1e-7)
    assert scaled.log_likelihood == pytest.approx(fit.log_likelihood, rel=1e-10)


HARD = [  # poorly fitting data on which plain Fisher scoring stalls
    ExceedanceData((0.44487828, 9.88495905, 72.32633896), (1, 6, 18), (1, 0, 18)),
    ExceedanceData((0.01, 0.0120337784, 0.0219638537, 0.0608022426, 4.93704785, 100.0),
                   (22, 13, 27, 1, 1, 20), (0, 0, 27, 0, 0, 20)),
]


@pytest.mark.parametrize("case", [*range(5), *HARD])
def test_bootstrap_refits_agree_with_the_scipy_fit(case):
    data = case if isinstance(case, ExceedanceData) else draw(
        15, seed=100 + case, levels=np.geomspace(0.4, 1.6, 6))
    fit = fit_fragility(data)
    assert fit.ok
    x, c = _centre(np.asarray(data.levels))
    a, b, ok = _fit_batch(x, np.asarray(data.runs, float),
                          np.asarray(data.exceeded, float)[None, :])
    assert ok[0]
    assert math.exp(c - a[0] / b[0]) == pytest.approx(fit.median, rel=1e-7)
    assert 1.0 / b[0] == pytest.approx(fit.dispersion, rel=1e-7)


def test_bootstrap_intervals_cover_the_truth_at_the_nominal_rate():
    levels = np.geomspace(0.4, 1.6, 8)
    trials, hits_theta, hits_beta = 200, 0, 0
    for k in range(trials):
        boot = bootstrap_fragility(draw(20, seed=1000 + k, levels=levels), n_resamples=200,
                                   confidence=0.9, seed=k)
        hits_theta += boot.median_interval[0] <= THETA <= boot.median_interval[1]
        hits_beta += boot.dispersion_interval[0] <= BETA <= boot.dispersion_interval[1]
    # 200 trials at 90 %: standard deviation 2.1 %; the percentile bootstrap runs a bit low
    assert 0.82 <= hits_theta / trials <= 0.97
    assert 0.82 <= hits_beta / trials <= 0.97


def test_bootstrap_is_seeded():
    data = draw(20, seed=5)
    one = bootstrap_fragility(data, n_resamples=100, seed=42)
    assert one == bootstrap_fragility(data, n_resamples=100, seed=42)
    other = bootstrap_fragility(data, n_resamples=100, seed=43)
    assert other.median_interval != one.median_interval
    assert (one.n_resamples, one.seed, one.confidence) == (100, 42, 0.95)


def test_sparse_data_report_degenerate_resamples():
    # two runs per level: many resamples are separated and are counted, not fitted
    data = ExceedanceData((0.5, 1.0, 2.0), (2, 2, 2), (0, 1, 2))
    fit = fit_fragility(data)
    assert fit.status is FitStatus.SINGLE_TRANSITION
    data = ExceedanceData((0.5, 0.7, 1.0, 1.4, 2.0), (2, 2, 2, 2, 2), (0, 1, 0, 2, 2))
    boot = bootstrap_fragility(data, n_resamples=300, seed=0)
    assert boot.fit.ok
    assert 0 < boot.n_degenerate < 300
    assert boot.degenerate_fraction == boot.n_degenerate / 300


X5 = (0.2, 0.4, 0.8, 1.6, 3.2)
N5 = (10, 10, 10, 10, 10)


@pytest.mark.parametrize(("z", "status", "median", "bounds"), [
    ((0, 0, 0, 0, 0), FitStatus.NONE_EXCEEDED, math.nan, (3.2, math.inf)),
    ((10, 10, 10, 10, 10), FitStatus.ALL_EXCEEDED, math.nan, (0.0, 0.2)),
    ((0, 0, 10, 10, 10), FitStatus.SEPARATED, math.nan, (0.4, 0.8)),
    ((0, 0, 4, 10, 10), FitStatus.SINGLE_TRANSITION, 0.8, (0.4, 1.6)),
    ((0, 0, 0, 0, 4), FitStatus.SINGLE_TRANSITION, 3.2, (1.6, math.inf)),
    ((10, 10, 6, 0, 0), FitStatus.NOT_INCREASING, math.nan, (0.0, math.inf)),
    ((6, 4, 5, 3, 2), FitStatus.NOT_INCREASING, math.nan, (0.0, math.inf)),
])
def test_degenerate_data_say_why_there_is_no_fit(z, status, median, bounds):
    data = ExceedanceData(X5, N5, z)
    fit = fit_fragility(data)
    assert fit.status is status and not fit.ok
    assert fit.median == median or (math.isnan(fit.median) and math.isnan(median))
    assert math.isnan(fit.dispersion)
    assert fit.median_range == bounds
    with pytest.raises(FragilityError, match=status.value):
        fit.probability(1.0)
    boot = bootstrap_fragility(data, n_resamples=50)
    assert boot.fit == fit and boot.n_resamples == 0
    assert all(math.isnan(v) for v in boot.median_interval + boot.dispersion_interval)
    d = fit.to_dict()
    assert d["status"] == status.value and d["dispersion"] is None


def test_degenerate_log_likelihood_is_the_supremum():
    # single transition: as β → 0 with θ at the level, only that level's binomial term remains
    data = ExceedanceData(X5, N5, (0, 0, 4, 10, 10))
    fit = fit_fragility(data)
    assert fit.log_likelihood == pytest.approx(4 * math.log(0.4) + 6 * math.log(0.6))
    def at(beta: float) -> float:  # θ → 0.8 as β → 0, with Φ = 0.4 at the level 0.8
        return log_likelihood(data, 0.8 * math.exp(-beta * norm.ppf(0.4)), beta)

    assert at(1e-3) == pytest.approx(fit.log_likelihood, rel=1e-9)
    assert at(0.6) < at(0.4) < at(0.2) < fit.log_likelihood
    # not increasing: the constant probability 0.4 beats every increasing curve
    data = ExceedanceData(X5, N5, (6, 4, 5, 3, 2))
    fit = fit_fragility(data)
    assert fit.log_likelihood == pytest.approx(20 * math.log(0.4) + 30 * math.log(0.6))
    # β → ∞ with ln θ = −β Φ⁻¹(0.4) (too large for exp): P → 0.4 at every level
    u = norm.ppf(0.4) + np.log(X5) / 1e6
    n, z = np.asarray(N5), np.asarray(data.exceeded)
    limit = np.sum(z * norm.logcdf(u) + (n - z) * norm.logsf(u))
    assert limit == pytest.approx(fit.log_likelihood, rel=1e-6)
    assert log_likelihood(data, 1.0, 1.0) < log_likelihood(data, 10.0, 5.0) < limit


def test_counts_from_outcome_tables():
    outcomes = np.array([[0, 0, 1, 1], [0, 1, 0, 1], [0, np.nan, 1, 1]])
    data = ExceedanceData.from_outcomes([0.1, 0.2, 0.3, 0.4], outcomes)
    assert data.runs == (3, 2, 3, 3) and data.exceeded == (0, 1, 2, 3)
    assert data.fractions == pytest.approx([0, 0.5, 2 / 3, 1])
    assert data.total_runs == 11
    empty = ExceedanceData.from_outcomes([0.1, 0.2], np.array([[np.nan, 1.0]]))
    assert empty.levels == (0.2,)
    with pytest.raises(FragilityError, match="0, 1 or NaN"):
        ExceedanceData.from_outcomes([0.1], np.array([[0.5]]))
    with pytest.raises(FragilityError, match="shape"):
        ExceedanceData.from_outcomes([0.1, 0.2], np.zeros((2, 3)))


@pytest.mark.parametrize(("levels", "runs", "exceeded", "match"), [
    ((0.1, 0.2), (1, 1), (0,), "same non-zero length"),
    ((0.0, 0.2), (1, 1), (0, 0), "> 0"),
    ((0.2, 0.1), (1, 1), (0, 0), "increasing"),
    ((0.1, 0.2), (1, 0), (0, 0), "runs >= 1"),
    ((0.1, 0.2), (1, 1), (0, 2), "exceeded <= runs"),
    ((0.1, 0.2), (1.5, 1), (0, 0), "whole numbers"),
])
def test_bad_exceedance_data(levels, runs, exceeded, match):
    with pytest.raises(FragilityError, match=match):
        ExceedanceData(levels, runs, exceeded)


def test_bad_bootstrap_parameters():
    data = draw(10, seed=0)
    with pytest.raises(FragilityError, match="n_resamples"):
        bootstrap_fragility(data, n_resamples=0)
    with pytest.raises(FragilityError, match="confidence"):
        bootstrap_fragility(data, confidence=1.0)


def test_monotone_fractions_have_no_island():
    assert find_non_monotone(LEVELS, np.linspace(0, 1, LEVELS.size)) == ()
    assert find_non_monotone([1.0, 2.0, 3.0], [0.0, 0.5, 0.5]) == ()


def test_single_record_safe_islands():
    levels = [1, 2, 3, 4, 5, 6, 7, 8]
    outcome = [0, 0, 1, 0, 0, 1, 0, 1]
    islands = find_non_monotone(levels, outcome)
    assert islands == (Island(4.0, 5.0, 0.0, 3.0, 1.0), Island(7.0, 7.0, 0.0, 3.0, 1.0))
    assert islands[0].drop == 1.0


def test_set_fractions_drops_and_tolerance():
    levels = [0.5, 1.0, 1.5, 2.0, 2.5]
    fractions = [0.1, 0.4, 0.35, 0.2, 0.6]
    (island,) = find_non_monotone(levels, fractions)
    assert (island.first_level, island.last_level) == (1.5, 2.0)
    assert island.fraction == 0.2 and island.peak_level == 1.0 and island.peak_fraction == 0.4
    assert island.drop == pytest.approx(0.2)
    # a tolerance hides the small drop at 1.5 but keeps the level at 2.0
    (big,) = find_non_monotone(levels, fractions, tolerance=0.1)
    assert (big.first_level, big.last_level, big.fraction) == (2.0, 2.0, 0.2)
    assert find_non_monotone(levels, fractions, tolerance=0.25) == ()


@pytest.mark.parametrize(("levels", "fractions", "tol", "match"), [
    ([1, 2], [0.0], 0.0, "one length"),
    ([2, 1], [0.0, 1.0], 0.0, "increasing"),
    ([1, 2], [0.0, 1.5], 0.0, r"\[0, 1\]"),
    ([1, 2], [0.0, 1.0], -0.1, "tolerance"),
])
def test_bad_monotonicity_input(levels, fractions, tol, match):
    with pytest.raises(FragilityError, match=match):
        find_non_monotone(levels, fractions, tolerance=tol)


# --- intensity measures of the analytic pulses ---------------------------------------------


@pytest.mark.parametrize(("cls", "c"), [(SinePulse, 2.0), (CosinePulse, 1.0)])
def test_pulse_measures_in_closed_form(cls, c):
    g = 9.81
    rock = Block(0.3, 0.3, 1.2, mass=1.0).rocking(g)
    pulse = cls(frequency=1.5, amplitude=-0.02)
    t = np.linspace(0.0, pulse.end_time, 200001)
    a_p, w = 0.02 * pulse.omega**2, pulse.omega
    assert intensity(pulse, "pga") == pytest.approx(a_p, rel=1e-12)
    assert intensity(pulse, "pgv") == pytest.approx(np.max(np.abs(pulse.velocity(t))), rel=1e-9)
    assert intensity(pulse, "pgv") == pytest.approx(c * a_p / w, rel=1e-12)
    ratios = pulse_ratios(pulse, rock, g)
    assert ratios.frequency_ratio == pytest.approx(w / rock.p)
    assert ratios.acceleration_ratio == pytest.approx(a_p / (g * math.tan(rock.lam)))
    assert intensity(pulse, "pga-uplift", rock, g) == pytest.approx(ratios.acceleration_ratio)
    # PGV p / (g tan λ) = c (a_p / (g tan λ)) / (ω_p / p)
    assert intensity(pulse, "pgv-rocking", rock, g) == pytest.approx(
        c * ratios.acceleration_ratio / ratios.frequency_ratio, rel=1e-12)


def test_pulse_ratios_are_a_similarity_law():
    """Two blocks of one slenderness under pulses of equal ω_p/p and a_p/(g tan λ) rock alike
    in the time p·t (Dimitrakopoulos & DeJong 2012)."""
    g = 9.81
    runs = []
    for size in (1.0, 3.0):
        block = Block(0.25 * size, 0.2, 1.0 * size, mass=1.0)
        rock = block.rocking(g)
        pulse = SinePulse.from_acceleration(1.6 * g * math.tan(rock.lam), 3.0 * rock.p)
        assert pulse_ratios(pulse, rock, g) == PulseRatios(pytest.approx(3.0),
                                                           pytest.approx(1.6))
        sc = Scenario(name="similar", geometry=stack((block,)), contact=Contact(friction=1.0),
                      excitation=pulse, duration=12.0 / rock.p, output_rate=400.0 * rock.p)
        tr = single_block_reference(sc)
        runs.append((tr.t * rock.p, tr.theta[:, 0] / rock.lam))
    (s1, th1), (s2, th2) = runs
    assert np.max(np.abs(th1)) > 0.3  # it rocks, without overturning
    assert np.max(np.abs(np.interp(s1, s2, th2) - th1)) < 1e-4


def test_intensity_errors():
    pulse = SinePulse(frequency=2.0, amplitude=0.01)
    with pytest.raises(ScenarioError, match="needs the block"):
        intensity(pulse, "pgv-rocking")
    with pytest.raises(ScenarioError, match="PGV of a TiltTable motion, which never ends"):
        intensity(TiltTable(rate=0.01), "pgv")
    # a windowed sinusoid (1-cycle ramps) reaches its steady velocity amplitude A ω
    assert intensity(Sinusoid(frequency=2.0, amplitude=0.01, duration=3.0), "pgv") == \
        pytest.approx(0.01 * 4.0 * math.pi, rel=1e-5)
    with pytest.raises(ScenarioError, match="sine or cosine pulse"):
        pulse_ratios(Sinusoid(frequency=2.0, amplitude=0.01), B_ROCK)
    assert [(m.value, m.units, m.needs_block, m.degree) for m in IntensityMeasure] == [
        ("pga", "m/s2", False, 1), ("pgv", "m/s", False, 1), ("pga-uplift", "1", True, 1),
        ("pgv-rocking", "1", True, 1), ("sa", "m/s2", False, 1), ("arias", "m/s", False, 2)]
    assert IntensityMeasure.parse(" PGA ") is IntensityMeasure.PGA
    assert IntensityMeasure.PGA_UPLIFT.label == "PGA / (g tan λ)"


# --- a method's median against the reference's (paired over records) ------------------------

IDA_LEVELS = np.geomspace(0.25, 4.0, 25)


def ida(capacities: np.ndarray) -> np.ndarray:
    """Outcome table of an IDA: record i exceeds at every level at or above its capacity."""
    return (IDA_LEVELS[None, :] >= capacities[:, None]).astype(float)


def test_identical_methods_compare_exactly_equal():
    cap = np.exp(np.random.default_rng(0).normal(0.0, 0.4, 30))
    cmp = compare_medians(IDA_LEVELS, ida(cap), ida(cap), n_resamples=200, seed=1)
    assert cmp.method == cmp.reference and cmp.ratio == 1.0
    assert cmp.ratio_interval == (1.0, 1.0) and cmp.log_difference == 0.0
    assert (cmp.n_resamples, cmp.n_degenerate, cmp.seed) == (200, 0, 1)


def test_a_biased_method_is_found_with_a_paired_interval():
    rng = np.random.default_rng(3)
    cap = np.exp(rng.normal(0.0, 0.4, 40))
    # the method overestimates every record's capacity by 25 %, with 5 % scatter of its own
    biased = cap * 1.25 * np.exp(rng.normal(0.0, 0.05, cap.size))
    cmp = compare_medians(IDA_LEVELS, ida(biased), ida(cap), n_resamples=400, seed=2)
    assert cmp.ratio_interval[0] < 1.25 < cmp.ratio_interval[1]
    assert cmp.ratio_interval[0] > 1.1  # the bias is resolved
    # pairing by record removes the record-to-record scatter both methods share
    ref = bootstrap_fragility(ExceedanceData.from_outcomes(IDA_LEVELS, ida(cap)),
                              n_resamples=400, seed=2)
    paired = math.log(cmp.ratio_interval[1] / cmp.ratio_interval[0])
    assert paired < 0.5 * math.log(ref.median_interval[1] / ref.median_interval[0])
    swapped = compare_medians(IDA_LEVELS, ida(cap), ida(biased), n_resamples=400, seed=2)
    assert swapped.ratio == pytest.approx(1.0 / cmp.ratio, rel=1e-12)
    assert swapped.ratio_interval == pytest.approx(
        (1.0 / cmp.ratio_interval[1], 1.0 / cmp.ratio_interval[0]), rel=1e-9)


def test_comparison_with_a_degenerate_fit_has_no_ratio():
    cap = np.full(10, 100.0)  # nothing ever exceeds
    cmp = compare_medians(IDA_LEVELS, ida(np.geomspace(0.5, 2, 10)), ida(cap))
    assert cmp.reference.status is FitStatus.NONE_EXCEEDED
    assert math.isnan(cmp.ratio) and cmp.n_resamples == 0
    assert all(math.isnan(v) for v in cmp.ratio_interval)
    with pytest.raises(FragilityError, match="shape"):
        compare_medians(IDA_LEVELS, ida(cap), ida(cap)[:, :3])
    with pytest.raises(FragilityError, match="shape"):
        compare_medians(IDA_LEVELS, ida(cap), ida(cap[:5]))


def test_probability_at_a_design_level_and_its_interval_cover_the_truth():
    # P(IM = a) = Φ(ln(a/θ)/β) of the fit; over repeated experiments its 90 % interval holds
    # the true probability about 90 % of the time
    level, trials, hits = 1.0, 200, 0
    truth = float(norm.cdf(math.log(level / THETA) / BETA))
    for k in range(trials):
        boot = bootstrap_fragility(draw(20, seed=3000 + k), n_resamples=200, confidence=0.9,
                                   seed=k)
        at = boot.probability_at(level)
        assert at.probability == pytest.approx(
            norm.cdf(math.log(level / boot.fit.median) / boot.fit.dispersion), rel=1e-12)
        hits += at.interval[0] <= truth <= at.interval[1]
    assert 0.82 <= hits / trials <= 0.97
    with pytest.raises(FragilityError, match="design level"):
        boot.probability_at(0.0)
    separated = bootstrap_fragility(ExceedanceData((1.0, 2.0), (5, 5), (0, 5)))
    assert math.isnan(separated.probability_at(1.5).probability)
