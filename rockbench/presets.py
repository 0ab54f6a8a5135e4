"""Settings files: engine knobs saved as TOML, read back with ``--settings FILE``.

A settings file holds one table per engine, with knob values as in ``--set``
and optionally a ``preset`` to start from::

    # written by `rockbench tune free-b1-0.5 --engine mujoco --target 0.01`
    [mujoco]
    timestep = 0.0005
    iterations = 20

    [pymunk]
    preset = "fast"
    iterations = 40

Commands that run engines combine, later winning: the ``--preset`` option, the
settings file, then ``--set`` options. ``rockbench tune`` writes such files.
"""

from __future__ import annotations

import argparse
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import tomli_w

from rockbench.engines import SettingsError
from rockbench.tomlfile import read_toml

__all__ = ["load_settings_file", "write_settings_file", "add_settings_file_argument",
           "settings_with_file", "typed_settings"]


def load_settings_file(path: str | Path) -> dict[str, dict[str, Any]]:
    """Read a settings file into ``{engine: {knob: value}}``.

    Raises
    ------
    SettingsError
        Unreadable file, malformed TOML, or a top-level value that is not a table.
    """
    path = Path(path)
    data = read_toml(path, SettingsError, "settings file")
    out: dict[str, dict[str, Any]] = {}
    for engine, table in data.items():
        if not isinstance(table, Mapping):
            raise SettingsError(f"{path}: {engine!r} must be a table of knobs ([{engine}])")
        for knob, value in table.items():
            if isinstance(value, Mapping):
                raise SettingsError(f"{path}: [{engine}] {knob} must be a value, not a table")
        out[engine] = dict(table)
    return out


def write_settings_file(path: str | Path, settings: Mapping[str, Mapping[str, Any]],
                        comment: Sequence[str] = ()) -> Path:
    """Write ``{engine: {knob: value}}`` as a settings file, with comment lines on top."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    head = "".join(f"# {line}\n" for line in comment)
    body = tomli_w.dumps({e: {k: v for k, v in s.items() if v is not None}
                          for e, s in settings.items()})
    path.write_text(head + body)
    return path


def add_settings_file_argument(p: argparse.ArgumentParser) -> None:
    """The ``--settings FILE`` option (a settings file, e.g. written by ``tune``)."""
    p.add_argument("--settings", dest="settings_file", default=None, metavar="FILE",
                   help="TOML file of engine knobs ([engine] knob = value), e.g. written by "
                        "`rockbench tune`; --set options override it")


def settings_with_file(args: argparse.Namespace,
                       engines: Sequence[str]) -> dict[str, dict[str, Any]]:
    """Per-engine settings from ``--preset``, ``--settings FILE`` and ``--set``, validated.

    Engines in the file that are not selected are ignored.

    Raises
    ------
    SettingsError
        Bad file, unknown knob or preset, or a value of the wrong type.
    """
    from rockbench.cli import engine_settings
    from rockbench.engines.registry import ALIASES

    path = getattr(args, "settings_file", None)
    if not path:
        return engine_settings(args, engines)
    from_file = {ALIASES.get(k, k): v for k, v in load_settings_file(path).items()}
    # file entries become --set options placed before the user's own, which win
    opts = [f"{e}.{k}={_as_option(v)}" for e, table in from_file.items() if e in engines
            for k, v in table.items()]
    merged = argparse.Namespace(**vars(args))
    merged.set_options = opts + list(getattr(args, "set_options", []) or [])
    try:
        return engine_settings(merged, engines)
    except SettingsError as exc:
        raise SettingsError(f"{path}: {exc}") from None


def _as_option(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        return ",".join(map(str, value))
    return str(value)


def typed_settings(engine: str, settings: Mapping[str, Any]) -> dict[str, Any]:
    """``settings`` with string knob values converted to the knobs' types.

    ``{"preset": "fast", "timestep": "5e-4"}`` becomes ``{"preset": "fast",
    "timestep": 0.0005}``, so equal settings compare (and hash) equal.

    Raises
    ------
    SettingsError
        Unknown knob or preset, or a value of the wrong type.
    """
    from rockbench.engines import engine_class

    s = dict(settings)
    preset = s.pop("preset", None)
    resolved = engine_class(engine).settings(preset, **s)
    out: dict[str, Any] = {"preset": preset} if preset else {}
    out.update({k: getattr(resolved, k) for k in s})
    return out
