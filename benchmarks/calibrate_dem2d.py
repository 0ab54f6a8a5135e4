"""Calibrate and measure the dem2d engine against the Housner reference (and the paper's DEM).

For each configuration (a preset plus optional knob overrides) it runs the
catalog's free-rocking cases (B0 at 0.5 λ; B1, B2, B3 at 0.2, 0.5, 0.99 λ;
20 s, 1 kHz output, friction 1, restitution 0), the six Single #2 one-sine
pulses (4 s) and the paper's eight two-block pulses, and prints Markdown
tables: max |θ − θ_ref| / λ (until the reference comes to rest), relative
errors of the first three impact times, the first post-impact peak against
Housner's (a direct measure of the energy an impact removes), the pulse peak
max |θ| / λ against Housner and the paper's 3DEC value (Table 6), the stack
peaks against the two-block model (scored where the reference peak is
≥ 0.02 λ; target 5 %) and the paper's Tables 9/10, and CPU times.

``--only eta`` prints the calibration of the impact damping instead: the
coefficient of restitution e(ζ) of the equivalent single-DOF corner contact
(linear spring and dashpot, separating when the contact force returns to zero)
and the impact ratio η that the engine shows on each free block (one probe
impact from 0.5 λ, :func:`rockbench.engines.dem2d_engine.probe_eta`) against
Housner's, for a range of ζ_c and of sub-contact counts.

Usage::

    python benchmarks/calibrate_dem2d.py [--config accurate --config accurate:impact_zeta=2 ...]
                                         [--duration 20] [--only free|pulse|stack|eta]

A configuration is ``preset[:knob=value,knob=value]``. Defaults: ``accurate``,
``fast`` and ``paper``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time

import numpy as np

from rockbench.engines.dem2d_engine import Dem2dEngine
from rockbench.scenarios import Scenario

try:
    from benchmarks import calibration as cal
except ImportError:  # run as a file: python benchmarks/calibrate_dem2d.py
    import calibration as cal

#: The paper's Table 6 max |θ|/λ per Single #2 pulse: (analytical, 3DEC DEM)
PAPER = dict(zip(cal.PULSES, [(0.183, 0.189), (0.115, 0.139), (0.209, 0.187),
                              (0.103, 0.089), (0.129, 0.107), (0.115, 0.122)], strict=True))
#: (f Hz, A mm) -> the paper's Tables 9/10 max |θ|/λ: (top analytical, top 3DEC,
#: bottom analytical, bottom 3DEC); NaN where the paper prints none
STACK_PULSES = {
    (3.3, 4): (math.nan, 0.320, math.nan, 0.067), (4.0, 3): (0.022, 0.227, 0.022, 0.052),
    (4.0, 4): (0.225, 0.151, 0.114, 0.033), (4.0, 5): (0.572, 0.208, 0.125, 0.056),
    (5.0, 2): (0.022, 0.108, 0.022, 0.031), (5.0, 3): (0.247, 0.125, 0.055, 0.030),
    (5.0, 4): (0.480, 0.221, 0.061, 0.086), (6.5, 2): (0.213, 0.077, 0.026, 0.025),
}
DEFAULT_CONFIGS = ["accurate", "fast", "paper"]
#: Stack peaks below this (in λ) are not scored (near the uplift threshold).
STACK_SCORED = 0.02

TIMESTEP = cal.col("Δt s", lambda r: r["traj"].settings["effective_timestep"], ".3g")
FREE_COLS = [*cal.CASE, cal.col("max err/λ (to rest)", "err", ".4f"),
             *cal.impact_cols(("+.3f", "+.2f", "+.2f"), "impact {} %"),
             cal.col("1st peak / Housner", "peak1", ".3f"), TIMESTEP, cal.CPU]
PULSE_COLS = [cal.col("pulse", "case"), cal.col("status", "status"),
              cal.col("max θ/λ dem2d", "peak", ".4f"), cal.col("Housner", "peak_ref", ".4f"),
              cal.ratio_col("+.1f", "dem2d/Housner − 1", " %"),
              cal.col("paper: analytical", lambda r: PAPER[r["case"]][0], ".3f"),
              cal.col("paper: 3DEC", lambda r: PAPER[r["case"]][1], ".3f"), TIMESTEP,
              cal.CPU]


def run_stacks(cfg: dict) -> None:
    """The paper's eight two-block pulses: peaks of both blocks (normalised by the
    scenario's λ) against the project's two-block analytic model and the paper."""
    from rockbench.analytic import critical_angle, reference
    from rockbench.scenarios.catalog import get_scenario

    print("| stack pulse | status | top dem2d | top analytic | top error | top paper an./3DEC "
          "| bottom dem2d | bottom analytic | bottom error | bottom paper an./3DEC | CPU s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    worst = 0.0
    for (f, a), (tan_, tdem, ban, bdem) in STACK_PULSES.items():
        sc = get_scenario(f"stack-pulse-{f:.1f}hz-{a}mm")
        lam = critical_angle(sc.geometry)
        tr = Dem2dEngine().simulate(sc, cfg)
        pk = np.max(np.abs(tr.theta), axis=0) / lam
        ref = reference(sc)
        rk = np.max(np.abs(ref.theta), axis=0) / lam
        rs = "" if str(ref.status) == "ok" else f" ({ref.status})"
        err = ["–" if r < STACK_SCORED else f"{100 * (p / r - 1):+.1f} %"
               for p, r in zip(pk, rk, strict=True)]
        worst = max([worst] + [abs(p / r - 1) for p, r in zip(pk, rk, strict=True)
                               if r >= STACK_SCORED])
        print(f"| {sc.name} | {tr.status} | {pk[1]:.3f} | {rk[1]:.3f}{rs} | {err[1]} | "
              f"{tan_:.3f} / {tdem:.3f} | {pk[0]:.3f} | {rk[0]:.3f} | {err[0]} | "
              f"{ban:.3f} / {bdem:.3f} | {tr.cpu_time:.2f} |", flush=True)
    print(f"\nworst scored stack peak error: {100 * worst:.1f} % (target 5 %)\n")


def restitution(zeta: float) -> float:
    """e of a linear spring–dashpot contact (ratio ζ) that separates when its force
    k x + c ẋ returns to zero: the equivalent single-DOF corner contact."""
    from scipy.integrate import solve_ivp

    def force(t: float, y: np.ndarray) -> float:
        return y[0] + 2 * zeta * y[1]

    force.terminal, force.direction = True, -1  # type: ignore[attr-defined]
    sol = solve_ivp(lambda t, y: [y[1], -y[0] - 2 * zeta * y[1]], (0, 1e3), [0.0, 1.0],
                    events=force, rtol=1e-10, atol=1e-12, max_step=0.01)
    return float(-sol.y_events[0][0][1]) if sol.t_events[0].size else 0.0


def run_eta(zetas: tuple[float, ...] = (0.0, 0.5, 1.0, 2.0, 3.0, 5.0)) -> None:
    """Impact ratio of the engine's corner contact against ζ_c (and sub-contacts)."""
    from rockbench.engines.dem2d_engine import probe_eta

    print("| ζ_c | e(ζ_c), single-DOF | " + " | ".join(
        f"{n[5:7]} η/η_H − 1" for n in cal.FREE if n.endswith("0.5") or n == "free-b0") + " |")
    cases = [sc for sc in cal.free_cases(2.0) if sc.name.endswith("0.5") or sc.name == "free-b0"]
    print("|---|---|" + "---|" * len(cases))
    for z in zetas:
        s = Dem2dEngine.settings("accurate", impact_zeta=z)
        cells = [f"{100 * (probe_eta(sc, s, 0.5) / sc.blocks[0].rocking().eta - 1):+.3f} %"
                 for sc in cases]
        print(f"| {z:g} | {restitution(z):.4f} | " + " | ".join(cells) + " |", flush=True)
    print()
    print("| sub-contacts, β | " + " | ".join(sc.name for sc in cases) + " |")
    print("|---|" + "---|" * len(cases))
    for n, kw in ((2, {}), (3, {}), (5, {}), (5, {"damping": "contact"}),
                  (5, {"damping": "contact", "beta": 1e-3})):
        s = Dem2dEngine.settings("accurate", subcontacts=n, **kw)
        cells = [f"{probe_eta(sc, s, 0.5):.4f} (H {sc.blocks[0].rocking().eta:.4f})"
                 for sc in cases]
        print(f"| {n}, {kw or 'impact ζ_c = 3'} | " + " | ".join(cells) + " |", flush=True)
    print()


def parse_config(text: str) -> dict:
    """``preset[:knob=value,...]`` -> settings mapping for Engine.simulate."""
    preset, _, rest = text.partition(":")
    out: dict = {"preset": preset or "accurate"}
    for kv in filter(None, rest.split(",")):
        k, _, v = kv.partition("=")
        out[k.strip()] = v.strip()
    return out


def first_peak(t: np.ndarray, th: np.ndarray, imps: np.ndarray) -> float:
    """max |θ| between the first and second impacts (NaN if fewer than two)."""
    if imps.size < 2:
        return math.nan
    m = (t > imps[0]) & (t < imps[1])
    return float(np.max(np.abs(th[m]))) if m.any() else math.nan


def measure_free(engine: Dem2dEngine, cfg: dict, sc: Scenario) -> dict:
    """The common free-rocking row plus the first post-impact peak against Housner's."""
    r = cal.measure_free(engine, cfg, sc)
    tr, ref = r["traj"], r["ref"]
    r["peak1"] = (first_peak(tr.t, tr.theta[:, 0], cal.zero_crossings(tr.t, tr.theta[:, 0]))
                  / first_peak(ref.t, ref.theta[:, 0], np.asarray(ref.impacts)))
    return r


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", action="append", default=None,
                    help="preset[:knob=value,...] (repeatable)")
    ap.add_argument("--duration", type=float, default=20.0)
    ap.add_argument("--only", choices=("free", "pulse", "stack", "eta"), default=None)
    args = ap.parse_args(argv)
    print(f"dem2d {Dem2dEngine.version()}\n")
    engine = Dem2dEngine()
    engine.simulate(cal.free_cases(0.01)[0])  # compile / load the kernels once
    if args.only == "eta":
        run_eta()
        return 0
    for text in args.config or DEFAULT_CONFIGS:
        cfg = parse_config(text)
        s = Dem2dEngine.settings(cfg["preset"], **{k: v for k, v in cfg.items()
                                                    if k != "preset"})
        print(f"### `{text}`: {s.to_dict()}\n")
        t0 = time.perf_counter()
        if args.only in (None, "free"):
            cal.table(FREE_COLS, cal.free_cases(args.duration),
                      lambda sc, cfg=cfg: measure_free(engine, cfg, sc))
            print()
        if args.only in (None, "pulse"):
            cal.table(PULSE_COLS, cal.pulse_cases(),
                      lambda sc, cfg=cfg: cal.measure_pulse(engine, cfg, sc))
            print()
        if args.only in (None, "stack"):
            run_stacks(cfg)
        print(f"(total {time.perf_counter() - t0:.1f} s)\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
