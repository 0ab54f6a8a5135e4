"""Scaling: cost against simulated duration, stack size and worker processes.

* Duration: B0 free rocking for D = 1, 2, 4, 8 s at each engine's ``accurate``
  preset; exponent of the log–log fit of CPU time against D (1 = linear) and
  the fixed (build) cost and cost per simulated second of the linear fit.
* Stacks: N = 1, 2, 4, 8, 16 equal blocks 0.5 × 0.3 × 0.25 m (width × depth ×
  height, 2670 kg/m³), a 5 Hz / 1 mm one-sine pulse that moves the base without
  rocking any of them (peak 0.99 m/s² < g tan λ of the 16-block column,
  1.23 m/s²), 1 s at the ``fast`` preset (the accurate presets of DART and
  Drake would take minutes at N = 16); exponent of CPU time against N.
* Matrix throughput: the same 8 jobs through :func:`rockbench.runner.run_jobs`
  (isolated child processes) with 1 and 2 workers; jobs per second (wall).
"""

from __future__ import annotations

import math

import numpy as np

from benchmarks import ENGINES, best_of, engine_status, interleaved, load, warm
from rockbench.engines import engine_class, get_engine
from rockbench.runner import ExecutionOptions, Job, run_jobs
from rockbench.scenarios import Block, Scenario, SinePulse, get_scenario, stack

__all__ = ["run", "stack_scenario"]

#: Skip larger stacks of an engine once one run takes longer than this (s, CPU).
STACK_BUDGET = 30.0


def stack_scenario(n: int, duration: float = 1.0) -> Scenario:
    """N equal blocks 0.5 × 0.3 × 0.25 m under a small (non-rocking) pulse."""
    blk = Block(width=0.5, depth=0.3, height=0.25, density=2670.0)
    return Scenario(name=f"stack-{n}", geometry=stack((blk,) * n),
                    excitation=SinePulse(frequency=5.0, amplitude=0.001),
                    duration=duration, output_rate=1000.0)


def _exponent(x: list[float], y: list[float]) -> float:
    if len(x) < 2:
        return math.nan
    return float(np.polyfit(np.log(x), np.log(y), 1)[0])


def _fmt_exponent(ex: float) -> str:
    return "–" if not math.isfinite(ex) else f"{ex:.2f}"


def _stack_row(name: str, preset: str, ns: list[int], dur: float) -> tuple[dict, bool]:
    """CPU cost of stacks of N blocks on one engine and preset; True if a run failed."""
    dims = engine_class(name).capabilities.dimensions
    cpu, notes = [], []
    skip = failed = False
    for n in ns:
        if skip:
            cpu.append(math.nan)
            continue
        sc = stack_scenario(n, dur)
        try:
            r = best_of(lambda sc=sc: get_engine(name).simulate(sc, preset), 1)
        except Exception as exc:
            cpu.append(math.nan)
            failed = True
            first = str(exc).split(". ")[0].splitlines()[0] if str(exc) else ""
            notes.append(f"N={n}: {type(exc).__name__} ({first[:70]})")
            continue
        cpu.append(r.cpu)
        if not _ok(r.result):
            failed = True
            notes.append(f"N={n}: {getattr(r.result.status, 'value', r.result.status)}")
        if r.cpu > STACK_BUDGET:
            skip = True
            notes.append(f"N>{n} skipped (> {STACK_BUDGET:g} s)")
    good = [(n, c) for n, c in zip(ns, cpu, strict=True) if math.isfinite(c)]
    ex = _exponent([n for n, _ in good if n >= 2], [c for n, c in good if n >= 2])
    return dict(engine=name, preset=preset, dims=dims, n=ns, cpu=cpu, exponent=ex,
                notes=notes), failed


def _ok(traj) -> bool:
    return str(getattr(traj.status, "value", traj.status)) == "ok"


def run(quick: bool = False, repeat: int | None = None) -> tuple[str, dict]:
    """Markdown section and raw numbers."""
    repeat = repeat or (1 if quick else 2)
    out: dict = {}
    lines = ["## 3. Scaling", ""]

    # ---------------------------------------------------------------- duration
    durations = [0.5, 1.0, 2.0] if quick else [1.0, 2.0, 4.0, 8.0]
    lines += [
        f"### Cost against simulated duration (B0 free rocking, accurate preset, best of "
        f"{repeat})",
        "",
        "| engine | " + " | ".join(f"{d:g} s" for d in durations)
        + " | exponent | build + per simulated s |",
        "|---|" + "---|" * len(durations) + "---|---|",
    ]
    dur_rows = []
    for name in ("analytic",) + ENGINES:
        ok, what = engine_status(name)
        if not ok:
            lines.append(f"| {name} | " + " | ".join("–" for _ in durations)
                         + f" | – | {what} |")
            continue
        cpu = []
        if name != "analytic":
            warm(name)
        for d in durations:
            sc = get_scenario("free-b0").replace(duration=d)
            try:
                r = best_of(lambda sc=sc, name=name: get_engine(name).simulate(sc, "accurate"),
                            repeat)
            except Exception as exc:  # an engine in progress may fail: report it
                cpu.append(math.nan)
                print(f"scaling: {name} failed: {exc}")
                continue
            cpu.append(r.cpu)
        good = [(d, c) for d, c in zip(durations, cpu, strict=True) if math.isfinite(c)]
        ex = _exponent([d for d, _ in good], [c for _, c in good])
        fit = np.polyfit([d for d, _ in good], [c for _, c in good], 1) if len(good) > 1 \
            else (math.nan, math.nan)
        dur_rows.append(dict(engine=name, durations=durations, cpu=cpu, exponent=ex,
                             per_s=float(fit[0]), fixed=float(fit[1])))
        lines.append(f"| {name} | " + " | ".join(f"{c:.3f}" for c in cpu)
                     + f" | {ex:.2f} | {max(fit[1], 0.0):.3f} s + {fit[0]:.3f} s/s |")
    out["duration"] = dur_rows
    lines += ["", "CPU seconds per run (build included). Exponent: slope of log cost "
              "against log duration (1 = linear; below 1 when the build cost is not "
              "negligible).", ""]

    # ---------------------------------------------------------------- stacks
    ns = [1, 2, 4, 8] if quick else [1, 2, 4, 8, 16]
    dur = 0.5 if quick else 1.0
    lines += [
        f"### Cost against the number of stacked blocks ({dur:g} s, fast preset, "
        "5 Hz / 1 mm pulse, CPU s; an engine whose fast preset fails gets a second row "
        "at its accurate preset)",
        "",
        "| engine | dims | " + " | ".join(f"N = {n}" for n in ns) + " | exponent | status |",
        "|---|---|" + "---|" * len(ns) + "---|---|",
    ]
    stack_rows = []
    for name in ENGINES:
        ok, what = engine_status(name)
        if not ok:
            lines.append(f"| {name} | – | " + " | ".join("–" for _ in ns) + f" | – | {what} |")
            continue
        # a preset that fails on some stack is a result; the accurate one shows the cost
        # that engine can still reach there
        for preset in ("fast", "accurate"):
            row, failed = _stack_row(name, preset, ns, dur)
            stack_rows.append(row)
            label = name if preset == "fast" else f"{name} (accurate)"
            lines.append(f"| {label} | {row['dims']}D | " + " | ".join(
                "–" if not math.isfinite(c) else f"{c:.3f}" for c in row["cpu"])
                + f" | {_fmt_exponent(row['exponent'])} | {'; '.join(row['notes']) or 'ok'} |")
            if not failed:
                break
    out["stacks"] = stack_rows
    lines += ["", "Exponent: slope of log cost against log N over N ≥ 2 (1 = linear). "
              "Stacks stay at rest: the cost is that of holding N resting contacts on a "
              "moving base. 2D engines are listed for comparison.", ""]

    # ---------------------------------------------------------------- jobs
    engines = [e for e in ("mujoco", "bullet", "dart", "pymunk") if engine_status(e)[0]]
    scen = [get_scenario("single-pulse-5.0hz-6mm"), get_scenario("free-b1-0.5").replace(
        duration=4.0)]
    preset = "fast" if quick else "accurate"
    jobs = [Job(sc, e, {"preset": preset}) for e in engines for sc in scen]
    res = interleaved({j: (lambda j=j: run_jobs(jobs, ExecutionOptions(jobs=j, timeout=300)))
                       for j in (1, 2)}, 1 if quick else 2)
    w1, w2 = res[1].wall, res[2].wall
    ok_all = all(_ok(t) for r in res.values() for t in r.result)
    out["jobs"] = dict(n=len(jobs), wall1=w1, wall2=w2, speedup=w1 / w2)
    lines += [
        f"### Matrix throughput against `--jobs` ({len(jobs)} jobs: {', '.join(engines)} × "
        f"single 5 Hz/6 mm pulse and B1 free 4 s, {preset} preset, isolated child processes, "
        "wall time, best of " + str(1 if quick else 2) + ")",
        "",
        "| --jobs | wall | jobs/s | speed-up |",
        "|---|---|---|---|",
        f"| 1 | {w1:.2f} s | {len(jobs) / w1:.2f} | 1.00 |",
        f"| 2 | {w2:.2f} s | {len(jobs) / w2:.2f} | {w1 / w2:.2f} |",
        "",
        f"All jobs ok: {ok_all}. {load()} at the end of this section (with other work "
        "on the machine, 2 workers cannot reach 2×).",
        "",
    ]
    out["load"] = load()
    return "\n".join(lines) + "\n", out


if __name__ == "__main__":  # pragma: no cover
    import sys

    print(run("--quick" in sys.argv)[0])
