"""Fuzzing scenario and record files: a valid scenario or one clear ScenarioError, nothing else.

Hypothesis mutates valid catalog scenarios (wrong types, removed and extra keys,
non-finite and absurd numbers, random bytes, deep nesting) and shipped record
files (bad tokens, headers, bytes). Every file must either load as a valid
scenario that saves and loads again unchanged, or raise :class:`ScenarioError`
with one line that starts with the file's name. Run with
``--hypothesis-show-statistics`` to see which refusals the cases met.
"""

from __future__ import annotations

import datetime
import math
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import hypothesis
import pytest
import tomli_w
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from rockbench.errors import ScenarioError
from rockbench.scenarios import (
    CosinePulse,
    Record,
    Scenario,
    get_scenario,
    load_scenario,
    save_scenario,
    scenario_to_dict,
)
from rockbench.scenarios.records import RECORDS_DIR
from rockbench.store import scenario_hash

FUZZ = settings(max_examples=200, deadline=None, database=None, derandomize=True,
                suppress_health_check=[HealthCheck.function_scoped_fixture,
                                       HealthCheck.too_slow])

#: First rows of the shipped CSV record and the same samples as a PEER AT2 file.
CSV_TEXT = "\n".join((RECORDS_DIR / "synthetic-1.csv").read_text().splitlines()[:41]) + "\n"
_AT2 = (RECORDS_DIR / "synthetic-1.AT2").read_text().splitlines()
AT2_TEXT = "\n".join(_AT2[:3] + ["NPTS=   40, DT=   .0100 SEC"] + _AT2[4:12]) + "\n"


def _bases() -> dict[str, dict[str, Any]]:
    """Valid scenario tables to mutate: catalog cases plus every excitation kind."""
    bases = {n: scenario_to_dict(get_scenario(n))
             for n in ("free-b1-0.5", "single-pulse-3.0hz-8mm", "stack-sine-4.0hz-4mm")}
    pulse = get_scenario("free-b2-0.5").replace(excitation=CosinePulse(2.0, 0.01, cycles=2))
    bases["cosine"] = scenario_to_dict(pulse)
    inline = Record([0.0, 0.1, 0.2, 0.3], [0.0, 2.0, -1.5, 0.0], scale=1.5)
    bases["inline-record"] = scenario_to_dict(pulse.replace(excitation=inline))
    bases["file-record"] = {**bases["cosine"], "excitation": {
        "type": "record", "file": "rec.csv", "units": "m/s2", "scale": 2.0}}
    return bases


BASES = _bases()


def _paths(node: Any, prefix: tuple = ()) -> list[tuple]:
    """Every key or index path inside a TOML structure (the root excluded)."""
    out = []
    items = node.items() if isinstance(node, dict) else enumerate(node) \
        if isinstance(node, list) else ()
    for k, v in items:
        out.append(prefix + (k,))
        out += _paths(v, prefix + (k,))
    return out


_scalars = st.one_of(
    st.text(max_size=8), st.booleans(), st.integers(-2**63, 2**63 - 1),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0, -1, 1e308, -1e308, 1e-300, 5e-324, 2**62, math.inf, math.nan]),
    st.dates(), st.times(), st.datetimes(max_value=datetime.datetime(9999, 1, 1)),
)
JUNK = st.recursive(_scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=3), st.dictionaries(st.text(max_size=6), inner, max_size=3)),
    max_leaves=6)


def _mutate(doc: dict, data: st.DataObject) -> dict:
    """Apply 1–3 random structural mutations to a deep copy of ``doc``."""
    doc = _copy(doc)
    for _ in range(data.draw(st.integers(1, 3), label="mutations")):
        paths = _paths(doc)
        if not paths:
            break
        path = data.draw(st.sampled_from(paths), label="path")
        parent = doc
        for k in path[:-1]:
            parent = parent[k]
        key = path[-1]
        op = data.draw(st.sampled_from(["replace", "replace", "delete", "extra", "scale"]),
                       label="op")
        if op == "replace":
            parent[key] = data.draw(JUNK, label="value")
        elif op == "delete":
            del parent[key]
        elif op == "extra" and isinstance(parent, dict):
            parent[data.draw(st.text(min_size=1, max_size=8), label="key")] = \
                data.draw(JUNK, label="value")
        elif op == "scale" and isinstance(parent[key], (int, float)):
            parent[key] = parent[key] * data.draw(
                st.sampled_from([-1, 0, 1e-9, 1e9, 1e300, math.inf, math.nan]), label="factor")
    return doc


def _copy(node: Any) -> Any:
    if isinstance(node, dict):
        return {k: _copy(v) for k, v in node.items()}
    if isinstance(node, list):
        return [_copy(v) for v in node]
    return node


@st.composite
def _byte_mutation(draw: st.DrawFn, data: bytes) -> bytes:
    """Random bytes flipped, inserted or cut, lines repeated, or deep nesting appended."""
    for _ in range(draw(st.integers(1, 4))):
        op = draw(st.sampled_from(["flip", "insert", "truncate", "nest", "line"]))
        i = draw(st.integers(0, max(len(data) - 1, 0)))
        if op == "flip" and data:
            data = data[:i] + bytes([draw(st.integers(0, 255))]) + data[i + 1:]
        elif op == "insert":
            data = data[:i] + draw(st.binary(min_size=1, max_size=8)) + data[i:]
        elif op == "truncate":
            data = data[:i]
        elif op == "nest":
            n = draw(st.integers(10, 3000))
            o, c = draw(st.sampled_from([("[", "]"), ("{a = ", "}")]))
            data += b"\nnest = " + (o * n + "1" + c * n).encode() + b"\n"
        elif op == "line":
            lines = data.split(b"\n")
            j = draw(st.integers(0, len(lines) - 1))
            data = b"\n".join(lines[:j] + [lines[j]] * 2 + lines[j:])
    return data


def _category(msg: str, path: Path) -> str:
    """A refusal message without its file names and numbers, for the statistics."""
    msg = msg.replace(str(path.parent) + "/", "")
    msg = re.sub(r"0x[0-9a-f]{2}", "0x…", msg)
    return re.sub(r"'[^']*'|(?<![\w-])-?\d[\d.e+-]*|\bnan\b|\binf\b", "…", msg)[:70]


def _check_load(path: Path) -> None:
    """A valid scenario that round-trips, or a one-line ScenarioError naming the file."""
    try:
        sc = load_scenario(path)
    except ScenarioError as exc:
        msg = str(exc)
        assert msg.startswith(f"{path}: "), msg
        assert "\n" not in msg and len(msg) < 400, msg
        event(f"refused: {_category(msg, path)}")
        return
    assert isinstance(sc, Scenario)
    again = load_scenario(save_scenario(sc, path.with_name("again.toml")))
    assert scenario_hash(again) == scenario_hash(sc)
    event("accepted")


@pytest.fixture(scope="module")
def fuzz_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    d = tmp_path_factory.mktemp("fuzz")
    (d / "rec.csv").write_text(CSV_TEXT)
    return d


@FUZZ
@given(base=st.sampled_from(sorted(BASES)), data=st.data())
def test_mutated_scenario_tables(fuzz_dir, base, data):
    doc = _mutate(BASES[base], data)
    try:
        text = tomli_w.dumps(doc)
    except (TypeError, ValueError):  # not expressible as TOML (nothing to read back)
        hypothesis.reject()
    path = fuzz_dir / "mutated.toml"
    path.write_text(text)
    _check_load(path)


@FUZZ
@given(base=st.sampled_from(sorted(BASES)), data=st.data())
def test_mutated_scenario_bytes(fuzz_dir, base, data):
    raw = data.draw(_byte_mutation(tomli_w.dumps(BASES[base]).encode()), label="bytes")
    path = fuzz_dir / "bytes.toml"
    path.write_bytes(raw)
    _check_load(path)


_BAD_TOKENS = ["nan", "inf", "-inf", "1e308", "-1e308", "1e999", ".", "", "abc", "0x10",
               "1_0", "\u0663", "true", "1,2", "9" * 400, "-0", "1e-320"]


@st.composite
def _record_text(draw: st.DrawFn, text: str) -> bytes:
    """A record file with numeric tokens replaced by bad ones, then maybe byte mutations."""
    tokens = re.split(r"([\s,=]+)", text)
    numeric = [i for i, tok in enumerate(tokens) if re.fullmatch(r"[-+.\dEe]+", tok)]
    for _ in range(draw(st.integers(0, 3))):
        i = draw(st.sampled_from(numeric))
        tokens[i] = draw(st.one_of(st.sampled_from(_BAD_TOKENS), st.text(max_size=6)))
    raw = "".join(tokens).encode()
    if draw(st.booleans()):
        raw = draw(_byte_mutation(raw))
    return raw


@FUZZ
@given(kind=st.sampled_from(["csv", "AT2"]), data=st.data())
@pytest.mark.slow
def test_mutated_record_files(fuzz_dir, kind, data):
    raw = data.draw(_record_text(CSV_TEXT if kind == "csv" else AT2_TEXT), label="record")
    rec = fuzz_dir / f"fuzzed.{kind}"
    rec.write_bytes(raw)
    try:
        r = Record.from_file(rec)
    except ScenarioError as exc:
        msg = str(exc)
        assert msg.startswith(f"{rec}: ") or msg.startswith("cannot read record file"), msg
        assert "\n" not in msg and len(msg) < 400, msg
        event(f"refused: {_category(msg, rec)}")
    else:
        a = r.acceleration(r.times)
        assert all(math.isfinite(x) for x in (*a, r.velocity(r.end_time),
                                              r.displacement(r.end_time)))
        event("accepted")
    # the same file through a scenario: the message starts with the scenario's name
    doc = {**BASES["cosine"], "excitation": {"type": "record", "file": rec.name}}
    path = fuzz_dir / "with-record.toml"
    path.write_text(tomli_w.dumps(doc))
    _check_load(path)


# ---------------------------------------------------------------- the command line
_B = "[[blocks]]\nwidth = 0.5\ndepth = 0.2\nheight = 1.0\nmass = 1.0\n"
CLI_CASES = {
    "binary": b"\x00\x9f\xff" + _B.encode(),
    "nested": ("x = " + "[" * 3000 + "]" * 3000 + "\n").encode(),
    "width-true": _B.replace("width = 0.5", "width = true").encode(),
    "cycles-inf": (_B + '[excitation]\ntype = "sine-pulse"\nfrequency = 3.0\n'
                   'amplitude = 0.01\ncycles = inf\n').encode(),
    "tilt-rad-negative-g": ("gravity = -9.81\n" + _B + "[initial]\ntilt_rad = 0.1\n").encode(),
    "off-support": (_B + _B + "offset = 0.4\n").encode(),
    "output-rate": ("output_rate = 1e-6\n" + _B).encode(),
    "overflowing-record": (_B + '[excitation]\ntype = "record"\ntimes = [0.0, 0.1, 0.2]\n'
                           "accelerations = [1e308, -1e308, 1e308]\n").encode(),
    "at2-header": (_B + '[excitation]\ntype = "record"\nfile = "dot.AT2"\n').encode(),
}


def _write_cli_case(tmp_path: Path, name: str) -> Path:
    (tmp_path / "dot.AT2").write_text(AT2_TEXT.replace("DT=   .0100", "DT= ."))
    path = tmp_path / f"{name}.toml"
    path.write_bytes(CLI_CASES[name])
    return path


@pytest.mark.parametrize("name", sorted(CLI_CASES))
def test_run_exits_2_with_one_line(tmp_path, capsys, name):
    from rockbench.cli import main

    path = _write_cli_case(tmp_path, name)
    assert main(["run", str(path), "--engine", "analytic"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith(f"rockbench: error: {path}: "), err


@pytest.mark.parametrize("name", ["binary", "overflowing-record"])
@pytest.mark.slow
def test_run_in_a_process_prints_no_traceback(tmp_path, name):
    path = _write_cli_case(tmp_path, name)
    proc = subprocess.run(
        [sys.executable, "-c", "import sys; from rockbench.cli import main; "
         "sys.exit(main(sys.argv[1:]))", "run", str(path), "--engine", "analytic"],
        capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    assert proc.stderr.splitlines() == [proc.stderr.strip()] and \
        proc.stderr.startswith(f"rockbench: error: {path}: "), proc.stderr
