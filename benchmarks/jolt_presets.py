"""Calibration table of the Jolt plugin: every preset against the closed forms.

``python -m benchmarks.jolt_presets [--suites paper-free,paper-single-pulse] [--set k=v]
[--per-case] [--duration S]`` runs each preset of
:class:`~rockbench.engines.jolt_engine.JoltEngine` (and any ``--set`` variant of
``accurate``) on the suites, in this process, and prints one Markdown row per preset and
suite (``--per-case``: per scenario): the worst max |θ − θ_ref|/λ, the worst error of the
first impact times, the worst peak error and the CPU seconds per simulated second. The
``game`` preset (culverin's 60 Hz step) runs each scenario at 60 output samples per
second, the most its step allows; ``--duration`` shortens every scenario. Needs culverin
(CPython ≥ 3.12). Not part of the test run (about 3 CPU minutes for the two default
suites).
"""

from __future__ import annotations

import argparse
from typing import Any

from rockbench.analytic import reference
from rockbench.engines.jolt_engine import JoltEngine
from rockbench.evaluation import evaluate_run
from rockbench.scenarios import get_scenario
from rockbench.scenarios.catalog import get_suite


def measure(names: list[str], settings: dict[str, Any], output_rate: float | None = None,
            duration: float | None = None) -> dict[str, float]:
    """Worst metrics of ``settings`` over the scenarios ``names``, CPU s per simulated s."""
    worst = {"max_error": 0.0, "impact_time_error": 0.0, "peak_error": 0.0}
    cpu = simulated = 0.0
    for name in names:
        sc = get_scenario(name)
        if output_rate is not None:
            sc = sc.replace(output_rate=output_rate)
        if duration is not None:
            sc = sc.replace(duration=min(duration, sc.duration))
        traj = JoltEngine().simulate(sc, settings)
        m = evaluate_run(sc, traj, reference(sc))
        for key in worst:
            value = getattr(m, key)
            if value is not None:
                worst[key] = max(worst[key], abs(value))
        cpu += traj.cpu_time
        simulated += sc.duration
    return {**worst, "cpu": cpu / simulated}


def main(argv: list[str] | None = None) -> None:
    """Print the table (see the module docstring)."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--suites", default="paper-free,paper-single-pulse")
    p.add_argument("--presets", default="accurate,fast,game")
    p.add_argument("--per-case", action="store_true", help="a row per scenario")
    p.add_argument("--duration", type=float, default=None, help="cut every scenario (s)")
    p.add_argument("--set", action="append", default=[], metavar="KNOB=VALUE",
                   help="an extra row: accurate with these knobs changed, comma-separated "
                        "(repeatable)")
    args = p.parse_args(argv)
    rows: list[tuple[str, dict[str, Any]]] = [(n, {"preset": n})
                                              for n in args.presets.split(",") if n]
    for item in args.set:
        knobs = dict(kv.partition("=")[::2] for kv in item.split(","))
        rows.append((f"accurate, {item}", {"preset": "accurate", **knobs}))
    print("| preset | suite or case | max abs(θ − θ_ref)/λ | impact times | peak | CPU s / s |")
    print("|---|---|---|---|---|---|")
    for label, settings in rows:
        rate = 60.0 if settings.get("preset") == "game" else None
        for suite in args.suites.split(","):
            groups = [[n] for n in get_suite(suite)] if args.per_case else [get_suite(suite)]
            for names in groups:
                r = measure(names, settings, rate, args.duration)
                print(f"| {label} | {names[0] if args.per_case else suite} | "
                      f"{r['max_error']:.4f} | "
                      f"{100 * r['impact_time_error']:.2f} % | "
                      f"{100 * r['peak_error']:.2f} % | {r['cpu']:.3f} |", flush=True)


if __name__ == "__main__":
    main()
