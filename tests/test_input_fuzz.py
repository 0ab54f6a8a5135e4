"""Fuzz: malformed settings files, tolerance files and command-line flags (issue 14).

Hypothesis writes arbitrary TOML-shaped tables (numbers of every kind, strings,
booleans, lists, nested tables) and raw bytes as settings and tolerance files,
and arbitrary ``--set``/``--timeout``/``--jobs`` values; each either loads or is
refused with a typed error whose message is one line naming the file (or flag).
The scenario and record files have their own fuzz test (test_scenario_fuzz.py).
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest
import tomli_w
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rockbench.cli import main
from rockbench.errors import RockbenchError
from rockbench.presets import layered_settings
from rockbench.studies.tolerances import load_tolerances

SETTINGS = settings(max_examples=150, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])

scalars = st.one_of(
    st.integers(-10**6, 10**6), st.floats(allow_nan=True, allow_infinity=True),
    st.booleans(), st.text(max_size=8), st.sampled_from(["fast", "accurate", "inf", "1e-3"]))
values = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=3), st.dictionaries(st.text(max_size=6), inner, max_size=3)),
    max_leaves=6)
knob_names = st.sampled_from(["timestep", "iterations", "collision_slop", "preset", "nope"])
engine_names = st.sampled_from(["pymunk", "analytic", "havok", "mujoco"])


def _one_line(exc: BaseException, needle: str) -> None:
    text = str(exc)
    assert "\n" not in text.strip(), text
    assert needle in text, text


def _write(path: Path, data: object) -> bool:
    """Write ``data`` as TOML; False if TOML cannot represent it (e.g. NaN keys)."""
    try:
        path.write_text(tomli_w.dumps(data))  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return False
    return True


@SETTINGS
@given(data=st.dictionaries(engine_names, st.one_of(
    scalars, st.dictionaries(knob_names, values, max_size=3)), max_size=3))
def test_settings_files(tmp_path: Path, data: dict) -> None:
    path = tmp_path / "settings.toml"
    if not _write(path, data):
        return
    try:
        out = layered_settings(["pymunk", "analytic"], settings_file=path)
    except RockbenchError as exc:
        _one_line(exc, str(path))
        return
    for knobs in out.values():  # what loads is typed: no string or bool where a number goes
        for k, v in knobs.items():
            if k in ("timestep", "collision_slop"):
                assert isinstance(v, float) and math.isfinite(v)
            if k == "iterations":
                assert isinstance(v, int) and not isinstance(v, bool)


@SETTINGS
@given(blob=st.binary(max_size=64))
def test_settings_and_tolerance_files_of_random_bytes(tmp_path: Path, blob: bytes) -> None:
    path = tmp_path / "f.toml"
    path.write_bytes(blob)
    for load in (lambda p: layered_settings(["pymunk"], settings_file=p), load_tolerances):
        try:
            load(path)
        except RockbenchError as exc:
            _one_line(exc, str(path))


limit_names = st.sampled_from(["max_error", "peak_error", "impact_time_error", "status",
                               "realtime_factor", "bogus"])


@SETTINGS
@given(data=st.dictionaries(
    st.sampled_from(["default", "engines", "suites", "regression", "scenarios", "x"]),
    st.one_of(scalars, st.dictionaries(st.one_of(limit_names, engine_names), values,
                                       max_size=3)), max_size=3))
def test_tolerance_files(tmp_path: Path, data: dict) -> None:
    path = tmp_path / "tol.toml"
    if not _write(path, data):
        return
    try:
        tol = load_tolerances(path)
    except RockbenchError as exc:
        _one_line(exc, str(path))
        return
    for engine in ("pymunk", "mujoco"):  # what loads gives numeric limits only
        for name, limit in tol.for_cell(engine, "free-b2-0.5").items():
            if name != "status" and limit is not None:
                assert isinstance(limit, float) and math.isfinite(limit), (name, limit)


flag_values = st.one_of(st.sampled_from(["inf", "nan", "-1", "0", "1e309", "x", "", "2.5",
                                         "1e-3", "True", "[1]"]), st.text(max_size=6))


@settings(max_examples=60, deadline=None)
@given(knob=knob_names, value=flag_values,
       flag=st.sampled_from(["--set", "--timeout", "--jobs", "--max-memory"]))
@pytest.mark.slow
def test_flags(knob: str, value: str, flag: str) -> None:
    argv = ["run", "free-b2-0.5", "--engine", "pymunk", "--no-isolate"]
    argv += [flag, f"pymunk.{knob}={value}" if flag == "--set" else value]
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse: a value of the wrong type (exit 2)
        code = exc.code
    assert code in (0, 2)


@pytest.mark.parametrize("value", ["inf", "nan", "-1", "0"])
def test_bad_timeouts_are_one_line(value: str, capsys: pytest.CaptureFixture) -> None:
    assert main(["run", "free-b2-0.5", "--timeout", value]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--timeout" in err[0]
