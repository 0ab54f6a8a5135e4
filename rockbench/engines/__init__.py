"""Engines: the :class:`Engine` base class, the plugin registry and the plugins."""

from rockbench.engines.base import (
    Capabilities,
    Engine,
    angles_from_quaternions,
    orientation_from_quaternions,
)
from rockbench.engines.registry import (
    EngineInfo,
    engine_class,
    engine_info,
    get_engine,
    list_engines,
    probe,
    register,
    resolve_engine_names,
    unregister,
)
from rockbench.engines.settings import (
    EngineSettings,
    KnobRole,
    SettingsError,
    parse_set_options,
)

__all__ = [
    "Engine", "Capabilities", "EngineSettings", "KnobRole", "SettingsError", "EngineInfo",
    "angles_from_quaternions", "orientation_from_quaternions", "engine_class", "engine_info",
    "get_engine", "list_engines",
    "probe", "register", "unregister", "resolve_engine_names", "parse_set_options",
]
