"""Values physics can use but that are probably a slip: warnings, not errors.

What no physics can use is refused where it is read (a 1e29 m block, a record sampled
1e-300 s apart: :mod:`rockbench.checks`, :mod:`rockbench.scenarios.excitation`). What is
merely implausible runs, with a one-line warning: :func:`review` lists it for a scenario
(block sizes far outside the structural range, sizes that look like millimetres, a base
acceleration above :data:`PLAUSIBLE_ACCELERATION_G`), :func:`warn_implausible` emits each
item as a :class:`~rockbench.errors.PlausibilityWarning`. The scenario file reader calls
it; the command line prints each warning as one line on stderr and goes on.

Example::

    import warnings
    from rockbench.scenarios import load_scenario
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        load_scenario("parapet.toml")
    print([str(w.message) for w in caught])
"""

from __future__ import annotations

import warnings

from rockbench.errors import PlausibilityWarning
from rockbench.scenarios.excitation import STANDARD_GRAVITY
from rockbench.scenarios.model import Scenario

__all__ = ["STRUCTURAL_SIZES", "MILLIMETRE_SLIP", "PLAUSIBLE_ACCELERATION_G", "review",
           "warn_implausible"]

#: Block sizes of masonry and its parts (m): from a centimetre to a tower.
STRUCTURAL_SIZES = (0.01, 50.0)
#: A scenario whose every block size is at least this (m) was probably typed in mm.
MILLIMETRE_SLIP = 10.0
#: Peak base acceleration above which a motion is flagged (g): beyond recorded ground
#: motions and the floor motions of buildings.
PLAUSIBLE_ACCELERATION_G = 3.0


def _sizes(scenario: Scenario) -> list[float]:
    """Every body's extents (m): width, height and depth (a prism's bounding box)."""
    return [x for body in scenario.geometry.bodies for x in (body.width, body.height, body.depth)]


def review(scenario: Scenario) -> list[str]:
    """What is implausible in ``scenario``, one sentence each (empty: nothing).

    Parameters
    ----------
    scenario : Scenario
        The scenario to review.

    Returns
    -------
    list of str
        The findings, each naming the field and the value.
    """
    found = []
    sizes = _sizes(scenario)
    lo, hi = min(sizes), max(sizes)
    small, large = STRUCTURAL_SIZES
    if lo >= MILLIMETRE_SLIP:
        found.append(f"every block size is {MILLIMETRE_SLIP:g} m or more ({lo:g} to {hi:g} m): "
                     f"lengths are in metres; did you mean millimetres?")
    elif hi > large or lo < small:
        far = hi if hi > large else lo
        found.append(f"a block size of {far:g} m is far outside the structural range "
                     f"({small:g} to {large:g} m; lengths are in metres)")
    motion = scenario.excitation.base_motion()
    peak = max(m.peak_acceleration(scenario.duration) for m in motion.components)
    if peak > PLAUSIBLE_ACCELERATION_G * STANDARD_GRAVITY:
        found.append(f"[excitation] the base acceleration peaks at {peak:.3g} m/s² "
                     f"({peak / STANDARD_GRAVITY:.3g} g), above any recorded ground or floor "
                     f"motion (amplitudes are in m, accelerations in m/s²)")
    return found


def warn_implausible(scenario: Scenario, where: str = "") -> None:
    """Emit each finding of :func:`review` as a :class:`PlausibilityWarning`.

    Parameters
    ----------
    scenario : Scenario
        The scenario to review.
    where : str
        Prefix of each message (e.g. the file name).
    """
    for finding in review(scenario):
        warnings.warn(f"{where}{finding}", PlausibilityWarning, stacklevel=2)
