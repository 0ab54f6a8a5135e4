"""The regression matrix: tolerance files, verdicts, baselines, JUnit XML and exit codes."""

from __future__ import annotations

import importlib
import json
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from rockbench.cli import main
from rockbench.engines import register, unregister
from rockbench.evaluation import NUMERIC_METRICS, RunMetrics
from rockbench.method import Method
from rockbench.report.grid import format_grid
from rockbench.report.junit import write_junit
from rockbench.scenarios import (
    Block,
    Scenario,
    SinePulse,
    get_scenario,
    get_suite,
    save_scenario,
)
from rockbench.store import Store
from rockbench.studies.baseline import (
    BaselineCell,
    BaselineError,
    baseline_data,
    load_baseline,
    write_baseline,
)
from rockbench.studies.matrix import (
    FAIL,
    REGRESSION,
    SKIP,
    Cell,
    MatrixResult,
    evaluate,
    regressions,
)
from rockbench.studies.tolerances import METRICS, ToleranceError, load_tolerances
from rockbench.trajectory import Status

sys.path.insert(0, str(Path(__file__).parent))
fault_engine = importlib.import_module("fault_engine")

GOOD = """
format = 1
suite = "smoke"
[defaults]
status = "reference"
max_error = 0.05
impact_time_error = 0.02
[scenarios."stack-*"]
max_error = 0.1
[scenarios."stack-pulse-4.0hz-4mm"]
peak_error = 0.3
[engines.mujoco]
max_error = 0.02
[engines.mujoco.scenarios."free-b2-0.5"]
max_error = 0.01
impact_time_error = false
[suites.paper.defaults]
max_error = 0.2
[regression]
rel = 0.5
abs = 0.001
metrics = ["max_error"]
"""


def test_tolerance_layers(tmp_path: Path) -> None:
    path = tmp_path / "t.toml"
    path.write_text(GOOD)
    tol = load_tolerances(path)
    assert tol.suite == "smoke" and tol.engines() == {"mujoco"}
    assert tol.for_cell("pymunk", "free-b1-0.5") == {
        "status": "reference", "max_error": 0.05, "impact_time_error": 0.02}
    assert tol.for_cell("pymunk", "stack-sine-4.0hz-4mm")["max_error"] == 0.1
    cell = tol.for_cell("pymunk", "stack-pulse-4.0hz-4mm")
    assert cell["max_error"] == 0.1 and cell["peak_error"] == 0.3
    assert tol.for_cell("mujoco", "stack-pulse-4.0hz-4mm")["max_error"] == 0.02  # engine wins
    cell = tol.for_cell("mujoco", "free-b2-0.5")
    assert cell["max_error"] == 0.01 and cell["impact_time_error"] is None
    assert tol.for_cell("mujoco", "free-b2-0.5", suite="paper")["max_error"] == 0.2
    assert tol.regression == {"rel": 0.5, "abs": 0.001, "metrics": ["max_error"]}


@pytest.mark.parametrize("text, words", [
    ("[defaults\nmax_error = 1", "malformed TOML"),
    ("[defaults]\nmax_eror = 0.1", "unknown metric 'max_eror'"),
    ("[defaults]\nmax_error = -0.1", "max_error must be a number >= 0"),
    ("[defaults]\nmax_error = 'small'", "max_error must be a number >= 0"),
    ("[defaults]\nmax_error = true", "max_error must be a number >= 0"),
    ("[defaults]\nstatus = 'fine'", "unknown status 'fine'"),
    ("[defaults]\nstatus = 3", "status must be one of"),
    ("[defaults]\nstatus = [['ok']]", "defaults.status must list status names"),
    ("[defaults]\nstatus = [{ok = 1}]", "defaults.status must list status names"),
    ("[defaults]\nrealtime_factor = 10", "is measured but is not a limit"),
    ("[regression]\nmetrics = [['max_error']]", "regression.metrics must be a list"),
    ("format = 2", "format 2 is not supported"),
    ("colour = 'red'", "unknown key 'colour'"),
    ("engines = 3", "engines must be a table"),
    ("[engines.mujoco.scenarios]\nx = 1", "must be a table of metric limits"),
    ("[suites.paper]\nregression = {}", "suites.paper may only hold"),
    ("[regression]\nrel = -1", "regression.rel must be a number >= 0"),
    ("[regression]\nmetrics = ['speed']", "regression.metrics must be a list"),
    ("[regression]\nmargin = 1", "unknown key 'margin'"),
])
def test_bad_tolerance_files(tmp_path: Path, text: str, words: str) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ToleranceError, match="bad.toml") as err:
        load_tolerances(path)
    assert words in str(err.value)


def test_missing_tolerance_file(tmp_path: Path) -> None:
    with pytest.raises(ToleranceError, match="cannot read"):
        load_tolerances(tmp_path / "nope.toml")


@pytest.mark.parametrize("suite", ["smoke", "paper"])
def test_shipped_tolerance_files(suite: str) -> None:
    tol = load_tolerances(suite)  # by suite name: the packaged file
    assert tol.suite == suite
    assert {"mujoco", "pymunk"} <= tol.engines()
    for name in get_suite(suite):
        limits = tol.for_cell("mujoco", name, suite)
        assert limits["status"] == "reference"
        assert any(v is not None for k, v in limits.items() if k != "status")


# ---------------------------------------------------------------------- verdicts
def test_tolerance_metrics_are_run_metrics() -> None:
    assert set(METRICS) <= NUMERIC_METRICS


def _metrics(status: Status = Status.OK, message: str = "", **values: object) -> RunMetrics:
    m: dict[str, object] = dict(
        status=status, message=message, n_blocks=1, critical_angle=0.17, duration=1.0,
        peaks=(0.5,), simulated_time=1.0, n_samples=101, wall_time=1.0, cpu_time=None,
        realtime_factor=1.0, time_to_rest=None, max_wobble=0.0, slide=0.0,
        reference_status=Status.OK, max_error=0.01, impacts_missing=0,
        impact_time_error=0.001)
    m.update(values)
    if isinstance(m["reference_status"], str):
        m["reference_status"] = Status(m["reference_status"])
    return RunMetrics(**m)  # type: ignore[arg-type]


def _cell(status: Status = Status.OK, **metrics: object) -> Cell:
    why = "why" if status != Status.OK else ""
    return Cell("free-b1-0.5", Method("mujoco"), _metrics(status, why, **metrics))


def test_evaluate() -> None:
    limits = {"status": "reference", "max_error": 0.05, "impact_time_error": 0.01,
              "peak_error": None}
    assert evaluate(_cell(), limits) == []
    assert evaluate(_cell(max_error=0.08), limits) == ["max_error 0.08 > 0.05"]
    assert evaluate(_cell(impacts_missing=2), limits) == [
        "missed 2 of the reference's first impacts"]
    fails = evaluate(_cell(Status.OVERTURNED), limits)
    assert fails == ["status overturned: why (expected ok)"]
    assert evaluate(_cell(Status.OVERTURNED, reference_status="overturned"), limits) == []
    # no reference: any completed run passes the status rule; absent metrics are not checked
    assert evaluate(_cell(reference_status=None, max_error=None), limits) == []
    assert evaluate(_cell(Status.CRASHED, reference_status=None), limits)
    assert evaluate(_cell(Status.TIMEOUT), {"status": "any"}) == []
    assert evaluate(_cell(Status.UNSTABLE), {"status": ("ok", "unstable")}) == []


def test_a_cell_whose_reference_did_not_complete_never_passes() -> None:
    """Issue 14: a crashed reference cannot vouch for a cell, unless only the status counts."""
    crashed = dict(reference_status="crashed", max_error=None, impact_time_error=None,
                   impacts_missing=None,
                   error_note="no analytic reference (crashed: eta must be in [0, 1])")
    limits = {"status": "reference", "max_error": 0.05}
    fails = evaluate(_cell(**crashed), limits)
    assert len(fails) == 1 and "eta must be in [0, 1]" in fails[0]
    assert "cannot be checked" in fails[0]
    assert evaluate(_cell(**crashed), {"status": "completed"}) == []  # status only
    assert evaluate(_cell(**crashed), {"status": "completed", "max_error": 0.05})
    # no analytic model at all (e.g. three blocks): the status is checked, as documented
    assert evaluate(_cell(reference_status=None, max_error=None), limits) == []


def test_regressions() -> None:
    reg = {"rel": 0.25, "abs": 0.002, "metrics": ["max_error", "impact_time_error"]}
    base = BaselineCell(Status.OK, {}, _metrics(max_error=0.01, impact_time_error=0.001))
    assert regressions(_cell(max_error=0.0145), base, reg) == []  # within 0.01·1.25 + 0.002
    assert regressions(_cell(max_error=0.02), base, reg) == ["max_error 0.01 → 0.02 (+100%)"]
    assert regressions(_cell(Status.CRASHED), base, reg) == ["status ok → crashed"]
    assert regressions(_cell(max_error=None), base, reg) == []


def _result() -> MatrixResult:
    mj, pm = Method("mujoco"), Method("pymunk")
    cells = {
        ("a", "mujoco"): Cell("a", mj, _metrics(max_error=0.001, wall_time=0.5)),
        ("a", "pymunk"): Cell("a", pm, _metrics(Status.CRASHED, "boom <&>", max_error=None,
                                                wall_time=0.0), outcome=FAIL,
                              reasons=["status crashed: boom <&> (expected ok)"]),
        ("b", "mujoco"): Cell("b", mj, _metrics(max_error=0.03, wall_time=1.5),
                              outcome=REGRESSION, reasons=["regression: max_error 0.01 → 0.03"]),
        ("b", "pymunk"): Cell("b", pm, _metrics(Status.UNSUPPORTED, "no stacks",
                                                max_error=None, wall_time=0.0),
                              outcome=SKIP, reasons=["no stacks"]),
    }
    return MatrixResult("smoke", ["a", "b"], ["mujoco", "pymunk"], cells, tolerances="t.toml")


def test_junit_xml_is_valid(tmp_path: Path) -> None:
    path = write_junit(_result(), tmp_path / "out" / "junit.xml")
    root = ET.parse(path).getroot()
    assert root.tag == "testsuites"
    assert (root.get("tests"), root.get("failures"), root.get("errors"),
            root.get("skipped")) == ("4", "2", "0", "1")
    suites = root.findall("testsuite")
    assert [s.get("name") for s in suites] == ["rockbench.smoke.mujoco", "rockbench.smoke.pymunk"]
    for s in suites:
        cases = s.findall("testcase")
        assert int(s.get("tests")) == len(cases)
        assert int(s.get("failures")) == len(s.findall("testcase/failure"))
        assert int(s.get("skipped")) == len(s.findall("testcase/skipped"))
        float(s.get("time"))
        for c in cases:
            assert c.get("name") in ("a", "b") and c.get("classname") == s.get("name")
            float(c.get("time"))
    fail = root.find(".//testcase[@classname='rockbench.smoke.pymunk'][@name='a']/failure")
    assert fail is not None and fail.get("type") == "tolerance"
    assert "boom <&>" in fail.get("message")  # escaped on write, intact on read
    regr = root.find(".//testcase[@classname='rockbench.smoke.mujoco'][@name='b']/failure")
    assert regr is not None and regr.get("type") == "regression"
    prop = root.find(".//testcase[@name='a']/properties/property[@name='max_error']")
    assert prop is not None and float(prop.get("value")) == 0.001


def test_plain_grid() -> None:
    result = _result()
    text = format_grid(result)
    lines = text.splitlines()
    assert lines[1].split() == ["scenario", "mujoco", "pymunk"]
    assert lines[3].split() == ["a", "PASS", "0.0010", "FAIL", "crashed"]
    assert "REGR mujoco × b: regression: max_error 0.01 → 0.03" in text
    assert "\x1b[" not in text
    assert result.exit_code == 1
    assert result.summary().startswith("4 cells: 1 passed, 1 failed, 1 regressed, 1 skipped")


def test_bad_baseline(tmp_path: Path) -> None:
    path = tmp_path / "b.json"
    path.write_text("{")
    with pytest.raises(BaselineError, match="not JSON"):
        load_baseline(path)
    path.write_text(json.dumps({"format": 2, "cells": {"x/y": {"status": "great"}}}))
    with pytest.raises(BaselineError, match="cell 'x/y'"):
        load_baseline(path)
    path.write_text("[]")
    with pytest.raises(BaselineError, match="not a rockbench baseline"):
        load_baseline(path)
    path.write_bytes(b"\xff\xfe{")
    with pytest.raises(BaselineError, match="not UTF-8"):
        load_baseline(path)
    path.write_text(json.dumps({"format": 1, "cells": {}}))
    with pytest.raises(BaselineError, match="format 1 is not supported"):
        load_baseline(path)


def test_baseline_round_trip_and_typed_fields(tmp_path: Path) -> None:
    m = _metrics(max_error=0.0123, peaks=(0.5, None), impact_time_errors=(0.001, None))
    data = baseline_data({"mujoco/a": (Status.OK, {"timestep": 0.001}, m)}, "smoke")
    path = write_baseline(data, tmp_path / "sub" / "b.json")
    base = load_baseline(path)
    assert base.suite == "smoke" and base.source == str(path)
    assert base.cells["mujoco/a"].metrics == m
    assert base.cells["mujoco/a"].settings == {"timestep": 0.001}
    # strings are never coerced into numbers: the file and the field are named
    good = path.read_text()
    for field, bad in (("max_error", "0.01"), ("n_samples", 1.5), ("peaks", ["0.5"]),
                       ("status", "fine"), ("wall_time", True)):
        doc = json.loads(good)
        doc["cells"]["mujoco/a"]["metrics"][field] = bad
        path.write_text(json.dumps(doc))
        with pytest.raises(BaselineError, match=f"b.json: cell 'mujoco/a': metrics.{field}"):
            load_baseline(path)


# ---------------------------------------------------------------------- the command
@pytest.fixture()
def tiny_suite(tmp_path: Path) -> str:
    register("fault", fault_engine.FaultEngine)
    block = Block(0.17, 0.5, 1.0, density=2670.0)
    scenarios = [
        Scenario("tiny-free", block, initial_tilt=0.5, duration=0.5, output_rate=200.0),
        Scenario("tiny-pulse", block, excitation=SinePulse(frequency=3.0, amplitude=0.008),
                 duration=0.5, output_rate=200.0),
    ]
    for sc in scenarios:
        fault_engine.reference(sc)
    yield ",".join(str(save_scenario(sc, tmp_path / f"{sc.name}.toml")) for sc in scenarios)
    unregister("fault")


def test_matrix_command_exit_codes(tmp_path: Path, tiny_suite: str,
                                   capsys: pytest.CaptureFixture[str]) -> None:
    tol = tmp_path / "tol.toml"
    tol.write_text("[defaults]\nmax_error = 0.05\n[regression]\nrel = 0.5\nabs = 0.0\n")
    common = ["matrix", "--suite", tiny_suite, "--engine", "fault", "--tolerances", str(tol),
              "--no-db", "--jobs", "2", "--set", "fault.follow=true"]
    base, junit = tmp_path / "base.json", tmp_path / "junit.xml"
    assert main([*common, "--write-baseline", str(base), "--junit", str(junit)]) == 0
    out = capsys.readouterr().out
    assert "PASS" in out and "2 cells: 2 passed" in out
    assert ET.parse(junit).getroot().get("failures") == "0"
    # coarser settings: still within tolerance, but worse than the baseline
    worse = [*common, "--set", "fault.iterations=2", "--baseline", str(base)]
    assert main(worse) == 1
    out = capsys.readouterr().out
    assert "REGR" in out and "regression: max_error" in out
    # a crash fails its cell; the other cell still runs
    crash = [*common, "--set", "fault.fault=exception", "--junit", str(junit)]
    assert main(crash) == 1
    assert "status crashed" in capsys.readouterr().out
    root = ET.parse(junit).getroot()
    assert root.get("failures") == "2" and root.get("tests") == "2"


@pytest.mark.parametrize("extra, words", [
    (["--tolerances", "missing.toml"], "cannot read tolerance file"),
    (["--baseline", "missing.json"], "cannot read baseline"),
    (["--engine", "nosuch"], "unknown engine 'nosuch'"),
    (["--set", "fault.nosuch=1"], "nosuch"),
    (["--jobs", "0"], "--jobs must be >= 1"),
    (["--scheduler", "tcp://localhost:1"], "--scheduler needs --executor dask"),
    (["--timeout", "0"], "--timeout must be a finite number of seconds > 0"),
    (["--timeout", "nan"], "--timeout must be a finite number of seconds > 0"),
    (["--timeout", "inf"], "--timeout must be a finite number of seconds > 0"),
    (["--junit", "{tmp}/regular-file/junit.xml"], "--junit"),
    (["--write-baseline", "/proc/rockbench-no/base.json"], "--write-baseline"),
    (["--write-baseline", "{tmp}"], "is a directory"),
])
def test_matrix_bad_input_exits_2(tmp_path: Path, tiny_suite: str,
                                  capsys: pytest.CaptureFixture[str], extra: list[str],
                                  words: str) -> None:
    tol = tmp_path / "tol.toml"
    tol.write_text("[defaults]\nmax_error = 0.05\n")
    (tmp_path / "regular-file").write_text("not a folder")
    extra = [x.replace("{tmp}", str(tmp_path)) for x in extra]
    args = ["matrix", "--suite", tiny_suite, "--engine", "fault", "--tolerances", str(tol),
            "--db", str(tmp_path / "x.db"), *extra]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert words in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "x.db").exists()  # refused before anything ran
    assert (tmp_path / "regular-file").read_text() == "not a folder"


def test_matrix_unknown_suite_exits_2(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["matrix", "--suite", "smok", "--tolerances", "smoke"]) == 2
    assert "did you mean 'smoke'" in capsys.readouterr().err


@pytest.mark.slow
def test_matrix_on_a_dask_local_cluster(tmp_path: Path, tiny_suite: str,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    distributed = pytest.importorskip("distributed")
    tol = tmp_path / "tol.toml"
    tol.write_text("[defaults]\nstatus = 'reference'\n")
    db = tmp_path / "d.db"
    with Store(db) as store:  # references cached: only the engine cells go to the cluster
        for path in tiny_suite.split(","):
            sc = get_scenario(path)
            store.save_reference(sc, fault_engine.reference(sc))
    # threads keep this quick; worker processes are covered in test_runner
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  dashboard_address=None) as cluster:
        code = main(["matrix", "--suite", tiny_suite, "--engine", "fault", "--tolerances",
                     str(tol), "--db", str(db), "--executor", "dask", "--scheduler",
                     cluster.scheduler_address])
    assert code == 0
    assert "2 cells: 2 passed" in capsys.readouterr().out
