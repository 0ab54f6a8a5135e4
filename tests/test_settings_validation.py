"""Engine knobs: typed values are never coerced, strings from the command line are parsed,
non-finite numbers are refused, and a settings file may not name an unknown engine."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from rockbench.cli import main
from rockbench.engines import SettingsError, get_engine


@pytest.mark.parametrize("knobs, needle", [
    ({"iterations": "inf"}, "finite"),
    ({"iterations": math.inf}, "finite"),
    ({"timestep": "nan"}, "finite"),
    ({"timestep": True}, "a number"),
    ({"iterations": [3]}, "an integer"),
    ({"iterations": 2.5}, "an integer"),
    ({"iterations": {"a": 1}}, "an integer"),
    ({"timestep": "fast"}, "a number"),
])
def test_bad_knob_values_are_refused(knobs: dict, needle: str) -> None:
    engine = get_engine("analytic")
    with pytest.raises(SettingsError, match=needle):
        _settings_of(engine, knobs)


def _settings_of(engine: object, knobs: dict) -> object:
    # the analytic engine has few knobs: exercise the typed coercion on a stand-in class
    from dataclasses import dataclass

    from rockbench.engines import EngineSettings

    @dataclass(frozen=True)
    class S(EngineSettings):
        timestep: float = 1e-3
        iterations: int = 10
        flag: bool = False

    return S().replace(**knobs)


def test_strings_from_the_command_line_are_parsed() -> None:
    s = _settings_of(None, {"timestep": "5e-4", "iterations": "20", "flag": "yes"})
    assert (s.timestep, s.iterations, s.flag) == (5e-4, 20, True)
    s = _settings_of(None, {"timestep": 2, "iterations": 20.0})
    assert isinstance(s.timestep, float) and s.iterations == 20


def test_unknown_engine_table_in_a_settings_file(tmp_path: Path,
                                                 capsys: pytest.CaptureFixture) -> None:
    path = tmp_path / "s.toml"
    path.write_text("[havok]\niterations = 3\n")
    assert main(["run", "free-b0", "--settings", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(path) in err[0] and "[havok]" in err[0]


def test_infinite_integer_knob_on_the_command_line(capsys: pytest.CaptureFixture) -> None:
    assert main(["run", "free-b0", "--engine", "pymunk", "--set", "pymunk.iterations=inf"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "iterations" in err[0] and "finite" in err[0]
