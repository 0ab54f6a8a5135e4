"""Physics tests of the DART engine plugin (``rockbench.engines.dart_engine``)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

pytest.importorskip("dartpy")

from engine_helpers import (  # noqa: E402, E501
    B0,
    B2,
    PAPER_STACK,
    SINGLE2,
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
from rockbench.engines.dart_engine import DartEngine, DartSettings, _prism_obj  # noqa: E402
from rockbench.engines.drive import BaseDrive  # noqa: E402
from rockbench.engines.settings import SettingsError  # noqa: E402
from rockbench.geometry import Block, Cylinder, Geometry, Support, stack  # noqa: E402
from rockbench.scenarios import Contact, Scenario, SinePulse, get_scenario  # noqa: E402
from rockbench.scenarios.excitation import Components  # noqa: E402
from rockbench.studies.references_3d import precession  # noqa: E402
from rockbench.trajectory import Status  # noqa: E402


def housner(scenario: Scenario) -> np.ndarray:
    """θ of the project's Housner reference at the scenario's output times."""
    ref = single_block_reference(scenario)
    return np.interp(scenario.output_times(), np.asarray(ref.t), np.asarray(ref.theta)[:, 0])


def crossings(t: np.ndarray, th: np.ndarray, n: int = 3) -> np.ndarray:
    """The first ``n`` zero crossings of θ."""
    return zero_crossings(t, th)[:n]


@pytest.mark.slow
def test_free_rocking_b2_accurate_matches_housner() -> None:
    sc = Scenario("free-b2-0.5", B2, initial_tilt=0.5, duration=2.5)
    traj = DartEngine().simulate(sc, "accurate")
    assert traj.status == "ok", traj.message
    ref = housner(sc)
    th = traj.theta[:, 0]
    assert np.max(np.abs(th - ref)) / lam(sc) <= 5e-3
    t = sc.output_times()
    tc, tc_ref = crossings(t, th), crossings(t, ref)
    assert tc.size == 3
    np.testing.assert_allclose(tc, tc_ref, rtol=5e-3)
    assert np.max(traj.wobble) < 1e-6  # planar motion stays planar


def test_free_rocking_b0_fast_within_5_percent_of_lambda() -> None:
    sc = Scenario("free-b0", B0, initial_tilt=0.5, duration=4.0)
    traj = DartEngine().simulate(sc, "fast")
    assert traj.status == "ok", traj.message
    err = np.max(np.abs(traj.theta[:, 0] - housner(sc))) / lam(sc)
    assert err <= 0.05
    # the first impact of B0 (closed form: 0.7761248546 s)
    assert crossings(sc.output_times(), traj.theta[:, 0], 1)[0] == pytest.approx(0.7761248546,
                                                                                 rel=5e-3)


def test_mirror_symmetry_fast() -> None:
    eng = DartEngine()
    sc = Scenario("m", B2, initial_tilt=0.5, duration=1.0)
    a = eng.simulate(sc, "fast").theta[:, 0]
    b = eng.simulate(sc.replace(initial_tilt=-0.5), "fast").theta[:, 0]
    np.testing.assert_allclose(a, -b, atol=1e-6 * lam(sc))


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
    eng.drive = BaseDrive(sc.motion, sc.duration)  # what simulate() sets before _build
    dt = eng._build(sc, eng.settings("fast"))
    n = int(round(0.1 / dt))
    eng._advance_driven(0.0, n, dt)
    assert eng._base_joint.getPosition(0) == pytest.approx(float(exc.displacement(n * dt)),
                                                           abs=1e-12)
    eng._teardown()


@pytest.mark.parametrize("geometry, preset", [
    (stack((Block(0.4, 0.3, 0.8, mass=10.0), Block(0.3, 0.3, 0.6, mass=5.0))), "fast"),
    (PAPER_STACK, "fast"),
    (PAPER_STACK, "accurate"),
])
def test_stack_at_rest_stays_at_rest(geometry: Geometry, preset: str) -> None:
    sc = Scenario("rest", geometry, duration=0.5)
    traj = DartEngine().simulate(sc, preset)
    assert traj.status == "ok", traj.message
    assert np.max(np.abs(traj.theta)) < 1e-4 * lam(sc)
    z0 = sc.geometry.centroids[:, 1]
    np.testing.assert_allclose(traj.z[-1], z0, atol=1e-4)
    np.testing.assert_allclose(traj.x[-1], 0.0, atol=1e-5)


def test_paper_stack_under_pulse_runs_sensibly() -> None:
    sc = Scenario("stack-pulse-3.3hz-8mm", PAPER_STACK,
                  excitation=SinePulse(frequency=3.3, amplitude=0.008), duration=1.5)
    traj = DartEngine().simulate(sc, "fast")
    assert traj.status == "ok", traj.message
    peak = np.max(np.abs(traj.theta), axis=0) / lam(sc)
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
    _prism_obj(blk.profile(), blk.depth, str(path))
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


# ---------------------------------------------------------------- assemblies
def test_assemblies_of_boxes_stay_at_rest() -> None:
    # fast preset (ODE, 1 ms): a column and a parapet on its wall keep their poses
    # (measured 5e-6 λ and 2.5e-7 λ, 1.7 µm and the first step's 9.8 µm sink)
    for name in ("column-5drums", "parapet-offset0.25"):
        check_assembly_stays_at_rest(DartEngine(), name, duration=1.0, turn=1e-4, drift=2e-5,
                                     settings="fast")


def test_prism_reads_back_its_own_pose_and_rocks_like_the_block() -> None:
    eng = DartEngine()
    block, prism = eng.simulate(inclined_scene(False), "single"), eng.simulate(inclined_scene(True),
                                                                           "single")
    assert block.status is prism.status is Status.OK
    assert np.max(np.abs(block.theta - 0.1)) < 1e-4 and np.max(np.abs(prism.theta)) < 1e-4
    assert np.max(np.abs(prism.x - block.x)) < 1e-5 and np.max(np.abs(prism.z - block.z)) < 1e-5
    # rocked by a pulse on the moving (mesh) support: peaks measured 0.05 % apart
    pulse = SinePulse(2.0, 0.04)
    rb = eng.simulate(inclined_scene(False, pulse), "single")
    rp = eng.simulate(inclined_scene(True, pulse), "single")
    peak_b, peak_p = np.max(np.abs(rb.theta - 0.1)), np.max(np.abs(rp.theta))
    assert peak_b > 0.05 and peak_p == pytest.approx(peak_b, rel=0.01)


def test_supports_move_with_the_base() -> None:
    # a block standing on a (box) support only rides with it under a sub-threshold pulse
    asm = Geometry((Block(0.4, 0.3, 0.6, density=2000.0),), ((0.0, 0.6, 0.0),),
                   (Support.rectangle(-0.3, 0.3, 0.0, 0.3),))
    amp = 0.002
    sc = Scenario("on-support", asm, excitation=SinePulse(2.0, amp), duration=1.0)
    tr = DartEngine().simulate(sc, "fast")
    assert tr.status is Status.OK, tr.message
    assert np.max(np.abs(tr.theta)) < 1e-4
    assert tr.x[-1, 0] - tr.x[0, 0] == pytest.approx(2 * math.pi * amp, rel=0.01)


def test_interface_friction_below_the_base_friction_off_a_column_is_unsupported() -> None:
    # a wall's bricks touch each other and the base at once: no per-body choice holds
    sc = get_scenario("wall-6x3").replace(
        contact=Contact(friction=1.0, interface_friction=0.5), duration=0.1)
    tr = DartEngine().simulate(sc, "fast")
    assert tr.status is Status.UNSUPPORTED and "smaller" in tr.message
    # a column (the parapet on its wall) is built: its bottom block carries μ, the rest μ_if
    sc = get_scenario("parapet-offset0.25").replace(
        contact=Contact(friction=1.0, interface_friction=0.5), duration=0.1)
    tr = DartEngine().simulate(sc, "fast")
    assert tr.status is Status.OK, tr.message


# Tilting table at 0.05 /s and 0.025 /s (fast preset; the single preset's onsets are
# the same), measured: parapet 0.1311 / 0.1289 against the LP's 0.125 (+3.2 %), 5-drum
# column 0.2487 / 0.2456 against 0.24 (+2.3 %), both extrapolated to rate 0 within 0.3 %.
@pytest.mark.slow
def test_tilting_table_onset_matches_the_collapse_factor() -> None:
    check_tilting_table("dart", {"preset": "fast"}, slower_first=False, extrapolated=0.01)


# ---------------------------------------------------------------- base motion along y and z
def test_the_base_joint_is_prismatic_along_x_only() -> None:
    assert DartEngine.capabilities.base_axes == "xyz"
    for exc, kind in ((SinePulse(3.0, 0.008), "PrismaticJoint"),
                      (Components(y=SinePulse(3.0, 0.008)), "TranslationalJoint"),
                      (Components(z=SinePulse(4.0, 0.003)), "TranslationalJoint")):
        sc = Scenario("drive", SINGLE2, excitation=exc, duration=0.3)
        eng = DartEngine()
        eng.drive = BaseDrive(sc.motion, sc.duration)  # what simulate() sets before _build
        dt = eng._build(sc, eng.settings("fast"))
        assert type(eng._base_joint).__name__ == kind
        n = int(round(0.1 / dt))
        eng._advance_driven(0.0, n, dt)
        # the base stands on u_g at the step nodes: along x, or along x, y and z
        u = sc.motion.displacement(n * dt)
        expected = u if kind == "TranslationalJoint" else u[:1]
        np.testing.assert_allclose(eng._base_joint.getPositions(), expected, atol=1e-12)
        eng._teardown()


def test_base_drives_y_and_z() -> None:
    """The engines' common check: Single #2 rides a base moving vertically and is carried
    by friction along y (this engine has no planar knob)."""
    # measured: z within 3.1e-12 m, the y drag's end within 2e-16 m
    check_base_drives_y_and_z(DartEngine(), z_tol=1e-6, planar=False)


def test_a_base_moving_along_y_carries_the_block() -> None:
    # measured: y within 6.1e-11 m of the base
    check_rides_a_base_along_y(DartEngine(), y_tol=1e-6)


def test_a_block_excited_along_y_rocks_about_x_like_housner() -> None:
    # measured: the roll within 1.7e-5 λ of −θ_ref
    check_rocks_about_x_like_housner(DartEngine(), plane_tol=1e-6)


# ---------------------------------------------------------------- cylinders and 3D starts
def test_a_cylinder_is_built_as_a_cylinder() -> None:
    # DART's native CylinderShape (FCL's primitive, not a mesh), the body's mass and
    # inertia; left alone it stands still on its flat end, its centre at z = H/2
    # (measured accurate / fast: z within 3.5e-8 / 9.8e-6 m (the first step's sink),
    # x, y and twist within 7.4e-9 / 3.2e-19, no tilt)
    cyl = Cylinder(0.3, 1.5, density=2000.0)
    sc = Scenario("cyl-rest", cyl, duration=0.5)
    eng = DartEngine()
    eng.drive = BaseDrive(sc.motion, sc.duration)  # what simulate() sets before _build
    eng._build(sc, eng.settings("accurate"))
    bn = eng._skels[0].getBodyNode(0)
    shape = bn.getShapeNode(0).getShape()
    assert type(shape).__name__ == "CylinderShape"
    assert (shape.getRadius(), shape.getHeight()) == (cyl.radius, cyl.height)
    assert bn.getMass() == cyl.m
    np.testing.assert_allclose(bn.getInertia().getMoment(), cyl.inertia_tensor, rtol=1e-15)
    detector = eng._world.getConstraintSolver().getCollisionDetector()
    assert detector.getPrimitiveShapeType() == detector.PrimitiveShape.PRIMITIVE
    eng._teardown()
    for preset in ("accurate", "fast"):
        tr = eng.simulate(sc, preset)
        assert tr.status is Status.OK, tr.message
        np.testing.assert_allclose(tr.z[:, 0], 0.5 * cyl.height, atol=2e-5)
        drift = max(np.max(np.abs(tr.x)), np.max(np.abs(tr.y)), np.max(np.abs(tr.twist)))
        assert drift < 1.5e-8 and np.max(tr.wobble) < 1e-12


def test_a_3d_start_sets_the_pose_and_world_velocities() -> None:
    # the precessing start: position, orientation, velocity of the centre of mass and
    # angular velocity read back from the FreeJoint in world axes
    sc, _ = precession(0.1)
    st = sc.initial_states()[0]
    eng = DartEngine()
    eng.drive = BaseDrive(sc.motion, sc.duration)
    eng._build(sc, eng.settings("fast"))
    bn = eng._skels[0].getBodyNode(0)
    tf = bn.getWorldTransform()
    np.testing.assert_allclose(tf.translation(), st[:3], atol=1e-15)
    w, x, y, z = st[3:7]
    np.testing.assert_allclose(tf.rotation(), Rotation.from_quat([x, y, z, w]).as_matrix(),
                               atol=1e-15)
    np.testing.assert_allclose(bn.getLinearVelocity(), st[7:10], atol=1e-14)
    np.testing.assert_allclose(bn.getAngularVelocity(), st[10:13], atol=1e-14)
    np.testing.assert_allclose(eng._read_poses()[0], st[:7], atol=1e-15)
    eng._teardown()


def test_cylinders_with_the_dart_detector_are_unsupported() -> None:
    sc = Scenario("drum", Cylinder(0.15, 1.0, density=2500.0), duration=0.05)
    tr = DartEngine().simulate(sc, {"preset": "fast", "collision_detector": "dart"})
    assert tr.status is Status.UNSUPPORTED and "cylinder" in tr.message


# measured (accurate / fast): first impact −0.0042 % / −0.125 %, roll 5.8e-11 / 2e-17 rad
@pytest.mark.parametrize("preset, rel, plane_tol", [("accurate", 8e-5, 1e-10),
                                                    ("fast", 2.5e-3, 1e-12)])
def test_drum_rocks_like_housner(preset: str, rel: float, plane_tol: float) -> None:
    check_cylinder_rocks_like_housner(DartEngine(), preset, rel=rel, plane_tol=plane_tol)


# measured (accurate / fast): landing −0.00014 % / −0.126 %, |θ + roll| 1.4e-15 / 2.9e-16 rad
@pytest.mark.parametrize("preset, rel", [("accurate", 3e-6), ("fast", 2.5e-3)])
def test_corner_release_lands_on_time_on_the_diagonal(preset: str, rel: float) -> None:
    check_corner_release(DartEngine(), preset, rel=rel, diagonal_tol=1e-12)


def test_steady_precession_accurate() -> None:
    # measured over 2 s: tilt within 9.4e-5 rad of 0.2, rate +0.029 %
    check_steady_precession(DartEngine(), "accurate", tilt_tol=1.5e-4, rate_rtol=5e-4)


@pytest.mark.xfail(strict=True, reason=(
    "ODE's cylinder-box contact (the fast preset's detector) does not hold a rolling rim: "
    "the tilt decays from 0.2 to 0.06 rad within 0.8 s and the rate is +99 % over 2 s, at "
    "1 ms, 0.5 ms, 0.1 ms and 0.025 ms alike; FCL at 1 ms holds it (2.4e-4 rad, +0.006 %)"))
def test_steady_precession_fast() -> None:
    check_steady_precession(DartEngine(), "fast", tilt_tol=0.01, rate_rtol=0.01)
