"""The pruned preset search of benchmarks/preset_pareto.py on synthetic outcomes (no runs)."""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence

import pytest

from benchmarks.preset_pareto import (
    ERROR_FLOOR,
    GRIDS,
    GUARD_TOL,
    PEAK_FLOOR,
    PRESETS,
    SLACK,
    CaseResult,
    candidates,
    group_bounds,
    guard_meets,
    prune_search,
)
from rockbench.engines import engine_info
from rockbench.trajectory import Status

OK = Status.OK
CASES = ("a", "b", "c", "d")


def _r(error: float, cpu: float, peak: float = 0.0, status: Status = OK) -> CaseResult:
    return CaseResult(status, error, peak, cpu)


class _Table:
    """A judge from a table of results; counts the runs it is asked for."""

    def __init__(self, table: Mapping[str, Mapping[str, CaseResult]],
                 known: Sequence[tuple[str, str]] = ()) -> None:
        self.table = table
        self.have = set(known)
        self.asked: list[tuple[str, str]] = []

    def known(self, label: str, case: str) -> bool:
        return (label, case) in self.have

    def results(self, label: str, cases: Sequence[str]) -> dict[str, CaseResult]:
        for n in cases:
            if (label, n) not in self.have:
                self.asked.append((label, n))
                self.have.add((label, n))
        return {n: self.table[label][n] for n in cases}


BOUND = {n: _r(0.01, 1.0, 0.01) for n in CASES}  # the preset: 4 s of CPU


def _all(error: float, cpu: float, peak: float = 0.01) -> dict[str, CaseResult]:
    return {n: _r(error, cpu, peak) for n in CASES}


def test_meets_rule_slack_floors_and_status() -> None:
    b = _r(0.01, 1.0, 0.01)
    assert _r(SLACK * 0.01, 1.0, 0.01).meets(b)
    assert not _r(SLACK * 0.01 * 1.01, 1.0, 0.01).meets(b)
    assert not _r(0.01, 1.0, SLACK * 0.01 * 1.01).meets(b)
    assert not _r(0.0, 1.0, 0.0, Status.OVERTURNED).meets(b)
    tiny = _r(1e-6, 1.0, 1e-6)  # a preset far more precise than the floors
    assert _r(ERROR_FLOOR, 1.0, PEAK_FLOOR).meets(tiny)
    assert not _r(1.01 * ERROR_FLOOR, 1.0, 0.0).meets(tiny)


def test_guard_rule_judges_the_peak_against_the_stack_limit() -> None:
    b = _r(0.5, 1.0, 0.017)
    assert guard_meets(_r(9.0, 1.0, GUARD_TOL), b)  # max |Δθ| not judged
    assert not guard_meets(_r(0.0, 1.0, 1.01 * GUARD_TOL), b)
    assert not guard_meets(_r(0.0, 1.0, 0.0, Status.UNSTABLE), b)


def test_picks_the_cheapest_meeting_candidate_and_prunes_the_rest() -> None:
    table = {
        "x": {**_all(0.005, 0.1), "c": _r(0.05, 0.1, 0.01)},  # cheapest, fails c
        "y": _all(0.011, 0.3),  # meets: 1.2 s
        "z": _all(0.001, 0.25),  # meets, but its estimate ranked it after y
        "w": _all(0.001, 0.5),  # estimate above y's cost: never run
    }
    judge = _Table(table)
    est = {"p": 4.0, "x": 0.4, "y": 1.0, "z": 1.1, "w": 1.3}
    s = prune_search("p", BOUND, est, judge, cost_cases=CASES, jobs=1)
    assert [t.label for t in s.trials] == ["x", "y", "z"]
    assert s.skipped == ("w",)
    assert s.best.label == "z"  # measured 1.0 s < y's 1.2 s, though estimated dearer
    assert s.ratio == pytest.approx(4.0 / 1.0)
    x, y, _ = s.trials
    assert x.failed == "c" and x.cpu is None and x.ran[-1] == "c"
    # y runs the case where x failed first
    assert y.met and y.ran[0] == "c" and set(y.ran) == set(CASES)
    assert not any(lab == "w" for lab, _ in judge.asked)


def test_known_runs_first_and_abandoned_at_the_first_failure() -> None:
    table = {"x": {**_all(0.001, 0.1), "b": _r(0.5, 0.1)}}
    judge = _Table(table, known=[("x", "d")])
    s = prune_search("p", BOUND, {"x": 0.4}, judge, cost_cases=CASES, jobs=2)
    (t,) = s.trials
    assert t.ran[0] == "d"  # the known (probe) run judged first, alone
    assert t.failed == "b"
    # cases in order of the preset's CPU (equal: given order), two at a time, abandoned after b
    assert t.ran == ("d", "a", "b")
    assert ("x", "c") not in judge.asked
    assert s.best.label == "p" and s.ratio == 1.0


def test_guards_judged_but_not_in_the_cost() -> None:
    bound = {**BOUND, "g": _r(0.3, 5.0, 0.02)}
    table = {"x": {**_all(0.001, 0.1), "g": _r(0.9, 5.0, 0.06)},
             "y": {**_all(0.001, 0.2), "g": _r(0.9, 5.0, 0.04)}}
    s = prune_search("p", bound, {"x": 0.4, "y": 0.8}, _Table(table), cost_cases=CASES,
                     guards=("g",), jobs=1)
    assert s.cost == pytest.approx(4.0)
    assert s.trials[0].failed == "g"
    assert s.best.label == "y" and s.best.cpu == pytest.approx(0.8)


def test_budget_leaves_the_rest_unjudged() -> None:
    table = {"x": _all(0.5, 0.1), "y": _all(0.001, 0.2)}
    calls = itertools.count()
    s = prune_search("p", BOUND, {"x": 0.4, "y": 0.8}, _Table(table), cost_cases=CASES,
                     stop=lambda: next(calls) >= 1)
    assert [t.label for t in s.trials] == ["x"] and s.unjudged == ("y",)
    assert s.best.label == "p"


@pytest.mark.parametrize("engine", sorted(GRIDS))
def test_grids_hold_the_presets_once_and_valid_settings(engine: str) -> None:
    info = engine_info(engine)
    if not info.available:  # blender: only in its own interpreter
        pytest.skip(info.reason)
    cands = candidates(engine)
    assert [k for k in cands if k.startswith("preset=")] == [f"preset={p}" for p in PRESETS]
    # both presets are grid points (their neighbours are the grid's other values): the
    # combinations equal to them are dropped, so the count is the grid's size
    assert len(cands) == math.prod(len(axis) for axis in GRIDS[engine])


def test_group_bounds_raise_each_case_to_its_groups_worst() -> None:
    bound = {"a": _r(0.01, 1.0, 0.02), "b": _r(0.03, 2.0, 0.001),
             "c": _r(float("inf"), 3.0, 0.05, Status.OVERTURNED), "g": _r(0.5, 1.0, 0.01)}
    gb = group_bounds(bound, [["a", "b", "c"]])
    assert gb["a"].error == gb["b"].error == gb["c"].error == 0.03  # the finite worst
    assert gb["a"].peak == 0.05 and gb["b"].cpu == 2.0
    assert gb["c"].status is Status.OVERTURNED and gb["g"] == bound["g"]
    assert _r(0.033, 1.0, 0.02).meets(gb["a"]) and not _r(0.033, 1.0, 0.02).meets(bound["a"])
