"""Limit analysis of rigid-block assemblies against closed forms and independent references.

References computed here, not by the code under test: moment balances of single
blocks, stacks and parapets; the uplift thresholds and start patterns of the
two-block model (two-block-model.md); an enumeration of the four-hinge
mechanisms of a voussoir arch by virtual work, with the weights of annular
sectors integrated in closed form; its continuous optimum for the minimum
thickness (Milankovitch 1907: t/R = 0.1075, radial joints, true self-weight,
no sliding; Heyman's 0.106 rests on a simplified tangency condition, see
Cocchetti, Colasante & Rizzi 2011, Appl. Mech. Rev. 64:050802).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar

from rockbench.analytic.static_collapse import LimitResult, limit_analysis, minimum_stable, stands
from rockbench.analytic.twoblock_model import BlockParams, Pattern, TwoBlockModel
from rockbench.geometry import Block, Geometry, Prism, Support, semicircular_arch, stack
from rockbench.geometry.builders import stack_poses

G = 9.81
RHO = 2000.0
INF = math.inf


def block_stack(sizes: list[tuple[float, float]], offsets: tuple[float, ...] = ()) -> Geometry:
    """Rectangular blocks (width, height), 1 m deep, of density RHO, stacked on the base."""
    return stack([Block(w, 1.0, h, density=RHO) for w, h in sizes], offsets)


def rectangle(width: float, height: float, centre: tuple[float, float]
              ) -> tuple[Block, tuple[float, float, float]]:
    """A 1 m deep block of density RHO and its upright pose centred at ``centre``."""
    return Block(width, 1.0, height, density=RHO), (float(centre[0]), float(centre[1]), 0.0)


def assert_bounds_agree(r: LimitResult) -> None:
    """Static and kinematic LPs are duals: equal optima (associative flow)."""
    assert r.status == "collapse"
    assert r.kinematic_load_factor == pytest.approx(r.load_factor, rel=1e-9, abs=1e-12)


# ---------------------------------------------------------------- one block
@pytest.mark.parametrize("width,height", [(1.0, 3.0), (0.4, 4.0), (2.0, 2.0)])
@pytest.mark.parametrize("direction", [1, -1])
def test_single_block_rocks_at_tan_lambda_about_the_leeward_corner(width, height, direction):
    b, h = width / 2, height / 2
    a = block_stack([(width, height)])
    r = limit_analysis(a, direction=direction)
    assert_bounds_agree(r)
    assert r.load_factor == pytest.approx(b / h, rel=1e-12)
    assert r.tilt_angle == pytest.approx(math.atan2(b, h), rel=1e-12)
    assert r.governing_mode == "rocking"
    (m,) = r.mechanism
    assert m.kind == "rotation" and m.rotation_sign == direction
    np.testing.assert_allclose(m.centre, [direction * b, 0.0], atol=1e-9)
    assert m.pivot is not None
    np.testing.assert_allclose(a.world_vertices(0)[m.pivot], [direction * b, 0.0])
    (j,) = r.joints
    assert j.kind == "hinge"
    # at collapse the whole weight bears on the pivot and friction carries the load
    (f,) = r.interface_forces
    weight = RHO * width * height * G
    n, t = f.resultant
    assert n == pytest.approx(weight, rel=1e-9)
    assert abs(t) == pytest.approx(b / h * weight, rel=1e-9)
    itf = a.interfaces[0]
    np.testing.assert_allclose(f.centre_of_pressure(itf.p0, itf.p1), [direction * b, 0.0],
                               atol=1e-9)


@pytest.mark.parametrize("mu", [0.0, 0.1, 0.3])
def test_single_block_slides_at_mu_when_mu_is_below_b_over_h(mu):
    r = limit_analysis(block_stack([(1.0, 3.0)]), friction=mu)  # b/h = 1/3
    assert_bounds_agree(r)
    assert r.load_factor == pytest.approx(mu, abs=1e-12)
    assert r.governing_mode == "sliding"
    assert r.mechanism[0].kind == "translation"
    assert r.joints[0].kind == "slide"
    # associative flow: the slip dilates by μ per unit slip
    u = r.mechanism[0].velocity
    assert u[0] > 0 and u[1] == pytest.approx(mu * u[0], abs=1e-9)


def test_friction_above_b_over_h_does_not_change_rocking():
    rock = limit_analysis(block_stack([(1.0, 3.0)]), friction=0.34)
    assert rock.load_factor == pytest.approx(1 / 3, rel=1e-12)
    assert rock.governing_mode == "rocking"


@pytest.mark.parametrize(
    "size,mu,mode",
    [((0.4, 4.0), 0.6, "rocking"),  # a slender column rocks: b/h = 0.1 < μ
     ((2.0, 1.0), 0.6, "sliding"),  # a squat block on a low-friction joint slides: μ < b/h = 2
     ((1.0, 1.0), 0.6, "sliding")],
)
def test_where_sliding_governs(size, mu, mode):
    r = limit_analysis(block_stack([size]), friction=mu)
    assert r.governing_mode == mode
    assert r.load_factor == pytest.approx(min(size[0] / size[1], mu), rel=1e-12)


# ------------------------------------------------------------ two-block stack
def _model(lower: tuple[float, float], upper: tuple[float, float]) -> TwoBlockModel:
    params = [BlockParams.uniform(w / 2, h / 2, RHO * w * h) for w, h in (lower, upper)]
    return TwoBlockModel(*params, g=G)


def _pattern(r: LimitResult, a: Geometry) -> Pattern:
    """The two-block model's pattern name of a limit-analysis mechanism."""
    lower, upper = r.mechanism
    base = 0
    if lower.kind == "rotation":
        assert a.world_vertices(0)[lower.pivot][1] == pytest.approx(0.0, abs=1e-12)
        base = lower.rotation_sign
    rel = upper.velocity[2] - lower.velocity[2]
    (between,) = (j for j, i in zip(r.joints, a.interfaces, strict=True) if (i.a, i.b) == (0, 1))
    iface = 0 if between.kind == "closed" else (1 if rel > 0 else -1)
    return Pattern(base, iface)


@pytest.mark.parametrize(
    "lower,upper",
    [((1.0, 3.0), (0.6, 2.0)),  # G_ref: the stack rocks as one (thresholds 2.215 < 2.943)
     ((1.2, 2.0), (0.4, 2.0)),  # G_U: the upper block rocks alone (1.962 < 3.924)
     ((0.6, 2.0), (1.0, 1.0))],  # wider on top: interface pivots at the lower block's corners
)
@pytest.mark.parametrize("accel_sign", [1, -1])
def test_two_block_stack_matches_the_uplift_thresholds_and_start_pattern(lower, upper,
                                                                          accel_sign):
    model = _model(lower, upper)
    a = block_stack([lower, upper])
    # a base acceleration a loads the blocks toward −sign(a)
    r = limit_analysis(a, direction=-accel_sign)
    assert_bounds_agree(r)
    assert r.load_factor * G == pytest.approx(model.threshold, rel=1e-12)
    assert r.governing_mode == "rocking"
    start = model.start_pattern(accel_sign * model.threshold * (1 + 1e-6))
    assert start.kind in ("M", "U")
    assert _pattern(r, a) == start


def test_published_two_block_thresholds():
    # two-block-model.md T6: g b_c/h2 = 2.943, g b1/ybar = 2.215161290323 m/s²
    a = block_stack([(1.0, 3.0), (0.6, 2.0)])
    assert limit_analysis(a).load_factor * G == pytest.approx(2.215161290323, rel=1e-12)
    upper, pose = rectangle(0.6, 2.0, (0.0, 4.0))
    alone = Geometry((upper,), (pose,), (Support(a.world_vertices(0)),), base=False)
    assert limit_analysis(alone).load_factor * G == pytest.approx(2.943, rel=1e-12)


def test_chamfered_scenario_stack_pivots_at_b_minus_chamfer():
    lo = Block(width=1.0, depth=0.5, height=3.0, density=RHO, chamfer=0.05)
    up = Block(width=0.6, depth=0.5, height=2.0, density=RHO, chamfer=0.05)
    geometry = stack((lo, up))
    model = TwoBlockModel(BlockParams.from_block(lo), BlockParams.from_block(up), g=G)
    r = limit_analysis(geometry, direction=-1)
    assert_bounds_agree(r)
    assert r.load_factor * G == pytest.approx(model.threshold, rel=1e-12)
    assert r.tilt_angle == pytest.approx(math.atan(model.threshold / G), rel=1e-12)


# ----------------------------------------------------------------- parapet
def _parapet(e: float, wall: tuple[float, float] = (1.0, 1.0),
             top: tuple[float, float] = (0.3, 1.0)) -> Geometry:
    """A parapet ``top`` (width, height) centred at x = e on a wall block ``wall``.

    Built from the poses, without :func:`stack`'s check that it stands (an overhanging
    parapet is one of the cases).
    """
    blocks = [Block(w, 1.0, h, density=RHO) for w, h in (wall, top)]
    return Geometry(tuple(blocks), stack_poses(blocks, (0.0, e)))


@pytest.mark.parametrize(
    "e,wall,top",
    [(0.0, (1.0, 1.0), (0.3, 1.0)), (0.2, (1.0, 1.0), (0.3, 1.0)),
     (0.4, (1.0, 1.0), (0.3, 1.0)), (-0.3, (1.0, 1.0), (0.3, 1.0)),
     (0.05, (0.6, 2.0), (0.5, 0.5)),  # a slender wall under a stocky parapet: the wall tips
     (0.2, (0.6, 2.0), (0.5, 0.5))],
)
@pytest.mark.parametrize("direction", [1, -1])
def test_offset_parapet_by_moments(e, wall, top, direction):
    a = _parapet(e, wall, top)
    m1, m2 = (b.m for b in a.bodies)
    bw, hw = wall[0] / 2, wall[1] / 2
    bt, ht = top[0] / 2, top[1] / 2
    # contact segment on the wall top; the parapet tips on its leeward end
    left, right = max(-bw, e - bt), min(bw, e + bt)
    pivot = right if direction > 0 else left
    parapet = direction * (pivot - e) / ht
    # the whole stack tips on the wall's leeward ground corner
    corner = direction * bw
    stack = direction * (m1 * corner + m2 * (corner - e)) / (m1 * hw + m2 * (2 * hw + ht))
    r = limit_analysis(a, direction=direction)
    assert_bounds_agree(r)
    assert r.load_factor == pytest.approx(min(parapet, stack), rel=1e-12)
    assert r.governing_mode == "rocking"
    if parapet < stack:
        assert r.moving_blocks == (1,)
        np.testing.assert_allclose(r.mechanism[1].centre, [pivot, 2 * hw], atol=1e-9)
    else:
        assert r.moving_blocks == (0, 1)
        for m in r.mechanism:
            np.testing.assert_allclose(m.centre, [corner, 0.0], atol=1e-9)


def test_overhanging_parapet_does_not_stand():
    a = _parapet(0.6)  # centroid beyond the wall's edge at x = 0.5
    assert not stands(a)
    with pytest.raises(ValueError, match="off its support"):  # the stack builder refuses it
        block_stack([(1.0, 1.0), (0.3, 1.0)], offsets=(0.0, 0.6))
    away = limit_analysis(a, direction=1)
    back = limit_analysis(a, direction=-1)
    assert away.status == back.status == "unstable"
    # only a push back toward the wall holds it: α between (0.6−0.5)/0.5 and (0.6−0.45)/0.5
    assert back.load_factor == pytest.approx(0.3, rel=1e-9)
    assert away.load_factor == pytest.approx(-0.2, rel=1e-9)
    assert away.mechanism == () and away.governing_mode is None


# -------------------------------------------------------------------- arch
def _hinge_powers(t: float, angles: np.ndarray, sides: np.ndarray,
                  radius: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Virtual powers of gravity and of a +x load for admissible four-hinge arch mechanisms.

    Hinges at polar angles ``angles`` (K, 4), increasing, on the intrados
    (side −1) or extrados (+1). The outer segments turn about hinges 1 and 4,
    the middle one about the intersection of the lines through hinges 1–2 and
    3–4. A hinge on the intrados must see its two sides turn so that the
    extrados opens (relative rate < 0 going round the arch toward larger
    angles), and vice versa.
    Each mechanism is returned with the sense of rotation that makes it
    admissible (unit density, depth, g). Weights of annular sectors are
    integrated in closed form.
    """
    ri, re = radius - t / 2, radius + t / 2
    r = np.where(sides > 0, re, ri)
    h = np.stack([r * np.cos(angles), r * np.sin(angles)], axis=-1)
    h1, h2, h3, h4 = (h[:, k] for k in range(4))
    d1, d2 = h2 - h1, h3 - h4
    den = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    ok = np.abs(den) > 1e-12
    w = h4 - h1
    s = (w[:, 0] * d2[:, 1] - w[:, 1] * d2[:, 0]) / np.where(ok, den, 1.0)
    c2 = h1 + s[:, None] * d1

    def ratio(u: np.ndarray, v: np.ndarray) -> np.ndarray:
        return np.einsum("ij,ij->i", u, v) / np.einsum("ij,ij->i", v, v)

    w1 = np.ones(len(angles))
    w2 = w1 * ratio(h2 - h1, h2 - c2)
    w3 = w2 * ratio(h3 - c2, h3 - h4)
    k3 = (re**3 - ri**3) / 3.0
    pg = np.zeros(len(angles))
    pl = np.zeros(len(angles))
    for u, v, om, c in ((angles[:, 0], angles[:, 1], w1, h1), (angles[:, 1], angles[:, 2], w2, c2),
                        (angles[:, 2], angles[:, 3], w3, h4)):
        mass = radius * t * (v - u)
        sx, sz = k3 * (np.sin(v) - np.sin(u)), k3 * (np.cos(u) - np.cos(v))
        # v = ω (z − c_z, −(x − c_x)): gravity power −m g v_z, +x load power m v_x
        pg += om * (sx - mass * c[:, 0])
        pl += om * (sz - mass * c[:, 1])
    rel = np.stack([w1, w2 - w1, w3 - w2, -w3], axis=1)
    fwd = np.all(rel * sides > 0, axis=1) & ok
    bwd = np.all(-rel * sides > 0, axis=1) & ok
    sign = np.where(fwd, 1.0, np.where(bwd, -1.0, 0.0))
    keep = sign != 0
    return (sign * pg)[keep], (sign * pl)[keep]


def _enumerate(n: int, t: float) -> tuple[np.ndarray, np.ndarray]:
    joints = np.linspace(0.0, math.pi, n + 1)
    combos = np.array(list(itertools.combinations(range(n + 1), 4)))
    sides = np.array(list(itertools.product((-1, 1), repeat=4)))
    angles = joints[np.repeat(combos, len(sides), axis=0)]
    return _hinge_powers(t, angles, np.tile(sides, (len(combos), 1)))


def _enumerated_minimum_thickness(n: int) -> float:
    return brentq(lambda t: _enumerate(n, t)[0].max(), 0.05, 0.2, xtol=1e-12)


def _continuous_minimum_thickness() -> tuple[float, float]:
    """Milankovitch's problem: hinges anywhere, symmetric mode springing–β–crown–(π−β)."""
    sides = np.array([[1, -1, 1, -1]])  # springing and crown on the extrados

    def worst(t: float) -> tuple[float, float]:
        def power(beta: float) -> float:
            pg, _ = _hinge_powers(t, np.array([[0.0, beta, math.pi / 2, math.pi - beta]]), sides)
            return -pg[0] if len(pg) else 1.0
        res = minimize_scalar(power, bounds=(0.2, 1.2), method="bounded",
                              options={"xatol": 1e-12})
        return -res.fun, res.x

    t_c = brentq(lambda t: worst(t)[0], 0.09, 0.12, xtol=1e-14)
    return t_c, worst(t_c)[1]


def _arch_minimum_thickness(n: int) -> float:
    return minimum_stable(lambda t: semicircular_arch(n, t), 0.10, 0.108, xtol=1e-9)


@pytest.mark.parametrize("n", [4, 6, 9])
def test_arch_minimum_thickness_equals_the_hinge_enumeration(n):
    assert _arch_minimum_thickness(n) == pytest.approx(_enumerated_minimum_thickness(n), abs=2e-9)


@pytest.mark.slow
def test_arch_minimum_thickness_approaches_milankovitch():
    t_c, beta = _continuous_minimum_thickness()
    # the reference itself: Milankovitch's t/R = 0.1075, intrados hinge 54.5° from the crown
    assert round(t_c, 4) == 0.1075
    assert 90 - math.degrees(beta) == pytest.approx(54.5, abs=0.05)
    ns = [6, 12, 24, 48, 96]
    ts = [_arch_minimum_thickness(n) for n in ns]
    # nested joints: every mechanism of n voussoirs is one of 2n, so t_min cannot fall
    assert all(b >= a - 2e-9 for a, b in itertools.pairwise(ts))
    # hinges only at joints: never thicker than the continuous arch; 96 voussoirs put a
    # joint 0.11° from Milankovitch's haunch hinge
    assert all(t <= t_c + 2e-9 for t in ts)
    assert t_c - ts[-1] < 2e-6
    assert t_c - ts[0] > 2e-3


def test_arch_under_horizontal_load_matches_enumeration_and_converges():
    t = 0.15
    for n in (5, 8):
        pg, pl = _enumerate(n, t)
        live = pl > 1e-14
        expect = float(np.min(-pg[live] / pl[live]))
        r = limit_analysis(semicircular_arch(n, t))
        assert_bounds_agree(r)
        assert r.load_factor == pytest.approx(expect, rel=1e-9)
        assert r.governing_mode == "rocking"
        assert sum(j.kind == "hinge" for j in r.joints) == 4
    alphas = [limit_analysis(semicircular_arch(n, t)).load_factor for n in (16, 32, 64, 128)]
    steps = np.abs(np.diff(alphas))
    # nested joints: α cannot rise with n; the refinements shrink
    assert all(b <= a + 1e-12 for a, b in itertools.pairwise(alphas))
    assert steps[-1] < steps[0] / 4 and steps[-1] < 1e-3
    # symmetric arch: the same factor either way
    assert limit_analysis(semicircular_arch(32, t), direction=-1).load_factor == pytest.approx(
        alphas[1], rel=1e-9)


def test_arch_with_low_friction_slides_at_a_springing_and_hinges_elsewhere():
    a = semicircular_arch(16, 0.15)
    alphas = [limit_analysis(a, friction=mu).load_factor for mu in (0.4, 0.45, 0.5, INF)]
    # friction can only help: α does not fall as μ grows, and μ = 0.5 already locks sliding
    assert all(b >= a_ - 1e-12 for a_, b in itertools.pairwise(alphas))
    assert alphas[2] == pytest.approx(alphas[3], rel=1e-12)
    r = limit_analysis(a, friction=0.4)  # associative: an upper bound for real Coulomb joints
    assert r.governing_mode == "mixed" and r.load_factor < 0.5 * alphas[3]
    active = [(i, j) for i, j in zip(a.interfaces, r.joints, strict=True) if j.kind != "closed"]
    assert sorted(j.kind for _, j in active) == ["hinge", "hinge", "hinge", "slide"]
    (slid,) = (i for i, j in active if j.slides)
    assert a.is_fixed(slid.b)  # a springing slips on its abutment


# ----------------------------------------------------------- tilting table
def _tilt_to_collapse(a: Geometry, friction: float = INF) -> float:
    """Tilting-table angle (rad, toward +x) at which the assembly stops standing."""
    return brentq(lambda phi: 1.0 if stands(a.rotated(phi), friction=friction) else -1.0,
                  0.0, 1.2, xtol=1e-10)


@pytest.mark.parametrize(
    "assembly,friction",
    [(block_stack([(1.0, 3.0)]), INF),
     (block_stack([(2.0, 1.0)]), 0.5),  # slides on the table
     (block_stack([(1.0, 3.0), (0.6, 2.0)]), INF),
     (_parapet(0.2), INF),
     (semicircular_arch(8, 0.15), INF)],
)
def test_tilting_table_collapses_at_atan_alpha(assembly, friction):
    r = limit_analysis(assembly, friction=friction, direction=1)
    assert _tilt_to_collapse(assembly, friction) == pytest.approx(r.tilt_angle, abs=1e-8)


def test_tilted_assembly_has_the_same_interfaces():
    a = semicircular_arch(6, 0.15)
    b = a.rotated(0.3, about=(0.4, -0.2))
    assert [(i.a, i.b) for i in b.interfaces] == [(i.a, i.b) for i in a.interfaces]
    for i, j in zip(a.interfaces, b.interfaces, strict=True):
        assert j.length == pytest.approx(i.length, rel=1e-12)


@pytest.mark.parametrize("friction", [INF, 0.3])
@pytest.mark.parametrize("direction", [1, -1])
def test_block_in_a_tight_slot_has_no_mechanism(friction, direction):
    walls = [Support(np.array([[x0, 0.0], [x0 + 0.5, 0.0], [x0 + 0.5, 2.0], [x0, 2.0]]))
             for x0 in (-1.0, 0.5)]
    block, pose = rectangle(1.0, 1.0, (0.0, 0.5))
    a = Geometry((block,), (pose,), (Support.ground(-1.0, 1.0), *walls), base=False)
    assert len(a.interfaces) == 3
    r = limit_analysis(a, friction=friction, direction=direction)
    assert r.status == "no_mechanism" and r.load_factor == INF


@pytest.mark.parametrize("direction", [1, -1])
def test_support_reactions_balance_the_loads_at_collapse(direction):
    a = semicircular_arch(12, 0.15)
    r = limit_analysis(a, direction=direction)
    weight = sum(b.m for b in a.bodies) * G
    total = np.zeros(2)
    for itf, f in zip(a.interfaces, r.interface_forces, strict=True):
        assert np.all(f.normal >= -1e-9 * weight)
        if a.is_fixed(itf.b):  # the force on the support is N n + T t
            total += f.normal.sum() * itf.normal + f.shear.sum() * itf.tangent
    np.testing.assert_allclose(total, [direction * r.load_factor * weight, -weight],
                               atol=1e-8 * weight)


# ------------------------------------------------- non-associative (real) Coulomb joints
def _running_bond(courses: int, bricks: int, length: float = 0.24, height: float = 0.12
                  ) -> tuple[Geometry, list[tuple[float, float, float]]]:
    """A running-bond wall (half bricks at both ends of every second course) and its bricks
    as (x, z, width), in the order of its blocks."""
    x0 = -0.5 * bricks * length
    bricks_xzw = []
    for c in range(courses):
        z = (c + 0.5) * height
        if c % 2 == 0:
            row = [(x0 + (k + 0.5) * length, length) for k in range(bricks)]
        else:
            row = ([(x0 + 0.25 * length, 0.5 * length)]
                   + [(x0 + (k + 1.0) * length, length) for k in range(bricks - 1)]
                   + [(-x0 - 0.25 * length, 0.5 * length)])
        bricks_xzw += [(x, z, w) for x, w in row]
    blocks, poses = zip(*(rectangle(w, height, (x, z)) for x, z, w in bricks_xzw), strict=True)
    return Geometry(blocks, poses, (Support.ground(-1.0, 1.0),), base=False), bricks_xzw


@pytest.mark.parametrize("direction", [1, -1])
def test_running_bond_wall_turns_a_stepped_wedge_out_with_coulomb_joints(direction):
    # 6 courses of 3 bricks 0.24 x 0.12, mu = 1. With real (non-dilatant) joints the
    # wedge above the first course, bounded by the 45° stepped line from the course's
    # leeward corner, turns about that corner while its head joints open: by virtual
    # work α = Σ m (x_pivot − x) / Σ m (z − z_pivot) = 3.30 / 5.70 = 11/19 (mass ∝ width).
    wall, bricks = _running_bond(6, 3)
    edge, z0, h = 0.36, 0.12, 0.12

    def in_wedge(x: float, z: float, w: float) -> bool:
        lee = direction * x + 0.5 * w  # the brick's leeward edge, mirrored for direction −1
        windward = lee - w
        return z > z0 and windward >= edge - (z + 0.5 * h - z0) - 1e-12 and lee <= edge + 1e-12

    wedge = tuple(i for i, (x, z, w) in enumerate(bricks) if in_wedge(x, z, w))
    assert len(wedge) == 9
    lever = sum(w * (edge - direction * bricks[i][0]) for i in wedge for w in [bricks[i][2]])
    arm = sum(bricks[i][2] * (bricks[i][1] - z0) for i in wedge)
    assert lever / arm == pytest.approx(11 / 19, rel=1e-12)
    r = limit_analysis(wall, friction=1.0, direction=direction, flow="non-associative")
    assert_bounds_agree(r)
    assert r.load_factor == pytest.approx(11 / 19, rel=1e-8)
    assert r.moving_blocks == wedge and r.governing_mode == "rocking"
    for m in (r.mechanism[i] for i in wedge):  # one rigid rotation about the pivot corner
        assert m.kind == "rotation" and m.rotation_sign == direction
        np.testing.assert_allclose(m.centre, [direction * edge, z0], atol=1e-7)
    # the associative LP presses the head joints with a prestress nothing creates and
    # leans on their friction: 0.992, near the monolithic 1 (b/h of the panel, and μ)
    assoc = limit_analysis(wall, friction=1.0, direction=direction)
    assert assoc.load_factor == pytest.approx(0.99232, abs=1e-5)
    assert r.flow == "non-associative" and r.iterations > 1 and assoc.iterations == 0


def test_coulomb_forces_at_the_walls_collapse_are_admissible_and_balance_the_loads():
    wall, _ = _running_bond(6, 3)
    r = limit_analysis(wall, friction=1.0, flow="non-associative")
    weight = sum(b.m for b in wall.bodies) * G
    total = np.zeros(2)
    for itf, f, j in zip(wall.interfaces, r.interface_forces, r.joints, strict=True):
        assert np.all(f.normal >= -1e-9 * weight)
        assert np.all(np.abs(f.shear) <= f.normal + 1e-9 * weight)  # |T| ≤ μ N
        # no force where the joint opens
        assert np.all(f.normal[j.opening > 1e-6] <= 1e-9 * weight)
        if wall.is_fixed(itf.b):  # the force on the base is N n + T t
            total += f.normal.sum() * itf.normal + f.shear.sum() * itf.tangent
    np.testing.assert_allclose(total, [r.load_factor * weight, -weight], atol=1e-8 * weight)


@pytest.mark.parametrize(
    "assembly,friction",
    [(block_stack([(1.0, 3.0)]), 1.0),  # rocks at b/h
     (block_stack([(2.0, 1.0)]), 0.5),  # slides at μ
     (block_stack([(1.0, 3.0), (0.6, 2.0)]), 1.0),
     (_parapet(0.2), 0.8),
     (semicircular_arch(16, 0.15), 0.4),  # slides at a springing, hinges elsewhere
     (semicircular_arch(9, 0.15), 1.0)],
)
def test_non_associative_flow_keeps_the_factor_where_the_lp_is_exact(assembly, friction):
    assoc = limit_analysis(assembly, friction=friction)
    real = limit_analysis(assembly, friction=friction, flow="non-associative")
    assert_bounds_agree(real)
    assert real.load_factor == pytest.approx(assoc.load_factor, rel=1e-8)
    assert real.moving_blocks == assoc.moving_blocks


# -------------------------------------------------------------- validation
def test_interfaces_found_with_their_segments():
    a = block_stack([(1.0, 1.0), (0.3, 1.0)], offsets=[0.0, 0.4])
    assert [(i.a, i.b) for i in a.interfaces] == [(0, 1), (0, 2)]
    top = a.interfaces[0]
    np.testing.assert_allclose(sorted([top.p0[0], top.p1[0]]), [0.25, 0.5])
    np.testing.assert_allclose(top.normal, [0.0, 1.0])  # out of the wall, into the parapet
    assert len(semicircular_arch(7, 0.1).interfaces) == 8  # 6 joints + 2 springings


@pytest.mark.parametrize(
    "make,match",
    [(lambda: Prism(np.array([[0, 0], [0, 1], [1, 1], [1, 0]]), 1.0, density=1.0),
      "counter-clockwise"),
     (lambda: Prism(np.array([[0, 0], [2, 0], [1, 0.2], [1, 1]]), 1.0, density=1.0),
      "not convex"),
     (lambda: Prism(np.array([[0, 0], [1, 0], [0, 1]]), 1.0, density=1.0, mass=1.0),
      "exactly one"),
     (lambda: Prism(np.array([[0, 0], [1, 0], [0, 1]]), 1.0, mass=1.0,
                    centre_of_gravity=(2, 2)), "outside"),
     (lambda: Prism(np.array([[0, 0], [1, 0]]), 1.0, mass=1.0), "at least 3"),
     (lambda: Geometry(*zip(rectangle(1.0, 1.0, (0.0, 0.5)), rectangle(1.0, 1.0, (1.5, 1.5)),
                            strict=True)), "touch no support"),
     (lambda: Geometry(*zip(rectangle(1, 1, (0, 0.4)), strict=True),
                       (Support.ground(-1, 1),), base=False), "overlap"),
     (lambda: Geometry((), (), (Support.ground(-1, 1),), base=False), "at least one block"),
     (lambda: limit_analysis(block_stack([(1, 1)]), direction=0), "direction"),
     (lambda: limit_analysis(block_stack([(1, 1)]), friction=-0.1), "friction"),
     (lambda: limit_analysis(block_stack([(1, 1)]), flow="plastic"), "flow"),
     (lambda: limit_analysis(block_stack([(1, 1)]), flow="non-associative"), "finite friction")],
)
def test_invalid_input_is_rejected_with_a_clear_message(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_minimum_stable_needs_a_bracket():
    with pytest.raises(ValueError, match="already stands"):
        minimum_stable(lambda t: semicircular_arch(8, t), 0.15, 0.2)
