"""``rockbench compare``: the report built from a small, fast suite on two methods.

Expected numbers are recomputed here from the stored trajectories with plain
numpy (never taken from the code under test), then looked up in the CSV, the
Markdown and the HTML.
"""

from __future__ import annotations

import csv
import math
import struct
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from rockbench.cli import main
from rockbench.engines import engine_info
from rockbench.scenarios import load_scenario
from rockbench.store import Store

FREE = """
name = "tiny-free"
duration = 2.0
output_rate = 200.0
[[blocks]]
width = 0.5
depth = 0.2
height = 1.0
mass = 1.0
[initial]
tilt = 0.5
"""
PULSE = """
name = "tiny-pulse"
duration = 1.5
output_rate = 200.0
[[blocks]]
width = 0.17
depth = 0.502
height = 1.0
density = 2670.0
[excitation]
type = "sine-pulse"
frequency = 3.0
amplitude = 0.008
"""
THREE = """
name = "tiny-three"
duration = 0.5
output_rate = 200.0
""" + """
[[blocks]]
width = 0.3
depth = 0.2
height = 0.6
mass = 1.0
""" * 3 + """
[excitation]
type = "sine-pulse"
frequency = 3.0
amplitude = 0.008
"""
SCENARIOS = ("tiny-free", "tiny-pulse", "tiny-three")


def _engine() -> str:
    """The physics engine used: pymunk, else mujoco; skip with the reason if neither."""
    reasons = []
    for name in ("pymunk", "mujoco"):
        info = engine_info(name)
        if info.available:
            return name
        reasons.append(info.reason)
    pytest.skip("no physics engine available for the report test: " + "; ".join(reasons))


@pytest.fixture(scope="module")
def report(tmp_path_factory: pytest.TempPathFactory) -> dict:
    tmp = tmp_path_factory.mktemp("report")
    files = []
    for name, text in zip(SCENARIOS, (FREE, PULSE, THREE), strict=True):
        path = tmp / f"{name}.toml"
        path.write_text(text)
        files.append(str(path))
    engine = _engine()
    out = tmp / "out"
    argv = ["compare", "--scenarios", ",".join(files), "--engine", engine,
            "--presets", "fast", "--out", str(out), "--db", str(tmp / "runs.db"), "--quiet"]
    assert main(argv) == 0
    return {"out": out, "engine": engine, "argv": argv, "files": files, "tmp": tmp}


def _csv(out: Path) -> list[dict[str, str]]:
    with (out / "results.csv").open(newline="") as fh:
        return list(csv.DictReader(fh))


def _row(rows: list[dict[str, str]], scenario: str, method: str) -> dict[str, str]:
    (r,) = [r for r in rows if r["scenario"] == scenario and r["method"] == method]
    return r


def _file(method: str) -> str:
    # trajectories are named engine-preset (the test runs the fast preset only)
    return method if method == "analytic" else f"{method}-fast"


def _theta(out: Path, scenario: str, method: str, block: int = 1) -> np.ndarray:
    with np.load(out / "trajectories" / scenario / f"{_file(method)}.npz") as f:
        return np.asarray(f[f"theta_{block}"])


def _archive(report: dict) -> dict[Path, int]:
    """Every trajectory the campaign archived beside the store (``runs.db`` → ``runs-runs/``),
    with its modification time."""
    with Store(report["tmp"] / "runs.db", create=False) as store:
        folder = store.archive
    assert folder is not None and folder.name == "runs-runs"
    return {p: p.stat().st_mtime_ns for p in folder.glob("*/*.npz")}


def _archived(report: dict, scenario: str, method: str) -> Path:
    """The archived trajectory of the report's run (the store keeps where it lies)."""
    key = _row(_csv(report["out"]), scenario, method)["settings_hash"]
    with Store(report["tmp"] / "runs.db", create=False) as store:
        paths = {r.trajectory for r in store.runs(scenario=scenario, kind="compare")
                 if r.method == method and r.metrics is not None
                 and r.metrics.settings_hash == key}
    (path,) = paths
    return Path(path)


def _lam(report: dict, scenario: str) -> float:
    # λ from the geometry, by hand: atan(b/h) of a single rectangular block
    s = load_scenario(report["tmp"] / f"{scenario}.toml")
    b = s.blocks[0]
    return math.atan(b.width / b.height)


def _table_lines(md: str, scenario: str) -> list[str]:
    return [ln for ln in md.splitlines() if ln.startswith(f"| **{scenario}**")]


@pytest.mark.slow
def test_files_exist(report: dict) -> None:
    out = report["out"]
    for name in ("index.html", "report.md", "results.csv"):
        assert (out / name).is_file() and (out / name).stat().st_size > 0
    for s in SCENARIOS:
        for m in ("analytic", report["engine"]):
            assert (out / "trajectories" / s / f"{_file(m)}.npz").is_file()
            assert (out / "trajectories" / s / f"{_file(m)}.json").is_file()


def test_csv_rows_are_scenarios_times_methods(report: dict) -> None:
    rows = _csv(report["out"])
    assert len(rows) == len(SCENARIOS) * 2
    assert {(r["scenario"], r["method"]) for r in rows} == {
        (s, m) for s in SCENARIOS for m in ("analytic", report["engine"])}
    for r in rows:
        assert r["settings_hash"] and r["engine_version"] and float(r["wall_time"]) >= 0


def test_csv_numbers_match_trajectories(report: dict) -> None:
    out, eng = report["out"], report["engine"]
    rows = _csv(out)
    for s in ("tiny-free", "tiny-pulse"):
        lam = _lam(report, s)
        for m in ("analytic", eng):
            peak = np.max(np.abs(_theta(out, s, m))) / lam
            assert float(_row(rows, s, m)["peak_ratio_1"]) == pytest.approx(peak, rel=1e-9)
        err = np.max(np.abs(_theta(out, s, eng) - _theta(out, s, "analytic"))) / lam
        assert float(_row(rows, s, eng)["max_error"]) == pytest.approx(err, rel=1e-9)
    assert float(_row(rows, "tiny-free", "analytic")["peak_ratio_1"]) == pytest.approx(0.5)


def test_tables_show_the_csv_numbers(report: dict) -> None:
    out, eng = report["out"], report["engine"]
    rows = _csv(out)
    md = (out / "report.md").read_text()
    page = (out / "index.html").read_text()
    # single-block pulse: the peak table row holds both peaks (3 decimals)
    peaks = [f"{float(_row(rows, 'tiny-pulse', m)['peak_ratio_1']):.3f}" for m in ("analytic", eng)]
    err = f"{float(_row(rows, 'tiny-pulse', eng)['max_error']):.3g}"
    lines = _table_lines(md, "tiny-pulse")
    assert any(all(f"| {p} |" in ln for p in peaks) for ln in lines), lines
    assert any(f"| {err} |" in ln for ln in lines), lines
    for p in peaks:
        assert f">{p}<" in page
    # free rocking: error against Housner and time to rest
    free_err = f"{float(_row(rows, 'tiny-free', eng)['max_error']):.3g}"
    assert any(f"| {free_err} |" in ln for ln in _table_lines(md, "tiny-free"))
    assert f">{free_err}<" in page
    # timing table: the wall time of each run
    wall = float(_row(rows, "tiny-pulse", eng)["wall_time"])
    assert any(f"| {wall:.2f} |" in ln for ln in lines) or wall >= 10


def test_failed_run_is_marked(report: dict) -> None:
    out = report["out"]
    rows = _csv(out)
    ref = _row(rows, "tiny-three", "analytic")
    assert ref["status"] == "unsupported" and ref["message"]
    eng = _row(rows, "tiny-three", report["engine"])
    assert eng["max_error"] == "" and "no analytic model" in eng["error_note"]
    md = (out / "report.md").read_text()
    assert any("⊘ unsupported" in ln for ln in _table_lines(md, "tiny-three"))
    assert ref["message"] in md
    page = (out / "index.html").read_text()
    assert 'class="unsupported"' in page and ref["message"] in page


class _Checker(HTMLParser):
    VOID = {"meta", "img", "br", "hr", "link", "input", "col", "source", "wbr"}

    def __init__(self) -> None:
        super().__init__()
        self.stack: list[str] = []
        self.images: list[str] = []
        self.tables = 0

    def handle_starttag(self, tag: str, attrs: list) -> None:
        if tag == "img":
            self.images.append(dict(attrs)["src"])
        if tag == "table":
            self.tables += 1
        if tag not in self.VOID:
            self.stack.append(tag)

    def handle_endtag(self, tag: str) -> None:
        assert self.stack and self.stack[-1] == tag, (tag, self.stack[-5:])
        self.stack.pop()


def _png_size(data: bytes) -> tuple[int, int]:
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return struct.unpack(">II", data[16:24])


def test_html_parses_and_embeds_figures(report: dict) -> None:
    import base64

    page = (report["out"] / "index.html").read_text()
    checker = _Checker()
    checker.feed(page)
    checker.close()
    assert checker.stack == []
    assert checker.tables >= 5
    assert checker.images and all(s.startswith("data:image/png;base64,") for s in checker.images)
    w, h = _png_size(base64.b64decode(checker.images[0].split(",", 1)[1]))
    assert w > 300 and h > 200


def test_figures_are_pngs(report: dict) -> None:
    figs = sorted((report["out"] / "figures").glob("*.png"))
    names = {f.name for f in figs}
    assert {"accuracy-speed.png", "history-tiny-free.png", "history-tiny-pulse.png",
            "history-tiny-three.png"} <= names
    assert any(n.startswith("peaks-") for n in names)
    for f in figs:
        data = f.read_bytes()
        w, h = _png_size(data)
        assert len(data) > 10_000 and w > 300 and h > 200, f.name


@pytest.mark.slow
def test_resume_skips_finished_runs(report: dict, capsys: pytest.CaptureFixture) -> None:
    out, eng = report["out"], report["engine"]
    # the campaign archives every run's trajectory beside the store; the report copies them
    before = _archive(report)
    assert len(before) == len(SCENARIOS) * 2
    rows_before = _csv(out)
    capsys.readouterr()
    assert main([a for a in report["argv"] if a != "--quiet"] + ["--resume"]) == 0
    said = capsys.readouterr().out
    assert "0 run, 6 reused" in said
    assert _archive(report) == before  # nothing rerun, nothing rewritten
    assert _csv(out) == rows_before
    # a changed knob re-runs that engine only
    knob = {"pymunk": "pymunk.iterations=7", "mujoco": "mujoco.iterations=7"}[eng]
    assert main(report["argv"] + ["--resume", "--set", knob]) == 0
    after = _archive(report)
    assert {p: after[p] for p in before} == before
    hashes = {_row(_csv(out), s, eng)["scenario_hash"]: s for s in SCENARIOS}
    changed = {hashes[p.parent.name] + "/" + p.stem.split("-")[0] for p in set(after) - set(before)}
    assert changed == {f"{s}/{eng}" for s in SCENARIOS}
    assert {_row(_csv(out), s, eng)["settings_hash"] for s in SCENARIOS} != {
        _row(rows_before, s, eng)["settings_hash"] for s in SCENARIOS}
    # the same knob from a settings file (as `tune` writes it) is the same run
    tuned = report["tmp"] / "tuned.toml"
    tuned.write_text(f"[{eng}]\niterations = 7\n")
    capsys.readouterr()
    assert main([a for a in report["argv"] if a != "--quiet"]
                + ["--resume", "--settings", str(tuned)]) == 0
    assert "0 run, 6 reused" in capsys.readouterr().out
    assert _archive(report) == after
    assert f"--settings {tuned}" in (out / "report.md").read_text()
    # presets are chosen with --presets, not by a file
    tuned.write_text(f'[{eng}]\npreset = "accurate"\n')
    assert main(report["argv"] + ["--resume", "--settings", str(tuned)]) == 2
    assert "--presets" in capsys.readouterr().err


def test_history_lists_compare_runs(report: dict, capsys: pytest.CaptureFixture) -> None:
    db = str(report["tmp"] / "runs.db")
    capsys.readouterr()
    assert main(["history", "--db", db]) == 0
    out = capsys.readouterr().out
    for s in SCENARIOS:
        assert s in out
    assert main(["history", "tiny-pulse", "--db", db, "--kind", "compare"]) == 0
    out = capsys.readouterr().out
    assert report["engine"] in out and "compare" in out


@pytest.mark.slow
def test_resume_reruns_a_torn_trajectory(report: dict, capsys: pytest.CaptureFixture) -> None:
    out, eng = report["out"], report["engine"]
    # other tests rewrite the files with other knobs: start from the fixture's settings
    assert main(report["argv"] + ["--resume"]) == 0
    torn = _archived(report, "tiny-pulse", eng)
    torn.write_bytes(torn.read_bytes()[:100])  # an interrupted write
    empty = _archived(report, "tiny-free", eng)
    empty.write_bytes(b"")
    capsys.readouterr()
    assert main([a for a in report["argv"] if a != "--quiet"] + ["--resume"]) == 0
    assert "2 run, 4 reused" in capsys.readouterr().out
    peak = float(_row(_csv(out), "tiny-pulse", eng)["peak_ratio_1"])
    for path in (torn, out / "trajectories" / "tiny-pulse" / f"{_file(eng)}.npz"):
        with np.load(path) as f:  # rewritten whole, in the archive and in the report
            assert float(np.max(np.abs(f["theta_1"]))) / _lam(report, "tiny-pulse") == \
                pytest.approx(peak, rel=1e-12)
    assert empty.stat().st_size > 0


def test_colliding_scenario_names_are_refused(tmp_path: Path,
                                              capsys: pytest.CaptureFixture) -> None:
    files = []
    for i, name in enumerate(("a b", "a-b")):
        path = tmp_path / f"s{i}.toml"
        path.write_text(FREE.replace('name = "tiny-free"', f'name = "{name}"'))
        files.append(str(path))
    argv = ["compare", "--scenarios", ",".join(files), "--engine", "analytic",
            "--out", str(tmp_path / "o"), "--no-db"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "'a b'" in err[0] and "'a-b'" in err[0]


def test_resume_needs_the_store(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    argv = ["compare", "--scenarios", "free-b2-0.5", "--engine", "analytic", "--out",
            str(tmp_path / "o"), "--no-db", "--resume"]
    assert main(argv) == 2
    assert "--no-db" in capsys.readouterr().err


def test_bad_suite_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    assert main(["compare", "--suite", "nope", "--out", str(tmp_path / "d")]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "nope" in err
    assert not (tmp_path / "d").exists()


def test_paper_data_has_citation_and_tables() -> None:
    from rockbench.report.paper import citation, paper_runtimes, paper_tables

    assert "10.1016/j.istruc.2025.110027" in citation()
    t = paper_tables()
    assert set(t) >= {"table6", "table7", "table9", "table10"}
    assert t["table6"].cases["3.0hz-8mm"][0] == 0.183  # transcribed, paper-brief.md
    assert t["table7"].cases["5.0hz-6mm"][3] == "collapsed"
    assert len(paper_runtimes()) == 5


def test_sensitivity_maps_knobs() -> None:
    from rockbench.engines import engine_class
    from rockbench.studies.sensitivity import KNOBS, map_knob

    eng = _engine()
    cls = engine_class(eng)
    by_key = {k.key: map_knob(eng, cls, k) for k in KNOBS}
    it = by_key["iterations"]
    assert [v.overrides for v in it.variations] == [{"iterations": n} for n in (10, 100, 1000)]
    sub = by_key["substeps"].variations
    assert [v.overrides["timestep"] for v in sub] == pytest.approx(
        [1 / (3 * 60), 1 / (21 * 60), 1 / (201 * 60)])
    shape = by_key["shape"]
    assert not shape.variations and "no collision-shape knob" in shape.skipped[0].reason


def test_sensitivity_starts_from_each_engines_own_preset() -> None:
    import importlib
    import sys
    from pathlib import Path

    from rockbench.engines import register, unregister
    from rockbench.studies.compare import CompareOptions, _plan

    sys.path.insert(0, str(Path(__file__).parent))
    fault = importlib.import_module("fault_engine").FaultEngine

    class OwnStart(fault):  # like Blender: Table 2 from its paper-like preset
        name = "own-start"
        sensitivity_preset = "fast"

    register("own-start", OwnStart)
    try:
        opts = CompareOptions(scenarios=[], engines=["own-start", "pymunk"], sensitivity=True)
        starts = {r.method.engine: r.method.settings.get("preset") for r in _plan(opts)[0]
                  if r.method.variation}
        assert starts == {"own-start": "fast", "pymunk": "accurate"}
        asked = CompareOptions(scenarios=[], engines=["own-start"], sensitivity=True,
                               sensitivity_from="accurate")
        assert {r.method.settings.get("preset") for r in _plan(asked)[0]
                if r.method.variation} == {"accurate"}
    finally:
        unregister("own-start")
