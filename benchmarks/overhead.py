"""Adapter overhead: ``Engine.simulate`` against the engine's minimal raw loop.

For every engine with a raw loop (:mod:`benchmarks.raw_loops`), on B0 free
rocking and on a forced single block (Single #2 under the 5 Hz / 6 mm
sinusoid, driven for the whole run), at the ``accurate`` preset, this times
side by side, interleaved, best of N (N ≥ 7 and enough rounds to fill
``MIN_TIME`` seconds, so that a few-millisecond case gets hundreds):

* ``simulate()``: the plugin through the shared template loop;
* the raw loop (same ``_build``, same dt, same base values, same output sampling).

(The MuJoCo, pybullet and pymunk plugins now drive the base in a tight
``_advance_driven`` and bind their per-step library calls once, as the
benchmark-only subclasses that used to be defined here proposed.)

The overhead is ``simulate / raw − 1`` on CPU time, the median over rounds of
the paired ratio (:func:`benchmarks.paired_ratio`; the wall time of the minima is
reported too); the trajectories are compared (max |Δθ| / λ; 0 means
bit-identical).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from benchmarks import ENGINES, engine_status, interleaved, load, paired_ratio, warm
from benchmarks.raw_loops import RAW_LOOPS, RAW_VARIANTS, run_raw
from rockbench.analytic import critical_angle
from rockbench.engines import engine_class, get_engine
from rockbench.scenarios import Scenario, get_scenario

__all__ = ["run", "cases"]

#: Overhead goal (fraction).
GOAL = 0.10
#: Seconds of interleaved rounds per case at least (short runs get many repeats).
MIN_TIME = 3.0
#: The engines timed: the benchmarks' list and the field's own tools (issue 16), each
#: skipped with its reason where it is unavailable (blender runs in its own venv only).
OVERHEAD_ENGINES = (*ENGINES, *(e for e in ("opensees", "blender") if e not in ENGINES))
#: What one plugin step is, where it is not one physics step.
STEP_NOTE = {"blender": "a step is one frame ({n} Bullet sub-steps)"}


# ---------------------------------------------------------------------- cases
def cases(quick: bool) -> list[tuple[str, Scenario]]:
    """(label, scenario) pairs: B0 free rocking and a forced single block."""
    free_d, forced_d = (1.0, 0.5) if quick else (2.0, 1.0)
    return [
        (f"B0 free {free_d:g} s", get_scenario("free-b0").replace(duration=free_d)),
        (f"Single #2 sine 5 Hz/6 mm {forced_d:g} s",
         get_scenario("single-sine-5.0hz-6mm").replace(duration=forced_d)),
    ]


def run(quick: bool = False, repeat: int | None = None) -> tuple[str, dict]:
    """Markdown section and raw numbers."""
    repeat = repeat or (3 if quick else 7)
    rows, data = [], []
    for name in OVERHEAD_ENGINES:
        ok, what = engine_status(name)
        if not ok:
            rows.append(f"| {name} | – | – | – | – | – | – | {what} |")
            continue
        if name not in RAW_LOOPS:
            rows.append(f"| {name} | – | – | – | – | – | – | no raw loop yet |")
            continue
        settings = engine_class(name).settings("accurate")
        warm(name)
        for label, sc in cases(quick):
            lam = critical_angle(sc.geometry)
            fns: dict[str, Any] = {
                "adapter": lambda sc=sc, name=name, st=settings: get_engine(name).simulate(sc, st),
                "raw": lambda sc=sc, name=name, st=settings: run_raw(name, sc, st),
            }
            if name in RAW_VARIANTS:
                vname, vloop = RAW_VARIANTS[name]
                fns["variant"] = lambda sc=sc, name=name, vloop=vloop, st=settings: run_raw(
                    name, sc, st, loop=vloop)
            try:
                res = interleaved(fns, repeat, min_time=MIN_TIME if not quick else 1.0)
            except Exception as exc:  # an engine in progress may fail: report it
                rows.append(f"| {name} | {label} | – | – | – | – | – | failed: "
                            f"{type(exc).__name__}: {str(exc)[:80]} |")
                continue
            traj = res["adapter"].result
            th_raw = res["raw"].result
            notes = []
            if name in STEP_NOTE:
                notes.append(STEP_NOTE[name].format(n=getattr(settings, "substeps_per_frame", 1)))
            if traj.status != "ok" and str(traj.status) != "Status.OK":
                notes.append(f"status {traj.status}")
            n = min(traj.theta.shape[0], th_raw.shape[0])
            diff = float(np.max(np.abs(traj.theta[:n] - th_raw[:n]))) / lam if n else math.nan
            a, r = res["adapter"], res["raw"]
            ovh = paired_ratio(a, r) - 1.0
            ovh_w = a.wall / r.wall - 1.0
            steps = round(sc.duration / traj.settings["effective_timestep"])
            entry = dict(engine=name, case=label, steps=steps, runs=a.n, adapter_cpu=a.cpu,
                         raw_cpu=r.cpu, adapter_wall=a.wall, raw_wall=r.wall,
                         overhead=ovh, overhead_wall=ovh_w, diff=diff)
            if "variant" in res:
                v = res["variant"]
                vd = float(np.max(np.abs(v.result - th_raw))) / lam
                notes.append(f"raw {RAW_VARIANTS[name][0]}: {1e6 * v.cpu / steps:.2f} µs/step "
                             f"(Δθ {vd:.0e} λ)")
            data.append(entry)
            verdict = "✓" if ovh <= GOAL else "✗"
            rows.append(
                f"| {name} | {label} | {steps} | {a.n} | {1e6 * a.cpu / steps:.2f} | "
                f"{1e6 * r.cpu / steps:.2f} | **{100 * ovh:+.0f} %** {verdict} "
                f"(wall {100 * ovh_w:+.0f} %) | Δθ {diff:.0e} λ"
                f"{'; ' + '; '.join(notes) if notes else ''} |")
    head = [
        "## 1. Adapter overhead (`simulate()` vs a minimal raw loop)",
        "",
        f"Accurate preset of each engine, 1 kHz output, best of the interleaved runs (at "
        f"least {repeat}, and enough for {MIN_TIME:g} s per case: the runs column), "
        f"{load()} at the end of this section. Times are CPU µs per physics step "
        "(build included, the same for both; best run); overhead = simulate / raw − 1 on CPU "
        f"time, the median of the rounds' paired ratios (goal ≤ {100 * GOAL:.0f} %). "
        "Δθ: max |θ_simulate − θ_raw| / λ (0: bit-identical).",
        "",
        "| engine | case | steps | runs | simulate µs/step | raw µs/step | overhead | notes |",
        "|---|---|---|---|---|---|---|---|",
    ]
    return "\n".join(head + rows) + "\n", {"rows": data, "load": load()}


if __name__ == "__main__":  # pragma: no cover
    import sys

    print(run("--quick" in sys.argv)[0])
