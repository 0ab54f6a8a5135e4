"""Figures and files of overturning spectra: the map figure, boundary/cell CSV, summary JSON."""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from rockbench.analytic.overturning import NO_UPLIFT, SAFE, outcome_label
from rockbench.studies.spectrum import FAILED, BlockSpec, SpectrumMap

__all__ = ["write_boundary_csv", "write_cells_csv", "write_summary_json", "spectrum_figure"]


def write_boundary_csv(path: str | Path, maps: Sequence[SpectrumMap], spec: BlockSpec,
                       kind: str) -> Path:
    """Boundary points of every map as CSV.

    Columns: method, pulse, omega_ratio (ω_p/p), omega_p (rad/s), accel_ratio
    (a_p/(g λ)), a_p (m/s²), kind (onset / island / mode), first (1 for the
    minimum overturning acceleration of its column), below/above (outcome
    codes and labels), bracket (final bisection width in a_p/(g λ)).
    """
    path = Path(path)
    rock = spec.rock
    with path.open("w", newline="") as fh:
        wr = csv.writer(fh)
        wr.writerow(["method", "pulse", "omega_ratio", "omega_p", "accel_ratio", "a_p", "kind",
                     "first", "below", "above", "below_label", "above_label", "bracket"])
        for mp in maps:
            first = mp.first_boundary()
            for b in sorted(mp.boundaries, key=lambda b: (b.w_ratio, b.a_ratio)):
                j = int(np.argmin(np.abs(mp.w_ratios - b.w_ratio)))
                is_first = b.kind == "onset" and b.a_ratio == first[j]
                wr.writerow([mp.method, kind, f"{b.w_ratio:.6g}", f"{b.w_ratio * rock.p:.6g}",
                             f"{b.a_ratio:.6g}", f"{b.a_ratio * spec.g * rock.lam:.6g}",
                             b.kind, int(is_first), b.below, b.above, outcome_label(b.below),
                             outcome_label(b.above), f"{b.width:.3g}"])
    return path


def write_cells_csv(path: str | Path, maps: Sequence[SpectrumMap]) -> Path:
    """Every grid cell of every map: method, omega_ratio, accel_ratio, code, label."""
    path = Path(path)
    with path.open("w", newline="") as fh:
        wr = csv.writer(fh)
        wr.writerow(["method", "omega_ratio", "accel_ratio", "code", "label"])
        for mp in maps:
            for j, w in enumerate(mp.w_ratios):
                for i, a in enumerate(mp.a_ratios):
                    c = int(mp.codes[j, i])
                    wr.writerow([mp.method, f"{w:.6g}", f"{a:.6g}", c,
                                 "failed" if c == FAILED else outcome_label(c)])
    return path


def write_summary_json(path: str | Path, maps: Sequence[SpectrumMap], spec: BlockSpec,
                       kind: str, extra: dict[str, Any] | None = None) -> Path:
    """Block constants, grid, timings and notes of the maps as JSON."""
    rock = spec.rock
    data = {
        "block": spec.name, "width": spec.block.width, "height": spec.block.height,
        "depth": spec.block.depth, "chamfer": spec.block.chamfer, "g": spec.g,
        "lambda": rock.lam, "p": rock.p, "eta_housner": rock.eta,
        "eta": spec.contact.eta, "pulse": kind,
        "maps": [{"method": m.method, "grid": list(m.codes.shape), "wall_time": m.wall_time,
                  "runs": m.n_runs, "notes": m.notes,
                  "first_boundary": [None if not np.isfinite(x) else float(x)
                                     for x in m.first_boundary()]} for m in maps],
    } | dict(extra or {})
    path = Path(path)
    path.write_text(json.dumps(data, indent=2))
    return path


# ---------------------------------------------------------------------- figure
#: Display classes: (codes, label, colour).
_CLASSES = [
    ((FAILED,), "run failed", "#4d4d4d"),
    ((NO_UPLIFT,), "safe: no uplift", "#ffffff"),
    ((SAFE,), "safe: rocks", "#cfe8cf"),
    ((1,), "overturns without impact (mode 1)", "#b2182b"),
    ((2,), "overturns after 1 impact (mode 2)", "#ef8a62"),
    ((3,), "overturns after 2 impacts", "#fddb7a"),
    (None, "overturns after ≥ 3 impacts", "#9e7cc1"),
]
_ENGINE_COLOURS = ["#1f77b4", "#2ca02c", "#9467bd", "#e377c2", "#17becf", "#8c564b"]


_ENGINE_MARKERS = ["o", "s", "^", "D", "v", "P"]
_ENGINE_DASHES = ["--", "-.", ":", (0, (5, 1)), (0, (3, 1, 1, 1, 1, 1)), "--"]


def _engine_style(k: int) -> dict[str, Any]:
    return {"c": _ENGINE_COLOURS[k % len(_ENGINE_COLOURS)], "lw": 2.0,
            "ls": _ENGINE_DASHES[k % len(_ENGINE_DASHES)],
            "marker": _ENGINE_MARKERS[k % len(_ENGINE_MARKERS)], "ms": 6,
            "mfc": "white", "mew": 1.5}


def _class_index(codes: np.ndarray) -> np.ndarray:
    idx = np.full(codes.shape, len(_CLASSES) - 1, dtype=int)
    for k, (cs, _, _) in enumerate(_CLASSES[:-1]):
        for c in cs or ():  # only the last class has no codes
            idx[codes == c] = k
    return idx


def _edges(v: np.ndarray) -> np.ndarray:
    if v.size == 1:
        return np.array([v[0] - 0.5, v[0] + 0.5])
    mid = 0.5 * (v[1:] + v[:-1])
    return np.concatenate([[v[0] - (mid[0] - v[0])], mid, [v[-1] + (v[-1] - mid[-1])]])


def _draw_map(ax: Any, mp: SpectrumMap) -> None:
    from matplotlib.colors import BoundaryNorm, ListedColormap

    cmap = ListedColormap([c for _, _, c in _CLASSES])
    norm = BoundaryNorm(np.arange(len(_CLASSES) + 1) - 0.5, cmap.N)
    ax.pcolormesh(_edges(mp.w_ratios), _edges(mp.a_ratios), _class_index(mp.codes).T,
                  cmap=cmap, norm=norm, shading="flat", rasterized=True)


def _draw_first(ax: Any, mp: SpectrumMap, **style: Any) -> Any:
    first = mp.first_boundary()
    ok = np.isfinite(first)
    (line,) = ax.plot(mp.w_ratios[ok], first[ok], **style)
    return line


def spectrum_figure(path: str | Path, ref: SpectrumMap, engines: Sequence[SpectrumMap],
                    spec: BlockSpec, kind: str) -> Path:
    """Draw the analytic map with every engine's first boundary, plus one panel per engine.

    Parameters
    ----------
    path : str or Path
        PNG file to write.
    ref : SpectrumMap
        The analytic map (drawn as coloured cells).
    engines : sequence of SpectrumMap
        Engine maps: their first overturning boundaries are overlaid on the
        analytic map; each also gets a small panel of its own cells.
    spec : BlockSpec
        The block (for the title).
    kind : {"sine", "cosine"}
        Pulse shape (for the title).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    n_eng = len(engines)
    ncols = min(n_eng, 3)
    nrows = 1 + (math.ceil(n_eng / 3) if n_eng else 0)
    fig = Figure(figsize=(11, 6.5 + 3.4 * (nrows - 1)), layout="constrained")
    FigureCanvasAgg(fig)
    heights = [2.0] + [1.0] * (nrows - 1)
    gs = fig.add_gridspec(nrows, max(ncols, 1), height_ratios=heights)
    ax = fig.add_subplot(gs[0, :])
    _draw_map(ax, ref)
    rock = spec.rock
    ax.set_xlabel("pulse frequency ω_p / p")
    ax.set_ylabel("pulse acceleration a_p / (g λ)")
    ax.set_xlim(_edges(ref.w_ratios)[0], _edges(ref.w_ratios)[-1])
    ax.set_ylim(_edges(ref.a_ratios)[0], _edges(ref.a_ratios)[-1])
    pulse = "a_p sin(ω_p t)" if kind == "sine" else "a_p cos(ω_p t)"
    ax.set_title(f"Overturning map, one-{kind} pulse ü_g = {pulse} — block {spec.name} "
                 f"({spec.block.width:g} × {spec.block.height:g} m, λ = {rock.lam:.4f} rad, "
                 f"p = {rock.p:.3f} rad/s); cells: {ref.method}", fontsize=10)
    # analytic boundaries: refined points of every boundary, the first one as a line
    handles: list[Any] = []
    pts = [b for b in ref.boundaries if b.kind != "mode"]
    if pts:
        ax.scatter([b.w_ratio for b in pts], [b.a_ratio for b in pts], s=6, c="k",
                   zorder=3, linewidths=0)
        handles.append(Line2D([], [], ls="", marker="o", ms=3, c="k",
                              label=f"{ref.method}: safe/overturn boundary points (bisection)"))
    handles.append(_draw_first(ax, ref, c="k", lw=1.8, zorder=4,
                               label=f"{ref.method}: minimum overturning a_p"))
    for k, em in enumerate(engines):
        handles.append(_draw_first(ax, em, zorder=5 + k, label=f"{em.method}: minimum "
                                   f"overturning a_p ({em.codes.shape[0]} columns, bisection)",
                                   **_engine_style(k)))
    uplift = 1.0 if "linear" in ref.method else math.tan(rock.lam) / rock.lam
    ax.axhline(uplift, c="0.4", lw=0.8, ls=":")
    handles.append(Line2D([], [], c="0.4", lw=0.8, ls=":", label="uplift threshold"))
    present = set(np.unique(_class_index(ref.codes)).tolist())
    for em in engines:
        present |= set(np.unique(_class_index(em.codes)).tolist())
    patches = [Patch(facecolor=c, edgecolor="0.5", label=lab)
               for k, (_, lab, c) in enumerate(_CLASSES) if k in present]
    fig.legend(handles=patches + handles, loc="outside lower center", fontsize=8, ncol=3,
               frameon=False)
    for k, em in enumerate(engines):
        sub = fig.add_subplot(gs[1 + k // 3, k % 3])
        _draw_map(sub, em)
        _draw_first(sub, ref, c="k", lw=1.2)
        _draw_first(sub, em, **(_engine_style(k) | {"ms": 4}))
        sub.set_xlim(_edges(ref.w_ratios)[0], _edges(ref.w_ratios)[-1])
        sub.set_ylim(_edges(ref.a_ratios)[0], _edges(ref.a_ratios)[-1])
        sub.set_title(f"{em.method}: {em.codes.shape[0]} × {em.codes.shape[1]} cells "
                      f"(black: {ref.method})", fontsize=9)
        sub.set_xlabel("ω_p / p", fontsize=8)
        sub.set_ylabel("a_p / (g λ)", fontsize=8)
        sub.tick_params(labelsize=7)
    path = Path(path)
    fig.savefig(path, dpi=120)
    return path
