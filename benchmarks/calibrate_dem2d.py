"""Measure the dem2d engine against the Housner reference (and the paper's DEM column).

For each configuration (a preset plus optional knob overrides) it runs the
catalog's free-rocking cases (B0 at 0.5 λ; B1, B2, B3 at 0.2, 0.5, 0.99 λ;
20 s, 1 kHz output, friction 1, restitution 0) and the six Single #2 one-sine
pulses (4 s) and the
paper's eight two-block pulses, and prints Markdown tables: max |θ − θ_ref| / λ (until the
reference comes to rest), relative errors of the first three impact times,
the first post-impact peak against Housner's (a direct measure of the energy
an impact removes), the pulse peak max |θ| / λ against Housner and the paper's
3DEC value (Table 6), and wall times.

Usage::

    python benchmarks/calibrate_dem2d.py [--config accurate --config accurate:subcontacts=10 ...]
                                         [--duration 20] [--only free|pulse]

A configuration is ``preset[:knob=value,knob=value]``. Defaults: ``accurate``,
``accurate:subcontacts=10``, ``fast`` and ``paper``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time

import numpy as np

from rockbench.analytic.housner import single_block_reference
from rockbench.engines.dem2d_engine import Dem2dEngine
from rockbench.metrics import impact_times
from rockbench.scenarios import Block, Contact, Scenario, SinePulse

FREE_BLOCKS = {
    "B0": (1.0, 0.2, 5.0),
    "B1": (0.5, 0.2, 0.75),
    "B2": (0.5, 0.2, 1.0),
    "B3": (0.5, 0.2, 1.25),
}
#: (f Hz, A m) -> the paper's Table 6 max |θ|/λ: (analytical, 3DEC DEM)
PULSES = {
    (3.0, 0.008): (0.183, 0.189), (3.3, 0.006): (0.115, 0.139), (3.3, 0.008): (0.209, 0.187),
    (5.0, 0.004): (0.103, 0.089), (5.0, 0.005): (0.129, 0.107), (5.0, 0.006): (0.115, 0.122),
}
#: (f Hz, A mm) -> the paper's Tables 9/10 max |θ|/λ: (top analytical, top 3DEC,
#: bottom analytical, bottom 3DEC); NaN where the paper prints none
STACK_PULSES = {
    (3.3, 4): (math.nan, 0.320, math.nan, 0.067), (4.0, 3): (0.022, 0.227, 0.022, 0.052),
    (4.0, 4): (0.225, 0.151, 0.114, 0.033), (4.0, 5): (0.572, 0.208, 0.125, 0.056),
    (5.0, 2): (0.022, 0.108, 0.022, 0.031), (5.0, 3): (0.247, 0.125, 0.055, 0.030),
    (5.0, 4): (0.480, 0.221, 0.061, 0.086), (6.5, 2): (0.213, 0.077, 0.026, 0.025),
}
DEFAULT_CONFIGS = ["accurate", "accurate:subcontacts=10", "fast", "paper"]


def free_cases(duration: float = 20.0) -> list[Scenario]:
    """The catalog's free-rocking scenarios."""
    out = []
    for name, (w, d, h) in FREE_BLOCKS.items():
        for tilt in (0.5,) if name == "B0" else (0.2, 0.5, 0.99):
            out.append(Scenario(f"free-{name.lower()}-{tilt}", Block(w, d, h, mass=1.0),
                                Contact(1.0, 0.0), initial_tilt=tilt, duration=duration,
                                output_rate=1000.0))
    return out


def pulse_cases(duration: float = 4.0) -> list[Scenario]:
    """The six Single #2 one-sine pulses."""
    blk = Block(0.17, 0.502, 1.0, density=2670.0)
    return [Scenario(f"single-pulse-{f}hz-{a * 1e3:g}mm", blk, Contact(1.0, 0.0),
                     SinePulse(f, a), duration=duration, output_rate=1000.0)
            for f, a in PULSES]


def run_stacks(cfg: dict) -> None:
    """The paper's eight two-block pulses: peaks of both blocks (normalised by the
    scenario's λ) against the project's two-block analytic model and the paper."""
    from rockbench.analytic import reference
    from rockbench.scenarios.catalog import get_scenario

    print("| stack pulse | status | top dem2d | top analytic | top paper an./3DEC "
          "| bottom dem2d | bottom analytic | bottom paper an./3DEC | wall s |")
    print("|---|---|---|---|---|---|---|---|---|")
    for (f, a), (tan_, tdem, ban, bdem) in STACK_PULSES.items():
        sc = get_scenario(f"stack-pulse-{f:.1f}hz-{a}mm")
        lam = sc.critical_angle
        tr = Dem2dEngine().simulate(sc, cfg)
        pk = np.max(np.abs(tr.theta), axis=0) / lam
        try:
            ref = reference(sc)
            rk = np.max(np.abs(ref.theta), axis=0) / lam
            rs = "" if str(ref.status) == "ok" else f" ({ref.status})"
        except Exception as exc:  # noqa: BLE001 - report, do not stop the benchmark
            rk, rs = (math.nan, math.nan), f" ({type(exc).__name__})"
        print(f"| {sc.name} | {tr.status} | {pk[1]:.3f} | {rk[1]:.3f}{rs} | {tan_:.3f} / "
              f"{tdem:.3f} | {pk[0]:.3f} | {rk[0]:.3f} | {ban:.3f} / {bdem:.3f} | "
              f"{tr.wall_time:.2f} |", flush=True)
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


def run_free(sc: Scenario, cfg: dict) -> dict:
    ref = single_block_reference(sc)
    tr = Dem2dEngine().simulate(sc, cfg)
    lam = sc.critical_angle
    rest = (ref.extra or {}).get("rest_time") or sc.duration
    n = min(tr.t.size, ref.t.size)
    upto = tr.t[:n] <= rest
    err = float(np.max(np.abs(tr.theta[:n, 0] - ref.theta[:n, 0])[upto])) / lam
    t_ref, t_eng = impact_times(ref), impact_times(tr)
    imp = [(t_eng[k] - t_ref[k]) / t_ref[k] * 100 if k < min(t_ref.size, t_eng.size)
           else math.nan for k in range(3)]
    pk = first_peak(tr.t, tr.theta[:, 0], t_eng) / first_peak(ref.t, ref.theta[:, 0], t_ref)
    return dict(case=sc.name, status=str(tr.status), err=err, imp=imp, peak1=pk,
                wall=tr.wall_time, dt=tr.settings["effective_timestep"])


def run_pulse(sc: Scenario, cfg: dict) -> dict:
    ref = single_block_reference(sc)
    tr = Dem2dEngine().simulate(sc, cfg)
    lam = sc.critical_angle
    pk = float(np.max(np.abs(tr.theta[:, 0]))) / lam
    pk_ref = float(np.max(np.abs(ref.theta[:, 0]))) / lam
    return dict(case=sc.name, status=str(tr.status), peak=pk, peak_ref=pk_ref,
                ratio=pk / pk_ref, wall=tr.wall_time, dt=tr.settings["effective_timestep"])


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", action="append", default=None,
                    help="preset[:knob=value,...] (repeatable)")
    ap.add_argument("--duration", type=float, default=20.0)
    ap.add_argument("--only", choices=("free", "pulse", "stack"), default=None)
    args = ap.parse_args(argv)
    print(f"dem2d {Dem2dEngine.version()}\n")
    Dem2dEngine().simulate(free_cases(0.01)[0])  # compile / load the kernels once
    for text in args.config or DEFAULT_CONFIGS:
        cfg = parse_config(text)
        s = Dem2dEngine.settings(cfg["preset"], **{k: v for k, v in cfg.items()
                                                    if k != "preset"})
        print(f"### `{text}`: {s.to_dict()}\n")
        t0 = time.perf_counter()
        if args.only in (None, "free"):
            print("| case | status | max err/λ (to rest) | impact 1 % | impact 2 % | impact 3 % "
                  "| 1st peak / Housner | Δt s | wall s |")
            print("|---|---|---|---|---|---|---|---|---|")
            for sc in free_cases(args.duration):
                r = run_free(sc, cfg)
                print(f"| {r['case']} | {r['status']} | {r['err']:.4f} | {r['imp'][0]:+.3f} | "
                      f"{r['imp'][1]:+.2f} | {r['imp'][2]:+.2f} | {r['peak1']:.3f} | "
                      f"{r['dt']:.3g} | {r['wall']:.2f} |", flush=True)
            print()
        if args.only in (None, "pulse"):
            print("| pulse | status | max θ/λ dem2d | Housner | dem2d/Housner − 1 | "
                  "paper: analytical | paper: 3DEC | Δt s | wall s |")
            print("|---|---|---|---|---|---|---|---|---|")
            for sc, (an, dem) in zip(pulse_cases(), PULSES.values(), strict=True):
                r = run_pulse(sc, cfg)
                print(f"| {r['case']} | {r['status']} | {r['peak']:.4f} | {r['peak_ref']:.4f} "
                      f"| {(r['ratio'] - 1) * 100:+.1f} % | {an:.3f} | {dem:.3f} | "
                      f"{r['dt']:.3g} | {r['wall']:.2f} |", flush=True)
            print()
        if args.only in (None, "stack"):
            run_stacks(cfg)
        print(f"(total {time.perf_counter() - t0:.1f} s)\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
