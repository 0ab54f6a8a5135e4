"""Overturning spectra: one-cosine pulses, the overturning decision, maps and the CLI.

The analytic boundaries are cross-checked against an independent formulation
written here: the linearised Housner model has a closed form between impacts
(cosh/sinh plus the harmonic particular solution), so a small event-driven
solver built on it, with root finding on the closed form and the overturning
decided by following the free motion (not by the energy criterion of
``rockbench.analytic.overturning``), is exact up to root-finding tolerances.
"""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from rockbench.analytic.closed_forms import cosine_pulse_linear_response
from rockbench.analytic.housner import scalar_acceleration, solve_single
from rockbench.analytic.overturning import (
    NO_UPLIFT,
    SAFE,
    free_motion_fate,
    housner_eta,
    minimum_overturning_acceleration,
    normalised_outcome,
    pulse_excitation,
    scan_column,
)
from rockbench.cli import main
from rockbench.errors import ScenarioError
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import (
    Block,
    CosinePulse,
    Free,
    SinePulse,
    load_scenario,
    save_scenario,
    scenario_from_dict,
)
from rockbench.studies.spectrum import (
    FAILED,
    analytic_map,
    classify_trajectory,
    grid_axes,
    parse_block,
    parse_grid,
)
from rockbench.trajectory import Status, Trajectory

G = 9.81
B0 = Block(1.0, 0.2, 5.0, mass=1.0)  # the 1 m × 5 m block of the specification's T13


@pytest.fixture(scope="module")
def rock():
    return B0.rocking(G)


# ---------------------------------------------------------------------- excitation
def test_cosine_pulse_starts_and_ends_at_rest_with_exact_integrals():
    c = CosinePulse.from_acceleration(3.0, 5.0)
    assert c.acceleration_amplitude == pytest.approx(3.0)
    assert c.omega == pytest.approx(5.0)
    assert c.acceleration(0.0) == pytest.approx(3.0)  # the jump at t = 0
    assert c.velocity(0.0) == 0.0 and c.displacement(0.0) == 0.0
    t_end = c.end_time
    assert t_end == pytest.approx(2 * math.pi / 5.0)
    for t in (t_end, t_end + 1.0):
        assert c.velocity(t) == pytest.approx(0.0, abs=1e-12)
        assert c.displacement(t) == pytest.approx(0.0, abs=1e-12)
    t = np.linspace(0.01, t_end - 0.01, 501)
    h = 1e-6
    dv = (c.velocity(t + h) - c.velocity(t - h)) / (2 * h)
    du = (c.displacement(t + h) - c.displacement(t - h)) / (2 * h)
    np.testing.assert_allclose(dv, c.acceleration(t), atol=1e-6)
    np.testing.assert_allclose(du, c.velocity(t), atol=1e-6)
    assert c.displacement(0.5 * t_end) == pytest.approx(2 * c.amplitude)  # peak 2A
    assert scalar_acceleration(c) is not None


def test_sine_pulse_from_acceleration_keeps_its_fields():
    s = SinePulse.from_acceleration(-4.0, 2 * math.pi * 3.0)
    assert s.frequency == pytest.approx(3.0)
    assert s.amplitude == pytest.approx(-4.0 / (2 * math.pi * 3.0) ** 2)
    assert s.acceleration_amplitude == pytest.approx(-4.0)
    with pytest.raises(ScenarioError):
        SinePulse.from_acceleration(1.0, 0.0)


def _toml(exc: dict) -> dict:
    return {"blocks": [{"width": 1.0, "depth": 0.2, "height": 5.0, "mass": 1.0}],
            "excitation": exc}


def test_cosine_pulse_scenario_files(tmp_path):
    sc = scenario_from_dict(_toml({"type": "cosine-pulse", "frequency": 2.0,
                                   "peak_acceleration": -3.0}))
    assert isinstance(sc.excitation, CosinePulse)
    assert sc.excitation.acceleration(0.0) == pytest.approx(-3.0)
    back = load_scenario(save_scenario(sc, tmp_path / "c.toml"))
    assert back.excitation == sc.excitation
    sp = scenario_from_dict(_toml({"type": "sine-pulse", "frequency": 2.0,
                                   "peak_acceleration": 3.0}))
    assert sp.excitation.peak_acceleration() == pytest.approx(3.0)
    for bad in ({"type": "cosine-pulse", "frequency": 2.0},
                {"type": "cosine-pulse", "frequency": 2.0, "amplitude": 0.01,
                 "peak_acceleration": 3.0},
                {"type": "cosine-pulse", "amplitude": 0.01},
                {"type": "cosine-pulse", "frequency": -1.0, "peak_acceleration": 3.0}):
        with pytest.raises(ScenarioError):
            scenario_from_dict(_toml(bad))


@pytest.mark.parametrize("a_ratio", [1.5, -3.0])
def test_cosine_pulse_linear_closed_form_matches_the_solver(rock, a_ratio):
    a_p, w = a_ratio * G * rock.lam, 2.0 * rock.p
    exc = CosinePulse.from_acceleration(a_p, w)
    t_out = np.linspace(0.0, exc.end_time, 401)
    sol = solve_single(rock, g=G, accel=exc.acceleration, breakpoints=exc.breakpoints,
                       end_time=exc.end_time, t_out=t_out, linear=True)
    assert sol.uplift_times[0] == 0.0
    t_imp = sol.impacts[0] if sol.impacts.size else exc.end_time
    m = sol.t < t_imp
    th, om = cosine_pulse_linear_response(rock.p, rock.lam, a_p, w, G, sol.t[m])
    np.testing.assert_allclose(sol.theta[m], th, atol=1e-9 * rock.lam)
    np.testing.assert_allclose(sol.theta_dot[m], om, atol=1e-8 * rock.p * rock.lam)
    assert np.all(np.sign(th[1:]) == -np.sign(a_p))
    with pytest.raises(ValueError):
        cosine_pulse_linear_response(rock.p, rock.lam, 0.5 * G * rock.lam, w, G, 0.1)


# ---------------------------------------------------------------------- independent solver
def _linear_cell(lam: float, p: float, eta: float, kind: str, a_p: float, w: float,
                 g: float = G, t_free: float = 40.0, max_impacts: int = 400) -> int:
    """Outcome code of a pulse on the linearised block, by closed-form event stepping.

    On side s the linearised equation θ'' = p²(θ − sλ) − p² ü_g/g with
    ü_g = a_p sin(ω t + φ) has θ = sλ + C sin(ωt + φ) + A cosh pτ + B sinh pτ,
    C = (a_p/g) p²/(p² + ω²). Events are found by dense sampling plus brentq.
    The block is followed after the pulse until it overturns (|θ| = π/2) or rests.
    """
    phi = 0.0 if kind == "sine" else 0.5 * math.pi
    t_pulse = 2 * math.pi / w
    thr = g * lam
    w_rest = 1e-7 * p * lam

    def acc(t: float) -> float:
        return a_p * math.sin(w * t + phi) if t <= t_pulse else 0.0

    def uplift_after(t0: float) -> float | None:
        tt = np.linspace(t0, t_pulse, 20001)
        av = np.abs(a_p * np.sin(w * tt + phi))
        over = np.flatnonzero(av > thr)
        if not over.size:
            return None
        i = int(over[0])
        if i == 0:
            return t0
        return brentq(lambda t: abs(a_p * math.sin(w * t + phi)) - thr, tt[i - 1], tt[i],
                      xtol=1e-14) + 1e-12

    def segment(t0: float, th0: float, om0: float, s: float, forced: bool):
        c = a_p / g * p * p / (p * p + w * w) if forced else 0.0
        a0 = th0 - s * lam - c * math.sin(w * t0 + phi)
        b0 = (om0 - c * w * math.cos(w * t0 + phi)) / p

        def th(t):
            tau = p * (np.asarray(t) - t0)
            return s * lam + c * np.sin(w * np.asarray(t) + phi) + a0 * np.cosh(tau) \
                + b0 * np.sinh(tau)

        def om(t):
            tau = p * (t - t0)
            return c * w * math.cos(w * t + phi) + p * (a0 * math.sinh(tau) + b0 * math.cosh(tau))
        return th, om

    t, th0, om0, s = 0.0, 0.0, 0.0, 1.0
    resting, impacts = True, 0
    t_stop = t_pulse + t_free / p
    while t < t_stop:
        if resting:
            tu = uplift_after(t) if t < t_pulse else None
            if tu is None:
                return NO_UPLIFT if impacts == 0 and t == 0.0 else SAFE
            t, th0, om0, s, resting = tu, 0.0, 0.0, -math.copysign(1.0, acc(tu)), False
        forced = t < t_pulse
        t_end = t_pulse if forced else t_stop
        th, om = segment(t, th0, om0, s, forced)
        tt = np.linspace(t, t_end, 4001)[1:]
        vals = s * th(tt)
        hit_zero = np.flatnonzero(vals <= 0.0)
        hit_over = np.flatnonzero(np.abs(th(tt)) >= 0.5 * math.pi)
        i0 = hit_zero[0] if hit_zero.size else tt.size
        i1 = hit_over[0] if hit_over.size else tt.size
        if i1 < i0:
            return impacts + 1
        if i0 == tt.size:  # end of the segment (pulse end): continue free
            t, th0, om0 = t_end, float(th(t_end)), om(t_end)
            continue
        if i0 == 0:  # impact within the first sample step: bracket on a finer grid
            fine = np.linspace(t, tt[0], 2001)[1:]
            j = int(np.flatnonzero(s * th(fine) <= 0.0)[0])
            if j == 0:  # a hop too short to resolve: the block is arrested
                resting, th0, om0 = True, 0.0, 0.0
                if t >= t_pulse:
                    return SAFE
                continue
            lo, hi = fine[j - 1], fine[j]
        else:
            lo, hi = tt[i0 - 1], tt[i0]
        ti = brentq(lambda x, s=s, th=th: s * float(th(x)), lo, hi, xtol=1e-15, rtol=1e-15)
        w_minus = om(ti)
        impacts += 1
        if impacts > max_impacts:
            return SAFE
        w_plus = eta * w_minus
        t = ti
        if abs(w_plus) < w_rest or w_minus * s > 0:
            resting, th0, om0 = True, 0.0, 0.0
            if t >= t_pulse:
                return SAFE
            continue
        th0, om0, s = 0.0, w_plus, math.copysign(1.0, w_plus)
    return SAFE


def _indep_boundary(rock, kind, w_ratio, lo, hi, tol=1e-4):
    def over(x):
        return _linear_cell(rock.lam, rock.p, rock.eta, kind, x * G * rock.lam,
                            w_ratio * rock.p) > SAFE
    assert over(lo) != over(hi)
    o_lo = over(lo)
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        if over(mid) == o_lo:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


@pytest.mark.parametrize("kind", ["sine", "cosine"])
def test_linear_cells_agree_with_the_independent_closed_form(rock, kind):
    a_grid = np.array([0.5, 1.5, 2.5, 4.0, 6.0, 9.0])
    for w_ratio in (0.8, 2.0, 5.0):
        col = scan_column(rock, kind, w_ratio, a_grid, g=G, linear=True, tol=None)
        ref = [_linear_cell(rock.lam, rock.p, rock.eta, kind, a * G * rock.lam,
                            w_ratio * rock.p) for a in a_grid]
        assert col.codes.tolist() == ref, (w_ratio, col.codes.tolist(), ref)


@pytest.mark.parametrize(("kind", "w_ratio"), [("sine", 2.0), ("sine", 5.0),
                                               ("cosine", 1.0), ("cosine", 4.0)])
def test_linear_first_boundary_matches_the_independent_closed_form(rock, kind, w_ratio):
    a_grid = np.linspace(0.0, 12.0, 25)
    col = scan_column(rock, kind, w_ratio, a_grid, g=G, linear=True, tol=1e-6, modes=False)
    first = col.minimum_overturning
    assert np.isfinite(first)
    i = int(np.searchsorted(a_grid, first))
    indep = _indep_boundary(rock, kind, w_ratio, a_grid[i - 1], a_grid[i], tol=1e-4)
    assert first == pytest.approx(indep, abs=1.5e-4)


def test_linear_mode1_boundary_of_the_specification(rock):
    """T13: linearised mode-1 boundary a_p/(g λ) = 2.34990313 at ω_p/p = 2 (closed form)."""
    col = scan_column(rock, "sine", 2.0, [2.3, 2.4], g=G, linear=True, tol=1e-7)
    modes = [b for b in col.boundaries if b.above == 1 or b.below == 1]
    assert modes and modes[0].a_ratio == pytest.approx(2.34990313, abs=1e-6)


@pytest.mark.parametrize(("w_ratio", "a_min"), [(2.0, 1.219869), (4.0, 1.725529)])
def test_exact_minimum_overturning_of_the_specification(rock, w_ratio, a_min):
    """T13: nonlinear minimum a_p/(g tan λ), reached after one impact (mode 2)."""
    a, code = minimum_overturning_acceleration(rock, "sine", w_ratio * rock.p, g=G, n_scan=60)
    assert a / (G * math.tan(rock.lam)) == pytest.approx(a_min, abs=2e-6)
    assert code == 2


# ---------------------------------------------------------------------- theory checks
@pytest.mark.parametrize("linear", [False, True], ids=["exact", "linear"])
@pytest.mark.parametrize("kind", ["sine", "cosine"])
def test_outcome_is_symmetric_under_sign_flip_of_the_pulse(rock, kind, linear):
    for w_ratio in (0.7, 3.0):
        for a in (0.9, 1.3, 2.5, 6.0):
            pos = normalised_outcome(rock, kind, a, w_ratio, g=G, linear=linear)
            neg = normalised_outcome(rock, kind, -a, w_ratio, g=G, linear=linear)
            assert (pos.code, pos.impacts) == (neg.code, neg.impacts)


@pytest.mark.parametrize("kind", ["sine", "cosine"])
def test_minimum_overturning_acceleration_grows_with_frequency(rock, kind):
    """Above ω_p/p ≈ 1 a faster pulse needs a larger acceleration to overturn."""
    w = np.array([1.0, 2.0, 3.0, 4.0]) if kind == "cosine" else np.array([1.0, 2.5, 4.0, 6.0])
    a_grid = np.linspace(0.0, 12.0, 25)
    firsts = [scan_column(rock, kind, x, a_grid, g=G, linear=True, tol=1e-2,
                          modes=False).minimum_overturning for x in w]
    assert np.all(np.isfinite(firsts)) and np.all(np.diff(firsts) > 0), firsts
    assert firsts[0] >= 1.0  # never below the uplift threshold g λ


def test_no_uplift_below_the_threshold_and_mode1_far_above(rock):
    for kind in ("sine", "cosine"):
        assert normalised_outcome(rock, kind, 0.99, 1.0, g=G, linear=True).code == NO_UPLIFT
        assert normalised_outcome(rock, kind, 30.0, 1.0, g=G).code == 1


def test_linear_map_depends_only_on_the_normalised_pulse_and_eta():
    """Linearised θ/λ depends on a_p/(gλ), ω_p/p and η only: two blocks, same numbers."""
    r1 = Block(1.0, 0.2, 5.0, mass=1.0).rocking(G)
    r2 = Block(0.3, 0.3, 2.0, mass=7.0).rocking(G)
    a = np.linspace(0.5, 8.0, 9)
    for w in (1.0, 3.0):
        c1 = scan_column(r1, "sine", w, a, g=G, linear=True, eta=0.9, tol=None).codes
        c2 = scan_column(r2, "sine", w, a, g=G, linear=True, eta=0.9, tol=None).codes
        assert c1.tolist() == c2.tolist()


@pytest.mark.parametrize("linear", [False, True], ids=["exact", "linear"])
def test_free_motion_fate_matches_integration(rock, linear):
    """The energy decision after a pulse against following the free motion with the solver."""
    rng = np.random.default_rng(3)
    lam, p = rock.lam, rock.p
    checked = 0
    for _ in range(40):
        th = rng.uniform(-1.3, 1.3) * lam
        om = rng.uniform(-1.2, 1.2) * p * lam
        over, n = free_motion_fate(th, om, lam=lam, p=p, eta=rock.eta, linear=linear)
        sol = solve_single(rock, g=G, accel=Free().acceleration, end_time=0.0, theta0=th,
                           omega0=om, t_out=np.array([0.0, 30.0 / p]), linear=linear)
        assert (sol.status == "overturned") == over, (th, om)
        if over:
            assert sol.impacts.size == n
        checked += 1
    assert checked == 40
    assert free_motion_fate(0.0, 0.0, lam=lam, p=p, eta=0.9) == (False, 0)


def test_housner_eta():
    assert housner_eta(B0.rocking(G).lam) == pytest.approx(B0.rocking(G).eta)


def test_scan_column_finds_islands_above_the_first_boundary(rock):
    """Zhang & Makris' safe region between the mode-2 and the mode-1 boundaries."""
    col = scan_column(rock, "sine", 4.0, np.linspace(0.0, 12.0, 61), g=G, tol=1e-3)
    kinds = [b.kind for b in col.boundaries]
    assert kinds[0] == "onset" and "island" in kinds
    over = col.codes > SAFE
    first = int(np.argmax(over))
    assert not over[first:].all()  # not monotone in a_p


# ---------------------------------------------------------------------- maps and CLI
def test_parse_block_refuses_a_prism():
    """A scenario whose first body is a prism has no block to map (it crashed later)."""
    with pytest.raises(ScenarioError, match="not a rectangular block"):
        parse_block("arch-9v-t0.15")


def test_parse_block_and_grid(tmp_path):
    b = parse_block("1x5")
    assert (b.block.width, b.block.height, b.g) == (1.0, 5.0, 9.81)
    cat = parse_block("free-b0")
    assert cat.block.height == 5.0 and cat.rock.lam == pytest.approx(B0.rocking(9.81).lam)
    assert parse_grid("40x60") == (40, 60)
    with pytest.raises(Exception, match="grid"):
        parse_grid("40")
    w, a = grid_axes(3, 4, (0.5, 10.0), (0.0, 12.0))
    assert w.tolist() == [0.5, 5.25, 10.0] and a[-1] == 12.0


def test_classify_engine_trajectories():
    lam = 0.2
    t = np.linspace(0, 1, 101)
    rest = Trajectory(t=t, theta=0.001 * np.sin(t)[:, None])
    assert classify_trajectory(rest, lam) == NO_UPLIFT
    rock_ = Trajectory(t=t, theta=0.1 * np.sin(10 * t)[:, None])
    assert classify_trajectory(rock_, lam) == SAFE
    fell = Trajectory(t=t, theta=-1.6 * t[:, None] ** 2, status=Status.OVERTURNED)
    assert classify_trajectory(fell, lam) == 1
    late = Trajectory(t=t, theta=np.where(t < 0.5, 0.1 * np.sin(4 * np.pi * t), 0.5 * t)[:, None])
    assert classify_trajectory(late, lam) == 3  # two sign changes, then beyond λ moving out
    crashed = Trajectory.failed(Status.CRASHED, "boom")
    assert classify_trajectory(crashed, lam) == FAILED


def test_analytic_map_in_parallel_equals_serial():
    spec = parse_block("1x5")
    w, a = grid_axes(4, 7, (0.5, 6.0), (0.0, 8.0))
    m1 = analytic_map(spec, "cosine", w, a, tol=1e-2, execution=ExecutionOptions(isolate=False))
    m2 = analytic_map(spec, "cosine", w, a, tol=1e-2, execution=ExecutionOptions(jobs=2))
    assert np.array_equal(m1.codes, m2.codes)
    np.testing.assert_allclose(m1.first_boundary(), m2.first_boundary())
    assert np.all(m1.codes[:, 0] == NO_UPLIFT)


def _pick_engine() -> str | None:
    from rockbench.engines import list_engines

    avail = {i.name for i in list_engines() if i.available and not i.analytic}
    return next((e for e in ("pymunk", "mujoco", "bullet") if e in avail), None)


def test_spectrum_command_end_to_end(tmp_path, capsys):
    engine = _pick_engine()
    if engine is None:
        pytest.skip("no physics engine installed (pymunk, mujoco or bullet)")
    out = tmp_path / "spec"
    rc = main(["spectrum", "--block", "0.17x1", "--pulse", "sine", "--engine", engine,
               "--grid", "5x6", "--engine-grid", "2x3", "--refine", "1", "--freq", "1:4",
               "--accel", "0:6", "--tol", "1e-2", "--jobs", "2", "--out", str(out)])
    assert rc == 0
    for name in ("spectrum.png", "boundary.csv", "cells.csv", "spectrum.json"):
        assert (out / name).stat().st_size > 0
    rows = list(csv.DictReader((out / "boundary.csv").open()))
    methods = {r["method"] for r in rows}
    assert "analytic" in methods and engine in methods
    first = [r for r in rows if r["method"] == "analytic" and r["first"] == "1"]
    assert len(first) == 5 and all(float(r["accel_ratio"]) >= 1.0 for r in first)
    cells = list(csv.DictReader((out / "cells.csv").open()))
    assert len([c for c in cells if c["method"] == engine]) == 6
    assert "overturning spectrum" in capsys.readouterr().out


def test_spectrum_command_bad_input(capsys):
    assert main(["spectrum", "--block", "nonsense-block", "--grid", "3x3"]) == 2
    assert main(["spectrum", "--grid", "3"]) == 2
    assert main(["spectrum", "--freq", "5:1", "--grid", "3x3"]) == 2
    assert main(["spectrum", "--refine", "-3", "--grid", "3x3"]) == 2
    assert main(["spectrum", "--timeout", "0", "--grid", "3x3"]) == 2
    assert main(["spectrum", "--grid", "3x3", "--out", "/proc/rockbench-no/spec"]) == 2
    err = capsys.readouterr().err
    assert err.count("rockbench: error:") == 6 and "--out /proc/rockbench-no" in err
    assert "--refine must be >= 0" in err and "--timeout must be" in err


def test_pulse_excitation_kinds():
    assert isinstance(pulse_excitation("sine", 1.0, 2.0), SinePulse)
    assert isinstance(pulse_excitation("cosine", 1.0, 2.0), CosinePulse)
    with pytest.raises(ValueError):
        pulse_excitation("square", 1.0, 2.0)
