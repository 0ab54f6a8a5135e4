"""The ``rockbench`` command line.

Every module of this package (except :mod:`rockbench.cli.common`, the shared
options) is a group of sub-commands: it declares ``COMMANDS`` (name → one-line
help) and, per command, ``configure_<name>(parser)`` and ``execute_<name>(args)
-> int``. They are found here by listing the package, so adding a command is
adding a module. Bad input becomes one clear line on stderr with exit status 2.
"""

from __future__ import annotations

import argparse
import importlib
import os
import pkgutil
import sys
import warnings
from collections.abc import Callable, Sequence
from types import ModuleType
from typing import NoReturn, TextIO

from rockbench import provenance
from rockbench.cli.common import memory_budget
from rockbench.errors import RockbenchError

__all__ = ["main", "build_parser", "commands"]

#: Commands listed first in ``--help``, in this order; the others follow by name.
_FIRST = ("engines", "scenarios", "run", "compare", "matrix", "history")


class _Version(argparse.Action):
    """``--version``: the exact code (release, source hash, git commit), computed when asked."""

    def __init__(self, option_strings: Sequence[str], dest: str = argparse.SUPPRESS,
                 **kwargs: object) -> None:
        super().__init__(option_strings, dest, nargs=0,
                         help="show rockbench's release and the exact code, then exit")

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: object, option_string: str | None = None) -> None:
        print(provenance.describe())
        parser.exit()


class _Parser(argparse.ArgumentParser):
    """argparse that reports errors as a single line (exit status 2)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


def _modules() -> list[ModuleType]:
    names = sorted(m.name for m in pkgutil.iter_modules(__path__)
                   if not m.name.startswith("_") and m.name != "common")
    return [importlib.import_module(f"{__name__}.{n}") for n in names]


def commands() -> dict[str, tuple[str, Callable[[argparse.ArgumentParser], None],
                                  Callable[[argparse.Namespace], int]]]:
    """Every sub-command: name → (help, configure, execute), in ``--help`` order."""
    found = {}
    for mod in _modules():
        for name, help_text in mod.COMMANDS.items():
            attr = name.replace("-", "_")
            found[name] = (help_text, getattr(mod, f"configure_{attr}"),
                           getattr(mod, f"execute_{attr}"))
    order = [n for n in _FIRST if n in found] + sorted(n for n in found if n not in _FIRST)
    return {n: found[n] for n in order}


def build_parser() -> argparse.ArgumentParser:
    """The full argument parser."""
    parser = _Parser(prog="rockbench", description=(
        "Benchmark rigid-block rocking in physics engines against Housner-type analytical "
        "solutions (Giordano et al. 2025)."))
    parser.add_argument("--version", action=_Version)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name, (help_text, configure, execute) in commands().items():
        p = sub.add_parser(name, help=help_text, description=help_text)
        configure(p)
        p.set_defaults(_execute=execute)
    return parser


def _one_line_warning(message: Warning | str, category: type[Warning], filename: str,
                      lineno: int, file: TextIO | None = None, line: str | None = None) -> None:
    """Print a warning as one line on stderr: a user's slip is news, a source line is not."""
    print(f"rockbench: warning: {message}", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``rockbench`` console script; returns the exit status."""
    parser = build_parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    args = parser.parse_args(argv)
    args.argv = argv  # what the reports show as their command
    if not getattr(args, "_execute", None):
        parser.print_help()
        return 2
    try:
        with memory_budget(args), warnings.catch_warnings():
            warnings.showwarning = _one_line_warning
            return int(args._execute(args))
    except RockbenchError as exc:
        print(f"rockbench: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("rockbench: interrupted; results written so far are kept", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # the reader of our output went away (``rockbench records --json | head``): stop
        # quietly, and keep Python from failing again when it flushes stdout at exit
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141
