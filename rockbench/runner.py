"""Running scenario × engine jobs, isolated in child processes with a time limit.

A crash (segfault, exception), a hang, NaN or an explosion in one run becomes
that run's :class:`~rockbench.trajectory.Status` with a reason; the others
carry on. Results are handed to a callback as each job finishes, so callers can
write them incrementally and lose nothing if the run is interrupted.

Executors
---------
``"process"`` (default)
    A local :class:`pebble.ProcessPool`; every job gets a fresh child process
    (``max_tasks=1``) that is killed when it exceeds its time limit.
``"dask"``
    The same jobs as tasks on a Dask distributed cluster (``pip install
    'rockbench[dask]'``). Each task starts the engine run in a fresh Python
    subprocess on the worker with the same time limit, so a segfault or a hang
    never takes a worker down. Engines registered at run time in this process
    (:func:`rockbench.engines.register`) are shipped to the workers by
    ``module:Class`` reference; the module must be importable there.
"""

from __future__ import annotations

import multiprocessing
import os
import pickle
import signal
import subprocess
import sys
import tempfile
import time
import traceback
from collections.abc import Callable, Iterable, Iterator, Mapping
from concurrent.futures import TimeoutError as FutureTimeout
from concurrent.futures import as_completed
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pebble import ProcessExpired, ProcessPool

from rockbench.bounds import check_trajectory
from rockbench.engines import engine_class, get_engine, register
from rockbench.errors import RockbenchError, UnknownEngine
from rockbench.scenarios import Scenario
from rockbench.trajectory import Status, Trajectory

__all__ = ["Job", "run_job", "run_jobs", "default_jobs", "run_job_subprocess", "dask_client",
           "EXECUTORS"]

#: Names accepted by ``run_jobs(executor=...)`` and ``--executor``.
EXECUTORS = ("process", "dask")


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
    try:
        return run_job(job)
    except RockbenchError as exc:
        raise _portable(exc) from None


def _context() -> multiprocessing.context.BaseContext:
    # fork keeps run-time registrations (e.g. test engines) visible in children
    methods = multiprocessing.get_all_start_methods()
    return multiprocessing.get_context("fork" if "fork" in methods else "spawn")


def run_jobs(
    jobs: Iterable[Job],
    *,
    n_jobs: int | None = 1,
    timeout: float | Callable[[Job], float | None] | None = None,
    isolate: bool = True,
    on_result: Callable[[Job, Trajectory], None] | None = None,
    executor: str = "process",
    scheduler: Any = None,
) -> list[Trajectory]:
    """Run jobs and return their trajectories in the order given.

    Parameters
    ----------
    jobs : iterable of Job
        What to run.
    n_jobs : int, optional
        Worker processes (None: the machine's cores). Ignored when not isolating
        and with a Dask scheduler address (the cluster decides).
    timeout : float or callable, optional
        Wall-time limit per job in s (or a function of the job); a job that
        exceeds it is killed and reported as ``timeout``.
    isolate : bool
        Run each job in its own child process (default). ``False`` runs in this
        process, without protection against crashes and hangs.
    on_result : callable, optional
        Called as ``on_result(job, trajectory)`` in this process as soon as
        each job finishes.
    executor : {"process", "dask"}
        Local process pool or a Dask distributed cluster.
    scheduler : str or distributed.Client, optional
        With ``executor="dask"``: the scheduler address (``tcp://host:8786``)
        or a connected client; None starts a local cluster of ``n_jobs``
        single-threaded workers for the duration of the call.

    Raises
    ------
    RockbenchError
        Bad input detected in a job (unknown engine, bad settings, unknown
        executor, Dask not installed).
    """
    jobs = list(jobs)
    results: list[Trajectory | None] = [None] * len(jobs)

    def limit(job: Job) -> float | None:
        return timeout(job) if callable(timeout) else timeout

    def done(i: int, traj: Trajectory) -> None:
        results[i] = traj
        if on_result is not None:
            on_result(jobs[i], traj)

    if executor not in EXECUTORS:
        raise RockbenchError(f"unknown executor {executor!r}; choose one of "
                             f"{', '.join(EXECUTORS)}")
    if not jobs:
        return []
    if executor == "dask":
        _run_dask(jobs, limit, done, n_jobs, scheduler)
        return results  # type: ignore[return-value]
    if not isolate:
        for i, job in enumerate(jobs):
            done(i, run_job(job))
        return results  # type: ignore[return-value]

    workers = min(n_jobs or default_jobs(), len(jobs))
    pool = ProcessPool(max_workers=workers, max_tasks=1, context=_context())
    try:
        futures = {pool.schedule(_pool_job, args=(job,), timeout=limit(job)): i
                   for i, job in enumerate(jobs)}
        for fut in as_completed(futures):
            i = futures[fut]
            job = jobs[i]
            try:
                traj = fut.result()
            except FutureTimeout:
                lim = limit(job) or 0.0
                traj = _failed(job, Status.TIMEOUT, f"killed after the {lim:g} s limit", lim)
            except ProcessExpired as exc:
                traj = _failed(job, Status.CRASHED, _death(exc.exitcode))
            except RockbenchError:
                raise
            except Exception as exc:  # e.g. unpicklable result
                traj = _failed(job, Status.CRASHED, f"{type(exc).__name__}: {exc}")
            done(i, traj)
    except BaseException:  # bad input, Ctrl-C: kill the children, keep what was reported
        pool.stop()
        pool.join()
        raise
    pool.close()
    pool.join()
    return results  # type: ignore[return-value]


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
            proc = subprocess.run([sys.executable, "-m", "rockbench.runner", str(src), str(dst)],
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


def _child_main(src: str, dst: str) -> int:
    """Entry point of the subprocess started by :func:`run_job_subprocess`."""
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


def _run_dask(jobs: list[Job], limit: Callable[[Job], float | None],
              done: Callable[[int, Trajectory], None], n_jobs: int | None,
              scheduler: Any) -> None:
    with dask_client(n_jobs, scheduler) as client:
        from distributed import as_completed as dask_completed

        specs = {name: _engine_spec(name) for name in {j.engine for j in jobs}}
        futures = {client.submit(run_job_subprocess, job, limit(job), specs[job.engine],
                                 pure=False, key=f"rockbench-{i}-{os.getpid()}-{time.time_ns()}"):
                   i for i, job in enumerate(jobs)}
        try:
            for fut in dask_completed(futures):
                i = futures[fut]
                try:
                    traj = fut.result()
                except RockbenchError:
                    raise
                except Exception as exc:  # worker lost, unpicklable result, ...
                    traj = _failed(jobs[i], Status.CRASHED, f"{type(exc).__name__}: {exc}")
                done(i, traj)
        except BaseException:
            client.cancel(list(futures))
            raise


if __name__ == "__main__":  # the isolated child of run_job_subprocess
    sys.exit(_child_main(sys.argv[1], sys.argv[2]))
