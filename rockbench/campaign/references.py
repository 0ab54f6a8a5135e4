"""Analytic references of a study's scenarios: computed once, cached in the results store.

Every study that compares engines with the analytic solution takes its
references from :func:`references`, so a scenario's reference is computed (and
cached by scenario content) the same way whichever study asks first.
"""

from __future__ import annotations

from collections.abc import Sequence

from rockbench import analytic
from rockbench.runner import ExecutionOptions, Job, run_jobs
from rockbench.scenarios import Scenario
from rockbench.store import Store
from rockbench.trajectory import Trajectory

__all__ = ["references", "NO_MODEL"]

#: Note of a scenario the analytic models do not cover.
NO_MODEL = "no analytic model (more than two or off-centre blocks)"


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
        if not analytic.has_reference(sc):
            refs[sc.name] = None
            notes[sc.name] = NO_MODEL
            continue
        cached = store.reference(sc) if store is not None else None
        if cached is not None:
            refs[sc.name] = cached
        else:
            todo.append(Job(sc, "analytic", {}))
    for job, traj in zip(todo, run_jobs(todo, execution), strict=True):
        refs[job.scenario.name] = traj
        if traj.status.completed:
            if store is not None:
                store.save_reference(job.scenario, traj)
        else:
            notes[job.scenario.name] = f"reference {traj.status.value}: {traj.message}"
    return refs, notes
