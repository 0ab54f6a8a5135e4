"""Physics tests of the Newton engine plugin (NVIDIA Warp, CPU, float32) against Housner.

The tolerances are the project's where Newton meets them, else the measured values with a
margin (each one says which); the calibration behind them is on docs/engines/newton.md.
Warp compiles a solver's kernels the first time a machine runs it (about 35 s of CPU for
XPBD on 2 cores, cached in ~/.cache/warp): an autouse module fixture does it once, so that
it shows up as the first test's setup time; the other solvers' tests compile their own
(slow tier).
"""

from __future__ import annotations

import inspect
import math

import numpy as np
import pytest

from rockbench.engines.newton_engine import (
    NewtonEngine,
    NewtonSettings,
    mean_frictions,
    prism_mesh,
)
from rockbench.errors import EngineUnavailable

try:
    NewtonEngine.check_available()
except EngineUnavailable as exc:  # pragma: no cover - depends on the environment
    pytest.skip(str(exc), allow_module_level=True)

from engine_helpers import (  # noqa: E402
    B0,
    B0_IMPACTS,
    B2,
    PAPER_STACK,
    SINGLE2,
    check_base_drives_y_and_z,
    check_base_follows_excitation,
    check_corner_release,
    check_cylinder_rocks_like_housner,
    check_drum_falls_alike_toward_any_azimuth,
    check_mirrored_release,
    check_paper_stack_under_pulse_runs,
    check_pulse_rocks_without_overturning,
    check_sine_pulse_peak,
    check_slides_like_coulomb,
    check_steady_precession,
    lam,
    max_error,
    zero_crossings,
)

from rockbench.analytic import reference  # noqa: E402
from rockbench.analytic.housner import single_block_reference  # noqa: E402
from rockbench.engines import SettingsError, engine_class  # noqa: E402
from rockbench.engines.drive import BaseDrive  # noqa: E402
from rockbench.engines.testing import parametrize_with_checks  # noqa: E402
from rockbench.geometry import Block, stack  # noqa: E402
from rockbench.scenarios import Contact, Scenario, SinePulse, get_scenario  # noqa: E402
from rockbench.studies.references_3d import (  # noqa: E402
    DRUM,
    corner_release,
    drum_release,
    precession,
)
from rockbench.trajectory import Status  # noqa: E402


@pytest.fixture(scope="module", autouse=True)
def _compiled() -> None:
    """XPBD's kernels compiled (or loaded from Warp's disk cache) before any test runs."""
    NewtonEngine.warm_up(("xpbd",))


@pytest.fixture(scope="module")
def engine() -> NewtonEngine:
    return NewtonEngine()


def free_b2(duration: float = 3.0) -> Scenario:
    return Scenario("free-b2-0.5", B2, initial_tilt=0.5, duration=duration)


# ---------------------------------------------------------------- the conformance kit
@pytest.mark.slow
@parametrize_with_checks([NewtonEngine])
def test_conformance(engine, check):
    check(engine)


# ---------------------------------------------------------------- registry and settings
def test_registry_and_presets(engine: NewtonEngine) -> None:
    newton = NewtonEngine.library("newton")
    warp = NewtonEngine.library("warp")
    assert engine_class("newton") is NewtonEngine
    assert engine.version() == f"{newton.__version__} (warp {warp.__version__})"
    assert {"accurate", "fast", "game"} <= set(engine.presets)
    assert engine.settings("accurate") == NewtonSettings()
    s = engine.settings("accurate")
    assert isinstance(s, NewtonSettings)
    assert (s.solver, s.timestep, s.iterations) == ("xpbd", 2.5e-4, 8)
    # every contact corrected in full, half of it per iteration (docs/engines/newton.md)
    assert (s.relaxation, s.contact_weighting, s.velocity_pass) == (0.5, False, False)
    # no hidden damping: Newton's rolling and torsional friction and angular damping off
    assert s.mu_rolling == s.mu_torsional == s.angular_damping == 0.0
    fast = engine.settings("fast")
    assert isinstance(fast, NewtonSettings)
    assert (fast.timestep, fast.iterations, fast.relaxation) == (1e-3, 8, 0.3)
    assert engine.settings(solver="steel").solver == "steel"
    for bad in ({"solver": "mujoco"}, {"timestep": -1e-4}, {"iterations": 0},
                {"solver": "steel", "planar": True},
                {"relaxation": 1.5}, {"contact_ke": -1.0}, {"mu_rolling": math.nan}):
        with pytest.raises(SettingsError):
            engine.settings(**bad)
    with pytest.raises(AttributeError):
        NewtonSettings().timestep = 1.0  # type: ignore[misc]


def test_game_preset_is_newtons_defaults() -> None:
    """The game preset is Newton's ShapeConfig, ModelBuilder and SolverXPBD defaults."""
    newton = NewtonEngine.library("newton")
    game = NewtonEngine.settings("game")
    assert isinstance(game, NewtonSettings)
    cfg = newton.ModelBuilder.ShapeConfig()
    assert (game.contact_ke, game.contact_kd, game.contact_kf) == (cfg.ke, cfg.kd, cfg.kf)
    assert (game.mu_torsional, game.mu_rolling) == (cfg.mu_torsional, cfg.mu_rolling)
    assert cfg.margin == 0.0  # the plugin's shapes have no margin either
    assert game.gap == newton.ModelBuilder().rigid_gap
    xpbd = inspect.signature(newton.solvers.SolverXPBD.__init__).parameters
    assert game.solver == "xpbd"
    assert game.iterations == xpbd["iterations"].default
    assert game.relaxation == xpbd["rigid_contact_relaxation"].default
    assert game.contact_weighting == xpbd["rigid_contact_con_weighting"].default
    assert game.velocity_pass == xpbd["enable_restitution"].default
    assert game.restitution_iterations == xpbd["rigid_contact_restitution_iterations"].default
    assert xpbd["angular_damping"].default == 0.0
    assert game.timestep == pytest.approx(1 / 60)


def test_mean_frictions() -> None:
    """Per-shape coefficients whose pairwise means are the scenario's μ and μ_if."""
    two = stack((Block(0.2, 0.2, 0.6, mass=1.0), Block(0.2, 0.2, 0.6, mass=1.0)))
    assert mean_frictions(two, 0.6, 0.6) == [0.6, 0.6, 0.6]
    for mu, mu_if in ((0.6, 0.2), (0.2, 0.6), (0.1, 1.0)):
        base, b1, b2 = mean_frictions(two, mu, mu_if) or []
        assert min(base, b1, b2) >= 0
        assert (base + b1) / 2 == pytest.approx(mu) and (b1 + b2) / 2 == pytest.approx(mu_if)
    wall = get_scenario("wall-6x3").geometry
    coeffs = mean_frictions(wall, 0.6, 0.4) or []
    assert coeffs[0] == pytest.approx(0.8) and set(coeffs[1:]) == {0.4}
    assert mean_frictions(wall, 0.2, 0.5) is None


def test_prism_mesh_is_closed_and_outward() -> None:
    """The hull mesh of a chamfered block: its signed volume is the prism's."""
    blk = Block(0.4, 0.3, 0.6, mass=1.0, chamfer=0.02)
    verts, idx = prism_mesh(blk.profile(), 0.15)
    tris = verts[idx.reshape(-1, 3)]
    volume = np.sum(np.einsum("ij,ij->i", tris[:, 0], np.cross(tris[:, 1], tris[:, 2]))) / 6
    area = 0.4 * 0.6 - 2 * 0.02**2  # four corners cut by half a 2 cm square each
    assert volume == pytest.approx(area * 0.3)


# ---------------------------------------------------------------- free rocking
def test_free_rocking_accurate(engine: NewtonEngine) -> None:
    """B2 from 0.5 λ for 3 s: within 0.01 λ of Housner (measured 0.0071: the project's 5e-3 λ
    is not met), the first three impact times within 0.5 % (measured 0.47 %), out of plane
    by 1e-3 rad at most (float32 position noise at the two pivot corners)."""
    sc = free_b2()
    tr = engine.simulate(sc, "accurate")
    assert tr.status is Status.OK
    th = tr.theta[:, 0]
    assert max_error(sc, th) <= 0.01
    impacts = np.asarray(single_block_reference(sc).impacts)[:3]
    np.testing.assert_allclose(zero_crossings(tr.t, th)[:3], impacts, rtol=5e-3)
    assert np.max(tr.wobble) < 1e-3
    assert tr.theta[0, 0] == pytest.approx(sc.theta0, rel=1e-6)  # float32 poses
    assert tr.settings["effective_timestep"] == pytest.approx(2.5e-4)


@pytest.mark.slow
def test_b0_impact_times_accurate_and_fast(engine: NewtonEngine) -> None:
    """The issue's measure: B0 from 0.5 λ, up to its third impact, the published impact
    times within 0.5 %; θ within 0.02 λ at both presets (measured 0.0098 at accurate, 0.0023
    at fast: the issue measured 0.011 at best)."""
    sc = Scenario("free-b0", B0, initial_tilt=0.5, duration=3.6)
    for preset, tol in (("accurate", 0.02), ("fast", 0.02)):
        tr = engine.simulate(sc, preset)
        assert tr.status is Status.OK
        th = tr.theta[:, 0]
        np.testing.assert_allclose(zero_crossings(tr.t, th)[:3], B0_IMPACTS, rtol=5e-3)
        assert max_error(sc, th) <= tol, preset


@pytest.mark.slow
def test_free_rocking_converges_as_the_step_shrinks(engine: NewtonEngine) -> None:
    """B2 over 2.2 s at 1, 0.5 and 0.25 ms (the accurate knobs otherwise): smaller at every
    halving (measured 0.019, 0.0093, 0.0071 λ); below 0.1 ms float32 makes it grow again and
    erratic (docs/engines/newton.md)."""
    sc = free_b2(2.2)
    errors = [max_error(sc, engine.simulate(sc, {"timestep": dt}).theta[:, 0])
              for dt in (1e-3, 5e-4, 2.5e-4)]
    assert errors[0] > errors[1] > errors[2] and errors[0] > 2 * errors[2], errors


@pytest.mark.slow
def test_a_block_released_next_to_its_tipping_point_stands_still(
        engine: NewtonEngine) -> None:
    """Known limit (float32 XPBD): B3 from 0.99 λ should fall back within 1.6 s; at 0.25 and
    0.5 ms its turn per step is below float32's resolution of the orientation and XPBD's
    converged position solve gives it no velocity, so it stands still; at 1 ms it falls
    (first impact 3.5 % late)."""
    sc = get_scenario("free-b3-0.99").replace(duration=2.0)
    stuck = engine.simulate(sc, "accurate")
    assert stuck.status is Status.OK
    assert np.max(np.abs(stuck.theta - stuck.theta[0])) < 1e-6  # measured 3e-8 rad
    falls = engine.simulate(sc, "fast")
    first = zero_crossings(falls.t, falls.theta[:, 0])[0]
    assert first == pytest.approx(float(single_block_reference(sc).impacts[0]), rel=0.05)


def test_sign_convention_and_mirror_symmetry(engine: NewtonEngine) -> None:
    """θ > 0 pivots on the +x edge; −tilt mirrors it (to float32 rounding)."""
    check_mirrored_release(engine)


# ---------------------------------------------------------------- pulses
def test_sine_pulse_peak(engine: NewtonEngine) -> None:
    # Single #2 under 3.3 Hz / 8 mm: the peak within 2 % of Housner's (measured 0.31 % at
    # accurate, 1.4 % at fast)
    check_sine_pulse_peak(engine, "accurate")
    check_sine_pulse_peak(engine, "fast")


def test_a_pulse_that_rocks_without_overturning(engine: NewtonEngine) -> None:
    # measured 0.12 %
    check_pulse_rocks_without_overturning(engine)


@pytest.mark.slow
def test_a_pulse_that_overturns(engine: NewtonEngine) -> None:
    """Single #2 under sine pulses at 3 × its uplift acceleration overturns (1 and 2 Hz)."""
    lam2 = SINGLE2.rocking().lam
    for f in (1.0, 2.0):
        amp = 3.0 * 9.81 * math.tan(lam2) / (2 * math.pi * f) ** 2
        sc = Scenario("overturn", SINGLE2, excitation=SinePulse(f, amp), duration=3.0)
        assert reference(sc).status is Status.OVERTURNED
        tr = engine.simulate(sc, "accurate")
        assert tr.status is Status.OVERTURNED, tr.message


def test_a_pulse_below_the_uplift_threshold_carries_the_block(engine: NewtonEngine) -> None:
    f = 3.0
    amp = 0.8 * 9.81 * math.tan(SINGLE2.rocking().lam) / (2 * math.pi * f) ** 2
    sc = Scenario("ride", SINGLE2, excitation=SinePulse(f, amp), duration=1.0)
    tr = engine.simulate(sc, "accurate")
    assert tr.status is Status.OK
    assert np.max(np.abs(tr.theta)) < 5e-4 * lam(sc)  # measured 1.2e-4 λ
    u = sc.motion.x.displacement(tr.t)
    # measured: 2.0e-5 m off at most, 1.1e-5 m ahead at the end (XPBD's friction is a
    # position constraint relaxed over the step: a sticking block slips microns)
    assert np.max(np.abs(tr.x[:, 0] - u)) < 5e-5
    assert tr.x[-1, 0] == pytest.approx(2 * math.pi * amp, abs=5e-5)


def test_frictionless_base_slides_under_the_block(engine: NewtonEngine) -> None:
    """Friction comes from the scenario: with μ = 0 the moving base cannot drag the block."""
    sc = Scenario("slide", SINGLE2, Contact(0.0, 0.0), SinePulse(3.0, 0.004), duration=0.5)
    tr = engine.simulate(sc, "fast")
    assert tr.status is Status.OK
    assert np.max(np.abs(tr.x[:, 0])) < 1e-5  # the base travels 2πA = 25 mm
    assert np.max(np.abs(tr.theta)) < 1e-5


def test_sliding_nearly_follows_the_coulomb_slider(engine: NewtonEngine) -> None:
    """Every pair sees the scenario's μ: B2 slides on μ = 0.2 within 3 % of the peak exact
    slip (measured 1.75 %; the project's 1 % is not met: XPBD's friction is a position
    constraint bounded by the normal correction of the same iteration)."""
    sc = get_scenario("slide-b2-pulse-2.0hz-20mm-mu0.20")
    check_slides_like_coulomb(sc, engine.simulate(sc, "accurate"), reference(sc),
                              slip_tol=0.03)


class _Probe(NewtonEngine):
    """Keeps the base's final position at teardown."""

    base_end = math.nan

    def _teardown(self) -> None:
        if self._views:
            self.base_end = float(self._views[self._cur]["body_q"][self._bases[0], 0])
        super()._teardown()


def test_base_follows_excitation_then_stays_put() -> None:
    check_base_follows_excitation(_Probe(), "fast", 1e-6)


def test_base_motion_along_z_and_y(engine: NewtonEngine) -> None:
    """A block rides a base that moves vertically; a base moving along y carries it by
    friction (unsupported with the planar lock, which would carry it rigidly)."""
    # measured 3.8e-5 m in z: the block follows the base a step late (its travel in a step)
    check_base_drives_y_and_z(engine, z_tol=1e-4, theta_tol=1e-4, drag_tol=1e-4)


# ---------------------------------------------------------------- stacks
def test_chamfered_stack_at_rest_stays_at_rest(engine: NewtonEngine) -> None:
    """The paper's stack, its chamfered blocks as convex hulls, stays put for 2 s."""
    sc = Scenario("rest", PAPER_STACK, duration=2.0)
    tr = engine.simulate(sc, "accurate")
    assert tr.status is Status.OK
    assert np.max(np.abs(tr.theta)) < 1e-4 * lam(sc)
    np.testing.assert_allclose(tr.x, 0.0, atol=1e-5)
    np.testing.assert_allclose(tr.z - tr.z[0], 0.0, atol=1e-5)


def test_paper_stack_under_a_pulse_runs(engine: NewtonEngine) -> None:
    check_paper_stack_under_pulse_runs(engine)


def test_interface_friction_above_twice_the_base_in_an_assembly_is_unsupported(
        engine: NewtonEngine) -> None:
    sc = get_scenario("wall-6x3")
    tr = engine.simulate(sc.replace(contact=Contact(friction=0.2, interface_friction=0.5),
                                    duration=0.1))
    assert tr.status is Status.UNSUPPORTED and "mean" in tr.message


# ---------------------------------------------------------------- determinism, knobs
@pytest.mark.slow
def test_runs_are_bit_identical_and_graphs_change_nothing(engine: NewtonEngine) -> None:
    """Two runs are bit-identical (Warp's CPU kernels run serially), and replaying the
    recorded CPU graphs gives the very numbers of launching the kernels from Python."""
    sc = get_scenario("single-pulse-3.0hz-8mm").replace(duration=1.0)
    a = engine.simulate(sc, "accurate")
    b = NewtonEngine().simulate(sc, "accurate")
    c = NewtonEngine().simulate(sc, {"graph": False})
    assert a.status is b.status is c.status is Status.OK
    for field in ("theta", "x", "z", "wobble"):
        assert np.array_equal(getattr(a, field), getattr(b, field)), field
        assert np.array_equal(getattr(a, field), getattr(c, field)), field
    assert c.cpu_time > 3 * a.cpu_time  # measured: 4.5 / 0.75 s over 0.6 s at 0.25 ms


@pytest.mark.slow
def test_knob_overrides_take_effect(engine: NewtonEngine) -> None:
    sc = free_b2(1.0)
    base = engine.simulate(sc, "fast")
    for knob, value in (("iterations", 2), ("relaxation", 0.4), ("contact_weighting", True),
                        ("mu_rolling", 1e-3), ("planar", True)):
        other = engine.simulate(sc, {"preset": "fast", knob: value})
        assert other.settings[knob] == value
        assert np.max(np.abs(other.theta - base.theta)) > 1e-6, knob
    # a step that does not divide the output interval is rounded to the nearest that does
    odd = engine.simulate(sc, {"preset": "fast", "timestep": 3e-4})
    assert odd.settings["effective_timestep"] == pytest.approx(1e-3 / 3)


def test_game_preset_runs_at_its_60_hz_step(engine: NewtonEngine) -> None:
    """Newton's defaults at 60 Hz: refused against a 1 ms output interval; at 60 samples per
    second B2 ends up far from Housner (measured 0.18 λ over 3 s)."""
    sc = free_b2()
    with pytest.raises(SettingsError, match="longer than the output interval"):
        engine.simulate(sc, "game")
    coarse = sc.replace(output_rate=60.0)
    tr = engine.simulate(coarse, "game")
    assert tr.status is Status.OK
    assert tr.settings["effective_timestep"] == pytest.approx(1 / 60)
    assert 0.05 < max_error(coarse, tr.theta[:, 0]) < 0.5


# ---------------------------------------------------------------- other solvers
@pytest.mark.slow
@pytest.mark.parametrize("solver, settings, low, high", [
    # measured on B2 from 0.5 λ over 3 s (docs/engines/newton.md)
    ("steel", {"iterations": 12}, 0.004, 0.02),
    ("semi_implicit", {"timestep": 1e-4}, 0.03, 0.15),
    ("featherstone", {"timestep": 1e-4}, 0.03, 0.15),
    ("vbd", {"iterations": 10}, 0.04, 0.2),
])
def test_other_solvers_rock_as_measured(solver: str, settings: dict, low: float,
                                        high: float) -> None:
    sc = free_b2()
    tr = NewtonEngine().simulate(sc, {"solver": solver, **settings})
    assert tr.status is Status.OK, tr.message
    assert low <= max_error(sc, tr.theta[:, 0]) <= high


# ---------------------------------------------------------------- batched worlds
def _same(a: object, b: object) -> bool:
    return (a.status == b.status and a.message == b.message  # type: ignore[attr-defined]
            and np.array_equal(a.theta, b.theta) and np.array_equal(a.x, b.x)  # type: ignore[attr-defined]
            and np.array_equal(a.z, b.z))  # type: ignore[attr-defined]


def _sweep(duration: float = 2.0) -> list[Scenario]:
    """Single #2 under 3 Hz pulses from rocking to overturning, a stack and free rocking:
    worlds of several geometries, moving and still bases, and both outcomes."""
    pulse = get_scenario("single-pulse-3.0hz-8mm").replace(duration=duration)
    return [*(pulse.replace(name=f"a{a}", excitation=SinePulse(3.0, a * 1e-3))
              for a in (5, 11, 20)),
            get_scenario("stack-pulse-4.0hz-4mm").replace(duration=duration),
            free_b2(duration)]


@pytest.mark.slow
def test_a_batch_of_worlds_equals_the_runs_alone(engine: NewtonEngine) -> None:
    scs = _sweep()
    alone = [engine.simulate(sc, "fast") for sc in scs]
    many = engine.simulate_many(scs, "fast")
    assert Status.OVERTURNED in {t.status for t in alone}  # a20 overturns
    for a, b in zip(alone, many, strict=True):
        assert _same(a, b), a.scenario  # bit for bit: no contact between worlds
        assert b.settings["batch_worlds"] == len(scs)
    # the batch's CPU time is shared among its worlds and is a fraction of the runs'
    assert sum(t.cpu_time for t in many) < sum(t.cpu_time for t in alone)


@pytest.mark.slow
def test_run_jobs_batches_newton_with_the_same_results() -> None:
    from rockbench.runner import ExecutionOptions, Job, run_jobs

    jobs = [Job(sc, "newton", {"preset": "fast"}) for sc in _sweep(1.0)]
    batched = run_jobs(jobs, ExecutionOptions(jobs=2))
    single = run_jobs(jobs, ExecutionOptions(jobs=2, batch=1))
    for a, b in zip(single, batched, strict=True):
        assert _same(a, b), a.scenario
    assert {b.settings.get("batch_worlds") for b in batched} <= {2, 3}


# ---------------------------------------------------------------- cylinders and 3D starts
def test_capabilities_declare_cylinders_and_3d_starts(engine: NewtonEngine) -> None:
    assert engine.capabilities.cylinders and engine.capabilities.start3d


def test_a_cylinder_is_built_as_a_cylinder(engine: NewtonEngine) -> None:
    """Newton's cylinder shape (axis along the body's z, radius R, half-height H/2) on a
    body with the cylinder's own mass and inertia, standing on the plane z = 0; at rest it
    stays on its cap, its centre H/2 up (measured over 1 s: within 6e-8 m, no drift, no
    turn)."""
    newton = NewtonEngine.library("newton")
    sc = Scenario("rest", DRUM, duration=1.0)
    built = NewtonEngine()
    built.drive = BaseDrive(sc.motion, sc.duration)
    built._build(sc, built.settings("accurate"))
    try:
        model = built._model
        body = built._rows[0]
        types, owners = model.shape_type.numpy(), model.shape_body.numpy()
        (shape,) = np.flatnonzero(owners == body)
        assert types[shape] == int(newton.GeoType.CYLINDER)
        np.testing.assert_allclose(model.shape_scale.numpy()[shape, :2], (DRUM.radius, DRUM.h),
                                   rtol=1e-6)
        # the shape's frame is the body's: its axis is the body's z
        np.testing.assert_array_equal(model.shape_transform.numpy()[shape],
                                      (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0))
        # the ground is Newton's plane (its cylinder routine), not the blocks' box
        assert list(types[owners == -1]) == [int(newton.GeoType.PLANE)]
        assert model.body_mass.numpy()[body] == pytest.approx(DRUM.m, rel=1e-6)
        np.testing.assert_allclose(model.body_inertia.numpy()[body], DRUM.inertia_tensor,
                                   rtol=1e-6)
    finally:
        built._teardown()

    tr = engine.simulate(sc, "accurate")
    assert tr.status is Status.OK
    assert np.max(np.abs(tr.z[:, 0] - DRUM.h)) < 2e-7
    assert np.max(np.abs(tr.x)) < 1e-7 and np.max(np.abs(tr.y)) < 1e-7
    assert np.max(np.abs(tr.theta)) < 1e-7 and np.max(np.abs(tr.roll)) < 1e-7


def test_drum_rocks_like_housner(engine: NewtonEngine) -> None:
    """First impact 0.080 % early at accurate and 0.45 % at fast (measured), the drum
    exactly in the plane (roll and twist 0)."""
    check_cylinder_rocks_like_housner(engine, "accurate", rel=1.5e-3, plane_tol=1e-7)
    check_cylinder_rocks_like_housner(engine, "fast", rel=8e-3, plane_tol=1e-7)


@pytest.mark.xfail(strict=True, reason=(
    "XPBD's position-level impact: at 0.125 ms (half the accurate step) the drum rebounds "
    "from its first impact to 1.04 times its release tilt (Housner: 0.70; 0.79 at 0.25 ms, "
    "0.77 at 1 ms, 0.69 at 0.0625 ms) and the watchdog stops it for energy gain at "
    "0.615 s; its first impact is 0.20 % early (0.080 % at 0.25 ms)"))
def test_drum_at_half_the_accurate_step(engine: NewtonEngine) -> None:
    check_cylinder_rocks_like_housner(engine, {"timestep": 1.25e-4}, rel=1.5e-3,
                                      plane_tol=1e-7)


def test_drum_released_toward_any_azimuth_falls_alike(engine: NewtonEngine) -> None:
    # measured: tilt within 1.4e-5 rad, azimuth 9.0e-5 rad of the in-plane release
    check_drum_falls_alike_toward_any_azimuth(engine, tilt_tol=3e-5, azimuth_tol=1.8e-4)


def test_corner_release(engine: NewtonEngine) -> None:
    """Landing 0.050 % early at accurate and 0.39 % at fast, on the diagonal to 1.1e-6 and
    2.1e-7 rad (measured)."""
    check_corner_release(engine, "accurate", rel=1e-3, diagonal_tol=2e-6)
    check_corner_release(engine, "fast", rel=6.5e-3, diagonal_tol=4e-7)


def test_steady_precession_accurate(engine: NewtonEngine) -> None:
    """Over 2 s: the tilt within 9.1e-4 rad of 0.2 (growing), the rate 0.30 % slow
    (measured)."""
    check_steady_precession(engine, "accurate", tilt_tol=1.6e-3, rate_rtol=5e-3)


def test_steady_precession_fast(engine: NewtonEngine) -> None:
    """Over 2 s: the tilt within 1.5e-3 rad of 0.2, the rate 0.30 % slow (measured)."""
    check_steady_precession(engine, "fast", tilt_tol=2.5e-3, rate_rtol=5e-3)


@pytest.mark.xfail(strict=True, reason=(
    "XPBD's rim contact drifts the precession's tilt by a bias that does not shrink with the "
    "step: after 2 s the tilt is 9.0e-4 rad off 0.2 at 0.125 ms (9.1e-4 at 0.25 ms, 1.7e-3 "
    "at 0.0625 ms, 1.5e-3 at the fast preset) and the rate 0.29 % slow (0.30 %, 0.46 %, "
    "0.30 %); nor with the iterations (16: 1.1e-3 rad) or the relaxation (0.3: 5.7e-4, "
    "0.8: 8.4e-4)"))
def test_steady_precession_converges_as_the_step_halves(engine: NewtonEngine) -> None:
    check_steady_precession(engine, {"timestep": 1.25e-4}, tilt_tol=3e-4, rate_rtol=1e-3)


def test_a_moving_start_is_applied_in_world_axes(engine: NewtonEngine) -> None:
    """The precession's start (velocity of the centre of gravity and angular velocity, world
    axes) is the first sample's motion: the centre moves along +y at the state's speed."""
    sc, _ = precession(0.05)
    st = sc.initial_states()[0]
    tr = engine.simulate(sc, "accurate")
    assert tr.status is Status.OK
    assert tr.x[0, 0] == pytest.approx(st[0], abs=1e-7)
    assert tr.z[0, 0] == pytest.approx(st[2], abs=1e-7)
    vy = (tr.y[1, 0] - tr.y[0, 0]) / (tr.t[1] - tr.t[0])
    assert vy == pytest.approx(st[8], rel=6e-5)  # measured 2.9e-5


@pytest.mark.slow
def test_a_moving_start_reaches_the_joint_space_solvers(engine: NewtonEngine) -> None:
    """Steel steps the free joints' coordinates: the start is written to them too (the
    centre's speed 5.7e-5 off the state's, the tilt within 5.1e-5 rad of 0.2 over 0.05 s,
    measured)."""
    sc, sp = precession(0.05)
    st = sc.initial_states()[0]
    tr = engine.simulate(sc, {"solver": "steel"})
    assert tr.status is Status.OK, tr.message
    vy = (tr.y[1, 0] - tr.y[0, 0]) / (tr.t[1] - tr.t[0])
    assert vy == pytest.approx(st[8], rel=1.2e-4)
    assert np.max(np.abs(tr.tilt[:, 0] - sp.theta)) < 1e-4


def test_3d_starts_in_a_batch_equal_the_runs_alone(engine: NewtonEngine) -> None:
    """Every world of a batch gets its own 3D start (bit for bit the runs alone)."""
    scs = [precession(0.3)[0], corner_release(0.3), drum_release(0.3), free_b2(0.3)]
    alone = [engine.simulate(sc, "fast") for sc in scs]
    many = engine.simulate_many(scs, "fast")
    for a, b in zip(alone, many, strict=True):
        assert b.status is Status.OK
        assert _same(a, b), a.scenario
        assert np.array_equal(a.y, b.y) and np.array_equal(a.roll, b.roll), a.scenario


def test_a_3d_start_with_planar_joints_is_unsupported(engine: NewtonEngine) -> None:
    tr = engine.simulate(corner_release(0.1), {"planar": True})
    assert tr.status is Status.UNSUPPORTED
    assert "planar" in tr.message
