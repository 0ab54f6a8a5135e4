"""Study overhead of the runner: warm workers against a fresh process per run (issue 19).

The overhead of a study is ``(wall × jobs) / (sum of the runs' own CPU time) − 1``:
the share of the workers' time not spent inside ``Engine.simulate`` (process
start-up, the engine's import, pickling, the parent's bookkeeping, idle
workers at the tail). On a shared machine the wall time also holds other
people's work, so the same ratio is given on CPU time too: the CPU of this
process and of its (reaped) worker processes (``getrusage``) over the runs'
own CPU time, minus 1.

Two studies, each run with warm workers (``ExecutionOptions()``, the default)
and with a fresh process per run (``warm=False``, the runner before issue 19),
interleaved (fresh, warm, fresh, warm, ...), ``--jobs 2``:

* the paper comparison, ``compare --suite paper --engine mujoco,bullet,dart,pymunk
  --presets accurate,fast``, as :func:`rockbench.studies.compare.run_comparison`
  (the engine runs, the analytic references and the predictability ensembles
  of 8 perturbed analytic runs per scenario that a comparison also runs, their
  metrics), and the trajectory files the report writes
  (:func:`rockbench.report.compare_report.write_trajectories`; not the rest of
  the report rendering), on every second
  scenario of each paper group (the whole suite takes five minutes per
  variant on an idle machine); the runs' CPU time is summed over every run the
  study dispatches;
* 1000 analytic runs: the two-block stack under the 4 Hz pulse for 2 s at
  1000 pulse amplitudes (40 ms of CPU each), one :func:`~rockbench.runner.run_jobs`.
"""

from __future__ import annotations

import dataclasses
import importlib
import resource
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

import rockbench.runner as runner
from benchmarks import engine_status, load
from rockbench.report.compare_report import write_trajectories
from rockbench.runner import ExecutionOptions, Job, run_jobs
from rockbench.scenarios import Scenario, get_scenario, get_suite
from rockbench.studies.compare import CompareOptions, run_comparison
from rockbench.trajectory import Trajectory

__all__ = ["run", "paper_scenarios", "analytic_jobs", "Measured", "GOAL"]

#: Overhead goal (fraction).
GOAL = 0.10
#: Engines and presets of the paper comparison.
ENGINES = ("mujoco", "bullet", "dart", "pymunk")
PRESETS = ["accurate", "fast"]
GROUPS = ("paper-free", "paper-single-pulse", "paper-single-sine", "paper-stack-pulse",
          "paper-stack-sine")
JOBS = 2


@dataclasses.dataclass(frozen=True)
class Measured:
    """One study run: wall and CPU (this process and its workers) against the runs' CPU."""

    variant: str
    runs: int
    wall: float
    cpu: float
    run_cpu: float

    @property
    def overhead_wall(self) -> float:
        """(wall × jobs) / (sum of run CPU) − 1."""
        return self.wall * JOBS / self.run_cpu - 1.0

    @property
    def overhead_cpu(self) -> float:
        """(CPU of the study's processes) / (sum of run CPU) − 1."""
        return self.cpu / self.run_cpu - 1.0


def _cpu() -> float:
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def _measure(variant: str, study: Callable[[ExecutionOptions], list[float]]) -> Measured:
    ex = ExecutionOptions(jobs=JOBS, warm=variant == "warm")
    c0, w0 = _cpu(), time.perf_counter()
    cpus = study(ex)
    wall, cpu = time.perf_counter() - w0, _cpu() - c0
    return Measured(variant, len(cpus), wall, cpu, float(sum(cpus)))


def paper_scenarios(stride: int) -> list[Scenario]:
    """Every ``stride``-th scenario of each paper group (all of them for stride 1)."""
    return [get_scenario(n) for g in GROUPS for n in get_suite(g)[::stride]]


@contextmanager
def _every_run() -> Iterator[list[float]]:
    """The CPU times of every run dispatched meanwhile (engine runs, references and the
    predictability ensembles a comparison runs too), as they pass the dispatcher."""
    cpus: list[float] = []
    plain = runner.map_tasks

    def counting(*args: Any, **kw: Any) -> list[Any]:
        out = plain(*args, **kw)
        cpus.extend(v.cpu_time for v in out if isinstance(v, Trajectory))
        return out

    runner.map_tasks = counting  # run_jobs looks the dispatcher up at each call
    try:
        yield cpus
    finally:
        runner.map_tasks = plain


def _paper_study(scenarios: list[Scenario], engines: list[str]) -> Callable[
        [ExecutionOptions], list[float]]:
    def study(ex: ExecutionOptions) -> list[float]:
        # every variant computes its references and predictability ensembles itself, as
        # the first one did: forget the ones this process keeps from the previous study
        importlib.import_module("rockbench.campaign.references")._MEMO.clear()
        with tempfile.TemporaryDirectory(prefix="rockbench-bench-") as tmp, \
                _every_run() as cpus:
            result = run_comparison(CompareOptions(scenarios=scenarios, engines=engines,
                                                   presets=PRESETS, execution=ex))
            write_trajectories(result, Path(tmp))
        return cpus
    return study


def analytic_jobs(n: int) -> list[Job]:
    """``n`` analytic runs of the two-block stack under pulses of different amplitudes."""
    base = get_scenario("stack-pulse-4.0hz-4mm").replace(duration=2.0)
    amps = np.linspace(0.6, 1.4, n) * base.excitation.amplitude
    return [Job(base.replace(name=f"{base.name}-{i}",
                             excitation=dataclasses.replace(base.excitation, amplitude=float(a))),
                "analytic") for i, a in enumerate(amps)]


def _analytic_study(n: int) -> Callable[[ExecutionOptions], list[float]]:
    jobs = analytic_jobs(n)

    def study(ex: ExecutionOptions) -> list[float]:
        return [t.cpu_time for t in run_jobs(jobs, ex)]
    return study


def _rows(case: str, ms: list[Measured]) -> list[str]:
    out = []
    for variant in ("fresh", "warm"):
        m = [x for x in ms if x.variant == variant]
        best = min(m, key=lambda x: x.wall)
        label = "fresh process per run (before)" if variant == "fresh" else "warm workers (after)"
        out.append(f"| {case} | {label} | {best.runs} | {best.wall:.1f} | {best.cpu:.1f} "
                   f"| {best.run_cpu:.1f} | {100 * best.overhead_wall:+.0f} % "
                   f"| {100 * min(x.overhead_cpu for x in m):+.0f} % | {len(m)} |")
    return out


def run(quick: bool = False, only: str = "") -> tuple[str, dict]:
    """Markdown section and raw numbers (``only``: "paper" or "analytic", else both)."""
    stride, n_analytic, rounds = (4, 200, 1) if quick else (2, 1000, 1)
    engines = [e for e in ENGINES if engine_status(e)[0]]
    scenarios = paper_scenarios(stride)
    studies = {
        f"paper subset ({len(scenarios)} of {len(get_suite('paper'))} scenarios × "
        f"{', '.join(engines)} × {', '.join(PRESETS)})": _paper_study(scenarios, engines),
        f"{n_analytic} analytic runs (stack pulse, 2 s)": _analytic_study(n_analytic),
    }
    if only:
        studies = {k: v for k, v in studies.items() if only in k}
    load0 = load()
    measured: dict[str, list[Measured]] = {case: [] for case in studies}
    for _ in range(rounds):
        for case, study in studies.items():
            for variant in ("fresh", "warm"):  # interleaved, before then after
                measured[case].append(_measure(variant, study))
    lines = [
        "## Study overhead: warm workers (issue 19)",
        "",
        "Overhead = (wall × jobs) / (sum of the runs' own CPU time) − 1, `--jobs 2`; "
        "the CPU column is the CPU of this process and of its worker processes, and the "
        "CPU overhead is that over the runs' CPU time − 1 (steadier on a shared machine: "
        "other work inflates the wall time, not this). 'fresh' is the runner before "
        "issue 19 (`ExecutionOptions(warm=False)`: a new process per run), 'warm' the "
        f"default now. Goal ≤ {100 * GOAL:.0f} %. Best of {rounds} interleaved round(s); "
        f"{load0} at the start, {load()} at the end.",
        "",
        "| study | runner | runs | wall (s) | CPU (s) | runs' CPU (s) | overhead (wall) "
        "| overhead (CPU) | rounds |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for case, ms in measured.items():
        lines += _rows(case, ms)
    lines.append("")
    data = {"rows": [dict(case=case, **dataclasses.asdict(m), overhead_wall=m.overhead_wall,
                          overhead_cpu=m.overhead_cpu)
                     for case, ms in measured.items() for m in ms]}
    return "\n".join(lines), data


if __name__ == "__main__":
    print(run(only=sys.argv[1] if len(sys.argv) > 1 else "")[0])
