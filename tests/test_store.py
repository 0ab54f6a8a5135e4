"""Results store: runs appended as they finish, reference cache, resume after an interruption."""

from __future__ import annotations

import dataclasses
import importlib
import sqlite3
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import rockbench
from rockbench import provenance
from rockbench.analytic import critical_angle
from rockbench.campaign import CampaignOptions, PlannedRun, run_campaign
from rockbench.campaign.predictability import DEFAULT_MEMBERS
from rockbench.cli import main
from rockbench.engines import register, unregister
from rockbench.evaluation import RunMetrics, evaluate_run
from rockbench.method import Method
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Block, Scenario, SinePulse, save_scenario
from rockbench.store import (
    RunIdentity,
    Store,
    StoreError,
    jsonable,
    scenario_hash,
    settings_key,
)
from rockbench.studies.matrix import run_matrix
from rockbench.studies.tolerances import Tolerances
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


INLINE = ExecutionOptions(isolate=False)


def _identity(scenario: Scenario, method: Method) -> RunIdentity:
    """The identity of running ``method`` on ``scenario`` with this code."""
    resolved = fault_engine.FaultEngine.resolve_settings(method.settings).to_dict()
    return RunIdentity.of(scenario, method, engine_version="0.0-test", resolved=resolved)


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
    fine, coarse = Method.of("fault", {"timestep": 0.001}), Method.of("fault", {"timestep": 0.002})
    ok = evaluate_run(TINY[0], _traj(), None)
    ident = _identity(TINY[0], fine)
    with Store(db, session="s1") as store:
        rid = store.record(TINY[0], fine, _traj(), ok, ident, kind="matrix", suite="smoke")
        crashed = _traj(Status.CRASHED)
        store.record(TINY[0], coarse, crashed, evaluate_run(TINY[0], crashed, None),
                     _identity(TINY[0], coarse), kind="sweep")
        assert rid == 1 and len(store) == 2
    with Store(db) as store:  # reopened: everything is there
        rec = store.find(ident)
        assert rec is not None
        assert rec.metrics == ok  # the typed metrics come back as they went in
        assert rec.metrics.peaks == pytest.approx(
            (np.sin(0.4) / critical_angle(TINY[0].geometry),))
        assert rec.status is Status.OK and rec.suite == "smoke" and rec.session == "s1"
        assert rec.engine_version == "0.0-test"
        assert rec.rockbench_version == rockbench.__version__
        assert rec.code_version == provenance.code_version("run") == rec.made_by
        assert rec.effective_settings == {"timestep": 0.001}
        assert rec.machine and rec.timestamp.endswith("+00:00")
        # every part of the identity must match
        for other in (dataclasses.replace(ident, engine_version="other"),
                      dataclasses.replace(ident, code_version="0.0.0+other"),
                      dataclasses.replace(ident, variation="halved"),
                      _identity(TINY[1], fine)):
            assert store.find(other) is None, other
        assert [r.kind for r in store.runs(scenario="tiny-0")] == ["matrix", "sweep"]
        assert [r.status for r in store.runs(kind="sweep")] == [Status.CRASHED]


def test_a_reader_does_not_hold_up_a_study_writing_to_the_store(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """WAL: ``rockbench history`` reads a store while a study appends runs to it."""
    db = tmp_path / "r.db"
    fine, coarse = Method.of("fault", {"timestep": 0.001}), Method.of("fault", {"timestep": 0.002})
    ok = evaluate_run(TINY[0], _traj(), None)
    with Store(db) as writer:
        assert writer.db.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
        writer.record(TINY[0], fine, _traj(), ok, _identity(TINY[0], fine), kind="matrix")
        with Store(db, create=False) as reader:
            reader.db.execute("BEGIN")  # a read in progress
            assert reader.db.execute("SELECT COUNT(*) FROM runs").fetchone()[0] == 1
            start = time.perf_counter()
            writer.record(TINY[0], coarse, _traj(), ok, _identity(TINY[0], coarse),
                          kind="matrix")
            assert time.perf_counter() - start < 5.0  # not blocked by the reader
            # the read sees the store as it began; the next one sees the new run
            assert reader.db.execute("SELECT COUNT(*) FROM runs").fetchone()[0] == 1
            reader.db.commit()
            assert len(reader) == 2
        assert main(["history", "--db", str(db)]) == 0  # the writer still holds it open
        assert "tiny-0" in capsys.readouterr().out


def _untimed(m: RunMetrics) -> RunMetrics:
    """``m`` without what the clock measures (it differs from one run to the next)."""
    return dataclasses.replace(m, wall_time=0.0, cpu_time=None, realtime_factor=None)


def test_a_campaign_records_the_identity_of_each_run(tmp_path: Path) -> None:
    method = Method.of("fault", {"follow": True})
    plan = [PlannedRun(TINY[0], method)]
    campaign = run_campaign(plan, CampaignOptions(kind="compare", db=tmp_path / "r.db",
                                                  execution=INLINE))
    (res,) = campaign.results
    m = res.metrics
    with Store(tmp_path / "r.db") as store:
        (rec,) = store.runs()
        assert store.find(_identity(TINY[0], method)) == rec
    # measured against the analytic reference it follows with a relative error of
    # 10 · timestep / iterations = 1e-3: from the release at 0.2 λ, 2e-4 λ
    assert m.max_error == pytest.approx(0.2 * 1e-3, rel=1e-9)
    assert m.reference_status is Status.OK
    assert rec.kind == "compare" and rec.metrics == m and rec.method == "fault"
    assert m.scenario_hash == scenario_hash(TINY[0])
    assert m.settings_hash == _identity(TINY[0], method).resolved_key  # the resolved knobs
    assert not res.reused
    no_store = run_campaign(plan, CampaignOptions(kind="compare", execution=INLINE))
    assert _untimed(no_store.results[0].metrics) == _untimed(m)  # measured alike, no store


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
    before = bad.read_bytes()
    with pytest.raises(StoreError, match="not a rockbench results store"):
        Store(bad)
    with pytest.raises(StoreError, match="not a rockbench results store"):
        Store(bad, create=False)
    assert bad.read_bytes() == before  # refused, never modified


def test_a_foreign_sqlite_file_is_refused_and_left_alone(tmp_path: Path) -> None:
    other = tmp_path / "other.db"
    with sqlite3.connect(other) as con:
        con.execute("CREATE TABLE customers (name TEXT)")
        con.execute("INSERT INTO customers VALUES ('Ada')")
    con.close()
    before = other.read_bytes()
    for create in (True, False):
        with pytest.raises(StoreError, match="another application"):
            Store(other, create=create)
    assert other.read_bytes() == before
    assert not Path(f"{other}-wal").exists()


def test_a_schema_1_store_is_upgraded_in_place(tmp_path: Path) -> None:
    db = tmp_path / "old.db"
    with sqlite3.connect(db) as con:
        con.executescript(SCHEMA_1)
        con.execute("INSERT INTO meta VALUES ('schema', '1')")
        con.execute(
            "INSERT INTO runs (session, kind, suite, scenario, scenario_hash, engine, "
            "engine_version, settings, settings_key, effective_settings, status, message, "
            "metrics, wall_time, machine, timestamp, rockbench_version) VALUES "
            "('s', 'matrix', '', 'tiny-0', ?, 'fault', '0.0-test', '{}', ?, '{}', 'ok', '', "
            "'{\"max_error\": 0.01}', 0.5, 'm', '2026-11-01T00:00:00+00:00', '0.1.0')",
            (scenario_hash(TINY[0]), settings_key({})))
    con.close()
    with Store(db) as store:
        (old,) = store.runs()
        assert old.status is Status.OK and old.metrics is None  # schema-1 metrics: a dict
        assert old.method == "fault" and old.cpu_time is None
        assert old.code_version == ""  # made by older code: never reused
        ident = _identity(TINY[0], Method("fault"))
        assert store.find(ident) is None
        m = evaluate_run(TINY[0], _traj(), None)
        store.record(TINY[0], Method("fault"), _traj(), m, ident, kind="matrix")
        assert store.find(ident).metrics == m
    with sqlite3.connect(db) as con:
        assert con.execute("SELECT value FROM meta WHERE key='schema'").fetchone()[0] == "3"
        assert con.execute("PRAGMA application_id").fetchone()[0] != 0
    con.close()


def test_history_refuses_empty_and_foreign_files(tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    empty = tmp_path / "empty.db"
    empty.touch()
    assert main(["history", "--db", str(empty)]) == 2
    err = capsys.readouterr().err
    assert "empty file" in err and len(err.strip().splitlines()) == 1
    assert empty.read_bytes() == b""  # not turned into a rockbench store
    other = tmp_path / "other.db"
    with sqlite3.connect(other) as con:
        con.execute("CREATE TABLE t (x)")
    con.close()
    before = other.read_bytes()
    assert main(["history", "--db", str(other)]) == 2
    assert "another application" in capsys.readouterr().err
    assert other.read_bytes() == before


SCHEMA_1 = """
CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT);
CREATE TABLE runs (
    id INTEGER PRIMARY KEY AUTOINCREMENT, session TEXT NOT NULL, kind TEXT NOT NULL,
    suite TEXT NOT NULL DEFAULT '', scenario TEXT NOT NULL, scenario_hash TEXT NOT NULL,
    engine TEXT NOT NULL, engine_version TEXT NOT NULL, settings TEXT NOT NULL,
    settings_key TEXT NOT NULL, effective_settings TEXT NOT NULL, status TEXT NOT NULL,
    message TEXT NOT NULL, metrics TEXT NOT NULL, wall_time REAL, machine TEXT NOT NULL,
    timestamp TEXT NOT NULL, rockbench_version TEXT NOT NULL
);
"""


def test_resume_after_an_interrupted_matrix(tmp_path: Path) -> None:
    db = tmp_path / "r.db"
    tol = Tolerances.from_dict({"defaults": {"max_error": 0.05}})
    done: list[str] = []

    def interrupt(cell: object) -> None:
        done.append(cell.scenario)  # type: ignore[attr-defined]
        if len(done) == 2:
            raise KeyboardInterrupt

    def stored() -> int:
        with Store(db) as store:
            return len(store)

    with pytest.raises(KeyboardInterrupt):
        run_matrix(TINY, ["fault"], tol, settings={"fault": {"follow": True}}, db=db,
                   execution=ExecutionOptions(jobs=1, timeout=30), on_cell=interrupt)
    with Store(db) as store:
        assert len(store) == 2  # nothing finished was lost
        assert len(store.runs(kind="matrix")) == 2
    reused: list[bool] = []
    result = run_matrix(TINY, ["fault"], tol, settings={"fault": {"follow": True}},
                        db=db, resume=True, execution=ExecutionOptions(jobs=2, timeout=30),
                        on_cell=lambda c: reused.append(c.reused))
    assert sorted(reused) == [False, True, True]
    assert result.exit_code == 0 and len(result.cells) == 3
    assert stored() == 3
    # other settings are another cell: not reused
    run_matrix(TINY[:1], ["fault"], tol, settings={"fault": {"follow": True,
                                                             "iterations": 20}},
               db=db, resume=True, execution=ExecutionOptions(jobs=1, timeout=30))
    assert stored() == 4


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
        # each scenario's reference and its predictability ensemble, cached once
        assert con.execute("SELECT COUNT(*) FROM refs").fetchone()[0] == 2 * (1 + DEFAULT_MEMBERS)
    assert main(["history", "--db", db]) == 0
    assert "tiny-0" in capsys.readouterr().out
    assert main(["history", "tiny-1", "--db", db, "--metric", "max_error"]) == 0
    out = capsys.readouterr().out
    assert "tiny-1 on fault" in out and "max_error" in out
    assert main(["history", "--db", str(tmp_path / "missing.db")]) == 2
    # runs of any study show, compare included
    run_campaign([PlannedRun(TINY[0], Method.of("fault", {"follow": True}))],
                 CampaignOptions(kind="compare", db=Path(db), execution=INLINE))
    capsys.readouterr()
    assert main(["history", "tiny-0", "--db", db, "--kind", "compare"]) == 0
    out = capsys.readouterr().out
    assert "tiny-0 on fault: 1 run(s)" in out and "compare" in out
    assert main(["history", "--db", db]) == 0
    assert "compare,matrix" in capsys.readouterr().out


def test_stored_metrics_are_type_checked() -> None:
    """RunMetrics read back from JSON (store rows, baselines) are checked, never coerced."""
    from rockbench.evaluation import RunMetrics

    good = {"status": "ok", "message": "", "n_blocks": 1, "critical_angle": 0.2,
            "duration": 1.0, "peaks": [0.5], "simulated_time": 1.0, "n_samples": 11,
            "wall_time": 0.1, "cpu_time": None, "realtime_factor": 10.0,
            "time_to_rest": None, "max_wobble": 0.0, "slide": None}
    m = RunMetrics.from_json(good)
    assert m.peaks == (0.5,) and m.status is Status.OK
    assert RunMetrics.from_json(m.to_json()) == m
    for key, bad, needle in (("peaks", ["0.5"], "peaks[0] must be a number"),
                             ("wall_time", "0.1", "wall_time must be a number"),
                             ("n_samples", True, "n_samples must be an integer"),
                             ("status", "fine", "status must be one of")):
        with pytest.raises(ValueError, match=needle.replace("[", r"\[")):
            RunMetrics.from_json({**good, key: bad})
    with pytest.raises(ValueError, match="critical_angle is missing"):
        RunMetrics.from_json({k: v for k, v in good.items() if k != "critical_angle"})
