"""Conformance kit for engine plugins (in the spirit of scikit-learn's ``check_estimator``).

Every check takes an engine instance (and optional settings), runs small
scenarios and raises :class:`AssertionError` with a physical explanation when
the engine misbehaves. :func:`conformance_checks` picks the checks that apply
to an engine's capabilities; :func:`check_engine` runs them all;
:func:`parametrize_with_checks` makes one pytest test per (engine, check),
with the engine's ``known_failures`` as strict expected failures.

Example
-------
>>> from rockbench.engines import get_engine
>>> from rockbench.engines.testing import check_engine
>>> check_engine(get_engine("mujoco"))  # doctest: +SKIP

In a plugin's own test suite (pytest)::

    from rockbench.engines.testing import parametrize_with_checks

    @parametrize_with_checks([MyEngine])
    def test_conformance(engine, check):
        check(engine)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from rockbench import analytic
from rockbench.analytic import cases_3d
from rockbench.engines.base import Engine
from rockbench.geometry import (
    Block,
    Body,
    Geometry,
    Prism,
    Support,
    running_bond_wall,
    single,
    voussoir_arch,
)
from rockbench.geometry.polygon import penetration, rotate
from rockbench.metrics import first_zero, impact_times, max_error
from rockbench.scenarios import Scenario, SinePulse, scenario_to_dict
from rockbench.scenarios.catalog import SINGLE2, STACK2
from rockbench.trajectory import Status, Trajectory

__all__ = ["Tolerances", "conformance_checks", "check_engine", "parametrize_with_checks"]

#: The B2 block of the paper (0.5 × 0.2 × 1.0 m, 1 kg): λ = 0.4636 rad.
B2 = Block(width=0.5, depth=0.2, height=1.0, mass=1.0)


@dataclass(frozen=True)
class Tolerances:
    """Bounds used by the checks (defaults are the project's conformance bounds).

    Attributes
    ----------
    rest : float
        Largest |θ|/λ allowed for a block that should stay at rest.
    free_error : float
        Largest max |θ − θ_ref|/λ over the first three impacts of free rocking.
    impact_time : float
        Largest relative error of the first three impact times.
    peak : float
        Largest relative error of the peak |θ| under a sine pulse.
    mirror : float
        Largest |θ(+) + θ(−)|/λ for mirrored scenarios.
    penetration : float
        Largest overlap of two bodies of an assembly at rest, as a fraction of
        the assembly's size: 1e-5 is 10 µm on a 1 m scene (measured at the
        accurate presets: pymunk 1e-13 m with collision_slop 0, MuJoCo 2e-8 m
        with its soft contacts).
    """

    rest: float = 2e-3
    free_error: float = 0.02
    impact_time: float = 0.02
    peak: float = 0.05
    mirror: float = 0.01
    penetration: float = 1e-5


def _scenario(name: str, geometry: Geometry | Block, **kw: Any) -> Scenario:
    geo = geometry if isinstance(geometry, Geometry) else single(geometry)
    return Scenario(name=f"conformance-{name}", geometry=geo, **kw)


def _lam(scenario: Scenario) -> float:
    """The scenario's normalising λ."""
    return analytic.critical_angle(scenario.geometry)


def _run(engine: Engine, scenario: Scenario, settings: Any) -> Trajectory:
    traj = engine.simulate(scenario, settings)
    assert traj.status in (Status.OK, Status.OVERTURNED), (
        f"{engine.name} on {scenario.name}: status {traj.status} ({traj.message})"
    )
    return traj


def check_rest(engine: Engine, settings: Any = None, tol: Tolerances = Tolerances()) -> None:
    """An upright block on a still base stays upright and in place (no drift, no creep)."""
    sc = _scenario("rest", B2, duration=2.0, output_rate=200.0)
    traj = _run(engine, sc, settings)
    lam = _lam(sc)
    assert traj.status is Status.OK, f"resting block ended {traj.status}: {traj.message}"
    worst = float(np.max(np.abs(traj.theta))) / lam
    assert worst <= tol.rest, f"resting block rotated to {worst:.2e} λ (limit {tol.rest:.0e} λ)"
    drift = float(np.max(np.abs(traj.x - traj.x[0])))
    assert drift <= 1e-3 * B2.height, f"resting block drifted {drift:.2e} m"


def check_free_rocking(engine: Engine, settings: Any = None,
                       tol: Tolerances = Tolerances()) -> None:
    """Free rocking of B2 from 0.5 λ follows Housner over the first three impacts."""
    sc = _scenario("free", B2, initial_tilt=0.5, duration=3.0, output_rate=1000.0)
    ref = analytic.reference(sc)
    traj = _run(engine, sc, settings)
    t_ref = impact_times(ref)[:3]
    t_eng = impact_times(traj)[:3]
    assert t_eng.size == 3, f"expected 3 impacts within 3 s, engine showed {t_eng.size}"
    rel = np.abs(t_eng - t_ref) / t_ref
    assert np.all(rel <= tol.impact_time), (
        f"impact times {np.round(t_eng, 4)} vs Housner {np.round(t_ref, 4)}: "
        f"errors {np.round(rel * 100, 2)} % (limit {tol.impact_time * 100:g} %)"
    )
    err = max_error(traj, ref, _lam(sc), t_end=float(t_ref[2]) + 0.05)
    assert err <= tol.free_error, (
        f"max |θ − θ_Housner| = {err:.4f} λ over 3 impacts (limit {tol.free_error} λ)"
    )


def check_subthreshold(engine: Engine, settings: Any = None,
                       tol: Tolerances = Tolerances()) -> None:
    """A base pulse below the uplift threshold g·tan λ does not lift the block."""
    lam = SINGLE2.rocking().lam
    f = 3.0
    amp = 0.8 * 9.81 * math.tan(lam) / (2 * math.pi * f) ** 2
    sc = _scenario("subthreshold", SINGLE2, excitation=SinePulse(f, amp), duration=1.0)
    traj = _run(engine, sc, settings)
    worst = float(np.max(np.abs(traj.theta))) / lam
    assert worst <= 5 * tol.rest, (
        f"a pulse at 0.8 × the uplift threshold rotated the block to {worst:.2e} λ"
    )
    # the block rides with the base: it must have moved by the pulse's displacement
    moved = traj.x[-1, 0] - traj.x[0, 0]
    expect = float(sc.motion.x.displacement(sc.duration))
    assert abs(moved - expect) <= 0.05 * abs(expect) + 1e-4, (
        f"block moved {moved:.4g} m, the base {expect:.4g} m: the base does not drag it"
    )


def check_mirror_symmetry(engine: Engine, settings: Any = None,
                          tol: Tolerances = Tolerances()) -> None:
    """Mirrored initial tilt and mirrored base motion give mirrored rocking."""
    for name, kw_pos, kw_neg in (
        ("tilt", dict(initial_tilt=0.5), dict(initial_tilt=-0.5)),
        ("pulse", dict(excitation=SinePulse(3.0, 0.008)),
         dict(excitation=SinePulse(3.0, -0.008))),
    ):
        block = B2 if name == "tilt" else SINGLE2
        pos = _run(engine, _scenario(f"mirror-{name}+", block, duration=1.5, **kw_pos), settings)
        neg = _run(engine, _scenario(f"mirror-{name}-", block, duration=1.5, **kw_neg), settings)
        lam = block.rocking().lam
        n = min(pos.t.size, neg.t.size)
        asym = float(np.max(np.abs(pos.theta[:n] + neg.theta[:n]))) / lam
        assert asym <= tol.mirror, f"{name}: mirrored runs differ by {asym:.2e} λ"


def check_determinism(engine: Engine, settings: Any = None,
                      tol: Tolerances = Tolerances()) -> None:
    """Two identical runs give identical trajectories."""
    sc = _scenario("determinism", SINGLE2, excitation=SinePulse(3.0, 0.008), duration=1.0)
    a = _run(engine, sc, settings)
    b = _run(engine, sc, settings)
    assert a.status == b.status and np.array_equal(a.theta, b.theta), (
        "two identical runs differ"
    )


def check_overturning(engine: Engine, settings: Any = None,
                      tol: Tolerances = Tolerances()) -> None:
    """A pulse that overturns the Housner block is reported as ``overturned``."""
    lam = SINGLE2.rocking().lam
    f = 1.0
    amp = 3.0 * 9.81 * math.tan(lam) / (2 * math.pi * f) ** 2
    sc = _scenario("overturn", SINGLE2, excitation=SinePulse(f, amp), duration=3.0)
    ref = analytic.reference(sc)
    assert ref.status is Status.OVERTURNED, "test case no longer overturns analytically"
    traj = engine.simulate(sc, settings)
    assert traj.status is Status.OVERTURNED, (
        f"expected overturned, got {traj.status} ({traj.message}); "
        f"max |θ| = {np.max(np.abs(traj.theta)):.3f} rad"
    )


def check_scenario_not_mutated(engine: Engine, settings: Any = None,
                               tol: Tolerances = Tolerances()) -> None:
    """simulate() leaves the scenario unchanged."""
    sc = _scenario("mutation", B2, initial_tilt=0.3, duration=0.2)
    before = scenario_to_dict(sc)
    engine.simulate(sc, settings)
    assert scenario_to_dict(sc) == before, "the scenario was modified by simulate()"


def check_stack_rest(engine: Engine, settings: Any = None,
                     tol: Tolerances = Tolerances()) -> None:
    """The paper's chamfered two-block stack stays at rest on a still base."""
    sc = _scenario("stack-rest", STACK2, duration=1.0, output_rate=200.0)
    traj = _run(engine, sc, settings)
    worst = float(np.max(np.abs(traj.theta))) / _lam(sc)
    assert traj.status is Status.OK and worst <= tol.rest, (
        f"resting stack: status {traj.status}, max |θ| = {worst:.2e} λ"
    )


def check_forced_peak(engine: Engine, settings: Any = None,
                      tol: Tolerances = Tolerances()) -> None:
    """The peak rocking angle under the paper's 3 Hz / 8 mm sine pulse matches Housner."""
    sc = _scenario("forced", SINGLE2, excitation=SinePulse(3.0, 0.008), duration=2.0)
    ref = analytic.reference(sc)
    traj = _run(engine, sc, settings)
    p_ref = float(np.max(np.abs(ref.theta)))
    p_eng = float(np.max(np.abs(traj.theta)))
    rel = abs(p_eng - p_ref) / p_ref
    assert rel <= tol.peak, (
        f"peak |θ| {p_eng:.5f} rad vs Housner {p_ref:.5f} rad ({rel * 100:.2f} %, "
        f"limit {tol.peak * 100:g} %)"
    )


def _assembly_scene(prisms: bool = True) -> Geometry:
    """A small assembly of every kind of body: a block on a support, a block on the base,
    a trapezoidal prism on top of it (asymmetric, so that mirroring it is a real test).

    Without ``prisms`` (an engine that builds rectangular blocks only) the top body is a
    box standing off-centre on its block, which keeps the scene asymmetric.
    """
    top: Body = Prism(((0.1, 0.9), (0.4, 0.9), (0.35, 1.2), (0.15, 1.2)), 0.3,
                               density=2000.0)
    top_pose = (0.0, 0.0, 0.0)
    if not prisms:
        top, top_pose = Block(0.2, 0.3, 0.3, density=2000.0), (0.3, 1.05, 0.0)
    return Geometry(
        (Block(0.4, 0.3, 0.6, density=2000.0), Block(0.3, 0.3, 0.9, density=2000.0), top),
        ((-0.3, 0.6, 0.0), (0.25, 0.45, 0.0), top_pose),
        (Support.rectangle(-0.5, -0.1, 0.0, 0.3),))


def _assembly_pulse(scene: Geometry, factor: float = 2.0) -> SinePulse:
    """A 3 Hz one-sine pulse peaking at ``factor`` × the scene's collapse acceleration."""
    f = 3.0
    alpha = math.tan(analytic.critical_angle(scene))
    return SinePulse(f, factor * 9.81 * alpha / (2 * math.pi * f) ** 2)


def _rest_assemblies(engine: Engine, duration: float = 2.0) -> list[Scenario]:
    """The scene above and an arch of voussoirs; for an engine without prisms, the scene
    of boxes and a running-bond wall (head joints, half bricks) in place of the arch."""
    prisms = engine.capabilities.prisms
    second = ("arch-rest", voussoir_arch(9, 0.2)) if prisms else \
        ("wall-rest", running_bond_wall(4, 3))
    return [_scenario("assembly-rest", _assembly_scene(prisms), duration=duration,
                      output_rate=200.0),
            _scenario(second[0], second[1], duration=duration, output_rate=200.0)]


def check_assembly_rest(engine: Engine, settings: Any = None,
                        tol: Tolerances = Tolerances()) -> None:
    """Assemblies on a still base (blocks on supports, a prism, an arch) stay at rest."""
    for sc in _rest_assemblies(engine):
        traj = _run(engine, sc, settings)
        assert traj.status is Status.OK, f"{sc.name}: status {traj.status} ({traj.message})"
        turn = float(np.max(np.abs(traj.theta - traj.theta[0]))) / _lam(sc)
        drift = float(np.max(np.hypot(traj.x - traj.x[0], traj.z - traj.z[0])))
        assert turn <= tol.rest, f"{sc.name}: a block turned by {turn:.2e} λ at rest"
        size = sc.geometry.size
        assert drift <= 1e-3 * size, f"{sc.name}: a block drifted {drift:.2e} m at rest"


def check_assembly_penetration(engine: Engine, settings: Any = None,
                               tol: Tolerances = Tolerances()) -> None:
    """At rest no two bodies of an assembly (blocks, supports, base) overlap beyond tol."""
    for sc in _rest_assemblies(engine, duration=1.0):
        traj = _run(engine, sc, settings)
        asm = sc.geometry
        polys = [c + rotate(b.profile(), th) for b, c, th in zip(
            asm.bodies, np.column_stack([traj.x[-1], traj.z[-1]]), traj.theta[-1], strict=True)]
        fixed = [s.array for s in asm.supports]
        worst, where = 0.0, ""
        for i, p in enumerate(polys):
            below = -float(p[:, 1].min())  # the base is z <= 0
            if below > worst:
                worst, where = below, f"block {i + 1} and the base"
            for j, q in enumerate(polys[i + 1:] + fixed, i + 1):
                d = penetration(p, q)
                if d > worst:
                    what = f"block {j + 1}" if j < len(polys) else f"support {j - len(polys) + 1}"
                    worst, where = d, f"block {i + 1} and {what}"
        assert worst <= tol.penetration * asm.size, (
            f"{sc.name}: {where} overlap by {worst:.2e} m at rest (limit "
            f"{tol.penetration * asm.size:.2e} m)")


def _mirrored_runs(engine: Engine, settings: Any) -> tuple[Trajectory, Trajectory, Scenario]:
    scene = _assembly_scene(engine.capabilities.prisms)
    pulse = _assembly_pulse(scene)
    pos = _scenario("assembly-mirror+", scene, excitation=pulse, duration=1.5)
    neg = _scenario("assembly-mirror-", scene.mirrored(),
                    excitation=SinePulse(pulse.frequency, -pulse.amplitude), duration=1.5)
    return _run(engine, pos, settings), _run(engine, neg, settings), pos


def check_assembly_mirror_symmetry(engine: Engine, settings: Any = None,
                                   tol: Tolerances = Tolerances()) -> None:
    """An assembly and its mirror image under a mirrored pulse rock as mirror images."""
    a, b, sc = _mirrored_runs(engine, settings)
    lam = _lam(sc)
    peak = float(np.max(np.abs(a.theta))) / lam
    assert peak > 0.05, f"the pulse should rock the scene, max |θ| = {peak:.2e} λ"
    n = min(a.t.size, b.t.size)
    asym = float(np.max(np.abs(a.theta[:n] + b.theta[:n]))) / lam
    shift = float(np.max(np.abs(a.x[:n] + b.x[:n])))
    assert asym <= tol.mirror, f"mirrored assemblies' rotations differ by {asym:.2e} λ"
    assert shift <= tol.mirror * sc.geometry.size, (
        f"mirrored assemblies' x differ by {shift:.2e} m")


def check_assembly_determinism(engine: Engine, settings: Any = None,
                               tol: Tolerances = Tolerances()) -> None:
    """Two identical runs of a rocking assembly give identical trajectories."""
    scene = _assembly_scene(engine.capabilities.prisms)
    sc = _scenario("assembly-determinism", scene, excitation=_assembly_pulse(scene),
                   duration=1.0)
    a, b = _run(engine, sc, settings), _run(engine, sc, settings)
    assert a.status == b.status and np.array_equal(a.theta, b.theta) and np.array_equal(
        a.x, b.x), "two identical runs of an assembly differ"


def check_cylinder_rocking(engine: Engine, settings: Any = None,
                           tol: Tolerances = Tolerances()) -> None:
    """A drum released in the x–z plane rocks on its rim as Housner's block of half-width R
    with the cylinder's inertia: its first impact on time. Where the engine also takes 3D
    starts, the drum released toward 40° tilts alike (a box in its place would pivot on a
    corner, with another lever and inertia)."""
    sc = cases_3d.drum_release()
    ref = analytic.reference(sc)
    t_ref = float(impact_times(ref)[0])
    traj = _run(engine, sc, settings)
    t_eng = first_zero(traj.t, traj.theta[:, 0])
    assert abs(t_eng / t_ref - 1.0) <= tol.impact_time, (
        f"the drum's first impact at {t_eng:.4f} s, Housner's with the cylinder's inertia at "
        f"{t_ref:.4f} s (limit {tol.impact_time * 100:g} %)")
    if not engine.capabilities.start3d:
        return
    turned = _run(engine, sc.replace(initial_azimuth=math.radians(40.0)), settings)
    before = ref.t < 0.9 * t_ref
    n = int(np.count_nonzero(before))
    err = float(np.max(np.abs(turned.tilt[:n, 0] - ref.theta[:n, 0]))) / _lam(sc)
    assert err <= tol.free_error, (
        f"released toward 40° the drum's tilt leaves Housner's by {err:.4f} λ before its "
        f"impact (limit {tol.free_error} λ): not rocking on a round rim")


def check_corner_rocking(engine: Engine, settings: Any = None,
                         tol: Tolerances = Tolerances()) -> None:
    """A square pillar released on its corner along its diagonal rocks in the diagonal plane
    and lands at Housner's quarter period with the diagonal's lever and inertia."""
    sc = cases_3d.corner_release()
    traj = _run(engine, sc, settings)
    t_land = cases_3d.corner_landing_time(cases_3d.PILLAR, sc.theta0, sc.g)
    t_eng = first_zero(traj.t, traj.theta[:, 0])
    assert abs(t_eng / t_land - 1.0) <= tol.impact_time, (
        f"the pillar lands at {t_eng:.4f} s, the closed form at {t_land:.4f} s (limit "
        f"{tol.impact_time * 100:g} %)")
    before = traj.t < 0.95 * t_land
    off = float(np.max(np.abs(traj.theta[before, 0] + traj.roll[before, 0]))) / sc.tilt_lambda()
    assert off <= tol.mirror, (
        f"the pillar leaves its diagonal plane by {off:.2e} λ before it lands (limit "
        f"{tol.mirror} λ)")


Check = Callable[..., None]

#: Every check of the kit, by name (what ``known_failures`` refers to).
CHECKS: dict[str, Check] = {
    c.__name__.removeprefix("check_"): c
    for c in (check_rest, check_subthreshold, check_mirror_symmetry, check_determinism,
              check_overturning, check_scenario_not_mutated, check_free_rocking,
              check_forced_peak, check_stack_rest, check_assembly_rest,
              check_assembly_penetration, check_assembly_mirror_symmetry,
              check_assembly_determinism, check_cylinder_rocking, check_corner_rocking)
}


def conformance_checks(engine: Engine | type[Engine]) -> list[tuple[str, Check]]:
    """The checks that apply to ``engine``'s capabilities, as (name, function) pairs.

    Comparisons with the analytic reference are left out for the reference itself,
    where they could not fail.

    Raises
    ------
    ValueError
        ``engine.known_failures`` names a check that is not in the kit.
    """
    unknown = sorted(set(engine.known_failures) - set(CHECKS))
    if unknown:
        raise ValueError(f"{engine.name}.known_failures names unknown check(s) "
                         f"{', '.join(unknown)}; checks: {', '.join(CHECKS)}")
    cap = engine.capabilities
    names = ["rest", "subthreshold", "mirror_symmetry", "determinism", "overturning",
             "scenario_not_mutated"]
    if not cap.analytic:
        names += ["free_rocking", "forced_peak"]
    if cap.max_blocks is None or cap.max_blocks >= 2:
        names.append("stack_rest")
    if cap.assemblies:
        names += ["assembly_rest", "assembly_penetration", "assembly_mirror_symmetry",
                  "assembly_determinism"]
    if cap.cylinders and not cap.analytic:
        names.append("cylinder_rocking")
    if cap.start3d and not cap.analytic:
        names.append("corner_rocking")
    return [(n, CHECKS[n]) for n in names]


def check_engine(engine: Engine, settings: Any = None, tol: Tolerances = Tolerances()) -> None:
    """Run every applicable check; raise AssertionError listing all failures."""
    failures = []
    for name, check in conformance_checks(engine):
        try:
            check(engine, settings, tol)
        except AssertionError as exc:
            failures.append(f"{name}: {exc}")
    if failures:
        raise AssertionError(f"{engine.name} fails {len(failures)} check(s):\n" +
                             "\n".join(failures))


def _engine_class(item: Engine | type[Engine] | str) -> type[Engine]:
    if isinstance(item, str):
        from rockbench.engines.registry import engine_class

        return engine_class(item)
    return item if isinstance(item, type) else type(item)


def parametrize_with_checks(engines: Iterable[Engine | type[Engine] | str]) -> Any:
    """A pytest ``parametrize`` decorator over every (engine, check) pair that applies.

    The decorated test takes the arguments ``engine`` (an instance) and
    ``check`` (a function of the engine) and calls ``check(engine)``. Test ids
    are ``<engine>-<check>``; a check in the engine's ``known_failures`` is a
    strict expected failure with the declared reason, so fixing it shows up as
    an unexpected pass. An engine whose libraries do not import (or whose
    ``version()`` fails) is one explicit skip with the reason and the install
    hint, ``<engine>-unavailable``.

    Parameters
    ----------
    engines : iterable of Engine, Engine subclass or str
        Instances (used as given by all their checks), classes (a fresh
        instance per check) or registered names (likewise).

    Returns
    -------
    pytest.MarkDecorator
        ``pytest.mark.parametrize(("engine", "check"), ...)``.

    Raises
    ------
    UnknownEngine
        A name that no plugin is registered under.
    ValueError
        A ``known_failures`` entry that names no check of the kit.

    Examples
    --------
    >>> @parametrize_with_checks([MyEngine])  # doctest: +SKIP
    ... def test_conformance(engine, check):
    ...     check(engine)
    """
    import pytest  # only the test suites need it

    from rockbench.engines.registry import probe
    from rockbench.errors import EngineUnavailable

    params = []
    for item in engines:
        name = item if isinstance(item, str) else item.name
        try:
            cls = _engine_class(item)
            probe(cls)
        except EngineUnavailable as exc:
            params.append(pytest.param(None, None, marks=pytest.mark.skip(reason=str(exc)),
                                       id=f"{name}-unavailable"))
            continue
        for check_name, check in conformance_checks(cls):
            reason = cls.known_failures.get(check_name)
            marks = [pytest.mark.xfail(strict=True, reason=reason)] if reason else []
            engine = item if isinstance(item, Engine) else cls()
            params.append(pytest.param(engine, check, marks=marks,
                                       id=f"{cls.name}-{check_name}"))
    return pytest.mark.parametrize(("engine", "check"), params)
