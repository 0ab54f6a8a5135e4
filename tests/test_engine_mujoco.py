"""Physics tests of the MuJoCo engine plugin against Housner's solution."""

from __future__ import annotations

import math

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from engine_helpers import (  # noqa: E402
    B2,
    PAPER_STACK,
    SINGLE2,
    check_b0_impact_times_accurate_and_fast,
    check_b2_free_rocking_accurate,
    check_base_drives_y_and_z,
    check_base_follows_excitation,
    check_corner_release,
    check_cylinder_rocks_like_housner,
    check_paper_stack_under_pulse_runs,
    check_rides_a_base_along_y,
    check_rocks_about_x_like_housner,
    check_sine_pulse_peak,
    check_stack_follows_two_block,
    check_steady_precession,
)

from rockbench.engines import SettingsError, engine_class  # noqa: E402
from rockbench.engines.mujoco_engine import (  # noqa: E402
    MujocoEngine,
    MujocoSettings,
    restitution_dampratio,
)
from rockbench.scenarios import Contact, Scenario, SinePulse  # noqa: E402
from rockbench.scenarios.excitation import Components  # noqa: E402
from rockbench.studies.references_3d import drum_release, precession  # noqa: E402
from rockbench.trajectory import Status  # noqa: E402


def test_registered_and_versioned() -> None:
    assert engine_class("mujoco") is MujocoEngine
    assert MujocoEngine.version() == mujoco.__version__
    assert MujocoEngine.settings("accurate") == MujocoSettings()
    assert set(MujocoEngine.presets) >= {"accurate", "fast"}


def test_b2_free_rocking_accurate() -> None:
    tr = check_b2_free_rocking_accurate(MujocoEngine())
    assert np.max(tr.wobble) < 1e-6  # a planar problem stays planar


def test_b0_impact_times_accurate_and_fast() -> None:
    check_b0_impact_times_accurate_and_fast(MujocoEngine())


@pytest.mark.parametrize("preset", ["accurate", "fast"])
def test_sine_pulse_peak(preset: str) -> None:
    check_sine_pulse_peak(MujocoEngine(), preset)


class _Probe(MujocoEngine):
    """Keeps the base position at teardown."""

    base_end = math.nan

    def _teardown(self) -> None:
        if self._data is not None:
            self.base_end = float(self._data.qpos[self._jq])
        super()._teardown()


def test_base_follows_excitation_then_stays_put() -> None:
    check_base_follows_excitation(_Probe(), "fast", 1e-9)


def test_stack_at_rest_stays_at_rest() -> None:
    sc = Scenario("paper-stack-rest", PAPER_STACK, duration=1.0)
    mjcf = MujocoEngine().mjcf(sc, MujocoSettings())
    assert mjcf.count('type="mesh"') == 2  # chamfered blocks are convex prisms
    tr = MujocoEngine().simulate(sc, "accurate")
    assert tr.status == Status.OK
    assert np.max(np.abs(tr.theta)) < 1e-6
    c0 = sc.geometry.centroids
    assert np.max(np.abs(tr.x[-1] - c0[:, 0])) < 1e-6
    assert np.max(np.abs(tr.z[-1] - c0[:, 1])) < 1e-5  # contact penetration only


def test_stack_under_pulse_runs() -> None:
    check_paper_stack_under_pulse_runs(MujocoEngine())


@pytest.mark.parametrize("case, tol", [("stack-pulse-5.0hz-4mm", 0.02),
                                        ("stack-sine-5.0hz-4mm", 0.05)])
def test_stack_follows_the_two_block_solution(case: str, tol: float) -> None:
    # the top block lifts to 0.48 λ (pulse) and 0.39 λ (sinusoid, 10 s); with critical
    # contact damping each interface impact bounced the upper block off its new pivot and
    # the sinusoid's peaks came out 43 % / 26 % low with 5.8e-4 m of interface slip
    # the interface stays stuck and closed (measured: < 2e-5 m of slip, < 2.3e-5 m of gap)
    check_stack_follows_two_block(MujocoEngine(), case, tol, slip=3e-5, gap=4e-5)


def test_knob_overrides_take_effect() -> None:
    sc = Scenario("free-b2-short", B2, initial_tilt=0.5, duration=0.8)
    eng = MujocoEngine()
    fine = eng.simulate(sc, "fast")
    coarse = eng.simulate(sc, {"preset": "fast", "timestep": "5e-4", "timeconst_factor": 8})
    assert coarse.settings["timestep"] == 5e-4
    assert coarse.settings["effective_timestep"] == pytest.approx(5e-4)
    assert not np.allclose(fine.theta, coarse.theta, atol=1e-6)
    s = MujocoEngine.settings("fast", integrator="implicitfast", noslip_iterations="3")
    assert s.integrator == "implicitfast" and s.noslip_iterations == 3
    with pytest.raises(SettingsError):
        MujocoEngine.settings(timestep=-1.0)
    with pytest.raises(SettingsError):
        MujocoEngine.settings(integrator="RK4")
    with pytest.raises(SettingsError):
        MujocoEngine.settings(no_such_knob=1)


def test_noslip_tolerance_reaches_the_model() -> None:
    # MuJoCo's default no-slip tolerance (1e-6) ends the pass after ~2 iterations (the
    # sliding cases gave the same trajectories with 20 and 100); 0 runs every one
    sc = Scenario("resting", B2, duration=0.01)
    iterations = {}
    for tol in ("1e-6", "0"):
        s = MujocoEngine.settings("accurate", noslip_iterations="30", noslip_tolerance=tol)
        model = mujoco.MjModel.from_xml_string(MujocoEngine().mjcf(sc, s))
        assert model.opt.noslip_tolerance == float(tol) and model.opt.noslip_iterations == 30
        data = mujoco.MjData(model)
        mujoco.mj_step(model, data, 2)  # the first step finds the contacts at zero depth
        assert data.ncon == 4
        iterations[tol] = int(data.solver_niter[0])  # main solver + no-slip passes
    assert MujocoSettings().noslip_tolerance == 1e-6
    assert iterations["1e-6"] < 10 and iterations["0"] == 31  # measured: 3 and 31
    with pytest.raises(SettingsError):
        MujocoEngine.settings(noslip_tolerance=-1e-9)


def test_restitution_maps_to_dampratio() -> None:
    assert restitution_dampratio(0.0) == 1.0
    z = restitution_dampratio(0.5)
    assert 0 < z < 1
    # the linear oscillator with that damping ratio bounces back with e = 0.5
    assert math.exp(-z * math.pi / math.sqrt(1 - z * z)) == pytest.approx(0.5)
    sc = Scenario("bouncy", B2, Contact(1.0, 0.5), initial_tilt=0.5)
    s = MujocoEngine.settings("fast")
    model = mujoco.MjModel.from_xml_string(MujocoEngine().mjcf(sc, s))
    # time constant τ = timeconst_factor · dt (2 ms at fast), damping ratio from e
    np.testing.assert_allclose(model.geom_solref, [[2e-3, z]] * model.ngeom)
    assert s.timeconst_factor * s.timestep == pytest.approx(2e-3)


def test_unsupported_near_elastic() -> None:
    sc = Scenario("elastic", B2, Contact(1.0, 0.995), initial_tilt=0.5, duration=0.1)
    tr = MujocoEngine().simulate(sc)
    assert tr.status == Status.UNSUPPORTED
    assert "restitution" in tr.message


# ---------------------------------------------------------------- base motion along y and z
def test_mjcf_has_a_slide_joint_per_moving_axis() -> None:
    assert MujocoEngine.capabilities.base_axes == "xyz"
    s = MujocoSettings()
    planar = MujocoEngine().mjcf(Scenario("x", SINGLE2, excitation=SinePulse(3.0, 0.008)), s)
    assert planar.count('type="slide"') == 1 and 'axis="1 0 0"' in planar
    yz = Components(y=SinePulse(3.0, 0.008), z=SinePulse(4.0, 0.003))
    mjcf = MujocoEngine().mjcf(Scenario("yz", SINGLE2, excitation=yz), s)
    assert mjcf.count('type="slide"') == 2 and 'name="slide_y"' in mjcf \
        and 'name="slide_z"' in mjcf and 'axis="1 0 0"' not in mjcf


def test_base_drives_y_and_z() -> None:
    """The engines' common check: Single #2 rides a base moving vertically and is carried
    by friction along y (this engine has no planar knob)."""
    # measured: z within 3.4e-7 m, the y drag's end within 3.9e-10 m
    check_base_drives_y_and_z(MujocoEngine(), z_tol=2e-6, planar=False)


def test_a_base_moving_along_y_carries_the_block() -> None:
    # measured: y within 7.1e-6 m of the base
    check_rides_a_base_along_y(MujocoEngine(), y_tol=2e-5)


def test_a_block_excited_along_y_rocks_about_x_like_housner() -> None:
    # measured: the roll within 1.2e-3 λ of −θ_ref
    check_rocks_about_x_like_housner(MujocoEngine(), plane_tol=1e-6)


# ---------------------------------------------------------------- cylinders and 3D starts
def test_a_cylinder_is_built_as_a_cylinder() -> None:
    mjcf = MujocoEngine().mjcf(drum_release(), MujocoSettings())
    assert 'type="cylinder" size="0.15 0.5"' in mjcf and 'type="box" size="0.15' not in mjcf


@pytest.mark.parametrize("preset, rel", [("accurate", 5e-4), ("fast", 3e-3)])
def test_a_drum_rocks_in_plane_like_housner(preset: str, rel: float) -> None:
    # measured: first impact −0.017 % (accurate), −0.15 % (fast); roll before it ≤ 9e-8 rad
    check_cylinder_rocks_like_housner(MujocoEngine(), preset, rel=rel, plane_tol=1e-6)


@pytest.mark.parametrize("preset, rel", [("accurate", 3e-4), ("fast", 3e-3)])
def test_a_pillar_released_on_its_corner_rocks_along_its_diagonal(preset: str,
                                                                   rel: float) -> None:
    # measured: landing −0.009 % (accurate), −0.13 % (fast); |θ + roll| ≤ 3e-16 rad
    check_corner_release(MujocoEngine(), preset, rel=rel, diagonal_tol=1e-9)


@pytest.mark.parametrize("preset", ["accurate", "fast"])
def test_a_cylinder_in_steady_precession_holds_its_tilt(preset: str) -> None:
    # measured over 2 s: tilt within 4.5e-4 rad (both presets), rate within 0.03 %
    check_steady_precession(MujocoEngine(), preset, tilt_tol=1e-3, rate_rtol=1e-3)


def test_a_soft_contact_lets_the_precession_creep() -> None:
    """MuJoCo's answer hangs on the contact's time constant, which no planar case shows:
    at 200 steps (its default 0.02 s) the tilt drifts ten times as far as at 2 steps."""
    sc, sp = precession(2.0)
    stiff = MujocoEngine().simulate(sc, "accurate")
    soft = MujocoEngine().simulate(sc, {"preset": "accurate", "timeconst_factor": 200})
    drift = [np.max(np.abs(tr.tilt[:, 0] - sp.theta)) for tr in (stiff, soft)]
    assert drift[1] > 5 * drift[0]
