"""The settings a calibration tries, derived from what an engine declares about its knobs.

An engine declares what its knobs do (``Engine.knob_roles``: a
:class:`~rockbench.engines.KnobRole` each, with the direction that resolves the
physics more finely) and its named presets. :func:`plan_search` turns that
declaration into settings, one knob moved at a time from a starting preset:

* a knob with a direction (time step, iterations, sub-steps, frame rate,
  tolerance, contact softness or stiffness, contact points) gets a ladder of
  ``levels`` rungs on either side of the preset's value, each a factor of 2
  coarser or finer (:meth:`KnobRole.refine`: a step, tolerance or softness halves
  per finer rung, iterations, rates and stiffnesses double, ``n`` sub-steps
  become ``(n + 1) · 2 − 1``); values the engine refuses are left out;
* a choice (a ``Literal`` or boolean knob without a direction, e.g. a collision
  shape) gets each of its other values when it has at most :data:`MAX_CHOICES`;
* any other knob (a slop, a margin: no direction), or one the preset leaves
  unset, stays at the preset and is listed in :attr:`SearchPlan.skipped` with
  the reason, as is a time step longer than the cases' output interval
  (``max_timestep``: the engine would refuse it);
* the engine's other named presets are added (unless ``presets=False``), so a
  calibration shows where they lie; a preset that resolves to a setting already
  planned is not run twice but named on that setting (:attr:`Setting.presets`).

:func:`explicit_plan` makes a plan of given variants instead. Running a plan is
:mod:`rockbench.studies.calibration`.
"""

from __future__ import annotations

import math
import typing
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

from rockbench.engines import Engine, EngineSettings, KnobRole, SettingsError, engine_class
from rockbench.errors import RockbenchError
from rockbench.method import Method

__all__ = ["CalibrationError", "Setting", "Skipped", "SearchPlan", "plan_search",
           "explicit_plan", "DEFAULT_LEVELS", "MAX_LEVELS", "MAX_CHOICES"]

#: Rungs on either side of the preset's value of every knob with a direction.
DEFAULT_LEVELS = 2
#: The most rungs a search takes on either side (2⁵ = 32 times finer: already costly).
MAX_LEVELS = 5
#: A choice knob with more values than this is not searched.
MAX_CHOICES = 6


class CalibrationError(RockbenchError, ValueError):
    """A bad calibration request: an undeclared knob, an unknown case, bad levels..."""


@dataclass(frozen=True)
class Setting:
    """One setting of a search: a preset, with at most one knob moved (or given overrides).

    Attributes
    ----------
    preset : str
        The named preset it starts from.
    knob : str
        The knob moved ('' for a preset itself or an explicit variant).
    value : Any
        The moved knob's value (None when no knob is moved).
    level : int
        Rungs from the preset's value: > 0 finer, < 0 coarser, 0 for a choice.
    overrides : tuple of (str, value)
        Every knob set on top of the preset, sorted by name.
    presets : tuple of str
        The engine's named presets that resolve to exactly this setting.
    """

    preset: str
    knob: str = ""
    value: Any = None
    level: int = 0
    overrides: tuple[tuple[str, Any], ...] = ()
    presets: tuple[str, ...] = ()

    @property
    def is_preset(self) -> bool:
        """No knob set on top of the preset: a named preset itself."""
        return not self.overrides

    @property
    def label(self) -> str:
        """The preset's name, or the overrides as ``knob=value``."""
        if self.is_preset:
            return self.preset
        return ", ".join(f"{k}={fmt_value(v)}" for k, v in self.overrides)

    @property
    def rung(self) -> str:
        """``preset``, ``choice``, ``variant`` or the signed level (``+1``: one rung finer)."""
        if self.is_preset:
            return "preset"
        if not self.knob:
            return "variant"
        return "choice" if self.level == 0 else f"{self.level:+d}"

    def method(self, engine: str) -> Method:
        """The method of this setting: the engine, the preset and the overrides."""
        return Method.of(engine, {"preset": self.preset, **dict(self.overrides)})


@dataclass(frozen=True)
class Skipped:
    """A declared knob, or one of its values, the search leaves out, and why."""

    knob: str
    reason: str


@dataclass(frozen=True)
class SearchPlan:
    """What a calibration tries.

    Attributes
    ----------
    engine : str
        The engine calibrated.
    preset : str
        The preset the search starts from.
    settings : tuple of Setting
        The starting preset first, then each knob's rungs (coarse to fine) and
        choices, then the other named presets.
    skipped : tuple of Skipped
        Declared knobs not searched, with the reason.
    levels : int
        Rungs on either side of the preset (0 for an explicit plan).
    """

    engine: str
    preset: str
    settings: tuple[Setting, ...]
    skipped: tuple[Skipped, ...] = ()
    levels: int = 0

    @property
    def knobs(self) -> tuple[str, ...]:
        """The knobs moved, in search order."""
        return tuple(dict.fromkeys(s.knob for s in self.settings if s.knob))

    def resolved(self, setting: Setting) -> EngineSettings:
        """The engine's settings that ``setting`` resolves to (every knob's value)."""
        return engine_class(self.engine).resolve_settings(setting.method(self.engine).settings)


def fmt_value(v: Any) -> str:
    """A knob value as tables show it (floats to 4 significant digits)."""
    return f"{v:.4g}" if isinstance(v, float) else str(v)


def _literal_choices(hint: Any) -> tuple[Any, ...] | None:
    """The values of a ``Literal`` (optionally ``| None``) or ``bool`` knob, else None."""
    if hint is bool:
        return (False, True)
    if typing.get_origin(hint) is typing.Literal:
        return typing.get_args(hint)
    args = [a for a in typing.get_args(hint) if a is not type(None)]
    if len(args) == 1 and typing.get_origin(args[0]) is typing.Literal:
        return (*typing.get_args(args[0]), None)
    return None


def _rung(role: KnobRole, value: int | float, level: int, hint: Any) -> int | float | None:
    """``value`` moved ``level`` rungs (negative: coarser); None where it cannot go."""
    moved = role.refine(value, level)
    whole = hint is int if hint in (int, float) else isinstance(value, int)
    if whole:
        moved = round(moved)
        return moved if moved >= (0 if role is KnobRole.SUBSTEPS else 1) else None
    moved = float(moved)
    return moved if math.isfinite(moved) and moved > 0 else None


def _same(a: Mapping[str, Any], b: Mapping[str, Any]) -> bool:
    """Two resolved settings equal knob by knob (floats to 1e-9 relative)."""
    if a.keys() != b.keys():
        return False
    for k, x in a.items():
        y = b[k]
        if isinstance(x, float) and isinstance(y, float):
            if not math.isclose(x, y, rel_tol=1e-9, abs_tol=0.0):
                return False
        elif x != y:
            return False
    return True


def _resolve(cls: type[Engine], preset: str, overrides: Mapping[str, Any]) -> dict[str, Any] | None:
    """The resolved knobs of ``preset`` with ``overrides``; None if the engine refuses them."""
    try:
        return cls.settings(preset, **overrides).to_dict()
    except SettingsError:
        return None


def _with_presets(cls: type[Engine], settings: list[Setting], add: bool) -> list[Setting]:
    """Name the presets each setting resolves to; append the other presets (``add``).

    A rung equal to a preset up to rounding takes the preset's own value, so that
    both are the same run (one identity in the store).
    """
    resolved = [_resolve(cls, s.preset, dict(s.overrides)) for s in settings]
    out = list(settings)
    for name in cls.presets:
        values = cls.settings(name).to_dict()
        hit = next((i for i, r in enumerate(resolved) if r is not None and _same(r, values)),
                   None)
        if hit is not None:
            s = out[hit]
            exact = tuple((k, values[k]) for k, _ in s.overrides)
            value = values[s.knob] if s.knob else s.value
            out[hit] = replace(s, overrides=exact, value=value, presets=(*s.presets, name))
        elif add:
            out.append(Setting(name, presets=(name,)))
            resolved.append(values)
    return out


def plan_search(engine: str, *, preset: str = "accurate", knobs: Sequence[str] | None = None,
                levels: int = DEFAULT_LEVELS, presets: bool = True,
                max_timestep: float | None = None) -> SearchPlan:
    """The settings a calibration of ``engine`` tries (see the module docstring).

    Parameters
    ----------
    engine : str
        A registered engine (not the analytic reference).
    preset : str
        The preset the search starts from.
    knobs : sequence of str, optional
        Restrict the search to these declared knobs (default: every one in
        ``knob_roles``, the engine's refinement knob first).
    levels : int
        Rungs on either side of each knob's preset value, 0 to :data:`MAX_LEVELS`
        (0: the preset, the choices and the other presets only).
    presets : bool
        Add the engine's other named presets.
    max_timestep : float, optional
        The longest time step the cases accept (their shortest output interval, s):
        longer rungs of a time-step knob are left out.

    Returns
    -------
    SearchPlan
        The settings, the starting preset first.

    Raises
    ------
    CalibrationError
        The analytic reference, an unknown preset, an undeclared knob or levels
        out of range (the message names the option).
    UnknownEngine, EngineUnavailable
        No such engine, or it cannot run here.
    """
    cls = engine_class(engine)
    if cls.capabilities.analytic:
        raise CalibrationError(f"ENGINE {engine!r} is the analytic reference the engines are "
                               "calibrated against: name a physics engine")
    if preset not in cls.presets:
        raise CalibrationError(f"--preset expects one of {', '.join(cls.presets)} (the presets "
                               f"of {engine}), got {preset!r}")
    if isinstance(levels, bool) or not isinstance(levels, int) or not 0 <= levels <= MAX_LEVELS:
        raise CalibrationError(f"--levels expects a whole number from 0 to {MAX_LEVELS}, "
                               f"got {levels!r}")
    declared = list(cls.knob_roles)
    first = cls.refinement or cls.knob(KnobRole.TIME_STEP)
    if first in declared:
        declared.insert(0, declared.pop(declared.index(first)))
    if knobs:
        bad = [k for k in knobs if k not in cls.knob_roles]
        if bad:
            raise CalibrationError(
                f"--knobs expects knobs that {engine} declares "
                f"({', '.join(cls.knob_roles) or 'none'}), got {bad[0]!r}")
        declared = [k for k in declared if k in knobs]
    if not declared:
        raise CalibrationError(f"ENGINE {engine!r} declares no knob to search (knob_roles)")
    base = cls.settings(preset)
    hints = typing.get_type_hints(cls.Settings)
    settings: list[Setting] = [Setting(preset)]
    skipped: list[Skipped] = []
    for knob in declared:
        role = cls.knob_roles[knob]
        value = getattr(base, knob)
        if role.finer is not None:
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                skipped.append(Skipped(knob, f"{preset} sets it to {value!r}, not a number "
                                             "to refine"))
                continue
            seen = {value}
            rungs: list[Setting] = []
            for level in [*range(-levels, 0), *range(1, levels + 1)]:
                moved = _rung(role, value, level, hints.get(knob))
                if moved is None or moved in seen or _resolve(cls, preset, {knob: moved}) is None:
                    continue
                step = cls.settings(preset, **{knob: moved}).physics_step
                if (max_timestep is not None and step is not None
                        and step > max_timestep * (1 + 1e-9)):
                    skipped.append(Skipped(knob, f"{fmt_value(moved)} gives a physics step of "
                                                 f"{step:.3g} s, longer than the cases' output "
                                                 f"interval {max_timestep:g} s"))
                    continue
                seen.add(moved)
                rungs.append(Setting(preset, knob, moved, level, ((knob, moved),)))
            settings += rungs
            if levels and not rungs:
                skipped.append(Skipped(knob, f"no valid value around {fmt_value(value)}"))
            continue
        choices = _literal_choices(hints.get(knob))
        if choices is None:
            skipped.append(Skipped(knob, f"a {role.value} has no finer direction and is not "
                                         "a choice"))
        elif len(choices) > MAX_CHOICES:
            skipped.append(Skipped(knob, f"{len(choices)} choices (more than {MAX_CHOICES})"))
        else:
            settings += [Setting(preset, knob, c, 0, ((knob, c),)) for c in choices
                         if c != value and _resolve(cls, preset, {knob: c}) is not None]
    return SearchPlan(engine, preset, tuple(_with_presets(cls, settings, presets)),
                      tuple(skipped), levels)


def explicit_plan(engine: str, variants: Sequence[Mapping[str, Any]], *,
                  preset: str = "accurate") -> SearchPlan:
    """A plan of given variants: each a mapping of knob overrides on top of ``preset``.

    An empty mapping is the preset itself. Variants are validated now.

    Raises
    ------
    SettingsError
        An unknown knob or a value of the wrong type.
    CalibrationError
        The analytic reference, an unknown preset or no variant.
    """
    cls = engine_class(engine)
    if cls.capabilities.analytic:
        raise CalibrationError(f"ENGINE {engine!r} is the analytic reference: name a "
                               "physics engine")
    if preset not in cls.presets:
        raise CalibrationError(f"preset expects one of {', '.join(cls.presets)}, got {preset!r}")
    if not variants:
        raise CalibrationError("an explicit plan needs at least one variant")
    out: list[Setting] = []
    for v in variants:
        cls.settings(preset, **v)
        out.append(Setting(preset, overrides=tuple(sorted(v.items()))))
    return SearchPlan(engine, preset, tuple(_with_presets(cls, out, False)))
