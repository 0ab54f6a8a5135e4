"""Cost of a verdict against the runs it judges.

``python -m benchmarks.verdict_cost [--engines A,B] [--quick] [--jobs N]``

Two cases, each measured on a fresh store and then again on the same store:

* **paper**: the paper suite (``--quick``: its six single-block pulses), every
  engine at its ``accurate`` and ``fast`` presets. Closed forms cover every case,
  so the verdict needs no ladder (``converge="auto"``); with ``converge="all"``
  the ladders also run, which is what a consensus costs where a closed form
  would not exist.
* **assembly**: a 5-drum column under a one-sine pulse at twice its static factor
  (no closed form), the same engines: the ladders and the consensus judge it.

Measured: the CPU time of the methods' own runs (what the verdict judges), the
CPU time of the ladders' further rungs (what the verdict adds), their ratio,
and the wall time; the second pass over the same store shows the reuse (the
preset is rung 0 of its ladder and every rung is stored). The results are
printed as a Markdown section for ``benchmarks/RESULTS.md``.
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from pathlib import Path

from benchmarks import load
from rockbench.analytic import critical_angle
from rockbench.geometry import drum_column
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Contact, Scenario, SinePulse, get_scenario, get_suite
from rockbench.studies.verify import VerifyOptions, run_verification

__all__ = ["run", "assembly_case", "DEFAULT_ENGINES"]

#: Engines measured by default (the main environment's fastest three families).
DEFAULT_ENGINES = ("pymunk", "mujoco", "dem2d")


def assembly_case() -> Scenario:
    """Five drums under a 1 Hz one-sine pulse at twice their static collapse factor."""
    geo = drum_column(5)
    alpha = math.tan(critical_angle(geo))
    return Scenario("column-5drums-pulse", geo, contact=Contact(friction=1.0),
                    excitation=SinePulse(1.0, 2.0 * alpha * 9.81 / (2 * math.pi) ** 2),
                    duration=2.0, output_rate=200.0)


def _measure(name: str, opts: VerifyOptions) -> dict:
    t0 = time.perf_counter()
    res = run_verification(opts)
    wall = time.perf_counter() - t0
    new = sum(r.cpu_time for lad in res.ladders for r in lad.rungs[1:] if not r.result.reused)
    return {"case": name, "converge": opts.converge, "runs": len(res.results),
            "ladders": len(res.ladders), "run_cpu": res.run_cpu,
            "verdict_cpu": res.verdict_cpu, "new_verdict_cpu": new, "wall": wall,
            "ratio": res.verdict_cpu / res.run_cpu if res.run_cpu else math.nan,
            "lines": res.verdict.lines()}


def run(quick: bool = False, *, engines: tuple[str, ...] = DEFAULT_ENGINES,
        jobs: int = 2) -> tuple[str, dict]:
    """Run the benchmark; its Markdown section and numbers."""
    names = get_suite("paper-single-pulse") if quick else get_suite("paper")
    paper = [get_scenario(n) for n in names]
    ex = ExecutionOptions(jobs=jobs)
    rows = []
    with tempfile.TemporaryDirectory(prefix="rockbench-verdict-") as tmp:
        for case, scenarios, converge in (("paper", paper, "auto"), ("paper", paper, "all"),
                                          ("assembly", [assembly_case()], "auto")):
            db = Path(tmp) / f"{case}-{converge}.db"
            opts = VerifyOptions(scenarios, list(engines), presets=["accurate", "fast"],
                                 converge=converge, db=db, execution=ex,
                                 max_level=2 if quick else 3)
            rows.append({**_measure(case, opts), "pass": "fresh store"})
            rows.append({**_measure(case, opts), "pass": "same store"})
    lines = ["## Cost of a verdict (`python -m benchmarks.verdict_cost`)", "",
             f"Engines {', '.join(engines)} at their accurate and fast presets, {jobs} "
             f"workers; {len(paper)} paper scenarios{' (quick)' if quick else ''}. "
             "Runs = the methods' own runs, which the verdict judges; verdict = the ladders' "
             "further rungs (CPU s).", "",
             "| case | ladders | pass | runs CPU (s) | verdict CPU (s) | run now (s) | "
             "verdict / runs | wall (s) |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['case']} | {r['converge']} ({r['ladders']}) | {r['pass']} | "
                     f"{r['run_cpu']:.3g} | {r['verdict_cpu']:.3g} | {r['new_verdict_cpu']:.3g} "
                     f"| {r['ratio']:.2f}× | {r['wall']:.1f} |")
    lines += ["", "Verdict of the assembly case:", ""]
    lines += [f"- {line}" for line in rows[-1]["lines"]]
    return "\n".join(lines) + "\n", {"rows": rows, "load": load()}


def main() -> None:
    """Print the Markdown section."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--engines", default=",".join(DEFAULT_ENGINES))
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()
    text, _ = run(args.quick, engines=tuple(e for e in args.engines.split(",") if e),
                  jobs=args.jobs)
    print(text)


if __name__ == "__main__":
    main()
