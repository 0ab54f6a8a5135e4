"""Physics tests of the pymunk engine plugin against the Housner reference."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest

pymunk = pytest.importorskip("pymunk")

from engine_helpers import B0, B2, PAPER_STACK, SINGLE2, lam, zero_crossings  # noqa: E402

from rockbench.analytic.housner import single_block_reference  # noqa: E402
from rockbench.analytic.sliding import solve_sliding  # noqa: E402
from rockbench.engines.pymunk_engine import PymunkEngine, PymunkSettings  # noqa: E402
from rockbench.engines.settings import SettingsError  # noqa: E402
from rockbench.geometry import Geometry, Support, stack  # noqa: E402
from rockbench.scenarios import Block, Contact, Scenario, SinePulse  # noqa: E402
from rockbench.scenarios.excitation import Components  # noqa: E402
from rockbench.trajectory import Status  # noqa: E402


# ---------------------------------------------------------------- reference
def reference_theta(sc: Scenario) -> np.ndarray:
    """θ of the project's Housner reference at the scenario's output times."""
    tr = single_block_reference(sc)
    return np.interp(sc.output_times(), tr.t, tr.theta[:, 0])


def free(block: Block, tilt: float, duration: float, **kw) -> Scenario:
    return Scenario("free", block, Contact(1.0, 0.0), initial_tilt=tilt, duration=duration,
                    output_rate=1000.0, **kw)


def test_reference_matches_published_b0_numbers() -> None:
    sc = free(B0, 0.5, 3.5)
    th = reference_theta(sc)
    zc = zero_crossings(sc.output_times(), th)
    np.testing.assert_allclose(zc[:3], [0.7761248546, 2.1263229608, 3.3271341884], rtol=1e-5)


# ---------------------------------------------------------------- free rocking
def test_b2_free_rocking_accurate() -> None:
    sc = free(B2, 0.5, 6.0)
    tr = PymunkEngine().simulate(sc, "accurate")
    assert tr.status is Status.OK
    ref = reference_theta(sc)
    err = np.max(np.abs(tr.theta[:, 0] - ref)) / lam(sc)
    assert err <= 5e-3, err
    zc, zr = zero_crossings(tr.t, tr.theta[:, 0]), zero_crossings(tr.t, ref)
    np.testing.assert_allclose(zc[:3], zr[:3], rtol=5e-3)
    # 2D engine: no wobble, y = 0 implied, θ starts at the requested tilt
    assert np.all(tr.wobble == 0.0)
    assert tr.theta[0, 0] == pytest.approx(sc.theta0, rel=1e-12)


def test_b0_free_rocking_fast_preset() -> None:
    sc = free(B0, 0.5, 6.0)
    tr = PymunkEngine().simulate(sc, "fast")
    assert tr.status is Status.OK
    err = np.max(np.abs(tr.theta[:, 0] - reference_theta(sc))) / lam(sc)
    assert err <= 0.05, err
    assert tr.settings["effective_timestep"] == pytest.approx(1e-3)


def test_sign_convention_and_mirror_symmetry() -> None:
    """θ > 0 pivots on the +x edge (centroid moves toward +x); −tilt mirrors it."""
    pos = PymunkEngine().simulate(free(B2, 0.5, 0.4), "fast")
    neg = PymunkEngine().simulate(free(B2, -0.5, 0.4), "fast")
    assert pos.theta[0, 0] > 0 and pos.x[0, 0] > 0
    np.testing.assert_allclose(neg.theta, -pos.theta, atol=1e-9)
    np.testing.assert_allclose(neg.x, -pos.x, atol=1e-9)
    np.testing.assert_allclose(neg.z, pos.z, atol=1e-9)


# ---------------------------------------------------------------- forced rocking
def test_single_pulse_peak_within_2_percent() -> None:
    sc = Scenario("pulse", SINGLE2, Contact(1.0, 0.0), SinePulse(5.0, 0.006), duration=1.2,
                  output_rate=1000.0)
    tr = PymunkEngine().simulate(sc, "accurate")
    assert tr.status is Status.OK
    ref = reference_theta(sc)
    peak, peak_ref = np.max(np.abs(tr.theta[:, 0])), np.max(np.abs(ref))
    assert peak == pytest.approx(peak_ref, rel=0.02)
    # a positive base acceleration tips the block to θ < 0 first
    first = tr.theta[np.nonzero(np.abs(tr.theta[:, 0]) > 1e-3)[0][0], 0]
    assert first < 0
    # the base really moves and carries the block along (it ends displaced by 2πA)
    assert np.max(tr.x[:, 0]) > 0.8 * 2 * math.pi * 0.006


def test_frictionless_base_slides_under_block() -> None:
    """Friction comes from the scenario: with μ = 0 the moving base cannot drag the block."""
    sc = Scenario("slide", SINGLE2, Contact(0.0, 0.0), SinePulse(3.0, 0.004), duration=0.5,
                  output_rate=1000.0)
    tr = PymunkEngine().simulate(sc, "fast")
    assert tr.status is Status.OK
    assert np.max(np.abs(tr.x[:, 0])) < 1e-5  # the base travels 2πA = 25 mm
    assert np.max(np.abs(tr.theta[:, 0])) < 1e-5


# ---------------------------------------------------------------- stacks
def test_two_block_stack_at_rest_stays_at_rest() -> None:
    sc = Scenario("rest", PAPER_STACK, Contact(1.0, 0.0), duration=2.0, output_rate=1000.0)
    tr = PymunkEngine().simulate(sc, "accurate")
    assert tr.status is Status.OK
    assert np.max(np.abs(tr.theta)) < 1e-6
    np.testing.assert_allclose(tr.x, 0.0, atol=1e-6)
    np.testing.assert_allclose(tr.z, tr.z[0] + 0.0 * tr.z, atol=1e-5)
    np.testing.assert_allclose(tr.z[0], PAPER_STACK.centroids[:, 1], atol=1e-9)


def test_stack_rocks_under_strong_pulse() -> None:
    sc = Scenario("stack", PAPER_STACK, Contact(1.0, 0.0), SinePulse(5.0, 0.006), duration=1.0,
                  output_rate=1000.0)
    tr = PymunkEngine().simulate(sc, "fast")
    assert tr.status is Status.OK
    peaks = np.max(np.abs(tr.theta), axis=0) / lam(sc)
    assert np.all(peaks > 0.05) and np.all(peaks < 1.0)


# ---------------------------------------------------------------- settings
def test_knob_overrides_take_effect() -> None:
    sc = free(B2, 0.5, 1.5)
    a = PymunkEngine().simulate(sc, "accurate")
    b = PymunkEngine().simulate(sc, {"preset": "accurate", "timestep": "1e-3"})
    assert a.settings["effective_timestep"] == pytest.approx(2.5e-5)
    assert b.settings["timestep"] == 1e-3
    assert np.max(np.abs(a.theta - b.theta)) > 1e-5
    # the other knobs reach the space too
    for knob, value in (("collision_slop", 0.01), ("collision_bias", 0.5)):
        c = PymunkEngine().simulate(sc, {knob: value})
        assert c.settings[knob] == value
        assert np.max(np.abs(a.theta - c.theta)) > 1e-6, knob


def test_non_dividing_timestep_is_used_as_given() -> None:
    sc = free(B2, 0.5, 0.3)
    tr = PymunkEngine().simulate(sc, {"timestep": 3e-4})
    assert tr.status is Status.OK
    assert tr.settings["effective_timestep"] == pytest.approx(3e-4)
    ref = PymunkEngine().simulate(sc, "accurate")
    assert np.max(np.abs(tr.theta - ref.theta)) / lam(sc) < 0.05


@pytest.mark.parametrize("vertical", [False, True])
def test_fast_driven_loop_equals_generic_loop(vertical: bool) -> None:
    """The tight _advance_driven loop is exactly _drive_base + _advance(1) per step."""
    exc = SinePulse(5.0, 0.006)
    if vertical:
        exc = Components(x=exc, z=SinePulse(5.0, 0.003))
    sc = Scenario("pulse", SINGLE2, Contact(1.0, 0.0), exc, duration=0.3,
                  output_rate=1000.0)

    class Generic(PymunkEngine):
        def _advance_driven(self, t0: float, n: int, dt: float) -> None:
            for j in range(n):
                self._drive_base(t0 + j * dt, dt)
                self._advance(1)

    a = PymunkEngine().simulate(sc, "fast")
    b = Generic().simulate(sc, "fast")
    np.testing.assert_array_equal(a.theta, b.theta)
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(a.z, b.z)


def test_settings_and_presets() -> None:
    s = PymunkEngine.settings()
    assert isinstance(s, PymunkSettings)
    assert s == PymunkEngine.settings("accurate")
    assert s.collision_slop == 0.0
    assert PymunkEngine.settings("fast").timestep == 1e-3
    assert PymunkEngine.settings(None, iterations="30").iterations == 30
    with pytest.raises(SettingsError):
        PymunkEngine.settings(None, iterations=0)
    with pytest.raises(SettingsError):
        PymunkEngine.settings(None, substeps=3)
    assert PymunkEngine.version() == pymunk.version
    assert PymunkEngine.capabilities.dimensions == 2
    assert PymunkEngine.capabilities.base_axes == "xz"


# ---------------------------------------------------------------- support
@dataclass(frozen=True)
class _OffsetBlock(Block):
    """A block with a (hypothetical) out-of-plane field the adapter does not know."""

    offset_y: float = 0.0


def test_unknown_out_of_plane_content_is_unsupported() -> None:
    odd = _OffsetBlock(0.5, 0.2, 1.0, mass=1.0, offset_y=0.1)
    tr = PymunkEngine().simulate(free(odd, 0.5, 0.1))
    assert tr.status is Status.UNSUPPORTED
    assert "2D" in tr.message and "offset_y" in tr.message
    # the same field at its planar (zero) value is fine
    ok = _OffsetBlock(0.5, 0.2, 1.0, mass=1.0)
    assert PymunkEngine().simulate(free(ok, 0.5, 0.1), "fast").status is Status.OK


@dataclass(frozen=True)
class _OffsetSupport(Support):
    """A support with a (hypothetical) out-of-plane field the adapter does not know."""

    offset_y: float = 0.0


@dataclass(frozen=True, eq=False)
class _SkewedGeometry(Geometry):
    """A geometry with a (hypothetical) out-of-plane field the adapter does not know."""

    skew_y: float = 0.0


@pytest.mark.parametrize("what", ["support", "geometry"])
def test_unknown_out_of_plane_geometry_content_is_unsupported(what: str) -> None:
    blk = Block(0.4, 0.3, 0.8, density=2000.0)
    poses = ((0.0, 0.6, 0.0),)  # on a 0.2 m plinth
    for value, status in ((0.1, Status.UNSUPPORTED), (0.0, Status.OK)):
        if what == "support":
            sup = _OffsetSupport(((-0.5, 0.0), (0.5, 0.0), (0.5, 0.2), (-0.5, 0.2)),
                                 offset_y=value)
            geo = Geometry((blk,), poses, (sup,))
            field = "_OffsetSupport.offset_y"
        else:
            geo = _SkewedGeometry((blk,), poses, (Support.rectangle(-0.5, 0.5, 0.0, 0.2),),
                                  skew_y=value)
            field = "_SkewedGeometry.skew_y"
        tr = PymunkEngine().simulate(Scenario("plinth", geo, duration=0.1), "fast")
        assert tr.status is status, tr.message
        if status is Status.UNSUPPORTED:
            assert "2D" in tr.message and field in tr.message


def test_base_motion_along_y_is_unsupported() -> None:
    sc = Scenario("y", SINGLE2, excitation=Components(y=SinePulse(5.0, 0.006)), duration=0.1)
    tr = PymunkEngine().simulate(sc)
    assert tr.status is Status.UNSUPPORTED and "moves along y" in tr.message


# ---------------------------------------------------------------- vertical base motion
def test_vertical_base_motion_carries_the_block() -> None:
    """A base moving only along z (a 2 Hz one-sine pulse of 0.5 g) lifts the block with it:
    it neither rocks nor slides and stays on the base (z − u_z = h)."""
    amp = 0.5 * 9.81 / (2 * math.pi * 2.0) ** 2
    sc = Scenario("up", SINGLE2, Contact(1.0, 0.0), Components(z=SinePulse(2.0, amp)),
                  duration=1.0, output_rate=1000.0)
    tr = PymunkEngine().simulate(sc, "accurate")
    assert tr.status is Status.OK, tr.message
    uz = sc.motion.displacement(tr.t)[:, 2]
    assert np.max(np.abs(uz)) > 0.19  # the base rises 2πA = 0.195 m
    assert np.max(np.abs(tr.theta)) < 1e-6
    assert np.max(np.abs(tr.x)) < 1e-6
    np.testing.assert_allclose(tr.z[:, 0] - uz, SINGLE2.h, atol=5e-5)


@pytest.mark.parametrize("ratio", [0.5, -0.5])
def test_vertical_and_horizontal_pulse_match_housner(ratio: float) -> None:
    """A horizontal 5 Hz / 6 mm pulse with a vertical one of ``ratio`` times its amplitude:
    θ within 5e-3 λ of the Housner reference (weight m (g + ü_z)), whose peak the vertical
    pulse moves by 7 %."""
    exc = Components(x=SinePulse(5.0, 0.006), z=SinePulse(5.0, ratio * 0.006))
    sc = Scenario("xz", SINGLE2, Contact(1.0, 0.0), exc, duration=2.0, output_rate=1000.0)
    ref = reference_theta(sc)
    flat = reference_theta(sc.replace(excitation=SinePulse(5.0, 0.006)))
    assert abs(np.max(np.abs(ref)) / np.max(np.abs(flat)) - 1.0) > 0.05
    tr = PymunkEngine().simulate(sc, "accurate")
    assert tr.status is Status.OK, tr.message
    assert np.max(np.abs(tr.theta[:, 0] - ref)) / lam(sc) <= 5e-3
    assert np.max(np.abs(tr.theta[:, 0])) == pytest.approx(np.max(np.abs(ref)), rel=0.01)


# ---------------------------------------------------------------- assemblies
def _side_by_side(mu: float, mu_if: float, peak_g: float) -> Scenario:
    """Two squat blocks (b/h = 2: they cannot rock below 2 g) touching side by side on the
    base, under a 2 Hz one-sine pulse of peak acceleration ``peak_g`` · g."""
    blk = Block(0.4, 0.3, 0.2, density=2000.0)
    amp = peak_g * 9.81 / (2 * math.pi * 2.0) ** 2
    asm = Geometry((blk, blk), ((-0.2, 0.1, 0.0), (0.2, 0.1, 0.0)), ())
    return Scenario(name="side-by-side", geometry=asm,
                    contact=Contact(mu, interface_friction=mu_if),
                    excitation=SinePulse(2.0, amp), duration=0.8, output_rate=200.0)


@pytest.mark.parametrize("mu_if", [0.5, 0.1])
def test_every_block_of_an_assembly_has_the_base_friction(mu_if: float) -> None:
    # both blocks stand on the base (μ = 0.3) at 0.2 g: neither may slide, whatever the
    # friction between them. A stack's alternation (blocks √-free, 1 and μ_if in turn)
    # would give the second block μ·μ_if on the base (0.15 or 0.03) and let it slide.
    sc = _side_by_side(0.3, mu_if, 0.2)
    tr = PymunkEngine().simulate(sc, "accurate")
    assert tr.status is Status.OK, tr.message
    base = 2 * math.pi * sc.excitation.amplitude
    np.testing.assert_allclose(tr.x[-1] - tr.x[0], [base, base], atol=2e-5)
    # at 0.5 g on μ = 0.15 both slide, together, as the exact Coulomb slider does
    sc = _side_by_side(0.15, mu_if, 0.5)
    tr = PymunkEngine().simulate(sc, "accurate")
    exact = solve_sliding(sc.excitation, 0.15, g=9.81, t_out=tr.t).slip
    slip = tr.x - tr.x[0] - np.asarray(sc.excitation.displacement(tr.t))[:, None]
    assert np.max(np.abs(exact)) > 0.02  # 2.5 cm at the end
    np.testing.assert_allclose(slip, np.column_stack([exact, exact]),
                               atol=0.01 * np.max(np.abs(exact)))


def test_interface_friction_zero_in_an_assembly_is_unsupported() -> None:
    tr = PymunkEngine().simulate(_side_by_side(0.3, 0.0, 0.2))
    assert tr.status is Status.UNSUPPORTED and "multiplies" in tr.message
    # a column's blocks alternate 1 and μ_if: μ_if = 0 holds there
    col = Scenario("column", stack((Block(0.4, 0.3, 0.2, density=2000.0),) * 2),
                   Contact(0.3, interface_friction=0.0), duration=0.1)
    assert PymunkEngine().simulate(col, "fast").status is Status.OK
