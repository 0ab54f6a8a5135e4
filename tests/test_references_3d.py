"""The 3D references study: its scenes, its verdicts, the report and the command."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from rockbench.analytic import reference
from rockbench.cli import main
from rockbench.method import Method
from rockbench.runner import ExecutionOptions
from rockbench.studies.references_3d import (
    SLENDER_CYLINDER,
    Errors3D,
    References3DOptions,
    precession,
    rim_contact,
    run_references_3d,
)

IN_PROCESS = ExecutionOptions(isolate=False)


def _row(drum: float, corner: float, off: float, drift: float, rate: float) -> Errors3D:
    return Errors3D(Method("x"), "x", 0, drum, corner, off, drift, rate, 0.0, ())


@pytest.mark.fast
def test_the_contact_point_of_the_reference_rolls_on_its_circle() -> None:
    """The rim point under the precessing cylinder rolls on the closed form's circle, of the
    cylinder's radius about the origin, and it lies under the lean (beyond the centre of
    mass's circle)."""
    sc, sp = precession(2.0)
    ref = reference(sc)
    p = rim_contact(ref, SLENDER_CYLINDER)
    np.testing.assert_allclose(np.hypot(p[:, 0], p[:, 1]), sp.contact_radius, atol=1e-9)
    np.testing.assert_allclose(p[0], [0.3, 0.0], atol=1e-12)
    assert sp.contact_radius > sp.com_radius


@pytest.mark.fast
def test_the_verdicts_follow_the_bounds_and_the_half_step() -> None:
    good = _row(1e-3, -2e-3, 1e-9, 2e-4, 1e-3)
    assert good.within_bounds() is True
    assert _row(0.02, 0.0, 0.0, 0.0, 0.0).within_bounds() is False  # a landing 2 % late
    assert _row(0.0, 0.0, 2e-3, 0.0, 0.0).within_bounds() is False  # off its diagonal
    assert _row(0.0, 0.0, 0.0, 0.05, 0.0).within_bounds() is False  # the tilt drifts
    assert _row(math.nan, 0.0, 0.0, 0.0, 0.0).within_bounds() is None  # a run failed
    assert good.converged(_row(1.5e-3, -2.5e-3, 0.0, 3e-4, 0.0)) is True
    assert good.converged(_row(3e-3, -2e-3, 0.0, 2e-4, 0.0)) is False  # impact moved 0.2 %
    assert good.converged(_row(1e-3, -2e-3, 0.0, 2e-3, 0.0)) is False  # drift grew 10×
    # a consistent fall is converged, and outside the bounds: converged is not right
    fall = _row(0.0, 0.0, 0.0, 0.2, 2.4)
    assert fall.converged(fall) is True and fall.within_bounds() is False


def test_mujoco_meets_the_3d_references_and_the_report_is_written(tmp_path) -> None:
    pytest.importorskip("mujoco")
    res = run_references_3d(References3DOptions(engines=["mujoco"], presets=["fast"],
                                                duration=1.0, execution=IN_PROCESS))
    ref, fast, half = res.rows
    assert ref.method.is_reference and ref.tilt_drift < 1e-12
    assert fast.label == half.label == "mujoco[fast]" and (fast.rung, half.rung) == (0, 1)
    assert fast.within_bounds() and fast.converged(half)
    # halving the step halves the first-order timing errors
    assert abs(half.drum_impact) < 0.7 * abs(fast.drum_impact)
    from rockbench.report.references_3d_report import write_report
    files = write_report(res, tmp_path / "r3d", embed_figures=False)
    assert [f.name for f in files] == ["index.html", "report.md", "references-3d.csv"]
    rows = list(csv.DictReader((tmp_path / "r3d" / "references-3d.csv").open()))
    assert [r["method"] for r in rows] == ["analytic", "mujoco[fast]", "mujoco[fast]"]
    assert rows[1]["within_bounds"] == "True" and rows[1]["converged"] == "True"
    for png in ("precession-tilt.png", "precession-contact.png"):
        assert (tmp_path / "r3d" / "figures" / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_command_skips_engines_without_cylinders_and_refuses_bad_input(
        tmp_path, capsys) -> None:
    pytest.importorskip("mujoco")
    code = main(["references-3d", "--engine", "mujoco,dem2d", "--preset", "fast",
                 "--duration", "0.5", "--no-converge", "--no-db", "--jobs", "1",
                 "--out", str(tmp_path / "r")])
    out = capsys.readouterr().out
    assert code == 0 and "skipped (no cylinders or 3D starts): dem2d" in out
    assert "mujoco[fast]: tilt drift" in out and (tmp_path / "r" / "index.html").exists()
    code = main(["references-3d", "--engine", "mujoco", "--duration", "-1", "--no-db",
                 "--out", str(tmp_path / "r")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--duration" in err[0]
