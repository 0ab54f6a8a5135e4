"""Warm workers: runs share worker processes, and a fault still costs only the run in flight."""

from __future__ import annotations

import importlib
import os
import signal
import sys
import threading
import time
from pathlib import Path
from typing import ClassVar

import numpy as np
import pytest

from rockbench.engines import register, unregister
from rockbench.runner import ExecutionError, ExecutionOptions, Job, map_tasks, run_jobs
from rockbench.scenarios import Block, Scenario
from rockbench.trajectory import Status, Trajectory

sys.path.insert(0, str(Path(__file__).parent))
fault_engine = importlib.import_module("fault_engine")

SCENARIO = Scenario("tiny-free", Block(0.2, 0.2, 0.8, mass=1.0), initial_tilt=0.0,
                    duration=0.3, output_rate=200.0)


class PidEngine(fault_engine.FaultEngine):
    """The fault engine, telling which process ran it through its version string."""

    name: ClassVar[str] = "pid"

    @classmethod
    def version(cls) -> str:
        return f"pid {os.getpid()}"


class FreshPidEngine(PidEngine):
    """The same, declaring global state: a fresh process for every run."""

    name: ClassVar[str] = "freshpid"
    fresh_process: ClassVar[bool] = True


@pytest.fixture(autouse=True)
def engines() -> object:
    register("pid", PidEngine)
    register("freshpid", FreshPidEngine)
    yield
    unregister("pid")
    unregister("freshpid")


def _pid(x: int) -> int:
    return os.getpid()


def _allocate(gb: float) -> int:
    """Touch ``gb`` GB (a memory blow-up) or report the process id for ``gb = 0``."""
    if gb:
        return int(np.ones(int(gb * 1e9 / 8)).size)
    return os.getpid()


def test_warm_workers_run_many_tasks_and_fresh_ones_one() -> None:
    warm = map_tasks(_pid, list(range(6)), ExecutionOptions(jobs=1))
    fresh = map_tasks(_pid, list(range(6)), ExecutionOptions(jobs=1), fresh=True)
    assert len(set(warm)) == 1 and os.getpid() not in warm
    assert len(set(fresh)) == 6


def test_engines_with_global_state_get_a_fresh_process_per_run() -> None:
    jobs = [Job(SCENARIO, e) for e in ("pid", "freshpid") for _ in range(3)]
    trajs = run_jobs(jobs, ExecutionOptions(jobs=1))
    assert all(t.status is Status.OK for t in trajs)
    pids = [t.engine_version for t in trajs]
    assert len(set(pids[:3])) == 1  # one warm worker of "pid" ran all three
    assert len(set(pids[3:])) == 3
    cold = run_jobs(jobs[:3], ExecutionOptions(jobs=1, warm=False))
    assert len({t.engine_version for t in cold}) == 3


def test_a_warm_worker_killed_mid_run_costs_only_that_run() -> None:
    """SIGKILL from outside while a reused worker hangs in a run (issue 19)."""
    faults = ["none", "hang", "none", "none"]
    jobs = [Job(SCENARIO, "pid", {"fault": f, "at": 0.0}) for f in faults]
    started: list[int] = []  # the warm worker's pid, as the first run reports it
    seen: list[str] = []
    first = threading.Event()

    def on_result(job: Job, traj: Trajectory) -> None:
        seen.append(job.settings["fault"])
        if not started:
            started.append(int(traj.engine_version.split()[1]))
            first.set()

    def killer() -> None:
        if first.wait(60):
            time.sleep(0.5)  # the same worker is in the hanging run now
            os.kill(started[0], signal.SIGKILL)

    thread = threading.Thread(target=killer, daemon=True)
    thread.start()
    start = time.monotonic()
    trajs = run_jobs(jobs, ExecutionOptions(jobs=1, timeout=120.0), on_result=on_result)
    thread.join(5)
    assert time.monotonic() - start < 60  # not the 120 s time limit
    assert [t.status for t in trajs] == [Status.OK, Status.CRASHED, Status.OK, Status.OK]
    assert "SIGKILL" in trajs[1].message and trajs[1].engine == "pid"
    assert seen == faults
    before, after = trajs[0].engine_version, {t.engine_version for t in trajs[2:]}
    assert len(after) == 1 and before not in after  # a fresh worker, warm again


@pytest.mark.slow
def test_timeouts_and_crashes_in_a_warm_worker_spare_the_next_runs() -> None:
    faults = ["none", "segfault", "none", "hang", "none", "exit", "none"]
    jobs = [Job(SCENARIO, "pid", {"fault": f, "at": 0.0}) for f in faults]
    trajs = run_jobs(jobs, ExecutionOptions(jobs=1, timeout=2.0))
    assert [t.status for t in trajs] == [Status.OK, Status.CRASHED, Status.OK, Status.TIMEOUT,
                                        Status.OK, Status.CRASHED, Status.OK]
    assert "SIGSEGV" in trajs[1].message and "exit code 3" in trajs[5].message
    pids = [t.engine_version for t in trajs if t.status is Status.OK]
    assert len(set(pids)) == 4  # a new worker after each of the three faults
    ok = [t for t in trajs if t.status is Status.OK]
    for t in ok:  # a reused or replaced worker computes the same thing
        np.testing.assert_array_equal(t.theta, ok[0].theta)


def test_a_memory_blow_up_is_a_fault_of_that_task_under_the_worker_limit() -> None:
    faults: list[str] = []
    out = map_tasks(_allocate, [0, 20.0, 0], ExecutionOptions(jobs=1, worker_memory=2.0),
                    on_fault=lambda i, f: faults.append(f.message) or -1)
    assert out[1] == -1 and "MemoryError" in faults[0]
    assert out[0] == out[2]  # the worker survived the refused allocation and goes on
    assert ExecutionOptions().worker_memory_bytes() >= 8e9
    assert ExecutionOptions(worker_memory=float("inf")).worker_memory_bytes() == float("inf")
    for bad in (0, -1.0, float("nan"), "8", True):
        with pytest.raises(ExecutionError, match="worker-memory"):
            ExecutionOptions(worker_memory=bad)
