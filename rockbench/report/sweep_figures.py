"""Figures of a settings sweep: stability maps over two knobs and accuracy versus cost.

:func:`stability_map` draws, per engine, a heat map over two knobs (colour =
error, markers for unstable / crashed / timeout / drifting runs and for runs
that end unlike the reference); :func:`pareto_plot` draws error against cost
with each engine's Pareto front (:func:`rockbench.studies.sweep.efficient_points`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from rockbench.studies.sweep import SweepResult, cheapest, efficient_points, grid_points

__all__ = ["stability_map", "pareto_plot", "metric_label"]

_MARKERS = {  # kind → (marker, colour, label)
    "unstable": ("^", "red", "unstable (NaN / explosion / energy gain)"),
    "crashed": ("X", "black", "crashed"),
    "timeout": ("s", "darkorange", "timeout"),
    "drift": ("D", "magenta", "non-physical drift (sliding / wobble)"),
    "mismatch": ("v", "royalblue", "ends unlike the reference"),
    "unsupported": ("o", "grey", "unsupported"),
}


def _fmt_knob(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.3g}"
    return str(v)


def _norm(result: SweepResult) -> tuple[float, float]:
    errs = [p.error(result.metric) for p in result.points if p.status.completed]
    errs = [e for e in errs if math.isfinite(e) and e > 0]
    if not errs:
        return 1e-4, 1.0
    lo, hi = min(errs), max(errs)
    if hi / lo < 10:
        lo, hi = lo / 3.0, hi * 3.0
    return lo, hi


def stability_map(result: SweepResult, engine: str, path: str | Path,
                  target: float | None = None) -> Path:
    """Heat map of the error over two of the engine's grid knobs, with failure markers.

    The first grid knob is the x axis, the second the y axis; further knobs
    give one panel per combination. Colour: log of the error metric; markers:
    unstable, crashed, timeout, drift and runs ending unlike the reference;
    a bold outline: the point meets ``target``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch, Rectangle

    path = Path(path)
    g = result.grid[engine]
    knobs = list(g)
    xk = knobs[0] if knobs else None
    yk = knobs[1] if len(knobs) > 1 else None
    rest = knobs[2:]
    xs = g[xk] if xk else [None]
    ys = g[yk] if yk else [None]
    panels = grid_points({k: g[k] for k in rest}) or [{}]
    pts = {tuple(sorted(p.knobs.items())): p for p in result.engine_points(engine)}
    lo, hi = _norm(result)
    norm = LogNorm(vmin=lo, vmax=hi)
    cmap = plt.get_cmap("viridis").copy()
    ncol = min(3, len(panels))
    nrow = math.ceil(len(panels) / ncol)
    cw = max(0.9, min(1.3, 9.0 / max(len(xs), 1)))
    fig_w = min(18.0, ncol * (1.8 + cw * len(xs))) + 1.6
    fig_h = nrow * (1.4 + 0.7 * len(ys)) + 1.8
    fig, axes = plt.subplots(nrow, ncol, figsize=(fig_w, fig_h), squeeze=False,
                             layout="constrained")
    seen: set[str] = set()
    for ax, extra in zip(axes.flat, panels, strict=False):
        data = np.full((len(ys), len(xs)), np.nan)
        for iy, yv in enumerate(ys):
            for ix, xv in enumerate(xs):
                knob = {**extra}
                if xk:
                    knob[xk] = xv
                if yk:
                    knob[yk] = yv
                p = pts.get(tuple(sorted(knob.items())))
                if p is None:
                    continue
                e = p.error(result.metric)
                kind = p.kind()
                if p.status.completed and math.isfinite(e):
                    data[iy, ix] = max(e, lo)
                    ax.text(ix, iy, f"{e:.2g}", ha="center", va="center", fontsize=8,
                            color="white" if norm(max(e, lo)) < 0.6 else "black")
                if kind != "ok":
                    mk, col, _ = _MARKERS.get(kind, ("o", "grey", kind))
                    ax.plot(ix, iy + (0.22 if math.isfinite(data[iy, ix]) else 0.0), mk,
                            color=col, markersize=11 if math.isnan(data[iy, ix]) else 7,
                            markeredgecolor="white", markeredgewidth=0.8)
                    seen.add(kind)
                if target is not None and p.meets(target, result.metric):
                    ax.add_patch(Rectangle((ix - 0.5, iy - 0.5), 1, 1, fill=False,
                                           edgecolor="red", linewidth=2.2))
                    seen.add("target")
        ax.set_facecolor("#e6e6e6")
        im = ax.imshow(np.ma.masked_invalid(data), cmap=cmap, norm=norm, origin="lower",
                       aspect="auto")
        ax.set_xticks(range(len(xs)), [_fmt_knob(v) for v in xs] if xk else [""])
        ax.set_yticks(range(len(ys)), [_fmt_knob(v) for v in ys] if yk else [""])
        ax.set_xlabel(xk or "")
        ax.set_ylabel(yk or "")
        ax.set_xlim(-0.5, len(xs) - 0.5)
        ax.set_ylim(-0.5, len(ys) - 0.5)
        if extra:
            ax.set_title(", ".join(f"{k}={_fmt_knob(v)}" for k, v in extra.items()),
                         fontsize=9)
    for ax in list(axes.flat)[len(panels):]:
        ax.axis("off")
    cbar = fig.colorbar(im, ax=axes.ravel().tolist(), shrink=0.9)
    cbar.set_label(metric_label(result.metric))
    handles: list[Any] = [Line2D([], [], linestyle="", marker=_MARKERS[k][0],
                                 color=_MARKERS[k][1], markersize=9, label=_MARKERS[k][2])
                          for k in _MARKERS if k in seen]
    if "target" in seen:
        handles.append(Patch(fill=False, edgecolor="red", linewidth=2,
                             label=f"meets target {result.metric} ≤ {target:g}"))
    if handles:
        fig.legend(handles=handles, loc="outside lower center", ncol=min(3, len(handles)),
                   fontsize=8, frameon=False)
    fig.suptitle(f"{engine} stability map: {result.scenario.name}", fontsize=11)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def metric_label(metric: str) -> str:
    """Axis label of an error metric."""
    return {"max_error": "max |Δθ|/λ vs analytic",
            "max_error_early": "max |Δθ|/λ up to the 3rd impact",
            "impact_time_error": "impact-time relative error",
            "peak_error": "peak |θ|/λ relative error"}.get(metric, metric)


def pareto_plot(result: SweepResult, path: str | Path, target: float | None = None) -> Path:
    """Error against cost for every point, each engine's Pareto front as a line.

    Runs that failed or ended unlike the reference are drawn in a band above
    the plot with their marker; the cheapest point meeting ``target`` is
    circled and labelled with its knobs.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    path = Path(path)
    fig, ax = plt.subplots(figsize=(8.0, 5.4))
    colours = plt.get_cmap("tab10")
    lo, hi = _norm(result)
    band = max(hi, target or 0.0) * 4.0
    seen: set[str] = set()
    for i, engine in enumerate(result.engines):
        col = colours(i % 10)
        pts = result.engine_points(engine)
        good = [p for p in pts if p.kind() == "ok" and math.isfinite(p.error(result.metric))]
        ax.scatter([p.cost for p in good], [max(p.error(result.metric), lo) for p in good],
                   color=col, s=28, alpha=0.75, label=engine, zorder=3)
        for p in pts:
            kind = p.kind()
            if kind == "ok" or not math.isfinite(p.cost) or p.cost <= 0:
                continue
            mk, mcol, _ = _MARKERS.get(kind, ("o", "grey", kind))
            y = p.error(result.metric) if kind == "drift" else band
            ax.plot(p.cost, max(y, lo) if math.isfinite(y) else band, mk, color=col,
                    markeredgecolor=mcol, markeredgewidth=1.5, markersize=8, zorder=3)
            seen.add(kind)
        front = efficient_points(pts, result.metric)
        if front:
            ax.step([p.cost for p in front], [max(p.error(result.metric), lo) for p in front],
                    where="post", color=col, linewidth=1.6, zorder=2)
        if target is not None:
            best = cheapest(pts, target, result.metric)
            if best is not None:
                ax.scatter([best.cost], [max(best.error(result.metric), lo)], s=160,
                           facecolors="none", edgecolors=col, linewidths=2, zorder=4)
                ax.annotate(" ".join(f"{k}={_fmt_knob(v)}" for k, v in best.knobs.items())
                            or "defaults", (best.cost, max(best.error(result.metric), lo)),
                            textcoords="offset points", xytext=(8, -14), fontsize=8,
                            color=col)
    if target is not None:
        ax.axhline(target, color="red", linestyle="--", linewidth=1)
        ax.text(0.01, target, f"target {target:g}", transform=ax.get_yaxis_transform(),
                color="red", va="bottom", fontsize=8)
    if seen - {"drift"}:
        ax.axhspan(band / 1.6, band * 1.6, color="#eeeeee", zorder=0)
        ax.text(0.01, band * 1.6, "failed / unlike the reference (error not meaningful)",
                transform=ax.get_yaxis_transform(), va="bottom", fontsize=8, color="dimgray")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("cost per run: CPU time (s; wall time where not measured)")
    ax.set_ylabel(metric_label(result.metric))
    ax.set_title(f"accuracy vs cost: {result.scenario.name}")
    ax.grid(True, which="both", alpha=0.25)
    handles, _ = ax.get_legend_handles_labels()
    handles += [Line2D([], [], linestyle="", marker=_MARKERS[k][0], color="white",
                       markeredgecolor=_MARKERS[k][1], markeredgewidth=1.5, markersize=8,
                       label=_MARKERS[k][2]) for k in _MARKERS if k in seen]
    handles.append(Line2D([], [], color="black", linewidth=1.6, label="Pareto front"))
    ax.legend(handles=handles, fontsize=8, loc="best")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


