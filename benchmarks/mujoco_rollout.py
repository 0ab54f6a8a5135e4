"""MuJoCo's ``rollout`` module against the per-run path, for an ensemble sharing one model.

The ensemble: B0 free rocking at ``N`` initial tilts spread around the catalog's
(``initial_tilt`` × 0.8 … 1.2), the ``accurate`` preset. Every member has the
same model (the MJCF depends on the block, not on its initial pose), so
``mujoco.rollout.rollout`` can step them all from their initial states in C
threads. Compared side by side, interleaved, best of ``repeat``:

* per run: ``MujocoEngine.simulate`` for each member, one after the other in
  this process (what a warm worker does); CPU and wall time;
* rollout, 1 thread: all members in one call per output chunk; CPU time is the
  like-for-like figure against the per-run path;
* rollout, 2 threads (the machine's cores): wall time against the per-run path
  on two warm workers (about half its single-process time at best).

Rollout returns the full physics state after every step, so it runs in chunks
of ``CHUNK`` output intervals (memory), each call starting from the last state
of the previous one. The trajectories are compared: the largest |Δθ| / λ
between a member's rollout and its ``simulate`` (0: bit-identical).
Only free rocking is batched: under base excitation the plugin overwrites the
base's position and velocity before every step, which an open-loop rollout
(controls and applied forces only) cannot do.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from benchmarks import engine_status, load
from rockbench.analytic import critical_angle
from rockbench.engines import get_engine
from rockbench.engines.base import angles_from_quaternions
from rockbench.scenarios import Scenario, get_scenario

__all__ = ["run", "ensemble", "rollout_theta"]

#: Output intervals per rollout call (the state of every step is returned).
CHUNK = 200


def ensemble(n: int, duration: float) -> list[Scenario]:
    """B0 free rocking at ``n`` initial tilts, 0.8 to 1.2 times the catalog's."""
    base = get_scenario("free-b0").replace(duration=duration)
    return [base.replace(name=f"{base.name}-{i}", initial_tilt=float(base.initial_tilt * f))
            for i, f in enumerate(np.linspace(0.8, 1.2, n))]


def rollout_theta(scenarios: list[Scenario], nthread: int) -> np.ndarray:
    """θ of every member at its output times (n_members × n_samples), by ``rollout``."""
    import mujoco
    from mujoco import rollout

    eng = get_engine("mujoco")
    s = eng.resolve_settings({"preset": "accurate"})
    model = mujoco.MjModel.from_xml_string(eng.mjcf(scenarios[0], s))
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    size = mujoco.mj_stateSize(model, spec)
    init = np.empty((len(scenarios), size))
    for i, sc in enumerate(scenarios):  # each member's initial state, from its own MJCF
        m = mujoco.MjModel.from_xml_string(eng.mjcf(sc, s))
        d = mujoco.MjData(m)
        mujoco.mj_forward(m, d)
        mujoco.mj_getState(m, d, init[i], spec)
    sc = scenarios[0]
    k = int(round(1.0 / (sc.output_rate * model.opt.timestep)))
    n_out = sc.output_times().size
    datas = [mujoco.MjData(model) for _ in range(nthread)]
    theta = np.empty((len(scenarios), n_out))
    q0 = 1  # FULLPHYSICS: time, then qpos
    theta[:, 0] = angles_from_quaternions(init[:, q0 + 3:q0 + 7])[0]
    state = init
    done = 1
    while done < n_out:
        chunk = min(CHUNK, n_out - done)
        out, _ = rollout.rollout(model, datas, state, nstep=chunk * k, persistent_pool=True)
        samples = out[:, k - 1::k, :]
        theta[:, done:done + chunk] = angles_from_quaternions(samples[..., q0 + 3:q0 + 7])[0]
        state = out[:, -1, :]
        done += chunk
    return theta


def _timed(fn: Any) -> tuple[float, float, Any]:
    c0, w0 = time.process_time(), time.perf_counter()
    out = fn()
    return time.perf_counter() - w0, time.process_time() - c0, out


def run(quick: bool = False, repeat: int | None = None) -> tuple[str, dict]:
    """Markdown section and raw numbers."""
    head = "## MuJoCo `rollout` against the per-run path (issue 19)"
    ok, what = engine_status("mujoco")
    if not ok:
        return f"{head}\n\nmujoco {what}: skipped.\n", {}
    repeat = repeat or (2 if quick else 3)
    n, duration = (4, 5.0) if quick else (8, 20.0)
    scs = ensemble(n, duration)
    eng = get_engine("mujoco")

    def per_run() -> np.ndarray:
        return np.array([eng.simulate(sc, {"preset": "accurate"}).theta[:, 0] for sc in scs])

    fns = {"per run (simulate)": per_run,
           "rollout, 1 thread": lambda: rollout_theta(scs, 1),
           "rollout, 2 threads": lambda: rollout_theta(scs, 2)}
    best: dict[str, tuple[float, float]] = {k: (np.inf, np.inf) for k in fns}
    thetas: dict[str, np.ndarray] = {}
    load0 = load()
    for _ in range(repeat):
        for name, fn in fns.items():
            w, c, th = _timed(fn)
            best[name] = (min(best[name][0], w), min(best[name][1], c))
            thetas[name] = th
    lam = critical_angle(scs[0].geometry)
    ref = thetas["per run (simulate)"]
    rows = []
    for name, (w, c) in best.items():
        diff = float(np.max(np.abs(thetas[name] - ref))) / lam
        rows.append(dict(variant=name, wall=w, cpu=c, diff=diff))
    base_w, base_c = best["per run (simulate)"]
    lines = [
        head, "",
        f"B0 free rocking, {duration:g} s, `accurate` preset, an ensemble of {n} initial tilts "
        f"(0.8–1.2 × the catalog's), one process; best of {repeat}, interleaved; {load0}. "
        "'vs per run' is the per-run time over this variant's (CPU for 1 thread, wall for 2).",
        "",
        "| variant | wall (s) | CPU (s) | per member CPU (s) | vs per run | max abs Δθ / λ |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        speed = base_w / r["wall"] if "2 threads" in r["variant"] else base_c / r["cpu"]
        lines.append(f"| {r['variant']} | {r['wall']:.2f} | {r['cpu']:.2f} | "
                     f"{r['cpu'] / n:.3f} | {speed:.2f}× | {r['diff']:.1e} |")
    lines.append("")
    return "\n".join(lines), {"rows": rows, "n": n, "duration": duration}
