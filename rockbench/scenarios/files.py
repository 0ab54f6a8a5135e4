"""Scenario files: TOML load and save (round trip), strict about unknown keys and types.

Each table is checked here with :mod:`rockbench.checks` (a string, boolean,
list or table is never read as a number); the ``[excitation]`` table is read by the
excitation class its ``type`` names (:func:`~rockbench.scenarios.excitation.excitation_from_table`).

Both forms describe one :class:`~rockbench.geometry.Geometry`: a stack (blocks
bottom first, each centred on the one below but for its ``offset``), unless a
block has a pose (``x``, ``z``, ``angle``) or ``vertices``, or the file has
``[[supports]]``: then every block is placed where it says (``width``/``height``
rectangles by their centroid, ``vertices`` polygons by their own frame) and
every support is a fixed polygon ``vertices`` moving with the base. A geometry
is written in the stack form when that form rebuilds it exactly.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import tomli_w

from rockbench import checks
from rockbench.errors import ScenarioError
from rockbench.geometry import Block, Body, Cylinder, Geometry, Prism, Support, Upright, stack
from rockbench.geometry.bodies import vertex_list
from rockbench.geometry.builders import stack_poses
from rockbench.scenarios.excitation import Excitation, excitation_from_table
from rockbench.scenarios.model import Contact, Scenario
from rockbench.scenarios.plausibility import warn_implausible
from rockbench.tomlfile import read_toml

__all__ = ["load_scenario", "save_scenario", "scenario_from_dict", "scenario_to_dict"]

_TOP = {"name", "description", "duration", "output_rate", "gravity", "blocks", "contact",
        "initial", "excitation", "supports"}
_BLOCK = {"width", "depth", "height", "mass", "density", "chamfer", "offset", "radius"}
_CYLINDER = {"radius", "height", "mass", "density"}
#: keys that make a block table (and its file) an assembly's
_POSE = {"x", "z", "angle", "vertices"}
_ASSEMBLY_BLOCK = (_BLOCK - {"offset"}) | _POSE
_SUPPORT = {"vertices"}
_CONTACT = {"friction", "restitution", "eta", "interface_friction"}
_INITIAL = {"tilt", "tilt_rad", "azimuth", "velocity", "angular_velocity"}


def _upright(raw: dict[str, Any]) -> Upright:
    """A block table's Block, or Cylinder where it gives a radius (pose keys taken off)."""
    if "radius" in raw:
        extra = set(raw) - _CYLINDER
        if extra:
            raise ScenarioError(f"is a cylinder (it has a radius): {', '.join(sorted(extra))} "
                                f"is for rectangular blocks")
        if "height" not in raw:
            raise ScenarioError("is missing height")
        return Cylinder(**raw)
    missing = {"width", "depth", "height"} - set(raw)
    if missing:
        raise ScenarioError(f"is missing {', '.join(sorted(missing))}")
    return Block(**raw)


def _named(exc: ScenarioError, where: str) -> ScenarioError:
    """The error with the table it comes from named first."""
    msg = str(exc)
    return ScenarioError(f"{where}{' ' if msg.startswith(('is ', 'takes ')) else ': '}{msg}")


def _blocks(raw_blocks: Any) -> tuple[list[Upright], list[float]]:
    if not isinstance(raw_blocks, list) or not raw_blocks:
        got = "" if raw_blocks is None else f", got {checks.describe(raw_blocks)}"
        raise ScenarioError(f"scenario needs at least one [[blocks]] table{got}")
    blocks, offsets = [], []
    for i, raw in enumerate(raw_blocks, 1):
        where = f"[[blocks]] #{i}"
        raw = checks.table(raw, where)
        checks.no_unknown(raw, _BLOCK, where)
        offsets.append(checks.coordinate(raw.pop("offset", 0.0), f"{where} offset"))
        try:
            blocks.append(_upright(raw))
        except ScenarioError as exc:
            raise _named(exc, where) from None
    return blocks, offsets


def _has_poses(data: dict[str, Any]) -> bool:
    raw = data.get("blocks")
    tables = raw if isinstance(raw, list) else []
    return "supports" in data or any(isinstance(b, dict) and _POSE & set(b) for b in tables)


def _placed(raw_blocks: Any, raw_supports: Any) -> Geometry:
    if not isinstance(raw_blocks, list) or not raw_blocks:
        got = "" if raw_blocks is None else f", got {checks.describe(raw_blocks)}"
        raise ScenarioError(f"scenario needs at least one [[blocks]] table{got}")
    blocks: list[Body] = []
    poses = []
    for i, raw in enumerate(raw_blocks, 1):
        where = f"[[blocks]] #{i}"
        raw = checks.table(raw, where)
        if "offset" in raw:
            raise ScenarioError(f"{where}: 'offset' is for stacks; in a file with poses, "
                                f"vertices or [[supports]] give the centroid 'x'")
        checks.no_unknown(raw, _ASSEMBLY_BLOCK, where)
        pose = (raw.pop("x", 0.0), raw.pop("z", None), raw.pop("angle", 0.0))
        try:
            if "vertices" in raw:
                if set(raw) & {"width", "height", "chamfer"}:
                    raise ScenarioError("takes 'vertices' or 'width'/'height'/'chamfer', "
                                        "not both")
                if pose[1] is None:
                    pose = (pose[0], 0.0, pose[2])
                if "depth" not in raw:
                    raise ScenarioError("is missing depth")
                blocks.append(Prism(raw.pop("vertices"), **raw))
            else:
                body = _upright(raw)
                if pose[1] is None:
                    raise ScenarioError("is missing z (the centroid's height) that a "
                                        "rectangle in an assembly needs")
                blocks.append(body)
        except ScenarioError as exc:
            raise _named(exc, where) from None
        poses.append(pose)
    supports = []
    if raw_supports is not None:
        if not isinstance(raw_supports, list):
            raise ScenarioError(f"[[supports]] must be an array of tables, got "
                                f"{checks.describe(raw_supports)}")
        for i, raw in enumerate(raw_supports, 1):
            where = f"[[supports]] #{i}"
            raw = checks.table(raw, where)
            checks.no_unknown(raw, _SUPPORT, where)
            if "vertices" not in raw:
                raise ScenarioError(f"{where} is missing vertices")
            try:
                supports.append(Support(vertex_list(raw["vertices"], "support vertices")))
            except ScenarioError as exc:
                raise ScenarioError(f"{where}: {exc}") from None
    try:
        return Geometry(tuple(blocks), tuple(poses), tuple(supports))
    except ScenarioError as exc:
        msg = str(exc)
        for i in range(len(blocks), 0, -1):  # name the file's tables, numbered from 1
            msg = msg.replace(f"block #{i} ", f"[[blocks]] #{i} ")
        raise ScenarioError(msg) from None


def scenario_from_dict(data: dict[str, Any], *, source: Path | None = None,
                       default_name: str = "scenario") -> Scenario:
    """Build a :class:`Scenario` from the parsed TOML structure.

    Parameters
    ----------
    data : dict
        Parsed scenario file.
    source : Path, optional
        The scenario file; relative record file paths are resolved against its
        folder (default: the working directory).
    default_name : str
        Name used when the file has none.

    Raises
    ------
    ScenarioError
        For any unknown key, wrong type or invalid value; the message names the field.
    """
    data = checks.table(data, "scenario")
    checks.no_unknown(data, _TOP, "the scenario file")
    if _has_poses(data):
        geometry = _placed(data.get("blocks"), data.get("supports"))
    else:
        blocks, offsets = _blocks(data.get("blocks"))
        geometry = stack(tuple(blocks), tuple(offsets))
    contact_raw = checks.table(data.get("contact", {}), "[contact]")
    checks.no_unknown(contact_raw, _CONTACT, "[contact]")
    initial = checks.table(data.get("initial", {}), "[initial]")
    checks.no_unknown(initial, _INITIAL, "[initial]")
    # gravity is checked before tilt_rad needs it for λ
    g = data.get("gravity", 9.81)
    checks.number(g, "gravity", low=0.0, unit="m/s²")
    if "tilt" in initial and "tilt_rad" in initial:
        raise ScenarioError("[initial] takes 'tilt' (fraction of λ) or 'tilt_rad', not both")
    tilt = initial.get("tilt", 0.0)
    if not checks.is_number(tilt):
        raise ScenarioError(f"[initial] tilt must be a number (fraction of λ), got "
                            f"{checks.describe(tilt)}")
    if "tilt_rad" in initial:
        if geometry.column is None:
            raise ScenarioError("[initial] tilt_rad is for a column of blocks on the base; "
                                "this geometry's blocks take their own angle")
        lam = geometry.column.blocks[0].rocking(float(g)).lam
        rad = checks.number(initial["tilt_rad"], "[initial] tilt_rad", unit="rad")
        if not abs(rad) < lam:
            raise ScenarioError(f"[initial] tilt_rad must be smaller in size than the bottom "
                                f"block's λ = {lam:.6g} rad, got {rad!r}")
        tilt = rad / lam
    name = checks.text(data.get("name", default_name), "name")
    description = checks.text(data.get("description", ""), "description")
    azimuth = checks.number(initial.get("azimuth", 0.0), "[initial] azimuth", unit="°")
    start = {f"initial_{k}": initial[k] for k in ("velocity", "angular_velocity")
             if k in initial}
    if azimuth and not tilt:
        raise ScenarioError("[initial] azimuth points the tilt: give a tilt too")
    return Scenario(
        name=name,
        description=description,
        geometry=geometry,
        contact=Contact(**contact_raw),
        excitation=_excitation(data.get("excitation", {"type": "free"}), source, geometry, g),
        initial_tilt=tilt,
        initial_azimuth=math.radians(azimuth),
        **start,
        duration=data.get("duration", 10.0),
        output_rate=data.get("output_rate", 1000.0),
        g=g,
    )


def _excitation(table: Any, source: Path | None, geometry: Geometry,
                g: float) -> Excitation:
    """The ``[excitation]``; a record of a set scaled to a block-normalised intensity
    (``pga-uplift``, ``pgv-rocking``) needs the rocking constants of the column just
    built: its block's, or a stack's as one body."""
    if not (isinstance(table, dict) and table.get("type") == "record" and "set" in table
            and "measure" in table):
        return excitation_from_table(table, source=source)
    from rockbench.scenarios.record_sets import SetRecord  # optional packages

    col = geometry.column
    rocking = (None if col is None else col.blocks[0].rocking(float(g))
               if len(col) == 1 else col.monolithic(float(g)))
    try:
        return SetRecord.from_table(table, source=source, rocking=rocking, g=float(g))
    except ScenarioError as exc:
        msg = str(exc)
        raise ScenarioError(msg if msg.startswith("[excitation]") else
                            f"[excitation] {msg}") from None


def scenario_to_dict(scenario: Scenario) -> dict[str, Any]:
    """The TOML structure of a scenario (inverse of :func:`scenario_from_dict`)."""
    geo = scenario.geometry
    blocks = _geometry_tables(geo)
    supports = [s.to_dict() for s in geo.supports]
    out: dict[str, Any] = {"name": scenario.name}
    if scenario.description:
        out["description"] = scenario.description
    out.update({
        "duration": scenario.duration,
        "output_rate": scenario.output_rate,
        "gravity": scenario.g,
        "blocks": blocks,
        **({"supports": supports} if supports else {}),
        "contact": scenario.contact.to_dict(),
        "initial": _initial_table(scenario),
        "excitation": scenario.excitation.to_table(),
    })
    return out


def _initial_table(scenario: Scenario) -> dict[str, Any]:
    """The ``[initial]`` table: the tilt, and the azimuth (degrees) and velocities if any."""
    out: dict[str, Any] = {"tilt": scenario.initial_tilt}
    if scenario.initial_azimuth:
        out["azimuth"] = math.degrees(scenario.initial_azimuth)
    if scenario.moving_start:
        out["velocity"] = list(scenario.initial_velocity)
        out["angular_velocity"] = list(scenario.initial_angular_velocity)
    return out


def _geometry_tables(geo: Geometry) -> list[dict[str, Any]]:
    """The ``[[blocks]]`` tables: the stack form where it rebuilds the geometry exactly."""
    col = geo.column
    if col is not None and stack_poses(col.blocks, col.offsets) == geo.poses:
        out = []
        for b, off in zip(col.blocks, col.offsets, strict=True):
            d = b.to_dict()
            if off:
                d["offset"] = off
            out.append(d)
        return out
    out = []
    for body, (x, z, a) in zip(geo.bodies, geo.poses, strict=True):
        d = body.to_dict()
        d.update({"x": x, "z": z, "angle": a})
        out.append(d)
    return out


def load_scenario(path: str | Path) -> Scenario:
    """Read a scenario TOML file.

    Values that are implausible but usable (a size that looks like millimetres, a
    base acceleration above 3 g) are read, each with a
    :class:`~rockbench.errors.PlausibilityWarning` naming the file
    (:mod:`rockbench.scenarios.plausibility`).

    Raises
    ------
    ScenarioError
        Unreadable file, malformed TOML, unknown keys or invalid values; the
        message starts with the file name.
    """
    path = Path(path)
    data = read_toml(path, ScenarioError, "scenario file")
    try:
        scenario = scenario_from_dict(data, source=path, default_name=path.stem)
    except ScenarioError as exc:
        raise ScenarioError(f"{path}: {exc}") from None
    warn_implausible(scenario, f"{path}: ")
    return scenario


def save_scenario(scenario: Scenario, path: str | Path) -> Path:
    """Write a scenario as TOML; :func:`load_scenario` reads back an equal scenario."""
    path = Path(path)
    data = scenario_to_dict(scenario)
    path.write_text(tomli_w.dumps(data))
    return path
