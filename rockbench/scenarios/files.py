"""Scenario files: TOML load and save (round trip), strict about unknown keys."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import tomli_w

from rockbench.errors import ScenarioError
from rockbench.scenarios.excitation import (
    CosinePulse,
    Excitation,
    Free,
    Record,
    SinePulse,
    Sinusoid,
)
from rockbench.scenarios.model import Block, Contact, Scenario, Stack
from rockbench.tomlfile import read_toml

__all__ = ["load_scenario", "save_scenario", "scenario_from_dict", "scenario_to_dict"]

_TOP = {"name", "description", "duration", "output_rate", "gravity", "blocks", "contact",
        "initial", "excitation"}
_BLOCK = {"width", "depth", "height", "mass", "density", "chamfer", "offset"}
_CONTACT = {"friction", "restitution", "eta"}
_INITIAL = {"tilt", "tilt_rad"}
_EXC = {
    "free": set(),
    "sine-pulse": {"frequency", "amplitude", "peak_acceleration", "cycles"},
    "cosine-pulse": {"frequency", "amplitude", "peak_acceleration", "cycles"},
    "sinusoid": {"frequency", "amplitude", "duration", "ramp_cycles"},
    "record": {"file", "units", "scale", "times", "accelerations"},
}


def _table(data: Any, where: str) -> dict[str, Any]:
    if not isinstance(data, dict):
        raise ScenarioError(f"{where} must be a table")
    return data


def _no_unknown(data: dict[str, Any], allowed: set[str], where: str) -> None:
    unknown = sorted(set(data) - allowed)
    if unknown:
        raise ScenarioError(
            f"unknown key{'s' if len(unknown) > 1 else ''} {', '.join(map(repr, unknown))} in "
            f"{where}; allowed: {', '.join(sorted(allowed)) or '(none)'}"
        )


def _pulse(cls: type[SinePulse] | type[CosinePulse], data: dict[str, Any],
           kind: str) -> Excitation:
    """A one-sine or one-cosine pulse from ``amplitude`` (m) or ``peak_acceleration`` (m/s²)."""
    if ("amplitude" in data) == ("peak_acceleration" in data):
        raise ScenarioError(f"[excitation] of type {kind!r} needs exactly one of 'amplitude' "
                            f"(displacement, m) and 'peak_acceleration' (m/s², signed)")
    if "frequency" not in data:
        raise ScenarioError(f"[excitation] of type {kind!r} needs 'frequency' (Hz)")
    if "peak_acceleration" in data:
        data = dict(data)
        a_p = data.pop("peak_acceleration")
        try:
            f = float(data.pop("frequency"))
            a = float(a_p)
        except (TypeError, ValueError):
            raise ScenarioError(f"[excitation] of type {kind!r}: frequency and "
                                f"peak_acceleration must be numbers") from None
        if not (math.isfinite(f) and f > 0 and math.isfinite(a)):
            raise ScenarioError(f"[excitation] of type {kind!r}: frequency must be finite and "
                                f"> 0 and peak_acceleration finite, got {f!r} and {a!r}")
        return cls.from_acceleration(a, 2.0 * math.pi * f, **data)
    return cls(**data)


def _excitation(data: dict[str, Any], base_dir: Path | None) -> Excitation:
    data = dict(_table(data, "[excitation]"))
    kind = data.pop("type", "free")
    if kind not in _EXC:
        raise ScenarioError(f"unknown excitation type {kind!r}; types: {', '.join(_EXC)}")
    _no_unknown(data, _EXC[kind], f"[excitation] of type {kind!r}")
    try:
        if kind == "free":
            return Free()
        if kind in ("sine-pulse", "cosine-pulse"):
            return _pulse(SinePulse if kind == "sine-pulse" else CosinePulse, data, kind)
        if kind == "sinusoid":
            return Sinusoid(**data)
    except TypeError as exc:
        raise ScenarioError(f"[excitation] of type {kind!r}: {exc}") from None
    if "file" in data:
        if "times" in data or "accelerations" in data:
            raise ScenarioError("record excitation takes either 'file' or 'times'/'accelerations'")
        src = str(data["file"])
        path = Path(src)
        if not path.is_absolute() and base_dir is not None:
            path = base_dir / path
        return Record.from_file(path, units=data.get("units"), scale=data.get("scale", 1.0),
                                source=src)
    if "times" not in data or "accelerations" not in data:
        raise ScenarioError("record excitation needs 'file' or both 'times' and 'accelerations'")
    return Record(data["times"], data["accelerations"], scale=data.get("scale", 1.0))


def scenario_from_dict(data: dict[str, Any], *, base_dir: Path | None = None,
                       default_name: str = "scenario") -> Scenario:
    """Build a :class:`Scenario` from the parsed TOML structure.

    Parameters
    ----------
    data : dict
        Parsed scenario file.
    base_dir : Path, optional
        Directory against which relative record file paths are resolved.
    default_name : str
        Name used when the file has none.

    Raises
    ------
    ScenarioError
        For any unknown key or invalid value.
    """
    data = _table(data, "scenario")
    _no_unknown(data, _TOP, "the scenario file")
    blocks_raw = data.get("blocks")
    if not isinstance(blocks_raw, list) or not blocks_raw:
        raise ScenarioError("scenario needs at least one [[blocks]] table")
    blocks, offsets = [], []
    for i, raw in enumerate(blocks_raw, 1):
        raw = dict(_table(raw, f"[[blocks]] #{i}"))
        _no_unknown(raw, _BLOCK, f"[[blocks]] #{i}")
        offsets.append(raw.pop("offset", 0.0))
        missing = {"width", "depth", "height"} - set(raw)
        if missing:
            raise ScenarioError(f"[[blocks]] #{i} is missing {', '.join(sorted(missing))}")
        try:
            blocks.append(Block(**raw))
        except ScenarioError as exc:
            raise ScenarioError(f"[[blocks]] #{i}: {exc}") from None
    contact_raw = _table(data.get("contact", {}), "[contact]")
    _no_unknown(contact_raw, _CONTACT, "[contact]")
    initial = _table(data.get("initial", {}), "[initial]")
    _no_unknown(initial, _INITIAL, "[initial]")
    stack = Stack(tuple(blocks), tuple(offsets))
    g = data.get("gravity", 9.81)
    if "tilt" in initial and "tilt_rad" in initial:
        raise ScenarioError("[initial] takes 'tilt' (fraction of λ) or 'tilt_rad', not both")
    tilt = initial.get("tilt", 0.0)
    if "tilt_rad" in initial:
        lam = blocks[0].rocking(float(g)).lam
        tilt = float(initial["tilt_rad"]) / lam
    return Scenario(
        name=str(data.get("name", default_name)),
        description=str(data.get("description", "")),
        stack=stack,
        contact=Contact(**contact_raw),
        excitation=_excitation(data.get("excitation", {"type": "free"}), base_dir),
        initial_tilt=tilt,
        duration=data.get("duration", 10.0),
        output_rate=data.get("output_rate", 1000.0),
        g=g,
    )


def scenario_to_dict(scenario: Scenario) -> dict[str, Any]:
    """The TOML structure of a scenario (inverse of :func:`scenario_from_dict`)."""
    blocks = []
    for b, off in zip(scenario.blocks, scenario.stack.offsets, strict=True):
        d = b.to_dict()
        if off:
            d["offset"] = off
        blocks.append(d)
    out: dict[str, Any] = {"name": scenario.name}
    if scenario.description:
        out["description"] = scenario.description
    out.update({
        "duration": scenario.duration,
        "output_rate": scenario.output_rate,
        "gravity": scenario.g,
        "blocks": blocks,
        "contact": scenario.contact.to_dict(),
        "initial": {"tilt": scenario.initial_tilt},
        "excitation": scenario.excitation.to_dict(),
    })
    return out


def load_scenario(path: str | Path) -> Scenario:
    """Read a scenario TOML file.

    Raises
    ------
    ScenarioError
        Unreadable file, malformed TOML, unknown keys or invalid values; the
        message starts with the file name.
    """
    path = Path(path)
    data = read_toml(path, ScenarioError, "scenario file")
    try:
        return scenario_from_dict(data, base_dir=path.parent, default_name=path.stem)
    except ScenarioError as exc:
        raise ScenarioError(f"{path}: {exc}") from None


def save_scenario(scenario: Scenario, path: str | Path) -> Path:
    """Write a scenario as TOML; :func:`load_scenario` reads back an equal scenario."""
    path = Path(path)
    data = scenario_to_dict(scenario)
    path.write_text(tomli_w.dumps(data))
    return path
