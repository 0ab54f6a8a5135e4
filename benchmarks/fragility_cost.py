"""Cost of the fragility study (issue 17): the analytic IDA of one block over a whole set.

``python -m benchmarks.fragility_cost [--set NAME] [--levels N] [--jobs N] [--quick]``

One parapet-like block (0.25 m × 1.25 m, 2000 kg/m³) under every record of a
set (default the FEMA P695 far-field set, 44 components) scaled to ``--levels``
values of PGA/(g tan λ) from 0.5 to 4 (default 15), on the analytic reference
only, through :func:`rockbench.studies.fragility.run_fragility` (isolated runs,
``--jobs`` workers, no store). Measured:

* the wall time of the study and the sum of its runs' own CPU time
  (``Engine.simulate``, measured in each run's process);
* the study's overhead ``(wall × jobs) / Σ CPU(runs) − 1``: everything that is not
  the physics (process start-up, pickling, planning, evaluation, the fits and
  their bootstraps, idle workers at the tail). On a shared machine the wall
  time also holds other people's work, so the same ratio is given on CPU
  time: (CPU of this process and its reaped workers, ``getrusage``) / Σ CPU(runs) − 1,
  and on the runs' own wall time: (wall × jobs) / Σ wall(runs) − 1 (what the study adds
  around runs slowed alike by the machine's load).

Loading the set (its package and the integration of every record) is timed
apart: it happens once per process. The results are printed as a Markdown
section for ``benchmarks/RESULTS.md``.
"""

from __future__ import annotations

import argparse
import resource
import time

import numpy as np

from benchmarks import load
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Block, Contact, Scenario, stack
from rockbench.studies.fragility import FragilityOptions, LimitState, run_fragility, set_records

__all__ = ["run", "GOAL"]

#: The overhead goal of issue 17.
GOAL = 0.10


def _cpu() -> float:
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def run(quick: bool = False, *, set_name: str = "fema-p695-far-field", n_levels: int = 15,
        jobs: int = 2, n_records: int | None = None) -> tuple[str, dict]:
    """Run the benchmark; its Markdown section and numbers (``quick``: 6 records, 5 levels)."""
    if quick:
        n_levels, n_records = 5, n_records or 6
    t0 = time.perf_counter()
    records = set_records(set_name)[:n_records]
    t_load = time.perf_counter() - t0
    block = Block(0.25, 0.25, 1.25, density=2000.0)
    scenario = Scenario("parapet", stack((block,)), Contact())
    levels = tuple(float(v) for v in np.linspace(0.5, 4.0, n_levels))
    opts = FragilityOptions(scenario, records, levels=levels, measure="pga-uplift",
                            execution=ExecutionOptions(jobs=jobs), set_name=set_name)
    c0, w0 = _cpu(), time.perf_counter()
    res = run_fragility(opts)
    wall, cpu_all = time.perf_counter() - w0, _cpu() - c0
    runs = [r.metrics for r in res.runs]
    run_cpu = sum(m.cpu_time or 0.0 for m in runs)
    run_wall = sum(m.wall_time for m in runs)
    sim = sum(m.simulated_time for m in runs)
    fit = res.curve("analytic", LimitState.OVERTURNING).bootstrap
    assert fit is not None
    med = (f"{fit.fit.median:.3g} [{fit.median_interval[0]:.3g}, {fit.median_interval[1]:.3g}]"
           if fit.fit.ok else fit.fit.status.value)
    disp = f"{fit.fit.dispersion:.3g}" if fit.fit.ok else "–"
    over_wall = wall * jobs / run_cpu - 1.0
    over_cpu = cpu_all / run_cpu - 1.0
    lines = [
        "## Fragility study cost (issue 17)",
        "",
        f"`python -m benchmarks.fragility_cost --set {set_name} --levels {n_levels} "
        f"--jobs {jobs}`: the analytic IDA of a 0.25 m × 1.25 m block over {len(records)} "
        f"records × {n_levels} levels of PGA/(g tan λ) (0.5–4) = {len(runs)} isolated runs, "
        "each the record plus 5 s at 200 samples/s, no store.",
        "",
        "| quantity | value |",
        "|---|---|",
        f"| loading the set (once per process) | {t_load:.1f} s |",
        f"| study wall time ({jobs} workers) | {wall:.1f} s |",
        f"| Σ CPU of the runs (simulate) | {run_cpu:.1f} s ({1e3 * run_cpu / len(runs):.0f} ms "
        f"per run, {sim:.0f} s simulated) |",
        f"| Σ wall of the runs (simulate) | {run_wall:.1f} s |",
        f"| overhead (wall × jobs)/Σ CPU − 1 (goal ≤ {100 * GOAL:.0f} %) | "
        f"{100 * over_wall:.0f} % |",
        f"| overhead on CPU: (CPU of study + workers)/Σ CPU − 1 | {100 * over_cpu:.0f} % |",
        f"| overhead on the runs' wall: (wall × jobs)/Σ wall(runs) − 1 | "
        f"{100 * (wall * jobs / run_wall - 1.0):.0f} % |",
        f"| analytic overturning median θ [95 %], β | {med}, {disp} |",
        "",
        f"({load()} at the end.)",
        "",
    ]
    return "\n".join(lines), {"runs": len(runs), "run_cpu": run_cpu, "overhead_wall": over_wall,
                              "overhead_cpu": over_cpu}


def main() -> None:
    p = argparse.ArgumentParser(prog="python -m benchmarks.fragility_cost")
    p.add_argument("--set", default="fema-p695-far-field")
    p.add_argument("--levels", type=int, default=15)
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--quick", action="store_true", help="the first 6 records only")
    a = p.parse_args()
    print(run(a.quick, set_name=a.set, n_levels=a.levels, jobs=a.jobs)[0])


if __name__ == "__main__":
    main()
