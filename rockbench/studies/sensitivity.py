"""Sensitivity study: the paper's Table 2 variations on B0 free rocking, per engine.

The paper varied Bullet's solver iterations, collision shape, collision margin,
sub-steps and frame rate one at a time. Each engine here gets the same
variations on the knobs it declares for those roles (``Engine.knob_roles``);
where an engine has none the variation is skipped with the reason.
Engines that only expose a time step get the paper's time step
Δt = 1 / ((n_s + 1) · FPS), with FPS = 60 for the sub-step study and n_s = 20
for the rate study (the paper's frame-rate/sub-step relation; the two fixed
values are our choice, stated in the report).
"""

from __future__ import annotations

import dataclasses
import typing
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from rockbench.engines import Engine, KnobRole, engine_class
from rockbench.method import REFERENCE, Method
from rockbench.scenarios import Scenario, get_scenario

__all__ = ["Knob", "KNOBS", "Variation", "Skipped", "map_knob", "plan_sensitivity",
           "SUITE", "SCENARIO", "OUTPUT_RATE", "SUBSTEP_FPS", "RATE_SUBSTEPS",
           "sensitivity_scenario"]

#: The pseudo-suite name that runs only the sensitivity study.
SUITE = "paper-sensitivity"
#: The catalog scenario varied (the paper's B0).
SCENARIO = "free-b0"
#: Output rate of the study (samples/s): the paper's coarsest settings step up to
#: 1/((2 + 1)·60 fps) = 5.6 ms (1/120 s in Blender), and no engine may step longer than
#: the output interval, so the study samples at 100 per second instead of the catalog's 1000.
OUTPUT_RATE = 100.0
#: Frame rate assumed when sub-steps map onto a time step.
SUBSTEP_FPS = 60.0
#: Sub-steps assumed when a frame rate maps onto a time step.
RATE_SUBSTEPS = 20


def sensitivity_scenario() -> Scenario:
    """B0 free rocking as the study runs it: the catalog case at :data:`OUTPUT_RATE`."""
    b0 = get_scenario(SCENARIO)
    return b0.replace(name=f"{SCENARIO}-sensitivity", output_rate=OUTPUT_RATE)


@dataclass(frozen=True)
class Knob:
    """One of the paper's Table 2 variations: the knob role it varies, and the role that
    stands in for it where an engine has none (with why)."""

    key: str
    title: str
    values: tuple[Any, ...]
    role: KnobRole
    unit: str = ""
    closest: tuple[KnobRole, str] | None = None


KNOBS: tuple[Knob, ...] = (
    Knob("iterations", "solver iterations", (10, 100, 1000), KnobRole.ITERATIONS),
    Knob("shape", "collision shape", ("box", "convex", "mesh"), KnobRole.COLLISION_SHAPE),
    Knob("margin", "collision margin", (1e-3, 1e-5, 1e-6), KnobRole.COLLISION_MARGIN, "m",
         closest=(KnobRole.CONTACT_SLOP, "the overlap the engine tolerates, its closest "
                                         "geometric contact tolerance")),
    Knob("substeps", "sub-steps per frame", (2, 20, 200), KnobRole.SUBSTEPS),
    Knob("rate", "simulation rate", (10, 50, 240), KnobRole.FRAME_RATE, "fps"),
)


@dataclass(frozen=True)
class Variation:
    """One value of one knob on one engine."""

    knob: str
    value: Any
    engine: str
    overrides: Mapping[str, Any]
    mapping: str
    note: str = ""

    @property
    def label(self) -> str:
        """``iterations=10``."""
        return f"{self.knob}={self.value:g}" if isinstance(self.value, float) else \
            f"{self.knob}={self.value}"


@dataclass(frozen=True)
class Skipped:
    """A knob (or one of its values) an engine cannot vary, with the reason."""

    knob: str
    engine: str
    reason: str
    value: Any = None


@dataclass
class _Plan:
    variations: list[Variation] = field(default_factory=list)
    skipped: list[Skipped] = field(default_factory=list)


def _fields(cls: type[Engine]) -> dict[str, Any]:
    hints = typing.get_type_hints(cls.Settings)
    return {f.name: hints[f.name] for f in dataclasses.fields(cls.Settings)}


def _literal_options(kind: Any) -> tuple[str, ...]:
    if typing.get_origin(kind) is typing.Literal:
        return tuple(str(a) for a in typing.get_args(kind))
    return ()


def _shape_option(value: str, options: Sequence[str]) -> str | None:
    words = {"box": ("box",), "convex": ("convex", "hull"), "mesh": ("mesh", "trimesh")}[value]
    for o in options:
        low = o.lower()
        if any(w in low for w in words) and not (value == "mesh" and "convex" in low):
            return o
    return None


def _companion(knob: Knob, cls: type[Engine], fields: dict[str, Any]) -> dict[str, Any]:
    """Fixed partner knobs so that every engine sees the paper's Δt = 1/((n_s + 1)·FPS).

    Varying the sub-steps holds the rate at :data:`SUBSTEP_FPS`, varying the rate
    holds the sub-steps at :data:`RATE_SUBSTEPS`; an explicit time-step knob that
    accepts None is cleared so that it does not override them.
    """
    other = {"substeps": "rate", "rate": "substeps"}.get(knob.key)
    if other is None:
        return {}
    partner = next(k for k in KNOBS if k.key == other)
    pf = cls.knob(partner.role)
    if pf is None:
        return {}
    out: dict[str, Any] = {pf: SUBSTEP_FPS if knob.key == "substeps" else RATE_SUBSTEPS}
    step = cls.knob(KnobRole.TIME_STEP)
    if step is not None and type(None) in typing.get_args(fields[step]):
        out[step] = None
    return out


def map_knob(name: str, cls: type[Engine], knob: Knob) -> _Plan:
    """Map one Table 2 knob onto an engine's closest settings field.

    Parameters
    ----------
    name : str
        Engine name.
    cls : type of Engine
        Its class (its ``knob_roles`` are read).
    knob : Knob
        The paper's variation.

    Returns
    -------
    _Plan
        The variations to run and what is skipped, with reasons.
    """
    plan = _Plan()
    fields = _fields(cls)
    field_name = cls.knob(knob.role)
    if knob.key == "shape":
        if field_name is None:
            plan.skipped.append(Skipped(knob.key, name, f"{name} has no collision-shape knob "
                                        f"(knobs: {', '.join(fields)})"))
            return plan
        options = _literal_options(fields[field_name])
        for v in knob.values:
            opt = _shape_option(v, options) if options else v
            if opt is None:
                plan.skipped.append(Skipped(knob.key, name, f"{name}.{field_name} has no "
                                            f"{v!r} option ({', '.join(options)})", v))
            else:
                plan.variations.append(Variation(knob.key, v, name, {field_name: opt},
                                                 f"{field_name} = {opt}"))
        return plan
    note = ""
    if field_name is None and knob.closest is not None:
        field_name = cls.knob(knob.closest[0])
        if field_name is not None:
            note = f"{name}.{field_name} stands in for the {knob.title}: {knob.closest[1]}"
    if field_name is not None:
        companion = _companion(knob, cls, fields)
        for v in knob.values:
            ov = {field_name: v, **companion}
            extra = "".join(f", {k} = {x}" for k, x in companion.items())
            plan.variations.append(Variation(knob.key, v, name, ov,
                                             f"{field_name} = {v:g}{extra}", note))
        return plan
    step = cls.knob(KnobRole.TIME_STEP)
    if knob.key in ("substeps", "rate") and step is not None:
        for v in knob.values:
            if knob.key == "substeps":
                dt = 1.0 / ((v + 1) * SUBSTEP_FPS)
                why = f"{step} = 1/(({v}+1)·{SUBSTEP_FPS:g} fps) = {dt:.3g} s"
            else:
                dt = 1.0 / ((RATE_SUBSTEPS + 1) * v)
                why = f"{step} = 1/(({RATE_SUBSTEPS}+1)·{v} fps) = {dt:.3g} s"
            plan.variations.append(Variation(knob.key, v, name, {step: dt}, why))
        return plan
    plan.skipped.append(Skipped(knob.key, name, f"{name} has no {knob.title} knob "
                                f"(knobs: {', '.join(fields)})"))
    return plan


def plan_sensitivity(engines: Sequence[str], *,
                     base: Mapping[str, Mapping[str, Any]] | None = None,
                     ) -> tuple[list[Method], list[Variation], list[Skipped]]:
    """Methods of the sensitivity study for the given engines.

    Parameters
    ----------
    engines : sequence of str
        Engine names (the analytic reference is left out).
    base : mapping, optional
        Per engine, the settings the variations start from (default: its
        ``sensitivity_preset``, ``accurate`` unless the engine says otherwise).

    Returns
    -------
    methods, variations, skipped
        One method per variation (its settings hold the knob overrides), the
        variations, and what was skipped with the reasons.
    """
    methods: list[Method] = []
    variations: list[Variation] = []
    skipped: list[Skipped] = []
    for eng in engines:
        if eng == REFERENCE:
            continue
        cls = engine_class(eng)
        if cls.capabilities.analytic:
            continue
        start = dict((base or {}).get(eng, {"preset": cls.sensitivity_preset}))
        for knob in KNOBS:
            plan = map_knob(eng, cls, knob)
            skipped += plan.skipped
            for v in plan.variations:
                settings = {**start, **v.overrides}
                cls.resolve_settings(settings)  # a bad override fails here, before any run
                methods.append(Method.of(eng, settings, variation=v.label))
                variations.append(v)
    return methods, variations, skipped
