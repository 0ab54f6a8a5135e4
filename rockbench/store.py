"""Results store: every run appended to a SQLite database as it finishes.

Every study (``compare``, ``matrix``, ``sweep``, ``tune``, ...) records each
finished run here: one row per run in table ``runs``: scenario name and content
hash, engine, method label, preset and variation, engine version, requested,
resolved and effective settings, status, message, the run's
:class:`~rockbench.evaluation.RunMetrics` (JSON), wall and CPU time, the
trajectory file when the study keeps one, machine, timestamp (UTC, ISO 8601),
rockbench's release and the code version that made it
(:func:`rockbench.provenance.code_version`), the command that produced it
(``kind``) and a session id. Rows are committed one by one, so an interrupted
study loses nothing and ``--resume`` can skip runs already done
(:meth:`Store.find`).

A run is reused only when its identity matches in full: the scenario's content,
the engine and its library version, the *resolved* settings (the preset's values,
not its name: a preset whose value changed reruns) and the code version; a
row written by older code (schema 2, or another code version) is never reused
and is shown as made by that code.

A file that exists and is not a rockbench store (another application's SQLite
database, or not SQLite at all) is refused and never modified: the store marks
its files with a SQLite ``application_id``.

Table ``refs`` caches analytic reference trajectories by scenario content hash
and the code version of the references (a change to the analytic code recomputes
them).

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

from rockbench import provenance
from rockbench.errors import RockbenchError
from rockbench.evaluation import RunMetrics
from rockbench.method import Method
from rockbench.scenarios import Record, Scenario, scenario_to_dict
from rockbench.trajectory import Status, Trajectory, write_npz

__all__ = ["Store", "RunRecord", "StoreError", "scenario_hash", "settings_key", "machine",
           "jsonable", "DEFAULT_DB", "RunIdentity"]

#: Default database file (in the current directory).
DEFAULT_DB = "rockbench.db"
SCHEMA_VERSION = 3
#: SQLite ``application_id`` of rockbench stores ("RkBn").
APPLICATION_ID = 0x526B426E
#: Columns added since schema 1 (an older store is upgraded in place; its rows keep
#: empty values there, so no new code takes them for its own).
_ADDED_COLUMNS = (("method", "TEXT NOT NULL DEFAULT ''"), ("preset", "TEXT NOT NULL DEFAULT ''"),
                  ("variation", "TEXT NOT NULL DEFAULT ''"), ("cpu_time", "REAL"),
                  ("trajectory", "TEXT NOT NULL DEFAULT ''"),
                  ("resolved_key", "TEXT NOT NULL DEFAULT ''"),
                  ("code_version", "TEXT NOT NULL DEFAULT ''"))

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
    rockbench_version TEXT NOT NULL,
    method TEXT NOT NULL DEFAULT '',
    preset TEXT NOT NULL DEFAULT '',
    variation TEXT NOT NULL DEFAULT '',
    cpu_time REAL,
    trajectory TEXT NOT NULL DEFAULT '',
    resolved_key TEXT NOT NULL DEFAULT '',
    code_version TEXT NOT NULL DEFAULT ''
);
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

    Records are hashed by their samples too, not only their file name.
    """
    data = scenario_to_dict(scenario)
    data.pop("name", None)
    data.pop("description", None)
    h = hashlib.sha256(_canonical(data).encode())
    for motion in scenario.motion.components:
        if isinstance(motion, Record):
            h.update(np.asarray(motion.times, float).tobytes())
            h.update(np.asarray(motion.accelerations, float).tobytes())
    return h.hexdigest()[:16]


def settings_key(settings: Mapping[str, Any]) -> str:
    """Hash of a settings mapping (order-independent)."""
    return hashlib.sha256(_canonical(dict(settings)).encode()).hexdigest()[:16]


@dataclass(frozen=True)
class RunIdentity:
    """What makes two runs the same run: a stored run is reused only if all of it matches.

    Attributes
    ----------
    scenario_hash : str
        :func:`scenario_hash` of what is simulated.
    engine, engine_version : str
        The engine and its library's version.
    resolved_key : str
        :func:`settings_key` of the settings the run resolves to (every knob's
        value, whatever preset or override named it).
    code_version : str
        :func:`rockbench.provenance.code_version` of the code that runs it.
    variation : str
        A study's named variation ('' for the main runs).
    """

    scenario_hash: str
    engine: str
    engine_version: str
    resolved_key: str
    code_version: str
    variation: str = ""

    @classmethod
    def of(cls, scenario: Scenario, method: Method, *, engine_version: str,
           resolved: Mapping[str, Any], scope: str = "run") -> RunIdentity:
        """The identity of running ``method`` (resolved to ``resolved``) on ``scenario`` now."""
        return cls(scenario_hash(scenario), method.engine, engine_version,
                   settings_key(resolved), provenance.code_version(scope), method.variation)


def machine() -> str:
    """A short description of this machine: host, OS, CPU architecture, Python."""
    return (f"{socket.gethostname()} {platform.system()} {platform.machine()} "
            f"py{platform.python_version()}")


def _now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds")


@dataclass(frozen=True)
class RunRecord:
    """One stored run (a row of table ``runs``).

    ``metrics`` is None for a row whose metrics cannot be read back (written by
    another rockbench version with other fields): its status still counts.
    """

    id: int
    session: str
    kind: str
    suite: str
    scenario: str
    scenario_hash: str
    engine: str
    method: str
    preset: str
    variation: str
    engine_version: str
    settings: dict[str, Any]
    settings_key: str
    effective_settings: dict[str, Any]
    status: Status
    message: str
    metrics: RunMetrics | None
    wall_time: float | None
    cpu_time: float | None
    trajectory: str
    machine: str
    timestamp: str
    rockbench_version: str
    code_version: str

    @property
    def made_by(self) -> str:
        """The code that made the run: its code version, or the release of older code."""
        return self.code_version or f"rockbench {self.rockbench_version} (older code)"


def _metrics(text: str) -> RunMetrics | None:
    try:
        return RunMetrics.from_json(json.loads(text))
    except (ValueError, KeyError, TypeError):  # a schema-1 row or another version's fields
        return None


_COLUMNS = ("id, session, kind, suite, scenario, scenario_hash, engine, method, preset, "
            "variation, engine_version, settings, settings_key, effective_settings, status, "
            "message, metrics, wall_time, cpu_time, trajectory, machine, timestamp, "
            "rockbench_version, code_version")


def _check_foreign(path: Path, *, reader: bool) -> None:
    """Refuse, without writing to it, a file that is not a rockbench store.

    A missing or empty file becomes a new store for a writer; a reader
    (``reader=True``) needs an existing rockbench store.
    """
    if not path.exists() or path.stat().st_size == 0:
        if reader and path.exists():
            raise StoreError(f"{path}: an empty file, not a rockbench results store")
        return
    try:
        with path.open("rb") as fh:
            head = fh.read(16)
    except OSError as exc:
        raise StoreError(f"{path}: cannot read the results store ({exc.strerror})") from None
    if head != b"SQLite format 3\x00":
        raise StoreError(f"{path}: not a rockbench results store (not an SQLite file); "
                         "refusing to modify it: choose another --db")
    try:
        ro = sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=30.0)
        try:
            app = ro.execute("PRAGMA application_id").fetchone()[0]
            tables = {r[0] for r in ro.execute(
                "SELECT name FROM sqlite_master WHERE type = 'table'")}
        finally:
            ro.close()
    except sqlite3.DatabaseError as exc:
        raise StoreError(f"{path}: not a usable results database ({exc})") from None
    legacy = app == 0 and {"meta", "runs"} <= tables  # schema 1 had no application_id
    if app != APPLICATION_ID and not legacy and (tables or reader):
        raise StoreError(f"{path}: not a rockbench results store (an SQLite database of "
                         "another application); refusing to modify it: choose another --db")


class Store:
    """The SQLite results store.

    Parameters
    ----------
    path : str or Path
        Database file (created if missing); ``":memory:"`` for a throw-away store.
    session : str, optional
        Id shared by the runs of one command invocation (default: a new one).
    create : bool
        Create the file if it does not exist (False for readers such as
        ``rockbench history``: a missing file is an error).

    Raises
    ------
    StoreError
        The file cannot be opened, or is not a rockbench database (it is then
        left untouched).
    """

    def __init__(self, path: str | Path = DEFAULT_DB, *, session: str | None = None,
                 create: bool = True) -> None:
        self.path = str(path)
        self.session = session or uuid.uuid4().hex[:12]
        self.machine = machine()
        if self.path != ":memory:":
            p = Path(self.path)
            if not create and not p.exists():
                raise StoreError(f"no results store at {self.path} (run a study first, "
                                 "or pass --db)")
            if p.is_dir():
                raise StoreError(f"{self.path}: is a directory, expected a results store file")
            _check_foreign(p, reader=not create)
            try:
                p.parent.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise StoreError(f"{self.path}: cannot create the results store's folder "
                                 f"({exc.strerror})") from None
        try:
            self.db = sqlite3.connect(self.path, timeout=30.0)
            self.db.execute("PRAGMA journal_mode=WAL")
            self._upgrade()
        except sqlite3.DatabaseError as exc:  # includes an unwritable location
            raise StoreError(f"{self.path}: not a usable results database ({exc})") from None

    def _upgrade(self) -> None:
        """Bring the store to this schema; a store already there is not written to (a
        reader such as ``rockbench history`` then never waits for a writer's lock)."""
        current = self.db.execute("SELECT name FROM sqlite_master WHERE type = 'table' AND "
                                  "name = 'meta'").fetchone() is not None and \
            self.db.execute("SELECT value FROM meta WHERE key='schema'").fetchone() == \
            (str(SCHEMA_VERSION),) and \
            self.db.execute("PRAGMA application_id").fetchone()[0] == APPLICATION_ID
        if current:
            return
        self.db.executescript(_SCHEMA)
        row = self.db.execute("SELECT value FROM meta WHERE key='schema'").fetchone()
        if row is not None and int(row[0]) > SCHEMA_VERSION:
            raise StoreError(f"{self.path}: results store schema {row[0]} is newer than "
                             f"this rockbench ({SCHEMA_VERSION}); upgrade rockbench")
        have = {r[1] for r in self.db.execute("PRAGMA table_info(runs)")}
        for name, decl in _ADDED_COLUMNS:
            if name not in have:
                self.db.execute(f"ALTER TABLE runs ADD COLUMN {name} {decl}")
        self.db.execute("CREATE INDEX IF NOT EXISTS runs_identity ON runs "
                        "(scenario_hash, engine, resolved_key, code_version)")
        self.db.execute("INSERT OR REPLACE INTO meta VALUES ('schema', ?)",
                        (str(SCHEMA_VERSION),))
        self.db.execute(f"PRAGMA application_id = {APPLICATION_ID}")
        self.db.commit()

    @property
    def archive(self) -> Path | None:
        """The folder beside the store where studies keep run trajectories
        (``rockbench.db`` → ``rockbench-runs/``); None for an in-memory store."""
        if self.path == ":memory:":
            return None
        p = Path(self.path)
        return p.parent / f"{p.stem}-runs"

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
        method: Method,
        traj: Trajectory,
        metrics: RunMetrics,
        identity: RunIdentity,
        *,
        kind: str,
        suite: str = "",
        trajectory: str = "",
    ) -> int:
        """Append one finished run and commit at once; returns its row id.

        Parameters
        ----------
        scenario : Scenario
            What was simulated.
        method : Method
            Engine and requested settings (the cell key).
        traj : Trajectory
            The result (effective settings).
        metrics : RunMetrics
            From :func:`rockbench.evaluation.evaluate_run`.
        identity : RunIdentity
            What makes it this run (:meth:`find` matches it).
        kind : str
            The study that ran it (``compare``, ``matrix``, ``sweep``, ``tune``...).
        suite : str
            Suite name, if any.
        trajectory : str
            The trajectory file kept for the run, if any.
        """
        settings = method.settings
        cur = self.db.execute(
            "INSERT INTO runs (session, kind, suite, scenario, scenario_hash, engine, method, "
            "preset, variation, engine_version, settings, settings_key, effective_settings, "
            "status, message, metrics, wall_time, cpu_time, trajectory, machine, timestamp, "
            "rockbench_version, resolved_key, code_version) VALUES (?, ?, ?, ?, ?, ?, ?, ?, "
            "?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
            (self.session, kind, suite, scenario.name, identity.scenario_hash, method.engine,
             method.label, method.preset, method.variation, identity.engine_version,
             _canonical(settings), settings_key(settings), _canonical(traj.settings),
             metrics.status.value, metrics.message, _canonical(metrics.to_json()),
             metrics.wall_time, metrics.cpu_time, trajectory, self.machine, _now(),
             provenance.RELEASE, identity.resolved_key, identity.code_version),
        )
        self.db.commit()
        return int(cur.lastrowid or 0)

    def find(self, identity: RunIdentity) -> RunRecord | None:
        """The latest stored run of exactly this identity whose metrics can be read, or None.

        Every part must match (:class:`RunIdentity`): a run made by other code, at
        other resolved settings or with another engine version is not found.
        """
        sql = (f"SELECT {_COLUMNS} FROM runs WHERE scenario_hash = ? AND engine = ? "
               "AND engine_version = ? AND resolved_key = ? AND code_version = ? "
               "AND variation = ? ORDER BY id DESC LIMIT 20")
        args = (identity.scenario_hash, identity.engine, identity.engine_version,
                identity.resolved_key, identity.code_version, identity.variation)
        for row in self.db.execute(sql, args):
            rec = self._row(row)
            if rec.metrics is not None:
                return rec
        return None

    def runs(
        self, *, scenario: str | None = None, engine: str | None = None,
        kind: str | None = None, session: str | None = None, limit: int | None = None,
    ) -> list[RunRecord]:
        """Stored runs, oldest first, filtered by scenario name, engine, kind or session."""
        sql, args = f"SELECT {_COLUMNS} FROM runs WHERE 1=1", []
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
            engine=r[6], method=r[7] or r[6], preset=r[8], variation=r[9], engine_version=r[10],
            settings=json.loads(r[11]), settings_key=r[12], effective_settings=json.loads(r[13]),
            status=Status(r[14]), message=r[15], metrics=_metrics(r[16]), wall_time=r[17],
            cpu_time=r[18], trajectory=r[19], machine=r[20], timestamp=r[21],
            rockbench_version=r[22], code_version=r[23],
        )

    # ------------------------------------------------------------------ references
    def reference(self, scenario: Scenario) -> Trajectory | None:
        """The cached analytic reference of ``scenario`` made by the current reference code."""
        row = self.db.execute(
            "SELECT data, meta FROM refs WHERE scenario_hash = ? AND version = ?",
            (scenario_hash(scenario), provenance.code_version("reference")),
        ).fetchone()
        if row is None:
            return None
        meta = json.loads(row[1])
        with np.load(io.BytesIO(row[0])) as f:
            arrays = {k: f[k] for k in f.files}
        return Trajectory(
            t=arrays["t"], theta=arrays["theta"], x=arrays["x"], z=arrays["z"],
            wobble=arrays["wobble"], y=arrays.get("y"), roll=arrays.get("roll"),
            twist=arrays.get("twist"), impacts=arrays.get("impacts"),
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
        arrays = traj.arrays()
        if traj.impacts is not None:
            arrays["impacts"] = traj.impacts
        write_npz(buf, arrays)
        meta = traj.metadata()
        self.db.execute(
            "INSERT OR REPLACE INTO refs VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
            (scenario_hash(scenario), provenance.code_version("reference"), scenario.name,
             traj.status.value,
             traj.message, float(traj.wall_time), buf.getvalue(), _canonical(meta), _now()),
        )
        self.db.commit()
