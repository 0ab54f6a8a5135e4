"""Running scenario × engine jobs, isolated in child processes with a time limit.

A crash (segfault, exception), a hang, NaN or an explosion in one run becomes
that run's :class:`~rockbench.trajectory.Status` with a reason; the others
carry on. Results are handed to a callback as each job finishes, so callers can
write them incrementally and lose nothing if the run is interrupted.

Every study says how to run through one :class:`ExecutionOptions` (workers,
time limit, executor, scheduler, isolation; validated once, for every command)
and dispatches through one function, :func:`map_tasks` (any picklable
function over tasks, locally or on Dask); :func:`run_jobs` is it applied to
engine jobs.

Executors
---------
``"process"`` (default)
    Local :class:`pebble.ProcessPool` s of *warm* workers, one pool per engine:
    a worker imports its engine once and runs many jobs (``max_tasks=0``), and
    at most ``jobs`` runs are in flight over all pools. A run that exceeds its
    time limit has its worker killed; a worker that dies (segfault, abort,
    ``os._exit``, SIGKILL from outside, the memory limit) fails its run with
    ``ProcessExpired``. Either way only the run in flight gets the status
    (``timeout`` / ``crashed``) and pebble starts a fresh worker for the next
    runs. Each worker dies with the study (:func:`die_with_parent`) and has an
    address-space limit (``ExecutionOptions.worker_memory``), so a memory
    blow-up is a ``MemoryError`` or a dead worker, not the machine's
    out-of-memory killer. Engines that keep global state between runs declare
    ``Engine.fresh_process = True`` and get a fresh child for every run, as
    does every engine with ``ExecutionOptions(warm=False)``.
``"dask"``
    The same jobs as tasks on a Dask distributed cluster (``pip install
    'rockbench[dask]'``). Each task starts the engine run in a fresh Python
    subprocess on the worker with the same time limit, so a segfault or a hang
    never takes a worker down. Engines registered at run time in this process
    (:func:`rockbench.engines.register`) are shipped to the workers by
    ``module:Class`` reference; the module must be importable there.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import pickle
import signal
import subprocess
import sys
import tempfile
import time
import traceback
from collections import Counter, deque
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, wait
from concurrent.futures import TimeoutError as FutureTimeout
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pebble import ProcessExpired, ProcessPool

from rockbench.bounds import check_trajectory
from rockbench.engines import engine_class, get_engine, register
from rockbench.errors import RockbenchError, UnknownEngine
from rockbench.limits import check_memory, memory_budget
from rockbench.method import Method
from rockbench.scenarios import Scenario
from rockbench.trajectory import Status, Trajectory

__all__ = ["Job", "ExecutionOptions", "ExecutionError", "TaskFault", "run_job", "run_jobs",
           "run_batch", "plan_batches",
           "cost_hint", "map_tasks", "default_jobs", "run_job_subprocess", "dask_client",
           "EXECUTORS", "DEFAULT_TIMEOUT", "WORKER_HEADROOM_GB", "WorkerGroup", "limit_memory"]

#: Names accepted by ``ExecutionOptions(executor=...)`` and ``--executor``.
EXECUTORS = ("process", "dask")
#: Time limit of a run when none is given (s): every run has one.
DEFAULT_TIMEOUT = 600.0
#: Address space a worker may map beyond the per-run memory budget, in GB. The
#: engines' libraries map 0.15-0.5 GB (VmPeak of one run, measured for mujoco,
#: bullet, dart, pymunk, drake, dem2d, analytic); the rest is room for thread
#: stacks and malloc arenas, which count against an address-space limit.
WORKER_HEADROOM_GB = 6.0


class ExecutionError(RockbenchError, ValueError):
    """Invalid execution options (workers, time limit, executor, scheduler)."""


def check_execution(jobs: Any, timeout: Any, executor: Any, scheduler: Any, *,
                    flag: str = "", worker_memory: Any = None, batch: Any = 0) -> None:
    """The one validation of execution options (``flag="--"`` names them as options).

    Raises
    ------
    ExecutionError
        ``jobs`` not an integer >= 1, ``timeout`` not a finite number > 0, an
        unknown executor, a scheduler without the Dask executor, or a
        ``worker_memory`` that is not None or a number of GB > 0, a ``batch`` that is
        not an integer >= 0.
    """
    if isinstance(batch, bool) or not isinstance(batch, int) or batch < 0:
        raise ExecutionError(f"{flag}batch must be an integer >= 0 (0: the engine's own "
                             f"batch size, 1: one run at a time), got {batch!r}")
    if worker_memory is not None and (
            isinstance(worker_memory, bool) or not isinstance(worker_memory, (int, float))
            or math.isnan(worker_memory) or worker_memory <= 0):
        raise ExecutionError(f"{flag}worker-memory must be a number of GB > 0 (inf: no "
                             f"limit), got {worker_memory!r}")
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ExecutionError(f"{flag}jobs must be >= 1, got {jobs!r}")
    if (isinstance(timeout, bool) or not isinstance(timeout, (int, float))
            or not math.isfinite(timeout) or timeout <= 0):
        raise ExecutionError(f"{flag}timeout must be a finite number of seconds > 0, "
                             f"got {timeout!r}")
    if executor not in EXECUTORS:
        raise ExecutionError(f"{flag}executor must be one of {', '.join(EXECUTORS)}, "
                             f"got {executor!r}")
    if scheduler is not None and scheduler != "" and executor != "dask":
        raise ExecutionError(f"{flag}scheduler needs {flag}executor dask")


@dataclass(frozen=True)
class ExecutionOptions:
    """How a study runs its work: the one execution-options type of every study.

    Attributes
    ----------
    jobs : int
        Parallel workers (local processes, or the size of a local Dask cluster).
    timeout : float
        Wall-time limit per run in s (finite, > 0: every run has a limit).
    executor : {"process", "dask"}
        Local process pool or a Dask distributed cluster.
    scheduler : str or distributed.Client, optional
        With ``executor="dask"``: a scheduler address or a connected client;
        None starts a local cluster of ``jobs`` workers for each call.
    isolate : bool
        Run each task in a child process (default). ``False`` runs in this
        process: no protection against crashes and hangs, no time limit.
    warm : bool
        Reuse local worker processes across runs of the same engine (default),
        except for engines declaring ``fresh_process``; ``False`` gives every
        run a fresh child process.
    worker_memory : float, optional
        Address-space limit of each local worker process in GB
        (``RLIMIT_AS``); None (default): the per-run memory budget
        (:func:`rockbench.limits.memory_budget`) plus
        :data:`WORKER_HEADROOM_GB`, 8 GB by default; ``math.inf``: no limit.
    batch : int
        The most runs an engine that steps many worlds at once
        (:class:`~rockbench.engines.batch.BatchEngine`) takes in one call: 0
        (default) its own ``max_batch``, 1 one run at a time. Local executors only.

    Raises
    ------
    ExecutionError
        Invalid values (:func:`check_execution`).
    """

    jobs: int = 1
    timeout: float = DEFAULT_TIMEOUT
    executor: str = "process"
    scheduler: Any = None
    isolate: bool = True
    warm: bool = True
    worker_memory: float | None = None
    batch: int = 0

    def __post_init__(self) -> None:
        check_execution(self.jobs, self.timeout, self.executor, self.scheduler,
                        worker_memory=self.worker_memory, batch=self.batch)
        object.__setattr__(self, "timeout", float(self.timeout))

    def worker_memory_bytes(self) -> float:
        """The workers' address-space limit in bytes (``math.inf``: none)."""
        if self.worker_memory is not None:
            return float(self.worker_memory) * 1e9
        return memory_budget() + WORKER_HEADROOM_GB * 1e9


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
        How the job's method is shown in progress lines (default: its
        :attr:`method`'s label).
    """

    scenario: Scenario
    engine: str
    settings: Mapping[str, Any] = field(default_factory=dict)
    label: str = ""

    @property
    def method(self) -> Method:
        """The method this job runs (engine and requested settings)."""
        return Method.of(self.engine, self.settings)


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


def _death(code: int | None) -> str:
    """Describe how a child process ended from its exit code."""
    if code is not None and code < 0:
        try:
            return f"engine process killed by signal {signal.Signals(-code).name}"
        except ValueError:
            return f"engine process killed by signal {-code}"
    return f"engine process died (exit code {code})"


def run_job(job: Job) -> Trajectory:
    """Run one job in this process.

    Exceptions from the physics become status ``crashed``; NaN and
    non-physical speeds found in the result become ``unstable``
    (:func:`rockbench.bounds.check_trajectory`).

    Raises
    ------
    RockbenchError
        Bad input (unknown engine, bad settings).
    """
    start = time.perf_counter()
    try:
        engine = get_engine(job.engine)
        traj = engine.simulate(job.scenario, dict(job.settings))
    except RockbenchError:
        raise  # bad input (unknown engine, bad knob): the caller reports it
    except Exception as exc:  # a physics library failing is a result, not our crash
        where = traceback.extract_tb(exc.__traceback__)[-1]
        return _failed(job, Status.CRASHED, f"{type(exc).__name__}: {exc} (in {where.name}, "
                       f"{Path(where.filename).name}:{where.lineno})",
                       time.perf_counter() - start)
    return check_trajectory(traj, job.scenario)


def _portable(exc: RockbenchError) -> RockbenchError:
    """``exc`` if it survives pickling (to cross a process boundary), else a plain copy."""
    try:
        pickle.loads(pickle.dumps(exc))
    except Exception:
        return RockbenchError(str(exc))
    return exc


def _pool_job(job: Job) -> Trajectory:
    """:func:`run_job` in a pool child: bad-input errors must unpickle in the parent."""
    return _in_pool(run_job, job)


def _in_pool(fn: Callable[[Any], Any], task: Any) -> Any:
    """``fn(task)`` in a pool child, a bad-input error made portable to the parent."""
    try:
        return fn(task)
    except RockbenchError as exc:
        raise _portable(exc) from None


def die_with_parent(parent: int) -> None:
    """Make this (child) process die when its parent does, however the parent ends.

    On Linux the kernel sends SIGKILL at the parent's death (``prctl``
    ``PR_SET_PDEATHSIG``), so a hanging engine never outlives a study that was
    killed (SIGTERM, SIGKILL, SIGHUP from a CI system or ``timeout``). A parent
    already gone before the call ends the child at once. Elsewhere this does
    nothing.

    Parameters
    ----------
    parent : int
        The parent's process id, taken in the parent.
    """
    if not sys.platform.startswith("linux"):
        return
    import ctypes

    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    if os.getppid() != parent:  # the parent died before the request took hold
        os._exit(1)


def limit_memory(limit: float) -> None:
    """Cap this process's address space at ``limit`` bytes (``RLIMIT_AS``; inf: no cap).

    Allocations beyond it fail (``MemoryError`` in Python, ``bad_alloc`` or an
    abort in C++) instead of growing until the kernel's out-of-memory killer
    picks a process of the machine. A hard limit below the request is kept.
    """
    import resource

    if not math.isfinite(limit):
        return
    _, hard = resource.getrlimit(resource.RLIMIT_AS)
    want = int(limit)
    if hard != resource.RLIM_INFINITY:
        want = min(want, hard)
    resource.setrlimit(resource.RLIMIT_AS, (want, hard))


def _init_worker(parent: int, memory: float) -> None:
    """Initializer of every pool worker: die with the study, cap the address space."""
    die_with_parent(parent)
    limit_memory(memory)


def _context() -> multiprocessing.context.BaseContext:
    # fork keeps run-time registrations (e.g. test engines) visible in children
    methods = multiprocessing.get_all_start_methods()
    return multiprocessing.get_context("fork" if "fork" in methods else "spawn")


def run_jobs(
    jobs: Iterable[Job],
    execution: ExecutionOptions | None = None,
    *,
    on_result: Callable[[Job, Trajectory], None] | None = None,
    timeout_of: Callable[[Job], float | None] | None = None,
) -> list[Trajectory]:
    """Run jobs and return their trajectories in the order given.

    Isolated local runs go to warm worker processes, one pool per engine (a
    fresh child per run for engines with ``fresh_process`` or with
    ``execution.warm`` False); on Dask each run is a fresh Python subprocess.
    A crash, a hang beyond the time limit or an unpicklable result becomes
    that job's status; the worker is replaced and the other jobs go on.

    Parameters
    ----------
    jobs : iterable of Job
        What to run.
    execution : ExecutionOptions, optional
        Workers, time limit, executor, scheduler and isolation (default:
        :class:`ExecutionOptions` ``()``: one isolated local worker).
    on_result : callable, optional
        Called as ``on_result(job, trajectory)`` in this process as soon as
        each job finishes.
    timeout_of : callable, optional
        A per-job time limit in s (instead of ``execution.timeout``).

    Raises
    ------
    RockbenchError
        Bad input detected in a job (unknown engine, bad settings, Dask not
        installed).
    """
    ex = execution or ExecutionOptions()
    jobs = list(jobs)
    for job in jobs:  # refused here, before any child allocates (or any run is lost)
        check_memory(job.scenario)

    def limit(job: Job) -> float | None:
        return timeout_of(job) if timeout_of is not None else ex.timeout

    def failed(i: int, fault: TaskFault) -> Trajectory:
        job = jobs[i]
        if fault.kind == "timeout":
            lim = limit(job) or 0.0
            return _failed(job, Status.TIMEOUT, f"killed after the {lim:g} s limit", lim)
        return _failed(job, Status.CRASHED, fault.message)

    def done(i: int, traj: Trajectory) -> None:
        if on_result is not None:
            on_result(jobs[i], traj)

    if ex.executor == "dask":
        specs = {name: _engine_spec(name) for name in {j.engine for j in jobs}}
        tasks: list[Any] = [(job, limit(job), specs[job.engine]) for job in jobs]
        return map_tasks(_subprocess_task, tasks, ex, on_done=done, on_fault=failed)
    batches = plan_batches(jobs, ex.batch, ex.jobs)
    if len(batches) == len(jobs):
        return _run_singly(jobs, ex, done, failed, limit)
    results: list[Any] = [None] * len(jobs)
    broken: list[int] = []  # jobs of batches that crashed or timed out: rerun one by one

    def batch_done(b: int, trajs: list[Trajectory] | None) -> None:
        if trajs is None:
            broken.extend(batches[b])
            return
        for i, traj in zip(batches[b], trajs, strict=True):
            results[i] = traj
            done(i, traj)

    def batch_failed(b: int, fault: TaskFault) -> list[Trajectory] | None:
        if len(batches[b]) == 1:
            return [failed(batches[b][0], fault)]
        return None

    groups = _worker_groups(jobs, ex)
    tasks = [[jobs[i] for i in b] for b in batches]
    fn = _pool_batch if ex.isolate else run_batch
    map_tasks(fn, tasks, ex, on_done=batch_done, on_fault=batch_failed,
              timeout_of=lambda b: _batch_limit([limit(jobs[i]) for i in batches[b]]),
              group_of=lambda b: groups[tasks[b][0].engine],
              order=sorted(range(len(tasks)), key=lambda b: -sum(map(cost_hint, tasks[b]))))
    if broken:
        broken.sort()
        again = _run_singly([jobs[i] for i in broken], ex, lambda k, t: done(broken[k], t),
                            lambda k, f: failed(broken[k], f), lambda job: limit(job))
        for i, traj in zip(broken, again, strict=True):
            results[i] = traj
    return results


def _run_singly(jobs: list[Job], ex: ExecutionOptions, done: Callable[[int, Trajectory], None],
                failed: Callable[[int, TaskFault], Trajectory],
                limit: Callable[[Job], float | None]) -> list[Trajectory]:
    """:func:`run_jobs` one run per task (the per-run path)."""
    if not ex.isolate:
        return map_tasks(run_job, jobs, ex, on_done=done)
    groups = _worker_groups(jobs, ex)
    # longest first: the last runs dispatched are the short ones, so that no worker
    # idles at the end of a study while another finishes a 20 s free-rocking run
    order = sorted(range(len(jobs)), key=lambda i: -cost_hint(jobs[i]))
    return map_tasks(_pool_job, jobs, ex, on_done=done, on_fault=failed,
                     timeout_of=lambda i: limit(jobs[i]), group_of=lambda i: groups[jobs[i].engine],
                     order=order)


def _worker_groups(jobs: Sequence[Job], ex: ExecutionOptions) -> dict[str, WorkerGroup]:
    """One pool of workers per engine: warm, or a fresh process per task where the engine
    keeps state between runs or ``ex.warm`` is off."""
    return {name: WorkerGroup(name, not ex.warm or _keeps_state(name))
            for name in {j.engine for j in jobs}}


def _batch_limit(limits: list[float | None]) -> float | None:
    """A batch's time limit: the sum of its runs' (None if any has none)."""
    return None if any(x is None for x in limits) else float(sum(x for x in limits if x))


def plan_batches(jobs: Sequence[Job], batch: int = 0, workers: int = 1) -> list[list[int]]:
    """Group jobs into the batches :func:`run_jobs` dispatches (lists of job indices).

    Jobs on an engine that steps many worlds at once
    (:class:`~rockbench.engines.batch.BatchEngine`) with equal settings and
    :func:`~rockbench.engines.batch.batch_key` go together, split evenly over
    ``workers`` and at most ``batch`` (0: the engine's ``max_batch``) per batch; every
    other job is a batch of its own. Batches keep the jobs' order.
    """
    from rockbench.engines.batch import batch_key, batch_size

    together: dict[Any, list[int]] = {}
    out: list[list[int]] = []
    caps: dict[str, int] = {}  # the most runs per batch, by engine
    for i, job in enumerate(jobs):
        try:
            if job.engine not in caps:
                own = batch_size(engine_class(job.engine))
                caps[job.engine] = min(own, batch) if own > 1 and batch else own
            key = (job.engine, job.method, batch_key(job.scenario))
            hash(key)
        except (RockbenchError, TypeError):  # unknown engine, unhashable knob value
            out.append([i])
            continue
        if caps[job.engine] <= 1:
            out.append([i])
        else:
            together.setdefault(key, []).append(i)
    for key, members in together.items():
        size = min(caps[key[0]], max(1, math.ceil(len(members) / workers)))
        out.extend(members[b:b + size] for b in range(0, len(members), size))
    return sorted(out)


def run_batch(jobs: Sequence[Job]) -> list[Trajectory]:
    """Run jobs of one engine and settings in this process, batched where the engine can
    (:func:`~rockbench.engines.batch.simulate_many`); as :func:`run_job` per result.

    A library exception in a batch reruns its jobs one by one, so that only the run that
    raises it is ``crashed``.

    Raises
    ------
    RockbenchError
        Bad input (unknown engine, bad settings).
    """
    from rockbench.engines.batch import simulate_many

    if len(jobs) == 1:
        return [run_job(jobs[0])]
    engine = get_engine(jobs[0].engine)
    try:
        trajs = simulate_many(engine, [j.scenario for j in jobs], dict(jobs[0].settings))
    except RockbenchError:
        raise
    except Exception:  # the library failed in one world or all: each run on its own says which
        return [run_job(job) for job in jobs]
    return [check_trajectory(t, j.scenario) for t, j in zip(trajs, jobs, strict=True)]


def _pool_batch(jobs: list[Job]) -> list[Trajectory]:
    """:func:`run_batch` in a pool child: bad input must unpickle in the parent."""
    return _in_pool(run_batch, jobs)


def cost_hint(job: Job) -> float:
    """A rough relative cost of ``job`` for the dispatch order: simulated time ×
    blocks / the engine's time step (its ``timestep`` knob, else the output interval).

    Engines differ in cost per step by orders of magnitude, so this only ranks a
    study's runs within an engine and by duration; a job whose settings do not
    resolve gets 0 (its worker reports the error).
    """
    sc = job.scenario
    try:
        step = getattr(engine_class(job.engine).resolve_settings(job.settings), "timestep", None)
    except (RockbenchError, TypeError):
        return 0.0
    if not isinstance(step, float) or not step > 0:
        step = 1.0 / sc.output_rate
    return sc.duration * sc.n_blocks / step


def _keeps_state(name: str) -> bool:
    """Whether engine ``name`` needs a fresh process per run (unknown names: yes,
    so that the child reports the bad name as before)."""
    try:
        return bool(engine_class(name).fresh_process)
    except UnknownEngine:
        return True


# ---------------------------------------------------------------------- the dispatcher
@dataclass(frozen=True)
class WorkerGroup:
    """Which local workers run a task: tasks of one group share a pool of warm
    workers (an engine's library imported once per worker) unless ``fresh``, when
    every task gets a new process."""

    name: str = ""
    fresh: bool = False


@dataclass(frozen=True)
class TaskFault:
    """Why a task gave no result: ``timeout`` (killed at its limit), ``died`` (the
    worker process ended) or ``error`` (an exception that is not bad input)."""

    kind: str
    message: str


def map_tasks(
    fn: Callable[[Any], Any],
    tasks: Sequence[Any],
    execution: ExecutionOptions | None = None,
    *,
    on_done: Callable[[int, Any], None] | None = None,
    on_fault: Callable[[int, TaskFault], Any] | None = None,
    timeout_of: Callable[[int], float | None] | None = None,
    fresh: bool = False,
    group_of: Callable[[int], WorkerGroup] | None = None,
    order: Sequence[int] | None = None,
) -> list[Any]:
    """Apply a picklable function to each task, locally or on Dask: the one dispatcher.

    Every study's parallel work goes through here (:func:`run_jobs` for engine
    runs, the spectrum's analytic column scans, ...).

    Parameters
    ----------
    fn : callable
        Module-level (picklable) function of one task.
    tasks : sequence
        Its arguments (picklable).
    execution : ExecutionOptions, optional
        ``isolate=False`` runs here, one task after the other; otherwise a
        local process pool of ``jobs`` workers or a Dask cluster.
    on_done : callable, optional
        ``on_done(index, result)`` in this process as each task finishes.
    on_fault : callable, optional
        ``on_fault(index, fault)`` turns a task that timed out, whose process
        died or that raised an unexpected exception into a result; without it
        such a task raises :class:`RockbenchError`.
    timeout_of : callable, optional
        Time limit of task ``index`` in s (default ``execution.timeout``);
        enforced by the local pool. On Dask ``fn`` must enforce its own limit
        (:func:`run_jobs` runs each job in a subprocess with one).
    fresh : bool
        A new worker process for every task (engines keep global state);
        default: warm workers that run many tasks.
    group_of : callable, optional
        The :class:`WorkerGroup` of task ``index`` (default: one group, fresh
        as ``fresh``): a local pool per group, at most ``execution.jobs`` tasks
        in flight over all of them. A worker killed at a time limit or dead
        fails only its task; its pool starts a new one.
    order : sequence of int, optional
        The order in which the local pool dispatches the tasks (a permutation of
        their indices; default: as given). Results keep the order of ``tasks``.

    Raises
    ------
    RockbenchError
        Bad input raised by a task (passed through), or a fault without ``on_fault``.
    """
    ex = execution or ExecutionOptions()
    results: list[Any] = [None] * len(tasks)

    def finish(i: int, value: Any) -> None:
        results[i] = value
        if on_done is not None:
            on_done(i, value)

    def fault(i: int, f: TaskFault) -> None:
        if on_fault is None:
            raise RockbenchError(f"task {i + 1} of {len(tasks)} failed: {f.message}")
        finish(i, on_fault(i, f))

    if not tasks:
        return []
    if ex.executor == "dask":
        _map_dask(fn, tasks, ex, finish, fault)
        return results
    if not ex.isolate:
        for i, task in enumerate(tasks):
            finish(i, fn(task))
        return results

    def limit(i: int) -> float | None:
        return timeout_of(i) if timeout_of is not None else ex.timeout

    group = group_of or (lambda i: WorkerGroup("", fresh))
    left = Counter(group(i) for i in range(len(tasks)))  # tasks not yet scheduled, per group
    pools: dict[WorkerGroup, ProcessPool] = {}
    memory = ex.worker_memory_bytes()

    workers: dict[WorkerGroup, int] = {}  # the workers of each group's pool

    def schedule(i: int) -> Any:
        g = group(i)
        if g not in pools:
            workers[g] = min(ex.jobs, left[g])
            pools[g] = ProcessPool(max_workers=workers[g],
                                   max_tasks=1 if g.fresh else 0, context=_context(),
                                   initializer=_init_worker, initargs=(os.getpid(), memory))
        fut = pools[g].schedule(fn, args=(tasks[i],), timeout=limit(i))
        left[g] -= 1
        if not left[g]:
            pools[g].close()  # its workers end when their last task is done
        return fut

    def can_schedule(i: int) -> bool:
        # at most ``jobs`` tasks run at once over all pools; a pool whose workers are
        # all busy may hold one more task per worker in its queue, which a worker
        # starts as soon as it is free (no round trip through this loop between two
        # short runs). Pebble counts a time limit from the task's start, not from here.
        g = group(i)
        n = workers.get(g, min(ex.jobs, left[g]))
        queued = Counter(group(k) for k in running.values())  # handed to a pool, not done
        if queued[g] >= n:
            return queued[g] < 2 * n
        return sum(min(q, workers[h]) for h, q in queued.items()) < ex.jobs

    waiting = deque(range(len(tasks)) if order is None else order)
    if sorted(waiting) != list(range(len(tasks))):
        raise ValueError("order must be a permutation of the task indices")
    running: dict[Any, int] = {}
    try:
        while waiting or running:
            while waiting and can_schedule(waiting[0]):
                i = waiting.popleft()
                running[schedule(i)] = i
            ready, _ = wait(running, return_when=FIRST_COMPLETED)
            # several may be done at once (a queued task runs without this loop): in
            # dispatch order, not the set's
            for fut in [f for f in running if f in ready]:
                i = running.pop(fut)
                try:
                    value = fut.result()
                except FutureTimeout:
                    fault(i, TaskFault("timeout",
                                       f"killed after the {limit(i) or 0.0:g} s limit"))
                    continue
                except ProcessExpired as exc:
                    fault(i, TaskFault("died", _death(exc.exitcode)))
                    continue
                except RockbenchError:
                    raise
                except Exception as exc:  # e.g. an unpicklable result
                    fault(i, TaskFault("error", f"{type(exc).__name__}: {exc}"))
                    continue
                finish(i, value)
    except BaseException:  # bad input, Ctrl-C: kill the children, keep what was reported
        for pool in pools.values():
            pool.stop()
        for pool in pools.values():
            pool.join()
        raise
    for pool in pools.values():
        pool.close()
        pool.join()
    return results


# ---------------------------------------------------------------------- subprocess isolation
def _engine_spec(name: str) -> str:
    """``module:Class`` of the engine registered as ``name`` (for other interpreters)."""
    cls = engine_class(name)
    return f"{cls.__module__}:{cls.__qualname__}"


def run_job_subprocess(job: Job, timeout: float | None = None,
                       engine_spec: str | None = None) -> Trajectory:
    """Run one job in a fresh Python subprocess with a time limit.

    Unlike the process pool this works inside daemonic processes (Dask
    workers). The job goes to the child as a pickle file and the trajectory
    comes back the same way.

    Parameters
    ----------
    job : Job
        What to run.
    timeout : float, optional
        Wall-time limit in s; the child is killed when it is exceeded.
    engine_spec : str, optional
        ``module:Class`` to register under ``job.engine`` in the child when the
        name is not an installed plugin (run-time registrations).

    Raises
    ------
    RockbenchError
        Bad input detected in the child (re-raised here).
    """
    with tempfile.TemporaryDirectory(prefix="rockbench-") as tmp:
        src, dst = Path(tmp, "job.pkl"), Path(tmp, "result.pkl")
        src.write_bytes(pickle.dumps((job, engine_spec)))
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(p for p in [*sys.path, env.get("PYTHONPATH", "")]
                                            if p)
        start = time.perf_counter()
        try:
            proc = subprocess.run([sys.executable, "-m", "rockbench.runner", str(src), str(dst),
                                   str(os.getpid())],
                                  env=env, timeout=timeout, stdin=subprocess.DEVNULL,
                                  stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, check=False)
        except subprocess.TimeoutExpired:
            return _failed(job, Status.TIMEOUT, f"killed after the {timeout:g} s limit",
                           time.perf_counter() - start)
        if not dst.exists():
            tail = proc.stderr.decode(errors="replace").strip().splitlines()[-1:]
            note = f" ({tail[0]})" if tail else ""
            return _failed(job, Status.CRASHED, _death(proc.returncode) + note,
                           time.perf_counter() - start)
        kind, payload = pickle.loads(dst.read_bytes())
    if kind == "error":
        raise payload
    return payload


def _child_main(src: str, dst: str, parent: int) -> int:
    """Entry point of the subprocess started by :func:`run_job_subprocess`."""
    die_with_parent(parent)
    job, spec = pickle.loads(Path(src).read_bytes())
    if spec:
        try:
            engine_class(job.engine)
        except UnknownEngine:
            register(job.engine, spec)
    try:
        out: tuple[str, Any] = ("ok", run_job(job))
    except RockbenchError as exc:
        out = ("error", _portable(exc))
    Path(dst).write_bytes(pickle.dumps(out))
    return 0


@contextmanager
def dask_client(n_jobs: int | None, scheduler: Any) -> Iterator[Any]:
    """A Dask client for the ``dask`` executor: ``scheduler`` itself if it is a
    ``distributed.Client``, a client of the scheduler at that address if it is a
    string, else a local cluster of ``n_jobs`` single-threaded worker processes.
    What it opened is closed on exit."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise RockbenchError("--executor dask needs Dask distributed: "
                             "pip install 'rockbench[dask]'") from None
    cluster = None
    if scheduler is None:
        cluster = LocalCluster(n_workers=n_jobs or default_jobs(), threads_per_worker=1,
                               processes=True, dashboard_address=None)
        client = Client(cluster)
    elif isinstance(scheduler, str):
        try:
            client = Client(scheduler, timeout="20s")
        except OSError as exc:
            raise RockbenchError(f"cannot reach the Dask scheduler {scheduler!r}: {exc}") from None
    else:
        client = scheduler
    try:
        yield client
    finally:
        if client is not scheduler:
            client.close()
        if cluster is not None:
            cluster.close()


def _subprocess_task(task: tuple[Job, float | None, str]) -> Trajectory:
    """One Dask task of :func:`run_jobs`: the job in a fresh subprocess with its limit."""
    job, limit, spec = task
    return run_job_subprocess(job, limit, spec)


def _map_dask(fn: Callable[[Any], Any], tasks: Sequence[Any], ex: ExecutionOptions,
              finish: Callable[[int, Any], None],
              fault: Callable[[int, TaskFault], None]) -> None:
    with dask_client(ex.jobs, ex.scheduler) as client:
        from distributed import as_completed as dask_completed

        stamp = f"{os.getpid()}-{time.time_ns()}"
        futures = {client.submit(fn, task, pure=False, key=f"rockbench-{i}-{stamp}"): i
                   for i, task in enumerate(tasks)}
        try:
            for fut in dask_completed(futures):
                i = futures[fut]
                try:
                    value = fut.result()
                except RockbenchError:
                    raise
                except Exception as exc:  # worker lost, unpicklable result, ...
                    fault(i, TaskFault("error", f"{type(exc).__name__}: {exc}"))
                    continue
                finish(i, value)
        except BaseException:
            client.cancel(list(futures))
            raise


if __name__ == "__main__":  # the isolated child of run_job_subprocess
    sys.exit(_child_main(sys.argv[1], sys.argv[2], int(sys.argv[3])))
