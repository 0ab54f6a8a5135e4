"""Fault isolation: every injected fault becomes a status with a reason; the parent carries on."""

from __future__ import annotations

import importlib
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from rockbench.bounds import SpeedBound, check_trajectory
from rockbench.engines import SettingsError, register, unregister
from rockbench.errors import RockbenchError
from rockbench.runner import (
    ExecutionError,
    ExecutionOptions,
    Job,
    cost_hint,
    default_jobs,
    map_tasks,
    run_job,
    run_job_subprocess,
    run_jobs,
)
from rockbench.scenarios import Block, Free, Scenario, SinePulse
from rockbench.trajectory import Status, Trajectory

# every test here runs engines for seconds (measured with --durations): the slow tier
pytestmark = pytest.mark.slow

sys.path.insert(0, str(Path(__file__).parent))
fault_engine = importlib.import_module("fault_engine")

SCENARIO = Scenario("tiny-free", Block(0.2, 0.2, 0.8, mass=1.0), initial_tilt=0.3,
                    duration=0.3, output_rate=200.0)

#: fault → (status, words expected in the message)
EXPECTED = {
    "none": (Status.OK, ""),
    "exception": (Status.CRASHED, "RuntimeError: injected fault"),
    "segfault": (Status.CRASHED, "SIGSEGV"),
    "abort": (Status.CRASHED, "SIGABRT"),
    "exit": (Status.CRASHED, "exit code 3"),
    "hang": (Status.TIMEOUT, "killed after the 2 s limit"),
    "nan": (Status.UNSTABLE, "NaN"),
    "explode": (Status.UNSTABLE, "left the scene"),
    "speed": (Status.UNSTABLE, "exceeds the physical bound"),
    "energy": (Status.UNSTABLE, "energy gain"),
}


@pytest.fixture(autouse=True)
def fault() -> object:
    register("fault", fault_engine.FaultEngine)
    yield
    unregister("fault")


def test_every_fault_becomes_a_status_and_the_parent_carries_on() -> None:
    jobs = [Job(SCENARIO, "fault", {"fault": f}) for f in EXPECTED]
    seen: list[str] = []
    start = time.perf_counter()
    trajs = run_jobs(jobs, ExecutionOptions(jobs=2, timeout=2.0),
                     on_result=lambda job, traj: seen.append(job.settings["fault"]))
    assert time.perf_counter() - start < 20
    assert sorted(seen) == sorted(EXPECTED)  # reported as each finished
    for job, traj in zip(jobs, trajs, strict=True):
        status, words = EXPECTED[job.settings["fault"]]
        assert traj.status is status, (job.settings, traj.message)
        assert words in traj.message
        assert traj.engine == "fault"
        assert traj.n_blocks == 1


def test_unstable_trajectories_keep_samples_up_to_the_fault() -> None:
    traj = run_jobs([Job(SCENARIO, "fault", {"fault": "nan", "at": 0.1})],
                    ExecutionOptions(timeout=10))[0]
    assert traj.status is Status.UNSTABLE
    assert 0.09 < traj.t[-1] < 0.13


def test_bad_settings_are_bad_input_not_a_crash() -> None:
    with pytest.raises(SettingsError):
        run_jobs([Job(SCENARIO, "fault", {"fault": "bogus"})], ExecutionOptions(timeout=10))
    with pytest.raises(SettingsError):
        run_job(Job(SCENARIO, "fault", {"no_such_knob": 1}))


def test_unknown_engine_crosses_the_process_boundary() -> None:
    with pytest.raises(RockbenchError, match="unknown engine"):
        run_jobs([Job(SCENARIO, "nosuchengine")], ExecutionOptions(timeout=10))


def test_in_process_run_and_default_jobs() -> None:
    traj = run_jobs([Job(SCENARIO, "fault")], ExecutionOptions(isolate=False))[0]
    assert traj.status is Status.OK and traj.t.size == 61
    assert default_jobs() >= 1
    with pytest.raises(RockbenchError, match="executor"):
        run_jobs([Job(SCENARIO, "fault")], ExecutionOptions(executor="threads"))


@pytest.mark.parametrize("kw, words", [
    ({"jobs": 0}, "jobs must be >= 1"),
    ({"jobs": 1.5}, "jobs must be >= 1"),
    ({"jobs": True}, "jobs must be >= 1"),
    ({"timeout": 0}, "timeout must be a finite number of seconds > 0"),
    ({"timeout": -1.0}, "timeout must be a finite number of seconds > 0"),
    ({"timeout": float("nan")}, "timeout must be a finite number of seconds > 0"),
    ({"timeout": float("inf")}, "timeout must be a finite number of seconds > 0"),
    ({"timeout": "10"}, "timeout must be a finite number of seconds > 0"),
    ({"executor": "threads"}, "executor must be one of process, dask"),
    ({"scheduler": "tcp://x:1"}, "scheduler needs executor dask"),
])
def test_execution_options_are_validated_once(kw: dict, words: str) -> None:
    with pytest.raises(ExecutionError, match=words):
        ExecutionOptions(**kw)


def _square(x: int) -> int:
    if x < 0:
        time.sleep(30)  # a task that hangs
    return x * x


def test_map_tasks_dispatches_any_function_locally() -> None:
    seen: list[int] = []
    local = map_tasks(_square, [3, 1, 2], ExecutionOptions(jobs=2),
                      on_done=lambda i, v: seen.append(v))
    here = map_tasks(_square, [3, 1, 2], ExecutionOptions(isolate=False))
    assert local == here == [9, 1, 4] and sorted(seen) == [1, 4, 9]
    faults: list[str] = []
    out = map_tasks(_square, [2, -1], ExecutionOptions(jobs=2, timeout=1.0),
                    on_fault=lambda i, f: faults.append(f.kind) or -1)
    assert out == [4, -1] and faults == ["timeout"]
    with pytest.raises(RockbenchError, match="task 2 of 2 failed: killed after the 1 s limit"):
        map_tasks(_square, [2, -1], ExecutionOptions(jobs=2, timeout=1.0))


def test_map_tasks_dispatches_in_the_order_asked_and_returns_in_task_order() -> None:
    seen: list[int] = []
    out = map_tasks(_square, [3, 1, 2], ExecutionOptions(jobs=1), order=[2, 0, 1],
                    on_done=lambda i, v: seen.append(i))
    assert out == [9, 1, 4] and seen == [2, 0, 1]  # one worker: done in dispatch order
    with pytest.raises(ValueError, match="permutation"):
        map_tasks(_square, [3, 1], ExecutionOptions(jobs=1), order=[0, 0])


def test_run_jobs_dispatches_the_longest_runs_first() -> None:
    # the same engine: cost ∝ duration × blocks / step, so the 0.3 s run at the
    # finer step goes first, the short one at the coarse step last
    short = SCENARIO.replace(name="short", duration=0.1)
    jobs = [Job(short, "fault", {"timestep": 1e-3}), Job(SCENARIO, "fault", {"timestep": 1e-3}),
            Job(SCENARIO, "fault", {"timestep": 5e-4})]
    hints = [cost_hint(j) for j in jobs]
    assert hints == pytest.approx([100.0, 300.0, 600.0])
    seen: list[str] = []
    trajs = run_jobs(jobs, ExecutionOptions(jobs=1),
                     on_result=lambda j, t: seen.append(f"{j.scenario.name}/{j.settings}"))
    assert seen == ["tiny-free/{'timestep': 0.0005}", "tiny-free/{'timestep': 0.001}",
                    "short/{'timestep': 0.001}"]
    assert [t.scenario for t in trajs] == ["short", "tiny-free", "tiny-free"]
    assert cost_hint(Job(SCENARIO, "fault", {"no_such_knob": 1})) == 0.0


def test_subprocess_isolation_ships_runtime_registrations() -> None:
    spec = "fault_engine:FaultEngine"
    assert run_job_subprocess(Job(SCENARIO, "fault", {"fault": "segfault"}), 20,
                              spec).status is Status.CRASHED
    traj = run_job_subprocess(Job(SCENARIO, "fault", {"fault": "hang"}), 1.5, spec)
    assert traj.status is Status.TIMEOUT
    with pytest.raises(RockbenchError, match="fault must be one of"):
        run_job_subprocess(Job(SCENARIO, "fault", {"fault": "bogus"}), 20, spec)


# ---------------------------------------------------------------------- physical bounds
def test_speed_bound_from_the_scenario() -> None:
    b = SpeedBound.for_scenario(SCENARIO)
    assert b.v_max == pytest.approx(3 * np.sqrt(2 * 9.81 * 0.8) + 0.5)
    k = np.sqrt((0.2**2 + 0.8**2) / 12)
    assert b.omega_max == pytest.approx(b.v_max / k)
    moving = SCENARIO.replace(excitation=SinePulse(frequency=2.0, amplitude=0.05))
    v_base = 0.05 * 2 * np.pi * 2.0 * 2  # peak of Aω(1 − cos ωt)
    assert SpeedBound.for_scenario(moving).v_max == pytest.approx(b.v_max + 3 * 2 * v_base,
                                                                  rel=1e-3)


def _traj(x: np.ndarray, theta: np.ndarray) -> Trajectory:
    t = np.arange(x.size) / 100.0
    return Trajectory(t=t, theta=theta, x=x, z=np.full(x.size, 0.4))


def test_check_trajectory_flags_and_cuts() -> None:
    n = 50
    calm = _traj(np.zeros(n), np.linspace(0, 0.1, n))
    assert check_trajectory(calm, SCENARIO) is calm
    x = np.zeros(n)
    x[20:] = 1.0  # 1 m in 10 ms = 100 m/s
    bad = check_trajectory(_traj(x, np.zeros(n)), SCENARIO)
    assert bad.status is Status.UNSTABLE and "centroid speed" in bad.message
    assert bad.t.size == 21
    th = np.zeros(n)
    th[30:] = 1.4  # 1.4 rad in 10 ms
    spin = check_trajectory(_traj(np.zeros(n), th), SCENARIO)
    assert spin.status is Status.UNSTABLE and "rocking rate" in spin.message
    th = np.zeros(n)
    th[10] = np.nan
    assert "NaN" in check_trajectory(_traj(np.zeros(n), th), SCENARIO).message
    analytic_like = Trajectory(t=np.arange(n) / 100.0, theta=np.zeros(n))  # x unknown
    assert check_trajectory(analytic_like, SCENARIO) is analytic_like
    failed = Trajectory.failed(Status.CRASHED, "x")
    assert check_trajectory(failed, SCENARIO) is failed


# ---------------------------------------------------------------------- Dask
def test_dask_local_cluster_runs_the_same_isolated_jobs() -> None:
    distributed = pytest.importorskip("distributed")
    scenario = SCENARIO.replace(excitation=Free())
    jobs = [Job(scenario, "fault", {"fault": f}) for f in ("none", "exception", "segfault",
                                                           "hang")]
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        seen = []
        trajs = run_jobs(jobs, ExecutionOptions(executor="dask", scheduler=client),
                         timeout_of=lambda job: 3.0 if job.settings["fault"] == "hang" else 60.0,
                         on_result=lambda j, t: seen.append(j.settings["fault"]))
        # the address form, as given by --scheduler
        again = run_jobs(jobs[:1], ExecutionOptions(executor="dask", timeout=20.0,
                                                    scheduler=cluster.scheduler_address))
        squares = map_tasks(_square, [1, 2, 3], ExecutionOptions(executor="dask",
                                                                 scheduler=client))
    assert [t.status for t in trajs] == [Status.OK, Status.CRASHED, Status.CRASHED,
                                        Status.TIMEOUT]
    assert "SIGSEGV" in trajs[2].message
    assert sorted(seen) == sorted(j.settings["fault"] for j in jobs)
    assert again[0].status is Status.OK
    assert squares == [1, 4, 9]


_PARENT = """
import signal, sys
# a study dies of these signals by default; the harness (nohup, CI) may have them ignored
for sig in (signal.SIGHUP, signal.SIGTERM):
    signal.signal(sig, signal.SIG_DFL)
sys.path.insert(0, {tests!r})
import fault_engine
from rockbench.engines import register
from rockbench.runner import ExecutionOptions, Job, run_job_subprocess, run_jobs
from rockbench.scenarios import Block, Scenario

register("fault", fault_engine.FaultEngine)
sc = Scenario("hang", Block(0.2, 0.2, 0.8, mass=1.0), duration=5.0, output_rate=200.0)
job = Job(sc, "fault", {{"fault": "hang", "at": 0.0}})
print("ready", flush=True)
if {subprocess!r}:
    run_job_subprocess(job, timeout=600.0, engine_spec="fault_engine:FaultEngine")
else:
    run_jobs([job], ExecutionOptions(jobs=1, timeout=600.0))
"""


def _children(pid: int) -> list[int]:
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            out.append(int(stat.parent.name))
    return out


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG is Linux's")
@pytest.mark.parametrize("how", ["pool", "subprocess"])
@pytest.mark.parametrize("sig", ["SIGKILL", "SIGTERM", "SIGHUP"])
def test_hanging_children_die_with_their_parent(how: str, sig: str) -> None:
    """A study killed by CI or `timeout` leaves no engine child hanging on (issue 14)."""
    import signal
    import subprocess

    code = _PARENT.format(tests=str(Path(__file__).parent), subprocess=how == "subprocess")
    parent = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE,
                              stderr=subprocess.DEVNULL, text=True)
    try:
        assert parent.stdout is not None and parent.stdout.readline().strip() == "ready"
        deadline = time.monotonic() + 60.0
        kids: list[int] = []
        while not kids and time.monotonic() < deadline:  # the engine child has started
            kids = [k for k in _children(parent.pid) if _alive(k)]
            time.sleep(0.2)
        assert kids, "no child process appeared"
        time.sleep(1.0)  # the child is hanging inside the engine now
        parent.send_signal(getattr(signal, sig))
        parent.wait(timeout=30)
        deadline = time.monotonic() + 20.0
        while any(_alive(k) for k in kids) and time.monotonic() < deadline:
            time.sleep(0.2)
        assert not any(_alive(k) for k in kids), f"children {kids} outlived their parent"
    finally:
        if parent.poll() is None:
            parent.kill()
