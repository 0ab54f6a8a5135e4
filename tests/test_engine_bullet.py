"""Physics tests of the pybullet engine plugin against the Housner reference."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("pybullet")

from engine_helpers import (  # noqa: E402
    check_arch_rides_its_supports,
    check_assembly_stays_at_rest,
    check_base_drives_y_and_z,
    check_corner_release,
    check_cylinder_rocks_like_housner,
    check_rides_a_base_along_y,
    check_rocks_about_x_like_housner,
    check_steady_precession,
    check_tilting_table,
    inclined_scene,
    lam,
    zero_crossings,
)

from rockbench.analytic.housner import single_block_reference  # noqa: E402
from rockbench.engines import EngineSettings, SettingsError, get_engine  # noqa: E402
from rockbench.engines.bullet_engine import (  # noqa: E402
    BulletEngine,
    BulletSettings,
    principal_frame,
)
from rockbench.geometry import Block, Cylinder, Prism  # noqa: E402
from rockbench.metrics import impact_times  # noqa: E402
from rockbench.scenarios import Contact, Scenario, SinePulse, get_scenario  # noqa: E402
from rockbench.trajectory import Status  # noqa: E402


@pytest.fixture(scope="module")
def engine() -> BulletEngine:
    eng = get_engine("bullet")
    assert isinstance(eng, BulletEngine)
    return eng


@pytest.fixture(scope="module")
def b2() -> Scenario:
    return get_scenario("free-b2-0.5").replace(duration=6.0)


@pytest.fixture(scope="module")
def b2_ref(b2: Scenario):
    return single_block_reference(b2)


def test_registry_and_presets(engine: BulletEngine) -> None:
    assert engine.name == "bullet"
    assert engine.version().startswith("3.")
    assert {"accurate", "fast"} <= set(engine.presets)
    # defaults are the accurate preset
    assert engine.settings("accurate") == engine.Settings()
    assert engine.settings().dt == pytest.approx(1e-4)
    assert engine.settings("fast").dt == pytest.approx(1e-3)
    # the paper's Δt = 1 / ((n_s + 1) · FPS) and the explicit override
    assert engine.settings(fps=240, substeps=20).dt == pytest.approx(1 / (21 * 240))
    assert engine.settings(substeps="3", timestep="2e-4").dt == pytest.approx(2e-4)
    with pytest.raises(SettingsError):
        engine.settings(collision_shape="sphere")
    with pytest.raises(SettingsError):
        engine.settings(substeps=-1)


def test_free_rocking_accurate(engine: BulletEngine, b2: Scenario, b2_ref) -> None:
    tr = engine.simulate(b2, "accurate")
    assert tr.status == Status.OK
    err = np.max(np.abs(tr.theta[:, 0] - b2_ref.theta[:, 0])) / lam(b2)
    assert err <= 5e-3
    zc = zero_crossings(tr.t, tr.theta[:, 0])[:3]
    np.testing.assert_allclose(zc, b2_ref.impacts[:3], rtol=5e-3)
    assert tr.settings["effective_timestep"] == pytest.approx(1e-4)
    # Bullet's friction pyramid lets the block twist slightly out of plane
    assert np.max(tr.wobble) < 1e-2


def test_free_rocking_fast(engine: BulletEngine) -> None:
    sc = get_scenario("free-b1-0.5").replace(duration=6.0)
    ref = single_block_reference(sc)
    tr = engine.simulate(sc, "fast")
    assert tr.status == Status.OK
    assert np.max(np.abs(tr.theta[:, 0] - ref.theta[:, 0])) / lam(sc) <= 0.05


def test_sine_pulse_peak(engine: BulletEngine) -> None:
    sc = get_scenario("single-pulse-3.0hz-8mm").replace(duration=1.5)
    ref = single_block_reference(sc)
    tr = engine.simulate(sc, "accurate")
    assert tr.status == Status.OK
    peak, peak_ref = np.max(np.abs(tr.theta)), np.max(np.abs(ref.theta))
    assert peak == pytest.approx(peak_ref, rel=0.02)
    # a positive base acceleration tips the block to θ < 0 first, as in the reference
    first = np.argmax(np.abs(tr.theta[:, 0]) > 1e-3 * lam(sc))
    assert tr.theta[first, 0] < 0 and ref.theta[first, 0] < 0


def test_base_drags_block(engine: BulletEngine) -> None:
    # sub-threshold pulse on a squat block: no uplift, the block rides on the base
    sc = Scenario("ride", Block(1.0, 0.5, 0.5, mass=10.0), excitation=SinePulse(2.0, 0.002),
                  duration=1.0)
    tr = engine.simulate(sc, "fast")
    assert tr.status == Status.OK
    assert np.max(np.abs(tr.theta)) < 1e-4
    u = sc.excitation.displacement(tr.t)
    assert np.max(np.abs(tr.x[:, 0] - u)) < 1e-4
    assert tr.x[-1, 0] == pytest.approx(2 * math.pi * 0.002, abs=1e-4)


def test_stack_at_rest_stays_at_rest(engine: BulletEngine) -> None:
    stack = get_scenario("stack-pulse-4.0hz-4mm").geometry
    sc = Scenario("rest", stack, duration=2.0)
    tr = engine.simulate(sc, "fast")
    assert tr.status == Status.OK
    assert np.max(np.abs(tr.theta)) < 1e-5
    assert np.max(np.abs(tr.x - tr.x[0])) < 1e-5
    assert np.max(np.abs(tr.z - tr.z[0])) < 1e-5


def test_stack_pulse_runs(engine: BulletEngine) -> None:
    sc = get_scenario("stack-pulse-5.0hz-4mm").replace(duration=1.5)
    tr = engine.simulate(sc, "fast")
    assert tr.status == Status.OK
    assert tr.theta.shape == (tr.t.size, 2)
    assert 0.0 < np.max(np.abs(tr.theta)) < lam(sc)


@pytest.mark.parametrize("shape", ["convex", "mesh"])
def test_hull_and_mesh_shapes(engine: BulletEngine, b2: Scenario, b2_ref, shape: str) -> None:
    sc = b2.replace(duration=3.0)
    tr = engine.simulate(sc, {"preset": "fast", "collision_shape": shape})
    assert tr.status == Status.OK
    n = tr.t.size
    assert np.max(np.abs(tr.theta[:, 0] - b2_ref.theta[:n, 0])) / lam(sc) < 0.05


def test_knob_overrides_take_effect(engine: BulletEngine, b2: Scenario) -> None:
    sc = b2.replace(duration=2.0)
    fine = engine.simulate(sc, "fast")
    # Δt = 1 / ((n_s + 1) · fps): 250 fps × 4 is the same 1 ms step
    same = engine.simulate(sc, {"preset": "fast", "fps": 250.0, "substeps": 3})
    assert same.settings["effective_timestep"] == pytest.approx(1e-3)
    np.testing.assert_array_equal(same.theta, fine.theta)
    other = engine.simulate(sc, {"preset": "fast", "contact_breaking_threshold": 0.02})
    assert np.max(np.abs(other.theta - fine.theta)) > 1e-6
    # the breaking threshold is global in Bullet: a later run must not inherit it
    again = engine.simulate(sc, "fast")
    np.testing.assert_array_equal(again.theta, fine.theta)
    half = engine.simulate(sc, {"preset": "fast", "timestep": 5e-4})
    assert half.settings["effective_timestep"] == pytest.approx(5e-4)
    assert np.max(np.abs(half.theta - fine.theta)) > 1e-6


def test_time_step_longer_than_output_interval(engine: BulletEngine, b2: Scenario) -> None:
    # the paper's 240 fps without sub-steps: Δt = 4.2 ms. Against the 1 ms output
    # interval it is refused (the output would claim a resolution the physics lacks);
    # at 240 samples/s, one step per sample, the rocking is still Housner's
    with pytest.raises(SettingsError, match="longer than the output interval"):
        engine.simulate(b2, {"fps": 240.0, "substeps": 0})
    coarse = b2.replace(output_rate=240.0)
    traj = engine.simulate(coarse, {"fps": 240.0, "substeps": 0})
    assert traj.status is Status.OK
    np.testing.assert_allclose(np.diff(traj.t), 1 / 240)
    assert traj.settings["effective_timestep"] == pytest.approx(1 / 240)
    first = impact_times(traj)[0]
    ref = single_block_reference(coarse)
    assert first == pytest.approx(float(impact_times(ref)[0]), rel=0.03)


def test_mesh_stack_unsupported(engine: BulletEngine) -> None:
    sc = Scenario("rest", get_scenario("stack-pulse-4.0hz-4mm").geometry, duration=0.1)
    traj = engine.simulate(sc, {"collision_shape": "mesh"})
    assert traj.status is Status.UNSUPPORTED and "concave" in traj.message


def test_settings_dataclass_is_frozen() -> None:
    s = BulletSettings()
    with pytest.raises(AttributeError):
        s.fps = 10.0  # type: ignore[misc]


# ---------------------------------------------------------------- assemblies
@pytest.mark.slow
def test_assemblies_of_boxes_stay_at_rest(engine: BulletEngine) -> None:
    # box-box contacts (four corner points per face from the first step): a column, a
    # parapet on its wall and a running-bond wall keep their poses to 1e-5 λ and 20 µm
    for name in ("column-5drums", "parapet-offset0.25", "wall-6x3"):
        check_assembly_stays_at_rest(engine, name, duration=0.5, turn=1e-4, drift=2e-5)


def test_principal_frame_of_an_isosceles_right_triangle() -> None:
    # legs a along x and z: the principal axes are the symmetry axis and its normal
    # (φ = ±45°), the in-plane centroidal moments ρ·a⁴/24 and ρ·a⁴/72
    a, depth = 0.6, 0.4
    tri = Prism(((0.0, 0.0), (a, 0.0), (0.0, a)), depth, mass=3.0)
    phi, moments = principal_frame(tri.inertia_tensor)
    assert abs(phi) == pytest.approx(math.pi / 4, rel=1e-12)
    rho = tri.m / (0.5 * a * a)
    slab = tri.m * depth**2 / 12.0
    in_plane = sorted((moments[0] - slab, moments[2] - slab))
    assert in_plane == pytest.approx([rho * a**4 / 72, rho * a**4 / 24], rel=1e-12)
    assert moments[1] == pytest.approx(tri.inertia_tensor[1, 1], rel=1e-15)


def test_prism_in_its_principal_frame_reads_back_its_own_pose(engine: BulletEngine) -> None:
    block, prism = engine.simulate(inclined_scene(False)), engine.simulate(inclined_scene(True))
    assert block.status is prism.status is Status.OK
    assert abs(principal_frame(inclined_scene(True).blocks[0].inertia_tensor)[0]) > 0.05
    # at rest on the slope: the block at 0.1 rad, the prism at its pose angle 0, both still
    assert np.max(np.abs(block.theta - 0.1)) < 1e-4
    assert np.max(np.abs(prism.theta)) < 1e-4
    assert np.max(np.abs(prism.x - block.x)) < 1e-5 and np.max(np.abs(prism.z - block.z)) < 1e-5
    # rocked by a pulse (box and hull collide differently: a few % apart)
    pulse = SinePulse(2.0, 0.04)
    rb = engine.simulate(inclined_scene(False, pulse))
    rp = engine.simulate(inclined_scene(True, pulse))
    peak_b, peak_p = np.max(np.abs(rb.theta - 0.1)), np.max(np.abs(rp.theta))
    assert peak_b > 0.05 and peak_p == pytest.approx(peak_b, rel=0.1)


@pytest.mark.slow
def test_supports_move_with_the_base(engine: BulletEngine) -> None:
    # (to 0.5 %: the voussoirs lag the base by a few 0.1 mm, Bullet's contacts creep)
    check_arch_rides_its_supports(engine, rtol=0.01, turn=0.01)


def test_interface_friction_zero_in_an_assembly_is_unsupported(engine: BulletEngine) -> None:
    # a running-bond wall's blocks touch blocks and the base at once: no per-body
    # coefficients give both products
    sc = get_scenario("wall-6x3")
    assert sc.geometry.column is None
    tr = engine.simulate(sc.replace(contact=Contact(friction=1.0, interface_friction=0.0),
                                    duration=0.1))
    assert tr.status is Status.UNSUPPORTED and "multiplies" in tr.message
    # a parapet on its wall is a column: its blocks alternate 1 and μ_if
    sc = get_scenario("parapet-offset0.25")
    assert sc.geometry.column is not None
    tr = engine.simulate(sc.replace(contact=Contact(friction=1.0, interface_friction=0.0),
                                    duration=0.1))
    assert tr.status is Status.OK


# Tilting table at 0.05 /s and 0.025 /s (accurate preset), measured: parapet onsets
# 0.1302 / 0.1275 against the LP's 0.125 (+2.0 %), 5-drum column 0.2484 / 0.2450
# against 0.24 (+2.1 %), the LP mechanism (the parapet alone; the column as one body).
@pytest.mark.slow
def test_tilting_table_onset_matches_the_collapse_factor() -> None:
    check_tilting_table("bullet")


# ---------------------------------------------------------------- base motion along y and z
def test_base_drives_y_and_z() -> None:
    """The engines' common check: Single #2 rides a base moving vertically and is carried
    by friction along y (this engine has no planar knob)."""
    # measured: z within 2.1e-11 m, the y drag's end within 3.8e-9 m
    check_base_drives_y_and_z(BulletEngine(), z_tol=1e-6, planar=False)


def test_a_base_moving_along_y_carries_the_block() -> None:
    # measured: y within 2.8e-8 m of the base
    check_rides_a_base_along_y(BulletEngine(), y_tol=1e-6)


def test_a_block_excited_along_y_rocks_about_x_like_housner() -> None:
    # measured: the roll within 7.4e-4 λ of −θ_ref
    check_rocks_about_x_like_housner(BulletEngine(), plane_tol=1e-5)


# ---------------------------------------------------------------- cylinders and 3D starts
# Measured (docs/engines/bullet.md, "Cylinders and 3D starts"): the drum's first impact
# +0.031 % (accurate) / −0.099 % (fast), roll and twist ≤ 2.7e-7 / 3.1e-7 rad; the corner
# landing −0.009 % / −0.127 %, |θ + roll| ≤ 1.2e-9 / 1.3e-6 rad; the 5 s precession's tilt
# within 9.4e-5 / 1.11e-3 rad of 0.2, its rate −0.048 % / −0.012 %.
@pytest.mark.parametrize(("preset", "rel", "plane_tol"),
                         [("accurate", 6e-4, 5e-7), ("fast", 2e-3, 6e-7)])
def test_cylinder_rocks_like_housner(preset: str, rel: float, plane_tol: float) -> None:
    check_cylinder_rocks_like_housner(BulletEngine(), preset, rel=rel, plane_tol=plane_tol)


@pytest.mark.parametrize(("preset", "rel", "diagonal_tol"),
                         [("accurate", 1.8e-4, 2.4e-9), ("fast", 2.5e-3, 2.5e-6)])
def test_corner_release(preset: str, rel: float, diagonal_tol: float) -> None:
    check_corner_release(BulletEngine(), preset, rel=rel, diagonal_tol=diagonal_tol)


@pytest.mark.parametrize(("preset", "tilt_tol", "rate_rtol"),
                         [("accurate", 1.5e-4, 9e-4), ("fast", 2e-3, 2.2e-4)])
def test_steady_precession(preset: str, tilt_tol: float, rate_rtol: float) -> None:
    check_steady_precession(BulletEngine(), preset, tilt_tol=tilt_tol, rate_rtol=rate_rtol,
                            duration=5.0)


class _ShapeProbe(BulletEngine):
    """Reads the first body's dynamics (and, from a multibody, its collision shape) back
    from pybullet at build."""

    def _build(self, scenario: Scenario, settings: EngineSettings) -> float:
        dt = super()._build(scenario, settings)
        pb, body, cid = self._pb, self._bodies[0], self._cid
        self.dynamics = pb.getDynamicsInfo(body, -1, physicsClientId=cid)
        # pybullet reads shapes back from multibodies only, not from a btRigidBody
        assert isinstance(settings, BulletSettings)
        if not settings.maximal_coordinates:
            self.shape = pb.getCollisionShapeData(body, -1, physicsClientId=cid)[0]
        return dt


def test_a_cylinder_is_built_as_a_cylinder() -> None:
    import pybullet as pb

    drum = Cylinder(0.15, 1.0, density=2500.0)
    sc = Scenario("drum-rest", drum, duration=0.5)
    BulletEngine().check_supported(sc)  # raises UnsupportedScenario if not
    for maximal in (True, False):
        probe = _ShapeProbe()
        tr = probe.simulate(sc, {"preset": "accurate", "maximal_coordinates": maximal})
        assert tr.status is Status.OK
        # the cylinder's mass and inertia, not those of a default density
        assert probe.dynamics[0] == pytest.approx(drum.m, rel=1e-12)
        assert probe.dynamics[2] == pytest.approx(drum.inertia, rel=1e-12)
        # standing on its base it stays at rest, its centre H/2 above the ground
        assert np.max(np.abs(tr.z[:, 0] - drum.h)) < 1e-6
        assert np.max(np.abs(tr.x)) < 1e-6 and np.max(np.abs(tr.y)) < 1e-6
        assert np.max(tr.tilt) < 1e-6
    # Bullet's own cylinder: (.., geometry type, dimensions (height, radius, ..), ..)
    assert probe.shape[2] == pb.GEOM_CYLINDER
    assert probe.shape[3][:2] == pytest.approx((drum.height, drum.radius), rel=1e-12)
