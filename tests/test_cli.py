"""The command line: listing, running, writing trajectories, one-line errors with status 2."""

import json
import subprocess
import sys

import numpy as np
import pytest

from rockbench.cli import main
from rockbench.trajectory import Trajectory


def _cli(*args):
    """Run the installed CLI in a subprocess, as a user would."""
    return subprocess.run([sys.executable, "-m", "rockbench.cli", *args], capture_output=True,
                          text=True, timeout=300)


def test_help_and_listing(capsys):
    assert main(["engines"]) == 0
    out = capsys.readouterr().out
    assert "analytic" in out and "mujoco" in out
    assert main(["scenarios", "--suite", "smoke"]) == 0
    assert "free-b2-0.5" in capsys.readouterr().out
    assert main(["scenarios", "--show", "free-b0"]) == 0
    assert 'name = "free-b0"' in capsys.readouterr().out


@pytest.mark.parametrize("args, needle", [
    (["run", "no-such-case"], "unknown scenario 'no-such-case'"),
    (["run", "free-b0", "--engine", "mujocco"], "did you mean 'mujoco'"),
    (["run", "free-b0", "--set", "analytic"], "engine.knob=value"),
    (["run", "free-b0", "--engine", "analytic", "--out", "x.txt"], ".csv or .npz"),
    (["run", "missing.toml"], "cannot read"),
    (["scenarios", "--suite", "nope"], "unknown suite 'nope'"),
    (["run"], "required"),
    (["run", "free-b0", "--settings", "missing.toml"], "missing.toml"),
])
def test_bad_input_is_one_line_and_status_2(args, needle):
    r = _cli(*args)
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0], r.stderr
    assert "Traceback" not in r.stderr


def test_bad_toml_file(tmp_path):
    f = tmp_path / "s.toml"
    f.write_text("[[blocks]]\nwidth = -1\ndepth = 0.2\nheight = 1\nmass = 1\n")
    r = _cli("run", str(f))
    assert r.returncode == 2 and "width" in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_run_analytic_writes_csv_and_sidecar(tmp_path, capsys):
    out = tmp_path / "free.csv"
    assert main(["run", "free-b1-0.5", "--engine", "reference", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "free-b1-0.5" in text and "ok" in text
    header = out.read_text().splitlines()[0]
    assert header == "t,theta_1,x_1,z_1,wobble_1"
    meta = json.loads(out.with_suffix(".json").read_text())
    assert meta["engine"] == "analytic" and meta["status"] == "ok"
    assert meta["scenario_definition"]["name"] == "free-b1-0.5"
    traj = Trajectory.load(out)
    # released from rest at 0.5 λ of B1
    lam = 0.5880026035475675
    assert traj.theta[0, 0] == pytest.approx(0.5 * lam, rel=1e-9)
    assert traj.t[-1] == pytest.approx(20.0)


def test_run_engine_against_reference_npz(tmp_path, capsys):
    pytest.importorskip("mujoco")
    out = tmp_path / "run.npz"
    f = tmp_path / "short.toml"
    f.write_text('name = "short"\nduration = 1.0\n[[blocks]]\nwidth = 0.5\ndepth = 0.2\n'
                 'height = 1.0\nmass = 1.0\n[initial]\ntilt = 0.5\n')
    assert main(["run", str(f), "--engine", "mujoco,analytic", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "vs analytic" in text
    mj = Trajectory.load(tmp_path / "run-mujoco.npz")
    ref = Trajectory.load(tmp_path / "run-analytic.npz")
    assert mj.engine == "mujoco" and ref.engine == "analytic"
    assert np.max(np.abs(mj.theta - ref.theta)) / 0.4636 < 0.02
