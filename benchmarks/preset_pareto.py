"""Presets against the cheapest settings that meet their accuracy (issue 19, item 2).

For each engine, a small grid of its cost knobs (time step, integrator or
contact solver, ...) is run on calibration cases: free rocking (B0 and B2 at
0.5 λ, 20 s), two Single #2 one-sine pulses and two stack pulses (``CASES``; a
representative subset of the calibration set of ``benchmarks/calibration.py``
and ``paper-stack-pulse``, chosen to keep the search within minutes on a shared
2-core machine). Each preset sets the bounds: on every case a candidate must
end with the same status and stay within ``SLACK`` × the preset's own
max |θ − θ_ref|/λ and |Δpeak|/peak against the analytic reference (floors
``ERROR_FLOOR`` = 1e-3 λ and ``PEAK_FLOOR`` = 0.2 %: the accuracy class the
``accurate`` presets are documented for, e.g. MuJoCo's "below 2e-3 λ and 0.11 %
on pulse peaks", and issue 19's "B0 at ≤ 1e-3 λ"; without them a preset far
more precise than needed on one case would demand that precision of every
cheaper candidate). Cost is the sum of
the runs' CPU times over the cases. The table reports, per preset,
cost(preset) / cost(cheapest candidate meeting its bounds) and that candidate
(a ratio of 1.0 means the preset is on the front of this grid).

Run ``python -m benchmarks --only pareto`` (the section) or
``python -m benchmarks.preset_pareto mujoco dart`` (chosen engines).
"""

from __future__ import annotations

import itertools
import sys
from dataclasses import dataclass
from typing import Any

from benchmarks import engine_status, load
from rockbench import analytic
from rockbench.evaluation import evaluate_run
from rockbench.runner import ExecutionOptions, Job, run_jobs
from rockbench.scenarios import Scenario, get_scenario
from rockbench.trajectory import Status

__all__ = ["run", "GRIDS", "CASES", "Outcome", "search"]

#: The calibration cases of the search.
CASES = ("free-b0", "free-b2-0.5", "single-pulse-3.0hz-8mm", "single-pulse-5.0hz-6mm",
         "stack-pulse-4.0hz-4mm", "stack-pulse-5.0hz-3mm")
#: A candidate may be this much worse than the preset on a case.
SLACK = 1.10
#: Smallest bounds: max |Δθ|/λ and |Δpeak|/peak.
ERROR_FLOOR = 1e-3
PEAK_FLOOR = 2e-3
#: Knob grids per engine (every combination is a candidate; the presets are added).
GRIDS: dict[str, dict[str, list[Any]]] = {
    "mujoco": {"timestep": [1e-4, 2e-4, 5e-4, 1e-3], "integrator": ["Euler", "implicitfast"],
               "timeconst_factor": [2.0, 4.0]},
    "dart": {"timestep": [2.5e-5, 5e-5, 1e-4, 2.5e-4, 1e-3],
             "collision_detector": ["fcl", "ode"]},
    "drake": {"timestep": [2.5e-4, 5e-4, 1e-3], "contact_approximation": ["sap", "similar",
                                                                          "tamsi"]},
}


@dataclass(frozen=True)
class Outcome:
    """One candidate on every case: statuses, errors and the total CPU time."""

    settings: tuple[tuple[str, Any], ...]
    status: tuple[Status, ...]
    error: tuple[float, ...]
    peak: tuple[float, ...]
    cpu: float

    def meets(self, preset: Outcome) -> bool:
        """Same statuses as ``preset`` and its accuracy (within SLACK) on every case."""
        return (self.status == preset.status
                and all(e <= max(SLACK * p, ERROR_FLOOR)
                        for e, p in zip(self.error, preset.error, strict=True))
                and all(e <= max(SLACK * p, PEAK_FLOOR)
                        for e, p in zip(self.peak, preset.peak, strict=True)))

    def label(self) -> str:
        """The knobs as ``k=v`` text."""
        return ", ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}"
                         for k, v in self.settings)


def _candidates(engine: str) -> list[dict[str, Any]]:
    grid = GRIDS[engine]
    combos = [dict(zip(grid, values, strict=True)) for values in itertools.product(*grid.values())]
    return [{"preset": p} for p in ("accurate", "fast")] + combos


def search(engine: str, cases: list[Scenario], jobs: int = 2) -> dict[str, Outcome]:
    """Every candidate's outcome, keyed by its label (presets as ``preset=...``)."""
    refs = {sc.name: analytic.reference(sc) for sc in cases}
    cands = _candidates(engine)
    todo = [Job(sc, engine, c) for c in cands for sc in cases]
    trajs = run_jobs(todo, ExecutionOptions(jobs=jobs, timeout=1800.0))
    out: dict[str, Outcome] = {}
    for k, c in enumerate(cands):
        part = trajs[k * len(cases):(k + 1) * len(cases)]
        ms = [evaluate_run(sc, t, refs[sc.name]) for sc, t in zip(cases, part, strict=True)]
        inf = float("inf")
        o = Outcome(tuple(c.items()), tuple(t.status for t in part),
                    tuple(m.max_error if m.max_error is not None else inf for m in ms),
                    tuple(abs(m.peak_error) if m.peak_error is not None
                          and not sc.excitation.is_free else 0.0
                          for m, sc in zip(ms, cases, strict=True)),
                    sum(t.cpu_time for t in part))
        out[o.label()] = o
    return out


def run(quick: bool = False, engines: list[str] | None = None) -> tuple[str, dict]:
    """Markdown section and raw numbers."""
    names = engines or ["mujoco", "dart"]
    cases = [get_scenario(n) for n in (CASES[::2] if quick else CASES)]
    lines = [
        "## Presets against the cheapest settings meeting their bounds (issue 19)",
        "",
        f"Cases: {', '.join(sc.name for sc in cases)}. A candidate meets a preset's bounds "
        f"when it ends with the same status on every case and stays within {SLACK:g} × the "
        f"preset's max |Δθ|/λ and |Δpeak|/peak there (floors {ERROR_FLOOR:g}, {PEAK_FLOOR:g}). "
        "Cost = sum of the runs' CPU times. Grids: "
        + "; ".join(f"{e}: " + ", ".join(f"{k} ∈ {{{', '.join(map(str, v))}}}"
                                          for k, v in GRIDS[e].items()) for e in names)
        + f". {load()} at the start.",
        "",
        "| engine | preset | CPU (s) | worst max abs Δθ/λ | cheapest meeting its bounds | CPU (s) "
        "| worst max abs Δθ/λ | cost(preset)/cost(cheapest) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    data: dict[str, Any] = {}
    for e in names:
        ok, what = engine_status(e)
        if not ok or e not in GRIDS:
            lines.append(f"| {e} | – | – | – | {what if not ok else 'no grid'} | – | – | – |")
            continue
        res = search(e, cases)
        data[e] = {k: dict(cpu=o.cpu, error=o.error, peak=o.peak,
                           status=[s.value for s in o.status]) for k, o in res.items()}
        for p in ("accurate", "fast"):
            pre = res[f"preset={p}"]
            fits = [o for o in res.values() if o.meets(pre)]
            best = min(fits, key=lambda o: o.cpu)
            lines.append(f"| {e} | {p} | {pre.cpu:.2f} | {max(pre.error):.2e} | {best.label()} "
                         f"| {best.cpu:.2f} | {max(best.error):.2e} | {pre.cpu / best.cpu:.2f} |")
        lines.append("")
        lines += [f"<details><summary>{e}: every candidate</summary>", "",
                  "| candidate | CPU (s) | " + " | ".join(sc.name for sc in cases) + " |",
                  "|---|---|" + "---|" * len(cases)]
        for o in sorted(res.values(), key=lambda o: o.cpu):
            cells = [f"{err:.1e} / {100 * pk:.2f} %" if st is Status.OK else st.value
                     for st, err, pk in zip(o.status, o.error, o.peak, strict=True)]
            lines.append(f"| {o.label()} | {o.cpu:.2f} | " + " | ".join(cells) + " |")
        lines += ["", "(cells: max |Δθ|/λ / |Δpeak|/peak)", "</details>", ""]
    return "\n".join(lines), data


if __name__ == "__main__":
    text, _ = run(engines=sys.argv[1:] or None)
    print(text)
