"""Scenarios: what is simulated (blocks, stacks, contact, base excitation), files and catalog."""

from rockbench.scenarios.excitation import (
    REPORT_GROUPS,
    STANDARD_GRAVITY,
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
from rockbench.scenarios.model import Block, Contact, RockingProperties, Scenario, Stack

__all__ = [
    "Block", "Stack", "Contact", "Scenario", "RockingProperties",
    "Assembly", "Prism", "Support", "TiltTable",
    "Excitation", "Free", "SinePulse", "CosinePulse", "Sinusoid", "Record", "STANDARD_GRAVITY",
    "REPORT_GROUPS", "excitation_kinds", "excitation_class", "excitation_from_table",
]
# after the model: assembly imports it (and the model imports assembly at its end)
from rockbench.scenarios.assembly import Assembly, Prism, Support  # noqa: E402
from rockbench.scenarios.catalog import (  # noqa: E402
    catalog,
    get_scenario,
    get_suite,
    resolve_scenarios,
    suites,
)
from rockbench.scenarios.files import (  # noqa: E402
    load_scenario,
    save_scenario,
    scenario_from_dict,
    scenario_to_dict,
)

__all__ += [
    "catalog", "get_scenario", "get_suite", "resolve_scenarios", "suites",
    "load_scenario", "save_scenario", "scenario_from_dict", "scenario_to_dict",
]
