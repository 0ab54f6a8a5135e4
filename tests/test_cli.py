"""The command line: listing, running, writing trajectories, one-line errors with status 2."""

import argparse
import json
import re
import shlex
import subprocess
import sys

import numpy as np
import pytest

from rockbench.cli import build_parser, main
from rockbench.cli.common import execution_options
from rockbench.runner import default_jobs
from rockbench.scenarios import catalog
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
    (["run", "free-b0", "--engine", "analytic", "--set", "analytic.foo=1"],
     "error: engine 'analytic' has no knob 'foo'; knobs: linear"),
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


@pytest.mark.slow
def test_a_closed_pipe_ends_the_output_quietly():
    """``rockbench records --json | head -1``: the reader goes away, no traceback."""
    cmd = f"{shlex.quote(sys.executable)} -m rockbench.cli records --json | head -1"
    r = subprocess.run(cmd, shell=True, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0 and r.stdout == "[\n"
    assert "Traceback" not in r.stderr and "BrokenPipe" not in r.stderr
    assert r.stderr == "", r.stderr


def test_catalog_descriptions_read_as_text(capsys):
    """Descriptions say what the scene is, not fragments of its name (``5drums drums``)."""
    texts = {}
    for name in catalog():
        assert main(["scenarios", "--show", name]) == 0
        (line,) = [ln for ln in capsys.readouterr().out.splitlines()
                   if ln.startswith("description = ")]
        texts[name] = line
    for name, text in texts.items():
        assert "drums drums" not in text and not re.search(r"\d(drums|offset)|offset\d", text), \
            (name, text)
    assert "multi-drum column of 5 drums 0.6 × 0.5 m" in texts["column-5drums"]
    assert "multi-drum column of 3 drums" in texts["column-3drums"]
    assert "its centre 0.25 m from the wall's" in texts["parapet-offset0.25"]
    assert "its centre 0.00 m from the wall's" in texts["parapet-offset0.00"]


#: The commands that run studies (each runs many simulations in parallel).
STUDIES = ("compare", "matrix", "sweep", "tune", "fragility", "collapse", "assemblies",
           "spectrum")


def test_every_study_runs_on_the_usable_cores_by_default():
    parser = build_parser()
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    for name in STUDIES:
        (jobs,) = [a for a in sub.choices[name]._actions if "--jobs" in a.option_strings]
        args = argparse.Namespace(jobs=jobs.default)
        assert execution_options(args).jobs == default_jobs(), name
        assert "cores" in jobs.help, (name, jobs.help)
