"""Reading TOML files with one-line errors (scenarios, settings and tolerance files)."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

__all__ = ["read_toml", "loads"]

loads = tomllib.loads


def read_toml(path: str | Path, error: type[Exception], what: str = "file") -> dict[str, Any]:
    """Parse a TOML file, raising ``error`` with a message that starts with the path.

    Parameters
    ----------
    path : str or Path
        The file.
    error : type
        Exception class raised on an unreadable file or malformed TOML.
    what : str
        What the file is, for the message ("settings file", ...).
    """
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise error(f"{path}: cannot read {what} ({exc.strerror})") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path}: malformed TOML ({exc})") from None
