"""Results store: runs appended as they finish, reference cache, resume after an interruption."""

from __future__ import annotations

import importlib
import sqlite3
import sys
from pathlib import Path

import numpy as np
import pytest

import rockbench
from rockbench.cli import main
from rockbench.engines import register, unregister
from rockbench.report.matrix import run_matrix
from rockbench.report.tolerances import Tolerances
from rockbench.scenarios import Block, Scenario, SinePulse, save_scenario
from rockbench.store import Store, StoreError, jsonable, scenario_hash, settings_key
from rockbench.trajectory import Status, Trajectory

sys.path.insert(0, str(Path(__file__).parent))
fault_engine = importlib.import_module("fault_engine")

BLOCK = Block(0.17, 0.5, 1.0, density=2670.0)
TINY = [Scenario(f"tiny-{i}", BLOCK, initial_tilt=0.2 + 0.2 * i, duration=0.4,
                 output_rate=200.0) for i in range(3)]


@pytest.fixture(autouse=True)
def fault() -> object:
    register("fault", fault_engine.FaultEngine)
    for sc in TINY:  # warm the analytic reference in the parent (children inherit it)
        fault_engine.reference(sc)
    yield
    unregister("fault")


def _traj(status: Status = Status.OK) -> Trajectory:
    t = np.arange(5) / 10.0
    return Trajectory(t=t, theta=np.sin(t), status=status, engine="fault",
                      engine_version="0.0-test", settings={"timestep": 0.001}, wall_time=0.25,
                      impacts=np.array([0.1, 0.3]))


def test_hashes() -> None:
    a = TINY[0]
    assert scenario_hash(a) == scenario_hash(a.replace(name="renamed", description="x"))
    assert scenario_hash(a) != scenario_hash(a.replace(duration=0.5))
    pulse = a.replace(excitation=SinePulse(frequency=3.0, amplitude=0.008))
    assert scenario_hash(pulse) != scenario_hash(pulse.replace(
        excitation=SinePulse(frequency=3.0, amplitude=0.009)))
    assert settings_key({"a": 1, "b": 2.0}) == settings_key({"b": 2.0, "a": 1})
    assert settings_key({"a": 1}) != settings_key({"a": 2})
    assert jsonable({"x": np.float64("nan"), "y": (np.int64(2), np.inf)}) == {
        "x": None, "y": [2, None]}


def test_record_find_and_runs(tmp_path: Path) -> None:
    db = tmp_path / "sub" / "r.db"
    with Store(db, session="s1") as store:
        rid = store.record(TINY[0], "fault", {"timestep": 0.001}, _traj(),
                           {"max_error": 0.01, "peak_ratio": [np.float64(0.5)],
                            "bad": float("nan")}, kind="matrix", suite="smoke")
        store.record(TINY[0], "fault", {"timestep": 0.002}, _traj(Status.CRASHED), {},
                     kind="sweep")
        assert rid == 1 and len(store) == 2
    with Store(db) as store:  # reopened: everything is there
        rec = store.find(TINY[0], "fault", {"timestep": 0.001})
        assert rec is not None
        assert rec.metrics == {"max_error": 0.01, "peak_ratio": [0.5], "bad": None}
        assert rec.status is Status.OK and rec.suite == "smoke" and rec.session == "s1"
        assert rec.engine_version == "0.0-test"
        assert rec.rockbench_version == rockbench.__version__
        assert rec.effective_settings == {"timestep": 0.001}
        assert rec.machine and rec.timestamp.endswith("+00:00")
        assert store.find(TINY[0], "fault", {"timestep": 0.001},
                          engine_version="other") is None
        assert store.find(TINY[1], "fault", {"timestep": 0.001}) is None
        assert [r.kind for r in store.runs(scenario="tiny-0")] == ["matrix", "sweep"]
        assert [r.status for r in store.runs(kind="sweep")] == [Status.CRASHED]


def test_reference_cache_round_trip(tmp_path: Path) -> None:
    with Store(tmp_path / "r.db") as store:
        assert store.reference(TINY[0]) is None
        store.save_reference(TINY[0], _traj())
        store.save_reference(TINY[1], _traj(Status.CRASHED))  # not cached
        ref = store.reference(TINY[0].replace(name="same-content"))
        assert ref is not None and store.reference(TINY[1]) is None
        np.testing.assert_allclose(ref.theta[:, 0], np.sin(np.arange(5) / 10.0))
        np.testing.assert_allclose(ref.impacts, [0.1, 0.3])
        assert ref.scenario == "same-content"


def test_not_a_database(tmp_path: Path) -> None:
    bad = tmp_path / "bad.db"
    bad.write_text("this is not sqlite " * 100)
    with pytest.raises(StoreError, match="not a usable results database"):
        Store(bad)


def test_resume_after_an_interrupted_matrix(tmp_path: Path) -> None:
    db = tmp_path / "r.db"
    tol = Tolerances.from_dict({"defaults": {"max_error": 0.05}})
    done: list[str] = []

    def interrupt(cell: object) -> None:
        done.append(cell.scenario)  # type: ignore[attr-defined]
        if len(done) == 2:
            raise KeyboardInterrupt

    with Store(db) as store, pytest.raises(KeyboardInterrupt):
        run_matrix(TINY, ["fault"], tol, settings={"fault": {"follow": True}}, store=store,
                   n_jobs=1, timeout=30, on_cell=interrupt)
    with Store(db) as store:
        assert len(store) == 2  # nothing finished was lost
        assert len(store.runs(kind="matrix")) == 2
        reused: list[bool] = []
        result = run_matrix(TINY, ["fault"], tol, settings={"fault": {"follow": True}},
                            store=store, resume=True, n_jobs=2, timeout=30,
                            on_cell=lambda c: reused.append(c.reused))
        assert sorted(reused) == [False, True, True]
        assert result.exit_code == 0 and len(result.cells) == 3
        assert len(store) == 3
        # other settings are another cell: not reused
        run_matrix(TINY[:1], ["fault"], tol, settings={"fault": {"follow": True,
                                                                 "iterations": 20}},
                   store=store, resume=True, n_jobs=1, timeout=30)
        assert len(store) == 4


def test_resume_and_history_through_the_cli(tmp_path: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    files = [str(save_scenario(sc, tmp_path / f"{sc.name}.toml")) for sc in TINY[:2]]
    tol = tmp_path / "tol.toml"
    tol.write_text("[defaults]\nmax_error = 0.05\n")
    db = str(tmp_path / "cli.db")
    args = ["matrix", "--suite", ",".join(files), "--engine", "fault", "--set",
            "fault.follow=true", "--tolerances", str(tol), "--db", db, "--jobs", "2"]
    assert main(args) == 0
    assert main([*args, "--resume"]) == 0
    out = capsys.readouterr()
    assert "(stored)" in out.err and "PASS" in out.out
    with sqlite3.connect(db) as con:
        assert con.execute("SELECT COUNT(*) FROM runs").fetchone()[0] == 2
        assert con.execute("SELECT COUNT(*) FROM refs").fetchone()[0] == 2
    assert main(["history", "--db", db]) == 0
    assert "tiny-0" in capsys.readouterr().out
    assert main(["history", "tiny-1", "--db", db, "--metric", "max_error"]) == 0
    out = capsys.readouterr().out
    assert "tiny-1 on fault" in out and "max_error" in out
    assert main(["history", "--db", str(tmp_path / "missing.db")]) == 2
