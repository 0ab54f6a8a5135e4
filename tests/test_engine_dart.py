"""Physics tests of the DART engine plugin (``rockbench.engines.dart_engine``)."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("dartpy")

from rockbench.engines.dart_engine import DartEngine, DartSettings, _prism_obj  # noqa: E402
from rockbench.engines.settings import SettingsError  # noqa: E402
from rockbench.scenarios import Block, Scenario, SinePulse, Stack  # noqa: E402

B0 = Block(1.0, 0.2, 5.0, mass=1.0)
B2 = Block(0.5, 0.2, 1.0, mass=1.0)
SINGLE2 = Block(width=0.17, depth=0.502, height=1.0, density=2670.0)
PAPER_STACK = Stack((Block(0.20, 0.40, 0.60, density=2670.0, chamfer=0.005),
                     Block(0.15, 0.55, 0.60, density=2670.0, chamfer=0.005)))


def housner(scenario: Scenario) -> np.ndarray:
    """θ_ref on the output times: the project's reference if present, else a
    compact event-driven Housner integration (DOP853, tight tolerances)."""
    try:
        from rockbench.analytic.housner import single_block_reference
    except ImportError:
        single_block_reference = None
    t_out = scenario.output_times()
    if single_block_reference is not None:
        ref = single_block_reference(scenario)
        th = np.asarray(ref.theta)
        th = th[:, 0] if th.ndim == 2 else th
        return np.interp(t_out, np.asarray(ref.t), th)
    from scipy.integrate import solve_ivp

    rp = scenario.blocks[0].rocking(scenario.g)
    lam, p, g, eta = rp.lam, rp.p, scenario.g, rp.eta
    exc = scenario.excitation

    def rhs(t: float, y: np.ndarray) -> list[float]:
        s = 1.0 if y[0] > 0 else -1.0
        a = float(exc.acceleration(t))
        return [y[1], -p * p * (math.sin(s * lam - y[0]) + a / g * math.cos(s * lam - y[0]))]

    out = np.zeros_like(t_out)
    fine = np.linspace(0.0, t_out[-1], int(t_out[-1] * 20000) + 1)
    a_fine = np.asarray(exc.acceleration(fine), float)
    t, y, resting = 0.0, np.array([scenario.theta0, 0.0]), scenario.theta0 == 0.0
    while t < t_out[-1]:
        if resting:
            idx = np.nonzero((fine > t) & (np.abs(a_fine) > g * math.tan(lam)))[0]
            if idx.size == 0:
                break
            t, resting = float(fine[idx[0]]), False
            y = np.array([-math.copysign(1e-12, a_fine[idx[0]]), 0.0])
            continue

        def hit(_t: float, yy: np.ndarray) -> float:
            return yy[0]

        hit.terminal, hit.direction = True, -math.copysign(1.0, y[0])
        sol = solve_ivp(rhs, (t, t_out[-1]), y, method="DOP853", rtol=1e-11, atol=1e-13,
                        events=hit, dense_output=True, max_step=5e-3)
        m = (t_out >= t) & (t_out <= sol.t[-1])
        if m.any():
            out[m] = sol.sol(t_out[m])[0]
        if sol.status != 1:
            break
        t, om = float(sol.t_events[0][0]), float(sol.y_events[0][0][1]) * eta
        resting = abs(om) < 1e-4
        y = np.array([math.copysign(1e-13, om), om])
    return out


def crossings(t: np.ndarray, th: np.ndarray, n: int = 3) -> np.ndarray:
    s = np.sign(th)
    i = np.nonzero(s[:-1] * s[1:] < 0)[0][:n]
    return t[i] - th[i] * (t[i + 1] - t[i]) / (th[i + 1] - th[i])


def test_free_rocking_b2_accurate_matches_housner() -> None:
    sc = Scenario("free-b2-0.5", B2, initial_tilt=0.5, duration=2.5)
    traj = DartEngine().simulate(sc, "accurate")
    assert traj.status == "ok", traj.message
    lam = sc.critical_angle
    ref = housner(sc)
    th = traj.theta[:, 0]
    assert np.max(np.abs(th - ref)) / lam <= 5e-3
    t = sc.output_times()
    tc, tc_ref = crossings(t, th), crossings(t, ref)
    assert tc.size == 3
    np.testing.assert_allclose(tc, tc_ref, rtol=5e-3)
    assert np.max(traj.wobble) < 1e-6  # planar motion stays planar


def test_free_rocking_b0_fast_within_5_percent_of_lambda() -> None:
    sc = Scenario("free-b0", B0, initial_tilt=0.5, duration=4.0)
    traj = DartEngine().simulate(sc, "fast")
    assert traj.status == "ok", traj.message
    err = np.max(np.abs(traj.theta[:, 0] - housner(sc))) / sc.critical_angle
    assert err <= 0.05
    # the first impact of B0 (closed form: 0.7761248546 s)
    assert crossings(sc.output_times(), traj.theta[:, 0], 1)[0] == pytest.approx(0.7761248546,
                                                                                 rel=5e-3)


def test_mirror_symmetry_fast() -> None:
    eng = DartEngine()
    sc = Scenario("m", B2, initial_tilt=0.5, duration=1.0)
    a = eng.simulate(sc, "fast").theta[:, 0]
    b = eng.simulate(sc.replace(initial_tilt=-0.5), "fast").theta[:, 0]
    np.testing.assert_allclose(a, -b, atol=1e-6 * sc.critical_angle)


def test_forced_pulse_peak_within_2_percent() -> None:
    sc = Scenario("single-pulse-3.0hz-8mm", SINGLE2,
                  excitation=SinePulse(frequency=3.0, amplitude=0.008), duration=1.5)
    ref = housner(sc)
    traj = DartEngine().simulate(sc, "accurate")
    assert traj.status == "ok", traj.message
    i_ref = int(np.argmax(np.abs(ref)))
    assert i_ref < ref.size - 50, "the reference peak must lie inside the window"
    peak, peak_ref = np.max(np.abs(traj.theta[:, 0])), np.max(np.abs(ref))
    assert abs(peak / peak_ref - 1.0) <= 0.02
    assert np.sign(traj.theta[i_ref, 0]) == np.sign(ref[i_ref])


def test_base_follows_excitation_displacement() -> None:
    exc = SinePulse(frequency=5.0, amplitude=0.004)
    sc = Scenario("drive", SINGLE2, excitation=exc, duration=0.3)
    eng = DartEngine()
    dt = eng._build(sc, eng.settings("fast"))
    n = int(round(0.1 / dt))
    eng._advance_driven(0.0, n, dt)
    assert eng._base_joint.getPosition(0) == pytest.approx(float(exc.displacement(n * dt)),
                                                           abs=1e-12)
    eng._teardown()


@pytest.mark.parametrize("stack, preset", [
    (Stack((Block(0.4, 0.3, 0.8, mass=10.0), Block(0.3, 0.3, 0.6, mass=5.0))), "fast"),
    (PAPER_STACK, "fast"),
    (PAPER_STACK, "accurate"),
])
def test_stack_at_rest_stays_at_rest(stack: Stack, preset: str) -> None:
    sc = Scenario("rest", stack, duration=0.5)
    traj = DartEngine().simulate(sc, preset)
    assert traj.status == "ok", traj.message
    assert np.max(np.abs(traj.theta)) < 1e-4 * sc.critical_angle
    z0 = sc.stack.centroids[:, 1]
    np.testing.assert_allclose(traj.z[-1], z0, atol=1e-4)
    np.testing.assert_allclose(traj.x[-1], 0.0, atol=1e-5)


def test_paper_stack_under_pulse_runs_sensibly() -> None:
    sc = Scenario("stack-pulse-3.3hz-8mm", PAPER_STACK,
                  excitation=SinePulse(frequency=3.3, amplitude=0.008), duration=1.5)
    traj = DartEngine().simulate(sc, "fast")
    assert traj.status == "ok", traj.message
    lam = sc.critical_angle
    peak = np.max(np.abs(traj.theta), axis=0) / lam
    assert np.all(peak > 0.05) and np.all(peak < 2.0)  # both blocks uplift, none overturns
    assert np.max(traj.wobble) < 1e-3  # no spurious out-of-plane motion
    # the base ends displaced by 2πA and the blocks travel with it
    assert np.all(np.abs(traj.x[-1] - 2 * math.pi * 0.008) < 0.1)


@pytest.mark.parametrize("shape", ["narrow_box", "mesh"])
def test_chamfered_block_pivots_inward(shape: str) -> None:
    # a chamfered block tilted by 0.5 λ rocks about its chamfer corners: the
    # first impact matches Housner with pivots at ±(b − c)
    blk = Block(0.5, 0.2, 1.0, mass=1.0, chamfer=0.02)
    sc = Scenario("cham", blk, initial_tilt=0.5, duration=0.6)
    traj = DartEngine().simulate(sc, {"preset": "fast", "chamfer_shape": shape})
    assert traj.status == "ok", traj.message
    t = sc.output_times()
    t1 = crossings(t, traj.theta[:, 0], 1)[0]
    assert t1 == pytest.approx(crossings(t, housner(sc), 1)[0], rel=5e-3)


def test_prism_obj_is_closed_and_outward(tmp_path) -> None:
    blk = Block(0.2, 0.4, 0.6, mass=1.0, chamfer=0.01)
    path = tmp_path / "p.obj"
    _prism_obj(blk, str(path))
    v, f = [], []
    for line in path.read_text().splitlines():
        kind, *rest = line.split()
        (v if kind == "v" else f).append([float(x) if kind == "v" else int(x) - 1 for x in rest])
    v, f = np.array(v), np.array(f)
    # signed volume by the divergence theorem: positive only with outward normals
    vol = np.sum(np.einsum("ij,ij->i", v[f[:, 0]], np.cross(v[f[:, 1]], v[f[:, 2]]))) / 6.0
    area = blk.width * blk.height - 2.0 * blk.chamfer**2
    assert vol == pytest.approx(area * blk.depth, rel=1e-12)


def test_knob_overrides_take_effect() -> None:
    sc = Scenario("knob", B2, initial_tilt=0.5, duration=0.5)
    eng = DartEngine()
    a = eng.simulate(sc, "fast")
    b = eng.simulate(sc, {"preset": "fast", "timestep": "5e-4"})
    assert b.settings["effective_timestep"] == pytest.approx(5e-4)
    assert a.settings["effective_timestep"] == pytest.approx(1e-3)
    assert np.max(np.abs(a.theta - b.theta)) > 1e-6
    c = eng.simulate(sc, {"preset": "fast", "lcp_solver": "pgs"})
    assert c.status == "ok" and c.settings["lcp_solver"] == "pgs"
    assert DartEngine.settings() == DartSettings(**DartEngine.presets["accurate"])
    with pytest.raises(SettingsError):
        DartEngine.settings(timestep=-1.0)
    with pytest.raises(SettingsError):
        DartEngine.settings(collision_detector="havok")


def test_chamfer_mesh_with_dart_detector_is_unsupported() -> None:
    sc = Scenario("cham", Block(0.5, 0.2, 1.0, mass=1.0, chamfer=0.01), initial_tilt=0.3,
                  duration=0.05)
    eng = DartEngine()
    traj = eng.simulate(sc, {"preset": "fast", "collision_detector": "dart",
                             "chamfer_shape": "mesh"})
    assert traj.status == "unsupported"
    assert "mesh" in traj.message
    # the default shape (a box with the prism's flat faces) works with it
    ok = eng.simulate(sc, {"preset": "fast", "collision_detector": "dart"})
    assert ok.status == "ok", ok.message
