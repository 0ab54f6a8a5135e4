"""
Does a pulse overturn the block?
================================

The paper's Single #2 block (0.17 m wide, 1.0 m high) under one-sine acceleration pulses
of 3 Hz. The analytic model gives the smallest pulse amplitude that overturns it
(:func:`rockbench.analytic.minimum_overturning_acceleration`); a pulse 10 % below and one
10 % above that boundary are then run on the analytic reference and on pymunk, which must
agree on the outcome.
"""

import math

import matplotlib.pyplot as plt

from rockbench import analytic
from rockbench.engines import get_engine
from rockbench.scenarios import SinePulse, get_scenario

base = get_scenario("single-pulse-3.0hz-8mm")
block = base.geometry.column.blocks[0]
rock = block.rocking(base.g)
omega = 2 * math.pi * 3.0
a_min, _ = analytic.minimum_overturning_acceleration(rock, "sine", omega, g=base.g)
print(f"uplift at {base.g * math.tan(rock.lam):.3f} m/s², overturning from {a_min:.3f} m/s² "
      f"({a_min / (base.g * math.tan(rock.lam)):.2f} × the uplift acceleration)")

# %%
# Run a pulse on each side of the boundary.

fig, ax = plt.subplots(figsize=(8, 3.5))
for factor, colour in ((0.9, "tab:blue"), (1.1, "tab:red")):
    pulse = SinePulse.from_acceleration(factor * a_min, omega)
    scenario = base.replace(name=f"pulse-{factor:.1f}", excitation=pulse, duration=3.0)
    ref = analytic.reference(scenario)
    run = get_engine("pymunk").simulate(scenario, "single")
    print(f"{factor:.1f} × a_min: analytic {ref.status}, pymunk {run.status}")
    ax.plot(ref.t, ref.theta[:, 0] / rock.lam, color=colour, lw=2.5,
            label=f"{factor:.1f} a_min, analytic ({ref.status})")
    ax.plot(run.t, run.theta[:, 0] / rock.lam, "--", color="k", lw=1)
ax.set_ylim(-3, 3)
ax.set_xlabel("t (s)")
ax.set_ylabel("θ / λ  (dashed: pymunk)")
ax.legend(loc="lower left")
fig.tight_layout()
