"""``rockbench calibrate``: the search plan, the physics it shows, reuse, the report, the CLI.

Runs use pymunk (cheap: a few ms of CPU per simulated second at its ``fast``
preset) on shortened free-rocking cases, in this process (``isolate=False``).
"""

from __future__ import annotations

import csv
import importlib
import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar, Literal

import matplotlib.image as mpimg
import pytest

from rockbench.cli import main
from rockbench.engines import (
    EngineSettings,
    KnobRole,
    SettingsError,
    engine_class,
    register,
    unregister,
)
from rockbench.report.calibration_report import (
    calibration_table,
    format_calibration,
    write_calibration_report,
)
from rockbench.report.options import ReportOptions
from rockbench.runner import ExecutionOptions
from rockbench.store import Store
from rockbench.studies.calibration import (
    FREE,
    PULSES,
    Calibration,
    CalibrationError,
    Tolerances,
    calibrate,
    calibration_cases,
    max_timestep,
    run_plan,
    stored_calibration,
)
from rockbench.studies.calibration_plan import explicit_plan, plan_search

pytest.importorskip("pymunk")

sys.path.insert(0, str(Path(__file__).parent))
FaultEngine = importlib.import_module("fault_engine").FaultEngine

#: In this process, one run after the other: no worker start-up in a test.
HERE = ExecutionOptions(jobs=1, isolate=False)


# ---------------------------------------------------------------------- the plan
@dataclass(frozen=True)
class LadderSettings(EngineSettings):
    """Knobs of every kind a search meets."""

    timestep: float | None = None
    substeps: int = 9
    stiffness: float = 1e6
    shape: Literal["box", "convex", "mesh"] = "box"
    margin: float = 0.01


class LadderEngine(FaultEngine):
    """The fault engine with :class:`LadderSettings` (planned, never run)."""

    Settings: ClassVar[type[EngineSettings]] = LadderSettings
    presets: ClassVar[dict] = {"accurate": {}, "fast": {"substeps": 1},
                               "stiff": {"stiffness": 2e6}}
    knob_roles: ClassVar[dict] = {
        "timestep": KnobRole.TIME_STEP, "stiffness": KnobRole.CONTACT_STIFFNESS,
        "substeps": KnobRole.SUBSTEPS, "shape": KnobRole.COLLISION_SHAPE,
        "margin": KnobRole.COLLISION_MARGIN}
    refinement: ClassVar[str] = "substeps"


@pytest.fixture
def ladder() -> object:
    register("ladder", LadderEngine)
    yield
    unregister("ladder")


def _rungs(plan, knob: str) -> list[tuple[int, object]]:
    return [(s.level, s.value) for s in plan.settings if s.knob == knob]


def test_plan_follows_the_declared_roles(ladder: object) -> None:
    plan = plan_search("ladder", levels=2)
    # the refinement knob first; n sub-steps → (n + 1)·2 − 1 per finer rung, so the step
    # 1/(n + 1) halves; a stiffness doubles; every other value of a choice
    assert plan.knobs == ("substeps", "stiffness", "shape")
    assert _rungs(plan, "substeps") == [(-2, 2), (-1, 4), (1, 19), (2, 39)]
    assert _rungs(plan, "stiffness") == [(-2, 2.5e5), (-1, 5e5), (1, 2e6), (2, 4e6)]
    assert _rungs(plan, "shape") == [(0, "convex"), (0, "mesh")]
    # left at the preset, with the reason: unset, and no direction
    assert {s.knob: s.reason for s in plan.skipped} == {
        "timestep": "accurate sets it to None, not a number to refine",
        "margin": "a collision margin has no finer direction and is not a choice"}
    # the start first; a rung equal to a preset is that preset (not run twice); the others
    # are added at the end
    assert plan.settings[0].label == "accurate" and plan.settings[0].presets == ("accurate",)
    stiff = next(s for s in plan.settings if s.knob == "stiffness" and s.level == 1)
    assert stiff.presets == ("stiff",)
    assert [s.label for s in plan.settings if s.is_preset] == ["accurate", "fast"]
    assert [s.label for s in plan_search("ladder", levels=0).settings] == [
        "accurate", "shape=convex", "shape=mesh", "fast", "stiff"]
    assert [s.label for s in plan_search("ladder", levels=1, presets=False,
                                         knobs=["substeps"]).settings] == [
        "accurate", "substeps=4", "substeps=19"]


def test_plan_of_pymunk_halves_its_step() -> None:
    plan = plan_search("pymunk", preset="accurate", levels=2)
    steps = sorted(_rungs(plan, "timestep"))
    assert [lvl for lvl, _ in steps] == [-2, -1, 1, 2]
    values = [v for _, v in steps[:2]] + [2.5e-5] + [v for _, v in steps[2:]]
    for coarse, fine in zip(values, values[1:], strict=False):
        assert fine == pytest.approx(coarse / 2, rel=1e-12)
    assert _rungs(plan, "iterations") == [(-2, 5), (-1, 10), (1, 40), (2, 80)]
    assert [s.knob for s in plan.skipped] == ["collision_slop"]
    # four times the accurate step is the single preset, exactly (one run identity)
    single = next(s for s in plan.settings if s.knob == "timestep" and s.level == -2)
    assert single.presets == ("single",) and single.value == 1e-4
    assert plan.resolved(single) == engine_class("pymunk").settings("single")
    assert [s.label for s in plan.settings if s.is_preset] == ["accurate", "fast", "fine"]
    # a step longer than the cases' output interval is left out, with the reason
    fast = plan_search("pymunk", preset="fast", levels=1,
                       max_timestep=max_timestep(calibration_cases("free")))
    assert _rungs(fast, "timestep") == [(1, 5e-4)]
    assert any("longer than the cases' output interval" in s.reason for s in fast.skipped)
    # the step a frame rate and sub-steps give too: Bullet's fast preset (1000 fps, no
    # sub-steps) at 500 fps steps 2 ms, which the engine would refuse on 1 kHz output
    bullet = plan_search("bullet", preset="fast", levels=1,
                         max_timestep=max_timestep(calibration_cases("free")))
    assert _rungs(bullet, "fps") == [(1, 2000.0)]
    assert [s.reason for s in bullet.skipped if s.knob == "fps"] == [
        "500 gives a physics step of 0.002 s, longer than the cases' output interval 0.001 s"]


@pytest.mark.parametrize("kwargs, words", [
    ({"engine": "analytic"}, "analytic reference"),
    ({"knobs": ["nope"]}, "--knobs expects knobs that pymunk declares"),
    ({"levels": -1}, "--levels expects"),
    ({"levels": 99}, "--levels expects"),
    ({"preset": "nope"}, "--preset expects one of"),
])
def test_plan_refuses_bad_requests(kwargs: dict, words: str) -> None:
    with pytest.raises(CalibrationError, match=words):
        plan_search(**{"engine": "pymunk", **kwargs})


def test_cases_and_explicit_plans() -> None:
    assert [sc.name for sc in calibration_cases("free")] == list(FREE)
    assert [sc.name for sc in calibration_cases("all")] == list(FREE + PULSES)
    assert len(FREE) == 10 and len(PULSES) == 6
    assert [sc.name for sc in calibration_cases("free-b0, pulses,free-b0")] == [
        "free-b0", *PULSES]
    assert {sc.duration for sc in calibration_cases("free", duration=2.0)} == {2.0}
    with pytest.raises(CalibrationError, match="--cases expects"):
        calibration_cases("free,nope")
    with pytest.raises(CalibrationError, match="--duration"):
        calibration_cases("free", duration=-1.0)
    plan = explicit_plan("pymunk", [{}, {"timestep": 1e-4}, {"iterations": 10}])
    assert [s.label for s in plan.settings] == ["accurate", "timestep=0.0001", "iterations=10"]
    assert plan.settings[1].presets == ("single",)
    with pytest.raises(SettingsError):
        explicit_plan("pymunk", [{"nope": 1}])
    with pytest.raises(CalibrationError, match="must be a number > 0"):
        Tolerances(max_error=0.0)


# ---------------------------------------------------------------------- the physics
def test_error_falls_as_the_step_is_refined() -> None:
    # free rocking of B1 from 0.2 λ: pymunk converges to Housner at first order, each
    # halving of the step about halves the error (1.2e-3, 7e-4, 4e-4, 2e-4 λ over 2 s)
    cal = calibrate("pymunk", cases="free-b1-0.2", preset="fast", knobs=["timestep"],
                    levels=3, presets=False, duration=2.0, execution=HERE)
    ladder = [cal.start, *sorted((r for r in cal.results if r.setting.knob == "timestep"),
                                 key=lambda r: r.setting.level)]
    assert [r.setting.level for r in ladder] == [0, 1, 2, 3]
    errors = [r.max_error for r in ladder]
    assert all(b < a for a, b in zip(errors, errors[1:], strict=False)), errors
    assert errors[-1] < 0.3 * errors[0]
    assert [r.impact_time_error for r in ladder][-1] < ladder[0].impact_time_error
    # finer steps cost more, and every run rocks to rest as the reference does
    costs = [r.cost for r in ladder]
    assert costs[-1] > 2 * costs[0]
    assert all(r.agreements == 1 and r.complete for r in ladder)
    # free rocking: the peak is the initial tilt, exactly
    assert all(r.peak_error < 1e-6 for r in ladder)


@pytest.fixture(scope="module")
def small(tmp_path_factory: pytest.TempPathFactory) -> tuple[Calibration, Path]:
    """pymunk from fast, one rung either side, the other presets, four 2 s free cases."""
    db = tmp_path_factory.mktemp("cal") / "cal.db"
    cal = calibrate("pymunk", cases="free-b0,free-b1-0.2,free-b2-0.5,free-b3-0.99",
                    preset="fast", levels=1, duration=2.0, db=db, execution=HERE,
                    tolerances=Tolerances(max_error=0.002, peak_error=0.02,
                                          impact_time_error=0.005))
    return cal, db


def test_cheapest_meets_and_nothing_cheaper_does(small: tuple[Calibration, Path]) -> None:
    cal, _ = small
    best = cal.cheapest()
    assert best is not None and best.meets(cal.tolerances)
    assert best.max_error <= 0.002 and best.agreements == 4
    # no cheaper setting, on the front or not, meets the tolerances
    cheaper = [r for r in cal.results if r.cost < best.cost]
    assert cheaper and not any(r.meets(cal.tolerances) for r in cheaper)
    assert all(r.misses(cal.tolerances) for r in cheaper)
    # the front: cheapest first, every step strictly more accurate, and no setting beats
    # a front member in both cost and error
    front = cal.front()
    assert [r.cost for r in front] == sorted(r.cost for r in front)
    errs = [r.max_error for r in front]
    assert all(b < a for a, b in zip(errs, errs[1:], strict=False))
    for f in front:
        assert not any(r.cost < f.cost and r.max_error < f.max_error for r in cal.results)
    # loose tolerances: the cheapest complete setting; impossible ones: none
    loose = Tolerances(max_error=1.0, peak_error=1.0, impact_time_error=1.0)
    assert cal.cheapest(loose) is min((r for r in cal.results if r.complete),
                                      key=lambda r: r.cost)
    assert cal.cheapest(Tolerances(max_error=1e-9)) is None


def test_second_calibration_runs_no_engine(small: tuple[Calibration, Path],
                                           monkeypatch: pytest.MonkeyPatch) -> None:
    cal, db = small
    assert cal.ran == len(cal.results) * len(cal.cases) and cal.reused == 0
    with Store(db) as store:
        rows = len(store)
    from rockbench.engines.pymunk_engine import PymunkEngine

    calls: list[str] = []
    original = PymunkEngine.simulate
    monkeypatch.setattr(PymunkEngine, "simulate",
                        lambda self, sc, s=None: calls.append(sc.name) or original(self, sc, s))
    again = run_plan(cal.plan, cal.cases, tolerances=cal.tolerances, db=db, execution=HERE)
    assert calls == [] and again.ran == 0 and again.reused == cal.ran
    with Store(db) as store:
        assert len(store) == rows
    # the same numbers, and the store alone gives them too
    stored = stored_calibration(cal.plan, cal.cases, db, tolerances=cal.tolerances)
    assert calls == []
    for a, b, c in zip(cal.results, again.results, stored.results, strict=True):
        assert a.max_error == b.max_error == c.max_error
        assert a.cost == b.cost == c.cost and not c.missing
    assert calibration_table(stored).rows == calibration_table(cal).rows
    assert stored.made_by and stored.ran == 0
    # a case the store lacks is missing, and the setting cannot meet the tolerances
    more = calibration_cases("free-b0,free-b1-0.5", duration=2.0)
    partial = stored_calibration(cal.plan, more, db, tolerances=cal.tolerances)
    assert all(r.missing == ("free-b1-0.5",) for r in partial.results)
    assert partial.cheapest() is None


def test_report_files(small: tuple[Calibration, Path], tmp_path: Path) -> None:
    cal, _ = small
    files = write_calibration_report(cal, ReportOptions(tmp_path))
    assert [f.name for f in files] == ["index.html", "report.md", "calibration.csv",
                                       "calibration.png"]
    image = mpimg.imread(files[3])
    assert image.shape[0] > 300 and image.shape[1] > 500
    rows = list(csv.DictReader(files[2].open()))
    assert [r["setting"] for r in rows] == [r.setting.label for r in cal.results]
    assert sum(int(r["cheapest"]) for r in rows) == 1
    assert {r["timestep"] for r in rows} >= {"0.001", "0.0005", "2.5e-05"}
    text = format_calibration(cal)
    assert "| setting | timestep | iterations | rung |" in text
    assert "✓ cheapest" in text and "Cheapest setting meeting the tolerances" in text
    assert "Pareto front" in files[1].read_text()
    assert math.isfinite(float(rows[0]["cost"]))


# ---------------------------------------------------------------------- the command
CLI = ["calibrate", "pymunk", "--cases", "free-b0,free-b1-0.2", "--preset", "fast",
       "--levels", "1", "--knobs", "timestep", "--no-presets", "--duration", "2",
       "--jobs", "1", "-q"]


def test_cli_runs_once_and_regenerates_from_the_store(tmp_path: Path,
                                                      capsys: pytest.CaptureFixture[str]
                                                      ) -> None:
    db = tmp_path / "cal.db"
    assert main([*CLI, "--db", str(db), "--out", str(tmp_path / "a")]) == 0
    first = capsys.readouterr().out
    assert "| **fast** | 0.001 | preset |" in first
    with Store(db) as store:
        rows = len(store)
    assert rows == 4
    # a second calibration reuses every run; --from-store runs nothing and says so
    assert main([*CLI[:-1], "--db", str(db), "--out", str(tmp_path / "b")]) == 0
    assert "0 runs now, 4 reused from the store" in capsys.readouterr().out
    assert main([*CLI[:-1], "--db", str(db), "--out", str(tmp_path / "c"),
                 "--from-store"]) == 0
    assert "from the store: 4 runs made by" in capsys.readouterr().out
    with Store(db) as store:
        assert len(store) == rows

    def table(name: str) -> str:
        text = (tmp_path / name / "report.md").read_text()
        return text[text.index("### Table 1"):text.index("![")]

    assert table("c") == table("a")
    assert (tmp_path / "c" / "calibration.csv").read_text() == \
        (tmp_path / "a" / "calibration.csv").read_text()


@pytest.mark.parametrize("argv, words", [
    (["calibrate", "nosuch"], "unknown engine 'nosuch'"),
    (["calibrate", "analytic"], "analytic reference"),
    (["calibrate", "pymunk", "--knobs", "timestep,nope"], "--knobs expects knobs"),
    (["calibrate", "pymunk", "--levels", "x"], "argument --levels: invalid int value"),
    (["calibrate", "pymunk", "--levels", "-1"], "--levels expects a whole number"),
    (["calibrate", "pymunk", "--cases", "free,nope"], "--cases expects"),
    (["calibrate", "pymunk", "--tolerance", "peak=1"], "--tolerance expects NAME=VALUE"),
    (["calibrate", "pymunk", "--from-store", "--no-db"], "--from-store reads"),
])
def test_cli_bad_input_is_one_line_and_status_2(argv: list[str], words: str, tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    try:
        status = main([*argv, "--db", str(tmp_path / "x.db"), "--out", str(tmp_path / "o")])
    except SystemExit as exc:  # argparse's own errors
        status = exc.code
    err = capsys.readouterr().err.strip().splitlines()
    err = [ln for ln in err if not ln.startswith("pybullet build time")]
    assert status == 2 and len(err) == 1 and words in err[0], err
    assert not (tmp_path / "o").exists() and not (tmp_path / "x.db").exists()
