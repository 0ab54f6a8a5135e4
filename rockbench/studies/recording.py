"""The one way a study turns a finished run into metrics and records it in the store.

Every study's ``finished`` callback (matrix, sweep, tune, compare, ...) calls
:func:`finish_run` (or :func:`measure` then :func:`record_run`) as each run
finishes, so every stored run carries the same identity (scenario hash,
settings hash, engine version) and nothing finished is lost if the study is
interrupted.
"""

from __future__ import annotations

from rockbench.engines import engine_class
from rockbench.evaluation import RunMetrics, evaluate_run
from rockbench.method import Method
from rockbench.scenarios import Scenario
from rockbench.store import Store, scenario_hash
from rockbench.trajectory import Trajectory

__all__ = ["measure", "record_run", "finish_run", "settings_hash"]


def settings_hash(method: Method) -> str:
    """Digest of the engine's effective settings for ``method`` (preset plus overrides)."""
    s = method.settings
    return engine_class(method.engine).settings(s.pop("preset", None), **s).digest()


def measure(scenario: Scenario, method: Method, traj: Trajectory,
            reference: Trajectory | None, *, engine_version: str = "",
            reference_note: str = "", horizon: float | None = None) -> RunMetrics:
    """:func:`~rockbench.evaluation.evaluate_run` with the run's identity filled in.

    Parameters
    ----------
    scenario, method, traj
        What ran, how, and its result.
    reference : Trajectory or None
        The scenario's analytic reference (may be one that did not complete).
    engine_version : str
        Version to record (default: the trajectory's, else the engine's).
    reference_note : str
        Why there is no reference (kept as the metrics' ``error_note``).
    horizon : float, optional
        The scenario's predictability horizon t*: errors stop there.
    """
    version = engine_version or traj.engine_version or engine_class(method.engine).version()
    return evaluate_run(scenario, traj, reference, is_reference=method.is_reference,
                        settings_hash=settings_hash(method), scenario_hash=scenario_hash(scenario),
                        engine_version=version, reference_note=reference_note,
                        horizon=horizon)


def record_run(store: Store | None, scenario: Scenario, method: Method, traj: Trajectory,
               metrics: RunMetrics, *, kind: str, suite: str = "",
               trajectory: str = "") -> int | None:
    """Append one finished run to ``store`` (nothing without a store); returns its row id."""
    if store is None:
        return None
    return store.record(scenario, method, traj, metrics, kind=kind, suite=suite,
                        trajectory=trajectory)


def finish_run(store: Store | None, scenario: Scenario, method: Method, traj: Trajectory,
               reference: Trajectory | None, *, kind: str, suite: str = "",
               trajectory: str = "", engine_version: str = "",
               reference_note: str = "", horizon: float | None = None) -> RunMetrics:
    """:func:`measure` then :func:`record_run`: the body of every study's ``finished``."""
    metrics = measure(scenario, method, traj, reference, engine_version=engine_version,
                      reference_note=reference_note, horizon=horizon)
    record_run(store, scenario, method, traj, metrics, kind=kind, suite=suite,
               trajectory=trajectory)
    return metrics
