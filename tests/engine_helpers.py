"""Shared pieces of the engine plugin tests (``tests/test_engine_*.py``).

Test blocks, the reference's zero crossings and errors, and the free-rocking
and pulse checks against Housner that several engines pass alike.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from rockbench.analytic import critical_angle, reference, slip_of
from rockbench.analytic.housner import single_block_reference
from rockbench.engines import Engine
from rockbench.evaluation import evaluate_run
from rockbench.geometry import Block, Geometry, Prism, Support, stack
from rockbench.geometry.polygon import rotate
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Scenario, SinePulse, get_scenario
from rockbench.scenarios.excitation import Components
from rockbench.studies.references_3d import (
    PILLAR,
    corner_landing_time,
    corner_release,
    drum_release,
    first_zero,
    precession,
)
from rockbench.studies.tilting import quasi_static, tilting_table
from rockbench.trajectory import Status, Trajectory

B0 = Block(1.0, 0.2, 5.0, mass=1.0)
B2 = Block(0.5, 0.2, 1.0, mass=1.0)
SINGLE2 = Block(0.17, 0.502, 1.0, density=2670.0)
PAPER_STACK = stack((Block(0.20, 0.40, 0.60, density=2670.0, chamfer=0.005),
                     Block(0.15, 0.55, 0.60, density=2670.0, chamfer=0.005)))
#: Exact first impact times of B0 released at 0.5 λ (event-driven Housner).
B0_IMPACTS = np.array([0.7761248546, 2.1263229608, 3.3271341884])


def zero_crossings(t: np.ndarray, th: np.ndarray) -> np.ndarray:
    """Times where θ changes sign (linear interpolation)."""
    s = np.sign(th)
    i = np.nonzero(s[:-1] * s[1:] < 0)[0]
    return t[i] - th[i] * (t[i + 1] - t[i]) / (th[i + 1] - th[i])


def lam(scenario: Scenario) -> float:
    """The scenario's normalising critical angle λ (rad)."""
    return critical_angle(scenario.geometry)


def max_error(scenario: Scenario, theta: np.ndarray) -> float:
    """max |θ − θ_ref| / λ until the reference comes to rest."""
    ref = single_block_reference(scenario)
    rest = (ref.extra or {}).get("rest_time") or scenario.duration
    n = min(theta.size, ref.theta.shape[0])
    upto = ref.t[:n] <= rest
    return float(np.max(np.abs(theta[:n] - ref.theta[:n, 0])[upto])) / lam(scenario)


def check_b2_free_rocking_accurate(engine: Engine) -> Trajectory:
    """B2 from 0.5 λ for 3 s, accurate preset: θ within 5e-3 λ of Housner's and the
    first three impact times within 0.5 %. Returns the trajectory for further checks."""
    sc = Scenario("free-b2-0.5", B2, initial_tilt=0.5, duration=3.0)
    tr = engine.simulate(sc, "accurate")
    assert tr.status == Status.OK
    th = tr.theta[:, 0]
    assert max_error(sc, th) <= 5e-3
    ref_imp = np.asarray(single_block_reference(sc).impacts)[:3]
    np.testing.assert_allclose(zero_crossings(tr.t, th)[:3], ref_imp, rtol=5e-3)
    return tr


def check_b0_impact_times_accurate_and_fast(engine: Engine) -> None:
    """B0 from 0.5 λ: the published impact times within 0.5 % with both presets, θ
    within 5e-3 λ (accurate) and 0.05 λ (fast) of Housner's."""
    sc = Scenario("free-b0", B0, initial_tilt=0.5, duration=3.6)
    for preset, tol in (("accurate", 5e-3), ("fast", 0.05)):
        tr = engine.simulate(sc, preset)
        assert tr.status == Status.OK
        th = tr.theta[:, 0]
        np.testing.assert_allclose(zero_crossings(tr.t, th)[:3], B0_IMPACTS, rtol=5e-3)
        assert max_error(sc, th) <= tol, preset


def check_sine_pulse_peak(engine: Engine, preset: str) -> None:
    """Single #2 under the 3.3 Hz / 8 mm pulse: peak within 2 % of Housner's, and the
    block first tips away from the base acceleration."""
    sc = Scenario("single-pulse-3.3hz-8mm", SINGLE2, excitation=SinePulse(3.3, 0.008),
                  duration=1.0)
    tr = engine.simulate(sc, preset)
    assert tr.status == Status.OK
    ref = single_block_reference(sc)
    peak, peak_ref = np.max(np.abs(tr.theta[:, 0])), np.max(np.abs(ref.theta[:, 0]))
    assert abs(peak / peak_ref - 1.0) <= 0.02
    # a positive base acceleration first tips the block to θ < 0
    assert tr.theta[np.argmax(np.abs(tr.theta[:, 0]) > 1e-3), 0] < 0


def check_base_follows_excitation(probe: Engine, preset: str, abs_tol: float) -> None:
    """Single #2 under a 5 Hz / 4 mm pulse (ends at 0.2 s, run 0.6 s): the base ends
    where the excitation left it. ``probe`` records ``base_end`` at teardown."""
    exc = SinePulse(5.0, 0.004)
    sc = Scenario("pulse", SINGLE2, excitation=exc, duration=0.6)  # pulse ends at 0.2 s
    tr = probe.simulate(sc, preset)
    assert tr.status == Status.OK
    assert probe.base_end == pytest.approx(float(exc.displacement(exc.end_time)), abs=abs_tol)


def check_base_drives_y_and_z(engine: Engine, *, z_tol: float, theta_tol: float = 1e-5,
                              drag_tol: float = 1e-5, planar: bool = True) -> None:
    """Single #2 on a base that moves vertically rides it within ``z_tol`` (m) without
    rocking (|θ| < ``theta_tol``); on a base moving along y (a 3 Hz / 4 mm pulse, at most
    1.4 m/s²: the block sticks on μ = 1) it is carried by friction to the base's end, within
    ``drag_tol`` (m), staying put in x and not rocking. With ``planar``, the engine's
    ``planar`` knob (which would carry the block rigidly along y) makes that unsupported."""
    up = Scenario("up", SINGLE2, excitation=Components(z=SinePulse(4.0, 0.003)), duration=0.5)
    tr = engine.simulate(up, "accurate")
    assert tr.status is Status.OK
    uz = up.motion.z.displacement(tr.t)
    np.testing.assert_allclose(tr.z[:, 0] - tr.z[0, 0], uz, atol=z_tol)
    assert np.max(np.abs(tr.theta)) < theta_tol
    pulse = SinePulse(3.0, 0.004)
    side = Scenario("side", SINGLE2, excitation=Components(y=pulse), duration=0.5)
    if planar:
        locked = engine.simulate(side, {"planar": True})
        assert locked.status is Status.UNSUPPORTED and "planar" in locked.message
    tr = engine.simulate(side, "accurate")
    assert tr.status is Status.OK
    assert tr.y[-1, 0] == pytest.approx(float(pulse.displacement(pulse.end_time)), abs=drag_tol)
    assert np.max(np.abs(tr.theta)) < 10 * theta_tol and np.max(np.abs(tr.x)) < drag_tol


#: Single #2 turned by 90° about z: its depth (0.17 m) is the rocking width of a motion along y.
SINGLE2_Y = Block(SINGLE2.depth, SINGLE2.width, SINGLE2.height, density=2670.0)


def check_rides_a_base_along_y(engine: Engine, *, y_tol: float, still_tol: float = 1e-6,
                               end_tol: float = 1e-6) -> None:
    """Single #2 turned by 90° under 0.8 of its uplift acceleration along y (g · depth /
    height) rides the base: its y within ``y_tol`` of the base's throughout and within
    ``end_tol`` of the base's end position, no rocking either way and no drift along x
    (within ``still_tol``)."""
    f = 3.0
    amp = 0.8 * 9.81 * (SINGLE2_Y.depth / SINGLE2_Y.height) / (2 * math.pi * f) ** 2
    sc = Scenario("side", SINGLE2_Y, excitation=Components(y=SinePulse(f, amp)), duration=1.0)
    tr = engine.simulate(sc, "accurate")
    assert tr.status is Status.OK, tr.message
    uy = sc.motion.y.displacement(tr.t)
    assert np.max(np.abs(tr.y[:, 0] - uy)) < y_tol
    assert tr.y[-1, 0] == pytest.approx(2 * math.pi * amp, abs=end_tol)
    assert np.max(np.abs(tr.roll)) < still_tol and np.max(np.abs(tr.theta)) < still_tol
    assert np.max(np.abs(tr.x)) < still_tol


def check_rocks_about_x_like_housner(engine: Engine, *, shape_tol: float = 0.01,
                                     plane_tol: float = 1e-5) -> None:
    """Single #2 turned by 90° under the 3 Hz / 8 mm pulse along y rocks about x as Housner's
    Single #2 does under it along x: the peak roll within the pulses' 2 %, the roll the
    mirror of θ_ref within ``shape_tol`` λ (the top leans toward −y as it would toward −x),
    the wobble equal to |roll|, and θ and x within ``plane_tol``."""
    pulse = SinePulse(3.0, 0.008)
    sc = Scenario("rock-y", SINGLE2_Y, excitation=Components(y=pulse), duration=1.5)
    ref = single_block_reference(Scenario("rock-x", SINGLE2, excitation=pulse, duration=1.5))
    tr = engine.simulate(sc, "accurate")
    assert tr.status is Status.OK, tr.message
    assert lam(sc) == pytest.approx(math.atan(SINGLE2.depth / SINGLE2.height))
    rx, th = tr.roll[:, 0], ref.theta[:, 0]
    assert np.max(np.abs(rx)) == pytest.approx(np.max(np.abs(th)), rel=0.02)
    np.testing.assert_allclose(tr.wobble[:, 0], np.abs(rx), atol=1e-6)
    i = int(np.argmax(np.abs(th)))
    assert np.sign(rx[i]) == -np.sign(th[i])
    assert np.max(np.abs(rx + th)) < shape_tol * lam(sc)
    assert np.max(np.abs(tr.theta)) < plane_tol and np.max(np.abs(tr.x)) < plane_tol


def check_mirrored_release(engine: Engine, atol: float = 1e-4) -> Trajectory:
    """B2 released from ±0.5 λ (0.4 s, ``fast``): θ > 0 pivots on the +x edge, and the −tilt
    run mirrors the +tilt run within ``atol`` (rad and m). Returns the +tilt run."""
    pos = engine.simulate(Scenario("free", B2, initial_tilt=0.5, duration=0.4), "fast")
    neg = engine.simulate(Scenario("free", B2, initial_tilt=-0.5, duration=0.4), "fast")
    assert pos.theta[0, 0] > 0 and pos.x[0, 0] > 0
    np.testing.assert_allclose(neg.theta, -pos.theta, atol=atol)
    np.testing.assert_allclose(neg.x, -pos.x, atol=atol)
    return pos


def check_pulse_rocks_without_overturning(engine: Engine, rel: float = 0.01) -> None:
    """Single #2 under the 3 Hz / 8 mm pulse rocks to 0.3–1 λ without overturning, its peak
    within ``rel`` of Housner's (the ``accurate`` preset)."""
    sc = get_scenario("single-pulse-3.0hz-8mm")
    ref = reference(sc)
    tr = engine.simulate(sc, "accurate")
    assert tr.status is ref.status is Status.OK
    peak, peak_ref = np.max(np.abs(tr.theta)), np.max(np.abs(ref.theta))
    assert 0.3 * lam(sc) < peak < lam(sc)
    assert peak == pytest.approx(peak_ref, rel=rel)


def check_paper_stack_under_pulse_runs(engine: Engine) -> None:
    """The paper's two-block stack under a 3.3 Hz / 4 mm pulse (fast preset) runs,
    stays finite and travels with the base."""
    sc = Scenario("paper-stack-pulse", PAPER_STACK, excitation=SinePulse(3.3, 0.004),
                  duration=1.0)
    tr = engine.simulate(sc, "fast")
    assert tr.status == Status.OK
    assert np.all(np.isfinite(tr.theta))
    # both blocks travel with the base (displacement 2πA after the pulse)
    np.testing.assert_allclose(tr.x[-1] - tr.x[0], 2 * math.pi * 0.004, atol=5e-3)


def check_assembly_stays_at_rest(engine: Engine, name: str, *, duration: float, turn: float,
                                 drift: float, settings: Any = None) -> Trajectory:
    """Catalog assembly ``name`` left alone for ``duration`` s: every block turns by less
    than ``turn`` λ and its centroid drifts by less than ``drift`` m from its first pose."""
    sc = get_scenario(name).replace(duration=duration)
    tr = engine.simulate(sc, settings)
    assert tr.status is Status.OK, f"{name}: {tr.message}"
    turned = float(np.max(np.abs(tr.theta - tr.theta[0]))) / lam(sc)
    drifted = float(np.max(np.hypot(tr.x - tr.x[0], tr.z - tr.z[0])))
    assert turned < turn and drifted < drift, \
        f"{name}: turn {turned:.2e} λ, drift {drifted:.2e} m"
    return tr


def check_stack_follows_two_block(engine: Engine, case: str, tol: float, *, slip: float,
                                  gap: float) -> None:
    """The paper's stack at the ``accurate`` preset against the two-block solution: both
    blocks' peaks within ``tol`` (issue 15: 2 % on pulses, 5 % on the well-posed
    sinusoids), the interface stuck and closed (largest slip and gap below ``slip`` and
    ``gap``, m)."""
    sc = get_scenario(case)
    tr = engine.simulate(sc, "accurate")
    assert tr.status is Status.OK, tr.message
    m = evaluate_run(sc, tr, reference(sc))
    assert max(abs(e) for e in m.peak_errors) <= tol, m.peak_errors
    assert m.interface_slip < slip and m.interface_gap < gap, (m.interface_slip,
                                                               m.interface_gap)


def inclined_scene(prism: bool, excitation: SinePulse | None = None) -> Scenario:
    """A block at 0.1 rad on a support whose top face slopes at that angle: placed as a
    Block turned by 0.1 rad, or as a Prism whose vertices are the turned rectangle (pose
    angle 0, a non-zero product of inertia: an engine must place its body frame turned)."""
    th, h = 0.1, 0.6
    top0, top1 = 0.3, 0.3 - 0.8 * math.tan(th)
    sup = Support(((-0.4, 0.0), (0.4, 0.0), (0.4, top1), (-0.4, top0)))
    c = np.array([0.0, 0.5 * (top0 + top1)]) + 0.5 * h * np.array([math.sin(th), math.cos(th)])
    blk = Block(0.3, 0.3, h, density=2000.0)
    if prism:
        verts = c + rotate(blk.profile(), th)
        asm = Geometry((Prism(tuple(map(tuple, verts.tolist())), 0.3, density=2000.0),),
                       ((0.0, 0.0, 0.0),), (sup,))
    else:
        asm = Geometry((blk,), ((float(c[0]), float(c[1]), th),), (sup,))
    kw = {} if excitation is None else {"excitation": excitation}
    return Scenario(name="inclined", geometry=asm, duration=1.5, output_rate=200.0, **kw)


#: The assemblies an engine's tilting-table test holds to the limit analysis.
TILT_CASES = ("parapet-offset0.25", "column-5drums")


def check_tilting_table(engine: str, settings: dict | None = None, *, overshoot: float = 0.04,
                        slower_first: bool = True, extrapolated: float | None = None) -> None:
    """Tilting table at 0.05 /s and 0.025 /s on :data:`TILT_CASES` against the LP.

    The onset at the slower rate lies within −0.5 % … ``overshoot`` of the LP
    factor, halving the rate moves it by < 3.5 % (quasi-static), the slower run
    is the earlier one (``slower_first``) or the rate-0 extrapolation within
    ``extrapolated``, and the blocks that moved are the LP mechanism's, turning
    its way.
    """
    cmps = tilting_table([get_scenario(n) for n in TILT_CASES], engine, rate=0.05,
                         settings=settings or {}, execution=ExecutionOptions(isolate=False))
    for name, c in zip(TILT_CASES, cmps, strict=True):
        what = (f"{name}: onset α {c.run.onset_factor:.4f} / {c.half.onset_factor:.4f}, "
                f"LP {c.limit.load_factor:.4f}")
        assert c.half.status.completed, f"{what}: {c.half.message}"
        assert -0.005 <= c.error <= overshoot, what
        assert quasi_static(c, 0.035), what
        if slower_first:
            assert c.half.onset_factor <= c.run.onset_factor, what
        if extrapolated is not None:
            assert abs(c.extrapolated_error) <= extrapolated, what
        assert c.mechanism_matches, f"{what}: moved {c.half.moved}"
        signs = tuple(c.limit.mechanism[i].rotation_sign for i in c.half.moved)
        assert c.half.rotation_sign == signs, what


def check_arch_rides_its_supports(engine: Engine, *, rtol: float, turn: float) -> None:
    """An arch stands on its two supports only: under a 2 Hz pulse at half its collapse
    acceleration it rides with them, ending displaced by the base's 2πA (within ``rtol``)
    with its voussoirs turned by less than ``turn`` λ."""
    sc = get_scenario("arch-9v-t0.20")
    f = 2.0
    amp = 0.5 * 9.81 * math.tan(lam(sc)) / (2 * math.pi * f) ** 2
    tr = engine.simulate(sc.replace(excitation=SinePulse(f, amp), duration=1.0))
    assert tr.status is Status.OK, tr.message
    np.testing.assert_allclose(tr.x[-1] - tr.x[0], 2 * math.pi * amp, rtol=rtol)
    assert np.max(np.abs(tr.theta - tr.theta[0])) < turn * lam(sc)


def check_slides_like_coulomb(scenario: Scenario, tr: Trajectory, ref: Trajectory, *,
                              slip_tol: float = 0.01, rock_tol: float = 0.01) -> None:
    """A run of a sliding-suite case against the exact Coulomb slider ``ref``.

    Every block's slip (centroid x minus upright x minus u_g) within ``slip_tol`` of the
    peak exact slip, no rocking beyond ``rock_tol`` λ, and a stack sliding as one body:
    its top block's slip on the lower one within ``slip_tol`` of the peak exact slip.
    """
    assert tr.status is Status.OK, tr.message
    assert tr.t.size == ref.t.size
    peak = np.max(np.abs(slip_of(ref, scenario)))
    for block in range(scenario.n_blocks):
        error = np.max(np.abs(slip_of(tr, scenario, block) - slip_of(ref, scenario, block))) / peak
        assert error <= slip_tol, f"block {block + 1}: slip error {error:.2%}"
    rocking = np.max(np.abs(tr.theta)) / lam(scenario)
    assert rocking <= rock_tol, f"rocks to {rocking:.3g} λ"
    if scenario.n_blocks == 2:
        relative = np.max(np.abs(slip_of(tr, scenario, 1) - slip_of(tr, scenario, 0))) / peak
        assert relative <= slip_tol, f"interface slip {relative:.2%} of the peak slip"



def check_cylinder_rocks_like_housner(engine: Engine, settings: Any = "accurate", *,
                                      rel: float = 0.01, plane_tol: float = 1e-4) -> Trajectory:
    """The drum released in the x–z plane at 0.5 λ rocks on its rim as Housner's block of
    half-width R with the cylinder's inertia: the first impact within ``rel`` of the
    reference's, θ up to it within 1 % λ, and no turn out of the plane (roll and twist
    below ``plane_tol`` rad) until then. Returns the trajectory."""
    sc = drum_release()
    ref = reference(sc)
    tr = engine.simulate(sc, settings)
    assert tr.status is Status.OK, tr.message
    t_ref = first_zero(ref.t, ref.theta[:, 0])
    assert first_zero(tr.t, tr.theta[:, 0]) == pytest.approx(t_ref, rel=rel)
    before = tr.t < 0.95 * t_ref
    assert np.max(np.abs(tr.theta[before, 0] - ref.theta[before, 0])) < 0.01 * lam(sc)
    assert np.max(np.abs(tr.roll[before])) < plane_tol
    assert np.max(np.abs(tr.twist[before])) < plane_tol
    return tr


def check_drum_falls_alike_toward_any_azimuth(engine: Engine, *, tilt_tol: float,
                                              azimuth_tol: float) -> None:
    """Axisymmetry, which a 2R × 2R box would not have (it would pivot on a corner): the drum
    released toward 45° or 1 rad tilts as the in-plane release within ``tilt_tol`` and its
    lean keeps its azimuth within ``azimuth_tol`` (rad) until the impact (``accurate``)."""
    plane = engine.simulate(drum_release(), "accurate")
    before = plane.t < 0.95 * first_zero(plane.t, plane.theta[:, 0])
    for az in (0.25 * math.pi, 1.0):
        tr = engine.simulate(drum_release().replace(initial_azimuth=az), "accurate")
        assert tr.status is Status.OK
        assert np.max(np.abs(tr.tilt[before, 0] - plane.tilt[before, 0])) < tilt_tol
        assert np.max(np.abs(np.unwrap(tr.azimuth[before, 0]) - az)) < azimuth_tol


def check_corner_release(engine: Engine, settings: Any = "accurate", *, rel: float = 0.01,
                         diagonal_tol: float = 1e-3) -> Trajectory:
    """The square pillar released from rest on its corner at 0.5 λ of the diagonal (azimuth
    45°) rocks in the diagonal plane until it lands: the landing (θ's first zero) within
    ``rel`` of :func:`corner_landing_time`, and the roll the mirror of θ (the top leans
    toward +x and +y alike) within ``diagonal_tol`` rad. Returns the trajectory."""
    sc = corner_release()
    tr = engine.simulate(sc, settings)
    assert tr.status is Status.OK, tr.message
    assert tr.tilt[0, 0] == pytest.approx(sc.theta0, rel=1e-6)
    assert tr.azimuth[0, 0] == pytest.approx(0.25 * math.pi, abs=1e-6)
    t_land = corner_landing_time(PILLAR, sc.theta0)
    assert first_zero(tr.t, tr.theta[:, 0]) == pytest.approx(t_land, rel=rel)
    before = tr.t < 0.95 * t_land
    assert np.max(np.abs(tr.theta[before, 0] + tr.roll[before, 0])) < diagonal_tol
    return tr


def check_steady_precession(engine: Engine, settings: Any = "accurate", *, tilt_tol: float,
                            rate_rtol: float, duration: float = 2.0) -> Trajectory:
    """The slender cylinder started in steady precession holds its tilt within ``tilt_tol``
    rad of 0.2 and precesses at the closed form's rate Ω within ``rate_rtol`` (the mean
    rate of its lean's azimuth). Returns the trajectory."""
    sc, sp = precession(duration)
    tr = engine.simulate(sc, settings)
    assert tr.status is Status.OK, tr.message
    assert tr.tilt[0, 0] == pytest.approx(sp.theta, abs=1e-6)
    assert np.max(np.abs(tr.tilt[:, 0] - sp.theta)) < tilt_tol
    az = np.unwrap(tr.azimuth[:, 0])
    assert (az[-1] - az[0]) / (tr.t[-1] - tr.t[0]) == pytest.approx(sp.psi_dot, rel=rate_rtol)
    return tr
