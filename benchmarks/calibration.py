"""Shared parts of the ``calibrate_<engine>.py`` scripts.

Every script measures one engine's presets against the project's Housner
reference (``rockbench.analytic.housner.single_block_reference``) on the
catalog's free-rocking cases (B0 at 0.5 λ; B1, B2, B3 at 0.2, 0.5, 0.99 λ;
20 s, 1 kHz output, friction 1, restitution 0) and the six Single #2 one-sine
pulses (4 s), and prints Markdown tables. This module holds the case lists,
the measurements (:func:`measure_free`, :func:`measure_pulse`), the table
writer, the adapter-overhead timing and the command-line helpers; the scripts
keep their engine's options, extra columns and raw loops.
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable, Iterable, Sequence
from operator import itemgetter
from typing import Any

import numpy as np

from rockbench.analytic import critical_angle
from rockbench.analytic.housner import single_block_reference
from rockbench.engines.drive import BaseDrive
from rockbench.metrics import zero_crossings
from rockbench.scenarios import Scenario, get_scenario
from rockbench.scenarios.catalog import FREE_BLOCKS, FREE_TILTS, SINGLE_CASES

#: Catalog names of the free-rocking cases, in table order.
FREE = [f"free-{b}" if b == "b0" else f"free-{b}-{t}" for b in FREE_BLOCKS
        for t in ((0.5,) if b == "b0" else FREE_TILTS)]
#: Catalog names of the Single #2 one-sine pulses, in table order.
PULSES = [f"single-pulse-{f:.1f}hz-{a}mm" for f, a in SINGLE_CASES]

#: A table column: header and the cell text of a result row.
Column = tuple[str, Callable[[dict], str]]


# ---------------------------------------------------------------------- cases
def free_cases(duration: float | None = None) -> list[Scenario]:
    """The catalog's free-rocking scenarios (optionally with another duration, s)."""
    cases = [get_scenario(n) for n in FREE]
    return cases if duration is None else [sc.replace(duration=duration) for sc in cases]


def pulse_cases() -> list[Scenario]:
    """The six Single #2 one-sine pulses of the catalog (4 s)."""
    return [get_scenario(n) for n in PULSES]


def select(cases: Iterable[Scenario], patterns: str) -> list[Scenario]:
    """The cases whose names contain one of the comma-separated substrings (all if none)."""
    keep = [p for p in patterns.split(",") if p]
    return [sc for sc in cases if not keep or any(p in sc.name for p in keep)]


# ---------------------------------------------------------------------- measurements
def _simulate(engine: Any, settings: object, scenario: Scenario) -> tuple[Any, float]:
    c0 = time.process_time()
    tr = engine.simulate(scenario, settings)
    return tr, time.process_time() - c0


def measure_free(engine: Any, settings: object, scenario: Scenario) -> dict:
    """One free-rocking run against Housner.

    Row keys: ``case``, ``status``, ``err`` (max |θ − θ_ref| / λ until the
    reference comes to rest at ``rest`` s), ``err_all`` (over the whole run),
    ``imp`` (relative errors in % of the first three impact times, the engine's
    zero crossings against the reference's impacts; NaN where either has fewer),
    ``wall``, ``cpu`` (s), ``traj`` and ``ref`` (the trajectories).
    """
    ref = single_block_reference(scenario)
    tr, cpu = _simulate(engine, settings, scenario)
    lam = critical_angle(scenario.geometry)
    th = tr.theta[:, 0]
    n = min(th.size, ref.theta.shape[0])
    rest = (ref.extra or {}).get("rest_time") or scenario.duration
    err = np.abs(th[:n] - ref.theta[:n, 0]) / lam
    zc, imp = zero_crossings(tr.t, th), np.asarray(ref.impacts)
    imp_err = [(zc[k] - imp[k]) / imp[k] * 100 if k < min(zc.size, imp.size) else math.nan
               for k in range(3)]
    return dict(case=scenario.name, status=str(tr.status), err=float(np.max(err[tr.t[:n] <= rest])),
                err_all=float(np.max(err)), imp=imp_err, rest=rest, wall=tr.wall_time, cpu=cpu,
                traj=tr, ref=ref)


def measure_pulse(engine: Any, settings: object, scenario: Scenario) -> dict:
    """One sine-pulse run against Housner.

    Row keys: ``case``, ``status``, ``peak`` and ``peak_ref`` (max |θ| / λ),
    ``ratio`` (peak / peak_ref), ``err`` (max |θ − θ_ref| / λ), ``drift`` (where
    the base ended minus where the excitation left it, if the engine records
    ``base_end`` at teardown, else NaN), ``wall``, ``cpu`` (s), ``traj``, ``ref``.
    """
    ref = single_block_reference(scenario)
    tr, cpu = _simulate(engine, settings, scenario)
    lam = critical_angle(scenario.geometry)
    th = tr.theta[:, 0]
    pk = float(np.max(np.abs(th))) / lam
    pk_ref = float(np.max(np.abs(ref.theta[:, 0]))) / lam
    motion = scenario.motion
    drift = (getattr(engine, "base_end", math.nan)
             - float(motion.displacement(motion.end_time)[0]))
    return dict(case=scenario.name, status=str(tr.status), peak=pk, peak_ref=pk_ref,
                ratio=pk / pk_ref if pk_ref > 0 else math.nan,
                err=float(np.max(np.abs(th - ref.theta[: tr.t.size, 0]))) / lam, drift=drift,
                wall=tr.wall_time, cpu=cpu, traj=tr, ref=ref)


# ---------------------------------------------------------------------- tables
def col(header: str, key: str | Callable[[dict], Any], fmt: str = "") -> Column:
    """A column showing ``row[key]`` (or ``key(row)``) formatted with ``fmt``."""
    get = key if callable(key) else itemgetter(key)
    return header, lambda r: format(get(r), fmt)


def impact_cols(fmts: str | Sequence[str], header: str = "impact {} (%)") -> list[Column]:
    """The three impact-time error columns (one format for all, or one each)."""
    fmts = [fmts] * 3 if isinstance(fmts, str) else list(fmts)
    return [col(header.format(k + 1), lambda r, k=k: r["imp"][k], f) for k, f in enumerate(fmts)]


def ratio_col(fmt: str, header: str = "ratio − 1 (%)", suffix: str = "") -> Column:
    """The pulse peak ratio as a deviation in %."""
    return header, lambda r: f"{100 * (r['ratio'] - 1):{fmt}}{suffix}"


#: Columns every table starts with.
CASE = [col("case", "case"), col("status", "status")]
WALL = col("wall (s)", "wall", ".2f")
WALL_S = col("wall s", "wall", ".2f")
CPU = col("CPU (s)", "cpu", ".2f")


def table(cols: Sequence[Column], cases: Iterable[Scenario],
          measure: Callable[[Scenario], dict]) -> list[dict]:
    """Print a Markdown table with one row per case (as soon as it is measured)."""
    print("| " + " | ".join(h for h, _ in cols) + " |")
    print("|" + "---|" * len(cols))
    rows = []
    for sc in cases:
        r = measure(sc)
        rows.append(r)
        print("| " + " | ".join(cell(r) for _, cell in cols) + " |", flush=True)
    return rows


# ---------------------------------------------------------------------- overhead
def build(engine: Any, scenario: Scenario, settings: object) -> float:
    """The plugin's ``_build`` as ``simulate()`` calls it: the base drive set first.

    Returns the time step ``_build`` returns.
    """
    engine.drive = BaseDrive(scenario.motion, scenario.duration)
    return engine._build(scenario, settings)


def hooks_loop(engine: Any, scenario: Scenario, settings: object) -> tuple[float, float, int]:
    """Drive the plugin's hooks like the base class's free-motion loop (build, advance,
    read poses, teardown; no watchdog). Returns (wall s, time step, steps per sample)."""
    n_out = scenario.output_times().size
    t0 = time.perf_counter()
    dt = build(engine, scenario, settings)
    k = max(1, round(1.0 / (scenario.output_rate * dt)))
    out = np.empty((n_out, 1, 7))
    out[0] = engine._read_poses()
    for i in range(1, n_out):
        engine._advance(k)
        out[i] = engine._read_poses()
    engine._teardown()
    return time.perf_counter() - t0, dt, k


def overhead(engine: Any, settings: object, duration: float,
             raw_loop: Callable[[Any, Scenario, Any, float, int], float],
             repeats: int = 3) -> tuple[float, float, float]:
    """Best-of wall times on B0 (1 kHz sampling): ``simulate()``, the plugin's hooks
    alone (:func:`hooks_loop`) and ``raw_loop(engine, scenario, settings, dt, k)``,
    a minimal loop of the engine's own API that returns its wall time."""
    sc = free_cases(duration)[0]
    s = engine.resolve_settings(settings)
    best_sim = min(engine.simulate(sc, s).wall_time for _ in range(repeats))
    best_hooks = best_raw = math.inf
    for _ in range(repeats):
        hooks, dt, k = hooks_loop(engine, sc, s)
        best_hooks = min(best_hooks, hooks)
        best_raw = min(best_raw, raw_loop(engine, sc, s, dt, k))
    return best_sim, best_hooks, best_raw


def print_overhead(label: str, duration: float, times: tuple[float, float, float]) -> None:
    a, h, r = times
    print(f"Overhead on B0 ({duration:g} s, best of 3): raw {label} loop {r:.3f} s; "
          f"plugin hooks {h:.3f} s ({100 * (h / r - 1):+.1f} %); full simulate() "
          f"{a:.3f} s ({100 * (a / r - 1):+.1f} %, includes the base-class watchdog)\n")


# ---------------------------------------------------------------------- command line
def parser(doc: str, *, overhead: bool = True) -> argparse.ArgumentParser:
    """The options every script shares (``--preset`` also spelt ``--presets``)."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--preset", "--presets", dest="preset", default="accurate,fast",
                    help="comma list of presets")
    ap.add_argument("--set", action="append", default=[], metavar="KNOB=VALUE")
    ap.add_argument("--duration", type=float, default=20.0, help="free-rocking duration (s)")
    ap.add_argument("--only", choices=["free", "pulse", "all"], default="all")
    ap.add_argument("--cases", default="", help="comma list of substrings of case names")
    if overhead:
        ap.add_argument("--no-overhead", "--skip-overhead", dest="no_overhead",
                        action="store_true")
    return ap


def overrides(args: argparse.Namespace) -> dict:
    """``--set knob=value`` options as a mapping."""
    return dict(kv.split("=", 1) for kv in args.set)


def run(args: argparse.Namespace, engine: Any, label: str, free_cols: Sequence[Column],
        pulse_cols: Sequence[Column], *, pulse_engine: Any = None,
        free_row: Callable[[dict], dict] | None = None,
        overhead: Callable[[object, float], None] | None = None, total: bool = False) -> int:
    """The usual calibration: per preset, the free-rocking table, the pulse table and
    (``overhead(settings, duration)``, unless ``--no-overhead``) the overhead line.
    ``free_row`` may adjust each free-rocking row before it is printed."""
    ov = overrides(args)
    print(f"{label} {engine.version()}; overrides {ov or 'none'}\n")
    for preset in args.preset.split(","):
        s = engine.settings(preset, **ov)
        print(f"### preset `{preset}`: {s.to_dict()}\n")
        t0 = time.perf_counter()
        if args.only in ("free", "all"):
            def measure(sc: Scenario, s: object = s) -> dict:
                r = measure_free(engine, s, sc)
                return free_row(r) if free_row else r

            table(free_cols, select(free_cases(args.duration), args.cases), measure)
            print()
        if args.only in ("pulse", "all"):
            table(pulse_cols, select(pulse_cases(), args.cases),
                  lambda sc, s=s: measure_pulse(pulse_engine or engine, s, sc))
            print()
        if overhead is not None and not args.no_overhead:
            overhead(s, args.duration)
        if total:
            print(f"(total {time.perf_counter() - t0:.1f} s)\n")
    return 0
