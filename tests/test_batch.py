"""Batched runs: a world of a batch is its scenario run alone, status and all.

Checked on a test engine that steps Housner's equation in many worlds at once
(tests/batch_engine.py), so that the batch loop, its isolation and the runner's
batching are tested on every machine; the same checks on Newton, the real batch
engine, are in tests/test_engine_newton.py.
"""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

import numpy as np
import pytest

from rockbench.analytic import reference
from rockbench.cli import main
from rockbench.engines import register, unregister
from rockbench.engines.batch import batch_size, simulate_many
from rockbench.evaluation import evaluate_run
from rockbench.runner import ExecutionError, ExecutionOptions, Job, plan_batches, run_jobs
from rockbench.scenarios import Block, Scenario, SinePulse, stack
from rockbench.trajectory import Status, Trajectory

sys.path.insert(0, str(Path(__file__).parent))
batch_engine = importlib.import_module("batch_engine")
Engine = batch_engine.HousnerBatchEngine

BLOCK = Block(0.2, 0.2, 0.8, mass=10.0)  # λ = 0.245 rad
FAST = {"preset": "fast"}  # a 1 ms step: the loop's checks need no accuracy


def pulses(n: int = 6, duration: float = 2.0) -> list[Scenario]:
    """2 Hz pulses from below uplift (g tan λ = 2.45 m/s²) to overturning."""
    return [Scenario(f"pulse-{a * 1e3:.0f}mm", BLOCK, excitation=SinePulse(2.0, a),
                     duration=duration, output_rate=500.0)
            for a in np.linspace(5e-3, 60e-3, n)]


@pytest.fixture(autouse=True)
def registered() -> object:
    register(Engine.name, Engine)
    yield
    unregister(Engine.name)


def same(a: Trajectory, b: Trajectory) -> bool:
    return (a.status == b.status and a.message == b.message
            and np.array_equal(a.t, b.t) and np.array_equal(a.theta, b.theta)
            and np.array_equal(a.x, b.x) and np.array_equal(a.z, b.z))


def test_the_test_engine_follows_housner() -> None:
    # the engine under the batch loop does real physics: free rocking within 2 % of λ
    sc = Scenario("free", BLOCK, initial_tilt=0.5 * BLOCK.rocking().lam, duration=2.0)
    traj = Engine().simulate(sc)
    assert evaluate_run(sc, traj, reference(sc)).max_error < 0.02


def test_worlds_of_a_batch_equal_their_runs_alone() -> None:
    scs = [*pulses(), Scenario("free", BLOCK, initial_tilt=0.1, duration=2.0,
                               output_rate=500.0)]
    alone = [Engine().simulate(sc, FAST) for sc in scs]
    many = Engine().simulate_many(scs, FAST)
    statuses = {t.status for t in alone}
    assert {Status.OK, Status.OVERTURNED} <= statuses  # the sweep spans both outcomes
    for a, b in zip(alone, many, strict=True):
        assert same(a, b), a.scenario
        assert b.settings["batch_worlds"] == len(scs)
        assert b.scenario == a.scenario


def test_a_failing_world_leaves_the_others_alone() -> None:
    scs = pulses()
    poisoned = {**FAST, "nan_world": 2, "nan_at": 0.5}
    many = Engine().simulate_many(scs, poisoned)
    bad = many[2]
    assert bad.status is Status.UNSTABLE and "NaN" in bad.message
    # cut at the first failing sample, not at the end of its chunk
    assert bad.t[-1] == pytest.approx(0.5, abs=2.5e-3)
    for i, sc in enumerate(scs):
        if i != 2:
            assert same(many[i], Engine().simulate(sc, FAST)), sc.name


def test_unsupported_and_shorter_scenarios_in_one_call() -> None:
    two = Scenario("two", stack((BLOCK, BLOCK)), duration=2.0, output_rate=500.0)
    short = pulses(2, duration=1.0)
    scs = [*pulses(3), two, *short]
    many = simulate_many(Engine(), scs, FAST)
    assert many[3].status is Status.UNSUPPORTED and "at most 1 block" in many[3].message
    for sc, traj in zip(scs, many, strict=True):
        if sc is not two:
            assert same(traj, Engine().simulate(sc, FAST)), sc.name
    # the shorter runs are worlds of the same batch, cut at their own end
    assert {t.settings.get("batch_worlds") for t in many} == {5, None}
    assert many[-1].t[-1] == pytest.approx(1.0)


def test_plan_splits_over_workers_and_the_cap() -> None:
    jobs = [Job(sc, Engine.name) for sc in pulses(40)]
    jobs.insert(5, Job(pulses(1)[0], "analytic"))
    plan = plan_batches(jobs, 0, workers=2)
    assert sorted(i for b in plan for i in b) == list(range(len(jobs)))
    assert [5] in plan
    sizes = sorted(len(b) for b in plan if b != [5])
    assert max(sizes) <= batch_size(Engine) == 16 and sum(sizes) == 40
    assert plan_batches(jobs, 1, workers=2) == [[i] for i in range(len(jobs))]
    assert max(len(b) for b in plan_batches(jobs, 4, workers=1)) == 4
    # other settings, other batches
    mixed = [Job(sc, Engine.name, {"preset": p}) for sc in pulses(4) for p in ("fast", "")]
    for b in plan_batches(mixed, 0, workers=1):
        assert len({mixed[i].settings.get("preset") for i in b}) == 1


@pytest.mark.slow
@pytest.mark.parametrize("isolate", [True, False])
def test_run_jobs_batched_equals_run_by_run(isolate: bool) -> None:
    jobs = [Job(sc, Engine.name, FAST) for sc in pulses(8)]
    seen: list[str] = []
    batched = run_jobs(jobs, ExecutionOptions(jobs=2, isolate=isolate),
                       on_result=lambda job, traj: seen.append(job.scenario.name))
    single = run_jobs(jobs, ExecutionOptions(jobs=2, isolate=isolate, batch=1))
    assert sorted(seen) == sorted(j.scenario.name for j in jobs)
    for a, b in zip(single, batched, strict=True):
        assert same(a, b)
        assert b.settings["batch_worlds"] == 4 and "batch_worlds" not in a.settings


def test_a_batch_that_raises_is_run_again_one_by_one(monkeypatch: pytest.MonkeyPatch) -> None:
    def broken(self: object, scenarios: object, settings: object = None) -> None:
        raise RuntimeError("injected")

    monkeypatch.setattr(Engine, "simulate_many", broken)
    jobs = [Job(sc, Engine.name, FAST) for sc in pulses(4)]
    out = run_jobs(jobs, ExecutionOptions(isolate=False))
    for job, traj in zip(jobs, out, strict=True):
        assert same(traj, Engine().simulate(job.scenario, FAST))


def test_bad_batch_option() -> None:
    with pytest.raises(ExecutionError, match="batch must be an integer >= 0"):
        ExecutionOptions(batch=-1)


def test_cli_rejects_a_bad_batch(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["matrix", "--suite", "smoke", "--engine", "analytic", "--batch", "-2",
                 "--tolerances", "smoke", "--no-db"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--batch must be an integer >= 0" in err[0]
