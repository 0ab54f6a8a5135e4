"""
Free rocking of one block against Housner
=========================================

Block B2 of the paper (0.5 × 0.2 × 1.0 m) is released from rest at half its critical
angle λ and rocks freely. Housner's solution (the analytic reference) is compared with
MuJoCo and pymunk at their ``fast`` presets: each run's error against the reference is
computed by :func:`rockbench.evaluation.evaluate_run`, the one definition of every metric.
"""

import matplotlib.pyplot as plt

from rockbench import analytic
from rockbench.engines import get_engine
from rockbench.evaluation import evaluate_run
from rockbench.scenarios import get_scenario

scenario = get_scenario("free-b2-0.5").replace(duration=2.5)
lam = analytic.critical_angle(scenario.geometry)
reference = analytic.reference(scenario)
print(f"λ = {lam:.4f} rad; first impacts of the reference: "
      + ", ".join(f"{t:.4f}" for t in reference.impacts[:3]) + " s")

# %%
# Run the engines in this process and measure them against the reference.

fig, ax = plt.subplots(figsize=(8, 3.5))
ax.plot(reference.t, reference.theta[:, 0] / lam, "k", lw=2.5, label="Housner (analytic)")
for name in ("mujoco", "pymunk"):
    trajectory = get_engine(name).simulate(scenario, "fast")
    metrics = evaluate_run(scenario, trajectory, reference)
    impacts = ", ".join(f"{e:.2%}" for e in metrics.impact_time_errors)
    print(f"{name}: {metrics.status}, max |θ − θ_ref|/λ = {metrics.max_error:.4f}")
    print(f"    errors of the first impact times: {impacts}; CPU {metrics.cpu_time:.2f} s")
    ax.plot(trajectory.t, trajectory.theta[:, 0] / lam, "--", label=f"{name} (fast)")
ax.set_xlabel("t (s)")
ax.set_ylabel("θ / λ")
ax.legend()
fig.tight_layout()
