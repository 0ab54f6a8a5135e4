"""Shared by the fragility tests: short synthetic records and a study run in this process."""

from __future__ import annotations

from typing import Any

import numpy as np

from rockbench.engines import engine_class
from rockbench.errors import EngineUnavailable
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Record, Scenario
from rockbench.studies.fragility import (
    FragilityOptions,
    FragilityResult,
    StudyRecord,
    run_fragility,
)

IN_PROCESS = ExecutionOptions(isolate=False)


def pymunk_missing() -> str:
    """Why pymunk cannot run here ('' when it can)."""
    try:
        engine_class("pymunk").check_available()
    except EngineUnavailable as exc:
        return str(exc)
    return ""


def noise_records(n: int = 6, seed: int = 3) -> tuple[StudyRecord, ...]:
    """Short broadband records: five random sines of 0.8–4 Hz under a sin² envelope."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 3.0 + 1e-9, 0.01)
    env = np.sin(np.pi * t / 3.0) ** 2
    out = []
    for i in range(n):
        a = sum(rng.normal() * np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi))
                for f in rng.uniform(0.8, 4.0, 5))
        out.append(StudyRecord(f"noise{i}", Record(t, a * env), f"synthetic, seed {seed}"))
    return tuple(out)


def study(scenario: Scenario, records: Any, levels: Any, **kw: Any) -> FragilityResult:
    """run_fragility in this process, with 200 bootstrap resamples unless told."""
    kw.setdefault("execution", IN_PROCESS)
    kw.setdefault("n_resamples", 200)
    return run_fragility(FragilityOptions(scenario, records, levels=levels, **kw))
