"""Engine registry: plugins are found through the ``rockbench.engines`` entry points.

Plugins are imported on demand, never at ``import rockbench``. Listing engines
never fails and never calls an engine available whose library is missing: a
plugin that does not load, whose ``requires`` do not import or whose
``version()`` fails is listed as unavailable with the reason (the exception's
type and message) and its ``pip install`` hint (rule 2 of
:mod:`rockbench.engines.base`).
"""

from __future__ import annotations

import importlib
import importlib.metadata
import importlib.util
from collections.abc import Callable, Iterable
from dataclasses import dataclass

from rockbench.engines.base import Engine, install_hint
from rockbench.errors import EngineUnavailable, UnknownEngine

__all__ = [
    "EngineInfo", "engine_info", "list_engines", "get_engine", "engine_class", "probe",
    "register", "unregister", "resolve_engine_names", "ALIASES",
]

GROUP = "rockbench.engines"
#: Other spellings accepted for engine names.
ALIASES = {"reference": "analytic", "pybullet": "bullet", "dartpy": "dart"}

_extra: dict[str, Callable[[], type[Engine]]] = {}
#: Classes whose libraries imported, by canonical name.
_cache: dict[str, type[Engine]] = {}


@dataclass(frozen=True)
class EngineInfo:
    """What ``rockbench engines`` shows for one plugin.

    Attributes
    ----------
    name : str
        Canonical engine name.
    available : bool
        True when its libraries import and its version is known.
    version : str
        The library's version (empty when unavailable).
    reason : str
        Why it is unavailable, ending with the ``pip install`` hint (empty when available).
    dimensions : int or None
        2 or 3 (None when the plugin does not load).
    analytic : bool
        True for reference solutions.
    """

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


def _unavailable(cls: type[Engine], what: str, exc: Exception) -> EngineUnavailable:
    if isinstance(exc, EngineUnavailable):
        return exc
    hint = install_hint(cls.extra, cls.requires[0] if cls.requires else cls.name)
    return EngineUnavailable(
        f"engine {cls.name!r} is unavailable: {what} failed ({type(exc).__name__}: {exc}); "
        f"install it with: {hint}"
    )


def _check_available(cls: type[Engine]) -> None:
    try:
        cls.check_available()
    except Exception as exc:  # an engine library can fail in many ways on import
        raise _unavailable(cls, "importing its libraries", exc) from exc


def probe(cls: type[Engine]) -> str:
    """The version of an engine class whose libraries import, or raise EngineUnavailable.

    Calls ``cls.check_available()`` and ``cls.version()``; any exception from
    either (a missing library, a broken binary, a bug in ``version``) becomes
    :class:`~rockbench.errors.EngineUnavailable` naming its type, with the
    install hint of the class's ``extra``.
    """
    _check_available(cls)
    try:
        return str(cls.version())
    except Exception as exc:  # version() imports the library too
        raise _unavailable(cls, "version()", exc) from exc


def _plugin_hint(exc: Exception) -> str:
    """What to install when a plugin module does not import."""
    missing = exc.name if isinstance(exc, ModuleNotFoundError) and exc.name else ""
    top = missing.partition(".")[0]
    if top and importlib.util.find_spec(top) is None:  # a library the plugin imports
        return f"install it with: {install_hint('', top)}"
    # the package is there but not the plugin's module (or the module itself fails)
    where = f": pip install --force-reinstall {top}" if top else ""
    return f"reinstall the package that provides it{where}"


def engine_class(name: str) -> type[Engine]:
    """The engine class registered as ``name``, once its libraries import.

    Raises
    ------
    UnknownEngine
        No such plugin (with a "did you mean").
    EngineUnavailable
        The plugin does not load or a library in its ``requires`` does not import.
    """
    name = _canonical(name)
    if name in _cache:
        return _cache[name]
    eps = _entry_points()
    if name not in eps:
        raise UnknownEngine(name, list(eps) + list(ALIASES))
    try:
        cls = eps[name]()
    except Exception as exc:  # a third-party plugin module may fail in many ways on import
        hint = _plugin_hint(exc)
        raise EngineUnavailable(
            f"engine {name!r} is unavailable: its plugin does not load "
            f"({type(exc).__name__}: {exc}); {hint}"
        ) from exc
    _check_available(cls)
    _cache[name] = cls
    return cls


def get_engine(name: str) -> Engine:
    """A fresh instance of the engine registered as ``name``."""
    return engine_class(name)()


def engine_info(name: str) -> EngineInfo:
    """Availability, version and reason for one engine; never raises for a registered name.

    Raises
    ------
    UnknownEngine
        No plugin is registered as ``name``.
    """
    name = _canonical(name)
    try:
        cls = engine_class(name)
        version = probe(cls)
    except EngineUnavailable as exc:
        return EngineInfo(name, False, "", str(exc))
    return EngineInfo(name, True, version, "", cls.capabilities.dimensions,
                      cls.capabilities.analytic)


def list_engines() -> list[EngineInfo]:
    """Every registered engine, analytic first, then alphabetical."""
    names = sorted(_entry_points(), key=lambda n: (n != "analytic", n))
    return [engine_info(n) for n in names]


def resolve_engine_names(spec: str | Iterable[str], *, include_analytic: bool = True) -> list[str]:
    """Expand an ``--engine`` value (``all`` or a comma list) into canonical names.

    ``all`` means every available engine (unavailable ones are left out).
    Unknown names raise :class:`UnknownEngine`; an explicitly named engine
    that is unavailable raises :class:`EngineUnavailable` (one line, with the
    install hint).
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
            probe(engine_class(raw))
            names = [_canonical(raw)]
        out += [n for n in names if n not in out and (include_analytic or n != "analytic")]
    if not out:
        raise UnknownEngine(str(spec), list(_entry_points()))
    return out
