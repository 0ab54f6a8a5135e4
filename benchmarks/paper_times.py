"""The paper's timing cases for every engine, and accuracy against speed.

* Timing cases of Giordano et al. (2025): Single #2 under the 5 Hz / 6 mm sine
  pulse (4 s) and sinusoid (10 s); the two-block stack under the 5 Hz / 4 mm
  pulse and sinusoid; every engine at its ``accurate`` preset and the analytic
  reference, next to the paper's run times (Bullet/Vortex on an i7-13700K, 3DEC
  on an i9-12900K).
* Accuracy against speed: B0 free rocking (20 s) and the 5 Hz / 6 mm pulse at
  the ``fast`` and ``accurate`` presets: max |θ − θ_ref| / λ against CPU time
  (the data of ``accuracy_speed.png``).
"""

from __future__ import annotations

import math

from benchmarks import ENGINES, best_of, engine_status, fmt_time, load, warm
from rockbench.analytic import critical_angle, reference
from rockbench.engines import get_engine
from rockbench.metrics import max_error
from rockbench.scenarios import get_scenario

__all__ = ["run", "PAPER_TIMES"]

#: case → (label, paper Bullet/Vortex s, paper DEM s)
PAPER_TIMES = {
    "single-pulse-5.0hz-6mm": ("single, 5 Hz / 6 mm pulse (4 s)", "≈150 s", "1440 s"),
    "single-sine-5.0hz-6mm": ("single, 5 Hz / 6 mm sinusoid (10 s)", "≈53 s", "1560 s"),
    "stack-pulse-5.0hz-4mm": ("stack, 5 Hz / 4 mm pulse (4 s)", "489 s", "7220 s"),
    "stack-sine-5.0hz-4mm": ("stack, 5 Hz / 4 mm sinusoid (10 s)", "358 s", "18055 s"),
}
#: accuracy-vs-speed cases: name → label
ACCURACY_CASES = {"free-b0": "B0 free rocking, 20 s",
                  "single-pulse-5.0hz-6mm": "Single #2, 5 Hz / 6 mm pulse, 4 s"}


def _status(traj) -> str:
    return str(getattr(traj.status, "value", traj.status))


def _simulate(name: str, sc, preset: str):
    if name == "analytic":
        return best_of(lambda: reference(sc), 1)
    return best_of(lambda: get_engine(name).simulate(sc, preset), 1)


def run(quick: bool = False) -> tuple[str, dict]:
    """Markdown section and raw numbers (``accuracy`` feeds the chart)."""
    avail = {n: engine_status(n) for n in ENGINES}
    engines = [n for n in ENGINES if avail[n][0]]
    for n in engines:
        warm(n)
    out: dict = {"paper": [], "accuracy": []}
    refs = {}

    # ---------------------------------------------------------------- paper cases
    cases = list(PAPER_TIMES)
    if quick:
        cases = [c for c in cases if "pulse" in c]
    head = ["| case | paper Bullet / Vortex | paper 3DEC | analytic | "
            + " | ".join(ENGINES) + " |",
            "|---|---|---|---|" + "---|" * len(ENGINES)]
    rows = []
    for case in cases:
        sc = get_scenario(case)
        lam = critical_angle(sc.geometry)
        ref = _simulate("analytic", sc, "")
        refs[case] = ref.result
        label, p_bullet, p_dem = PAPER_TIMES[case]
        cells = []
        for n in ENGINES:
            if not avail[n][0]:
                cells.append("n/a")
                continue
            try:
                r = _simulate(n, sc, "accurate")
            except Exception as exc:
                cells.append(f"failed ({type(exc).__name__})")
                continue
            st = _status(r.result)
            err = max_error(r.result, ref.result, lam) if r.result.t.size else math.nan
            out["paper"].append(dict(case=case, engine=n, cpu=r.cpu, wall=r.wall, status=st,
                                     error=err))
            extra = "" if st == "ok" else f", {st}"
            cells.append(f"{fmt_time(r.cpu)} ({r.wall:.2f} s wall; {err:.3f} λ{extra})")
        out["paper"].append(dict(case=case, engine="analytic", cpu=ref.cpu, wall=ref.wall,
                                 status=_status(ref.result), error=0.0))
        rows.append(f"| {label} | {p_bullet} | {p_dem} | {fmt_time(ref.cpu)} | "
                    + " | ".join(cells) + " |")
    lines = [
        "## 4. The paper's timing cases",
        "",
        "Each engine at its `accurate` preset, 1 kHz output, one run each: CPU time, "
        "(wall time; max |θ − θ_ref| / λ over all blocks against the analytic "
        "reference). The paper's times are wall times on an i7-13700K (Bullet inside "
        "Blender, Vortex) and an i9-12900K (3DEC).",
        "",
        *head, *rows, "",
        f"({load()} at the end of this section; engines unavailable here: "
        f"{', '.join(f'{n} ({avail[n][1]})' for n in ENGINES if not avail[n][0]) or 'none'}.)",
        "",
    ]

    # ---------------------------------------------------------------- accuracy vs speed
    acc_cases = dict(ACCURACY_CASES)
    lines += ["## 5. Accuracy against speed", "",
              "max |θ − θ_ref| / λ and CPU time per preset (the data of "
              "`accuracy_speed.png`).", "",
              "| case | engine | preset | dt | CPU | error / λ | status |",
              "|---|---|---|---|---|---|---|"]
    for case, label in acc_cases.items():
        sc = get_scenario(case)
        if quick and case == "free-b0":
            sc = sc.replace(duration=5.0)
            label = "B0 free rocking, 5 s"
        lam = critical_angle(sc.geometry)
        ref = refs.get(case) or reference(sc)
        ref_t = best_of(lambda sc=sc: reference(sc), 1)
        out["accuracy"].append(dict(case=label, engine="analytic", preset="reference",
                                    cpu=ref_t.cpu, error=0.0, status="ok"))
        for n in engines:
            for preset in ("fast", "accurate"):
                try:
                    r = _simulate(n, sc, preset)
                except Exception as exc:
                    lines.append(f"| {label} | {n} | {preset} | – | – | – | failed "
                                 f"({type(exc).__name__}) |")
                    continue
                st = _status(r.result)
                err = max_error(r.result, ref, lam) if r.result.t.size else math.nan
                dt = r.result.settings.get("effective_timestep", math.nan)
                out["accuracy"].append(dict(case=label, engine=n, preset=preset, cpu=r.cpu,
                                            wall=r.wall, error=err, status=st, dt=dt))
                lines.append(f"| {label} | {n} | {preset} | {dt:.3g} s | {fmt_time(r.cpu)} | "
                             f"{err:.4f} | {st} |")
    lines += ["", f"({load()} at the end of this section.)", ""]
    out["load"] = load()
    return "\n".join(lines) + "\n", out


if __name__ == "__main__":  # pragma: no cover
    import sys

    print(run("--quick" in sys.argv)[0])
