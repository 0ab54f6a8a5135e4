"""Sensitivity study: the paper's Table 2 variations on B0 free rocking, per engine.

The paper varied Bullet's solver iterations, collision shape, collision margin,
sub-steps and frame rate one at a time. Each engine here gets the same
variations on its closest knobs, found by reading its ``Settings`` fields;
where an engine has no such knob the variation is skipped with the reason.
Engines that only expose a time step get the paper's time step
Δt = 1 / ((n_s + 1) · FPS), with FPS = 60 for the sub-step study and n_s = 20
for the rate study (the paper's frame-rate/sub-step relation; the two fixed
values are our choice, stated in the report).
"""

from __future__ import annotations

import dataclasses
import typing
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rockbench.engines import Engine, engine_class
from rockbench.report.figures import sensitivity_figure
from rockbench.report.results import REFERENCE, Run
from rockbench.report.tables import Cell, Table, fmt_error, fmt_factor, fmt_seconds
from rockbench.runner import Job
from rockbench.scenarios import Scenario
from rockbench.trajectory import Trajectory

__all__ = ["Knob", "KNOBS", "Variation", "Skipped", "map_knob", "plan_sensitivity",
           "sensitivity_table", "sensitivity_figures", "SUITE", "SCENARIO",
           "SUBSTEP_FPS", "RATE_SUBSTEPS"]

#: The pseudo-suite name that runs only the sensitivity study.
SUITE = "paper-sensitivity"
#: The scenario varied (the paper's B0).
SCENARIO = "free-b0"
#: Frame rate assumed when sub-steps map onto a time step.
SUBSTEP_FPS = 60.0
#: Sub-steps assumed when a frame rate maps onto a time step.
RATE_SUBSTEPS = 20


@dataclass(frozen=True)
class Knob:
    """One of the paper's Table 2 variations."""

    key: str
    title: str
    values: tuple[Any, ...]
    unit: str = ""
    fields: tuple[str, ...] = ()
    closest: tuple[tuple[str, str], ...] = ()


KNOBS: tuple[Knob, ...] = (
    Knob("iterations", "solver iterations", (10, 100, 1000),
         fields=("iterations", "solver_iterations", "num_solver_iterations", "num_iterations",
                 "max_iterations")),
    Knob("shape", "collision shape", ("box", "convex", "mesh"),
         fields=("collision_shape", "shape", "block_shape", "geometry")),
    Knob("margin", "collision margin", (1e-3, 1e-5, 1e-6), "m",
         fields=("collision_margin", "margin", "contact_margin"),
         closest=(("collision_slop", "the overlap Chipmunk tolerates, its closest "
                                     "geometric contact tolerance"),)),
    Knob("substeps", "sub-steps per frame", (2, 20, 200),
         fields=("substeps", "sub_steps", "num_substeps", "num_sub_steps", "substeps_per_frame")),
    Knob("rate", "simulation rate", (10, 50, 240), "fps",
         fields=("fps", "rate", "frame_rate", "frames_per_second", "simulation_rate")),
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


def _companion(knob: Knob, fields: dict[str, Any]) -> dict[str, Any]:
    """Fixed partner knobs so that every engine sees the paper's Δt = 1/((n_s + 1)·FPS).

    Varying the sub-steps holds the rate at :data:`SUBSTEP_FPS`, varying the rate
    holds the sub-steps at :data:`RATE_SUBSTEPS`; an explicit time-step knob that
    accepts None is cleared so that it does not override them.
    """
    other = {"substeps": "rate", "rate": "substeps"}.get(knob.key)
    if other is None:
        return {}
    partner = next(k for k in KNOBS if k.key == other)
    pf = next((f for f in partner.fields if f in fields), None)
    if pf is None:
        return {}
    out: dict[str, Any] = {pf: SUBSTEP_FPS if knob.key == "substeps" else RATE_SUBSTEPS}
    if "timestep" in fields and type(None) in typing.get_args(fields["timestep"]):
        out["timestep"] = None
    return out


def map_knob(name: str, cls: type[Engine], knob: Knob) -> _Plan:
    """Map one Table 2 knob onto an engine's closest settings field.

    Parameters
    ----------
    name : str
        Engine name.
    cls : type of Engine
        Its class (its ``Settings`` fields are read).
    knob : Knob
        The paper's variation.

    Returns
    -------
    _Plan
        The variations to run and what is skipped, with reasons.
    """
    plan = _Plan()
    fields = _fields(cls)
    field_name = next((f for f in knob.fields if f in fields), None)
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
    if field_name is None:
        closest = next(((f, why) for f, why in knob.closest if f in fields), None)
        if closest is not None:
            field_name = closest[0]
            note = f"{name}.{field_name} stands in for the {knob.title}: {closest[1]}"
    if field_name is not None:
        companion = _companion(knob, fields)
        for v in knob.values:
            ov = {field_name: v, **companion}
            extra = "".join(f", {k} = {x}" for k, x in companion.items())
            plan.variations.append(Variation(knob.key, v, name, ov,
                                             f"{field_name} = {v:g}{extra}", note))
        return plan
    if knob.key in ("substeps", "rate") and "timestep" in fields:
        for v in knob.values:
            if knob.key == "substeps":
                dt = 1.0 / ((v + 1) * SUBSTEP_FPS)
                why = f"timestep = 1/(({v}+1)·{SUBSTEP_FPS:g} fps) = {dt:.3g} s"
            else:
                dt = 1.0 / ((RATE_SUBSTEPS + 1) * v)
                why = f"timestep = 1/(({RATE_SUBSTEPS}+1)·{v} fps) = {dt:.3g} s"
            plan.variations.append(Variation(knob.key, v, name, {"timestep": dt}, why))
        return plan
    plan.skipped.append(Skipped(knob.key, name, f"{name} has no {knob.title} knob "
                                f"(knobs: {', '.join(fields)})"))
    return plan


def plan_sensitivity(engines: Sequence[str], scenario: Scenario, *,
                     base: Mapping[str, Mapping[str, Any]] | None = None,
                     make_run: Callable[[Job, str, str, str, Mapping[str, Any]], Run],
                     ) -> tuple[list[Run], list[Variation], list[Skipped]]:
    """Runs of the sensitivity study for the given engines.

    Parameters
    ----------
    engines : sequence of str
        Engine names (the analytic reference is left out).
    scenario : Scenario
        The scenario varied (B0).
    base : mapping, optional
        Per engine, the settings the variations start from (default: ``accurate``).
    make_run : callable
        ``make_run(job, method, preset, variation, knobs)`` builds a :class:`Run`
        (the caller knows settings hashes and versions).

    Returns
    -------
    runs, variations, skipped
        Planned runs (one per variation), the variations, and what was skipped.
    """
    runs: list[Run] = []
    variations: list[Variation] = []
    skipped: list[Skipped] = []
    for eng in engines:
        if eng == REFERENCE:
            continue
        cls = engine_class(eng)
        if cls.capabilities.analytic:
            continue
        start = dict((base or {}).get(eng, {"preset": "accurate"}))
        for knob in KNOBS:
            plan = map_knob(eng, cls, knob)
            skipped += plan.skipped
            for v in plan.variations:
                settings = {**start, **v.overrides}
                cls.settings(settings.get("preset"),
                             **{k: x for k, x in settings.items() if k != "preset"})
                method = f"{eng}[{v.label}]"
                job = Job(scenario, eng, settings, label=method)
                runs.append(make_run(job, method, str(start.get("preset", "")), v.label,
                                     v.overrides))
                variations.append(v)
    return runs, variations, skipped


def sensitivity_table(number: int, scenario: Scenario, variations: Sequence[Variation],
                      skipped: Sequence[Skipped], rows: Mapping[str, Mapping[str, Any]],
                      ref_row: Mapping[str, Any] | None) -> Table:
    """Error and cost of every variation (and the skipped ones, with their reasons).

    Parameters
    ----------
    number : int
        Table number.
    scenario : Scenario
        The scenario varied.
    variations : sequence of Variation
        What was run.
    skipped : sequence of Skipped
        What was not, and why.
    rows : mapping
        Method label (``engine[knob=value]``) → result row.
    ref_row : mapping or None
        The analytic reference's row (its time to rest goes in the caption).
    """
    t_rest = fmt_seconds(ref_row["time_to_rest"]) if ref_row else "–"
    t = Table(
        key="sensitivity", title=f"Table {number}. Sensitivity of {scenario.name} to the "
                                 "paper's Table 2 variations",
        caption=(f"Each of the paper's knobs varied alone on the {scenario.name} free-rocking "
                 "case, starting from each engine's accurate preset and applied to the "
                 "engine's closest setting (column 'engine setting'). Error against "
                 "Housner's solution max |θ − θ_ref|/λ, time to rest (Housner: "
                 f"{t_rest} s), wall time and real-time factor. Knobs an engine does not "
                 "have are listed with the reason."),
        columns=["knob", "paper value", "engine", "engine setting", "status", "max |Δθ|/λ",
                 "t_rest (s)", "wall (s)", "RTF"])
    for knob in KNOBS:
        for v in [x for x in variations if x.knob == knob.key]:
            r = rows.get(f"{v.engine}[{v.label}]")
            val = f"{v.value:g} {knob.unit}".strip() if isinstance(v.value, float) else \
                f"{v.value} {knob.unit}".strip()
            setting = Cell(v.mapping, note=t.note(v.note) if v.note else 0, title=v.note)
            head = [Cell(knob.title, kind="head"), val, v.engine, setting]
            if r is None:
                t.add_row([*head, Cell("not run", kind="crashed"), "", "", "", ""])
                continue
            st = r["status"]
            stc = Cell("ok") if st == "ok" else t.status_cell(st, r["message"], v.engine)
            err = Cell(fmt_error(r["max_error"])) if st == "ok" else Cell("")
            t.add_row([*head, stc, err,
                       Cell(fmt_seconds(r["time_to_rest"])) if st == "ok" else Cell(""),
                       fmt_seconds(r["wall_time"]),
                       fmt_factor(r["realtime_factor"]) if st in ("ok", "overturned") else ""])
        for s in [x for x in skipped if x.knob == knob.key]:
            val = "all" if s.value is None else str(s.value)
            t.add_row([Cell(knob.title, kind="head"), val, s.engine, "–",
                       Cell("⊘ not varied", kind="unsupported", note=t.note(s.reason),
                            title=s.reason), "", "", "", ""])
    return t


def sensitivity_figures(out: Path, scenario: Scenario, variations: Sequence[Variation],
                        trajs: Mapping[str, Trajectory], reference: Trajectory | None,
                        ) -> list[tuple[Path, str]]:
    """One figure per knob (panels per engine), like the paper's Fig. 4.

    Returns
    -------
    list of (Path, str)
        PNG paths and captions.
    """
    figs = []
    for knob in KNOBS:
        vs = [v for v in variations if v.knob == knob.key]
        if not vs:
            continue
        panels: list[tuple[str, dict[str, Trajectory]]] = []
        for eng in dict.fromkeys(v.engine for v in vs):
            d = {}
            for v in vs:
                if v.engine == eng and f"{eng}[{v.label}]" in trajs:
                    unit = f" {knob.unit}" if knob.unit else ""
                    val = f"{v.value:g}" if isinstance(v.value, float) else str(v.value)
                    d[f"{knob.title} = {val}{unit}"] = trajs[f"{eng}[{v.label}]"]
            panels.append((eng, d))
        title = f"{knob.title} varied ({', '.join(map(str, knob.values))} {knob.unit})".strip()
        path = sensitivity_figure(Path(out) / "figures" / f"sensitivity-{knob.key}.png",
                                  scenario, title.replace(" )", ")"), panels, reference)
        maps = "; ".join(sorted({f"{v.engine}: {v.mapping.split(' = ')[0]}" for v in vs}))
        notes = " ".join(sorted({v.note + "." for v in vs if v.note}))
        figs.append((path, f"{scenario.name} free rocking with the {knob.title} varied as in "
                           f"the paper's Table 2, one panel per engine, Housner's solution in "
                           f"black (engine knobs: {maps}). {notes}".strip()))
    return figs
