"""Report figures (PNG, matplotlib's Agg canvas: no display, no global pyplot state).

* :func:`time_history_figure` — θ/λ against time per block, every method overlaid
  (the paper's Figs. 4, 5, 7, 10, 12, 14);
* :func:`peak_input_figure` — max |θ|/λ against ü_g/(g tan λ) (Figs. 8, 11, 13, 15);
* :func:`accuracy_speed_figure` — error against the analytic reference versus cost
  per engine × preset, Pareto front marked;
* :func:`sensitivity_figure` — one knob varied on one scenario, per engine (Fig. 4).

Failed, unstable, overturned and unsupported runs are drawn as crosses with their
status in the legend, never silently left out.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import NullFormatter

from rockbench.analytic import critical_angle, uplift_ratio
from rockbench.evaluation import RunResult
from rockbench.method import CONSENSUS, REFERENCE, Method
from rockbench.scenarios import Scenario
from rockbench.studies.pareto import pareto_front
from rockbench.trajectory import Status, Trajectory

__all__ = ["MethodStyle", "method_styles", "save_figure", "time_history_figure",
           "peak_input_figure", "accuracy_speed_figure", "sensitivity_figure", "SpeedPoint",
           "variations_speed_figure"]

_COLORS = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2",
           "#17becf", "#bcbd22", "#7f7f7f"]
_DASHES = ["-", "--", ":", "-."]
_DPI = 110


@dataclass(frozen=True)
class MethodStyle:
    """How one method is drawn."""

    color: str
    linestyle: str
    linewidth: float
    marker: str
    zorder: int


def method_styles(methods: Sequence[Method]) -> dict[str, MethodStyle]:
    """A colour per engine, a dash and a marker per preset; the reference (analytic or
    consensus) in black.

    Keyed by method label.
    """
    engines: list[str] = []
    presets: dict[str, list[str]] = {}
    for m in methods:
        if m.engine not in engines:
            engines.append(m.engine)
        presets.setdefault(m.engine, []).append(m.label)
    out: dict[str, MethodStyle] = {}
    markers = "o^sDv"
    ci = 0
    for eng in engines:
        if eng in (REFERENCE, CONSENSUS):
            color = "#000000"
        else:
            color = _COLORS[ci % len(_COLORS)]
            ci += 1
        for k, label in enumerate(presets[eng]):
            ref = eng in (REFERENCE, CONSENSUS)
            out[label] = MethodStyle(color=color, linestyle=_DASHES[k % len(_DASHES)],
                                     linewidth=2.2 if ref else 1.3,
                                     marker="o" if ref else markers[k % len(markers)],
                                     zorder=1 if ref else 3)
    return out


def save_figure(fig: Figure, path: Path) -> Path:
    """Draw ``fig`` with the Agg canvas into the PNG ``path`` (its folder made); return it."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    FigureCanvasAgg(fig)
    fig.savefig(path, dpi=_DPI)
    return path


def _status_label(method: str, traj: Trajectory | None) -> str:
    if traj is None:
        return f"{method}: not run"
    if str(traj.status) == "ok":
        return method
    return f"{method}: {traj.status}"


def _shown_duration(scenario: Scenario, trajs: Mapping[str, Trajectory]) -> float:
    """The whole duration, or less in free rocking when every run is at rest early."""
    if not scenario.excitation.is_free:
        return scenario.duration
    lam = critical_angle(scenario.geometry)
    last = 0.0
    for traj in trajs.values():
        if not traj.t.size:
            continue
        if str(traj.status) != "ok":
            return scenario.duration
        moving = np.nonzero(np.any(np.abs(traj.theta) > 0.01 * lam, axis=1))[0]
        if moving.size and moving[-1] >= traj.t.size - 1:
            return scenario.duration
        last = max(last, float(traj.t[moving[-1]]) if moving.size else 0.0)
    shown = max(1.0, 1.3 * last)
    return scenario.duration if shown > 0.7 * scenario.duration else shown


def time_history_figure(path: Path, scenario: Scenario, trajs: Mapping[str, Trajectory],
                        styles: Mapping[str, MethodStyle]) -> Path:
    """θ/λ against time for every block of ``scenario``, all methods overlaid.

    Parameters
    ----------
    path : Path
        PNG file to write.
    scenario : Scenario
        The case (its critical angle normalises θ).
    trajs : mapping
        Method → trajectory.
    styles : mapping
        Method → :class:`MethodStyle`.

    Returns
    -------
    Path
        The PNG written.
    """
    lam = critical_angle(scenario.geometry)
    nb = scenario.n_blocks
    fig = Figure(figsize=(9.5, 1.2 + 2.4 * nb), layout="constrained")
    axes = fig.subplots(nb, 1, sharex=True, squeeze=False)[:, 0]
    handles: list[Any] = []
    t_end = _shown_duration(scenario, trajs)
    for row, block in enumerate(range(nb - 1, -1, -1)):  # top block on top
        ax = axes[row]
        # y range from the runs that finished normally: a diverging or overturning run
        # must not flatten the others; it leaves the window and is marked at the edge
        ok = [t.theta[:, block] / lam for t in trajs.values()
              if t.t.size and str(t.status) == "ok"]
        if ok:
            lo = min(0.0, min(float(np.min(y)) for y in ok))
            hi = max(0.0, max(float(np.max(y)) for y in ok))
            pad = 0.08 * max(hi - lo, 1e-3)
            ylim: tuple[float, float] | None = (lo - pad, hi + pad)
        else:
            ylim = None
        for method, traj in trajs.items():
            st = styles[method]
            label = _status_label(method, traj)
            if traj.t.size:
                y = traj.theta[:, block] / lam
                if method == REFERENCE:  # a wide grey band under the engines' lines
                    (ln,) = ax.plot(traj.t, y, color="black", lw=3.4, alpha=0.45, zorder=1,
                                    label=label, solid_capstyle="butt")
                else:
                    (ln,) = ax.plot(traj.t, y, color=st.color, ls=st.linestyle,
                                    lw=st.linewidth, zorder=st.zorder, label=label)
                if str(traj.status) != "ok":
                    yx = float(y[-1]) if np.isfinite(y[-1]) else 0.0
                    if ylim is not None:
                        yx = float(np.clip(yx, *ylim))
                    ax.plot(traj.t[-1], yx, "x", color=st.color, ms=11, mew=2.5, zorder=5,
                            clip_on=False)
                    ax.annotate(f" {traj.status} at {traj.t[-1]:.2f} s", (traj.t[-1], yx),
                                fontsize=8, color=st.color, va="center",
                                xytext=(6, 0), textcoords="offset points")
                    ln = Line2D([], [], color=st.color, ls=st.linestyle, marker="x", ms=8,
                                mew=2, label=label)
            else:
                ln = Line2D([], [], color=st.color, ls="none", marker="x", ms=8, mew=2,
                            label=label)
            if row == 0:
                handles.append(ln)
        if ylim is not None:
            ax.set_ylim(*ylim)
        ax.axhline(0.0, color="0.6", lw=0.6, zorder=0)
        ax.grid(True, color="0.9", lw=0.6)
        name = ("block" if nb == 1 else "top block" if block == nb - 1 and nb > 1
                else "bottom block" if block == 0 else f"block {block + 1}")
        ax.set_ylabel(f"θ/λ, {name}" if nb > 1 else "θ/λ")
    axes[-1].set_xlabel("time t (s)" + ("" if t_end >= scenario.duration else
                                        f" (shown to {t_end:.3g} s of {scenario.duration:g} s: "
                                        "every run is at rest after)"))
    axes[-1].set_xlim(0.0, t_end)
    desc = f"λ = {lam:.4f} rad"
    if not scenario.excitation.is_free:
        desc += f", ü_g/(g tan λ) = {uplift_ratio(scenario):.2f}"
    else:
        desc += f", θ0 = {scenario.initial_tilt:g} λ"
    fig.suptitle(f"{scenario.name}  ({desc})", fontsize=11)
    fig.legend(handles=handles, loc="outside lower center", ncol=min(len(handles), 5),
               fontsize=9, frameon=False)
    return save_figure(fig, path)


def peak_input_figure(path: Path, title: str, scenarios: Sequence[Scenario],
                      methods: Sequence[str], rows: Mapping[tuple[str, str], RunResult],
                      styles: Mapping[str, MethodStyle],
                      published: Sequence[tuple[int, str, float, Scenario]] = (),
                      ) -> Path:
    """max |θ|/λ against the normalised input acceleration ü_g/(g tan λ), per block.

    Parameters
    ----------
    path : Path
        PNG file to write.
    title : str
        Figure title.
    scenarios : sequence of Scenario
        The cases (each one point per method).
    methods : sequence of str
        Labels of the methods to draw.
    rows : mapping
        (scenario, method label) → result.
    styles : mapping
        Method → :class:`MethodStyle`.
    published : sequence
        The paper's values as (block, paper method, value, scenario), drawn hollow.

    Returns
    -------
    Path
        The PNG written.
    """
    nb = max(s.n_blocks for s in scenarios)
    fig = Figure(figsize=(5.2 * nb + 1.5, 4.6), layout="constrained")
    axes = fig.subplots(1, nb, squeeze=False)[0]
    paper_marks = {"analytical": "o", "Bullet": "s", "Vortex": "^", "DEM": "D"}
    handles: dict[str, Any] = {}
    names = {s.name for s in scenarios}
    xs_all = [uplift_ratio(s) for s in scenarios]
    span = max(max(xs_all) - min(xs_all), 0.4)
    for col, block in enumerate(range(nb, 0, -1)):
        ax = axes[col]
        finite = [p for (sn, _), r in rows.items()
                  if sn in names and r.status is Status.OK and block <= r.metrics.n_blocks
                  and (p := r.metrics.peaks[block - 1]) is not None]
        finite += [float(v) for b, _, v, _ in published if b == block and isinstance(v, float)]
        top = max([*finite, 0.1]) * 1.15
        failed_any = False
        for k, m in enumerate(methods):
            st = styles[m]
            xs, ys, fx = [], [], []
            for s in scenarios:
                r = rows.get((s.name, m))
                if r is None or block > s.n_blocks:
                    continue
                if r.status is Status.OK:
                    xs.append(uplift_ratio(s))
                    ys.append(r.metrics.peaks[block - 1])
                else:
                    fx.append(uplift_ratio(s))
            # small horizontal offsets keep coincident markers visible
            dx = (k - (len(methods) - 1) / 2) * 0.008 * span
            h = ax.plot(np.add(xs, dx), ys, ls="none", marker=st.marker, color=st.color,
                        ms=7 if m != REFERENCE else 8, mfc=st.color if m != REFERENCE else "none",
                        mew=1.6, label=m, zorder=st.zorder + 2)[0]
            if xs:
                handles.setdefault(m, h)
            if fx:
                failed_any = True
                ax.plot(np.add(fx, dx), [top] * len(fx), ls="none", marker="x", color=st.color,
                        ms=10, mew=2.5, zorder=6)
                handles[f"{m}: failed/overturned"] = Line2D(
                    [], [], ls="none", marker="x", color=st.color, ms=9, mew=2.2,
                    label=f"{m}: failed or overturned")
        for b, pm, v, s in published:
            if b != block or not isinstance(v, float):
                continue
            h = ax.plot(uplift_ratio(s), v, ls="none", marker=paper_marks.get(pm, "o"),
                        mfc="none", mec="0.45", ms=7, mew=1.0, label=f"paper: {pm}", zorder=1)[0]
            handles.setdefault(f"paper: {pm}", h)
        if failed_any:
            ax.axhline(top, color="0.75", lw=0.8, ls=":")
            ax.text(0.01, top, " failed / overturned", va="bottom", ha="left", fontsize=8,
                    color="0.35", transform=ax.get_yaxis_transform())
        ax.set_ylim(0.0, top * 1.08)
        ax.set_xlim(min(xs_all) - 0.12 * span, max(xs_all) + 0.12 * span)
        ax.grid(True, color="0.9", lw=0.6)
        ax.set_xlabel("normalised input acceleration ü_g/(g tan λ)")
        name = ("" if nb == 1 else ", top block" if block == nb else ", bottom block"
                if block == 1 else f", block {block}")
        ax.set_ylabel(f"max |θ|/λ{name}")
    fig.suptitle(title, fontsize=11)
    order = [k for m in methods for k in (m, f"{m}: failed/overturned") if k in handles]
    order += [k for k in handles if k not in order]
    fig.legend(handles=[handles[k] for k in order], loc="outside right center", fontsize=8.5,
               frameon=False)
    return save_figure(fig, path)


@dataclass(frozen=True)
class SpeedPoint:
    """One engine × preset on the accuracy-versus-speed chart.

    Attributes
    ----------
    method : str
        Label.
    cost : float
        Wall time per simulated second (s/s), summed over the completed runs.
    error : float
        Median over scenarios of max |θ − θ_ref|/λ (NaN if none).
    peak_error : float
        Median over scenarios and blocks of |Δpeak|/peak (NaN if none).
    failed : int
        Runs that did not end as their reference (or ok, where there is none).
    total : int
        Runs of the method.
    compared : int
        Scenarios whose error stands behind the point (the medians' sample size).
    """

    method: str
    cost: float
    error: float
    peak_error: float
    failed: int
    total: int
    compared: int = 0


def _front(xy: Sequence[tuple[float, float]]) -> list[int]:
    """Indices of the Pareto-front points (positive errors only), cheapest first."""
    return pareto_front(range(len(xy)), cost=lambda i: xy[i][0],
                        error=lambda i: xy[i][1] if xy[i][1] > 0 else math.nan)


def accuracy_speed_figure(path: Path, points: Sequence[SpeedPoint],
                          styles: Mapping[str, MethodStyle], subtitle: str = "") -> Path:
    """Error against the analytic reference versus cost, log–log, Pareto front marked.

    Two panels: (a) the time-history error max |Δθ|/λ, (b) the peak error |Δpeak|/peak.
    Methods with no successful comparison are crosses on the top edge.

    Returns
    -------
    Path
        The PNG written.
    """
    fig = Figure(figsize=(11.5, 4.8), layout="constrained")
    axes = fig.subplots(1, 2)
    for ax, attr, label in ((axes[0], "error", "median max |θ − θ_ref|/λ"),
                            (axes[1], "peak_error", "median |Δpeak|/peak")):
        xy = [(p.cost, getattr(p, attr)) for p in points]
        good = [v for v in xy if math.isfinite(v[0]) and math.isfinite(v[1]) and v[1] > 0]
        if good:
            ylo = min(v[1] for v in good) / 3
            yhi = max(v[1] for v in good) * 3
        else:
            ylo, yhi = 1e-4, 1.0
        front = _front(xy)
        if len(front) > 1:
            fx = [xy[i][0] for i in front]
            fy = [xy[i][1] for i in front]
            ax.step(fx, fy, where="post", color="0.55", lw=1.2, ls="--", zorder=1,
                    label="Pareto front")
        placed: list[tuple[float, float]] = []
        for i, p in enumerate(points):
            st = styles.get(p.method) or MethodStyle("#555555", "-", 1, "o", 2)
            x, y = xy[i]
            note = f" ({p.failed}/{p.total} unlike the reference)" if p.failed else ""
            if p.compared < p.total:
                note += f" [{p.compared} of {p.total} scenarios]"
            if math.isfinite(x) and math.isfinite(y) and y > 0:
                ax.plot(x, y, marker=st.marker, color=st.color, ms=9, ls="none", zorder=3,
                        mec="black" if i in front else st.color, mew=1.6 if i in front else 1)
                # labels of neighbours (within ~0.3 decade) alternate above and below
                near = sum(abs(math.log10(x / a)) < 0.3 and abs(math.log10(y / b)) < 0.12
                           for a, b in placed)
                placed.append((x, y))
                ax.annotate(p.method + note, (x, y), textcoords="offset points",
                            xytext=(7, 5 if near % 2 == 0 else -13), fontsize=8.5)
            elif math.isfinite(x):
                ax.plot(x, yhi, marker="x", color=st.color, ms=11, mew=2.5, ls="none",
                        zorder=4, clip_on=False)
                ax.annotate(f"{p.method}: no successful run{note}", (x, yhi),
                            textcoords="offset points", xytext=(7, -12), fontsize=8.5)
        ax.set_xscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())  # minor labels overlap on short ranges
        ax.set_yscale("log")
        ax.set_ylim(ylo, yhi * 1.05)
        xs = [v[0] for v in xy if math.isfinite(v[0]) and v[0] > 0]
        if xs:
            ax.set_xlim(min(xs) / 2.5, max(xs) * 4)
        ax.grid(True, which="major", color="0.9", lw=0.6)
        ax.set_xlabel("wall time per simulated second (s/s, log)")
        ax.set_ylabel(f"{label} (log)")
        if len(front) > 1:
            ax.legend(loc="lower left", fontsize=8.5, frameon=False)
    axes[0].set_title("(a) time-history error", fontsize=10)
    axes[1].set_title("(b) peak error", fontsize=10)
    fig.suptitle("Accuracy versus speed against the analytic reference"
                 + (f" — {subtitle}" if subtitle else ""), fontsize=11)
    return save_figure(fig, path)


def sensitivity_figure(path: Path, scenario: Scenario, knob_title: str,
                       panels: Sequence[tuple[str, Mapping[str, Trajectory]]],
                       reference: Trajectory | None) -> Path:
    """One knob varied: θ/λ against time, one panel per engine, one line per value.

    Parameters
    ----------
    path : Path
        PNG file to write.
    scenario : Scenario
        The scenario varied (the paper's B0).
    knob_title : str
        What is varied (figure title).
    panels : sequence of (engine, {value label: trajectory})
        One panel per engine.
    reference : Trajectory or None
        Housner's solution, overlaid in black.

    Returns
    -------
    Path
        The PNG written.
    """
    lam = critical_angle(scenario.geometry)
    n = max(1, len(panels))
    fig = Figure(figsize=(9.5, 0.9 + 2.5 * n), layout="constrained")
    axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    cmap = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd"]
    for ax, (engine, trajs) in zip(axes, panels, strict=False):
        if reference is not None and reference.t.size:
            ax.plot(reference.t, reference.theta[:, 0] / lam, color="black", lw=2.2,
                    label="Housner (analytic)", zorder=1)
        for k, (label, traj) in enumerate(trajs.items()):
            c = cmap[k % len(cmap)]
            lab = label if str(traj.status) == "ok" else f"{label}: {traj.status}"
            if traj.t.size:
                ax.plot(traj.t, traj.theta[:, 0] / lam, color=c, lw=1.2,
                        ls=_DASHES[k % len(_DASHES)], label=lab, zorder=3)
                if str(traj.status) != "ok":
                    ax.plot(traj.t[-1], traj.theta[-1, 0] / lam, "x", color=c, ms=11, mew=2.5)
            else:
                ax.plot([], [], "x", color=c, ms=9, mew=2, label=lab)
        ax.axhline(0.0, color="0.6", lw=0.6, zorder=0)
        ax.grid(True, color="0.9", lw=0.6)
        ax.set_ylabel(f"{engine}\nθ/λ")
        ax.legend(loc="upper right", fontsize=8, ncol=2, framealpha=0.85)
    axes[-1].set_xlabel("time t (s)")
    axes[-1].set_xlim(0.0, scenario.duration)
    fig.suptitle(f"{scenario.name}: {knob_title}", fontsize=11)
    return save_figure(fig, path)


def variations_speed_figure(path: Path, points: Sequence[SpeedPoint],
                            engine_of: Mapping[str, str], group_of: Mapping[str, str],
                            title: str) -> Path:
    """Many settings variations on one chart: colour = engine, marker = varied knob.

    Only the Pareto-front points are labelled; runs that did not finish ok are
    crosses on the top edge.

    Parameters
    ----------
    path : Path
        PNG file to write.
    points : sequence of SpeedPoint
        One per variation (``error`` is the y value).
    engine_of, group_of : mapping
        Method → engine name, method → knob name.
    title : str
        Figure title.

    Returns
    -------
    Path
        The PNG written.
    """
    fig = Figure(figsize=(10.5, 5.6), layout="constrained")
    ax = fig.subplots()
    engines = list(dict.fromkeys(engine_of[p.method] for p in points))
    groups = list(dict.fromkeys(group_of[p.method] for p in points))
    colors = {e: _COLORS[i % len(_COLORS)] for i, e in enumerate(engines)}
    marks = {g: "osD^vP*X"[i % 8] for i, g in enumerate(groups)}
    xy = [(p.cost, p.error) for p in points]
    good = [y for x, y in xy if math.isfinite(x) and math.isfinite(y) and y > 0]
    yhi = max(good) * 3 if good else 1.0
    ylo = min(good) / 3 if good else 1e-4
    front = _front(xy)
    if len(front) > 1:
        ax.step([xy[i][0] for i in front], [xy[i][1] for i in front], where="post",
                color="0.55", lw=1.2, ls="--", zorder=1)
    for i, p in enumerate(points):
        x, y = xy[i]
        c, mk = colors[engine_of[p.method]], marks[group_of[p.method]]
        if math.isfinite(x) and math.isfinite(y) and y > 0:
            ax.plot(x, y, marker=mk, color=c, ms=8, ls="none", zorder=3,
                    mec="black" if i in front else c, mew=1.6 if i in front else 0.8)
            if i in front:
                ax.annotate(p.method, (x, y), textcoords="offset points", xytext=(7, 4),
                            fontsize=8)
        elif math.isfinite(x):
            ax.plot(x, yhi, marker="x", color=c, ms=10, mew=2.2, ls="none", zorder=4,
                    clip_on=False)
    ax.set_xscale("log")
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_yscale("log")
    ax.set_ylim(ylo, yhi * 1.1)
    ax.grid(True, which="major", color="0.9", lw=0.6)
    ax.set_xlabel("wall time per simulated second (s/s, log)")
    ax.set_ylabel("max |θ − θ_ref|/λ (log)")
    handles = [Line2D([], [], ls="none", marker="s", ms=9, color=colors[e], label=e)
               for e in engines]
    handles += [Line2D([], [], ls="none", marker=marks[g], ms=8, color="0.4", mfc="none",
                       label=f"varied: {g}") for g in groups]
    handles += [Line2D([], [], ls="none", marker="x", ms=9, mew=2, color="0.3",
                       label="not ok (top edge)"),
                Line2D([], [], ls="--", color="0.55", label="Pareto front (labelled)")]
    fig.legend(handles=handles, loc="outside right center", fontsize=8.5, frameon=False)
    fig.suptitle(title, fontsize=11)
    return save_figure(fig, path)
