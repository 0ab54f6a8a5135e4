"""The verdict: convergence ladders, the consensus, and which method to trust.

Physics first: on cases with a closed form the consensus and the verdict agree
with it; a method made wrong on purpose is named untrusted (against the closed
form and against a consensus); a ladder that does not settle is reported as not
converging; a chaotic case is not judged on its time history beyond t*.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import ClassVar

import numpy as np
import pytest

from rockbench import analytic
from rockbench.cli import main
from rockbench.engines import register, unregister
from rockbench.evaluation import evaluate_run
from rockbench.geometry import Block, drum_column
from rockbench.method import Method
from rockbench.runner import ExecutionOptions
from rockbench.scenarios import Contact, Scenario, SinePulse, get_scenario
from rockbench.studies.convergence import _estimate, _history_change, converge, response
from rockbench.studies.verdict import Trust, judge_closed_form
from rockbench.studies.verify import VerifyOptions, run_verification
from rockbench.trajectory import Trajectory

sys.path.insert(0, str(Path(__file__).parent))
import fault_engine  # noqa: E402

INLINE = ExecutionOptions(isolate=False)
SINGLE2 = Block(0.17, 0.502, 1.0, density=2670.0)
#: Single #2 under the 3 Hz / 8 mm pulse, shortened (peak 0.418 λ).
PULSE = Scenario("pulse", SINGLE2, excitation=SinePulse(3.0, 0.008), duration=1.2,
                 output_rate=100.0)


@pytest.mark.parametrize("order", [1.0, 2.0, 3.0])
def test_richardson_recovers_the_limit_of_a_sequence_of_known_order(order: float) -> None:
    limit, c = 0.4, 0.05
    values = [limit + c * 2.0 ** (-order * k) for k in range(4)]
    est = _estimate(values)
    assert est is not None
    assert est.order == pytest.approx(order, rel=1e-9)
    assert est.value == pytest.approx(limit, abs=1e-12)
    # the uncertainty is Roache's 1.25 |correction|: it covers the true error of the finest
    assert est.uncertainty == pytest.approx(1.25 * abs(values[-1] - limit), rel=1e-9)


def test_two_rungs_estimate_the_finest_with_their_difference() -> None:
    est = _estimate([0.30, 0.31])
    assert est is not None and est.value == 0.31 and est.uncertainty == pytest.approx(0.01)
    assert est.order is None


@pytest.fixture
def fault() -> Iterator[None]:
    register("fault", fault_engine.FaultEngine)
    yield
    unregister("fault")


class WobblyEngine(fault_engine.FaultEngine):
    """Follows the reference with an error that flips sign at every refinement: never
    settles, however fine the step."""

    name: ClassVar[str] = "wobbly"
    contact_model: ClassVar[str] = "wobbly"

    def _build(self, scenario, settings):  # type: ignore[no-untyped-def]
        dt = super()._build(scenario, settings)
        self.gain = 1.0 + 0.1 * math.cos(math.pi * math.log2(settings.timestep))
        return dt


def test_a_ladder_converges_to_the_closed_form_with_its_order(fault: None) -> None:
    """The fault engine follows the reference with a relative error 10·dt/iterations: a
    first-order method whose ladder must settle on the closed-form peak."""
    method = Method.of("fault", {"follow": True, "timestep": 4e-3, "iterations": 2})
    c = converge(PULSE, method, execution=INLINE)
    assert c.converged, c.reason
    exact = float(np.max(np.abs(analytic.reference(PULSE).theta))) / \
        analytic.critical_angle(PULSE.geometry)
    (peak,) = c.peaks
    assert peak is not None
    assert abs(peak.value - exact) <= max(peak.uncertainty, 1e-6 * exact)
    assert peak.order == pytest.approx(1.0, abs=0.05)
    (err,) = c.peak_errors()
    assert err == pytest.approx(0.02, rel=0.05)  # rung 0: 10 · 4e-3 / 2 = 2 % high
    assert [r.level for r in c.rungs] == list(range(len(c.rungs)))


def test_a_ladder_that_does_not_settle_is_reported_not_converging() -> None:
    register("wobbly", WobblyEngine)
    try:
        c = converge(PULSE, Method.of("wobbly", {"follow": True, "timestep": 4e-3}),
                     execution=INLINE, max_level=3)
    finally:
        unregister("wobbly")
    assert not c.converged
    assert "no agreement" in c.reason and "peaks" in c.reason
    assert len(c.rungs) == 4 and c.peaks == ()


def test_a_step_ten_times_too_long_is_named_untrusted_against_the_closed_form(
        fault: None) -> None:
    """The fault engine (one iteration) at its accurate step is 1 % off; ten times the
    step, 10 %."""
    opts = VerifyOptions([PULSE], ["fault"], presets=["accurate"], converge="none",
                         overrides={"fault": {"follow": True, "iterations": 1}},
                         execution=INLINE, horizon_members=0)
    good = run_verification(opts).verdict
    bad = run_verification(VerifyOptions(
        [PULSE], ["fault"], presets=["accurate"], converge="none",
        overrides={"fault": {"follow": True, "iterations": 1, "timestep": 1e-2}},
        execution=INLINE, horizon_members=0)).verdict
    (g,), (b,) = good.methods, bad.methods
    assert g.trust is Trust.TRUSTED and good.cheapest is g
    assert b.trust is Trust.NOT_TRUSTED and bad.cheapest is None
    assert "beyond the tolerance: peaks" in b.judgements[0].evidence
    assert b.judgements[0].reference == "closed form"


def test_the_consensus_agrees_with_the_closed_form_and_so_does_the_verdict() -> None:
    res = run_verification(VerifyOptions(
        [PULSE], ["pymunk", "mujoco"], presets=["fast"], converge="all", max_level=2,
        execution=INLINE, horizon_members=0))
    (check,) = res.consensus_check
    assert check.consensus.formed and check.consensus.families == 2
    assert check.within, check.peak_errors
    assert abs(check.peak_errors[0]) < 0.01
    for mv in res.verdict.methods:
        assert mv.trust is Trust.TRUSTED, mv.judgements[0].evidence
        assert mv.references == {"closed form": 1}
    assert res.verdict_cpu > 0 and res.run_cpu > 0


def test_without_a_closed_form_a_step_ten_times_too_long_is_named_untrusted() -> None:
    """Three drums under a one-sine pulse at twice their static factor: no closed form.
    pymunk and MuJoCo (two contact-model families) converge and agree; MuJoCo at ten
    times its fast step converges too as it refines, but its own run is 6 % off the
    consensus: untrusted, while pymunk at its fast preset is trusted."""
    geo = drum_column(3)
    alpha = math.tan(analytic.critical_angle(geo))
    sc = Scenario("drums", geo, contact=Contact(friction=1.0),
                  excitation=SinePulse(1.0, 2.0 * alpha * 9.81 / (2 * math.pi) ** 2),
                  duration=1.5, output_rate=100.0)
    assert not analytic.has_reference(sc)
    res = run_verification(VerifyOptions(
        [sc], ["pymunk", "mujoco"], presets=["fast"], overrides={"mujoco": {"timestep": 1e-2}},
        converge="auto", max_level=3, execution=ExecutionOptions(jobs=2),
        horizon_members=0))
    cons = res.verdict.consensus["drums"]
    assert cons.formed and cons.families == 2, cons.note
    assert min(p.value for p in cons.peaks) > 1.0  # it rocks hard
    trust = {mv.method.engine: mv for mv in res.verdict.methods}
    assert trust["pymunk"].trust is Trust.TRUSTED, trust["pymunk"].judgements[0].evidence
    assert trust["mujoco"].trust is Trust.NOT_TRUSTED
    assert "beyond the tolerance: peaks" in trust["mujoco"].judgements[0].evidence
    assert res.verdict.cheapest is trust["pymunk"]


def test_a_chaotic_case_is_not_judged_beyond_its_horizon() -> None:
    """A run that follows the reference up to t* and leaves it after is trusted: beyond
    t* the reference itself is not predictable."""
    sc = PULSE
    ref = analytic.reference(sc)
    lam = analytic.critical_angle(sc.geometry)
    t_star = 0.6
    theta = ref.theta.copy()
    after = ref.t > t_star
    theta[after] += 0.3 * lam  # far off, but only after the horizon
    run = Trajectory(t=ref.t, theta=theta, x=ref.x, z=ref.z, wobble=ref.wobble,
                     status=ref.status, engine="made-up")
    from rockbench.evaluation import RunResult

    judged = judge_closed_form(RunResult(sc, Method.of("made-up"),
                                         evaluate_run(sc, run, ref, horizon=t_star)), ref)
    assert judged.trust is Trust.TRUSTED, judged.evidence
    assert "up to t* = 0.60 s" in judged.evidence
    whole = judge_closed_form(RunResult(sc, Method.of("made-up"),
                                        evaluate_run(sc, run, ref)), ref)
    assert whole.trust is Trust.NOT_TRUSTED  # judged over the whole run it is 0.3 λ off


def test_verify_prints_the_verdict_and_writes_the_report(tmp_path: Path,
                                                         capsys: pytest.CaptureFixture[str]
                                                         ) -> None:
    out = tmp_path / "v"
    code = main(["verify", "single-pulse-3.0hz-8mm", "--engine", "pymunk", "--presets",
                 "fast", "--converge", "none", "--no-db", "--horizon-members", "0",
                 "--out", str(out), "--jobs", "1"])
    assert code == 0
    printed = capsys.readouterr().out
    assert "pymunk: trusted on 1 scenario (closed form 1)" in printed
    assert "use pymunk: the cheapest trusted method" in printed
    html = (out / "index.html").read_text()
    assert "Verdict: which method to trust here" in html and "Use pymunk" in html
    assert (out / "verdict.csv").read_text().splitlines()[1].startswith(
        "single-pulse-3.0hz-8mm,pymunk,pymunk,fast,closed form,trusted,")


@pytest.mark.parametrize("bad", ["peak", "peak=-1", "speed=0.1", "history=nan"])
def test_a_bad_tolerance_is_one_line_and_exit_2(bad: str, tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["verify", "free-b2-0.5", "--engine", "pymunk", "--tolerance", bad,
                 "--no-db", "--out", str(tmp_path / "v")])
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--tolerance" in err[0]


def test_compare_puts_the_verdict_first(tmp_path: Path) -> None:
    from rockbench.report.compare_report import write_report
    from rockbench.report.options import ReportOptions
    from rockbench.studies.compare import CompareOptions, run_comparison

    sc = get_scenario("free-b2-0.5").replace(duration=2.0)
    result = run_comparison(CompareOptions([sc], ["pymunk"], presets=["fast"],
                                           horizon_members=0, execution=INLINE))
    assert result.verdict is not None
    (mv,) = result.verdict.methods
    assert mv.trust is Trust.TRUSTED
    write_report(result, ReportOptions(tmp_path))
    html = (tmp_path / "index.html").read_text()
    assert html.index("Verdict: which method to trust here") < html.index("Overview")


def _leaning(theta: np.ndarray, roll: np.ndarray) -> Trajectory:
    t = np.linspace(0.0, 1.0, theta.size)
    zero = np.zeros((t.size, 1))
    return Trajectory(t=t, theta=theta[:, None], x=zero, z=zero, wobble=zero, y=zero,
                      roll=roll[:, None], twist=zero)


def test_a_run_out_of_plane_is_judged_on_its_tilt_and_its_roll() -> None:
    """A run rocking on a corner: its peak is its tilt about any axis, and two rungs with the
    same θ whose roll differs (one leaves the diagonal) do not agree."""
    s = np.sin(np.linspace(0.0, math.pi, 101))
    on_diagonal = _leaning(0.1 * s, -0.1 * s)
    off = _leaning(0.1 * s, -0.05 * s)
    peak = response(on_diagonal, 0.2).peaks[0]
    assert peak == pytest.approx(math.atan(math.hypot(math.tan(0.1), math.tan(0.1))) / 0.2)
    assert _history_change(on_diagonal, off, 0.2, None) == pytest.approx(0.05 / 0.2)
    planar = _leaning(0.1 * s, 0.0 * s)
    assert response(planar, 0.2).peaks[0] == pytest.approx(0.1 / 0.2)
    assert _history_change(planar, _leaning(0.1 * s, 0.0 * s), 0.2, None) == 0.0
