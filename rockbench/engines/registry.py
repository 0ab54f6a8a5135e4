"""Engine registry: plugins are found through the ``rockbench.engines`` entry points.

Plugins are imported on demand, never at ``import rockbench``. A plugin whose
library is missing is listed as unavailable with the reason and an install hint.
"""

from __future__ import annotations

import importlib
import importlib.metadata
from collections.abc import Callable, Iterable
from dataclasses import dataclass

from rockbench.engines.base import Engine
from rockbench.errors import EngineUnavailable, UnknownEngine

__all__ = [
    "EngineInfo", "engine_info", "list_engines", "get_engine", "engine_class",
    "register", "unregister", "resolve_engine_names", "ALIASES",
]

GROUP = "rockbench.engines"
#: Other spellings accepted for engine names.
ALIASES = {"reference": "analytic", "pybullet": "bullet", "dartpy": "dart"}

_extra: dict[str, Callable[[], type[Engine]]] = {}
_cache: dict[str, type[Engine]] = {}


@dataclass(frozen=True)
class EngineInfo:
    """What ``rockbench engines`` shows for one plugin."""

    name: str
    available: bool
    version: str
    reason: str
    dimensions: int | None = None
    analytic: bool = False


def _entry_points() -> dict[str, Callable[[], type[Engine]]]:
    eps = {ep.name: ep.load for ep in importlib.metadata.entry_points(group=GROUP)}
    eps.update(_extra)
    return eps


def register(name: str, cls: type[Engine] | str) -> None:
    """Register an engine class (or ``"module:Class"``) at run time, e.g. in tests."""
    if isinstance(cls, str):
        module, _, attr = cls.partition(":")
        _extra[name] = lambda: getattr(importlib.import_module(module), attr)
    else:
        _extra[name] = lambda: cls
    _cache.pop(name, None)


def unregister(name: str) -> None:
    """Remove a run-time registration."""
    _extra.pop(name, None)
    _cache.pop(name, None)


def _canonical(name: str) -> str:
    name = name.strip().lower()
    return ALIASES.get(name, name)


def engine_class(name: str) -> type[Engine]:
    """The engine class registered as ``name``.

    Raises
    ------
    UnknownEngine
        No such plugin (with a "did you mean").
    EngineUnavailable
        The plugin's library is not installed or fails to import.
    """
    name = _canonical(name)
    if name in _cache:
        return _cache[name]
    eps = _entry_points()
    if name not in eps:
        raise UnknownEngine(name, list(eps) + list(ALIASES))
    try:
        cls = eps[name]()
    except Exception as exc:  # an engine library can fail in many ways on import
        hint = f"pip install 'rockbench[{name}]'"
        raise EngineUnavailable(f"engine {name!r} is unavailable ({exc}); try: {hint}") from exc
    _cache[name] = cls
    return cls


def get_engine(name: str) -> Engine:
    """A fresh instance of the engine registered as ``name``."""
    return engine_class(name)()


def engine_info(name: str) -> EngineInfo:
    """Availability, version and reason for one engine."""
    try:
        cls = engine_class(name)
        return EngineInfo(name, True, cls.version(), "", cls.capabilities.dimensions,
                          cls.capabilities.analytic)
    except EngineUnavailable as exc:
        return EngineInfo(name, False, "", str(exc))


def list_engines() -> list[EngineInfo]:
    """Every registered engine, analytic first, then alphabetical."""
    names = sorted(_entry_points(), key=lambda n: (n != "analytic", n))
    return [engine_info(n) for n in names]


def resolve_engine_names(spec: str | Iterable[str], *, include_analytic: bool = True) -> list[str]:
    """Expand an ``--engine`` value (``all`` or a comma list) into canonical names.

    ``all`` means every available engine. Unknown names raise :class:`UnknownEngine`;
    explicitly named but unavailable ones raise :class:`EngineUnavailable`.
    """
    items = spec.split(",") if isinstance(spec, str) else list(spec)
    out: list[str] = []
    for raw in items:
        raw = raw.strip()
        if not raw:
            continue
        if raw.lower() == "all":
            names = [i.name for i in list_engines() if i.available]
        else:
            engine_class(raw)
            names = [_canonical(raw)]
        out += [n for n in names if n not in out and (include_analytic or n != "analytic")]
    if not out:
        raise UnknownEngine(str(spec), list(_entry_points()))
    return out
