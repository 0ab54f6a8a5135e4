"""Result rows of a comparison: one per scenario × method, from trajectories.

Everything a report shows is derived from the trajectories written under
``DIR/trajectories/<scenario>/<method>.npz`` (+ ``.json`` sidecar), so a report
can always be rebuilt from them. Each trajectory is written as soon as its run
finishes, and ``results.csv`` grows one row at a time, so an interrupted
comparison loses nothing; ``--resume`` reads the trajectories back and skips
the runs whose settings hash, scenario hash and engine version are unchanged.
"""

from __future__ import annotations

import csv
import hashlib
import json
import math
import os
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rockbench import metrics
from rockbench.runner import Job
from rockbench.scenarios import CosinePulse, Free, Scenario, SinePulse, Sinusoid, scenario_to_dict
from rockbench.trajectory import Status, Trajectory

__all__ = ["Run", "scenario_group", "GROUP_TITLES", "scenario_hash", "method_slug",
           "run_slug", "trajectory_path", "save_trajectory", "load_finished", "compute_row",
           "result_columns", "ResultsWriter", "read_results", "REFERENCE", "N_IMPACTS"]

#: Method name of the analytic reference.
REFERENCE = "analytic"
#: Number of first impacts whose times are compared.
N_IMPACTS = 3
#: What must be identical for --resume to reuse a stored run.
_REUSE_KEYS = ("engine", "preset", "variation", "settings_hash", "scenario_hash",
               "engine_version")
#: Statuses that --resume re-runs (possibly transient failures).
_RERUN = {Status.CRASHED, Status.TIMEOUT}

#: Titles of scenario groups, in report order.
GROUP_TITLES: dict[str, str] = {
    "free": "Free rocking of a single block",
    "single-pulse": "Single block, one-cycle sine pulse",
    "single-sine": "Single block, sinusoidal base motion",
    "single-record": "Single block, recorded ground motion",
    "stack-free": "Two stacked blocks, free rocking",
    "stack-pulse": "Two stacked blocks, one-cycle sine pulse",
    "stack-sine": "Two stacked blocks, sinusoidal base motion",
    "stack-record": "Two stacked blocks, recorded ground motion",
}


def scenario_group(scenario: Scenario) -> str:
    """Group of a scenario: ``free``, ``single-pulse``, ``stack-sine``, ``stack3-pulse`` ..."""
    exc = scenario.excitation
    kind = ("free" if isinstance(exc, Free)
            else "pulse" if isinstance(exc, (SinePulse, CosinePulse))
            else "sine" if isinstance(exc, Sinusoid) else "record")
    nb = scenario.n_blocks
    prefix = "single" if nb == 1 else "stack" if nb == 2 else f"stack{nb}"
    if kind == "free" and nb == 1:
        return "free"
    return f"{prefix}-{kind}"


def group_title(group: str) -> str:
    """Human title of a scenario group."""
    if group in GROUP_TITLES:
        return GROUP_TITLES[group]
    m = re.match(r"stack(\d+)-(\w+)", group)
    if m:
        return f"Stacks of {m.group(1)} blocks, {m.group(2)}"
    return group


def scenario_hash(scenario: Scenario) -> str:
    """Short stable hash of a scenario definition."""
    text = json.dumps(scenario_to_dict(scenario), sort_keys=True, default=str)
    return hashlib.sha1(text.encode()).hexdigest()[:10]


def method_slug(method: str) -> str:
    """A file-name-safe form of a method label (``mujoco[fast]`` → ``mujoco-fast``)."""
    slug = re.sub(r"[^A-Za-z0-9_.=+-]+", "-", method).strip("-")
    return slug or "method"


@dataclass(frozen=True)
class Run:
    """One planned run of a comparison: a job plus what the report needs to know.

    Attributes
    ----------
    job : Job
        What the runner executes.
    method : str
        Column label in tables (``analytic``, ``mujoco``, ``mujoco[fast]``, ...).
    preset : str
        Settings preset (empty for the reference).
    variation : str
        Sensitivity variation (``iterations=10``), empty for the main comparison.
    settings_hash : str
        Digest of the resolved engine settings.
    engine_version : str
        Version of the engine library.
    knobs : dict
        The knob overrides that define the variation (display only).
    """

    job: Job
    method: str
    preset: str = ""
    variation: str = ""
    settings_hash: str = ""
    engine_version: str = ""
    knobs: Mapping[str, Any] = field(default_factory=dict)

    @property
    def scenario(self) -> Scenario:
        """The scenario simulated."""
        return self.job.scenario

    @property
    def engine(self) -> str:
        """Engine name."""
        return self.job.engine

    @property
    def is_reference(self) -> bool:
        """True for the analytic reference of the main comparison."""
        return self.engine == REFERENCE

    @property
    def key(self) -> tuple[str, str]:
        """(scenario name, method)."""
        return (self.scenario.name, self.method)


def run_slug(run: Run) -> str:
    """File stem of a run: ``analytic``, ``mujoco-fast``, ``mujoco-iterations=10``.

    It names the engine and preset even when the table label omits the preset,
    so that ``--resume`` with another ``--presets`` list still finds the run.
    """
    if run.variation or run.is_reference or not run.preset:
        return method_slug(run.method)
    return method_slug(f"{run.engine}[{run.preset}]")


def trajectory_path(out: Path, run: Run) -> Path:
    """``out/trajectories/<scenario>/<engine>-<preset>.npz``."""
    return Path(out) / "trajectories" / method_slug(run.scenario.name) / (run_slug(run) + ".npz")


def _identity(run: Run) -> dict[str, Any]:
    return {"method": run.method, "engine": run.engine, "preset": run.preset,
            "variation": run.variation, "settings_hash": run.settings_hash,
            "scenario_hash": scenario_hash(run.scenario), "engine_version": run.engine_version}


def save_trajectory(out: Path, run: Run, traj: Trajectory) -> Path:
    """Write a finished run's trajectory (``.npz`` + ``.json``) and return the ``.npz`` path."""
    path = trajectory_path(out, run)
    traj.extra = {**traj.extra, "report": _identity(run)}
    traj.scenario = traj.scenario or run.scenario.name
    traj.save(path, scenario=scenario_to_dict(run.scenario))
    return path


def load_finished(out: Path, run: Run) -> Trajectory | None:
    """The stored trajectory of ``run`` if it can be reused, else None.

    Reusable: same method, settings hash, scenario hash and engine version, and a
    status other than ``crashed`` or ``timeout`` (those are run again).
    """
    path = trajectory_path(out, run)
    side = path.with_suffix(".json")
    if not (path.exists() and side.exists()):
        return None
    try:
        meta = json.loads(side.read_text())
        stored = meta.get("extra", {}).get("report") or {}
        if any(stored.get(k) != v for k, v in _identity(run).items() if k in _REUSE_KEYS):
            return None
        if Status(meta["status"]) in _RERUN:
            return None
        return Trajectory.load(path)
    except (OSError, ValueError, KeyError):
        return None


def result_columns(max_blocks: int) -> list[str]:
    """Column names of ``results.csv`` for stacks of up to ``max_blocks`` blocks."""
    blocks = range(1, max_blocks + 1)
    return [
        "scenario", "group", "method", "engine", "preset", "variation", "reference",
        "status", "message", "n_blocks", "critical_angle", "uplift_ratio", "duration",
        "simulated_time",
        *[f"peak_ratio_{i}" for i in blocks],
        "max_error",
        *[f"peak_error_{i}" for i in blocks],
        *[f"impact_error_{k}" for k in range(1, N_IMPACTS + 1)],
        "time_to_rest", "reference_time_to_rest", "error_note",
        "wall_time", "time_per_simulated_second", "realtime_factor",
        "settings_hash", "scenario_hash", "engine_version", "trajectory",
    ]


def _f(x: Any) -> float:
    try:
        v = float(x)
    except (TypeError, ValueError):
        return math.nan
    return v


def compute_row(run: Run, traj: Trajectory, ref: Trajectory | None, *,
                ref_reason: str = "", trajectory: str = "") -> dict[str, Any]:
    """One ``results.csv`` row: status, peaks, errors against the reference, cost.

    Parameters
    ----------
    run : Run
        The planned run.
    traj : Trajectory
        Its result.
    ref : Trajectory or None
        The analytic reference of the scenario (None if there is none).
    ref_reason : str
        Why there is no usable reference (shown where errors are "-").
    trajectory : str
        Relative path of the stored trajectory.

    Returns
    -------
    dict
        Column → value (floats are NaN where undefined).
    """
    s = run.scenario
    lam = s.critical_angle
    nb = s.n_blocks
    peaks = metrics.peak_ratio(traj, lam)
    simulated = float(traj.t[-1]) if traj.t.size else 0.0
    wall = float(traj.wall_time)
    row: dict[str, Any] = {
        "scenario": s.name, "group": scenario_group(s), "method": run.method,
        "engine": run.engine, "preset": run.preset, "variation": run.variation,
        "reference": int(run.is_reference and not run.variation),
        "status": str(traj.status), "message": traj.message, "n_blocks": nb,
        "critical_angle": lam,
        "uplift_ratio": math.nan if s.excitation.is_free else s.uplift_ratio,
        "duration": s.duration, "simulated_time": simulated,
        "wall_time": wall,
        "time_per_simulated_second": wall / simulated if simulated > 0 else math.nan,
        "realtime_factor": simulated / wall if wall > 0 and simulated > 0 else math.nan,
        "settings_hash": run.settings_hash, "scenario_hash": scenario_hash(s),
        "engine_version": traj.engine_version or run.engine_version, "trajectory": trajectory,
        "time_to_rest": metrics.time_to_rest(traj, lam) if traj.t.size else math.nan,
        "reference_time_to_rest": math.nan, "max_error": math.nan, "error_note": "",
    }
    for i in range(nb):
        row[f"peak_ratio_{i + 1}"] = float(peaks[i])
        row[f"peak_error_{i + 1}"] = math.nan
    for k in range(1, N_IMPACTS + 1):
        row[f"impact_error_{k}"] = math.nan
    if run.is_reference and not run.variation:
        row["error_note"] = "reference"
        return row
    if ref is None or not ref.t.size:
        row["error_note"] = ref_reason or "no analytic reference"
        return row
    row["reference_time_to_rest"] = metrics.time_to_rest(ref, lam)
    if not traj.t.size:
        row["error_note"] = f"{traj.status}: {traj.message}"
        return row
    try:
        row["max_error"] = metrics.max_error(traj, ref, lam)
    except ValueError as exc:
        row["error_note"] = str(exc)
        return row
    for i, e in enumerate(metrics.peak_relative_error(traj, ref, lam)):
        row[f"peak_error_{i + 1}"] = float(e)
    for k, e in enumerate(metrics.impact_time_errors(traj, ref, N_IMPACTS)):
        row[f"impact_error_{k + 1}"] = float(e)
    if ref.status is not Status.OK:
        row["error_note"] = f"reference {ref.status}: {ref.message}"
    return row


def _cell(v: Any) -> str:
    if isinstance(v, float):
        return "" if math.isnan(v) else repr(v)
    if isinstance(v, (np.floating, np.integer)):
        return _cell(v.item())
    return str(v)


class ResultsWriter:
    """Writes ``results.csv`` one row at a time (flushed), then rewrites it sorted.

    Parameters
    ----------
    path : Path
        The CSV file (truncated when opened).
    max_blocks : int
        Largest number of blocks among the scenarios (fixes the columns).
    """

    def __init__(self, path: Path, max_blocks: int) -> None:
        self.path = Path(path)
        self.columns = result_columns(max_blocks)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._fh = self.path.open("w", newline="", encoding="utf-8")
        self._writer = csv.writer(self._fh)
        self._writer.writerow(self.columns)
        self._fh.flush()

    def append(self, row: Mapping[str, Any]) -> None:
        """Append one row and flush it to disk."""
        self._writer.writerow([_cell(row.get(c, "")) for c in self.columns])
        self._fh.flush()

    def close(self) -> None:
        """Close the file."""
        if not self._fh.closed:
            self._fh.close()

    def rewrite(self, rows: Iterable[Mapping[str, Any]]) -> None:
        """Replace the file by ``rows`` in the given order (atomically)."""
        self.close()
        tmp = self.path.with_suffix(".csv.tmp")
        with tmp.open("w", newline="", encoding="utf-8") as fh:
            w = csv.writer(fh)
            w.writerow(self.columns)
            for row in rows:
                w.writerow([_cell(row.get(c, "")) for c in self.columns])
        os.replace(tmp, self.path)


_TEXT = {"scenario", "group", "method", "engine", "preset", "variation", "status", "message",
         "error_note", "settings_hash", "scenario_hash", "engine_version", "trajectory"}


def read_results(path: str | Path) -> list[dict[str, Any]]:
    """Read ``results.csv`` back: text columns as str, the others as float (NaN if empty)."""
    with Path(path).open(newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    out = []
    for r in rows:
        out.append({k: (v if k in _TEXT else _f(v) if v != "" else math.nan)
                    for k, v in r.items()})
    return out


def order_rows(rows: Sequence[Mapping[str, Any]], scenarios: Sequence[str],
               methods: Sequence[str]) -> list[Mapping[str, Any]]:
    """Rows sorted by scenario order, then method order."""
    si = {n: i for i, n in enumerate(scenarios)}
    mi = {n: i for i, n in enumerate(methods)}
    return sorted(rows, key=lambda r: (si.get(r["scenario"], 1 << 30),
                                       mi.get(r["method"], 1 << 30), r["method"]))
