"""Running scenario × engine jobs, isolated in child processes with a time limit.

A crash (segfault, exception), a hang or an unsupported scenario in one run
becomes that run's :class:`~rockbench.trajectory.Status`; the others carry on.
Results are handed to a callback as each job finishes, so callers can write
them incrementally and lose nothing if the run is interrupted.
"""

from __future__ import annotations

import multiprocessing
import os
import time
import traceback
from collections.abc import Callable, Iterable, Mapping
from concurrent.futures import TimeoutError as FutureTimeout
from concurrent.futures import as_completed
from dataclasses import dataclass, field
from typing import Any

from pebble import ProcessExpired, ProcessPool

from rockbench.engines import get_engine
from rockbench.errors import RockbenchError
from rockbench.scenarios import Scenario
from rockbench.trajectory import Status, Trajectory

__all__ = ["Job", "run_job", "run_jobs", "default_jobs"]


@dataclass(frozen=True)
class Job:
    """One simulation: a scenario on an engine with settings.

    Attributes
    ----------
    scenario : Scenario
        What to simulate.
    engine : str
        Registered engine name.
    settings : Mapping
        Knob overrides; the key ``"preset"`` selects a preset first.
    label : str
        How the job's method is shown in tables (default: the engine name, plus
        the preset if one is given).
    """

    scenario: Scenario
    engine: str
    settings: Mapping[str, Any] = field(default_factory=dict)
    label: str = ""

    @property
    def method(self) -> str:
        """Display name of the method: ``label`` or ``engine[preset]``."""
        if self.label:
            return self.label
        preset = self.settings.get("preset")
        return f"{self.engine}[{preset}]" if preset else self.engine


def default_jobs() -> int:
    """Number of worker processes by default: the machine's usable cores."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


def _failed(job: Job, status: Status, message: str, wall: float = 0.0) -> Trajectory:
    return Trajectory.failed(status, message, n_blocks=job.scenario.n_blocks, engine=job.engine,
                             scenario=job.scenario.name, settings=dict(job.settings),
                             wall_time=wall)


def run_job(job: Job) -> Trajectory:
    """Run one job in this process; exceptions become status ``crashed``."""
    start = time.perf_counter()
    try:
        engine = get_engine(job.engine)
        return engine.simulate(job.scenario, dict(job.settings))
    except RockbenchError:
        raise  # bad input (unknown engine, bad knob): the caller reports it
    except Exception as exc:  # a physics library failing is a result, not our crash
        tb = traceback.format_exc(limit=3).strip().splitlines()[-1]
        return _failed(job, Status.CRASHED, f"{type(exc).__name__}: {exc} ({tb})",
                       time.perf_counter() - start)


def _context() -> multiprocessing.context.BaseContext:
    # fork keeps run-time registrations (e.g. test engines) visible in children
    methods = multiprocessing.get_all_start_methods()
    return multiprocessing.get_context("fork" if "fork" in methods else "spawn")


def run_jobs(
    jobs: Iterable[Job],
    *,
    n_jobs: int | None = 1,
    timeout: float | Callable[[Job], float] | None = None,
    isolate: bool = True,
    on_result: Callable[[Job, Trajectory], None] | None = None,
) -> list[Trajectory]:
    """Run jobs and return their trajectories in the order given.

    Parameters
    ----------
    jobs : iterable of Job
        What to run.
    n_jobs : int, optional
        Worker processes (None: the machine's cores). Ignored when not isolating.
    timeout : float or callable, optional
        Wall-time limit per job in s (or a function of the job); a job that
        exceeds it is killed and reported as ``timeout``.
    isolate : bool
        Run each job in its own child process (default). ``False`` runs in this
        process, without protection against crashes and hangs.
    on_result : callable, optional
        Called as ``on_result(job, trajectory)`` as soon as each job finishes.

    Raises
    ------
    RockbenchError
        Bad input detected in a job (unknown engine, bad settings).
    """
    jobs = list(jobs)
    results: list[Trajectory | None] = [None] * len(jobs)

    def limit(job: Job) -> float | None:
        return timeout(job) if callable(timeout) else timeout

    def done(i: int, traj: Trajectory) -> None:
        results[i] = traj
        if on_result is not None:
            on_result(jobs[i], traj)

    if not isolate:
        for i, job in enumerate(jobs):
            done(i, run_job(job))
        return results  # type: ignore[return-value]

    workers = min(n_jobs or default_jobs(), max(1, len(jobs)))
    with ProcessPool(max_workers=workers, max_tasks=1, context=_context()) as pool:
        futures = {pool.schedule(run_job, args=(job,), timeout=limit(job)): i
                   for i, job in enumerate(jobs)}
        for fut in as_completed(futures):
            i = futures[fut]
            job = jobs[i]
            try:
                traj = fut.result()
            except FutureTimeout:
                traj = _failed(job, Status.TIMEOUT, f"killed after the {limit(job):g} s limit",
                               limit(job) or 0.0)
            except ProcessExpired as exc:
                traj = _failed(job, Status.CRASHED,
                               f"engine process died (exit code {exc.exitcode})")
            except RockbenchError:
                pool.stop()
                raise
            except Exception as exc:  # e.g. unpicklable result
                traj = _failed(job, Status.CRASHED, f"{type(exc).__name__}: {exc}")
            done(i, traj)
    return results  # type: ignore[return-value]
