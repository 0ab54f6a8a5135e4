"""
Which engine to trust: a verdict
================================

:func:`rockbench.studies.verify.run_verification` judges each engine at each preset on
a scenario: against the closed form where one exists, otherwise against the consensus of
engines of independent contact models that converged on their convergence ladders. Here,
one short Single #2 pulse with two cheap engines; ``converge="all"`` also climbs the
ladders where the closed form exists, which shows how far the consensus lies from it.
"""

from rockbench.runner import ExecutionOptions
from rockbench.scenarios import get_scenario
from rockbench.studies.verify import VerifyOptions, run_verification

scenario = get_scenario("single-pulse-5.0hz-6mm").replace(duration=2.0)
result = run_verification(VerifyOptions(
    scenarios=[scenario], engines=["pymunk", "mujoco"], presets=["fast"], converge="all",
    max_level=2, horizon_members=0, execution=ExecutionOptions(jobs=1, isolate=False)))

print("\n".join(result.verdict.lines()))

# %%
# The convergence ladders: each rung halves the engine's time step, until two rungs agree.

for ladder in result.ladders:
    print(f"{ladder.method.label}: {'converged' if ladder.converged else 'not converged'}: "
          f"{ladder.reason}")
for check in result.consensus_check:
    print("consensus against the closed form: peak errors",
          ", ".join(f"{e:+.2%}" for e in check.peak_errors),
          "(within its uncertainty)" if check.within else "(outside its uncertainty)")
print(f"CPU: {result.run_cpu:.2f} s for the methods' own runs, "
      f"{result.verdict_cpu:.2f} s for the ladders")
