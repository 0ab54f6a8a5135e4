"""The architecture contract: each layer imports only the layers below it, no import circle.

The layers are declared once, in ``pyproject.toml`` (``[tool.importlinter]``);
``lint-imports`` checks them in CI and this test runs the same check in the test
suite, so a broken contract fails locally before it reaches CI.
"""

from __future__ import annotations

import os

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib
from pathlib import Path

import pytest

importlinter_cli = pytest.importorskip("importlinter.cli")

ROOT = Path(__file__).resolve().parents[1]


def test_layers_and_acyclic_contracts_hold(capsys: pytest.CaptureFixture[str]) -> None:
    cwd = os.getcwd()
    os.chdir(ROOT)
    try:
        code = importlinter_cli.lint_imports(config_filename=str(ROOT / "pyproject.toml"),
                                             no_cache=True, no_logo=True)
    finally:
        os.chdir(cwd)
    out = capsys.readouterr().out
    assert code == 0, out
    assert "2 kept, 0 broken" in out


def test_every_module_is_in_a_layer() -> None:
    """A new top-level module or package must be placed in the layers (else nothing
    checks what it may import)."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    layers = config["tool"]["importlinter"]["contracts"][0]["layers"]
    named = {n.strip() for layer in layers for n in layer.split("|")}
    package = ROOT / "rockbench"
    found = {p.stem for p in package.glob("*.py") if p.stem != "__init__"}
    found |= {p.name for p in package.iterdir()
              if p.is_dir() and (p / "__init__.py").exists()}
    assert found - named == set(), f"modules outside the layers: {sorted(found - named)}"
