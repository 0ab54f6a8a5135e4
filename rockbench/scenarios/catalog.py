"""Built-in catalog: every case of Giordano et al. (2025), and named suites.

Names follow DESIGN.md: ``free-b0``, ``free-b1-0.5``, ``single-pulse-3.0hz-8mm``,
``stack-sine-5.0hz-4mm``, ... Suites group them (``paper-free``, ``paper``, ``smoke``...).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from functools import partial
from pathlib import Path

from rockbench.errors import UnknownScenario
from rockbench.geometry import (
    Block,
    Geometry,
    drum_column,
    parapet,
    running_bond_wall,
    single,
    stack,
    voussoir_arch,
)
from rockbench.scenarios.excitation import Excitation, SinePulse, Sinusoid
from rockbench.scenarios.files import load_scenario
from rockbench.scenarios.model import Contact, Scenario
from rockbench.scenarios.records import record_scenarios

__all__ = ["catalog", "get_scenario", "suites", "get_suite", "resolve_scenarios",
           "FREE_BLOCKS", "SINGLE_CASES", "STACK_CASES"]

#: Free-rocking blocks of the paper's Section 4: (width, depth, height) in m, mass 1 kg.
FREE_BLOCKS = {
    "b0": (1.00, 0.20, 5.00),
    "b1": (0.50, 0.20, 0.75),
    "b2": (0.50, 0.20, 1.00),
    "b3": (0.50, 0.20, 1.25),
}
FREE_TILTS = (0.2, 0.5, 0.99)
#: Single #2 inputs (Hz, mm), Tables 6 and 7.
SINGLE_CASES = ((3.0, 8), (3.3, 6), (3.3, 8), (5.0, 4), (5.0, 5), (5.0, 6))
#: Two-block inputs (Hz, mm), Tables 9-12.
STACK_CASES = ((3.3, 4), (4.0, 3), (4.0, 4), (4.0, 5), (5.0, 2), (5.0, 3), (5.0, 4), (6.5, 2))

FREE_DURATION = 20.0
PULSE_DURATION = 4.0
SINE_DURATION = 10.0
RATE = 1000.0
PAPER = "Giordano et al. (2025), doi:10.1016/j.istruc.2025.110027"

#: Peña et al. (2008) granite block "Single #2": the 0.17 m side rocks.
SINGLE2 = Block(width=0.17, depth=0.502, height=1.0, density=2670.0)
#: Peña et al. (2008) two-block specimen, 5 mm chamfers.
STACK2 = stack((
    Block(width=0.20, depth=0.40, height=0.60, density=2670.0, chamfer=0.005),
    Block(width=0.15, depth=0.55, height=0.60, density=2670.0, chamfer=0.005),
))


def _hzmm(f: float, a_mm: int) -> str:
    return f"{f:.1f}hz-{a_mm}mm"


# The catalog holds builders (functools.partial of these), so that every lookup
# builds a fresh scenario.
def _free(name: str, key: str, size: tuple[float, float, float], tilt: float) -> Scenario:
    w, d, h = size
    return Scenario(
        name=name, geometry=single(Block(w, d, h, mass=1.0)), initial_tilt=tilt,
        duration=FREE_DURATION, output_rate=RATE,
        description=f"{key.upper()} free rocking from {tilt} λ ({PAPER}, Section 4)",
    )


def _single_driven(name: str, kind: str, exc_cls: type[SinePulse | Sinusoid], f: float,
                   a: int, dur: float) -> Scenario:
    return Scenario(
        name=name, geometry=single(SINGLE2), contact=Contact(friction=1.0),
        excitation=exc_cls(frequency=f, amplitude=a / 1000.0), duration=dur,
        output_rate=RATE,
        description=f"Single #2 block, {f} Hz / {a} mm {kind} ({PAPER}, Section 5)",
    )


def _stack_driven(name: str, kind: str, exc_cls: type[SinePulse | Sinusoid], f: float,
                  a: int, dur: float) -> Scenario:
    return Scenario(
        name=name, geometry=STACK2, contact=Contact(friction=1.0),
        excitation=exc_cls(frequency=f, amplitude=a / 1000.0), duration=dur,
        output_rate=RATE,
        description=f"two stacked blocks, {f} Hz / {a} mm {kind} ({PAPER}, Section 6)",
    )


def _build() -> dict[str, Callable[[], Scenario]]:
    cat: dict[str, Callable[[], Scenario]] = {}
    for key, size in FREE_BLOCKS.items():
        tilts = (0.5,) if key == "b0" else FREE_TILTS
        for tilt in tilts:
            name = f"free-{key}" if key == "b0" else f"free-{key}-{tilt}"
            cat[name] = partial(_free, name, key, size, tilt)
    drives: tuple[tuple[str, type[SinePulse | Sinusoid], float], ...] = (
        ("pulse", SinePulse, PULSE_DURATION), ("sine", Sinusoid, SINE_DURATION))
    for kind, exc_cls, dur in drives:
        for f, a in SINGLE_CASES:
            name = f"single-{kind}-{_hzmm(f, a)}"
            cat[name] = partial(_single_driven, name, kind, exc_cls, f, a, dur)
        for f, a in STACK_CASES:
            name = f"stack-{kind}-{_hzmm(f, a)}"
            cat[name] = partial(_stack_driven, name, kind, exc_cls, f, a, dur)
    return cat


_CATALOG = {**_build(), **record_scenarios()}


def catalog() -> list[str]:
    """Names of every built-in scenario."""
    return list(_CATALOG)


def get_scenario(name: str) -> Scenario:
    """A catalog scenario by name, or a scenario read from a ``.toml`` file path.

    Raises
    ------
    UnknownScenario
        Neither a catalog name nor an existing ``.toml`` file (with a "did you mean").
    ScenarioError
        The file exists but is invalid.
    """
    if name in _CATALOG:
        return _CATALOG[name]()
    if name.endswith(".toml") or Path(name).exists():
        return load_scenario(name)
    raise UnknownScenario(name, list(_CATALOG))


def suites() -> dict[str, list[str]]:
    """Named suites: suite name → scenario names."""
    names = list(_CATALOG)
    groups = {
        "paper-free": [n for n in names if n.startswith("free-")],
        "paper-single-pulse": [n for n in names if n.startswith("single-pulse-")],
        "paper-single-sine": [n for n in names if n.startswith("single-sine-")],
        "paper-stack-pulse": [n for n in names if n.startswith("stack-pulse-")],
        "paper-stack-sine": [n for n in names if n.startswith("stack-sine-")],
    }
    groups["paper"] = [n for g in groups.values() for n in g]
    groups["records"] = [n for n in names if n.startswith("record-")]
    groups["smoke"] = ["free-b2-0.5", "single-pulse-3.0hz-8mm", "stack-pulse-4.0hz-4mm"]
    groups["sliding"] = [n for n in names if n.startswith("slide-")]
    for family in ASSEMBLY_FAMILIES:
        groups[f"assembly-{family}"] = [n for n in names if n.startswith(f"{family}-")]
    groups["assemblies"] = [n for f in ASSEMBLY_FAMILIES for n in groups[f"assembly-{f}"]]
    return groups


def get_suite(name: str) -> list[str]:
    """Scenario names of a suite.

    Raises
    ------
    UnknownScenario
        No such suite (with a "did you mean").
    """
    s = suites()
    if name not in s:
        raise UnknownScenario(name, list(s), kind="suite")
    return list(s[name])


def resolve_scenarios(spec: str) -> list[Scenario]:
    """Scenarios from a comma list of catalog names, suite names and ``.toml`` files."""
    out: list[Scenario] = []
    s = suites()
    for item in (x.strip() for x in spec.split(",")):
        if not item:
            continue
        if item in s:
            out += [get_scenario(n) for n in s[item]]
        else:
            out.append(get_scenario(item))
    return out


#: Low-friction cases, (name, blocks, excitation, μ, duration): μ is below every uplift
#: ratio b/h, so the blocks slide on the base without rocking (exact reference:
#: rockbench.analytic.sliding). The stack has one μ for every contact: it slides on the
#: base as one body while its interface carries the largest friction it can.
SLIDING_CASES = (
    ("slide-single-pulse-3.0hz-8mm-mu0.10", single(SINGLE2), SinePulse(3.0, 0.008), 0.10, 1.5),
    ("slide-single-pulse-5.0hz-6mm-mu0.15", single(SINGLE2), SinePulse(5.0, 0.006), 0.15, 1.5),
    ("slide-single-sine-3.0hz-8mm-mu0.15", single(SINGLE2), Sinusoid(3.0, 0.008), 0.15, 3.0),
    ("slide-b2-pulse-2.0hz-20mm-mu0.20", single(Block(*FREE_BLOCKS["b2"], mass=1.0)),
     SinePulse(2.0, 0.020), 0.20, 1.5),
    ("slide-stack-pulse-5.0hz-4mm-mu0.10", STACK2, SinePulse(5.0, 0.004), 0.10, 1.5),
)


def _sliding() -> dict[str, Callable[[], Scenario]]:
    cat: dict[str, Callable[[], Scenario]] = {}
    for name, geo, exc, mu, dur in SLIDING_CASES:
        cat[name] = partial(_sliding_case, name, geo, exc, mu, dur)
    return cat


def _sliding_case(name: str, geo: Geometry, exc: Excitation, mu: float,
                  dur: float) -> Scenario:
    return Scenario(
        name=name, geometry=geo, contact=Contact(friction=mu), excitation=exc,
        duration=dur, output_rate=RATE,
        description=f"low friction μ = {mu:g}: slides without rocking (Coulomb sliding)",
    )


_CATALOG.update(_sliding())


#: Interface slip: the paper's stack on a base whose friction μ holds it, with a lower
#: interface friction μᵢ: the upper block slides on the lower one, which moves with the
#: base; nothing rocks (bounds and exact reference: rockbench.analytic.sliding).
#: (name, excitation, μ, μᵢ, duration).
INTERFACE_SLIDING_CASES = (
    ("slide-stack-pulse-5.0hz-3mm-mu0.25-if0.05", SinePulse(5.0, 0.003), 0.25, 0.05, 1.5),
)


def _interface_sliding() -> dict[str, Callable[[], Scenario]]:
    cat: dict[str, Callable[[], Scenario]] = {}
    for name, exc, mu, mu_i, dur in INTERFACE_SLIDING_CASES:
        cat[name] = partial(_interface_sliding_case, name, exc, mu, mu_i, dur)
    return cat


def _interface_sliding_case(name: str, exc: Excitation, mu: float, mu_i: float,
                            dur: float) -> Scenario:
    return Scenario(
        name=name, geometry=STACK2, contact=Contact(friction=mu, interface_friction=mu_i),
        excitation=exc, duration=dur, output_rate=RATE,
        description=f"interface friction μᵢ = {mu_i:g} under base friction μ = {mu:g}: "
                    "the upper block slides on the lower one (Coulomb sliding)",
    )


_CATALOG.update(_interface_sliding())


#: Masonry assemblies at rest on a still base: name → builder. The families are
#: parametrised (rockbench.geometry.builders); the catalog keeps a few members each.
ASSEMBLY_CASES: dict[str, Callable[[], Geometry]] = {
    **{f"column-{n}drums": partial(drum_column, n) for n in (3, 5, 10)},
    **{f"parapet-offset{e:.2f}": partial(parapet, e) for e in (0.0, 0.25)},
    **{f"wall-{c}x{b}": partial(running_bond_wall, c, b) for c, b in ((6, 3), (10, 3))},
    **{f"arch-{n}v-t{t:.2f}": partial(voussoir_arch, n, t) for n, t in ((9, 0.15), (9, 0.20))},
}
#: Family prefixes of ASSEMBLY_CASES; each has the suite ``assembly-<family>``.
ASSEMBLY_FAMILIES = ("column", "parapet", "wall", "arch")
#: Family → (description with the case's parameters, how to read a name's parameters).
_ASSEMBLY_TEXT = {
    "column": "multi-drum column of {} drums 0.6 × 0.5 m",
    "parapet": "parapet 0.3 × 0.8 m on a wall 0.6 × 1.2 m, its centre {} m from the wall's",
    "wall": "dry-stack wall panel in running bond, {} courses of {} bricks 0.24 × 0.12 m",
    "arch": "semicircular arch R = 1 m of {} voussoirs {} m thick on two springer supports",
}
#: The numbers of a case name (``column-5drums`` → 5, ``arch-9v-t0.15`` → 9, 0.15).
_NUMBER = re.compile(r"\d+(?:\.\d+)?")


def _assemblies() -> dict[str, Callable[[], Scenario]]:
    cat: dict[str, Callable[[], Scenario]] = {}
    for name, build in ASSEMBLY_CASES.items():
        family, param = name.split("-", 1)
        text = _ASSEMBLY_TEXT[family].format(*_NUMBER.findall(param))
        cat[name] = partial(_assembly_case, name, build, text)
    return cat


def _assembly_case(name: str, build: Callable[[], Geometry], text: str) -> Scenario:
    return Scenario(
        name=name, geometry=build(), contact=Contact(friction=1.0), duration=2.0,
        output_rate=RATE, description=f"{text}, at rest",
    )


_CATALOG.update(_assemblies())
