"""Physics engines on the low-friction catalog cases against the exact sliding reference.

Every built-in physics engine runs each case of the ``sliding`` suite at its
``accurate`` preset, through the runner (so the result checks apply), and must

* slide like the exact Coulomb solution: max_t |s − s_ref| within 1 % of the
  peak exact slip, for every block (s: centroid x minus upright x minus u_g);
* stay in the sliding regime: max |θ| ≤ 0.01 λ (the exact solution never rocks);
* for the stack, slide as one body: the top block's slip relative to the lower
  one within 1 % of the peak exact slip (one friction coefficient for every
  contact: the interface carries the most friction it can and does not slip).

Friction: every engine applies ``scenario.contact.friction`` to the contact
pairs, combining the per-body coefficients the way its library does (Bullet
and Chipmunk multiply them, so those adapters set √μ on each body; MuJoCo,
DART and Drake are given μ on every body). An engine whose library is missing
is a skip with the reason; known failures are strict xfails with the numbers
measured on this machine.
"""

from __future__ import annotations

import functools

import pytest
from engine_helpers import check_slides_like_coulomb

from rockbench.analytic import reference
from rockbench.engines import engine_class
from rockbench.errors import EngineUnavailable
from rockbench.runner import Job, run_job
from rockbench.scenarios import Scenario, get_scenario, get_suite
from rockbench.trajectory import Trajectory

#: Built-in physics engines.
ENGINES = ("bullet", "dart", "dem2d", "drake", "mujoco", "pymunk")
#: Slip error and relative interface slip allowed, as fractions of the peak exact slip.
SLIP_TOL = 0.01
#: Largest rocking angle of a sliding block, as a fraction of λ.
ROCK_TOL = 0.01

S3 = "slide-single-pulse-3.0hz-8mm-mu0.10"
S5 = "slide-single-pulse-5.0hz-6mm-mu0.15"
SS = "slide-single-sine-3.0hz-8mm-mu0.15"
B2 = "slide-b2-pulse-2.0hz-20mm-mu0.20"
ST = "slide-stack-pulse-5.0hz-4mm-mu0.10"

#: (engine, case) → measured reason (slip error as max |Δs| / max |s_ref|).
KNOWN: dict[tuple[str, str], str] = {
    ("mujoco", SS): "slip error 195 %, rocks to 0.20 λ: a sliding contact opens at v_n ≈ μ|v_t| "
                    "after each contact step (in contact one step in 26 at 0.3 s), the near-stick "
                    "at 0.70 s ends late (0.8 mm off by 0.75 s) and the one-edge impulses rock it; "
                    "no knob passes (best 1.8 % with 100 no-slip passes at tolerance 0, erratic)",
    ("mujoco", ST): "slip errors 8.5 % / 9.1 %, interface slip 2.1e-3 m: both contacts chatter "
                    "while sliding (in contact 13 % / 48 % of the steps) and the interface, which "
                    "needs exactly μN, gets 0.87 μN on average",
}


@functools.cache
def exact(case: str) -> Trajectory:
    return reference(get_scenario(case))


def run(engine: str, sc: Scenario) -> Trajectory:
    try:
        presets = engine_class(engine).presets
    except EngineUnavailable as exc:
        pytest.skip(str(exc))
    return run_job(Job(sc, engine, dict(presets["accurate"])))


def _cases() -> list[str]:
    """The cases that slide as one body (an interface of its own friction is checked by
    test_interface_motion.py)."""
    return [c for c in get_suite("sliding")
            if get_scenario(c).contact.interface_friction is None]


def _params() -> list:
    out = []
    for engine in ENGINES:
        for case in _cases():
            marks = ()
            if (engine, case) in KNOWN:
                marks = (pytest.mark.xfail(strict=True, reason=KNOWN[(engine, case)]),)
            out.append(pytest.param(engine, case, marks=marks, id=f"{engine}-{case}"))
    return out


def test_the_known_failures_name_real_cases():
    cases = set(_cases())
    assert all(e in ENGINES and c in cases for e, c in KNOWN)


@pytest.mark.parametrize("engine, case", _params())
@pytest.mark.slow
def test_engine_slides_like_the_exact_solution(engine, case):
    sc = get_scenario(case)
    ref = exact(case)
    assert ref.engine_version.startswith("sliding-")
    check_slides_like_coulomb(sc, run(engine, sc), ref, slip_tol=SLIP_TOL, rock_tol=ROCK_TOL)
