"""Which code made a result: rockbench's release and a hash of the sources that produce it.

A stored run or cached reference is reused only when it was made by the same
code. rockbench's release number changes rarely; the code changes with every
commit (and every local edit). So every result carries a *code version*,
``<release>+<hash>``, where the hash covers the source files of the layers
that compute it (the architecture contract in ``pyproject.toml`` keeps each
layer from importing the ones above it, so nothing else can change it):

``reference``
    the analytic references: neutral types, geometry, scenarios, analytic.
``run``
    an engine run and its metrics: the above plus the engines, the metrics,
    the physical bounds and the runner that isolates runs.
``all``
    every source file (what ``rockbench --version`` names).
"""

from __future__ import annotations

import functools
import hashlib
import subprocess
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

__all__ = ["RELEASE", "code_version", "source_hash", "describe", "SCOPES"]

try:
    RELEASE = version("rockbench")
except PackageNotFoundError:  # running from a source tree without installation
    RELEASE = "0.0.0"

_ROOT = Path(__file__).resolve().parent

#: The package's modules and subpackages each scope covers (all: every one).
SCOPES: dict[str, tuple[str, ...]] = {
    "reference": ("errors", "checks", "tomlfile", "trajectory", "geometry", "scenarios",
                  "analytic"),
}
SCOPES["run"] = SCOPES["reference"] + ("method", "metrics", "bounds", "limits", "engines",
                                       "evaluation", "runner")


def _files(scope: str) -> list[Path]:
    """The source and data files of a scope, in a stable order."""
    if scope == "all":
        parts: tuple[str, ...] = tuple(sorted({p.name.removesuffix(".py")
                                               for p in _ROOT.iterdir()}))
    elif scope in SCOPES:
        parts = SCOPES[scope]
    else:
        raise ValueError(f"unknown code scope {scope!r}; scopes: all, {', '.join(SCOPES)}")
    out: list[Path] = []
    for name in parts:
        module, package = _ROOT / f"{name}.py", _ROOT / name
        if module.is_file():
            out.append(module)
        if package.is_dir():
            out += sorted(p for p in package.rglob("*")
                          if p.is_file() and "__pycache__" not in p.parts
                          and p.suffix not in (".pyc", ".pyo"))
    return out


@functools.cache
def source_hash(scope: str = "all") -> str:
    """SHA-256 (12 hex digits) of the files of ``scope``: paths and contents."""
    h = hashlib.sha256()
    for path in _files(scope):
        h.update(path.relative_to(_ROOT).as_posix().encode())
        h.update(b"\0")
        h.update(path.read_bytes())
        h.update(b"\0")
    return h.hexdigest()[:12]


def code_version(scope: str = "all") -> str:
    """``<release>+<source hash of scope>``: the identity of the code behind a result."""
    return f"{RELEASE}+{source_hash(scope)}"


def describe() -> str:
    """One line naming the exact code: release, source hash, and git commit when known."""
    text = f"rockbench {RELEASE} (code {source_hash('all')}"
    try:
        git = subprocess.run(["git", "-C", str(_ROOT), "describe", "--always", "--dirty",
                              "--abbrev=12"], capture_output=True, text=True, timeout=5,
                             check=False)
    except (OSError, subprocess.SubprocessError):
        git = None
    if git is not None and git.returncode == 0 and git.stdout.strip():
        text += f", git {git.stdout.strip()}"
    return text + ")"
