"""Physics tests of the LMGC90 engine plugin (compas_lmgc90) against Housner and closed forms."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest
from engine_helpers import (
    B0_IMPACTS,
    SINGLE2,
    check_arch_rides_its_supports,
    check_assembly_stays_at_rest,
    check_base_drives_y_and_z,
    check_base_follows_excitation,
    check_corner_release,
    check_cylinder_rocks_like_housner,
    check_rides_a_base_along_y,
    check_rocks_about_x_like_housner,
    check_sine_pulse_peak,
    check_stack_follows_two_block,
    check_steady_precession,
    check_tilting_table,
    inclined_scene,
    lam,
)

from rockbench.analytic.housner import single_block_reference
from rockbench.engines.drive import BaseDrive
from rockbench.engines.lmgc90_engine import (
    Lmgc90Engine,
    Lmgc90Settings,
    _cylinder,
    _polyhedron_volume,
    _quaternions,
    _velocity_table,
)
from rockbench.engines.settings import SettingsError
from rockbench.errors import EngineUnavailable
from rockbench.geometry import Cylinder
from rockbench.metrics import impact_times
from rockbench.scenarios import Block, Components, Contact, Scenario, SinePulse, get_scenario
from rockbench.trajectory import Status, Trajectory


def test_unavailable_without_the_binding(monkeypatch: pytest.MonkeyPatch) -> None:
    # without compas_lmgc90 the engine is unavailable with the install hint
    monkeypatch.setitem(sys.modules, "compas_lmgc90.solver", None)
    with pytest.raises(EngineUnavailable, match=r"rockbench\[lmgc90\]"):
        Lmgc90Engine.check_available()


def test_presets_and_knobs() -> None:
    assert Lmgc90Engine.requires == ("compas_lmgc90",)
    assert Lmgc90Engine.extra == "lmgc90"
    assert Lmgc90Engine.settings("accurate") == Lmgc90Settings()
    assert Lmgc90Engine.settings("fast").timestep == pytest.approx(1e-3)
    for bad in ({"timestep": 0.0}, {"theta": 0.4}, {"theta": 1.5}, {"alert": -1.0},
                {"f2f_tol": 0.0}, {"f2f_tol": 1.5}, {"cylinder_facets": 7},
                {"cylinder_facets": 6}, {"law": "IQS_CLB"}):
        with pytest.raises(SettingsError):
            Lmgc90Engine.settings(**bad)


def _unavailable() -> str | None:
    """Why the engine cannot run here (the registry's reason), or None."""
    try:
        Lmgc90Engine.check_available()
    except EngineUnavailable as exc:
        return str(exc)
    return None


_WHY = _unavailable()
needs_lmgc90 = pytest.mark.skipif(_WHY is not None, reason=_WHY or "")


@pytest.fixture(scope="module")
def engine() -> Lmgc90Engine:
    return Lmgc90Engine()


@pytest.fixture(scope="module")
def b0_accurate(engine: Lmgc90Engine) -> Trajectory:
    """B0 released at 0.5 λ, 3.6 s (three impacts) at the accurate preset."""
    return engine.simulate(get_scenario("free-b0").replace(duration=3.6), "accurate")


@needs_lmgc90
def test_free_rocking_b0_accurate(b0_accurate: Trajectory) -> None:
    tr = b0_accurate
    sc = get_scenario("free-b0").replace(duration=3.6)
    ref = single_block_reference(sc)
    assert tr.status is Status.OK
    lam_ = lam(sc)
    # θ starts at the requested tilt, pivoting on the +x corner (centroid toward +x)
    assert tr.theta[0, 0] == pytest.approx(sc.theta0, rel=1e-9) and tr.x[0, 0] > 0
    # the first swing is exact (a rigid block on a rigid pivot, no contact stiffness) ...
    imp = impact_times(tr)
    assert imp[0] == pytest.approx(B0_IMPACTS[0], rel=2e-4)
    # ... and LMGC90's inelastic impact keeps a little more than Housner's η: measured
    # (Δt 0.1 and 0.2 ms alike) the 2nd and 3rd impacts 0.63 % and 0.39 % late,
    # max |θ − θ_ref| 0.018 λ up to the 3rd impact
    np.testing.assert_allclose(imp[:3], B0_IMPACTS, rtol=1e-2)
    assert np.all(imp[1:3] > B0_IMPACTS[1:3])
    err = np.max(np.abs(tr.theta[:, 0] - ref.theta[:, 0])) / lam_
    assert err <= 0.025
    # no energy gain: never higher than the release, the block stays in its plane
    assert np.max(np.abs(tr.theta[:, 0])) <= sc.theta0 * (1 + 1e-6)
    assert np.max(tr.wobble) < 1e-3


@needs_lmgc90
def test_small_amplitude_rocking_is_housners(engine: Lmgc90Engine) -> None:
    # from 0.2 λ LMGC90's impacts are Housner's (measured: B1–B3 within 0.0022 λ over 20 s):
    # B2 over 1 s, while it rocks down below 0.01 λ (at 0.78 s), the first five impacts
    sc = get_scenario("free-b2-0.2").replace(duration=1.0)
    ref = single_block_reference(sc)
    tr = engine.simulate(sc, "accurate")
    assert tr.status is Status.OK
    assert np.max(np.abs(tr.theta[:, 0] - ref.theta[:, 0])) / lam(sc) <= 5e-3
    np.testing.assert_allclose(impact_times(tr)[:5], impact_times(ref)[:5], rtol=5e-3)


@needs_lmgc90
@pytest.mark.xfail(strict=True, reason="measured: LMGC90's impact dissipates less than "
                   "Housner's eta on B0 (2nd impact 0.63 % late at dt 0.1 and 0.2 ms alike)")
def test_b0_impact_times_within_half_percent(b0_accurate: Trajectory) -> None:
    np.testing.assert_allclose(impact_times(b0_accurate)[:3], B0_IMPACTS, rtol=5e-3)


@needs_lmgc90
def test_binding_face_to_face_tolerance_loses_tilted_contact(engine: Lmgc90Engine) -> None:
    # the binding's own STO face-to-face tolerance (1e-3 on 1 − cos of the faces' angle,
    # 2.56°) finds no contact under a block tilted 0.5 λ = 5.65°: it falls through the
    # ground in free fall (2.5 m in 0.71 s); the plugin's default tolerance holds it
    sc = get_scenario("free-b0").replace(duration=0.8)
    lost = engine.simulate(sc, {"preset": "fast", "f2f_tol": 1e-3})
    z0 = lost.z[0, 0]
    np.testing.assert_allclose(z0 - lost.z[:, 0], 0.5 * sc.g * lost.t**2, rtol=1e-2, atol=1e-6)
    np.testing.assert_allclose(lost.theta[:, 0], sc.theta0, rtol=1e-9)
    kept = engine.simulate(sc, "fast")
    assert kept.status is Status.OK
    assert float(np.min(kept.z[:, 0])) > 0.99 * sc.blocks[0].h


@needs_lmgc90
def test_sine_pulse_peak_accurate(engine: Lmgc90Engine) -> None:
    check_sine_pulse_peak(engine, "accurate")


@needs_lmgc90
def test_base_follows_excitation(engine: Lmgc90Engine) -> None:
    # the base's velocity table is the exact u̇_g at every step: the trapezoidal
    # positions end where the excitation left the base (measured 2e-10 m)
    check_base_follows_excitation(engine, "fast", abs_tol=1e-6)
    # and friction drags a squat block below the uplift threshold along with it
    sc = Scenario("ride", Block(1.0, 0.5, 0.5, mass=10.0), excitation=SinePulse(2.0, 0.002),
                  duration=1.0)
    tr = engine.simulate(sc, "fast")
    assert tr.status is Status.OK
    assert np.max(np.abs(tr.theta)) < 1e-6
    np.testing.assert_allclose(tr.x[:, 0], sc.excitation.displacement(tr.t), atol=1e-5)


@needs_lmgc90
def test_runs_in_one_process_are_identical(engine: Lmgc90Engine) -> None:
    # LMGC90's Fortran state is reset by every new Solver (compas_lmgc90 >= 0.1.11): a run
    # after another scenario in the same process repeats the first to the bit
    sc = Scenario("pulse", SINGLE2, excitation=SinePulse(3.3, 0.008), duration=0.8)
    first = engine.simulate(sc, "fast")
    engine.simulate(get_scenario("free-b0").replace(duration=0.3), "fast")
    again = Lmgc90Engine().simulate(sc, "fast")
    assert first.status is Status.OK
    np.testing.assert_array_equal(again.theta, first.theta)


@needs_lmgc90
@pytest.mark.parametrize(("change", "why"), [
    ({"g": 9.0}, "gravity"),
    ({"contact": Contact(friction=1.0, restitution=0.5)}, "restitution"),
])
def test_unsupported(engine: Lmgc90Engine, change: dict, why: str) -> None:
    sc = get_scenario("free-b0").replace(duration=0.1, **change)
    tr = engine.simulate(sc, "fast")
    assert tr.status is Status.UNSUPPORTED and why in tr.message


def test_velocity_table_is_the_exact_base_velocity() -> None:
    exc = SinePulse(5.0, 0.004)  # ends at 0.2 s
    sc = Scenario("pulse", SINGLE2, excitation=exc, duration=0.5)
    table = _velocity_table(BaseDrive(sc.motion, sc.duration), sc.duration, 1e-3)
    t, v = table
    assert np.all(np.diff(t) > 0) and t[-1] > sc.duration
    during = t <= exc.end_time
    np.testing.assert_allclose(v[during], exc.velocity(t[during]), rtol=0, atol=1e-15)
    assert np.all(v[~during] == 0.0)
    # the trapezoidal rule of the table moves the base by the pulse's displacement
    u_end = float(np.sum(0.5 * (v[1:] + v[:-1]) * np.diff(t)))
    assert u_end == pytest.approx(2 * math.pi * 0.004, rel=1e-5)


def test_quaternion_of_rotation_matrices() -> None:
    from scipy.spatial.transform import Rotation

    rots = Rotation.random(200, random_state=1)
    # every branch of Shepperd's method: near-identity, and half turns about each axis
    rots = Rotation.concatenate([rots, Rotation.from_rotvec(np.diag([3.1, 3.1, 3.1])),
                                 Rotation.from_rotvec([[0.0, 0.3, 0.0]])])
    q = _quaternions(rots.as_matrix())
    ref = np.roll(rots.as_quat(), 1, axis=-1)  # SciPy's (x, y, z, w) as (w, x, y, z)
    sign = np.sign(np.sum(q * ref, axis=-1, keepdims=True))
    np.testing.assert_allclose(sign * q, ref, atol=1e-12)
    # θ about +y has the quaternion (cos θ/2, 0, sin θ/2, 0) the base class reads back
    c, s = math.cos(0.3), math.sin(0.3)
    q = _quaternions(np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]))
    np.testing.assert_allclose(q, [math.cos(0.15), 0.0, math.sin(0.15), 0.0], atol=1e-15)


# ---------------------------------------------------------------- assemblies
@needs_lmgc90
@pytest.mark.parametrize("name", ["column-5drums", "parapet-offset0.25", "wall-6x3",
                                  "arch-9v-t0.20"])
def test_assemblies_stay_at_rest(engine: Lmgc90Engine, name: str) -> None:
    # non-smooth contact on STO's face-to-face points, no contact compliance: over 0.5 s
    # (accurate) the blocks turn by 1.5e-9 to 1.7e-8 λ and drift by 1e-10 to 7.3e-9 m
    # (measured: column 1.66e-8 λ / 7.3e-9 m, parapet 1.45e-9 / 9.5e-11, wall 5.5e-9 /
    # 3.4e-9, arch 6.0e-9 / 1.6e-9)
    check_assembly_stays_at_rest(engine, name, duration=0.5, turn=1e-6, drift=1e-6)


@needs_lmgc90
def test_prism_in_its_principal_frame_reads_back_its_own_pose(engine: Lmgc90Engine) -> None:
    # LMGC90 reports the principal frame; the pose read back is the frame's change applied
    # to the block's orientation, so a prism (product of inertia ≠ 0) reads its own pose
    block, prism = engine.simulate(inclined_scene(False)), engine.simulate(inclined_scene(True))
    assert block.status is prism.status is Status.OK
    # at rest on the slope (measured: 9.2e-12 rad from the pose, x and z identical)
    assert np.max(np.abs(block.theta - 0.1)) < 1e-9
    assert np.max(np.abs(prism.theta)) < 1e-9
    assert np.max(np.abs(prism.x - block.x)) < 1e-9 and np.max(np.abs(prism.z - block.z)) < 1e-9
    # rocked by a pulse: the same polyhedron either way (peaks 0.084156 rad, 1.4e-10 apart)
    pulse = SinePulse(2.0, 0.04)
    rb = engine.simulate(inclined_scene(False, pulse))
    rp = engine.simulate(inclined_scene(True, pulse))
    assert np.max(np.abs(rb.theta - 0.1)) > 0.05
    np.testing.assert_allclose(rp.theta, rb.theta - 0.1, atol=1e-8)


@needs_lmgc90
def test_supports_move_with_the_base(engine: Lmgc90Engine) -> None:
    # measured: within 3.7e-7 of 2πA, voussoirs turned by 1.6e-6 λ
    check_arch_rides_its_supports(engine, rtol=1e-5, turn=1e-4)


@needs_lmgc90
def test_interface_friction_in_an_assembly_is_unsupported(engine: Lmgc90Engine) -> None:
    # one contact law for every pair: blocks on blocks cannot have their own friction
    sc = get_scenario("parapet-offset0.25")
    tr = engine.simulate(sc.replace(contact=Contact(friction=0.8, interface_friction=0.5),
                                    duration=0.1))
    assert tr.status is Status.UNSUPPORTED and "interface friction" in tr.message


# Tilting table at 0.05 /s and 0.025 /s (accurate preset), measured: parapet onsets
# 0.1311 / 0.1289 against the LP's 0.125 (+3.1 %), 5-drum column 0.2487 / 0.2456 against
# 0.24 (+2.3 %), the LP mechanism (the parapet alone; the column as one body). The tilt
# is the base acceleration ramp of TiltTable, LMGC90's driven base velocity: gravity
# stays the binding's (0, 0, −9.81).
@needs_lmgc90
def test_tilting_table_onset_matches_the_collapse_factor() -> None:
    check_tilting_table("lmgc90", overshoot=0.045)


# The stack-convergence measurements (docs/engines/stack-convergence.md; accurate,
# Δt 0.1 ms): the 5 Hz / 4 mm pulse's peaks
# −0.5 / −0.4 %, interface slip < 1e-6 m (non-smooth contact); the sinusoid moves away as
# the step shrinks (−2 / −21 / −31 % at 0.2 / 0.1 / 0.05 ms): LMGC90's impacts keep more
# energy than Housner's η
@needs_lmgc90
@pytest.mark.parametrize("case, tol", [
    ("stack-pulse-5.0hz-4mm", 0.02),
    pytest.param("stack-sine-5.0hz-4mm", 0.05, marks=pytest.mark.xfail(
        strict=True, reason="bottom block's peak −21 % of the two-block solution at 0.1 ms, "
                            "−31 % at 0.05 ms: its impacts keep more energy than Housner's "
                            "eta (docs/engines/stack-convergence.md)")),
])
def test_stack_follows_the_two_block_solution(engine: Lmgc90Engine, case: str,
                                              tol: float) -> None:
    check_stack_follows_two_block(engine, case, tol, slip=1e-5, gap=2e-5)


# ---------------------------------------------------------------- base motion along y and z
@needs_lmgc90
def test_base_drives_y_and_z(engine: Lmgc90Engine) -> None:
    # each moving axis is its own velocity table of the driven base (no planar knob):
    # measured, rides a vertical pulse within 1.6e-9 m (θ 5.3e-12 rad); dragged along y to
    # the base's end within 1.2e-10 m, θ 7.6e-10 rad, x 3.8e-10 m
    check_base_drives_y_and_z(engine, z_tol=3e-9, theta_tol=1.5e-10, drag_tol=8e-10,
                              planar=False)


@needs_lmgc90
def test_rides_a_base_along_y(engine: Lmgc90Engine) -> None:
    # measured: y within 2.3e-8 m of the base's, roll 4.5e-8 rad, θ 2.1e-10 rad, x 1.8e-10 m
    check_rides_a_base_along_y(engine, y_tol=5e-8, still_tol=1e-7)


@needs_lmgc90
def test_rocks_about_x_like_housner(engine: Lmgc90Engine) -> None:
    # measured: peak roll −0.45 % of Housner's, roll + θ_ref within 0.0053 λ, θ and x 2.6e-7
    check_rocks_about_x_like_housner(engine, shape_tol=0.01, plane_tol=5e-7)


def test_velocity_table_along_each_axis() -> None:
    pulse = SinePulse(5.0, 0.004)
    sc = Scenario("yz", SINGLE2, excitation=Components(y=pulse, z=SinePulse(4.0, 0.002)),
                  duration=0.5)
    drive = BaseDrive(sc.motion, sc.duration)
    for axis, exc in ((1, pulse), (2, SinePulse(4.0, 0.002))):
        t, v = _velocity_table(drive, sc.duration, 1e-3, axis=axis)
        during = t <= exc.end_time
        np.testing.assert_allclose(v[during], exc.velocity(t[during]), rtol=0, atol=1e-15)
    t, v = _velocity_table(drive, sc.duration, 1e-3)  # x does not move
    assert np.all(v == 0.0)


# ---------------------------------------------------------------- cylinders and 3D starts
def test_faceted_cylinder() -> None:
    # the prism on a regular n-gon inscribed in the circle: its volume, outward faces
    for n in (8, 64):
        v, faces = _cylinder(0.3, 0.75, n)
        area = 0.5 * n * 0.3**2 * math.sin(2 * math.pi / n)
        assert _polyhedron_volume(v, faces) == pytest.approx(area * 1.5, rel=1e-12)
        assert np.allclose(np.hypot(v[:, 0], v[:, 1]), 0.3)
        assert v[0, 0] == pytest.approx(0.3) and v[0, 1] == 0.0  # a vertex at azimuth 0


@needs_lmgc90
def test_cylinder_is_built_as_a_cylinder(engine: Lmgc90Engine) -> None:
    # the drum stands at rest on its end face: z = H/2 and no turn (not a 2R × 2R box,
    # whose centre would be at R)
    cyl = Cylinder(0.15, 1.0, density=2000.0)
    tr = engine.simulate(Scenario("rest", cyl, duration=0.2), "fast")
    assert tr.status is Status.OK
    np.testing.assert_allclose(tr.z[:, 0], cyl.h, atol=1e-8)
    assert np.max(np.abs(tr.tilt)) < 1e-9
    assert np.max(np.abs(tr.x)) < 1e-9 and np.max(np.abs(tr.y)) < 1e-9


# Measured (docs/engines/lmgc90.md, "Cylinders and 3D starts"): the drum's rim is a 64-gon
# with a vertex at azimuth 0, on which the in-plane release pivots.
@needs_lmgc90
@pytest.mark.parametrize(("preset", "rel", "plane_tol"), [
    ("fast", 8e-3, 6e-6),  # measured: first impact +0.41 %, roll 1.9e-7, twist 2.7e-6 rad
    pytest.param("accurate", 8e-3, 2e-5, marks=pytest.mark.slow),  # +0.40 %, 8.8e-7, 9.7e-6
])
def test_cylinder_rocks_like_housner(engine: Lmgc90Engine, preset: str, rel: float,
                                     plane_tol: float) -> None:
    # θ within 0.0041 λ of the reference up to the impact at both presets
    check_cylinder_rocks_like_housner(engine, preset, rel=rel, plane_tol=plane_tol)


@needs_lmgc90
@pytest.mark.parametrize(("preset", "rel", "diagonal_tol"), [
    ("fast", 3e-4, 1e-6),       # measured: landing +0.016 %, |θ + roll| 5.2e-7 rad
    ("accurate", 8e-5, 8e-8),   # measured: landing +0.0036 %, |θ + roll| 3.7e-8 rad
])
def test_corner_release(engine: Lmgc90Engine, preset: str, rel: float,
                        diagonal_tol: float) -> None:
    check_corner_release(engine, preset, rel=rel, diagonal_tol=diagonal_tol)


@needs_lmgc90
def test_steady_precession_fast(engine: Lmgc90Engine) -> None:
    # measured over 2 s at fast: tilt within 0.0196 rad of 0.2, rate −2.0 % of Ω
    check_steady_precession(engine, "fast", tilt_tol=0.03, rate_rtol=0.035)
