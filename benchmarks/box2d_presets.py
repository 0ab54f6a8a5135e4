"""Calibration table of the Box2D plugin: every preset against the closed forms.

``python -m benchmarks.box2d_presets [--suites paper-free,paper-single-pulse] [--set k=v]
[--per-case]`` runs each preset of :class:`~rockbench.engines.box2d_engine.Box2dEngine` (and
any ``--set`` variant of ``accurate``, e.g. ``--set contact_hertz=1000`` or
``--set "timestep=2e-4;substeps=16"``) on the suites, in this process, and prints one
Markdown row per preset and suite (``--per-case``: per scenario): the worst max
|θ − θ_ref|/λ, the worst error of the first impact times, the worst peak error and the CPU
seconds per simulated second. The ``game`` preset (a 60 Hz step) runs each scenario at 60
output samples per second, the most its step allows. Not part of the test run (about 20
CPU seconds for the two default suites and the three presets).
"""

from __future__ import annotations

import argparse
from typing import Any

from rockbench.analytic import reference
from rockbench.engines import Engine
from rockbench.engines.box2d_engine import Box2dEngine
from rockbench.evaluation import evaluate_run
from rockbench.scenarios import get_scenario
from rockbench.scenarios.catalog import get_suite


def measure(engine: type[Engine], names: list[str], settings: dict[str, Any],
            output_rate: float | None = None) -> dict[str, float]:
    """Worst metrics of ``engine`` with ``settings`` over the scenarios ``names``, and its
    CPU seconds per simulated second."""
    worst = {"max_error": 0.0, "impact_time_error": 0.0, "peak_error": 0.0}
    cpu = simulated = 0.0
    for name in names:
        sc = get_scenario(name)
        if output_rate is not None:
            sc = sc.replace(output_rate=output_rate)
        traj = engine().simulate(sc, settings)
        m = evaluate_run(sc, traj, reference(sc))
        for key in worst:
            value = getattr(m, key)
            if value is not None:
                worst[key] = max(worst[key], abs(value))
        cpu += traj.cpu_time
        simulated += sc.duration
    return {**worst, "cpu": cpu / simulated}


def _variant(text: str) -> dict[str, Any]:
    """``"k=v;k2=v2"`` as a mapping of knob overrides."""
    return dict(item.split("=", 1) for item in text.split(";") if item)


def main(argv: list[str] | None = None) -> None:
    """Print the table (see the module docstring)."""
    p = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    p.add_argument("--suites", default="paper-free,paper-single-pulse")
    p.add_argument("--presets", default="accurate,fast,game")
    p.add_argument("--per-case", action="store_true", help="a row per scenario")
    p.add_argument("--set", action="append", default=[], metavar="KNOB=VALUE[;...]",
                   help="an extra row: accurate with these knobs changed (repeatable)")
    args = p.parse_args(argv)
    rows: list[tuple[str, dict[str, Any]]] = [(n, {"preset": n})
                                              for n in args.presets.split(",") if n]
    rows += [(f"accurate, {item}", {"preset": "accurate", **_variant(item)})
             for item in args.set]
    print("| preset | suite or case | max abs(θ − θ_ref)/λ | impact times | peak | CPU s / s |")
    print("|---|---|---|---|---|---|")
    for label, settings in rows:
        rate = 60.0 if settings.get("preset") == "game" else None
        for suite in args.suites.split(","):
            groups = [[n] for n in get_suite(suite)] if args.per_case else [get_suite(suite)]
            for names in groups:
                r = measure(Box2dEngine, names, settings, rate)
                print(f"| {label} | {names[0] if args.per_case else suite} | "
                      f"{r['max_error']:.4f} | "
                      f"{100 * r['impact_time_error']:.2f} % | "
                      f"{100 * r['peak_error']:.2f} % | {r['cpu']:.2g} |", flush=True)


if __name__ == "__main__":
    main()
