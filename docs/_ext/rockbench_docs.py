"""Sphinx directives that generate the documentation's tables from the code.

``engine-settings NAME``
    An engine's capabilities, knobs (from its ``Settings`` docstring, with
    their defaults and roles), presets and known failures, read from the class
    registered under the entry-point group ``rockbench.engines``: what the engine
    page says about knobs is always the code's.
``cli-help [COMMAND]``
    The ``--help`` text of ``rockbench`` or of one of its commands.
``validation-table``
    Runs a few paper cases on the analytic reference and MuJoCo through
    :func:`rockbench.studies.compare.run_comparison` into a results store in the
    build folder (``docs/_build/validation.db``; runs of the same code are reused),
    then renders, *from the store*, the analytic reference against Housner's closed
    forms and the engine's errors against the reference.

``calibration-table ENGINE``
    Runs a small calibration of the engine (:func:`rockbench.studies.calibration.calibrate`;
    options ``:cases:``, ``:preset:``, ``:levels:``; default the ten free-rocking cases
    from the ``fast`` preset, two rungs each way) into a results store in the build folder
    (``docs/_build/calibration.db``; runs of the same code are reused), then renders its
    table *from the store* (:func:`rockbench.studies.calibration.stored_calibration`), as
    ``rockbench calibrate ENGINE --from-store`` does.

The directives write reStructuredText and parse it in place, so in a Markdown page
they are used inside an ``{eval-rst}`` block.
"""

from __future__ import annotations

import dataclasses
import inspect
import math
import re
import time
import types
from importlib.metadata import entry_points
from pathlib import Path
from typing import Any

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.application import Sphinx
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective
from sphinx.util.nodes import nested_parse_with_titles

logger = logging.getLogger(__name__)

#: The paper cases of the validation table (cheap: about 10 s of CPU in all).
VALIDATION_CASES = ("free-b1-0.5", "free-b2-0.5", "free-b3-0.99", "single-pulse-3.0hz-8mm",
                    "single-pulse-5.0hz-6mm", "stack-pulse-5.0hz-4mm")
VALIDATION_ENGINES = ("mujoco",)
VALIDATION_PRESETS = ("accurate", "fast")
#: Impacts of free rocking compared with the closed form.
VALIDATION_IMPACTS = 5


def engine_classes() -> dict[str, type]:
    """Engine classes by name, loaded from the entry points without importing their
    libraries (a plugin imports its library only when it runs)."""
    return {ep.name: ep.load() for ep in entry_points(group="rockbench.engines")}


def _cell(text: str) -> list[str]:
    lines = [ln.rstrip() for ln in str(text).strip().splitlines()] or [""]
    return lines


def list_table(header: list[str], rows: list[list[str]], *, widths: str = "auto",
               title: str = "") -> list[str]:
    """A reStructuredText ``list-table`` (cells may span several lines)."""
    out = [f".. list-table:: {title}".rstrip(), "   :header-rows: 1", f"   :widths: {widths}",
           "   :class: rockbench-table", ""]
    for row in [header, *rows]:
        for i, cell in enumerate(row):
            lines = _cell(cell)
            lead = "   * - " if i == 0 else "     - "
            out.append(lead + lines[0])
            out.extend("       " + ln if ln else "" for ln in lines[1:])
    out.append("")
    return out


class _RstDirective(SphinxDirective):
    def parse(self, lines: list[str]) -> list[nodes.Node]:
        node = nodes.section() if self.options.get("titles") else nodes.container()
        node.document = self.state.document
        content = StringList(lines, source=f"<{self.name}>")
        nested_parse_with_titles(self.state, content, node)
        return node.children if isinstance(node, nodes.section) else [node]


def _default(field: dataclasses.Field[Any]) -> Any:
    if field.default is not dataclasses.MISSING:
        return field.default
    if field.default_factory is not dataclasses.MISSING:
        return field.default_factory()
    return "(required)"


def _literal(value: Any) -> str:
    return f"``{value!r}``"


class EngineSettingsDirective(_RstDirective):
    """``.. engine-settings:: NAME``: capabilities, knobs, presets, known failures."""

    required_arguments = 1
    has_content = False

    def run(self) -> list[nodes.Node]:
        from numpydoc.docscrape import NumpyDocString

        name = self.arguments[0]
        classes = engine_classes()
        if name not in classes:
            raise self.error(f"no engine {name!r} (engines: {', '.join(sorted(classes))})")
        cls = classes[name]
        self.env.note_dependency(inspect.getfile(cls))
        settings = cls.Settings
        doc = NumpyDocString(inspect.getdoc(settings) or "")
        described = {}
        for section in ("Parameters", "Attributes"):
            for param in doc[section]:
                for knob in (n.strip() for n in param.name.split(",")):
                    described[knob] = "\n".join(param.desc)
        roles = {k: r.value for k, r in dict(cls.knob_roles).items()}
        fields = dataclasses.fields(settings)
        lines: list[str] = []

        cap = cls.capabilities
        req = ", ".join(f"``{m}``" for m in cls.requires) or "nothing beyond rockbench"
        install = (f"``pip install 'rockbench[{cls.extra}]'``" if cls.extra
                   else "ships with rockbench")
        facts = [
            ["dimensions", f"{cap.dimensions}D" + (" (x–z plane)" if cap.dimensions == 2
                                                    else "")],
            ["base motion applied along", ", ".join(cap.base_axes)],
            ["largest column", "any" if cap.max_blocks is None else f"{cap.max_blocks} blocks"],
            ["chamfered blocks", "yes" if cap.chamfer else "no"],
            ["assemblies (any geometry)", "yes" if cap.assemblies else f"no: {cap.no_assemblies}"],
        ]
        if cap.assemblies:
            facts.append(["convex polygonal prisms", "yes" if cap.prisms
                          else f"no: {cap.no_prisms}"])
        facts += [
            ["contact-model family", f"``{cls.contact_model}``" if cls.contact_model
             else "(not declared)"],
            ["preset of the assembly studies", f"``{cls.assembly_preset}``"],
            ["libraries", req],
            ["install", install],
        ]
        lines += list_table(["", ""], facts, widths="30 70")

        rows = []
        for f in fields:
            if f.name.startswith("_"):
                continue
            rows.append([f"``{f.name}``", _literal(_default(f)), roles.get(f.name, ""),
                         described.get(f.name, "")])
        lines += ["**Knobs** (``--set " + name + ".KNOB=VALUE``; defaults are the "
                  "``accurate`` preset's unless a preset below says otherwise):", ""]
        lines += list_table(["knob", "default", "role", "what it does"], rows,
                            widths="18 14 14 54")

        preset_rows = []
        for preset, overrides in cls.presets.items():
            changes = ", ".join(f"``{k} = {v!r}``" for k, v in overrides.items())
            preset_rows.append([f"``{preset}``", changes or "the defaults"])
        lines += ["**Presets** (``--preset NAME``, ``--presets P1,P2``):", ""]
        lines += list_table(["preset", "knobs changed from the defaults"], preset_rows,
                            widths="20 80")
        if cls.known_failures:
            lines += ["**Known failures of the conformance kit** (strict expected failures "
                      "in the tests, with the measured reason):", ""]
            for check, why in cls.known_failures.items():
                lines += [f"- ``{check}``: {why}", ""]
        return self.parse(lines)


class CliHelpDirective(SphinxDirective):
    """``.. cli-help:: [COMMAND]``: the help text of ``rockbench [COMMAND] --help``."""

    optional_arguments = 1
    has_content = False

    def run(self) -> list[nodes.Node]:
        import argparse

        from rockbench.cli import build_parser

        parser = build_parser()
        if self.arguments:
            sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
            command = self.arguments[0]
            if command not in sub.choices:
                raise self.error(f"no command {command!r}")
            parser = sub.choices[command]
        text = parser.format_help()
        block = nodes.literal_block(text, text)
        block["language"] = "text"
        return [block]


def _validation_store(app: Sphinx) -> Path:
    """Run the validation cases once per build into the store (reusing what it holds)."""
    path = Path(app.outdir).parent / "validation.db"
    if getattr(app, "_rockbench_validation", None):
        return path
    from rockbench.runner import ExecutionOptions
    from rockbench.scenarios import get_scenario
    from rockbench.studies.compare import CompareOptions, run_comparison

    start, cpu = time.perf_counter(), time.process_time()
    run_comparison(CompareOptions(
        scenarios=[get_scenario(n) for n in VALIDATION_CASES],
        engines=list(VALIDATION_ENGINES), presets=list(VALIDATION_PRESETS),
        db=path, resume=True, horizon_members=0, suite="docs-validation",
        execution=ExecutionOptions(jobs=2)))
    logger.info("[rockbench] validation runs: %.1f s wall, %.1f s CPU in this process",
                time.perf_counter() - start, time.process_time() - cpu)
    app._rockbench_validation = True  # type: ignore[attr-defined]
    return path


def _fmt(x: float | None, spec: str) -> str:
    return "–" if x is None or (isinstance(x, float) and not math.isfinite(x)) else \
        format(x, spec)


class ValidationTableDirective(_RstDirective):
    """``.. validation-table::``: the validation tables, from the store of this build."""

    has_content = False
    option_spec = {"part": lambda s: s.strip()}

    def run(self) -> list[nodes.Node]:
        from rockbench.analytic import free_impact_times
        from rockbench.scenarios import get_scenario
        from rockbench.store import Store

        part = self.options.get("part", "engines")
        path = _validation_store(self.env.app)
        with Store(path, create=False) as store:
            if part == "closed-forms":
                return self.parse(self._closed_forms(store, get_scenario, free_impact_times))
            records = [r for r in store.runs(kind="compare")
                       if r.scenario in VALIDATION_CASES]
        latest: dict[tuple[str, str], Any] = {}
        for r in records:
            latest[(r.scenario, r.method)] = r
        order = {n: i for i, n in enumerate(VALIDATION_CASES)}
        rows: list[list[str]] = []
        codes: set[str] = set()
        for (sc, method), r in sorted(latest.items(), key=lambda kv: (order[kv[0][0]],
                                                                      kv[0][1] != "analytic",
                                                                      kv[0][1])):
            m = r.metrics
            if m is None:
                continue
            peaks = ", ".join(_fmt(p, ".4f") for p in m.peaks)
            ref = r.engine == "analytic"
            impact = m.impact_time_error
            rows.append([
                f"``{sc}``", f"``{method}``", str(r.status), peaks,
                "reference" if ref else _fmt(m.max_error, ".2e"),
                "exact events" if ref else _fmt(None if impact is None else 100 * impact, ".3f"),
                "reference" if ref else _fmt(None if m.peak_error is None
                                             else 100 * m.peak_error, ".3f"),
                "–" if ref else _fmt(r.cpu_time if r.cpu_time else r.wall_time, ".2f"),
            ])
            codes.add(r.made_by)
        lines = list_table(
            ["scenario", "method", "status", "peak θ/λ per block",
             "max abs(θ − θ_ref)/λ", "impact times, worst error (%)",
             "peak error, worst (%)", "CPU (s)"],
            rows, widths="22 16 9 11 11 11 11 9")
        made = ", ".join(f"``{c}``" for c in sorted(codes))
        return self.parse([f"Runs made by rockbench {made} (``rockbench --version``).", "",
                           *lines])

    def _closed_forms(self, store: Any, get_scenario: Any, free_impact_times: Any) -> list[str]:
        rows = []
        for name in VALIDATION_CASES:
            if not name.startswith("free-"):
                continue
            sc = get_scenario(name)
            ref = store.reference(sc)
            if ref is None or ref.impacts is None:
                continue
            rock = sc.geometry.column.blocks[0].rocking(sc.g)
            eta = sc.contact.eta if sc.contact.eta is not None else rock.eta
            n = min(VALIDATION_IMPACTS, len(ref.impacts))
            exact = free_impact_times(rock.p, rock.lam, sc.theta0, eta, n)
            err = max(abs(a - b) for a, b in zip(ref.impacts[:n], exact, strict=True))
            rows.append([f"``{name}``", f"{rock.lam:.6f}", f"{rock.p:.6f}", f"{eta:.6f}",
                         ", ".join(f"{t:.5f}" for t in exact), f"{err:.1e}"])
        return list_table(
            ["scenario", "λ (rad)", "p (rad/s)", "η", f"first {VALIDATION_IMPACTS} impacts, "
             "closed form (s)", "largest difference of the stored reference (s)"],
            rows, widths="16 10 10 10 38 16")


#: The calibration of the ``calibration-table`` directive (about 33 s of CPU for pymunk).
CALIBRATION_DEFAULTS = {"cases": "free", "preset": "fast", "levels": "2"}


def _calibration_store(app: Sphinx, engine: str, cases: str, preset: str,
                       levels: int) -> Path:
    """Run one calibration once per build into the store (reusing what it holds)."""
    path = Path(app.outdir).parent / "calibration.db"
    done: set[tuple[str, str, str, int]] = getattr(app, "_rockbench_calibrations", set())
    key = (engine, cases, preset, levels)
    if key in done:
        return path
    from rockbench.runner import ExecutionOptions
    from rockbench.studies.calibration import calibrate

    start, cpu = time.perf_counter(), time.process_time()
    cal = calibrate(engine, cases=cases, preset=preset, levels=levels, db=path,
                    execution=ExecutionOptions(jobs=2))
    logger.info("[rockbench] calibration of %s: %d runs, %d reused; %.1f s wall, %.1f s CPU "
                "in this process", engine, cal.ran, cal.reused, time.perf_counter() - start,
                time.process_time() - cpu)
    app._rockbench_calibrations = done | {key}  # type: ignore[attr-defined]
    return path


class CalibrationTableDirective(_RstDirective):
    """``.. calibration-table:: ENGINE``: a calibration's table, from the store of this build."""

    required_arguments = 1
    has_content = False
    option_spec = {name: lambda s: s.strip() for name in CALIBRATION_DEFAULTS}

    def run(self) -> list[nodes.Node]:
        from rockbench.report.calibration_report import calibration_table
        from rockbench.studies.calibration import (
            calibration_cases,
            max_timestep,
            stored_calibration,
        )
        from rockbench.studies.calibration_plan import plan_search

        engine = self.arguments[0]
        opts = {**CALIBRATION_DEFAULTS, **self.options}
        levels = int(opts["levels"])
        path = _calibration_store(self.env.app, engine, opts["cases"], opts["preset"], levels)
        cases = calibration_cases(opts["cases"])
        plan = plan_search(engine, preset=opts["preset"], levels=levels,
                           max_timestep=max_timestep(cases))
        cal = stored_calibration(plan, cases, path)
        table = calibration_table(cal)
        best = cal.cheapest()
        made = ", ".join(f"``{c}``" for c in cal.made_by)
        lines = [f"``rockbench calibrate {engine} --cases {opts['cases']} --preset "
                 f"{opts['preset']} --levels {levels}``, runs made by rockbench {made}. "
                 + table.caption, ""]
        lines += list_table(table.columns, [[c.text for c in row] for row in table.rows])
        for i, note in enumerate(table.notes, 1):
            lines += [f"[{i}] {note}", ""]
        lines += ["No setting meets the tolerances." if best is None else
                  f"Cheapest setting meeting the tolerances: ``{best.setting.label}`` "
                  f"({best.cost:.3g} CPU s per simulated s).", ""]
        return self.parse(lines)


#: Literal and interpreted-text segments of a line (``code``, :role:`text`), left as they are.
_LITERAL = re.compile(r"``.+?``|:[a-z:]+:`[^`]*`|`[^`]*`_?")


def escape_bars(line: str) -> str:
    """Escape the bars of ``|θ|``-style absolute values in a docstring line.

    rockbench's docstrings write absolute values and norms as ``|x|``, which
    reStructuredText would read as substitution references; outside literals and
    roles every unescaped ``|`` becomes ``\\|``. Lines of grid tables and line
    blocks (starting with ``| ``, ``+-`` or ``+=``) are left alone.
    """
    if "|" not in line or line.lstrip().startswith(("| ", "+-", "+=")):
        return line
    out, pos = [], 0
    for m in _LITERAL.finditer(line):
        out.append(re.sub(r"(?<!\\)\|", r"\\|", line[pos:m.start()]))
        out.append(m.group(0))
        pos = m.end()
    out.append(re.sub(r"(?<!\\)\|", r"\\|", line[pos:]))
    return "".join(out)


def _process_docstring(app: Sphinx, what: str, name: str, obj: Any, options: Any,
                       lines: list[str]) -> None:
    lines[:] = [escape_bars(ln) for ln in lines]


def _skip_aliases(app: Sphinx, what: str, name: str, obj: Any, skip: bool,
                  options: Any) -> bool | None:
    # a type alias (``Pose = tuple[float, float, float]``) is not a class autodoc can sign
    if isinstance(obj, types.GenericAlias):
        return True
    return None


def _drop_generated_modules(app: Sphinx) -> list[Any]:
    # viewcode lists the synthetic module of a typing.NamedTuple's generated methods
    # (``namedtuple_Pattern``), which has no source page: a dead link in its index
    modules = getattr(app.env, "_viewcode_modules", {})
    for name in [m for m in modules if m.startswith("namedtuple_")]:
        del modules[name]
    return []


def _always_outdated(app: Sphinx, env: Any, added: set[str], changed: set[str],
                     removed: set[str]) -> list[str]:
    # the validation page and the calibration tables are made from runs of the current
    # code: read their pages on every build
    def generated(doc: str) -> bool:
        try:
            return "calibration-table::" in Path(env.doc2path(doc)).read_text(encoding="utf-8")
        except OSError:
            return False

    return [doc for doc in env.found_docs if doc == "validation" or generated(doc)]


def setup(app: Sphinx) -> dict[str, Any]:
    app.add_directive("engine-settings", EngineSettingsDirective)
    app.add_directive("cli-help", CliHelpDirective)
    app.add_directive("validation-table", ValidationTableDirective)
    app.add_directive("calibration-table", CalibrationTableDirective)
    app.connect("env-get-outdated", _always_outdated)
    # after numpydoc (priority 500), on the reStructuredText it produced
    app.connect("autodoc-process-docstring", _process_docstring, priority=600)
    app.connect("autodoc-skip-member", _skip_aliases)
    app.connect("html-collect-pages", _drop_generated_modules, priority=400)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
