"""Trajectory files: CSV and NPZ with a JSON sidecar, round trip."""

import json

import numpy as np
import pytest

from rockbench.trajectory import Status, Trajectory


def _traj():
    t = np.linspace(0, 1, 11)
    return Trajectory(t=t, theta=np.column_stack([np.sin(t), -np.sin(t)]),
                      x=np.column_stack([t, 2 * t]), z=np.ones((11, 2)),
                      status="overturned", message="block 2 overturned", wall_time=0.5,
                      engine="e", engine_version="1", settings={"dt": 1e-3}, scenario="s",
                      impacts=[0.2, 0.4])


@pytest.mark.parametrize("suffix", [".csv", ".npz"])
def test_round_trip(tmp_path, suffix):
    tr = _traj()
    side = tr.save(tmp_path / f"run{suffix}", scenario={"name": "s"})
    back = Trajectory.load(tmp_path / f"run{suffix}")
    for q in ("t", "theta", "x", "z", "wobble"):
        np.testing.assert_allclose(getattr(back, q), getattr(tr, q), rtol=1e-9)
    assert back.status is Status.OVERTURNED and back.message == tr.message
    assert back.settings == {"dt": 1e-3}
    assert json.loads(side.read_text())["scenario_definition"] == {"name": "s"}


def test_csv_columns(tmp_path):
    _traj().save(tmp_path / "r.csv")
    header = (tmp_path / "r.csv").read_text().splitlines()[0]
    assert header == "t,theta_1,x_1,z_1,wobble_1,theta_2,x_2,z_2,wobble_2"


def test_failed_trajectory_saves(tmp_path):
    tr = Trajectory.failed("crashed", "boom", n_blocks=2, engine="e")
    tr.save(tmp_path / "f.csv")
    back = Trajectory.load(tmp_path / "f.csv")
    assert back.status is Status.CRASHED and back.t.size == 0 and back.n_blocks == 2


def test_bad_shapes_and_format(tmp_path):
    with pytest.raises(ValueError, match="shape"):
        Trajectory(t=np.zeros(3), theta=np.zeros((4, 1)))
    with pytest.raises(ValueError, match="format"):
        _traj().save(tmp_path / "x.txt")


@pytest.mark.parametrize("suffix", [".csv", ".npz"])
def test_motion_out_of_the_plane_round_trips_and_planar_files_stay_as_they_were(
        tmp_path, suffix):
    tr = _traj()
    assert tr.planar and "roll_1" not in tr.columns()
    t = tr.t
    lean = Trajectory(t=t, theta=np.column_stack([0.1 * t, 0 * t]), x=tr.x, z=tr.z,
                      y=np.column_stack([0.01 * t, 0 * t]),
                      roll=np.column_stack([-0.1 * t, 0 * t]),
                      twist=np.column_stack([0.02 * t, 0 * t]))
    assert not lean.planar
    assert list(lean.columns())[:8] == ["t", "theta_1", "x_1", "z_1", "wobble_1", "y_1",
                                        "roll_1", "twist_1"]
    lean.save(tmp_path / f"lean{suffix}")
    back = Trajectory.load(tmp_path / f"lean{suffix}")
    for q in ("y", "roll", "twist"):
        np.testing.assert_allclose(getattr(back, q), getattr(lean, q), rtol=1e-9)
    # equal lean toward +x and toward +y (roll < 0): tilt = atan(√2 tan θ), azimuth 45°
    end = back.tilt[-1, 0], back.azimuth[-1, 0]
    assert end[0] == pytest.approx(np.arctan(np.sqrt(2.0) * np.tan(0.1)), rel=1e-12)
    assert end[1] == pytest.approx(np.pi / 4, rel=1e-12)
    # a file written before the 3D quantities existed loads with them at zero
    tr.save(tmp_path / f"old{suffix}")
    old = Trajectory.load(tmp_path / f"old{suffix}")
    assert old.planar and old.roll.shape == old.theta.shape
