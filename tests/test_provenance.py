"""Provenance: results are reused only when the code, the settings and the scenario match.

A cached analytic reference is recomputed when the analytic code changes; a resumed
run is rerun when its preset's values change, in every study that resumes; an old
store still opens and shows its runs as made by older code.
"""

from __future__ import annotations

import csv
import shutil
import sqlite3
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

import rockbench
from rockbench import provenance
from rockbench.cli import main
from rockbench.engines import register, unregister
from rockbench.method import Method
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Block, Record, Scenario, SinePulse
from rockbench.store import RunIdentity, Store, scenario_hash
from rockbench.studies.compare import CompareOptions, run_comparison
from rockbench.studies.fragility import FragilityOptions, StudyRecord, run_fragility
from rockbench.studies.matrix import run_matrix
from rockbench.studies.sweep import run_sweep
from rockbench.studies.tolerances import Tolerances

sys.path.insert(0, str(Path(__file__).parent))
import fault_engine  # noqa: E402

PACKAGE = Path(rockbench.__file__).resolve().parent
B2 = Block(0.5, 0.2, 1.0, mass=1.0)


def _copy_package(tmp_path: Path) -> Path:
    """A copy of the rockbench sources under ``tmp_path/src`` (returned: its root)."""
    root = tmp_path / "src"
    shutil.copytree(PACKAGE, root / "rockbench",
                    ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    return root


def test_each_scope_changes_with_its_own_code_only(tmp_path: Path,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    root = _copy_package(tmp_path)

    def hashes() -> dict[str, str]:
        provenance.source_hash.cache_clear()
        return {s: provenance.source_hash(s) for s in ("reference", "run", "all")}

    monkeypatch.setattr(provenance, "_ROOT", root / "rockbench")
    before = hashes()
    with (root / "rockbench" / "report" / "html.py").open("a") as f:
        f.write("\n# a change to the rendering only\n")
    after_report = hashes()
    assert after_report["reference"] == before["reference"]
    assert after_report["run"] == before["run"]
    assert after_report["all"] != before["all"]
    with (root / "rockbench" / "engines" / "base.py").open("a") as f:
        f.write("\n# a change to the engines\n")
    after_engines = hashes()
    assert after_engines["reference"] == before["reference"]
    assert after_engines["run"] != before["run"]
    with (root / "rockbench" / "analytic" / "housner.py").open("a") as f:
        f.write("\n# a change to the references\n")
    after_analytic = hashes()
    assert after_analytic["reference"] != before["reference"]
    assert after_analytic["run"] != after_engines["run"]
    provenance.source_hash.cache_clear()


def test_version_names_the_exact_code(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    out = capsys.readouterr().out.strip()
    assert out.startswith(f"rockbench {provenance.RELEASE} (code {provenance.source_hash()}")


def _compare_rows(src: Path, out: Path, db: Path) -> dict[str, dict[str, str]]:
    """``rockbench compare`` of free-b2-0.5 on pymunk with the sources at ``src``."""
    cmd = [sys.executable, "-m", "rockbench.cli", "compare", "--scenarios", "free-b2-0.5",
           "--engine", "pymunk", "--presets", "fast", "--horizon-members", "0", "--jobs", "1",
           "--out", str(out), "--db", str(db), "--quiet"]
    env = {"PYTHONPATH": str(src), "PATH": "/usr/bin:/bin", "MPLBACKEND": "Agg"}
    # run outside the checkout: ``-m`` puts the working folder first on sys.path
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=600,
                          check=False, cwd=src.parent)
    assert proc.returncode == 0, proc.stderr
    with (out / "results.csv").open() as f:
        return {row["method"]: row for row in csv.DictReader(f)}


@pytest.mark.slow
def test_a_change_to_the_analytic_code_recomputes_the_cached_reference(tmp_path: Path) -> None:
    """The issue's case: η halved in the analytic code, compare rerun in the same folder."""
    src = _copy_package(tmp_path)
    db = tmp_path / "rockbench.db"
    first = _compare_rows(src, tmp_path / "r1", db)
    housner = src / "rockbench" / "analytic" / "housner.py"
    text = housner.read_text()
    old = "eta = float(max(rock.eta, 0.0) if eta is None else eta)"
    assert old in text
    housner.write_text(text.replace(old, f"{old} * 0.5"))
    second = _compare_rows(src, tmp_path / "r2", db)
    fresh = _compare_rows(src, tmp_path / "r3", tmp_path / "fresh.db")
    for key in ("max_error", "time_to_rest"):
        assert second["pymunk"][key] == fresh["pymunk"][key], key
    assert second["analytic"]["time_to_rest"] == fresh["analytic"]["time_to_rest"]
    # the halved η stops the block far earlier, and the engine's error grows
    assert float(second["analytic"]["time_to_rest"]) < 0.5 * float(
        first["analytic"]["time_to_rest"])
    assert float(second["pymunk"]["max_error"]) > 10 * float(first["pymunk"]["max_error"])
    with Store(db) as store:
        versions = {r[0] for r in store.db.execute("SELECT version FROM refs")}
    assert len(versions) == 2  # one cached reference per code version


@pytest.fixture
def fault() -> Iterator[None]:
    register("fault", fault_engine.FaultEngine)
    yield
    unregister("fault")


TINY = Scenario("tiny", B2, initial_tilt=0.3, duration=0.2, output_rate=100.0)
INLINE = ExecutionOptions(isolate=False)


def _compare(db: Path) -> None:
    run_comparison(CompareOptions([TINY], ["fault"], presets=["fast"], db=db, resume=True,
                                  horizon_members=0, execution=INLINE))


def _matrix(db: Path) -> None:
    run_matrix([TINY], ["fault"], Tolerances.from_dict({}), settings={"fault": {"preset": "fast"}},
               db=db, resume=True, execution=INLINE, horizon_members=0)


def _sweep(db: Path) -> None:
    run_sweep(TINY, {"fault": {"iterations": [10]}}, base={"fault": {"preset": "fast"}},
              db=db, resume=True, execution=INLINE)


def _fragility(db: Path) -> None:
    t = np.linspace(0.0, 0.5, 51)
    rec = StudyRecord("pulse", Record(t, np.sin(2 * np.pi * 2 * t)), "synthetic one-sine")
    run_fragility(FragilityOptions(TINY, (rec,), levels=(0.5,), engines=["fault"],
                                   presets=["fast"], db=db, resume=True, settle=0.1,
                                   execution=INLINE))


@pytest.mark.parametrize("study", [_compare, _matrix, _sweep, _fragility],
                         ids=["compare", "matrix", "sweep", "fragility"])
def test_resume_reruns_a_run_whose_preset_changed(study, fault: None, tmp_path: Path,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    db = tmp_path / "r.db"

    def fault_rows() -> int:
        with Store(db) as store:
            return len(store.runs(engine="fault"))

    study(db)
    first = fault_rows()
    assert first >= 1
    study(db)
    assert fault_rows() == first  # the same preset: every run reused
    fast = dict(fault_engine.FaultEngine.presets["fast"], timestep=4e-3)
    monkeypatch.setitem(fault_engine.FaultEngine.presets, "fast", fast)
    study(db)
    assert fault_rows() == 2 * first  # the preset's value changed: every run again


SCHEMA_2 = """
CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT);
CREATE TABLE runs (
    id INTEGER PRIMARY KEY AUTOINCREMENT, session TEXT NOT NULL, kind TEXT NOT NULL,
    suite TEXT NOT NULL DEFAULT '', scenario TEXT NOT NULL, scenario_hash TEXT NOT NULL,
    engine TEXT NOT NULL, engine_version TEXT NOT NULL, settings TEXT NOT NULL,
    settings_key TEXT NOT NULL, effective_settings TEXT NOT NULL, status TEXT NOT NULL,
    message TEXT NOT NULL, metrics TEXT NOT NULL, wall_time REAL, machine TEXT NOT NULL,
    timestamp TEXT NOT NULL, rockbench_version TEXT NOT NULL,
    method TEXT NOT NULL DEFAULT '', preset TEXT NOT NULL DEFAULT '',
    variation TEXT NOT NULL DEFAULT '', cpu_time REAL, trajectory TEXT NOT NULL DEFAULT ''
);
CREATE TABLE refs (
    scenario_hash TEXT NOT NULL, version TEXT NOT NULL, scenario TEXT NOT NULL,
    status TEXT NOT NULL, message TEXT NOT NULL, wall_time REAL, data BLOB NOT NULL,
    meta TEXT NOT NULL, timestamp TEXT NOT NULL, PRIMARY KEY (scenario_hash, version)
);
"""


def test_an_old_store_opens_and_shows_its_runs_as_made_by_older_code(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    db = tmp_path / "old.db"
    sc = Scenario("pulse", B2, excitation=SinePulse(2.0, 0.01), duration=0.5)
    with sqlite3.connect(db) as con:
        con.executescript(SCHEMA_2)
        con.execute("INSERT INTO meta VALUES ('schema', '2')")
        con.execute(
            "INSERT INTO runs (session, kind, scenario, scenario_hash, engine, engine_version, "
            "settings, settings_key, effective_settings, status, message, metrics, "
            "wall_time, machine, timestamp, rockbench_version, method, preset) VALUES "
            "('s', 'compare', 'pulse', ?, 'pymunk', '7.3.1', '{\"preset\": \"fast\"}', 'k', "
            "'{}', 'ok', '', '{}', 0.5, 'm', '2026-11-01T00:00:00+00:00', '0.1.0', 'pymunk', "
            "'fast')", (scenario_hash(sc),))
    con.close()
    with Store(db) as store:
        (old,) = store.runs()
        assert old.code_version == "" and "older code" in old.made_by
        assert "0.1.0" in old.made_by
        ident = RunIdentity.of(sc, Method.of("pymunk", {"preset": "fast"}),
                               engine_version="7.3.1", resolved={})
        assert store.find(ident) is None  # never reused by this code
    assert main(["history", "--db", str(db)]) == 0
    assert "0.1.0 (older code)" in capsys.readouterr().out
