"""Calibration table of one engine plugin: its presets against the closed forms.

``python -m benchmarks.engine_presets ENGINE [--suites paper-free,paper-single-pulse |
--cases NAME,...] [--presets accurate,fast,game] [--base PRESET] [--set k=v[;k=v]]
[--per-case] [--duration S] [--warm-up]`` runs each preset of the engine (the presets it
has among ``--presets``, and each ``--set`` variant of the ``--base`` preset, several knobs
separated by ``;``) on the suites, in this process, and prints one Markdown row per
preset and suite (``--per-case``: per scenario): the worst max |θ − θ_ref|/λ over the
whole run and up to the third impact, the worst error of the first impact times, the
worst peak error and the CPU seconds per simulated second; runs whose status is not the
reference's are listed under their row. A preset whose step is longer than a scenario's
output interval (a ``game`` preset at 60 Hz) runs the scenario sampled once per step.
``--duration`` shortens every scenario; ``--warm-up`` calls the engine's ``warm_up()``
where it has one (Newton compiles its kernels on first use), so that the CPU times are
the runs' own. Not part of the test run (one to three CPU minutes per row of the two
default suites, depending on the engine).
"""

from __future__ import annotations

import argparse
from typing import Any

from rockbench.analytic import reference
from rockbench.engines import engine_class, get_engine
from rockbench.evaluation import evaluate_run
from rockbench.method import Method
from rockbench.scenarios import get_scenario
from rockbench.scenarios.catalog import get_suite
from rockbench.studies.restitution import sampled_for

__all__ = ["measure", "main"]

METRICS = ("max_error", "max_error_early", "impact_time_error", "peak_error")


def measure(engine: str, names: list[str], settings: dict[str, Any],
            duration: float | None = None) -> dict[str, Any]:
    """Worst metrics of ``engine`` with ``settings`` over the scenarios ``names``, its CPU s
    per simulated s, and the runs whose status was not the reference's."""
    worst = dict.fromkeys(METRICS, 0.0)
    cpu = simulated = 0.0
    bad: list[str] = []
    eng = get_engine(engine)
    method = Method.of(engine, settings)
    for name in names:
        sc = sampled_for(get_scenario(name), method)
        if duration is not None:
            sc = sc.replace(duration=min(duration, sc.duration))
        ref = reference(sc)
        traj = eng.simulate(sc, settings)
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
    p.add_argument("engine", help="a registered engine name, e.g. rapier")
    p.add_argument("--suites", default="paper-free,paper-single-pulse")
    p.add_argument("--cases", default="", help="scenario names instead of the suites")
    p.add_argument("--presets", default="accurate,fast,game")
    p.add_argument("--base", default="accurate", help="the preset --set rows change")
    p.add_argument("--set", action="append", default=[], metavar="KNOB=VALUE[;KNOB=VALUE]",
                   help="an extra row: the base preset with these knobs changed (repeatable)")
    p.add_argument("--per-case", action="store_true", help="a row per scenario")
    p.add_argument("--duration", type=float, default=None, help="cut every scenario (s)")
    p.add_argument("--warm-up", action="store_true", help="the engine's warm_up() first")
    args = p.parse_args(argv)
    cls = engine_class(args.engine)
    rows: list[tuple[str, dict[str, Any]]] = [
        (n, {"preset": n}) for n in args.presets.split(",") if n in cls.presets]
    for item in args.set:
        knobs = dict(kv.partition("=")[::2] for kv in item.split(";"))
        rows.append((f"{args.base}, {item}", {"preset": args.base, **knobs}))
    warm_up = getattr(cls, "warm_up", None)
    if args.warm_up and warm_up is not None:
        warm_up()
    suites = ([(c, [c]) for c in args.cases.split(",")] if args.cases else
              [(suite, list(get_suite(suite))) for suite in args.suites.split(",")])
    print(f"{args.engine} {cls.version()}\n")
    print("| preset | suite or case | max abs(θ − θ_ref)/λ | up to 3rd impact | impact times "
          "| peak | CPU s / s |")
    print("|---|---|---|---|---|---|---|")
    for label, settings in rows:
        for suite, members in suites:
            for names in ([[n] for n in members] if args.per_case else [members]):
                r = measure(args.engine, names, settings, args.duration)
                print(f"| {label} | {names[0] if args.per_case else suite} | "
                      f"{r['max_error']:.4f} | {r['max_error_early']:.4f} | "
                      f"{100 * r['impact_time_error']:.2f} % | "
                      f"{100 * r['peak_error']:.2f} % | {r['cpu']:.3f} |", flush=True)
                for line in r["bad"]:
                    print(f"<!-- {label}: {line} -->", flush=True)


if __name__ == "__main__":
    main()
