"""The conformance kit run over every registered engine, through parametrize_with_checks.

An engine whose library is missing is an explicit skip with the reason, never a
pass. A check an engine is known to fail is declared on the engine class
(``known_failures``, with the measured reason) and becomes a strict xfail, so a
fix shows up as an unexpected pass. The second half checks the helper itself
the way a third-party plugin's test suite would use it.
"""

from typing import ClassVar

import numpy as np
import pytest

from rockbench.engines import list_engines
from rockbench.engines.analytic_engine import AnalyticEngine
from rockbench.engines.testing import CHECKS, conformance_checks, parametrize_with_checks
from rockbench.errors import UnknownEngine
from rockbench.trajectory import Trajectory

# every test here runs engines for seconds (measured with --durations): the slow tier
pytestmark = pytest.mark.slow


@parametrize_with_checks([info.name for info in list_engines()])
def test_conformance(engine, check):
    check(engine)


# ---------------------------------------------------------------- a third-party plugin
class NoisyAnalytic(AnalyticEngine):
    """A throw-away plugin: the analytic reference plus 1e-9 rad of fresh random noise.

    The noise is far below every tolerance of the kit (1e-9 rad against 2e-3 λ
    at rest, 0.01 λ for mirror symmetry) except determinism, which compares two
    runs exactly: that one check must fail, and only that one.
    """

    name: ClassVar[str] = "noisy-analytic"
    known_failures: ClassVar[dict[str, str]] = {
        "determinism": "adds 1e-9 rad of fresh random noise to every sample",
    }

    def _run(self, scenario, settings, meta) -> Trajectory:
        traj = super()._run(scenario, settings, meta)
        traj.theta = traj.theta + 1e-9 * np.random.default_rng().standard_normal(
            traj.theta.shape)
        return traj


class MissingLibrary(NoisyAnalytic):
    """A plugin whose library is not installed."""

    name: ClassVar[str] = "missing-library"
    requires: ClassVar[tuple[str, ...]] = ("rockbench_no_such_library",)


@parametrize_with_checks([NoisyAnalytic])
def test_third_party_plugin(engine, check):
    check(engine)


def _params(decorator):
    argnames, params = decorator.mark.args
    assert argnames == ("engine", "check")
    return {p.id: p for p in params}


def test_helper_ids_checks_and_strict_xfails():
    params = _params(parametrize_with_checks([NoisyAnalytic]))
    names = [n for n, _ in conformance_checks(NoisyAnalytic)]
    # the analytic capabilities: no comparison with itself, at most two blocks
    assert names == ["rest", "subthreshold", "mirror_symmetry", "determinism", "overturning",
                     "scenario_not_mutated", "stack_rest"]
    assert set(params) == {f"noisy-analytic-{n}" for n in names}
    for check_name in names:
        p = params[f"noisy-analytic-{check_name}"]
        engine, check = p.values
        assert isinstance(engine, NoisyAnalytic) and check is CHECKS[check_name]
        xfails = [m for m in p.marks if m.name == "xfail"]
        if check_name == "determinism":
            assert len(xfails) == 1 and xfails[0].kwargs == {
                "strict": True, "reason": NoisyAnalytic.known_failures["determinism"]}
            with pytest.raises(AssertionError, match="two identical runs differ"):
                check(engine)
        else:
            assert xfails == []
    # a class gives a fresh instance per check, an instance is used as given
    assert len({id(p.values[0]) for p in params.values()}) == len(names)
    given = NoisyAnalytic()
    assert all(p.values[0] is given
               for p in _params(parametrize_with_checks([given])).values())


def test_helper_accepts_names_and_skips_unavailable_engines():
    params = _params(parametrize_with_checks(["reference", MissingLibrary]))
    assert "analytic-rest" in params and "analytic-free_rocking" not in params
    assert isinstance(params["analytic-rest"].values[0], AnalyticEngine)
    skip = params["missing-library-unavailable"]
    assert skip.values == (None, None)
    (mark,) = skip.marks
    assert mark.name == "skip"
    reason = mark.kwargs["reason"]
    assert "rockbench_no_such_library" in reason and "pip install" in reason
    assert not any(i.startswith("missing-library-") and i != "missing-library-unavailable"
                   for i in params)


def test_helper_refuses_unknown_names():
    class Typo(NoisyAnalytic):
        known_failures: ClassVar[dict[str, str]] = {"determinsm": "misspelt"}

    with pytest.raises(ValueError, match="unknown check.*determinsm"):
        parametrize_with_checks([Typo])
    with pytest.raises(UnknownEngine):
        parametrize_with_checks(["no-such-engine"])
