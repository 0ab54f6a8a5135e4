"""A missing engine library never crashes the command line (rule 2 of the engine contract).

For each engine's library in turn, a child process runs with that library's
import blocked (a ``sitecustomize`` on PYTHONPATH installs a meta-path finder
that raises ModuleNotFoundError for it, as for a package that is not
installed). ``rockbench engines`` must list the engine as unavailable with the
``pip install`` hint of its extra, and ``run``/``compare --engine all`` must run
every other engine and leave that one out, all with exit status 0 and no
traceback. numba is optional for dem2d: without it dem2d stays available,
interpreted, and says so in its version.

bpy (blender) is blocked in every child besides the library under test: the
bpy wheel here prints NumPy-ABI warnings with tracebacks of its own on import
(caught inside bpy), which would hide a real traceback, and it is slow to import.
"""

import csv
import importlib.metadata
import importlib.util
import json
import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from rockbench.engines import (
    engine_class,
    list_engines,
    register,
    resolve_engine_names,
    unregister,
)
from rockbench.engines.analytic_engine import AnalyticEngine
from rockbench.errors import EngineUnavailable

# a child process per engine library, seconds each (measured with --durations): slow tier
pytestmark = pytest.mark.slow

#: blocked import name -> (engine that needs it, rockbench extra that installs it)
LIBRARIES = {
    "mujoco": ("mujoco", "mujoco"),
    "pybullet": ("bullet", "bullet"),
    "dartpy": ("dart", "dart"),
    "pymunk": ("pymunk", "pymunk"),
    "pydrake": ("drake", "drake"),
    "numba": ("dem2d", "dem"),
    "bpy": ("blender", "blender"),
    "openseespy": ("opensees", "opensees"),
    "compas_lmgc90": ("lmgc90", "lmgc90"),
}
#: blocked in every child (see the module docstring)
ALWAYS_BLOCKED = "bpy"
#: engines that still run without their library (an optional accelerator)
OPTIONAL = {"numba"}

SITECUSTOMIZE = '''\
import os
import sys

_BLOCKED = tuple(os.environ["ROCKBENCH_TEST_BLOCKED"].split(","))


class _Blocker:
    """Meta-path finder that makes one package (and its submodules) impossible to import."""

    @staticmethod
    def find_spec(name, path=None, target=None):
        if name.partition(".")[0] in _BLOCKED:
            raise ModuleNotFoundError(f"No module named {name!r} (blocked by the test)",
                                      name=name)
        return None


sys.meta_path.insert(0, _Blocker())
'''

TINY = '''\
name = "tiny"
duration = 0.2
output_rate = 100.0
[[blocks]]
width = 0.5
depth = 0.2
height = 1.0
mass = 1.0
[initial]
tilt = 0.5
'''


#: Runs each command line of argv[1] (JSON) through the CLI's main(), as the
#: ``rockbench`` script does, in one process (the libraries are imported once),
#: and writes each one's exit status and output to the JSON file argv[2].
DRIVER = '''\
import contextlib, io, json, sys, traceback
from rockbench.cli import main

results = []
for argv in json.loads(sys.argv[1]):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as exc:
            code = exc.code
        except BaseException:
            traceback.print_exc()
            code = None
    results.append({"argv": argv, "code": code, "stdout": out.getvalue(),
                    "stderr": err.getvalue()})
with open(sys.argv[2], "w") as fh:
    json.dump(results, fh)
'''


@dataclass(frozen=True)
class Outcome:
    """Exit status and output of one command line."""

    argv: list[str]
    code: int | None
    stdout: str
    stderr: str


def _env(tmp: Path, blocked: str) -> dict[str, str]:
    """The environment of a child process that cannot import ``blocked`` (nor bpy)."""
    site = tmp / "site"
    site.mkdir(exist_ok=True)
    (site / "sitecustomize.py").write_text(SITECUSTOMIZE)
    path = os.pathsep.join([str(site), *filter(None, [os.environ.get("PYTHONPATH")])])
    return {**os.environ, "PYTHONPATH": path,
            "ROCKBENCH_TEST_BLOCKED": f"{blocked},{ALWAYS_BLOCKED}",
            "PYTHONWARNINGS": "ignore", "MPLBACKEND": "Agg"}


def _blocked_cli(tmp: Path, blocked: str, *commands: list[str]) -> list[Outcome]:
    """Run CLI command lines in a child process (in ``tmp``) that cannot import ``blocked``.

    Each must exit with status 0 and print no traceback (nor may the child, whose
    stderr also holds that of the isolated engine runs).
    """
    results = tmp / "results.json"
    # cwd tmp: any file a command writes by default lands there
    child = subprocess.run([sys.executable, "-c", DRIVER, json.dumps(commands), str(results)],
                           capture_output=True, text=True, timeout=600, env=_env(tmp, blocked),
                           cwd=tmp)
    assert child.returncode == 0 and "Traceback" not in child.stderr, child.stderr
    outcomes = [Outcome(**r) for r in json.loads(results.read_text())]
    for o in outcomes:
        assert o.code == 0 and "Traceback" not in o.stderr, (
            f"rockbench {' '.join(o.argv)} with {blocked} blocked: status {o.code}\n{o.stderr}")
    return outcomes


def _rows(table: str) -> dict[str, list[str]]:
    """The rows of a rich table printed by the CLI: first cell -> cells (wrapped lines joined)."""
    rows: dict[str, list[str]] = {}
    last = None
    for line in table.splitlines():
        if not line.startswith("│"):
            continue
        cells = [c.strip() for c in line.strip("│").split("│")]
        if cells[0]:
            last = cells[0]
            rows[last] = cells
        elif last is not None:  # a wrapped line continues the row above
            rows[last] = [f"{a} {b}".strip() for a, b in zip(rows[last], cells, strict=True)]
    return rows


@pytest.fixture(scope="module")
def registered() -> dict[str, type]:
    """Engine classes under the ``rockbench.engines`` entry points whose module loads.

    Loaded directly from the entry points (a plugin module imports no library),
    independently of the registry under test.
    """
    classes = {}
    for ep in importlib.metadata.entry_points(group="rockbench.engines"):
        try:
            classes[ep.name] = ep.load()
        except ImportError:  # an entry point left by another checkout: unavailable anyway
            continue
    return classes


@pytest.fixture(scope="module")
def installed(registered) -> set[str]:
    """Registered engines whose libraries are installed here (``find_spec``), bpy's excepted."""
    return {name for name, cls in registered.items()
            if ALWAYS_BLOCKED not in cls.requires
            and all(importlib.util.find_spec(m) is not None for m in cls.requires)}


@pytest.mark.parametrize("blocked", list(LIBRARIES))
def test_blocked_library(tmp_path, registered, installed, blocked):
    engine, extra = LIBRARIES[blocked]
    if engine not in registered:
        pytest.skip(f"engine {engine!r} is not registered (or its module is missing) here")
    expected = installed if blocked in OPTIONAL else installed - {engine}
    hint = f"pip install 'rockbench[{extra}]'"

    scenario = tmp_path / "tiny.toml"
    scenario.write_text(TINY)
    out = tmp_path / "report"
    listing, run, _ = _blocked_cli(
        tmp_path, blocked, ["engines"], ["run", str(scenario), "--engine", "all"],
        ["compare", "--scenarios", str(scenario), "--engine", "all", "--presets", "fast",
         "--out", str(out), "--no-db", "--quiet"])

    rows = _rows(listing.stdout)
    assert set(rows) >= installed | {engine}
    if blocked in OPTIONAL:
        assert rows[engine][1] == "yes" and "interpreted" in rows[engine][2], rows[engine]
    else:
        available, version, note = rows[engine][1], rows[engine][2], rows[engine][4]
        assert (available, version) == ("no", ""), rows[engine]
        assert blocked in note and hint in note, note
    assert {n for n, cells in rows.items() if cells[1] == "yes"} == expected

    rows = _rows(run.stdout)
    assert set(rows) == expected
    assert all(rows[n][1] == "ok" for n in expected), rows

    with open(out / "results.csv", newline="") as fh:
        results = list(csv.DictReader(fh))
    assert {r["engine"] for r in results} == expected
    assert all(r["status"] == "ok" for r in results), [(r["engine"], r["status"]) for r in results]


def test_explicitly_named_unavailable_engine_is_one_line_error(tmp_path):
    # the real command line, in a process of its own: status 2 and one line on stderr
    r = subprocess.run([sys.executable, "-m", "rockbench.cli", "run", "free-b0", "--engine",
                        "mujoco"], capture_output=True, text=True, timeout=600,
                       env=_env(tmp_path, "mujoco"), cwd=tmp_path)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1, r.stderr
    assert "mujoco" in lines[0] and "pip install 'rockbench[mujoco]'" in lines[0]


# ------------------------------------------------------------ the registry, in process
class _BrokenVersion(AnalyticEngine):
    """A plugin whose library imports but whose version() fails (e.g. a broken build)."""

    name = "broken-version"
    extra = "mujoco"

    @classmethod
    def version(cls) -> str:
        raise AttributeError("module 'mujoco' has no attribute '__version__'")


class _MissingLibrary(AnalyticEngine):
    """A third-party plugin (no rockbench extra) whose library is not installed."""

    name = "missing-library"
    requires = ("rockbench_no_such_library",)


@pytest.fixture
def broken_plugins():
    for cls in (_BrokenVersion, _MissingLibrary):
        register(cls.name, cls)
    yield
    for cls in (_BrokenVersion, _MissingLibrary):
        unregister(cls.name)


def test_registry_reports_any_failure_as_unavailable(broken_plugins):
    infos = {i.name: i for i in list_engines()}
    bad = infos["broken-version"]
    assert not bad.available and bad.version == "" and bad.dimensions is None
    assert "AttributeError" in bad.reason and "pip install 'rockbench[mujoco]'" in bad.reason
    missing = infos["missing-library"]
    assert not missing.available
    assert "ModuleNotFoundError" in missing.reason
    assert "pip install rockbench_no_such_library" in missing.reason
    assert infos["analytic"].available
    names = resolve_engine_names("all")
    assert "analytic" in names and not {"broken-version", "missing-library"} & set(names)
    for name in ("broken-version", "missing-library"):
        with pytest.raises(EngineUnavailable) as exc:
            resolve_engine_names(f"analytic,{name}")
        assert str(exc.value) == infos[name].reason and "\n" not in str(exc.value)
    with pytest.raises(EngineUnavailable, match="rockbench_no_such_library"):
        engine_class("missing-library")
