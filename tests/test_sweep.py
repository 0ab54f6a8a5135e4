"""Settings sweeps and tuning: grid parsing, a small sweep's table and images, presets."""

from __future__ import annotations

import csv
import importlib
import math
import sys
from pathlib import Path

import matplotlib.image as mpimg
import pytest

from rockbench.cli import main
from rockbench.engines import SettingsError, register, unregister
from rockbench.presets import layered_settings, load_settings_file, write_settings_file
from rockbench.report.sweep_figures import pareto_plot, stability_map
from rockbench.report.sweep_tables import write_table
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Block, Scenario, SinePulse, save_scenario
from rockbench.studies.pareto import pareto_front
from rockbench.studies.sweep import (
    SweepError,
    cheapest,
    efficient_points,
    parse_grid,
    run_sweep,
)
from rockbench.studies.tune import tunable_knobs, tune
from rockbench.trajectory import Status

EXEC = ExecutionOptions(jobs=2, timeout=30)

sys.path.insert(0, str(Path(__file__).parent))
fault_engine = importlib.import_module("fault_engine")

SCENARIO = Scenario("tiny-pulse", Block(0.17, 0.5, 1.0, density=2670.0),
                    excitation=SinePulse(frequency=3.0, amplitude=0.008), duration=0.6,
                    output_rate=100.0)
#: follows the reference with error ∝ timestep / iterations; NaN above 5 ms; crash below 2 its
BASE = {"follow": True, "unstable_dt": 0.005, "crash_below": 2, "at": 0.2}


@pytest.fixture(autouse=True)
def fault() -> object:
    register("fault", fault_engine.FaultEngine)
    fault_engine.reference(SCENARIO)
    yield
    unregister("fault")


def test_parse_grid() -> None:
    grid = parse_grid(["fault.timestep=1e-3, 2e-3,1e-3", "fault.iterations=5,10"], ["fault"])
    assert grid == {"fault": {"timestep": [0.001, 0.002], "iterations": [5, 10]}}
    assert parse_grid([], ["fault"]) == {"fault": {}}
    for bad, words in [("fault.timestep", "expects engine.knob"),
                       ("timestep=1", "expects engine.knob"),
                       ("fault.timestep=", "expects engine.knob"),
                       ("mujoco.timestep=1", "not selected")]:
        with pytest.raises(SweepError, match=words):
            parse_grid([bad], ["fault"])
    with pytest.raises(SweepError, match="twice"):
        parse_grid(["fault.iterations=1", "fault.iterations=2"], ["fault"])
    with pytest.raises(SettingsError):
        parse_grid(["fault.iterations=many"], ["fault"])
    with pytest.raises(SettingsError):
        parse_grid(["fault.nosuch=1"], ["fault"])


def test_small_sweep_table_and_images(tmp_path: Path) -> None:
    grid = parse_grid(["fault.timestep=0.01,0.005,0.0025", "fault.iterations=1,4,16"],
                      ["fault"])
    result = run_sweep(SCENARIO, grid, base={"fault": BASE}, execution=EXEC)
    assert len(result.points) == 9
    by = {(p.knobs["timestep"], p.knobs["iterations"]): p for p in result.points}
    assert by[(0.01, 4)].status is Status.UNSTABLE  # beyond the stability limit
    assert by[(0.005, 1)].status is Status.CRASHED
    ok = by[(0.0025, 16)]
    assert ok.status is Status.OK and ok.kind() == "ok" and not ok.drift
    peak = max(abs(p) for p in ok.metrics.peaks)
    assert ok.error() == pytest.approx(10 * 0.0025 / 16 * peak, rel=0.05)
    assert by[(0.005, 4)].error() > ok.error()
    # the cheapest point meeting the target and the Pareto front
    target = 0.004
    best = cheapest(result.points, target)
    assert best is not None and best.meets(target)
    assert all(p.cost >= best.cost for p in result.points if p.meets(target))
    front = efficient_points(result.points)
    assert front and all(a.cost <= b.cost and a.error() > b.error()
                         for a, b in zip(front, front[1:], strict=False))
    assert all(p.kind() == "ok" for p in front)
    # no point off the front beats a front point in both cost and error
    assert not any(q.cost <= p.cost and q.error() < p.error()
                   for p in front for q in result.points if q.kind() == "ok")
    # the cost is the CPU time of the run where it was measured
    assert all(p.cost == p.metrics.cpu_time for p in result.points
               if p.metrics.cpu_time)
    # table
    table = write_table(result, tmp_path / "sweep.csv")
    rows = list(csv.DictReader(table.open()))
    assert len(rows) == 9
    assert {r["status"] for r in rows} == {"ok", "unstable", "crashed"}
    assert {"engine", "timestep", "iterations", "max_error", "cost", "wall_time", "cpu_time",
            "drift", "message"} <= set(rows[0])
    # images
    smap = stability_map(result, "fault", tmp_path / "stab.png", target)
    pplot = pareto_plot(result, tmp_path / "pareto.png", target)
    for png in (smap, pplot):
        img = mpimg.imread(png)
        assert img.shape[0] > 300 and img.shape[1] > 400
        assert img[..., :3].std() > 0.05  # not blank


def test_pareto_front() -> None:
    pts = [(1.0, 1.0), (2.0, 0.5), (3.0, 0.7), (0.5, 2.0), (float("nan"), 0.1), (2.0, 0.5)]
    front = pareto_front(range(len(pts)), cost=lambda i: pts[i][0], error=lambda i: pts[i][1])
    assert front == [3, 0, 1]  # cheapest first; the NaN and the duplicate take no part


def test_sweep_command(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = save_scenario(SCENARIO, tmp_path / "tiny.toml")
    out = tmp_path / "sw"
    code = main(["sweep", str(path), "--engine", "fault", "--set", "fault.follow=true",
                 "--grid", "fault.timestep=0.01,0.005", "--grid", "fault.iterations=2,8",
                 "--target", "0.01", "--out", str(out), "--db", str(tmp_path / "s.db"),
                 "--jobs", "2"])
    assert code == 0
    text = capsys.readouterr().out
    assert "cheapest settings with max_error ≤ 0.01" in text
    assert "--set fault.timestep=" in text
    for name in ("sweep.csv", "stability-fault.png", "pareto.png"):
        assert (out / name).stat().st_size > 1000 or name == "sweep.csv"
    assert main(["sweep", str(path), "--engine", "fault", "--grid", "fault=1"]) == 2
    assert "--grid expects" in capsys.readouterr().err


def test_sweep_folder_is_named_by_the_slug_of_the_scenario(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 14: a scenario name is not a path (no writing outside the working folder)."""
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    path = save_scenario(SCENARIO.replace(name="x/../../elsewhere"), tmp_path / "evil.toml")
    assert main(["sweep", str(path), "--engine", "fault", "--set", "fault.follow=true",
                 "--no-db", "--jobs", "1"]) == 0
    assert [p.name for p in work.iterdir()] == ["sweep-x-..-..-elsewhere"]
    assert (work / "sweep-x-..-..-elsewhere" / "sweep.csv").is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["evil.toml", "work"]
    (tmp_path / "file").write_text("x")
    assert main(["sweep", str(path), "--engine", "fault", "--no-db",
                 "--out", str(tmp_path / "file" / "sub")]) == 2


def test_settings_files(tmp_path: Path) -> None:
    path = write_settings_file(tmp_path / "p.toml", {"fault": {"timestep": 0.002,
                                                               "follow": True}},
                               comment=["made by a test"])
    assert path.read_text().startswith("# made by a test\n")
    assert load_settings_file(path) == {"fault": {"timestep": 0.002, "follow": True}}
    merged = layered_settings(["fault"], settings_file=path,
                              set_options=["fault.timestep=0.004"])["fault"]
    assert merged == {"follow": True, "timestep": 0.004}  # typed; --set wins over the file
    # the file wins over --preset; engines it names but not selected are ignored
    assert layered_settings(["fault"], preset="fast", settings_file=path)["fault"] == {
        "preset": "fast", "timestep": 0.002, "follow": True}
    assert layered_settings([], settings_file=path) == {}
    bad = tmp_path / "bad.toml"
    bad.write_text("timestep = 1\n")
    with pytest.raises(SettingsError, match="must be a table"):
        load_settings_file(bad)
    bad.write_text("[fault]\nnosuch = 1\n")
    with pytest.raises(SettingsError, match="bad.toml"):
        layered_settings(["fault"], settings_file=bad)


@pytest.mark.slow
def test_tune_finds_the_cheapest_settings_and_writes_a_preset(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert tunable_knobs("fault") == {"timestep": "smaller", "iterations": "larger"}
    res = tune(SCENARIO, "fault", 0.01, base={"follow": True}, budget=12, execution=EXEC)
    assert res.best is not None and res.best.meets(0.01)
    assert len(res.evaluated) <= 12
    assert not math.isnan(res.best.cost)
    with pytest.raises(SweepError, match="no knob 'bogus'"):
        tune(SCENARIO, "fault", 0.01, knobs=["bogus"])
    # through the command: the preset it writes is accepted by other commands
    path = save_scenario(SCENARIO, tmp_path / "tiny.toml")
    preset = tmp_path / "tuned.toml"
    code = main(["tune", str(path), "--engine", "fault", "--set", "fault.follow=true",
                 "--target", "0.01", "--budget", "8", "--out", str(preset), "--no-db",
                 "--knob", "iterations"])
    assert code == 0
    settings = load_settings_file(preset)["fault"]
    assert settings["follow"] is True and "iterations" in settings
    assert "wrote" in capsys.readouterr().out
    tol = tmp_path / "tol.toml"
    tol.write_text("[defaults]\nmax_error = 0.01\n")
    assert main(["matrix", "--suite", str(path), "--engine", "fault", "--settings",
                 str(preset), "--tolerances", str(tol), "--no-db"]) == 0
    # an unreachable target: exit 1, nothing written
    assert main(["tune", str(path), "--engine", "fault", "--target", "1e-9", "--budget", "3",
                 "--out", str(tmp_path / "never.toml"), "--no-db"]) == 1
    assert not (tmp_path / "never.toml").exists()
