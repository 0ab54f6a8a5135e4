"""Options and helpers shared by every ``rockbench`` command.

Engine selection and settings layers, the results-store options, the
parallelism options and the one place the command line builds an
:class:`~rockbench.runner.ExecutionOptions` (:func:`execution_options`), the
check that an output file can be written before a study runs, and the
progress bar.
"""

from __future__ import annotations

import argparse
import contextlib
import sys
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from rockbench.errors import RockbenchError

__all__ = ["command_line", "selected_engines", "add_engine_arguments", "memory_budget",
           "add_settings_arguments", "engine_settings", "Progress",
           "add_run_arguments", "add_store_arguments", "add_parallel_arguments",
           "add_worker_arguments",
           "check_parallel_arguments", "execution_options", "store_path", "check_output_path"]


# ---------------------------------------------------------------------- engines and settings
def add_engine_arguments(p: argparse.ArgumentParser, default: str = "all") -> None:
    """The engine selection and settings flags shared by every command that runs engines."""
    from rockbench.limits import BUDGET_ENV, DEFAULT_BUDGET_GB

    p.add_argument("--engine", "-e", default=default, metavar="NAMES",
                   help=f"'all' or a comma list of engines (default: {default})")
    add_settings_arguments(p)
    p.add_argument("--max-memory", type=float, default=None, metavar="GB",
                   help=f"memory budget of one run's output samples (default: "
                        f"{DEFAULT_BUDGET_GB:g} GB, or ${BUDGET_ENV}); a scenario needing more "
                        "is refused before it runs")


@contextlib.contextmanager
def memory_budget(args: argparse.Namespace) -> Iterator[None]:
    """While a command runs, pass ``--max-memory`` to this process and every engine child
    (``ROCKBENCH_MAX_MEMORY``); the previous value is restored afterwards.

    Raises
    ------
    RockbenchError
        Not a positive finite number of GB.
    """
    import math
    import os

    from rockbench.limits import BUDGET_ENV

    gb = getattr(args, "max_memory", None)
    if gb is None:
        yield
        return
    if not (math.isfinite(gb) and gb > 0):
        raise RockbenchError(f"--max-memory must be a positive number of GB, got {gb:g}")
    old = os.environ.get(BUDGET_ENV)
    os.environ[BUDGET_ENV] = repr(gb)
    try:
        yield
    finally:
        if old is None:
            os.environ.pop(BUDGET_ENV, None)
        else:
            os.environ[BUDGET_ENV] = old


def command_line(args: argparse.Namespace) -> str:
    """The command as the user gave it (``rockbench`` and the parsed arguments), for reports."""
    import shlex

    return shlex.join(["rockbench", *getattr(args, "argv", sys.argv[1:])])


def selected_engines(spec: str, *, include_analytic: bool = True) -> list[str]:
    """The engines an ``--engine`` value selects; ``all`` says on stderr which it left out.

    Raises
    ------
    UnknownEngine, EngineUnavailable
        A named engine that does not exist or cannot run (one clear line).
    """
    from rockbench.engines import list_engines, resolve_engine_names

    names = resolve_engine_names(spec, include_analytic=include_analytic)
    if "all" in [x.strip().lower() for x in spec.split(",")]:
        missing = [i.name for i in list_engines() if not i.available]
        if missing:
            print(f"rockbench: --engine all leaves out the unavailable {', '.join(missing)} "
                  "(see `rockbench engines`)", file=sys.stderr)
    return names


def add_settings_arguments(p: argparse.ArgumentParser) -> None:
    """``--preset``, ``--settings FILE`` and ``--set``: the layers of :func:`engine_settings`."""
    p.add_argument("--preset", default=None, metavar="NAME",
                   help="settings preset for every engine (e.g. accurate, fast)")
    p.add_argument("--settings", dest="settings_file", default=None, metavar="FILE",
                   help="TOML file of engine knobs ([engine] knob = value), e.g. written by "
                        "`rockbench tune`; it overrides --preset, and --set overrides it")
    p.add_argument("--set", dest="set_options", action="append", default=[],
                   metavar="ENGINE.KNOB=VALUE",
                   help="override an engine knob, e.g. --set bullet.substeps=20 (repeatable)")


def engine_settings(args: argparse.Namespace, engines: Sequence[str]) -> dict[str, dict[str, Any]]:
    """Per-engine settings from ``--preset``, ``--settings FILE`` and ``--set``, validated now.

    See :func:`rockbench.presets.layered_settings` (values typed, later layers win).

    Raises
    ------
    SettingsError
        Bad settings file, unknown knob or preset, or a value of the wrong type.
    UnknownEngine
        ``--set`` names an engine that is not selected or does not exist.
    """
    from rockbench.presets import layered_settings

    return layered_settings(engines, preset=args.preset, settings_file=args.settings_file,
                            set_options=args.set_options)


# ---------------------------------------------------------------------- store and execution
def add_store_arguments(p: argparse.ArgumentParser) -> None:
    """``--db FILE`` and ``--no-db``: where a study records its runs."""
    from rockbench.store import DEFAULT_DB

    p.add_argument("--db", default=DEFAULT_DB, metavar="FILE",
                   help=f"results store (SQLite), appended as each run finishes "
                        f"(default: ./{DEFAULT_DB})")
    p.add_argument("--no-db", action="store_true", help="do not write the results store")


def add_run_arguments(p: argparse.ArgumentParser, *, timeout: float | None = None) -> None:
    """Options of the studies that record runs: the store, parallelism, time limit, executor."""
    add_store_arguments(p)
    add_parallel_arguments(p, timeout=timeout)


def add_parallel_arguments(p: argparse.ArgumentParser, *, timeout: float | None = None,
                           jobs: int | None = None) -> None:
    """``--jobs``, ``--timeout``, ``--executor`` and ``--scheduler``.

    ``timeout`` is the default limit per run (None:
    :data:`rockbench.runner.DEFAULT_TIMEOUT`); ``jobs`` the default workers
    (None: the machine's cores).
    """
    from rockbench.runner import DEFAULT_TIMEOUT, EXECUTORS, default_jobs

    limit = DEFAULT_TIMEOUT if timeout is None else timeout
    n = default_jobs() if jobs is None else jobs
    p.add_argument("--jobs", "-j", type=int, default=n, metavar="N",
                   help=f"parallel runs (default: {n}"
                   + (", the machine's cores)" if jobs is None else ")"))
    p.add_argument("--timeout", type=float, default=limit, metavar="S",
                   help=f"wall-time limit per run in s (default: {limit:g})")
    p.add_argument("--executor", choices=EXECUTORS, default="process",
                   help="local processes (default) or a Dask distributed cluster")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="Dask scheduler address, e.g. tcp://10.0.0.1:8786 (with --executor "
                        "dask; default: a local Dask cluster)")
    add_worker_arguments(p)


def add_worker_arguments(p: argparse.ArgumentParser) -> None:
    """``--no-warm``, ``--worker-memory`` and ``--batch``: how engine workers are kept."""
    p.add_argument("--no-warm", action="store_true",
                   help="a fresh process for every run instead of warm workers that import "
                        "an engine once (a crash or hang still costs only its run either way)")
    p.add_argument("--worker-memory", type=float, default=None, metavar="GB",
                   help="address-space limit of each engine worker (default: the run budget "
                        "+ 6 GB); a run past it ends as that run's failure")
    p.add_argument("--batch", type=int, default=0, metavar="N",
                   help="runs an engine that steps many worlds at once (newton) takes per "
                        "call: 0 (default) its own batch size, 1 one run at a time")


def check_parallel_arguments(args: argparse.Namespace) -> None:
    """Reject bad ``--jobs``, ``--timeout``, ``--executor``, ``--scheduler`` (one line, exit 2).

    The one validation of every command (:func:`rockbench.runner.check_execution`);
    a ``--timeout`` left at None means the study's own default limit.
    """
    from rockbench.runner import DEFAULT_TIMEOUT, check_execution, default_jobs

    timeout = getattr(args, "timeout", None)
    jobs = getattr(args, "jobs", None)
    check_execution(default_jobs() if jobs is None else jobs,
                    DEFAULT_TIMEOUT if timeout is None else timeout,
                    getattr(args, "executor", "process"), getattr(args, "scheduler", None),
                    flag="--", batch=getattr(args, "batch", 0))


def execution_options(args: argparse.Namespace, *, isolate: bool = True) -> Any:
    """The :class:`~rockbench.runner.ExecutionOptions` of a command's flags, validated.

    Raises
    ------
    ExecutionError
        A bad ``--jobs``, ``--timeout``, ``--executor`` or ``--scheduler`` (named as flags).
    """
    from rockbench.runner import DEFAULT_TIMEOUT, ExecutionOptions, default_jobs

    check_parallel_arguments(args)
    timeout = getattr(args, "timeout", None)
    memory = getattr(args, "worker_memory", None)
    extra = {} if memory is None else {"worker_memory": memory}
    jobs = getattr(args, "jobs", None)
    return ExecutionOptions(jobs=default_jobs() if jobs is None else jobs,
                            timeout=DEFAULT_TIMEOUT if timeout is None else timeout,
                            executor=getattr(args, "executor", "process"),
                            scheduler=getattr(args, "scheduler", None) or None,
                            isolate=isolate, warm=not getattr(args, "no_warm", False),
                            batch=getattr(args, "batch", 0), **extra)


def store_path(args: argparse.Namespace) -> Path | None:
    """The results store named by ``--db`` (None with ``--no-db``), checked before a
    study runs: opened once (created if missing) and closed.

    Raises
    ------
    StoreError
        The file cannot be used or is not a rockbench store (it is left untouched).
    """
    from rockbench.store import Store

    if getattr(args, "no_db", False):
        return None
    Store(args.db).close()
    return Path(args.db)


def check_output_path(path: str | Path, flag: str) -> Path:
    """Check, before a study runs, that ``path`` can be written; returns it.

    Creates the missing folders and the file, then removes what it created: a
    file that exists is not modified.

    Raises
    ------
    RockbenchError
        The path is a directory, lies under a regular file, or its folder is not
        writable (one line naming the flag).
    """
    path = Path(path)
    if path.is_dir():
        raise RockbenchError(f"{flag} {path}: is a directory, expected a file")
    existed = path.exists()
    made: list[Path] = []
    try:
        for d in reversed([d for d in [path.parent, *path.parent.parents] if not d.exists()]):
            d.mkdir()
            made.append(d)
        with path.open("a"):
            pass
    except OSError as exc:
        raise RockbenchError(f"{flag} {path}: cannot write here "
                             f"({exc.strerror or type(exc).__name__})") from None
    finally:
        with contextlib.suppress(OSError):
            if not existed:
                path.unlink(missing_ok=True)
            for d in reversed(made):
                d.rmdir()
    return path


# ---------------------------------------------------------------------- progress
class Progress:
    """A progress bar on a terminal (rich), a plain line per finished job otherwise."""

    def __init__(self, total: int, description: str, *, quiet: bool = False) -> None:
        self.total = total
        self.description = description
        self.done = 0
        self.quiet = quiet
        self._bar = None
        if not quiet and sys.stderr.isatty():
            from rich.progress import BarColumn, MofNCompleteColumn, TextColumn, TimeElapsedColumn
            from rich.progress import Progress as RichProgress

            self._bar = RichProgress(TextColumn("{task.description}"), BarColumn(),
                                     MofNCompleteColumn(), TimeElapsedColumn(),
                                     transient=True)

    def __enter__(self) -> Progress:
        if self._bar is not None:
            self._bar.start()
            self._task = self._bar.add_task(self.description, total=self.total)
        return self

    def advance(self, text: str = "") -> None:
        """Count one finished job (``text`` describes it)."""
        self.done += 1
        if self._bar is not None:
            self._bar.update(self._task, advance=1, description=f"{self.description} {text}")

    def __exit__(self, *exc: object) -> None:
        if self._bar is not None:
            self._bar.stop()


# ---------------------------------------------------------------------- the element studied
#: Density of the ``--block`` shortcut (kg/m³, stone masonry).
BLOCK_DENSITY = 2000.0


def scenario_or_block(args: argparse.Namespace) -> Any:
    """The :class:`~rockbench.scenarios.Scenario` of ``--scenario NAME|FILE``, or of
    ``--block WIDTH,HEIGHT``: one block of that width and height (m), square in plan, of
    :data:`BLOCK_DENSITY` kg/m³.

    Raises
    ------
    RockbenchError
        ``--block`` that is not two numbers; a ScenarioError for a bad scenario.
    """
    from rockbench.scenarios import Block, Scenario, get_scenario, single

    if args.scenario:
        return get_scenario(args.scenario)
    try:
        width, height = (float(v) for v in args.block.split(","))
    except ValueError:
        raise RockbenchError(f"--block takes WIDTH,HEIGHT in m, got {args.block!r}") from None
    block = Block(width, width, height, density=BLOCK_DENSITY)
    return Scenario(f"block-{width:g}x{height:g}", single(block),
                    description=f"block {width:g} m × {height:g} m, {BLOCK_DENSITY:g} kg/m³")
