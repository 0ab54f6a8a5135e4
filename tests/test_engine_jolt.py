"""Physics tests of the Jolt engine plugin (culverin) against Housner and closed forms.

The tolerances are the project's where Jolt meets them, else the measured values with a
margin (each one says which); the calibration behind them is on docs/engines/jolt.md.
culverin has wheels for CPython >= 3.12 only: elsewhere the module is skipped.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rockbench.engines.jolt_engine import DAMPING, JoltEngine, JoltSettings, _gyroscopic
from rockbench.errors import EngineUnavailable

try:
    JoltEngine.check_available()
except EngineUnavailable as exc:  # pragma: no cover - depends on the environment
    pytest.skip(str(exc), allow_module_level=True)

from engine_helpers import (  # noqa: E402
    B2,
    PAPER_STACK,
    SINGLE2,
    check_assembly_stays_at_rest,
    check_base_drives_y_and_z,
    check_corner_release,
    check_cylinder_rocks_like_housner,
    check_mirrored_release,
    check_paper_stack_under_pulse_runs,
    check_pulse_rocks_without_overturning,
    check_sine_pulse_peak,
    check_slides_like_coulomb,
    check_stack_follows_two_block,
    check_steady_precession,
    inclined_scene,
    lam,
    max_error,
    zero_crossings,
)

from rockbench.analytic import reference, slip_of  # noqa: E402
from rockbench.analytic.housner import single_block_reference  # noqa: E402
from rockbench.engines import EngineSettings, SettingsError, get_engine  # noqa: E402
from rockbench.engines.base import OVERTURN_MARGIN  # noqa: E402
from rockbench.engines.testing import parametrize_with_checks  # noqa: E402
from rockbench.geometry import Block, Cylinder, single  # noqa: E402
from rockbench.scenarios import (  # noqa: E402
    Contact,
    Scenario,
    SinePulse,
    get_scenario,
)
from rockbench.trajectory import Status  # noqa: E402


@pytest.fixture(scope="module")
def engine() -> JoltEngine:
    eng = get_engine("jolt")
    assert isinstance(eng, JoltEngine)
    return eng


def free_b2(duration: float = 3.0, tilt: float = 0.5) -> Scenario:
    return Scenario(f"free-b2-{tilt}", B2, initial_tilt=tilt, duration=duration)


# ---------------------------------------------------------------- the conformance kit
@pytest.mark.slow
@parametrize_with_checks([JoltEngine])
def test_conformance(engine, check):
    check(engine)


# ---------------------------------------------------------------- registry and settings
def test_registry_and_presets(engine: JoltEngine) -> None:
    assert engine.name == "jolt" and engine.capabilities.dimensions == 3
    assert engine.capabilities.base_axes == "xyz" and engine.capabilities.assemblies
    assert engine.version().startswith("0.")
    assert {"accurate", "fast", "game"} <= set(engine.presets)
    assert engine.settings("accurate") == engine.Settings()
    fast = engine.settings("fast")
    assert isinstance(fast, JoltSettings)
    assert fast.timestep == 2e-4 and fast.cancel_damping and fast.small_rotations
    game = engine.settings("game")
    assert isinstance(game, JoltSettings)
    # culverin's step() default and Jolt's behaviour left alone
    assert game.timestep == pytest.approx(1 / 60)
    assert not (game.cancel_damping or game.small_rotations or game.gyroscopic or game.planar
                or game.ccd)
    assert engine.capabilities.cylinders and engine.capabilities.start3d
    assert engine.settings(timestep="5e-5").timestep == 5e-5
    for bad in ({"timestep": -1e-4}, {"timestep": 0.0}, {"chamfer_shape": "sphere"}):
        with pytest.raises(SettingsError):
            engine.settings(**bad)
    with pytest.raises(AttributeError):
        JoltSettings().timestep = 1.0  # type: ignore[misc]


# ---------------------------------------------------------------- what culverin does
def _world(c, gravity: float = 0.0):
    return c.PhysicsWorld(settings={"gravity": (0.0, 0.0, -gravity), "num_threads": 1})


def test_culverin_facts_the_plugin_relies_on() -> None:
    """Jolt as culverin 0.15 builds it (each fact is why a knob exists): every dynamic body
    is damped by 0.05 /s; a step turning a body by ≤ 1e-6 rad leaves it unturned; the
    friction of a pair is the geometric mean of its bodies'."""
    c = JoltEngine.library("culverin")
    w = _world(c)
    spin = w.create_body(pos=(0, 0, 0), size=(0.25, 0.1, 0.5), shape=c.SHAPE_BOX, mass=1.0)
    slow = w.create_body(pos=(5, 0, 0), size=(0.25, 0.1, 0.5), shape=c.SHAPE_BOX, mass=1.0)
    w.step(0.0)
    w.set_angular_velocity(spin, 0.0, 1.0, 0.0)
    w.set_angular_velocity(slow, 0.0, 0.009, 0.0)  # 9e-7 rad per 0.1 ms step
    for _ in range(1000):
        w.step(1e-4)
    # (float32 velocities: 2e-5 off the double-precision product)
    assert w.get_angular_velocity(spin)[1] == pytest.approx((1 - DAMPING * 1e-4) ** 1000,
                                                            rel=1e-4)
    assert w.get_rotation(slow) == (0.0, 0.0, 0.0, 1.0)  # 0.09 s at 0.009 rad/s: not turned
    # a block sliding at 1 m/s on μ 1.0 and 0.04: decelerates at √0.04 g (+ the damping)
    w = _world(c, 9.81)
    w.create_body(pos=(0, 0, -1), size=(50, 5, 1), shape=c.SHAPE_BOX, motion=c.MOTION_STATIC,
                  friction=1.0)
    box = w.create_body(pos=(0, 0, 0.1), size=(0.25, 0.25, 0.1), shape=c.SHAPE_BOX, mass=1.0,
                        friction=0.04)
    w.step(0.0)
    for _ in range(100):
        w.step(1e-3)
    w.set_linear_velocity(box, 1.0, 0.0, 0.0)
    for _ in range(200):
        w.step(1e-3)
    mu = (1.0 - w.get_velocity(box)[0]) / (0.2 * 9.81)
    assert mu == pytest.approx(0.2 + DAMPING * 0.9 / 9.81, abs=2e-3)


# ---------------------------------------------------------------- free rocking
def test_free_rocking_accurate(engine: JoltEngine) -> None:
    """B2 from 0.5 λ for 3 s: within 7.5e-3 λ of Housner (measured 0.0050, a hair over the
    project's 5e-3: the limit is 1.5× the measured value; 0.0026 without the added small
    turns), the first three impact times within the project's 0.5 %, wobble below 0.02 rad."""
    sc = free_b2()
    tr = engine.simulate(sc, "accurate")
    assert tr.status is Status.OK
    th = tr.theta[:, 0]
    assert max_error(sc, th) <= 7.5e-3
    impacts = np.asarray(single_block_reference(sc).impacts)[:3]
    np.testing.assert_allclose(zero_crossings(tr.t, th)[:3], impacts, rtol=5e-3)
    assert np.max(tr.wobble) < 0.02
    assert tr.theta[0, 0] == pytest.approx(sc.theta0, rel=1e-6)  # float32 rotations
    assert tr.settings["effective_timestep"] == pytest.approx(1e-4)


def test_free_rocking_fast(engine: JoltEngine) -> None:
    """fast: within the project's 0.05 λ (measured 0.0067 on B2 over 3 s)."""
    sc = free_b2()
    fast = engine.simulate(sc, "fast")
    assert fast.status is Status.OK and max_error(sc, fast.theta[:, 0]) <= 0.05


@pytest.mark.slow
def test_jolt_damping_is_cancelled(engine: JoltEngine) -> None:
    """With Jolt's 0.05 /s damping left on, B2 loses amplitude: 0.015 λ off over 5 s against
    0.0050 cancelled (measured; the limits are 2× and 1.5× those)."""
    sc = free_b2(5.0)
    on = max_error(sc, engine.simulate(sc, "accurate").theta[:, 0])
    off = max_error(sc, engine.simulate(sc, {"cancel_damping": False}).theta[:, 0])
    assert on <= 0.0075 and off > 2 * on


def test_slow_turns_are_not_dropped(engine: JoltEngine) -> None:
    """B2 released at 0.99 λ turns at first slower than 1e-6 rad per step: Jolt drops those
    turns and the block hangs at its start while its centre of mass moves (0.084 λ off
    over 2 s, measured); with the turns added, 0.0041 λ (the limits: 0.01 and 0.05 λ)."""
    sc = free_b2(2.0, 0.99)
    added = engine.simulate(sc, "accurate")
    dropped = engine.simulate(sc, {"small_rotations": False})
    assert max_error(sc, added.theta[:, 0]) <= 0.01
    assert max_error(sc, dropped.theta[:, 0]) > 0.05


def test_sign_convention_and_mirror_symmetry(engine: JoltEngine) -> None:
    """θ > 0 pivots on the +x edge; −tilt mirrors it (to float32 rounding)."""
    check_mirrored_release(engine)


# ---------------------------------------------------------------- pulses
def test_sine_pulse_peak(engine: JoltEngine) -> None:
    # Single #2 under 3.3 Hz / 8 mm: the peak within the project's 2 % at both presets
    # (measured −0.29 % accurate, −0.43 % fast)
    check_sine_pulse_peak(engine, "accurate")
    check_sine_pulse_peak(engine, "fast")


def test_a_pulse_that_rocks_without_overturning(engine: JoltEngine) -> None:
    # measured −0.38 %
    check_pulse_rocks_without_overturning(engine)


def test_a_pulse_that_overturns(engine: JoltEngine) -> None:
    """Single #2 under sine pulses at 3 × its uplift acceleration overturns, as the
    reference does."""
    lam2 = SINGLE2.rocking().lam
    for f in (2.0, 1.0):
        amp = 3.0 * 9.81 * math.tan(lam2) / (2 * math.pi * f) ** 2
        sc = Scenario("overturn", SINGLE2, excitation=SinePulse(f, amp), duration=3.0)
        assert reference(sc).status is Status.OVERTURNED
        tr = engine.simulate(sc, "accurate")
        assert tr.status is Status.OVERTURNED, tr.message
        assert abs(tr.theta[-1, 0]) > math.pi / 2 - OVERTURN_MARGIN


def test_a_pulse_below_the_uplift_threshold_carries_the_block(engine: JoltEngine) -> None:
    f = 3.0
    amp = 0.8 * 9.81 * math.tan(SINGLE2.rocking().lam) / (2 * math.pi * f) ** 2
    sc = Scenario("ride", SINGLE2, excitation=SinePulse(f, amp), duration=1.0)
    tr = engine.simulate(sc, "accurate")
    assert tr.status is Status.OK
    assert np.max(np.abs(tr.theta)) < 1e-4 * lam(sc)
    u = sc.motion.x.displacement(tr.t)
    assert np.max(np.abs(tr.x[:, 0] - u)) < 2e-6  # measured 1.7e-8 m
    assert tr.x[-1, 0] == pytest.approx(2 * math.pi * amp, abs=1e-5)


def test_frictionless_base_slides_under_the_block(engine: JoltEngine) -> None:
    """Friction comes from the scenario: with μ = 0 the moving base cannot drag the block."""
    sc = Scenario("slide", SINGLE2, Contact(0.0, 0.0), SinePulse(3.0, 0.004), duration=0.5)
    tr = engine.simulate(sc, "fast")
    assert tr.status is Status.OK
    assert np.max(np.abs(tr.x[:, 0])) < 1e-5  # the base travels 2πA = 25 mm
    assert np.max(np.abs(tr.theta)) < 1e-5


def test_sliding_follows_the_coulomb_slider(engine: JoltEngine) -> None:
    """Every pair sees the scenario's μ (geometric mean of μ on each body): B2 slides on
    μ = 0.2 like the exact Coulomb slider (within the project's 1 % of the peak exact slip,
    measured below 0.01 %)."""
    sc = get_scenario("slide-b2-pulse-2.0hz-20mm-mu0.20")
    check_slides_like_coulomb(sc, engine.simulate(sc, "accurate"), reference(sc))


def test_interface_friction_of_a_stack(engine: JoltEngine) -> None:
    """A stack whose interface alone is slippery (μ 0.25 on the base, μ_if 0.05): each pair
    sees its own coefficient, the upper block slides on the lower one like the exact
    solution (within the project's 1 % of the peak exact slip, measured 0.007 %)."""
    sc = get_scenario("slide-stack-pulse-5.0hz-3mm-mu0.25-if0.05")
    ref, tr = reference(sc), engine.simulate(sc, "accurate")
    assert tr.status is Status.OK
    peak = max(np.max(np.abs(slip_of(ref, sc, b))) for b in range(2))
    for b in range(2):
        assert np.max(np.abs(slip_of(tr, sc, b) - slip_of(ref, sc, b))) <= 0.01 * peak, b


def test_base_motion_along_z_and_y(engine: JoltEngine) -> None:
    """A block rides a base that moves vertically; a base moving along y carries it by
    friction (unsupported with the planar lock, which would carry it rigidly)."""
    check_base_drives_y_and_z(engine, z_tol=2e-6)


# ---------------------------------------------------------------- stacks
def test_two_block_stack_at_rest_stays_at_rest(engine: JoltEngine) -> None:
    sc = Scenario("rest", PAPER_STACK, duration=2.0)
    tr = engine.simulate(sc, "accurate")
    assert tr.status is Status.OK
    assert np.max(np.abs(tr.theta)) < 1e-4 * lam(sc)
    # measured: x within 1.2e-8 m, z within 5.6e-9 m (rapier's limits kept)
    np.testing.assert_allclose(tr.x, 0.0, atol=1e-5)
    np.testing.assert_allclose(tr.z, tr.z[0] + 0.0 * tr.z, atol=5e-6)


def test_paper_stack_under_a_pulse_runs(engine: JoltEngine) -> None:
    check_paper_stack_under_pulse_runs(engine)


@pytest.mark.slow
def test_stack_pulse_follows_the_two_block_solution(engine: JoltEngine) -> None:
    # the project's 2 %; measured: peaks −0.42 % and −0.42 %, interface slip 1.6e-6 m,
    # gap 1.5e-7 m
    check_stack_follows_two_block(engine, "stack-pulse-4.0hz-4mm", 0.02, slip=2e-5, gap=1e-5)


def test_interface_friction_zero_in_an_assembly_is_unsupported(engine: JoltEngine) -> None:
    sc = get_scenario("wall-6x3")
    tr = engine.simulate(sc.replace(contact=Contact(friction=1.0, interface_friction=0.0),
                                    duration=0.1))
    assert tr.status is Status.UNSUPPORTED and "geometric mean" in tr.message


def test_planar_holds_boxes_only(engine: JoltEngine) -> None:
    """culverin's convex hulls take no allowed degrees of freedom: planar with a hull is
    unsupported; a box held in the plane rocks as the free one does."""
    sc = Scenario("stack", PAPER_STACK, duration=0.1)
    assert engine.simulate(sc, {"planar": True}).status is Status.UNSUPPORTED
    boxes = engine.simulate(sc, {"planar": True, "chamfer_shape": "narrow_box"})
    assert boxes.status is Status.OK
    planar = engine.simulate(free_b2(1.5), {"planar": True})
    assert planar.status is Status.OK and np.max(planar.wobble) == 0.0
    assert max_error(free_b2(1.5), planar.theta[:, 0]) <= 5e-3


# ---------------------------------------------------------------- determinism, knobs
def test_runs_are_bit_identical(engine: JoltEngine) -> None:
    sc = get_scenario("single-pulse-3.0hz-8mm").replace(duration=1.5)
    a = engine.simulate(sc, "accurate")
    b = JoltEngine().simulate(sc, "accurate")
    assert a.status is b.status is Status.OK
    for field in ("theta", "x", "z", "wobble"):
        assert np.array_equal(getattr(a, field), getattr(b, field)), field


def test_knob_overrides_take_effect(engine: JoltEngine) -> None:
    sc = free_b2(1.0)
    base = engine.simulate(sc, "fast")
    for knob, value in (("cancel_damping", False), ("small_rotations", False),
                        ("planar", True), ("timestep", 5e-4)):
        other = engine.simulate(sc, {"preset": "fast", knob: value})
        assert other.settings[knob] == value
        assert np.max(np.abs(other.theta - base.theta)) > 1e-6, knob
    # a step that does not divide the output interval is rounded to the nearest that does
    odd = engine.simulate(sc, {"preset": "fast", "timestep": 3e-4})
    assert odd.settings["effective_timestep"] == pytest.approx(1e-3 / 3)


def test_game_preset_runs_at_its_60_hz_step(engine: JoltEngine) -> None:
    """Jolt's defaults at 60 Hz: refused against a 1 ms output interval, and 0.05–0.5 λ off
    on B2 at 60 samples per second (measured 0.14 λ over 3 s)."""
    sc = free_b2()
    with pytest.raises(SettingsError, match="longer than the output interval"):
        engine.simulate(sc, "game")
    coarse = sc.replace(output_rate=60.0)
    tr = engine.simulate(coarse, "game")
    assert tr.status is Status.OK
    assert tr.settings["effective_timestep"] == pytest.approx(1 / 60)
    assert 0.05 < max_error(coarse, tr.theta[:, 0]) < 0.5


# ---------------------------------------------------------------- assemblies
def test_prism_reads_back_its_own_pose(engine: JoltEngine) -> None:
    block, prism = engine.simulate(inclined_scene(False)), engine.simulate(inclined_scene(True))
    assert block.status is prism.status is Status.OK
    # at rest on the slope: the block at 0.1 rad, the prism at its pose angle 0, both still
    assert np.max(np.abs(block.theta - 0.1)) < 1e-4
    assert np.max(np.abs(prism.theta)) < 1e-4
    assert np.max(np.abs(prism.x - block.x)) < 1e-4
    # rocked by a pulse, the box and the hull rock alike
    pulse = SinePulse(2.0, 0.04)
    rb = engine.simulate(inclined_scene(False, pulse))
    rp = engine.simulate(inclined_scene(True, pulse))
    peak_b, peak_p = np.max(np.abs(rb.theta - 0.1)), np.max(np.abs(rp.theta))
    assert peak_b > 0.05 and peak_p == pytest.approx(peak_b, rel=0.1)


def test_thin_boxes_are_built(engine: JoltEngine) -> None:
    """Boxes thinner than Jolt's 5 cm convex radius (culverin fixes it) still stand."""
    thin = Block(0.06, 0.04, 0.3, density=2000.0)
    tr = engine.simulate(Scenario("thin", thin, duration=0.5, output_rate=200.0))
    assert tr.status is Status.OK
    assert np.max(np.abs(tr.theta)) < 1e-4 and np.max(np.abs(tr.x)) < 1e-5


@pytest.mark.slow
def test_assemblies_of_boxes_stay_at_rest(engine: JoltEngine) -> None:
    for name in ("column-5drums", "parapet-offset0.25", "wall-6x3"):
        check_assembly_stays_at_rest(engine, name, duration=0.5, turn=1e-3, drift=1e-4)


# ---------------------------------------------------------------- cylinders and 3D starts
# Measured (docs/engines/jolt.md, "Cylinders and 3D starts"): the drum's first impact
# −0.153 % (accurate) / +0.685 % (fast), roll ≤ 2.6e-4 / 1.5e-3 rad, twist ≤ 4.0e-6 /
# 5.0e-5 rad; the corner landing −0.158 % / −0.174 %, abs(θ + roll) ≤ 2.3e-7 / 4.2e-8 rad.
@pytest.mark.parametrize(("preset", "rel", "plane_tol"),
                         [("accurate", 3e-3, 5e-4), ("fast", 1.2e-2, 2.5e-3)])
def test_cylinder_rocks_like_housner(preset: str, rel: float, plane_tol: float) -> None:
    check_cylinder_rocks_like_housner(JoltEngine(), preset, rel=rel, plane_tol=plane_tol)


@pytest.mark.parametrize(("preset", "rel", "diagonal_tol"),
                         [("accurate", 3e-3, 5e-7), ("fast", 3.5e-3, 1e-7)])
def test_corner_release(preset: str, rel: float, diagonal_tol: float) -> None:
    check_corner_release(JoltEngine(), preset, rel=rel, diagonal_tol=diagonal_tol)


@pytest.mark.xfail(strict=True, reason=(
    "Jolt's cylinder rolls on a polygon: its supporting face is the cap approximated by "
    "8 vertices, so the rim's contact jumps between them; over 5 s the tilt drifts 2.1e-2 "
    "rad from 0.2 and the rate is −4.5 % at 0.2, 0.1, 0.05 and 0.025 ms alike (−5.3 % "
    "without the added gyroscopic torque)"))
def test_steady_precession() -> None:
    check_steady_precession(JoltEngine(), "accurate", tilt_tol=0.01, rate_rtol=0.01,
                            duration=5.0)


class _ShapeProbe(JoltEngine):
    """Casts rays down onto the first body's top at build (x, y offsets in ``self.rays``)."""

    rays: tuple[tuple[float, float], ...] = ()

    def _build(self, scenario: Scenario, settings: EngineSettings) -> float:
        dt = super()._build(scenario, settings)
        self.hits = [self._world.raycast((x, y, 10.0), (0.0, 0.0, -1.0), 20.0)
                     for x, y in self.rays]
        return dt


def test_a_cylinder_is_built_as_a_cylinder() -> None:
    """The drum is Jolt's cylinder with its axis on z: a ray down at 0.75 R from the axis
    (along x, y and the diagonal) meets its top at H, one at (0.75 R, 0.75 R), inside the
    2R × 2R box but outside the circle, meets the ground. Standing on its base it stays at
    rest, its centre H/2 above the ground (measured 9e-8 m: Jolt's float32 rotations)."""
    drum = Cylinder(0.15, 1.0, density=2500.0)
    r = 0.75 * drum.radius
    probe = _ShapeProbe()
    probe.rays = ((r, 0.0), (0.0, r), (r * math.sqrt(0.5), r * math.sqrt(0.5)), (r, r))
    sc = Scenario("drum-rest", single(drum), duration=0.5)
    probe.check_supported(sc)  # raises UnsupportedScenario if not
    tr = probe.simulate(sc, "accurate")
    assert tr.status is Status.OK
    tops = [10.0 - 20.0 * hit[1] for hit in probe.hits[:3]]
    assert tops == pytest.approx([drum.height] * 3, abs=1e-5)
    assert 10.0 - 20.0 * probe.hits[3][1] == pytest.approx(0.0, abs=1e-5)
    assert np.max(np.abs(tr.z[:, 0] - drum.h)) < 2e-7
    assert np.max(np.abs(tr.x)) < 1e-7 and np.max(np.abs(tr.y)) < 1e-7
    assert np.max(tr.tilt) < 1e-6


def test_a_moving_start_is_applied_in_world_axes() -> None:
    """The precession's start (a spinning, rolling cylinder): the first sample after 5 ms
    has moved as the initial velocities say (world axes, the centre of mass's velocity)."""
    from rockbench.studies.references_3d import precession

    sc, sp = precession(0.005)
    tr = JoltEngine().simulate(sc, "accurate")
    assert tr.status is Status.OK
    v, dt = sc.initial_states()[0, 7:10], tr.t[-1] - tr.t[0]
    moved = np.array([tr.x[-1, 0] - tr.x[0, 0], tr.y[-1, 0] - tr.y[0, 0]])
    assert np.linalg.norm(v[:2]) > 0.1
    np.testing.assert_allclose(moved, v[:2] * dt, rtol=0.02, atol=1e-4 * np.linalg.norm(v))
    az = np.unwrap(tr.azimuth[:, 0])
    assert az[-1] - az[0] == pytest.approx(sp.psi_dot * dt, rel=0.02)


def test_gyroscopic_step_keeps_the_momentum() -> None:
    """The added gyroscopic torque (Jolt's own form): one step changes the body-frame
    momentum by −dt ω × Iω to first order and keeps its magnitude."""
    inertia, dt = (2.0, 0.5, 2.0), 1e-3
    w = (1.0, 3.0, -0.5)
    q = [0.0, 0.0, 0.0, 1.0]  # body axes = world axes
    out = np.array(_gyroscopic(q, w, inertia, dt))
    m0, m1 = np.multiply(inertia, w), np.multiply(inertia, out)
    assert np.linalg.norm(m1) == pytest.approx(np.linalg.norm(m0), rel=1e-12)
    # (to first order: the second-order remainder is below dt² ω² abs(Iω) = 6e-5)
    np.testing.assert_allclose(m1 - m0, -dt * np.cross(w, m0), rtol=0, atol=1e-5)
    # turned bodies: the same step seen in other axes
    a = 0.3
    qz = [0.0, 0.0, math.sin(0.5 * a), math.cos(0.5 * a)]
    rz = np.array([[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0],
                   [0.0, 0.0, 1.0]])
    np.testing.assert_allclose(_gyroscopic(qz, tuple(rz @ w), inertia, dt), rz @ out,
                               rtol=1e-12, atol=1e-12)
