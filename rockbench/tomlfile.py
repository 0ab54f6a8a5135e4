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
        Exception class raised on an unreadable file, bytes that are not UTF-8 or
        malformed TOML (including arrays or tables nested too deeply to parse).
    what : str
        What the file is, for the message ("settings file", ...).
    """
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise error(f"{path}: cannot read {what} ({exc.strerror or exc})") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"{path}: a {what} must be UTF-8 TOML text; byte 0x{raw[exc.start]:02x} at "
                    f"offset {exc.start} is not UTF-8") from None
    # the newline translation of a text-mode read, as before the bytes were read directly
    text = text.replace("\r\n", "\n").replace("\r", "\n")
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path}: malformed TOML ({exc})") from None
    except RecursionError:
        # tomllib parses nested arrays and inline tables recursively
        raise error(f"{path}: malformed TOML (arrays or inline tables nested too deeply for "
                    f"a {what})") from None
