"""Analytic references of a study's scenarios: computed once, cached in the results store.

Every study that compares engines with the analytic solution takes its
references from :func:`references`, so a scenario's reference is computed (and
cached by scenario content) the same way whichever study asks first.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

from rockbench import analytic, provenance
from rockbench.runner import ExecutionOptions, Job, run_jobs
from rockbench.scenarios import Scenario
from rockbench.store import Store, scenario_hash
from rockbench.trajectory import Trajectory

__all__ = ["references"]


def references(
    scenarios: Sequence[Scenario],
    store: Store | None = None,
    *,
    execution: ExecutionOptions | None = None,
) -> tuple[dict[str, Trajectory | None], dict[str, str]]:
    """The analytic reference of every scenario, from the store's cache or computed now.

    Parameters
    ----------
    scenarios : sequence of Scenario
        The study's scenarios (names unique).
    store : Store, optional
        Results store whose reference cache is read and filled (completed
        references only).
    execution : ExecutionOptions, optional
        How the analytic runs are dispatched (isolated, with a time limit).

    Returns
    -------
    refs : dict
        Scenario name → reference trajectory. None where the analytic models do
        not cover the scenario; a reference that did not complete is kept (its
        status and message say why), so that
        :func:`rockbench.evaluation.evaluate_run` records its status and no
        judge mistakes it for a scenario without a model.
    notes : dict
        Scenario name → why there is no usable reference.
    """
    refs: dict[str, Trajectory | None] = {}
    notes: dict[str, str] = {}
    todo = []
    for sc in scenarios:
        why = analytic.coverage(sc)
        if why:
            refs[sc.name] = None
            notes[sc.name] = why
            continue
        key = (scenario_hash(sc), provenance.code_version("reference"))
        stored = store.reference(sc) if store is not None else None
        cached = _MEMO.get(key) or stored
        if cached is not None and store is not None and stored is None:
            store.save_reference(sc, cached)  # known in this process: cache it in this store too
        if cached is not None:
            refs[sc.name] = _MEMO[key] = _named(cached, sc.name)
        else:
            todo.append(Job(sc, "analytic", {}))
    for job, traj in zip(todo, run_jobs(todo, execution), strict=True):
        refs[job.scenario.name] = traj
        if traj.status.completed:
            _remember((scenario_hash(job.scenario), provenance.code_version("reference")), traj)
            if store is not None:
                store.save_reference(job.scenario, traj)
        else:
            notes[job.scenario.name] = f"reference {traj.status.value}: {traj.message}"
    return refs, notes


#: References computed or read in this process, by scenario content and reference code
#: (a study that asks again, like the tuner's rounds, does not recompute them).
_MEMO: dict[tuple[str, str], Trajectory] = {}
#: Largest number of references kept in :data:`_MEMO`.
_MEMO_SIZE = 256


def _remember(key: tuple[str, str], traj: Trajectory) -> None:
    if len(_MEMO) >= _MEMO_SIZE:
        _MEMO.pop(next(iter(_MEMO)))
    _MEMO[key] = traj


def _named(traj: Trajectory, name: str) -> Trajectory:
    """``traj`` under the scenario name asked for (the same content may have two names)."""
    if traj.scenario == name:
        return traj
    return dataclasses.replace(traj, scenario=name)
