"""Plausibility limits: memory budget before allocation, physics step vs output interval."""

from __future__ import annotations

import pytest

from rockbench.cli import main
from rockbench.engines import SettingsError, get_engine
from rockbench.errors import ScenarioError
from rockbench.limits import BUDGET_ENV, BYTES_PER_SAMPLE, check_memory, estimated_bytes
from rockbench.runner import ExecutionOptions, Job, run_jobs
from rockbench.scenarios import Block, Scenario

BLOCK = Block(0.5, 0.2, 1.0, mass=1.0)


def test_estimate_counts_samples_and_blocks() -> None:
    sc = Scenario("s", BLOCK, initial_tilt=0.5, duration=10.0, output_rate=100.0)
    assert estimated_bytes(sc) == pytest.approx(1001 * (BYTES_PER_SAMPLE + 8))


def test_budget_refuses_before_allocation(monkeypatch: pytest.MonkeyPatch) -> None:
    huge = Scenario("huge", BLOCK, initial_tilt=0.5, duration=1e6)  # 1e9 samples
    with pytest.raises(ScenarioError, match="over the 2 GB budget"):
        check_memory(huge)
    with pytest.raises(ScenarioError, match="--max-memory"):  # refused in the parent
        run_jobs([Job(huge, "analytic", {})], ExecutionOptions())
    with pytest.raises(ScenarioError):  # and by the engine itself (API users)
        get_engine("analytic").simulate(huge)
    monkeypatch.setenv(BUDGET_ENV, "1e6")
    check_memory(huge)  # a raised budget lets it through
    monkeypatch.setenv(BUDGET_ENV, "nan")
    with pytest.raises(ScenarioError, match=BUDGET_ENV):
        check_memory(huge)


def test_max_memory_flag(tmp_path, capsys: pytest.CaptureFixture) -> None:
    path = tmp_path / "s.toml"
    path.write_text('name = "s"\nduration = 60.0\n[[blocks]]\nwidth = 0.5\ndepth = 0.2\n'
                    'height = 1.0\nmass = 1.0\n[initial]\ntilt = 0.5\n')
    assert main(["run", str(path), "--max-memory", "0.001"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "0.001 GB budget" in err[0]
    assert main(["run", str(path), "--max-memory", "-2"]) == 2
    assert "--max-memory" in capsys.readouterr().err


def test_physics_step_longer_than_output_interval_is_refused() -> None:
    sc = Scenario("s", BLOCK, initial_tilt=0.5, duration=0.5, output_rate=1000.0)
    with pytest.raises(SettingsError, match="longer than the output interval"):
        get_engine("pymunk").simulate(sc, {"timestep": 10.0})
    with pytest.raises(SettingsError, match="longer than the output interval"):
        get_engine("pymunk").simulate(sc, {"timestep": 2e-3})
    ok = get_engine("pymunk").simulate(sc, {"timestep": 1e-3})  # equal is fine
    assert ok.status.completed
