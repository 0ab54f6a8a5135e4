"""Engine settings from the command line: presets, settings files and ``--set``.

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
settings file (``--settings FILE``), then ``--set`` options
(:func:`layered_settings`). ``rockbench tune`` writes such files.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import tomli_w

from rockbench.engines import SettingsError
from rockbench.tomlfile import read_toml

__all__ = ["load_settings_file", "write_settings_file", "layered_settings", "typed_settings"]


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


def layered_settings(engines: Sequence[str], *, preset: str | None = None,
                     settings_file: str | Path | None = None,
                     set_options: Sequence[str] = ()) -> dict[str, dict[str, Any]]:
    """Per-engine knob overrides from a preset, a settings file and ``--set`` options.

    Later layers win: ``preset`` (every engine but the analytic reference),
    then the file's table for the engine, then the ``engine.knob=value``
    options. Engines in the file that are not selected are ignored.

    Parameters
    ----------
    engines : sequence of str
        Selected engines (canonical names).
    preset : str, optional
        Preset for every engine (``--preset``).
    settings_file : str or Path, optional
        A settings file (``--settings FILE``).
    set_options : sequence of str
        ``engine.knob=value`` strings (``--set``; aliases accepted).

    Returns
    -------
    dict
        ``{engine: {"preset": name, knob: value, ...}}`` with every value
        converted to its knob's type (``"preset"`` only when one applies), so
        that equal settings compare and hash equal.

    Raises
    ------
    SettingsError
        Bad file (its path leads the message), unknown knob or preset, or a
        value of the wrong type.
    UnknownEngine
        ``--set`` names an engine that is not selected or does not exist.
    """
    from rockbench.engines import engine_class, parse_set_options
    from rockbench.engines.registry import ALIASES
    from rockbench.errors import EngineUnavailable, UnknownEngine

    options: dict[str, dict[str, Any]] = {}
    for name, knobs in parse_set_options(list(set_options)).items():
        canon = ALIASES.get(name, name)
        if canon not in engines:
            raise UnknownEngine(name, list(engines))
        options.setdefault(canon, {}).update(knobs)
    from_file: dict[str, dict[str, Any]] = {}
    if settings_file:
        from_file = {ALIASES.get(k, k): v for k, v in load_settings_file(settings_file).items()}
        for name in from_file:  # tables of unselected engines are ignored, not of unknown ones
            try:
                engine_class(name)
            except UnknownEngine as exc:
                raise SettingsError(f"{settings_file}: [{name}] is not an engine: {exc}") from None
            except EngineUnavailable:
                pass
    out: dict[str, dict[str, Any]] = {}
    for name in engines:
        default = None if engine_class(name).capabilities.analytic else preset
        if name in from_file:
            try:  # the file alone first, so that its errors name it
                typed_settings(name, {"preset": default, **from_file[name]})
            except SettingsError as exc:
                raise SettingsError(f"{settings_file}: {exc}") from None
        layer = {"preset": default, **from_file.get(name, {}), **options.get(name, {})}
        out[name] = typed_settings(name, layer)
    return out


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
    preset = s.pop("preset", None) or None
    resolved = engine_class(engine).settings(preset, **s)
    out: dict[str, Any] = {"preset": preset} if preset else {}
    out.update({k: getattr(resolved, k) for k in s})
    return out
