"""The sensitivity study's table and figures (the paper's Table 2 and Fig. 4)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

from rockbench.evaluation import RunResult
from rockbench.report.figures import sensitivity_figure
from rockbench.report.tables import Cell, Table, fmt_error, fmt_factor, fmt_seconds
from rockbench.scenarios import Scenario
from rockbench.studies.sensitivity import KNOBS, Skipped, Variation
from rockbench.trajectory import Trajectory

__all__ = ["sensitivity_table", "sensitivity_figures"]


def sensitivity_table(number: int, scenario: Scenario, variations: Sequence[Variation],
                      skipped: Sequence[Skipped], rows: Mapping[str, RunResult],
                      ref_row: RunResult | None) -> Table:
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
        Method label (``engine[knob=value]``) → result.
    ref_row : RunResult or None
        The analytic reference's result (its time to rest goes in the caption).
    """
    t_rest = fmt_seconds(ref_row.metrics.time_to_rest) if ref_row else "–"
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
            head: list[Cell | str] = [Cell(knob.title, kind="head"), val, v.engine, setting]
            if r is None:
                t.add_row([*head, Cell("not run", kind="crashed"), "", "", "", ""])
                continue
            m = r.metrics
            st = m.status.value
            stc = Cell("ok") if st == "ok" else t.status_cell(st, m.message, v.engine)
            err = Cell(fmt_error(m.max_error)) if st == "ok" else Cell("")
            t.add_row([*head, stc, err,
                       Cell(fmt_seconds(m.time_to_rest)) if st == "ok" else Cell(""),
                       fmt_seconds(m.wall_time),
                       fmt_factor(m.realtime_factor) if m.completed else ""])
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
