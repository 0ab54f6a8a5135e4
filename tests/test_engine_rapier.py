"""Physics tests of the Rapier engine plugin (rapier3d) against Housner and closed forms.

The tolerances are the project's where Rapier meets them, else the measured values with a
margin (each one says which); the calibration behind them is on docs/engines/rapier.md.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rockbench.engines.rapier_engine import RapierEngine, RapierSettings
from rockbench.errors import EngineUnavailable

try:
    RapierEngine.check_available()
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
    check_drum_falls_alike_toward_any_azimuth,
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
from rockbench.engines import SettingsError, get_engine  # noqa: E402
from rockbench.engines.base import OVERTURN_MARGIN  # noqa: E402
from rockbench.engines.testing import parametrize_with_checks  # noqa: E402
from rockbench.scenarios import (  # noqa: E402
    Contact,
    Scenario,
    SinePulse,
    get_scenario,
)
from rockbench.studies.references_3d import (  # noqa: E402
    DRUM,
    precession,
)
from rockbench.trajectory import Status  # noqa: E402


@pytest.fixture(scope="module")
def engine() -> RapierEngine:
    eng = get_engine("rapier")
    assert isinstance(eng, RapierEngine)
    return eng


def free_b2(duration: float = 3.0) -> Scenario:
    return Scenario("free-b2-0.5", B2, initial_tilt=0.5, duration=duration)


# ---------------------------------------------------------------- the conformance kit
@pytest.mark.slow
@parametrize_with_checks([RapierEngine])
def test_conformance(engine, check):
    check(engine)


# ---------------------------------------------------------------- registry and settings
def test_registry_and_presets(engine: RapierEngine) -> None:
    assert engine.name == "rapier" and engine.capabilities.dimensions == 3
    assert engine.version().startswith("0.")
    assert {"accurate", "fast", "game"} <= set(engine.presets)
    assert engine.settings("accurate") == engine.Settings()
    fast = engine.settings("fast")
    assert isinstance(fast, RapierSettings)
    assert (fast.timestep, fast.solver_iterations) == (1e-3, 10)
    game = engine.settings("game")
    assert isinstance(game, RapierSettings)
    # Rapier's own IntegrationParameters::default() and its 60 Hz step
    assert game.timestep == pytest.approx(1 / 60) and game.solver_iterations == 4
    assert game.friction_model == "simplified" and game.contact_frequency == 30.0
    assert game.contact_recycling and not game.planar and not engine.settings().planar
    assert engine.settings(contact_frequency="500").contact_frequency == 500.0
    for bad in ({"friction_model": "viscous"}, {"timestep": -1e-4}, {"solver_iterations": 0},
                {"contact_frequency": 0.0}, {"hull_radius": -1.0}):
        with pytest.raises(SettingsError):
            engine.settings(**bad)
    with pytest.raises(AttributeError):
        RapierSettings().timestep = 1.0  # type: ignore[misc]


def test_rapier_defaults_match_the_game_preset() -> None:
    """The game preset is Rapier's IntegrationParameters::default() (but the step)."""
    r = RapierEngine.library("rapier3d")
    default = r.IntegrationParameters()
    game = RapierEngine.settings("game")
    ours = RapierEngine._parameters(r, game, default.dt)
    for field in ("num_solver_iterations", "num_internal_pgs_iterations",
                  "num_internal_stabilization_iterations", "friction_model",
                  "normalized_allowed_linear_error", "normalized_prediction_distance",
                  "normalized_max_corrective_velocity", "contact_clustering",
                  "contact_recycling", "length_unit"):
        assert getattr(ours, field) == getattr(default, field), field
    assert ours.contact_softness.natural_frequency == default.contact_softness.natural_frequency
    assert ours.contact_softness.damping_ratio == default.contact_softness.damping_ratio
    assert game.timestep == pytest.approx(default.dt, rel=1e-7)


# ---------------------------------------------------------------- free rocking
def test_free_rocking_accurate(engine: RapierEngine) -> None:
    """B2 from 0.5 λ for 3 s: within the project's 5e-3 λ of Housner (measured 0.0029),
    the first three impact times within 0.5 %, out of plane by 5e-3 rad at most."""
    sc = free_b2()
    tr = engine.simulate(sc, "accurate")
    assert tr.status is Status.OK
    th = tr.theta[:, 0]
    assert max_error(sc, th) <= 5e-3
    impacts = np.asarray(single_block_reference(sc).impacts)[:3]
    np.testing.assert_allclose(zero_crossings(tr.t, th)[:3], impacts, rtol=5e-3)
    assert np.max(tr.wobble) < 0.02
    assert tr.theta[0, 0] == pytest.approx(sc.theta0, rel=1e-6)  # float32 poses
    assert tr.settings["effective_timestep"] == pytest.approx(1e-4)


def test_free_rocking_fast_and_with_the_planar_joint(engine: RapierEngine) -> None:
    """fast: within 0.02 λ (measured 0.0048); held in the x–z plane by the joint, the
    block hardly wobbles (2.5e-6 rad, the joint's softness) and rocks within 0.01 λ
    (measured 0.0030)."""
    sc = free_b2()
    fast = engine.simulate(sc, "fast")
    assert fast.status is Status.OK and max_error(sc, fast.theta[:, 0]) <= 0.02
    planar = engine.simulate(sc, {"planar": True})
    assert planar.status is Status.OK and max_error(sc, planar.theta[:, 0]) <= 0.01
    assert np.max(planar.wobble) < 1e-5


def test_free_rocking_converges_as_the_step_shrinks(engine: RapierEngine) -> None:
    """One sub-step per step: the error on B2 is 5-6 times smaller at 0.1 ms than at 1 and
    0.5 ms (measured 0.018, 0.015, then 0.025 at 0.2 ms, and 0.0029 λ): not monotonic, and
    below about 0.05 ms per sub-step float32 makes it grow again (docs/engines/rapier.md)."""
    sc = free_b2()
    errors = [max_error(sc, engine.simulate(sc, {"timestep": dt}).theta[:, 0])
              for dt in (1e-3, 5e-4, 1e-4)]
    assert min(errors[:2]) > 3 * errors[-1], errors


def test_sign_convention_and_mirror_symmetry(engine: RapierEngine) -> None:
    """θ > 0 pivots on the +x edge; −tilt mirrors it (to float32 rounding)."""
    check_mirrored_release(engine)


# ---------------------------------------------------------------- pulses
def test_sine_pulse_peak(engine: RapierEngine) -> None:
    # Single #2 under 3.3 Hz / 8 mm: the peak within 2 % of Housner's at both presets
    check_sine_pulse_peak(engine, "accurate")
    check_sine_pulse_peak(engine, "fast")


def test_a_pulse_that_rocks_without_overturning(engine: RapierEngine) -> None:
    # measured 0.06 %
    check_pulse_rocks_without_overturning(engine)


def test_a_pulse_that_overturns(engine: RapierEngine) -> None:
    """Single #2 under sine pulses at 3 × its uplift acceleration overturns, as the reference
    does; at 1 Hz it settles on its side 2e-7 rad short of π/2 (float32), which the base loop
    counts as overturned (OVERTURN_MARGIN)."""
    lam2 = SINGLE2.rocking().lam
    for f in (2.0, 1.0):
        amp = 3.0 * 9.81 * math.tan(lam2) / (2 * math.pi * f) ** 2
        sc = Scenario("overturn", SINGLE2, excitation=SinePulse(f, amp), duration=3.0)
        assert reference(sc).status is Status.OVERTURNED
        tr = engine.simulate(sc, "accurate")
        assert tr.status is Status.OVERTURNED, tr.message
        assert abs(tr.theta[-1, 0]) > math.pi / 2 - OVERTURN_MARGIN


def test_a_pulse_below_the_uplift_threshold_carries_the_block(engine: RapierEngine) -> None:
    f = 3.0
    amp = 0.8 * 9.81 * math.tan(SINGLE2.rocking().lam) / (2 * math.pi * f) ** 2
    sc = Scenario("ride", SINGLE2, excitation=SinePulse(f, amp), duration=1.0)
    tr = engine.simulate(sc, "accurate")
    assert tr.status is Status.OK
    assert np.max(np.abs(tr.theta)) < 1e-4 * lam(sc)
    u = sc.motion.x.displacement(tr.t)
    assert np.max(np.abs(tr.x[:, 0] - u)) < 2e-6  # measured 2.2e-7 m
    assert tr.x[-1, 0] == pytest.approx(2 * math.pi * amp, abs=1e-5)


def test_frictionless_base_slides_under_the_block(engine: RapierEngine) -> None:
    """Friction comes from the scenario: with μ = 0 the moving base cannot drag the block."""
    sc = Scenario("slide", SINGLE2, Contact(0.0, 0.0), SinePulse(3.0, 0.004), duration=0.5)
    tr = engine.simulate(sc, "fast")
    assert tr.status is Status.OK
    assert np.max(np.abs(tr.x[:, 0])) < 1e-5  # the base travels 2πA = 25 mm
    assert np.max(np.abs(tr.theta)) < 1e-5


def test_sliding_follows_the_coulomb_slider(engine: RapierEngine) -> None:
    """Every pair sees the scenario's μ: B2 slides on μ = 0.2 like the exact Coulomb slider
    (slip within 1 % of the peak exact slip, measured 0.15 %)."""
    sc = get_scenario("slide-b2-pulse-2.0hz-20mm-mu0.20")
    check_slides_like_coulomb(sc, engine.simulate(sc, "accurate"), reference(sc))


def test_interface_friction_of_a_stack(engine: RapierEngine) -> None:
    """A stack whose interface alone is slippery (μ 0.25 on the base, μ_if 0.05): each pair
    sees its own coefficient (MULTIPLY rule), the upper block slides on the lower one like
    the exact solution (within 1 % of the peak exact slip, measured 0.32 %)."""
    sc = get_scenario("slide-stack-pulse-5.0hz-3mm-mu0.25-if0.05")
    ref, tr = reference(sc), engine.simulate(sc, "accurate")
    assert tr.status is Status.OK
    peak = max(np.max(np.abs(slip_of(ref, sc, b))) for b in range(2))
    for b in range(2):
        assert np.max(np.abs(slip_of(tr, sc, b) - slip_of(ref, sc, b))) <= 0.01 * peak, b


def test_base_motion_along_z_and_y(engine: RapierEngine) -> None:
    """A block rides a base that moves vertically; a base moving along y carries it by
    friction (unsupported with the planar lock, which would carry it rigidly)."""
    # measured: z within 2e-6 m (float32), y at the base's end within 1e-5 m
    check_base_drives_y_and_z(engine, z_tol=2e-6)


# ---------------------------------------------------------------- stacks
def test_two_block_stack_at_rest_stays_at_rest(engine: RapierEngine) -> None:
    sc = Scenario("rest", PAPER_STACK, duration=2.0)
    tr = engine.simulate(sc, "accurate")
    assert tr.status is Status.OK
    assert np.max(np.abs(tr.theta)) < 1e-4 * lam(sc)
    # measured: x within 3.9e-6 m, z within 3e-7 m
    np.testing.assert_allclose(tr.x, 0.0, atol=1e-5)
    np.testing.assert_allclose(tr.z, tr.z[0] + 0.0 * tr.z, atol=5e-6)


def test_paper_stack_under_a_pulse_runs(engine: RapierEngine) -> None:
    check_paper_stack_under_pulse_runs(engine)


@pytest.mark.slow
def test_stack_pulse_follows_the_two_block_solution(engine: RapierEngine) -> None:
    # measured: peaks −0.31 % and −0.30 %, interface slip 2.4e-6 m, gap 2.0e-6 m
    check_stack_follows_two_block(engine, "stack-pulse-4.0hz-4mm", 0.02, slip=2e-5, gap=1e-5)


def test_interface_friction_zero_in_an_assembly_is_unsupported(engine: RapierEngine) -> None:
    sc = get_scenario("wall-6x3")
    tr = engine.simulate(sc.replace(contact=Contact(friction=1.0, interface_friction=0.0),
                                    duration=0.1))
    assert tr.status is Status.UNSUPPORTED and "multiplies" in tr.message


# ---------------------------------------------------------------- determinism, knobs
def test_runs_are_bit_identical(engine: RapierEngine) -> None:
    sc = get_scenario("single-pulse-3.0hz-8mm").replace(duration=1.5)
    a = engine.simulate(sc, "accurate")
    b = RapierEngine().simulate(sc, "accurate")
    assert a.status is b.status is Status.OK
    for field in ("theta", "x", "z", "wobble"):
        assert np.array_equal(getattr(a, field), getattr(b, field)), field


def test_knob_overrides_take_effect(engine: RapierEngine) -> None:
    sc = free_b2(1.0)
    base = engine.simulate(sc, "fast")
    for knob, value in (("contact_frequency", 100.0), ("friction_model", "coulomb"),
                        ("contact_damping_ratio", 1.0), ("solver_iterations", 4),
                        ("planar", True)):
        other = engine.simulate(sc, {"preset": "fast", knob: value})
        assert other.settings[knob] == value
        assert np.max(np.abs(other.theta - base.theta)) > 1e-6, knob
    # a step that does not divide the output interval is rounded to the nearest that does
    odd = engine.simulate(sc, {"preset": "fast", "timestep": 3e-4})
    assert odd.settings["effective_timestep"] == pytest.approx(1e-3 / 3)


def test_game_preset_runs_at_its_60_hz_step(engine: RapierEngine) -> None:
    """Rapier's defaults at 60 Hz: refused against a 1 ms output interval, and 0.05–0.2 λ
    off on B2 at 60 samples per second (measured 0.081 λ over 20 s)."""
    sc = free_b2()
    with pytest.raises(SettingsError, match="longer than the output interval"):
        engine.simulate(sc, "game")
    coarse = sc.replace(output_rate=60.0)
    tr = engine.simulate(coarse, "game")
    assert tr.status is Status.OK
    assert tr.settings["effective_timestep"] == pytest.approx(1 / 60)
    assert 0.05 < max_error(coarse, tr.theta[:, 0]) < 0.2


# ---------------------------------------------------------------- assemblies
def test_prism_in_its_principal_frame_reads_back_its_own_pose(engine: RapierEngine) -> None:
    block, prism = engine.simulate(inclined_scene(False)), engine.simulate(inclined_scene(True))
    assert block.status is prism.status is Status.OK
    # at rest on the slope: the block at 0.1 rad, the prism at its pose angle 0, both still
    assert np.max(np.abs(block.theta - 0.1)) < 1e-4
    assert np.max(np.abs(prism.theta)) < 1e-4
    assert np.max(np.abs(prism.x - block.x)) < 1e-4
    # rocked by a pulse, the box and the rounded hull rock alike
    pulse = SinePulse(2.0, 0.04)
    rb = engine.simulate(inclined_scene(False, pulse))
    rp = engine.simulate(inclined_scene(True, pulse))
    peak_b, peak_p = np.max(np.abs(rb.theta - 0.1)), np.max(np.abs(rp.theta))
    assert peak_b > 0.05 and peak_p == pytest.approx(peak_b, rel=0.1)


@pytest.mark.slow
def test_assemblies_of_boxes_stay_at_rest(engine: RapierEngine) -> None:
    for name in ("column-5drums", "parapet-offset0.25", "wall-6x3"):
        check_assembly_stays_at_rest(engine, name, duration=0.5, turn=1e-3, drift=1e-4)


# ---------------------------------------------------------------- cylinders and 3D starts
def test_capabilities_declare_cylinders_and_3d_starts(engine: RapierEngine) -> None:
    assert engine.capabilities.cylinders and engine.capabilities.start3d


def test_a_cylinder_is_built_as_a_cylinder(engine: RapierEngine) -> None:
    """The collider is Rapier's cylinder, its axis turned onto the body's z, with the
    cylinder's own mass and inertia (not a density's); at rest it stands still on its cap,
    its centre H/2 up (measured: within 3e-8 m, turned by 3e-7 rad)."""
    r = RapierEngine.library("rapier3d")
    world = r.PhysicsWorld(gravity=(0.0, 0.0, 0.0))
    handle = world.add_body(r.RigidBody.dynamic(), [RapierEngine._cylinder_collider(r, DRUM)])
    body = world.rigid_bodies[handle]
    (collider,) = (world.colliders[h] for h in body.colliders)
    shape = collider.shape.as_cylinder()
    assert shape is not None
    assert (shape.half_height, shape.radius) == pytest.approx((DRUM.h, DRUM.radius), rel=1e-6)
    props = body.mass_properties
    assert props.mass == pytest.approx(DRUM.m, rel=1e-6)
    frame = np.reshape(props.principal_inertia_local_frame.to_matrix(), (3, 3))
    tensor = frame @ np.diag(props.principal_inertia.to_tuple()) @ frame.T
    np.testing.assert_allclose(tensor, DRUM.inertia_tensor, rtol=1e-6, atol=1e-6 * DRUM.m)
    # the axis: the collider's local y is the body's z (to float32 rounding)
    np.testing.assert_allclose(collider.rotation.transform_vector((0.0, 1.0, 0.0)).to_tuple(),
                               (0.0, 0.0, 1.0), atol=1e-6)

    tr = engine.simulate(Scenario("rest", DRUM, duration=1.0), "accurate")
    assert tr.status is Status.OK
    assert np.max(np.abs(tr.z[:, 0] - DRUM.h)) < 1e-7
    assert np.max(np.abs(tr.x)) < 1e-6 and np.max(np.abs(tr.y)) < 1e-6
    assert np.max(np.abs(tr.theta)) < 1e-6 and np.max(np.abs(tr.roll)) < 1e-6


def test_drum_rocks_like_housner(engine: RapierEngine) -> None:
    """First impact 0.44 % early at accurate and 0.41 % at fast (measured), the drum in
    the plane to 7e-10 and 6e-9 rad: the simplified friction model lets the rim pivot slide
    (next test)."""
    check_cylinder_rocks_like_housner(engine, "accurate", rel=7e-3, plane_tol=2e-9)
    check_cylinder_rocks_like_housner(engine, "fast", rel=7e-3, plane_tol=1e-8)


def test_drum_with_coulomb_friction_pivots_in_place(engine: RapierEngine) -> None:
    """One Coulomb constraint per contact point holds the rim pivot (it slides 3 µm, against
    0.49 mm outward with the simplified model): the first impact within 0.014 % at accurate
    and 0.016 % at fast, in the plane to 4.4e-9 and 1.5e-8 rad (measured)."""
    check_cylinder_rocks_like_housner(engine, {"friction_model": "coulomb"}, rel=3e-4,
                                      plane_tol=1e-8)
    check_cylinder_rocks_like_housner(engine, {"preset": "fast", "friction_model": "coulomb"},
                                      rel=3e-4, plane_tol=3e-8)


@pytest.mark.xfail(strict=True, reason=(
    "the simplified friction model (the presets') solves one friction constraint at the "
    "manifold's centre: the drum's rim pivot slides 0.49 mm outward before the impact, which "
    "comes 0.44 % early (0.014 % with friction_model='coulomb'); independent of the step "
    "(0.44 % at 0.1, 0.05 and 0.025 ms) and of contact_frequency (1-10 kHz)"))
def test_drum_first_impact_within_a_tenth_of_a_percent(engine: RapierEngine) -> None:
    check_cylinder_rocks_like_housner(engine, "accurate", rel=1e-3, plane_tol=1e-8)


def test_drum_released_toward_any_azimuth_falls_alike(engine: RapierEngine) -> None:
    # measured: tilt within 2.8e-6 rad, azimuth 1.6e-5 rad of the in-plane release
    check_drum_falls_alike_toward_any_azimuth(engine, tilt_tol=5e-6, azimuth_tol=3e-5)


def test_corner_release(engine: RapierEngine) -> None:
    """Landing 0.14 % early at accurate and 0.11 % at fast, on the diagonal to 7.4e-8 and
    3.5e-8 rad (measured)."""
    check_corner_release(engine, "accurate", rel=2.5e-3, diagonal_tol=1.5e-7)
    check_corner_release(engine, "fast", rel=2e-3, diagonal_tol=7e-8)


def test_steady_precession_accurate(engine: RapierEngine) -> None:
    """Over 2 s: the tilt within 4.4e-5 rad of 0.2, the rate 0.011 % off (measured)."""
    check_steady_precession(engine, "accurate", tilt_tol=8e-5, rate_rtol=2e-4)


def test_steady_precession_fast(engine: RapierEngine) -> None:
    """Over 2 s: the tilt within 1.4e-3 rad of 0.2, the rate 0.40 % slow (measured)."""
    check_steady_precession(engine, "fast", tilt_tol=2.5e-3, rate_rtol=7e-3)


def test_a_moving_start_is_applied_in_world_axes(engine: RapierEngine) -> None:
    """The precession's start (velocity of the centre of gravity and angular velocity, world
    axes) is the first sample's motion: the centre moves along +y at the state's speed."""
    sc, _ = precession(0.05)
    st = sc.initial_states()[0]
    tr = engine.simulate(sc, "accurate")
    assert tr.status is Status.OK
    assert tr.x[0, 0] == pytest.approx(st[0], abs=1e-7)
    assert tr.z[0, 0] == pytest.approx(st[2], abs=1e-7)
    vy = (tr.y[1, 0] - tr.y[0, 0]) / (tr.t[1] - tr.t[0])
    assert vy == pytest.approx(st[8], rel=8e-5)  # measured 3.7e-5
