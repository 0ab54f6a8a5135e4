"""Physics tests of the MuJoCo engine plugin against Housner's solution."""

from __future__ import annotations

import math

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from rockbench.analytic.housner import single_block_reference  # noqa: E402
from rockbench.engines import SettingsError, engine_class  # noqa: E402
from rockbench.engines.mujoco_engine import (  # noqa: E402
    MujocoEngine,
    MujocoSettings,
    restitution_dampratio,
)
from rockbench.scenarios import Block, Contact, Scenario, SinePulse, Stack  # noqa: E402
from rockbench.trajectory import Status  # noqa: E402

B0 = Block(1.0, 0.2, 5.0, mass=1.0)
B2 = Block(0.5, 0.2, 1.0, mass=1.0)
SINGLE2 = Block(0.17, 0.502, 1.0, density=2670.0)
PAPER_STACK = Stack((Block(0.20, 0.40, 0.60, density=2670.0, chamfer=0.005),
                     Block(0.15, 0.55, 0.60, density=2670.0, chamfer=0.005)))
#: Exact first impact times of B0 released at 0.5 λ (event-driven Housner).
B0_IMPACTS = np.array([0.7761248546, 2.1263229608, 3.3271341884])


def zero_crossings(t: np.ndarray, th: np.ndarray) -> np.ndarray:
    s = np.sign(th)
    i = np.nonzero(s[:-1] * s[1:] < 0)[0]
    return t[i] - th[i] * (t[i + 1] - t[i]) / (th[i + 1] - th[i])


def max_error(scenario: Scenario, theta: np.ndarray) -> float:
    """max |θ − θ_ref| / λ until the reference comes to rest."""
    ref = single_block_reference(scenario)
    rest = (ref.extra or {}).get("rest_time") or scenario.duration
    n = min(theta.size, ref.theta.shape[0])
    upto = ref.t[:n] <= rest
    return float(np.max(np.abs(theta[:n] - ref.theta[:n, 0])[upto])) / scenario.critical_angle


def test_registered_and_versioned() -> None:
    assert engine_class("mujoco") is MujocoEngine
    assert MujocoEngine.version() == mujoco.__version__
    assert MujocoEngine.settings("accurate") == MujocoSettings()
    assert set(MujocoEngine.presets) >= {"accurate", "fast"}


def test_b2_free_rocking_accurate() -> None:
    sc = Scenario("free-b2-0.5", B2, initial_tilt=0.5, duration=3.0)
    tr = MujocoEngine().simulate(sc, "accurate")
    assert tr.status == Status.OK
    th = tr.theta[:, 0]
    assert max_error(sc, th) <= 5e-3
    ref_imp = np.asarray(single_block_reference(sc).impacts)[:3]
    np.testing.assert_allclose(zero_crossings(tr.t, th)[:3], ref_imp, rtol=5e-3)
    assert np.max(tr.wobble) < 1e-6  # a planar problem stays planar


def test_b0_impact_times_accurate_and_fast() -> None:
    sc = Scenario("free-b0", B0, initial_tilt=0.5, duration=3.6)
    for preset, tol in (("accurate", 5e-3), ("fast", 0.05)):
        tr = MujocoEngine().simulate(sc, preset)
        assert tr.status == Status.OK
        th = tr.theta[:, 0]
        np.testing.assert_allclose(zero_crossings(tr.t, th)[:3], B0_IMPACTS, rtol=5e-3)
        assert max_error(sc, th) <= tol, preset


@pytest.mark.parametrize("preset", ["accurate", "fast"])
def test_sine_pulse_peak(preset: str) -> None:
    sc = Scenario("single-pulse-3.3hz-8mm", SINGLE2, excitation=SinePulse(3.3, 0.008),
                  duration=1.0)
    tr = MujocoEngine().simulate(sc, preset)
    assert tr.status == Status.OK
    ref = single_block_reference(sc)
    peak, peak_ref = np.max(np.abs(tr.theta[:, 0])), np.max(np.abs(ref.theta[:, 0]))
    assert abs(peak / peak_ref - 1.0) <= 0.02
    # a positive base acceleration first tips the block to θ < 0
    assert tr.theta[np.argmax(np.abs(tr.theta[:, 0] ) > 1e-3), 0] < 0


class _Probe(MujocoEngine):
    """Keeps the base position at teardown."""

    base_end = math.nan

    def _teardown(self) -> None:
        if self._data is not None:
            self.base_end = float(self._data.qpos[self._jq])
        super()._teardown()


def test_base_follows_excitation_then_stays_put() -> None:
    exc = SinePulse(5.0, 0.004)
    sc = Scenario("pulse", SINGLE2, excitation=exc, duration=0.6)  # pulse ends at 0.2 s
    eng = _Probe()
    tr = eng.simulate(sc, "fast")
    assert tr.status == Status.OK
    assert eng.base_end == pytest.approx(float(exc.displacement(exc.end_time)), abs=1e-9)


def test_stack_at_rest_stays_at_rest() -> None:
    sc = Scenario("paper-stack-rest", PAPER_STACK, duration=1.0)
    mjcf = MujocoEngine().mjcf(sc, MujocoSettings())
    assert mjcf.count('type="mesh"') == 2  # chamfered blocks are convex prisms
    tr = MujocoEngine().simulate(sc, "accurate")
    assert tr.status == Status.OK
    assert np.max(np.abs(tr.theta)) < 1e-6
    c0 = sc.stack.centroids
    assert np.max(np.abs(tr.x[-1] - c0[:, 0])) < 1e-6
    assert np.max(np.abs(tr.z[-1] - c0[:, 1])) < 1e-5  # contact penetration only


def test_stack_under_pulse_runs() -> None:
    sc = Scenario("paper-stack-pulse", PAPER_STACK, excitation=SinePulse(3.3, 0.004),
                  duration=1.0)
    tr = MujocoEngine().simulate(sc, "fast")
    assert tr.status == Status.OK
    assert np.all(np.isfinite(tr.theta))
    # both blocks travel with the base (displacement 2πA after the pulse)
    np.testing.assert_allclose(tr.x[-1] - tr.x[0], 2 * math.pi * 0.004, atol=5e-3)


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


def test_restitution_maps_to_dampratio() -> None:
    assert restitution_dampratio(0.0) == 1.0
    z = restitution_dampratio(0.5)
    assert 0 < z < 1
    # the linear oscillator with that damping ratio bounces back with e = 0.5
    assert math.exp(-z * math.pi / math.sqrt(1 - z * z)) == pytest.approx(0.5)
    sc = Scenario("bouncy", B2, Contact(1.0, 0.5), initial_tilt=0.5)
    xml = MujocoEngine().mjcf(sc, MujocoEngine.settings("fast"))
    model = mujoco.MjModel.from_xml_string(xml)
    np.testing.assert_allclose(model.geom_solref, [[4e-3, z]] * model.ngeom)


def test_unsupported_near_elastic() -> None:
    sc = Scenario("elastic", B2, Contact(1.0, 0.995), initial_tilt=0.5, duration=0.1)
    tr = MujocoEngine().simulate(sc)
    assert tr.status == Status.UNSUPPORTED
    assert "restitution" in tr.message
