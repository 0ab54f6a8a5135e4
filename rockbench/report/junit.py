"""JUnit XML of a matrix: one ``testsuite`` per engine, one ``testcase`` per scenario."""

from __future__ import annotations

import os
import tempfile
import xml.etree.ElementTree as ET
from datetime import datetime, timezone
from pathlib import Path

from rockbench.evaluation import NUMERIC_METRICS
from rockbench.studies.matrix import FAIL, PASS, REGRESSION, SKIP, Cell, MatrixResult

__all__ = ["write_junit"]


def _properties(case: ET.Element, cell: Cell) -> None:
    props = ET.SubElement(case, "properties")
    ET.SubElement(props, "property", name="status", value=cell.status.value)
    m = cell.metrics
    if m.reference_status is not None:
        ET.SubElement(props, "property", name="reference_status",
                      value=m.reference_status.value)
    for name in sorted(NUMERIC_METRICS):
        v = m.value(name)
        if v is not None:
            ET.SubElement(props, "property", name=name, value=repr(v))


def write_junit(result: MatrixResult, path: str | Path) -> Path:
    """Write JUnit XML (atomically: write, then rename).

    Failed and regressed cells carry a ``failure`` element (type ``tolerance``
    or ``regression``), unsupported ones a ``skipped`` element; the scalar
    metrics go to ``properties`` and the run's wall time to ``time``.
    """
    path = Path(path)
    root = ET.Element("testsuites", name=f"rockbench matrix {result.suite}".strip())
    totals = {"tests": 0, "failures": 0, "errors": 0, "skipped": 0}
    stamp = datetime.now(timezone.utc).isoformat(timespec="seconds")
    total_time = 0.0
    for engine in result.engines:
        cells = [result.cells[(s, engine)] for s in result.scenarios
                 if (s, engine) in result.cells]
        n_fail = sum(c.outcome in (FAIL, REGRESSION) for c in cells)
        n_skip = sum(c.outcome == SKIP for c in cells)
        t_suite = sum(c.metrics.wall_time for c in cells)
        name = f"rockbench.{result.suite or 'matrix'}.{engine}"
        suite_el = ET.SubElement(root, "testsuite", name=name, tests=str(len(cells)),
                                 failures=str(n_fail), errors="0", skipped=str(n_skip),
                                 time=f"{t_suite:.3f}", timestamp=stamp)
        for c in cells:
            case = ET.SubElement(suite_el, "testcase", name=c.scenario, classname=name,
                                 time=f"{c.metrics.wall_time:.3f}")
            _properties(case, c)
            if c.outcome in (FAIL, REGRESSION):
                kind = "tolerance" if c.outcome == FAIL else "regression"
                fail = ET.SubElement(case, "failure", type=kind, message="; ".join(c.reasons))
                fail.text = "\n".join(c.reasons + ([f"message: {c.message}"]
                                                   if c.message else []))
            elif c.outcome == SKIP:
                ET.SubElement(case, "skipped", message="; ".join(c.reasons))
            if c.message and c.outcome == PASS:
                ET.SubElement(case, "system-out").text = c.message
        totals["tests"] += len(cells)
        totals["failures"] += n_fail
        totals["skipped"] += n_skip
        total_time += t_suite
    for k, v in totals.items():
        root.set(k, str(v))
    root.set("time", f"{total_time:.3f}")
    ET.indent(root)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            ET.ElementTree(root).write(fh, encoding="utf-8", xml_declaration=True)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path
