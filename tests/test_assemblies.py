"""Assemblies in the Scenario (issue 18 items 1-2): representation, files, validation,
limit analysis of the same geometry, engines that build them and the conformance checks."""

from __future__ import annotations

import hashlib
import math
from pathlib import Path

import numpy as np
import pytest

from rockbench.analytic import critical_angle
from rockbench.analytic.static_collapse import limit_analysis
from rockbench.engines import get_engine
from rockbench.engines.testing import CHECKS, conformance_checks
from rockbench.errors import ScenarioError
from rockbench.geometry import (
    Geometry,
    Prism,
    Support,
    drum_column,
    parapet,
    running_bond_wall,
    voussoir_arch,
)
from rockbench.geometry.polygon import penetration
from rockbench.scenarios import (
    Block,
    Scenario,
    SinePulse,
    catalog,
    get_scenario,
    get_suite,
    load_scenario,
    save_scenario,
    scenario_to_dict,
)
from rockbench.scenarios.catalog import STACK2
from rockbench.store import _canonical, scenario_hash
from rockbench.trajectory import Status

FAMILIES = ("column", "parapet", "wall", "arch")


# ---------------------------------------------------------------- single blocks and stacks
#: scenario_hash since issue 25 of the excited cases above (it no longer samples ü_g).
NEW_DIGESTS = {"single-pulse-3.0hz-8mm": "3c83b26c0a39d9e1",
               "stack-pulse-6.5hz-2mm": "5e62b3b7dc9634dd",
               "stack-sine-5.0hz-4mm": "8cb1b97799c3e535",
               "slide-stack-pulse-5.0hz-4mm-mu0.10": "1b0a5a4705660030"}


@pytest.mark.parametrize(("name", "digest"), [
    ("free-b0", "002a216362e61bdc"), ("free-b3-0.99", "d218e1b67fcf6fbe"),
    ("single-pulse-3.0hz-8mm", "254c643db22110c9"), ("stack-pulse-6.5hz-2mm", "b37c0be9ed06777e"),
    ("stack-sine-5.0hz-4mm", "a1d639028e6a5940"),
    ("slide-stack-pulse-5.0hz-4mm-mu0.10", "f0c94abecdd150e6"),
])
def test_stacks_keep_their_content_hash(name, digest):
    # the hashes of these catalog scenarios before assemblies existed, by the hash of that
    # time (it sampled the base acceleration): their content has not changed since
    sc = get_scenario(name)
    assert sc.geometry.column is not None  # a stack: upright blocks each on the one below
    data = scenario_to_dict(sc)
    data.pop("name")
    data.pop("description", None)
    h = hashlib.sha256(_canonical(data).encode())
    if not sc.excitation.is_free:
        t = np.linspace(0.0, sc.duration, 2001)
        h.update(np.round(np.asarray(sc.excitation.acceleration(t), float), 12).tobytes())
    assert h.hexdigest()[:16] == digest
    # issue 25's hash adds the samples of records only: the same digest without a record
    assert scenario_hash(sc) == NEW_DIGESTS.get(name, digest)


def test_stack_scenarios_have_upright_blocks_and_no_supports():
    sc = get_scenario("stack-pulse-4.0hz-4mm")
    assert np.array_equal(sc.geometry.angles, np.zeros(2)) and sc.geometry.supports == ()
    poses = sc.initial_poses()
    assert np.all(poses[:, 2] == 0.0) and np.array_equal(poses[:, :2], sc.geometry.centroids)


# ---------------------------------------------------------------- catalog families
def test_each_family_has_a_small_suite_of_assemblies():
    names = set(catalog())
    total = []
    for family in FAMILIES:
        suite = get_suite(f"assembly-{family}")
        assert 2 <= len(suite) <= 4 and set(suite) <= names
        total += suite
        for n in suite:
            # drum columns and parapets are columns (blocks each on the one below); walls
            # and arches are no column
            assert (get_scenario(n).geometry.column is None) == (family in ("wall", "arch"))
    assert get_suite("assemblies") == total


@pytest.mark.parametrize("n", range(3, 11))
def test_drum_column_collapses_as_one_body_at_width_over_height(n):
    # equal drums: the top k drums rock at α = b/(k h/2), least for k = n (the whole column)
    col = drum_column(n, width=0.6, drum_height=0.5)
    res = limit_analysis(col, friction=1.0)
    assert res.status == "collapse" and res.governing_mode == "rocking"
    assert res.load_factor == pytest.approx(0.6 / (0.5 * n), rel=1e-7)
    assert res.moving_blocks == tuple(range(n))
    assert critical_angle(col) == pytest.approx(math.atan(0.6 / (0.5 * n)), rel=1e-7)


def test_parapet_overhanging_its_wall_rocks_alone_on_the_wall_edge():
    # parapet 0.3 x 0.8 at +0.25 on a 0.6 wide wall: contact from x = 0.1 to the wall
    # edge 0.3; levers 0.05 (toward +x) and 0.15 (toward −x) over half-height 0.4
    asm = parapet(0.25)
    plus = limit_analysis(asm, direction=1)
    minus = limit_analysis(asm, direction=-1)
    assert plus.load_factor == pytest.approx(0.05 / 0.4, rel=1e-7)
    assert minus.load_factor == pytest.approx(0.15 / 0.4, rel=1e-7)
    assert plus.moving_blocks == minus.moving_blocks == (1,)
    # its mirror image swaps the two directions
    mirror = limit_analysis(asm.mirrored(), direction=-1)
    assert mirror.load_factor == pytest.approx(plus.load_factor, rel=1e-7)


def test_running_bond_courses_span_the_same_length_with_half_bricks_at_the_ends():
    wall = running_bond_wall(4, 3, length=0.24, height=0.12)
    assert len(wall) == 3 + 4 + 3 + 4
    for z in (0.06, 0.18, 0.30, 0.42):
        row = [i for i in range(len(wall)) if abs(wall.centroids[i, 1] - z) < 1e-12]
        v = np.concatenate([wall.world_vertices(i) for i in row])
        assert v[:, 0].min() == pytest.approx(-0.36) and v[:, 0].max() == pytest.approx(0.36)
        widths = sorted(wall.bodies[i].width for i in row)
        assert widths[0] == pytest.approx(0.12 if len(row) == 4 else 0.24)
    # every brick's weight reaches the base: the total mass is that of a full 0.72 x 0.48 panel
    assert sum(b.m for b in wall.bodies) == pytest.approx(1800.0 * 0.72 * 0.48 * 0.12)


def test_arch_rests_on_its_two_supports_with_springings_at_their_top():
    arch = voussoir_arch(9, 0.2, 1.0)
    assert len(arch.supports) == 2 and len(arch) == 9
    # springing voussoirs touch a support, none touches the base (the last fixed body)
    base = arch.n_bodies + 2
    assert arch.describe(base) == "the base"
    on_base = [itf for itf in arch.interfaces if itf.b == base]
    on_supports = {(itf.a, itf.b - arch.n_bodies) for itf in arch.interfaces
                   if itf.b >= arch.n_bodies and itf.b != base}
    assert not on_base and on_supports == {(0, 0), (8, 1)}
    assert min(float(arch.world_vertices(i)[:, 1].min()) for i in range(9)) == pytest.approx(0.2)


def test_stack_as_assembly_gives_the_stacks_limit_analysis():
    asm = Geometry(STACK2.bodies, tuple((float(x), float(z), 0.0) for x, z in STACK2.centroids))
    assert asm.column is not None  # the same stack, recognised as a column
    for d in (1, -1):
        a = limit_analysis(asm, direction=d)
        b = limit_analysis(STACK2, direction=d)
        assert a.load_factor == pytest.approx(b.load_factor, rel=1e-9)
        assert a.moving_blocks == b.moving_blocks
    assert STACK2.n_bodies == 2


# ---------------------------------------------------------------- prisms
def test_prism_of_a_rectangle_has_the_blocks_mass_and_inertia():
    blk = Block(0.4, 0.3, 1.1, density=2500.0)
    pr = Prism(((-0.2, -0.55), (0.2, -0.55), (0.2, 0.55), (-0.2, 0.55)), 0.3, density=2500.0)
    assert pr.m == pytest.approx(blk.m, rel=1e-12)
    assert pr.inertia == pytest.approx(blk.inertia, rel=1e-12)
    assert np.allclose(pr.profile(), blk.profile())


def test_triangular_prism_inertia_against_closed_forms():
    # right triangle, legs a along x and c along z: centroid (a/3, c/3), area ac/2;
    # ∫x² = c a³/36, ∫z² = a c³/36 and ∫xz = −a²c²/72 about the centroid
    a, c, d, m = 0.6, 0.9, 0.2, 5.0
    pr = Prism(((0.0, 0.0), (a, 0.0), (0.0, c)), d, mass=m)
    rho = m / (0.5 * a * c)
    assert pr.centroid == pytest.approx([a / 3, c / 3])
    t = pr.inertia_tensor
    assert t[1, 1] == pytest.approx(rho * (c * a**3 + a * c**3) / 36.0, rel=1e-12)
    assert t[0, 0] == pytest.approx(m * d * d / 12 + rho * a * c**3 / 36.0, rel=1e-12)
    assert t[2, 2] == pytest.approx(m * d * d / 12 + rho * c * a**3 / 36.0, rel=1e-12)
    assert t[0, 2] == pytest.approx(rho * a * a * c * c / 72.0, rel=1e-12)


def test_penetration_of_convex_polygons():
    sq = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    assert penetration(sq, sq + [0.9, 0.2]) == pytest.approx(0.1)
    assert penetration(sq, sq + [1.0, 0.0]) == pytest.approx(0.0, abs=1e-15)
    assert penetration(sq, sq + [1.25, 0.0]) == pytest.approx(-0.25)


# ---------------------------------------------------------------- files
EXAMPLE = """
name = "two on a pier"
duration = 1.0

[[blocks]]            # a rectangle placed by its centroid
width = 0.4
depth = 0.3
height = 0.6
density = 2000.0
x = -0.3
z = 0.6

[[blocks]]            # a convex polygon, vertices in its own frame, placed by x, z
vertices = [[-0.15, 0.0], [0.15, 0.0], [0.1, 0.4], [-0.1, 0.4]]
depth = 0.3
mass = 40.0
x = 0.25
z = 0.0

[[supports]]          # a fixed pier on the base
vertices = [[-0.5, 0.0], [-0.1, 0.0], [-0.1, 0.3], [-0.5, 0.3]]
"""


def _write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "scene.toml"
    p.write_text(text)
    return p


def test_example_file_loads_as_an_assembly_and_round_trips(tmp_path):
    sc = load_scenario(_write(tmp_path, EXAMPLE))
    asm = sc.geometry
    assert isinstance(asm, Geometry) and asm.column is None and len(asm.supports) == 1
    assert isinstance(asm.bodies[0], Block) and isinstance(asm.bodies[1], Prism)
    # trapezoid of bases 0.3 and 0.2, height 0.4: centroid at 0.4 (0.3 + 2·0.2)/(3·0.5)
    assert asm.centroids[1] == pytest.approx([0.25, 0.4 * 0.7 / 1.5])
    assert asm.bodies[0].m == pytest.approx(2000.0 * 0.4 * 0.3 * 0.6)
    back = load_scenario(save_scenario(sc, tmp_path / "again.toml"))
    assert back == sc and scenario_hash(back) == scenario_hash(sc)


@pytest.mark.parametrize("name", get_suite("assemblies"))
def test_catalog_assemblies_round_trip(tmp_path, name):
    sc = get_scenario(name)
    back = load_scenario(save_scenario(sc, tmp_path / f"{name}.toml"))
    assert back == sc.replace(name=name) and scenario_hash(back) == scenario_hash(sc)


BAD = [
    ("z = 0.6", "z = 0.5", "overlap"),  # the rectangle sinks into the pier
    ("z = 0.6", "z = 0.7", "touch no support"),  # ... or floats above it
    ("[[-0.15, 0.0], [0.15, 0.0], [0.1, 0.4], [-0.1, 0.4]]",
     "[[-0.1, 0.4], [0.1, 0.4], [0.15, 0.0], [-0.15, 0.0]]", "counter-clockwise"),
    ("[[-0.15, 0.0], [0.15, 0.0], [0.1, 0.4], [-0.1, 0.4]]",
     "[[-0.15, 0.0], [0.15, 0.0], [0.0, 0.1], [0.1, 0.4], [-0.1, 0.4]]", "not convex"),
    ("x = -0.3\n", "x = -0.3\noffset = 0.1\n", "'offset' is for stacks"),
    ("z = 0.6\n", "\n", "missing z"),
    ("x = 0.25\n", "x = 0.25\nangle = 1.6\n", "angle must be within"),
    ("mass = 40.0\n", "mass = 40.0\nheight = 0.4\n", "not both"),
    ('duration = 1.0', 'duration = 1.0\n[initial]\ntilt = 0.2', "initial tilt is for a column"),
    ("[-0.5, 0.3]]", "[-0.5, 0.3], [-0.45, 0.15]]", "[[supports]] #1: support"),
    ("x = 0.25\n", 'x = "a"\n', "[[blocks]] #2 x must be a finite number"),
]


@pytest.mark.parametrize(("old", "new", "expect"), BAD, ids=[b[2] for b in BAD])
def test_bad_assembly_files_give_one_line_naming_file_and_field(tmp_path, old, new, expect):
    assert old in EXAMPLE
    path = _write(tmp_path, EXAMPLE.replace(old, new, 1))
    with pytest.raises(ScenarioError) as err:
        load_scenario(path)
    msg = str(err.value)
    assert msg.startswith(str(path)) and "\n" not in msg and expect in msg, msg


def test_overlap_message_names_the_bodies():
    with pytest.raises(ScenarioError, match=r"block 0 and block 1 overlap by 0\.1"):
        Geometry((Block(1.0, 1.0, 1.0, mass=1.0),) * 2, ((0.0, 0.5, 0.0), (0.9, 0.5, 0.0)))


# ---------------------------------------------------------------- engines
def _inclined() -> Scenario:
    """A block at 0.1 rad resting on a support whose top face slopes at the same angle."""
    th, w, h = 0.1, 0.3, 0.6
    top0, top1 = 0.3, 0.3 - 0.8 * math.tan(th)  # the face descends toward +x
    sup = Support(((-0.4, 0.0), (0.4, 0.0), (0.4, top1), (-0.4, top0)))
    mid = np.array([0.0, 0.5 * (top0 + top1)])
    c = mid + 0.5 * h * np.array([math.sin(th), math.cos(th)])
    asm = Geometry((Block(w, 0.3, h, density=2000.0),), ((float(c[0]), float(c[1]), th),), (sup,))
    return Scenario(name="inclined", geometry=asm, duration=1.0, output_rate=200.0)


def _pymunk():
    return get_engine("pymunk")


def test_inclined_block_keeps_its_angle_and_is_not_called_overturned():
    sc = _inclined()
    traj = _pymunk().simulate(sc)
    assert traj.status is Status.OK, traj.message
    assert traj.theta[:, 0] == pytest.approx(0.1, abs=1e-6)


def test_stack_built_as_an_assembly_rocks_like_the_stack():
    exc = SinePulse(4.0, 0.004)
    stack = Scenario(name="s", geometry=STACK2, excitation=exc, duration=1.5)
    asm = Geometry(STACK2.bodies, tuple((float(x), float(z), 0.0) for x, z in STACK2.centroids))
    other = stack.replace(geometry=asm)
    a, b = _pymunk().simulate(stack), _pymunk().simulate(other)
    assert a.status is b.status is Status.OK
    assert np.max(np.abs(a.theta)) > 0.01  # it rocks
    assert np.max(np.abs(a.theta - b.theta)) < 1e-9
    assert np.max(np.abs(a.x - b.x)) < 1e-9


def test_engines_without_assemblies_say_unsupported():
    traj = get_engine("analytic").simulate(_inclined())
    assert traj.status is Status.UNSUPPORTED
    assert "builds only blocks standing on each other: no dynamic closed form" in traj.message
    # the offset parapet is a column now, but no closed form covers an off-centre one
    traj = get_engine("analytic").simulate(get_scenario("parapet-offset0.25"))
    assert traj.status is Status.UNSUPPORTED
    assert "no analytic model: one block or two centred stacked blocks only" in traj.message
    assert not get_engine("analytic").capabilities.assemblies
    assert _pymunk().capabilities.assemblies


def test_toppling_block_of_an_assembly_is_reported_overturned():
    sc = get_scenario("parapet-offset0.25").replace(
        excitation=SinePulse(1.0, 3.0 * 9.81 * 0.125 / (2 * math.pi) ** 2), duration=3.0)
    traj = _pymunk().simulate(sc)
    assert traj.status is Status.OVERTURNED and "block 2" in traj.message, traj.message
    # the wall below the parapet did not go over
    assert np.max(np.abs(traj.theta[:, 0])) < 0.5 * math.pi


ASSEMBLY_CHECKS = [n for n in CHECKS if n.startswith("assembly_")]


@pytest.mark.parametrize("engine", ["pymunk", "mujoco"])
@pytest.mark.parametrize("check", ASSEMBLY_CHECKS)
def test_assembly_conformance(engine, check):
    eng = get_engine(engine)
    chosen = dict(conformance_checks(eng))
    assert check in chosen and check not in eng.known_failures
    chosen[check](eng)


def test_assembly_checks_are_chosen_by_the_capability():
    names = [n for n, _ in conformance_checks(get_engine("analytic"))]
    assert not set(ASSEMBLY_CHECKS) & set(names)
