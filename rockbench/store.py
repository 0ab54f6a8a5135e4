"""Results store: every run appended to a SQLite database as it finishes.

One row per run in table ``runs``: scenario name and content hash, engine,
engine version, requested and effective settings, status, message, metrics
(JSON), wall time, machine, timestamp (UTC, ISO 8601), rockbench version, the
command that produced it (``kind``: matrix, sweep, tune) and a session id.
Rows are committed one by one, so an interrupted matrix loses nothing and
``--resume`` can skip cells already done (:meth:`Store.find`).

Table ``refs`` caches analytic reference trajectories by scenario content hash
and rockbench version (the analytic models are versioned with rockbench).

The database is opened in WAL mode; it is safe to read (``rockbench history``)
while a matrix is writing.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import platform
import socket
import sqlite3
import uuid
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import numpy as np

import rockbench
from rockbench.errors import RockbenchError
from rockbench.scenarios import Scenario, scenario_to_dict
from rockbench.trajectory import Status, Trajectory

__all__ = ["Store", "RunRecord", "StoreError", "scenario_hash", "settings_key", "machine",
           "jsonable", "DEFAULT_DB"]

#: Default database file (in the current directory).
DEFAULT_DB = "rockbench.db"
SCHEMA_VERSION = 1

_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT);
CREATE TABLE IF NOT EXISTS runs (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    session TEXT NOT NULL,
    kind TEXT NOT NULL,
    suite TEXT NOT NULL DEFAULT '',
    scenario TEXT NOT NULL,
    scenario_hash TEXT NOT NULL,
    engine TEXT NOT NULL,
    engine_version TEXT NOT NULL,
    settings TEXT NOT NULL,
    settings_key TEXT NOT NULL,
    effective_settings TEXT NOT NULL,
    status TEXT NOT NULL,
    message TEXT NOT NULL,
    metrics TEXT NOT NULL,
    wall_time REAL,
    machine TEXT NOT NULL,
    timestamp TEXT NOT NULL,
    rockbench_version TEXT NOT NULL
);
CREATE INDEX IF NOT EXISTS runs_cell ON runs (scenario_hash, engine, settings_key);
CREATE INDEX IF NOT EXISTS runs_name ON runs (scenario, engine);
CREATE TABLE IF NOT EXISTS refs (
    scenario_hash TEXT NOT NULL,
    version TEXT NOT NULL,
    scenario TEXT NOT NULL,
    status TEXT NOT NULL,
    message TEXT NOT NULL,
    wall_time REAL,
    data BLOB NOT NULL,
    meta TEXT NOT NULL,
    timestamp TEXT NOT NULL,
    PRIMARY KEY (scenario_hash, version)
);
"""


class StoreError(RockbenchError):
    """The results database cannot be opened or is not a rockbench store."""


def _canonical(obj: Any) -> str:
    return json.dumps(jsonable(obj), sort_keys=True, separators=(",", ":"))


def jsonable(obj: Any) -> Any:
    """``obj`` with NumPy values, tuples and non-finite floats made JSON-safe (NaN → None)."""
    if isinstance(obj, Mapping):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, np.ndarray)):
        return [jsonable(v) for v in (obj.tolist() if isinstance(obj, np.ndarray) else obj)]
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, Status):
        return obj.value
    return obj


def scenario_hash(scenario: Scenario) -> str:
    """Content hash of a scenario: everything simulated, not its name or description.

    Records are hashed by their samples, not their file name.
    """
    data = scenario_to_dict(scenario)
    data.pop("name", None)
    data.pop("description", None)
    h = hashlib.sha256(_canonical(data).encode())
    exc = scenario.excitation
    if not exc.is_free:
        t = np.linspace(0.0, scenario.duration, 2001)
        h.update(np.round(np.asarray(exc.acceleration(t), float), 12).tobytes())
    return h.hexdigest()[:16]


def settings_key(settings: Mapping[str, Any]) -> str:
    """Hash of the requested settings mapping (order-independent)."""
    return hashlib.sha256(_canonical(dict(settings)).encode()).hexdigest()[:16]


def machine() -> str:
    """A short description of this machine: host, OS, CPU architecture, Python."""
    return (f"{socket.gethostname()} {platform.system()} {platform.machine()} "
            f"py{platform.python_version()}")


def _now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds")


@dataclass(frozen=True)
class RunRecord:
    """One stored run (a row of table ``runs``)."""

    id: int
    session: str
    kind: str
    suite: str
    scenario: str
    scenario_hash: str
    engine: str
    engine_version: str
    settings: dict[str, Any]
    settings_key: str
    effective_settings: dict[str, Any]
    status: Status
    message: str
    metrics: dict[str, Any]
    wall_time: float | None
    machine: str
    timestamp: str
    rockbench_version: str


class Store:
    """The SQLite results store.

    Parameters
    ----------
    path : str or Path
        Database file (created if missing); ``":memory:"`` for a throw-away store.
    session : str, optional
        Id shared by the runs of one command invocation (default: a new one).

    Raises
    ------
    StoreError
        The file cannot be opened or is not a rockbench database.
    """

    def __init__(self, path: str | Path = DEFAULT_DB, *, session: str | None = None) -> None:
        self.path = str(path)
        self.session = session or uuid.uuid4().hex[:12]
        self.machine = machine()
        if self.path != ":memory:":
            Path(self.path).parent.mkdir(parents=True, exist_ok=True)
        try:
            self.db = sqlite3.connect(self.path, timeout=30.0)
            self.db.execute("PRAGMA journal_mode=WAL")
            self.db.executescript(_SCHEMA)
            row = self.db.execute("SELECT value FROM meta WHERE key='schema'").fetchone()
            if row is None:
                self.db.execute("INSERT INTO meta VALUES ('schema', ?)", (str(SCHEMA_VERSION),))
                self.db.commit()
            elif int(row[0]) > SCHEMA_VERSION:
                raise StoreError(f"{self.path}: results store schema {row[0]} is newer than "
                                 f"this rockbench ({SCHEMA_VERSION}); upgrade rockbench")
        except sqlite3.DatabaseError as exc:
            raise StoreError(f"{self.path}: not a usable results database ({exc})") from None

    # ------------------------------------------------------------------ lifecycle
    def close(self) -> None:
        """Close the database."""
        self.db.close()

    def __enter__(self) -> Store:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------ runs
    def record(
        self,
        scenario: Scenario,
        engine: str,
        settings: Mapping[str, Any],
        traj: Trajectory,
        metrics: Mapping[str, Any],
        *,
        kind: str,
        suite: str = "",
        engine_version: str | None = None,
    ) -> int:
        """Append one finished run and commit at once; returns its row id.

        Parameters
        ----------
        scenario : Scenario
            What was simulated.
        engine : str
            Engine name.
        settings : mapping
            The requested settings (overrides, maybe ``preset``): the cell key.
        traj : Trajectory
            The result (status, message, wall time, effective settings).
        metrics : mapping
            JSON-able metrics of the run.
        kind : str
            The command that ran it (``matrix``, ``sweep``, ``tune``...).
        suite : str
            Suite name, if any.
        engine_version : str, optional
            Overrides ``traj.engine_version`` (empty for runs that never started).
        """
        version = engine_version if engine_version is not None else traj.engine_version
        cur = self.db.execute(
            "INSERT INTO runs (session, kind, suite, scenario, scenario_hash, engine, "
            "engine_version, settings, settings_key, effective_settings, status, message, "
            "metrics, wall_time, machine, timestamp, rockbench_version) "
            "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
            (self.session, kind, suite, scenario.name, scenario_hash(scenario), engine,
             version or "", _canonical(dict(settings)), settings_key(settings),
             _canonical(traj.settings), traj.status.value, traj.message, _canonical(metrics),
             float(traj.wall_time), self.machine, _now(), rockbench.__version__),
        )
        self.db.commit()
        return int(cur.lastrowid or 0)

    def find(
        self, scenario: Scenario, engine: str, settings: Mapping[str, Any], *,
        engine_version: str | None = None, rockbench_version: str | None = None,
    ) -> RunRecord | None:
        """The latest stored run of a cell, or None.

        A cell is the scenario content, the engine, the requested settings and,
        when given, the engine and rockbench versions (``--resume`` passes the
        current ones, so upgrading either reruns the cell).
        """
        sql = ("SELECT * FROM runs WHERE scenario_hash = ? AND engine = ? AND settings_key = ?")
        args: list[Any] = [scenario_hash(scenario), engine, settings_key(settings)]
        if engine_version is not None:
            sql += " AND engine_version = ?"
            args.append(engine_version)
        if rockbench_version is not None:
            sql += " AND rockbench_version = ?"
            args.append(rockbench_version)
        row = self.db.execute(sql + " ORDER BY id DESC LIMIT 1", args).fetchone()
        return None if row is None else self._row(row)

    def runs(
        self, *, scenario: str | None = None, engine: str | None = None,
        kind: str | None = None, session: str | None = None, limit: int | None = None,
    ) -> list[RunRecord]:
        """Stored runs, oldest first, filtered by scenario name, engine, kind or session."""
        sql, args = "SELECT * FROM runs WHERE 1=1", []
        for col, val in (("scenario", scenario), ("engine", engine), ("kind", kind),
                         ("session", session)):
            if val is not None:
                sql += f" AND {col} = ?"
                args.append(val)
        sql += " ORDER BY id DESC"
        if limit is not None:
            sql += f" LIMIT {int(limit)}"
        return [self._row(r) for r in reversed(self.db.execute(sql, args).fetchall())]

    def __iter__(self) -> Iterator[RunRecord]:
        return iter(self.runs())

    def __len__(self) -> int:
        return int(self.db.execute("SELECT COUNT(*) FROM runs").fetchone()[0])

    @staticmethod
    def _row(r: tuple[Any, ...]) -> RunRecord:
        return RunRecord(
            id=r[0], session=r[1], kind=r[2], suite=r[3], scenario=r[4], scenario_hash=r[5],
            engine=r[6], engine_version=r[7], settings=json.loads(r[8]), settings_key=r[9],
            effective_settings=json.loads(r[10]), status=Status(r[11]), message=r[12],
            metrics=json.loads(r[13]), wall_time=r[14], machine=r[15], timestamp=r[16],
            rockbench_version=r[17],
        )

    # ------------------------------------------------------------------ references
    def reference(self, scenario: Scenario) -> Trajectory | None:
        """The cached analytic reference of ``scenario`` for this rockbench version."""
        row = self.db.execute(
            "SELECT data, meta FROM refs WHERE scenario_hash = ? AND version = ?",
            (scenario_hash(scenario), rockbench.__version__),
        ).fetchone()
        if row is None:
            return None
        meta = json.loads(row[1])
        with np.load(io.BytesIO(row[0])) as f:
            arrays = {k: f[k] for k in f.files}
        return Trajectory(
            t=arrays["t"], theta=arrays["theta"], x=arrays["x"], z=arrays["z"],
            wobble=arrays["wobble"], impacts=arrays.get("impacts"),
            status=Status(meta["status"]), message=meta["message"],
            wall_time=meta["wall_time"], engine=meta["engine"],
            engine_version=meta["engine_version"], settings=meta["settings"],
            scenario=scenario.name, extra=meta.get("extra", {}),
        )

    def save_reference(self, scenario: Scenario, traj: Trajectory) -> None:
        """Cache a completed analytic reference (other statuses are not cached)."""
        if not traj.status.completed:
            return
        buf = io.BytesIO()
        arrays = {"t": traj.t, "theta": traj.theta, "x": traj.x, "z": traj.z,
                  "wobble": traj.wobble}
        if traj.impacts is not None:
            arrays["impacts"] = traj.impacts
        np.savez_compressed(buf, **arrays)
        meta = traj.metadata()
        self.db.execute(
            "INSERT OR REPLACE INTO refs VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
            (scenario_hash(scenario), rockbench.__version__, scenario.name, traj.status.value,
             traj.message, float(traj.wall_time), buf.getvalue(), _canonical(meta), _now()),
        )
        self.db.commit()
