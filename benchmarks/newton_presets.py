"""Calibration table of the Newton plugin: presets and solvers against the closed forms.

``python -m benchmarks.newton_presets [--suites paper-free,paper-single-pulse | --cases
NAME,...] [--presets accurate,fast,game] [--set k=v[;k=v]] [--per-case] [--warm-up]`` runs each
preset of :class:`~rockbench.engines.newton_engine.NewtonEngine` (and each ``--set``
variant of ``accurate``, several knobs separated by ``;``) on the suites, in this
process, and prints one Markdown row per preset and suite (``--per-case``: per
scenario): the worst max |θ − θ_ref|/λ over the whole run and up to the third impact
(the issue's measure), the worst error of the first impact times, the worst peak
error and the CPU seconds per simulated second. The ``game`` preset (a 60 Hz step)
runs each scenario at 60 output samples per second, the most its step allows.

Warp compiles a solver's kernels the first time a machine runs it (about a minute on
2 cores, cached in ``~/.cache/warp``); ``--warm-up`` compiles or loads them first, so
that the CPU times are the runs' own. Not part of the test run (about 2 CPU minutes
per row of the two default suites at ``accurate``).
"""

from __future__ import annotations

import argparse
from typing import Any

from rockbench.analytic import reference
from rockbench.engines.newton_engine import NewtonEngine, NewtonSettings
from rockbench.evaluation import evaluate_run
from rockbench.scenarios import get_scenario
from rockbench.scenarios.catalog import get_suite

METRICS = ("max_error", "max_error_early", "impact_time_error", "peak_error")


def resolved(settings: dict[str, Any]) -> NewtonSettings:
    """The engine's settings for a preset and overrides."""
    s = NewtonEngine.resolve_settings(settings)
    assert isinstance(s, NewtonSettings)
    return s


def measure(names: list[str], settings: dict[str, Any], output_rate: float | None = None
            ) -> dict[str, Any]:
    """Worst metrics of ``settings`` over the scenarios ``names``, CPU s per simulated s,
    and the statuses that were not the reference's."""
    worst = dict.fromkeys(METRICS, 0.0)
    cpu = simulated = 0.0
    bad: list[str] = []
    for name in names:
        sc = get_scenario(name)
        if output_rate is not None:
            sc = sc.replace(output_rate=output_rate)
        ref = reference(sc)
        traj = NewtonEngine().simulate(sc, settings)
        if traj.status != ref.status:
            bad.append(f"{name}: {traj.status.value} ({traj.message})")
        m = evaluate_run(sc, traj, ref)
        for key in worst:
            value = getattr(m, key)
            if value is not None:
                worst[key] = max(worst[key], abs(value))
        cpu += traj.cpu_time
        simulated += sc.duration
    return {**worst, "cpu": cpu / simulated, "bad": bad}


def main(argv: list[str] | None = None) -> None:
    """Print the table (see the module docstring)."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--suites", default="paper-free,paper-single-pulse")
    p.add_argument("--cases", default="", help="scenario names instead of the suites")
    p.add_argument("--presets", default="accurate,fast,game")
    p.add_argument("--per-case", action="store_true", help="a row per scenario")
    p.add_argument("--warm-up", action="store_true", help="compile the kernels first")
    p.add_argument("--set", action="append", default=[], metavar="KNOB=VALUE[;KNOB=VALUE]",
                   help="an extra row: accurate with these knobs changed (repeatable)")
    args = p.parse_args(argv)
    rows: list[tuple[str, dict[str, Any]]] = [(n, {"preset": n})
                                              for n in args.presets.split(",") if n]
    for item in args.set:
        knobs = dict(kv.partition("=")[::2] for kv in item.split(";"))
        rows.append((f"accurate, {item}", {"preset": "accurate", **knobs}))
    if args.warm_up:
        NewtonEngine.warm_up(sorted({resolved(s).solver for _, s in rows}))
    print("| preset | suite or case | max abs(θ − θ_ref)/λ | up to 3rd impact | impact times "
          "| peak | CPU s / s |")
    print("|---|---|---|---|---|---|---|")
    for label, settings in rows:
        # a step longer than the catalog's 1 ms output interval (game): 60 samples per s
        rate = 60.0 if resolved(settings).timestep > 1e-3 else None
        suites = [(c, [c]) for c in args.cases.split(",")] if args.cases else \
            [(suite, list(get_suite(suite))) for suite in args.suites.split(",")]
        for suite, members in suites:
            groups = [[n] for n in members] if args.per_case else [members]
            for names in groups:
                r = measure(names, settings, rate)
                print(f"| {label} | {names[0] if args.per_case else suite} | "
                      f"{r['max_error']:.4f} | {r['max_error_early']:.4f} | "
                      f"{100 * r['impact_time_error']:.2f} % | "
                      f"{100 * r['peak_error']:.2f} % | {r['cpu']:.3f} |", flush=True)
                for line in r["bad"]:
                    print(f"<!-- {label}: {line} -->", flush=True)


if __name__ == "__main__":
    main()
