"""Earthquake-record excitations: the shipped synthetic records, readers, catalog, CLI run."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

from rockbench.analytic import critical_angle, uplift_ratio
from rockbench.analytic.housner import single_block_reference
from rockbench.cli import main
from rockbench.errors import ScenarioError
from rockbench.scenarios import (
    STANDARD_GRAVITY,
    Record,
    get_scenario,
    get_suite,
    load_scenario,
    save_scenario,
)
from rockbench.scenarios.records import RECORD_CASES, RECORDS_DIR, record_path
from rockbench.trajectory import Trajectory

ROOT = Path(__file__).resolve().parents[1]
NAMES = ("synthetic-1", "synthetic-2")


@pytest.mark.parametrize("name", NAMES)
def test_at2_and_csv_give_the_same_record(name):
    at2 = Record.from_file(RECORDS_DIR / f"{name}.AT2")
    csv = Record.from_file(RECORDS_DIR / f"{name}.csv")
    assert at2.units == "g" and csv.units == "m/s2"
    assert at2.times.size == csv.times.size == 1000
    assert at2.end_time == pytest.approx(9.99)
    t = np.linspace(-0.5, 11.0, 4001)
    for f in ("acceleration", "velocity", "displacement"):
        a, b = getattr(at2, f)(t), getattr(csv, f)(t)
        assert np.max(np.abs(a - b)) <= 1e-9 * (1 + np.max(np.abs(a)))


@pytest.mark.parametrize(("name", "pga_g"), [("synthetic-1", 0.35), ("synthetic-2", 0.3075)])
def test_records_start_and_end_at_rest(name, pga_g):
    rec = Record.from_file(RECORDS_DIR / f"{name}.AT2")
    assert rec.accelerations[0] == 0.0
    assert rec.velocity(0.0) == 0.0 and rec.displacement(0.0) == 0.0
    assert rec.velocity(rec.end_time) == pytest.approx(0.0, abs=1e-12)
    assert rec.acceleration(rec.end_time + 0.1) == 0.0
    # the baseline correction removes a constant: it must stay small against the PGA
    raw = rec.accelerations.max() - rec.accelerations.min()
    assert np.ptp(rec.acceleration(rec.times)) == pytest.approx(raw, rel=0.01)
    assert rec.peak_acceleration() / STANDARD_GRAVITY == pytest.approx(pga_g, abs=0.01)


def test_shipped_files_are_reproduced_by_the_generator(tmp_path):
    spec = importlib.util.spec_from_file_location("make_records",
                                                  ROOT / "benchmarks" / "make_records.py")
    if spec is None or spec.loader is None or not (ROOT / "benchmarks").exists():
        pytest.skip("benchmarks/make_records.py not available (installed package)")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    assert mod.main(["--out", str(tmp_path)]) == 0
    for name in NAMES:
        for suffix in (".AT2", ".csv"):
            assert (tmp_path / f"{name}{suffix}").read_text() == \
                (RECORDS_DIR / f"{name}{suffix}").read_text()
    assert (RECORDS_DIR / "README.md").exists()


def test_bad_record_files(tmp_path):
    bad = tmp_path / "bad.AT2"
    bad.write_text("a\nb\nc\nno header here\n1 2 3\n")
    with pytest.raises(ScenarioError, match="NPTS"):
        Record.from_file(bad)
    short = tmp_path / "short.AT2"
    short.write_text("a\nb\nc\nNPTS= 10, DT= 0.01 SEC\n0.1 0.2\n")
    with pytest.raises(ScenarioError, match="NPTS=10"):
        Record.from_file(short)
    with pytest.raises(ScenarioError, match="cannot read"):
        Record.from_file(tmp_path / "missing.csv")
    three = tmp_path / "three.csv"
    three.write_text("t,acc\n0,0\n0.1,1,2\n")
    with pytest.raises(ScenarioError, match="2 columns"):
        Record.from_file(three)


def test_catalog_record_scenarios():
    names = get_suite("records")
    assert set(names) == set(RECORD_CASES)
    for n in names:
        sc = get_scenario(n)
        assert isinstance(sc.excitation, Record) and sc.n_blocks == 1
        assert Path(sc.excitation.source).exists()
        assert uplift_ratio(sc) > 1.0  # every one makes its block rock
    assert record_path("synthetic-1.AT2").exists()


def test_analytic_response_to_the_pulse_record():
    """Regression value of the reference: synthetic-2 × 2.5 rocks B2 to about 0.65 λ."""
    sc = get_scenario("record-synth2-b2")
    tr = single_block_reference(sc)
    assert str(tr.status) == "ok"
    peak = np.max(np.abs(tr.theta)) / critical_angle(sc.geometry)
    assert peak == pytest.approx(0.6534, abs=2e-3)
    assert tr.impacts is not None and tr.impacts.size > 5


def _write_toml(tmp_path: Path, file: str, scale: float = 2.5) -> Path:
    """A scenario file next to a copy of a record, referenced by a relative path."""
    data = (RECORDS_DIR / file).read_text()
    (tmp_path / "records").mkdir(exist_ok=True)
    (tmp_path / "records" / file).write_text(data)
    path = tmp_path / "quake.toml"
    path.write_text(f"""name = "quake"
duration = 8.0
output_rate = 200.0

[[blocks]]
width = 0.5
depth = 0.2
height = 1.0
mass = 1.0

[contact]
friction = 1.0

[excitation]
type = "record"
file = "records/{file}"
scale = {scale}
""")
    return path


@pytest.mark.parametrize("file", ["synthetic-2.AT2", "synthetic-2.csv"])
def test_record_scenario_file_round_trip(tmp_path, file):
    sc = load_scenario(_write_toml(tmp_path, file))
    assert isinstance(sc.excitation, Record) and sc.excitation.scale == 2.5
    assert sc.excitation.units == ("g" if file.endswith(".AT2") else "m/s2")
    again = load_scenario(save_scenario(sc, tmp_path / "again.toml"))
    t = np.linspace(0, 10, 501)
    np.testing.assert_allclose(again.excitation.acceleration(t), sc.excitation.acceleration(t))


def _available_engine() -> str | None:
    from rockbench.engines import list_engines

    avail = {i.name for i in list_engines() if i.available and not i.analytic}
    return next((e for e in ("pymunk", "mujoco", "bullet") if e in avail), None)


def test_run_command_on_a_record_scenario_end_to_end(tmp_path, capsys):
    engine = _available_engine()
    if engine is None:
        pytest.skip("no physics engine installed (pymunk, mujoco or bullet): only the "
                    "analytic part could run")
    path = _write_toml(tmp_path, "synthetic-2.AT2")
    out = tmp_path / "traj.csv"
    rc = main(["run", str(path), "--engine", f"analytic,{engine}", "--out", str(out),
               "--timeout", "120"])
    assert rc == 0
    text = capsys.readouterr().out
    assert "quake" in text and engine in text and "analytic" in text
    trajs = {e: Trajectory.load(tmp_path / f"traj-{e}.csv") for e in ("analytic", engine)}
    ref, eng = trajs["analytic"], trajs[engine]
    assert str(ref.status) == "ok" and str(eng.status) in ("ok", "overturned")
    lam = math.atan(0.25 / 0.5)
    assert np.max(np.abs(ref.theta)) / lam == pytest.approx(0.653, abs=0.01)
    # the engine rocks as well, with a peak of the same order
    assert 0.2 < np.max(np.abs(eng.theta)) / lam < 3.0


def test_run_command_reports_an_unreadable_record(tmp_path, capsys):
    path = _write_toml(tmp_path, "synthetic-1.AT2")
    (tmp_path / "records" / "synthetic-1.AT2").write_text("garbage\n")
    assert main(["run", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("rockbench: error:") and "quake.toml" in err


AT2_HEAD = "PEER\nrecord\nunits g\n"


@pytest.mark.parametrize("name, data, match", [
    ("bin.csv", b"0,0\n\xff\xfe,1\n", "not a text record file .*byte 0xff at offset 4"),
    ("bin.AT2", AT2_HEAD.encode() + b"NPTS=2, DT=0.01\n\x80\x81\n", "byte 0x80"),
    ("dot.AT2", (AT2_HEAD + "NPTS= 3, DT= . SEC\n0.1 0.2 0.3\n").encode(),
     "line 4 must give DT as a finite number of seconds > 0, got DT=."),
    ("inf.AT2", (AT2_HEAD + "NPTS= 3, DT= 1e999 SEC\n0.1 0.2 0.3\n").encode(), "DT=1E999"),
    ("zero.AT2", (AT2_HEAD + "NPTS= 3, DT= 0.0 SEC\n0.1 0.2 0.3\n").encode(), "DT=0.0"),
    ("one.AT2", (AT2_HEAD + "NPTS= 1, DT= 0.01 SEC\n0.1 0.2 0.3\n").encode(),
     "at least 2 samples"),
    ("nan.csv", b"0,0\n0.1,nan\n0.2,1\n", "NaN or infinite"),
    ("back.csv", b"0,0\n0.2,1\n0.1,0\n", "strictly increasing"),
    ("huge.csv", b"0,1e308\n0.1,-1e308\n0.2,1e308\n", r"reaches 1e\+308 m/s²"),
    ("huge.AT2", (AT2_HEAD + "NPTS= 3, DT= 0.01 SEC\n1e307 -1e307 1e307\n").encode(),
     r"base accelerations above 1e\+06 m/s² are refused"),
    ("long.csv", ("t,acc\n0,0\n0.1," + "9" * 500 + "x\n").encode(), r"line 3 is not two .*\.\.\."),
])
def test_malformed_record_files_name_the_file(tmp_path, name, data, match):
    f = tmp_path / name
    f.write_bytes(data)
    with pytest.raises(ScenarioError, match=match) as info:
        Record.from_file(f)
    msg = str(info.value)
    assert msg.startswith(f"{f}: ") and "\n" not in msg and len(msg) < 300


def test_a_malformed_record_names_the_scenario_and_the_record(tmp_path):
    path = _write_toml(tmp_path, "synthetic-1.csv")
    rec = tmp_path / "records" / "synthetic-1.csv"
    rec.write_bytes(b"0,0\n0.1,1e308\n0.2,-1e308\n")
    with pytest.raises(ScenarioError, match="accelerations above") as info:
        load_scenario(path)
    assert str(info.value).startswith(f"{path}: [excitation] {rec}: ")
    text = _write_toml(tmp_path, "synthetic-1.csv").read_text()
    for old, new, match in (("scale = 2.5", 'scale = "2.5"', "record scale must be a finite "
                             "number, got '2.5' \\(a string\\)"),
                            ("scale = 2.5", 'units = ["g"]', "record units must be 'g' or"),
                            ('file = "records/synthetic-1.csv"', "file = 3",
                             "record file must be a string, got 3")):
        path.write_text(text.replace(old, new))
        with pytest.raises(ScenarioError, match=match):
            load_scenario(path)


def test_records_compare_by_value():
    from rockbench.scenarios.excitation import Record

    t, a = np.linspace(0.0, 1.0, 11), np.sin(np.linspace(0.0, 3.0, 11))
    one, same = Record(times=t, accelerations=a), Record(times=t.copy(), accelerations=a.copy())
    assert one == same and hash(one) == hash(same) and len({one, same}) == 1
    assert one != Record(times=t, accelerations=2 * a) and one != Record(t, a, scale=2.0)
    sc = get_scenario("single-pulse-3.0hz-8mm")
    assert sc.replace(excitation=one) == sc.replace(excitation=same)

