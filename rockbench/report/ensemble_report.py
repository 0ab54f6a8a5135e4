"""The predictability section of the comparison report, and ``ensembles.csv``/``.json``.

Drawn from :attr:`CompareResult.predictability` (t* per case,
:mod:`rockbench.campaign.predictability`) and :attr:`CompareResult.ensembles`
(peak distributions beyond t*, :mod:`rockbench.studies.ensembles`); nothing is
simulated or measured here.
"""

from __future__ import annotations

import csv
import io
import json
import os
import tempfile
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from rockbench.method import slug
from rockbench.report.document import FigureItem, Section
from rockbench.report.tables import Cell, Table, fmt_error, fmt_ratio, fmt_seconds
from rockbench.studies.compare import CompareResult
from rockbench.studies.ensembles import Distance, EnsembleComparison, PeakDistribution

__all__ = ["predictability_section", "write_ensemble_files", "distribution_figure"]


def _fmt_p(v: float | None) -> str:
    return f"{v:.2f}" if v is not None else "–"


def _fmt_distance(d: Distance | None) -> str:
    if d is None:
        return "–"
    return (f"{d.value:.3f} [{d.low:.3f}, {d.high:.3f}] "
            f"{'>' if d.significant else '≤'} noise {d.noise:.3f}")


def _median_iqr(x: Sequence[float]) -> str:
    if not x:
        return "–"
    q1, med, q3 = np.quantile(x, [0.25, 0.5, 0.75])
    return f"{fmt_ratio(med)} ({fmt_ratio(q1)}–{fmt_ratio(q3)})"


def _t_star_table(result: CompareResult, number: int) -> Table:
    names = [s.name for s in result.options.scenarios]
    pert = next(iter(result.predictability.values())).perturbation
    frac = next(iter(result.predictability.values())).fraction
    t = Table(
        key="predictability", title=f"Table {number}. Predictability horizon t* per case",
        caption=(f"Ensemble of analytic reference runs: the nominal input and "
                 f"{next(iter(result.predictability.values())).members} members with the "
                 f"{pert.describe()}. Spread: the largest over the blocks of the range of θ/λ "
                 f"across the members; t* = first time it exceeds {frac:g} λ (the duration: "
                 f"well posed). 'outcomes differ': some members overturn, others do not."),
        columns=["scenario", "duration (s)", "t* (s)", "largest spread (λ)", "verdict"])
    for name in names:
        p = result.predictability.get(name)
        if p is None:
            continue
        verdict = p.describe() + ("; outcomes differ" if p.diverged_outcome else "")
        t.add_row([Cell(name, kind="head"), fmt_seconds(p.duration), fmt_seconds(p.t_star),
                   fmt_error(p.spread), verdict])
    return t


def _distribution_table(ensembles: Sequence[EnsembleComparison], number: int) -> Table:
    nb = max(len(c.engine.peaks) for c in ensembles)
    blocks = ["bottom", "top"] if nb == 2 else [str(i + 1) for i in range(nb)]
    cols = ["scenario", "method", "members (ok/overturned/failed)", "P(overturn)",
            "ΔP(overturn)"]
    for b in blocks:
        cols += [f"peak/λ {b}: median (IQR)", f"W₁ {b} (λ) [95 %]"]
    t = Table(
        key="ensemble-distributions", title=f"Table {number}. Distributions beyond t*",
        caption=("Per method, the same perturbed members of each case: peak max |θ|/λ per "
                 "block over the members that did not overturn (median and interquartile "
                 "range), the probability of overturning and its difference from the "
                 "reference's, and the 1-Wasserstein distance W₁ between the engine's and the "
                 "reference's peak distributions in units of λ (the mean shift that maps one "
                 "onto the other), with a bias-corrected percentile bootstrap interval (both "
                 "ensembles resampled) and the noise floor: the 95th percentile of W₁ between "
                 "random splits of the pooled members, what identical distributions show at "
                 "these ensemble sizes ('> noise': the distributions differ at the 5 % level). "
                 "Reference rows first."),
        columns=cols)
    seen: set[str] = set()
    for c in ensembles:
        rows: list[tuple[PeakDistribution, EnsembleComparison | None]] = []
        if c.scenario not in seen:
            seen.add(c.scenario)
            rows.append((c.reference, None))
        rows.append((c.engine, c))
        for d, comp in rows:
            ok = d.completed - d.overturned
            cells: list[Cell | str] = [
                Cell(d.scenario, kind="head"),
                Cell(d.method, kind="ref" if comp is None else ""),
                f"{ok}/{d.overturned}/{d.failed}", _fmt_p(d.p_overturn),
                "–" if comp is None or comp.overturn_difference is None
                else f"{comp.overturn_difference:+.2f}"]
            for i in range(nb):
                peaks = d.peaks[i] if i < len(d.peaks) else ()
                cells.append(_median_iqr(peaks))
                cells.append("–" if comp is None or i >= len(comp.distances)
                             else _fmt_distance(comp.distances[i]))
            t.add_row(cells)
    return t


def distribution_figure(path: Path, scenario: str,
                        dists: Sequence[PeakDistribution]) -> Path:
    """Peak |θ|/λ of every member, per block (columns) and method (dots, quartiles)."""
    nb = max(len(d.peaks) for d in dists)
    fig = Figure(figsize=(4.2 * nb, 0.55 * len(dists) + 1.6))
    axes = [fig.add_subplot(1, nb, i + 1) for i in range(nb)]
    rng = np.random.default_rng(0)  # jitter of the dots only
    for i, ax in enumerate(axes):
        for k, d in enumerate(dists):
            x = np.asarray(d.peaks[i] if i < len(d.peaks) else (), float)
            y = len(dists) - 1 - k
            if x.size:
                q1, med, q3 = np.quantile(x, [0.25, 0.5, 0.75])
                # quartile bar and median tick by hand (boxplot's orientation API moved)
                ax.plot([q1, q3], [y, y], "-", lw=6, color="0.8", solid_capstyle="butt")
                ax.plot([med, med], [y - 0.25, y + 0.25], "-", lw=2, color="black")
                ax.plot(x, y + rng.uniform(-0.15, 0.15, x.size), "o", ms=3, alpha=0.6,
                        color="black" if k == 0 else f"C{k % 10}")
        ax.set_yticks(range(len(dists)))
        ax.set_yticklabels([d.method + (f"\nP(overturn) {d.p_overturn:.2f}"
                                        if d.p_overturn else "") for d in reversed(dists)])
        which = ("bottom block" if i == 0 else "top block") if nb == 2 else f"block {i + 1}"
        ax.set_xlabel(f"peak |θ|/λ, {which}")
        ax.grid(True, axis="x", alpha=0.3)
    fig.suptitle(f"{scenario}: peaks of the perturbed ensemble", fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    FigureCanvasAgg(fig)
    fig.savefig(path, dpi=110)
    return path


def predictability_section(result: CompareResult, out: Path, fig: Callable[..., FigureItem],
                           number: Callable[[], int]) -> Section | None:
    """The report's section on t* and the distributions (None when t* was not measured)."""
    if not result.predictability:
        return None
    sec = Section("predictability", "Predictability horizon and distributions beyond it")
    chaotic = [p for p in result.predictability.values() if not p.well_posed]
    sec.paragraphs.append(
        f"{len(chaotic)} of {len(result.predictability)} cases are chaotic within their "
        "duration: tiny perturbations of the input grow until the reference itself is another "
        "trajectory. Time-history, impact and peak errors in this report stop at each case's "
        "t*; past it an engine can only be judged by the distribution of what happens."
        + ("" if result.ensembles else
           " Run with --ensemble N (e.g. 16) to compare the distributions."))
    sec.items.append(_t_star_table(result, number()))
    if result.ensembles:
        sec.items.append(_distribution_table(result.ensembles, number()))
        by_case: dict[str, list[PeakDistribution]] = {}
        for c in result.ensembles:
            by_case.setdefault(c.scenario, [c.reference]).append(c.engine)
        for name, dists in by_case.items():
            p = distribution_figure(out / "figures" / f"ensemble-{slug(name)}.png", name, dists)
            sec.items.append(fig(p, (
                "Peak |θ|/λ of each perturbed member (dots), their interquartile range (grey "
                "bar) and median (black tick) per method, analytic reference on top in "
                "black; members that overturned are counted in P(overturn), not drawn."),
                f"Distributions, {name}"))
    return sec


def _atomic_write(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    with os.fdopen(fd, "w", encoding="utf-8", newline="") as f:
        f.write(text)
    os.replace(tmp, path)


def _dist_json(d: PeakDistribution) -> dict[str, Any]:
    return {"method": d.method, "members": d.members, "overturned": d.overturned,
            "failed": d.failed, "p_overturn": d.p_overturn, "peaks": [list(p) for p in d.peaks]}


def write_ensemble_files(result: CompareResult, out: Path) -> list[Path]:
    """``predictability.json`` and, with ensembles, ``ensembles.csv`` and ``ensembles.json``
    in the report folder ``out``."""
    if not result.predictability:
        return []
    pred = {name: {"t_star": p.t_star, "duration": p.duration, "spread": p.spread,
                   "members": p.members, "fraction": p.fraction, "well_posed": p.well_posed,
                   "diverged_outcome": p.diverged_outcome,
                   "perturbation": {"low": p.perturbation.low, "high": p.perturbation.high,
                                    "amplitude": p.perturbation.amplitude,
                                    "tilt": p.perturbation.tilt,
                                    "seed": p.perturbation.seed}}
            for name, p in result.predictability.items()}
    files = [out / "predictability.json"]
    _atomic_write(files[0], json.dumps(pred, indent=1))
    if not result.ensembles:
        return files
    rows = []
    for c in result.ensembles:
        for i, d in enumerate(c.distances):
            rows.append({"scenario": c.scenario, "method": c.method, "block": i + 1,
                         "members": c.engine.members, "p_overturn": c.engine.p_overturn,
                         "p_overturn_reference": c.reference.p_overturn,
                         "w1": d.value if d else None, "w1_low": d.low if d else None,
                         "w1_high": d.high if d else None,
                         "w1_noise": d.noise if d else None,
                         "median_peak": float(np.median(c.engine.peaks[i]))
                         if c.engine.peaks[i] else None,
                         "median_peak_reference": float(np.median(c.reference.peaks[i]))
                         if c.reference.peaks[i] else None})
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(rows[0]))
    w.writeheader()
    w.writerows(rows)
    files.append(out / "ensembles.csv")
    _atomic_write(files[-1], buf.getvalue())
    data = [{"scenario": c.scenario, "engine": _dist_json(c.engine),
             "reference": _dist_json(c.reference),
             "distances": [None if d is None else {"w1": d.value, "low": d.low, "high": d.high,
                                                  "noise": d.noise}
                           for d in c.distances],
             "overturn_difference": c.overturn_difference} for c in result.ensembles]
    files.append(out / "ensembles.json")
    _atomic_write(files[-1], json.dumps(data, indent=1))
    return files
