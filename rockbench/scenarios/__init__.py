"""Scenarios: what is simulated (geometry, contact, base motion), files and catalog."""

from rockbench.geometry import Block, Geometry, Prism, Support, single, stack

# the record sets register their table reader with the excitations on import
from rockbench.scenarios import record_sets  # noqa: F401
from rockbench.scenarios.catalog import (
    catalog,
    get_scenario,
    get_suite,
    resolve_scenarios,
    suites,
)
from rockbench.scenarios.excitation import (
    REPORT_GROUPS,
    STANDARD_GRAVITY,
    AxialExcitation,
    Components,
    CosinePulse,
    Excitation,
    Free,
    Record,
    SinePulse,
    Sinusoid,
    TiltTable,
    excitation_class,
    excitation_from_table,
    excitation_kinds,
)
from rockbench.scenarios.files import (
    load_scenario,
    save_scenario,
    scenario_from_dict,
    scenario_to_dict,
)
from rockbench.scenarios.model import Contact, Scenario
from rockbench.scenarios.motion import BaseMotion, Motion, Still

__all__ = [
    "Scenario", "Contact", "Block", "Prism", "Support", "Geometry", "single", "stack",
    "Excitation", "AxialExcitation", "Motion", "Still", "Components", "BaseMotion", "Free",
    "SinePulse", "CosinePulse",
    "Sinusoid", "Record", "TiltTable", "STANDARD_GRAVITY", "REPORT_GROUPS", "excitation_kinds",
    "excitation_class", "excitation_from_table",
    "catalog", "get_scenario", "get_suite", "resolve_scenarios", "suites",
    "load_scenario", "save_scenario", "scenario_from_dict", "scenario_to_dict",
]
