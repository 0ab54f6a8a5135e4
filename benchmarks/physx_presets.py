"""Calibration table of the PhysX plugin: every preset against the closed forms.

``python -m benchmarks.physx_presets [--suites paper-free,paper-single-pulse]
[--scenarios free-b2-0.5,...] [--set k=v] [--base PRESET]`` runs each preset of
:class:`~rockbench.engines.physx_engine.PhysxEngine` (and any ``--set`` variant of the
``--base`` preset, ``accurate`` by default) on the suites, in this process, and prints
one Markdown row per preset and suite: the worst max |θ − θ_ref|/λ, the worst error of
the first impact times, the worst peak error and the CPU seconds per simulated second.
The ``game`` preset (a 60 Hz step) runs each scenario at 60 output samples per second,
the most its step allows. Not part of the test run (about 1 CPU minute for the two
default suites).
"""

from __future__ import annotations

import argparse
from typing import Any

from rockbench.analytic import reference
from rockbench.engines.physx_engine import PhysxEngine
from rockbench.evaluation import evaluate_run
from rockbench.scenarios import get_scenario
from rockbench.scenarios.catalog import get_suite


def measure(names: list[str], settings: dict[str, Any], output_rate: float | None = None
            ) -> dict[str, float]:
    """Worst metrics of ``settings`` over the scenarios ``names`` and their CPU s per
    simulated s."""
    worst = {"max_error": 0.0, "impact_time_error": 0.0, "peak_error": 0.0}
    cpu = simulated = 0.0
    for name in names:
        sc = get_scenario(name)
        if output_rate is not None:
            sc = sc.replace(output_rate=output_rate)
        traj = PhysxEngine().simulate(sc, settings)
        if traj.status.value not in ("ok", "overturned"):
            print(f"  {name}: {traj.status.value} ({traj.message})")
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
    p.add_argument("--scenarios", default="",
                   help="a comma list of scenarios, one row each set of settings")
    p.add_argument("--presets", default="accurate,fast,game")
    p.add_argument("--base", default="accurate", help="the preset --set rows change")
    p.add_argument("--set", action="append", default=[], metavar="KNOB=VALUE[;KNOB=VALUE]",
                   help="an extra row: the base preset with these knobs changed (repeatable)")
    args = p.parse_args(argv)
    rows: list[tuple[str, dict[str, Any]]] = [(n, {"preset": n})
                                              for n in args.presets.split(",") if n]
    for item in args.set:
        changes = dict(kv.partition("=")[::2] for kv in item.split(";"))
        rows.append((f"{args.base}, {item}", {"preset": args.base, **changes}))
    groups = ([("scenarios", args.scenarios.split(","))] if args.scenarios else
              [(suite, get_suite(suite)) for suite in args.suites.split(",")])
    print("| preset | suite | max abs(θ − θ_ref)/λ | impact times | peak | CPU s / s |")
    print("|---|---|---|---|---|---|")
    for label, settings in rows:
        rate = 60.0 if settings.get("preset") == "game" else None
        for group, names in groups:
            r = measure(list(names), settings, rate)
            print(f"| {label} | {group} | {r['max_error']:.4f} | "
                  f"{100 * r['impact_time_error']:.2f} % | {100 * r['peak_error']:.2f} % | "
                  f"{r['cpu']:.3f} |", flush=True)


if __name__ == "__main__":
    main()
