"""Batched worlds against runs one by one (issue 29, item 2).

``python -m benchmarks.batched_runs [--runs N] [--duration S] [--quick]``

An amplitude sweep of the paper's Single #2 block under the 3 Hz sine pulse (``--runs``
amplitudes from 2 to 20 mm: below uplift, rocking, overturning), each run against
Housner's reference. Side by side in this process:

* Newton (``accurate`` and ``fast``) run by run (:meth:`Engine.simulate`), and as
  batches of 8 worlds and of every run at once (:meth:`BatchEngine.simulate_many`);
* the per-run engines of comparable accuracy (pymunk, MuJoCo, Rapier at ``fast``);
* the campaign's path, :func:`rockbench.runner.run_jobs` on 2 workers, batched
  (the default) against ``batch=1``.

Printed: CPU seconds per run and per simulated second (CPU next to wall); over the runs
that stand, as the reference's do, the worst error of the peak rotation and the median
max |θ − θ_ref|/λ (near the overturning threshold the time histories part, so the worst
of that says little); and the outcomes (overturned or not) that differ from Housner's.
Not part of the test run (about 5 CPU minutes at the defaults; Newton's kernels are
compiled first, outside the timings).
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np

from rockbench.analytic import reference
from rockbench.engines import get_engine
from rockbench.engines.batch import simulate_many
from rockbench.errors import EngineUnavailable
from rockbench.evaluation import evaluate_run
from rockbench.runner import ExecutionOptions, Job, run_jobs
from rockbench.scenarios import Scenario, SinePulse, get_scenario
from rockbench.trajectory import Status, Trajectory

__all__ = ["run", "sweep"]


def sweep(n: int, duration: float) -> list[Scenario]:
    """``n`` Single #2 scenarios under 3 Hz pulses of 2–20 mm amplitude."""
    base = get_scenario("single-pulse-3.0hz-8mm").replace(duration=duration)
    return [base.replace(name=f"single2-3hz-{a * 1e3:.2f}mm", excitation=SinePulse(3.0, a))
            for a in np.linspace(2e-3, 20e-3, n)]


def _score(scenarios: list[Scenario], trajs: list[Trajectory], refs: list[Trajectory]
           ) -> tuple[float, float, int]:
    """Over the runs that end as the reference does and stand: the worst peak error and
    the median max |Δθ|/λ; and the outcomes (overturned or not) that differ."""
    peaks, errors, wrong = [0.0], [0.0], 0
    for sc, traj, ref in zip(scenarios, trajs, refs, strict=True):
        over, ref_over = traj.status is Status.OVERTURNED, ref.status is Status.OVERTURNED
        if over != ref_over or traj.status not in (Status.OK, Status.OVERTURNED):
            wrong += 1
        elif not ref_over:
            m = evaluate_run(sc, traj, ref)
            peaks.append(abs(m.peak_error or 0.0))
            errors.append(float(m.max_error or 0.0))
    return max(peaks), float(np.median(errors)), wrong


def _row(label: str, scenarios: list[Scenario], refs: list[Trajectory], go: Any) -> str:
    cpu0, wall0 = time.process_time(), time.perf_counter()
    trajs = go()
    cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
    peak, median, wrong = _score(scenarios, trajs, refs)
    simulated = sum(sc.duration for sc in scenarios)
    n = len(scenarios)
    return (f"| {label} | {cpu / n:.3f} | {wall / n:.3f} | {cpu / simulated:.4f} | "
            f"{peak:.2%} | {median:.3f} | {wrong}/{n} |")


def run(quick: bool = False, runs: int = 32, duration: float = 3.0) -> tuple[str, dict]:
    """The Markdown table (and nothing else as data)."""
    if quick:
        runs, duration = 8, 2.0
    try:
        newton = get_engine("newton")
    except EngineUnavailable as exc:  # the extra is not installed here: say so
        return f"Not measured: {exc}\n", {}
    scenarios = sweep(runs, duration)
    refs = [reference(sc) for sc in scenarios]
    type(newton).warm_up()  # type: ignore[attr-defined]
    lines = [f"Single #2, 3 Hz sine pulses of 2–20 mm, {runs} runs of {duration:g} s; "
             "CPU and wall seconds per run measured in one process, side by side.", "",
             "| method | CPU s / run | wall s / run | CPU s / simulated s | worst peak "
             "error | median max abs(Δθ)/λ | outcome ≠ Housner |",
             "|---|---|---|---|---|---|---|"]
    for preset in ("accurate", "fast"):
        lines.append(_row(f"newton[{preset}], run by run", scenarios, refs,
                          lambda p=preset: [newton.simulate(sc, p) for sc in scenarios]))
        for size in sorted({8, runs}):
            def batched(p: str = preset, k: int = size) -> list[Trajectory]:
                return [t for b in range(0, runs, k)
                        for t in simulate_many(newton, scenarios[b:b + k], p)]
            lines.append(_row(f"newton[{preset}], batches of {size}", scenarios, refs, batched))
    for name in ("pymunk", "mujoco", "rapier"):
        try:
            eng = get_engine(name)
        except Exception as exc:  # not installed here: say so in the table
            lines.append(f"| {name}[fast] | not installed ({type(exc).__name__}) | | | | | |")
            continue
        lines.append(_row(f"{name}[fast], run by run", scenarios, refs,
                          lambda e=eng: [e.simulate(sc, "fast") for sc in scenarios]))
    lines += ["", "The campaign's path: `run_jobs` on 2 isolated workers (wall time; CPU of "
              "the workers is not in this process).", "",
              "| newton[fast] through run_jobs | wall s | wall s / run |", "|---|---|---|"]
    jobs = [Job(sc, "newton", {"preset": "fast"}) for sc in scenarios]
    for label, batch in (("batched (default)", 0), ("batch=1 (run by run)", 1)):
        start = time.perf_counter()
        run_jobs(jobs, ExecutionOptions(jobs=2, batch=batch))
        wall = time.perf_counter() - start
        lines.append(f"| {label} | {wall:.1f} | {wall / runs:.3f} |")
    return "\n".join(lines) + "\n", {}


def main(argv: list[str] | None = None) -> None:
    """Print the tables (see the module docstring)."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--runs", type=int, default=32)
    p.add_argument("--duration", type=float, default=3.0)
    p.add_argument("--quick", action="store_true")
    args = p.parse_args(argv)
    print(run(args.quick, args.runs, args.duration)[0])


if __name__ == "__main__":
    main()
