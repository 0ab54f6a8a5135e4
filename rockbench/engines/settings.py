"""Engine settings: frozen dataclasses of knobs, with presets and string overrides."""

from __future__ import annotations

import dataclasses
import enum
import hashlib
import json
import math
import types
import typing
from collections.abc import Mapping
from typing import Any, TypeVar

from rockbench.errors import RockbenchError

__all__ = ["EngineSettings", "SettingsError", "KnobRole", "parse_set_options"]


class SettingsError(RockbenchError, ValueError):
    """An engine knob does not exist or its value has the wrong type."""


class KnobRole(enum.Enum):
    """What a knob does, as an engine declares it (``Engine.knob_roles``).

    Studies and the command line ask the engine which knob plays a role instead
    of guessing from names: the tuner and the convergence ladders refine the
    knobs with a direction (:attr:`finer`), the paper's sensitivity study varies
    the knob of each of its Table 2 roles.
    """

    TIME_STEP = "time step"
    ITERATIONS = "solver iterations"
    SUBSTEPS = "sub-steps per frame"
    FRAME_RATE = "frame rate"
    TOLERANCE = "solver tolerance"
    CONTACT_SOFTNESS = "contact softness"
    CONTACT_STIFFNESS = "contact stiffness"
    CONTACT_POINTS = "contact points"
    COLLISION_SHAPE = "collision shape"
    COLLISION_MARGIN = "collision margin"
    CONTACT_SLOP = "contact slop"

    @property
    def finer(self) -> str | None:
        """``"smaller"`` or ``"larger"``: which values resolve the physics more finely
        (at a higher cost); None for a choice or a knob without such a direction."""
        if self in (KnobRole.TIME_STEP, KnobRole.TOLERANCE, KnobRole.CONTACT_SOFTNESS):
            return "smaller"
        if self in (KnobRole.ITERATIONS, KnobRole.SUBSTEPS, KnobRole.FRAME_RATE,
                    KnobRole.CONTACT_STIFFNESS, KnobRole.CONTACT_POINTS):
            return "larger"
        return None

    def refine(self, value: Any, level: int) -> Any:
        """``value`` refined ``level`` times by a factor of 2 in the :attr:`finer` direction.

        A time step, tolerance or softness is halved, iterations, rates and
        stiffnesses doubled; ``n`` sub-steps per frame become (n + 1) · 2 − 1, so that
        the step they set halves.

        Raises
        ------
        ValueError
            A role without a direction, or a value that is not a number.
        """
        if self.finer is None or isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"a {self.value} of {value!r} cannot be refined")
        k = 2 ** level
        if self is KnobRole.SUBSTEPS:
            return (int(value) + 1) * k - 1
        if self.finer == "smaller":
            return value / k
        return type(value)(value * k)


_TRUE = {"1", "true", "yes", "on"}
_FALSE = {"0", "false", "no", "off"}


def _coerce(value: Any, kind: Any, name: str) -> Any:
    """Convert a (possibly string) value to the annotated type of a knob."""
    origin = typing.get_origin(kind)
    args = typing.get_args(kind)
    if origin is typing.Union or origin is types.UnionType:
        non_none = [a for a in args if a is not type(None)]
        if value is None or (isinstance(value, str) and value.lower() == "none"):
            return None
        return _coerce(value, non_none[0], name)
    if origin is typing.Literal:
        if isinstance(value, (list, dict)) or value not in args:
            raise SettingsError(f"{name} must be one of {', '.join(map(str, args))}, got {value!r}")
        return value
    if origin is tuple:
        if isinstance(value, str):
            value = [v for v in value.replace("(", "").replace(")", "").split(",") if v.strip()]
        if not isinstance(value, (list, tuple)):
            raise SettingsError(f"{name} must be a list of values, got {value!r}")
        elem = args[0] if args else float
        return tuple(_coerce(v, elem, name) for v in value)
    # strings come from the command line and are parsed; typed values (settings
    # files, the API) must already have the knob's type: a boolean, a list or a
    # table is never read as a number
    bad = SettingsError(f"{name} must be {_KIND_NAMES.get(kind, getattr(kind, '__name__', kind))}"
                        f", got {value!r}")
    if kind is bool:
        if isinstance(value, bool):
            return value
        if isinstance(value, str) and value.strip().lower() in _TRUE | _FALSE:
            return value.strip().lower() in _TRUE
        raise bad
    if kind in (int, float):
        if isinstance(value, str):
            try:
                value = float(value)
            except ValueError:
                raise bad from None
        elif isinstance(value, bool) or not isinstance(value, (int, float)):
            raise bad
        if not math.isfinite(value):
            raise SettingsError(f"{name} must be a finite number, got {value!r}")
        if kind is int:
            if value != int(value):
                raise bad
            if abs(value) > _MAX_INT:  # engines hand integer knobs to C as an int
                raise SettingsError(f"{name} must be an integer of at most {_MAX_INT} in size "
                                    f"(the engines pass it to C as an int), got {value!r}")
            return int(value)
        return float(value)
    if kind is str:
        if not isinstance(value, str):
            raise bad
        return value
    return value


_KIND_NAMES = {bool: "a boolean (true/false)", int: "an integer", float: "a number",
               str: "a string"}
#: Largest integer knob accepted: a C int, as the engines' libraries take them.
_MAX_INT = 2**31 - 1


_SettingsT = TypeVar("_SettingsT", bound="EngineSettings")


@dataclasses.dataclass(frozen=True)
class EngineSettings:
    """Base class of every engine's knobs.

    Subclasses are frozen dataclasses whose fields are the knobs, with the
    calibrated defaults. Field types drive the conversion of ``--set`` strings.
    """

    def replace(self: _SettingsT, **overrides: Any) -> _SettingsT:
        """A copy with some knobs changed; values may be strings (converted by type)."""
        hints = typing.get_type_hints(type(self))
        names = {f.name for f in dataclasses.fields(self)}
        clean = {}
        for key, val in overrides.items():
            if key not in names:
                raise SettingsError(f"no knob {key!r}; "
                                    f"knobs: {', '.join(sorted(names))}")
            clean[key] = _coerce(val, hints[key], key)
        try:
            return dataclasses.replace(self, **clean)
        except ValueError as exc:  # validation in a subclass __post_init__
            raise SettingsError(str(exc)) from None

    @property
    def physics_step(self) -> float | None:
        """The physics step (s) these settings give: ``dt`` where an engine derives one (a
        frame rate and sub-steps), else the ``timestep`` knob; None when it has neither."""
        step = getattr(self, "dt", getattr(self, "timestep", None))
        if isinstance(step, bool) or not isinstance(step, (int, float)):
            return None
        return float(step)

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able dictionary of the knobs."""
        # knobs are scalars or tuples of scalars: no need for asdict's deep copies
        out = {}
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            out[f.name] = list(v) if isinstance(v, tuple) else v
        return out

    def digest(self) -> str:
        """Short stable hash of the knob values (for result tables and caches)."""
        text = json.dumps(self.to_dict(), sort_keys=True, default=str)
        return hashlib.sha1(text.encode()).hexdigest()[:10]

    @classmethod
    def knobs(cls) -> dict[str, str]:
        """Knob names with their type names."""
        hints = typing.get_type_hints(cls)
        return {f.name: str(hints[f.name]) for f in dataclasses.fields(cls)}


def parse_set_options(options: list[str] | None) -> dict[str, dict[str, str]]:
    """Parse ``engine.knob=value`` strings into ``{engine: {knob: value}}``.

    Raises
    ------
    SettingsError
        If an option does not have the form ``engine.knob=value``.
    """
    out: dict[str, dict[str, str]] = {}
    for opt in options or []:
        key, sep, value = opt.partition("=")
        engine, dot, knob = key.strip().partition(".")
        if not (sep and dot and engine and knob):
            raise SettingsError(f"--set expects engine.knob=value, got {opt!r}")
        out.setdefault(engine, {})[knob.strip()] = value.strip()
    return out


def merge_overrides(*maps: Mapping[str, Any] | None) -> dict[str, Any]:
    """Merge override mappings, later ones winning."""
    out: dict[str, Any] = {}
    for m in maps:
        out.update(m or {})
    return out
