"""The report of the code check (:mod:`rockbench.studies.code_check`).

Writes, in the report directory:

* ``report.md``: the site and its spectrum, the mechanism's code quantities and
  the linear and non-linear checks per direction, with the clauses applied;
* ``check.json``: every number (:meth:`CodeCheckResult.to_dict`);
* ``figures/capacity.png``: left, the capacity curve a(d) of each direction from
  finite kinematics with the Circolare 2009 linear curve and the point d_SLV;
  right, the displacement demand against the period (ground S_De, or the floor's
  [C8.7.1.12], for ξ = 8 %) with each direction's capacity d_SLV at T_SLV: a point
  below the demand fails.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from rockbench import provenance
from rockbench.studies.code_check import CodeCheckResult, DirectionCheck

__all__ = ["write_code_check_report", "capacity_figure", "summary_lines"]

_DPI = 110
_COLORS = {1: "#1f77b4", -1: "#d62728"}


def _fmt(x: float, digits: int = 4) -> str:
    return "–" if x is None or not math.isfinite(x) else f"{x:.{digits}g}"


def _verdict(ok: bool) -> str:
    return "pass" if ok else "**fail**"


def _distinct(result: CodeCheckResult) -> list[tuple[DirectionCheck, str]]:
    """The directions to draw, with their labels: "±x" once where both give the same curve
    and check (a symmetric mechanism)."""
    dirs = list(result.directions)
    if len(dirs) == 2:
        k1, k2 = dirs[0].kinematics, dirs[1].kinematics
        if k1 is not None and k2 is not None and k1.curve is not None \
                and k2.curve is not None and k1.curve.displacement.shape == \
                k2.curve.displacement.shape \
                and np.allclose(k1.curve.displacement, k2.curve.displacement, rtol=1e-9) \
                and np.allclose(k1.curve.acceleration, k2.curve.acceleration, rtol=1e-9):
            return [(dirs[0], "±x")]
    return [(d, d.label) for d in dirs]


def capacity_figure(path: Path, result: CodeCheckResult) -> Path:
    """``path``: capacity curves and the displacement demand against the capacities."""
    fig = Figure(figsize=(10.0, 4.2), layout="constrained")
    ax, bx = fig.subplots(1, 2)
    g = result.scenario.g
    drawn = False
    for d, label in _distinct(result):
        k = d.kinematics
        if k is None or k.curve is None:
            continue
        drawn = True
        c = _COLORS[d.direction]
        curve = k.curve
        ax.plot(curve.displacement * 100, curve.acceleration / g, color=c, lw=2,
                label=f"loads {label}: a(d), finite kinematics")
        lin = np.array([k.linear_acceleration_at(x) for x in curve.displacement])
        ax.plot(curve.displacement * 100, lin / g, color=c, lw=1, ls="--",
                label=f"loads {label}: a₀*(1 − d/d₀) (Circ. 2009)")
        ax.plot([k.d_slv * 100], [k.a_slv / g], "o", color=c, ms=6)
        ax.annotate(f"d_SLV = {k.d_slv * 100:.3g} cm", (k.d_slv * 100, k.a_slv / g),
                    textcoords="offset points", xytext=(6, 6), fontsize=8, color=c)
    ax.set_xlabel("spectral displacement d (cm)")
    ax.set_ylabel("spectral acceleration a / g")
    ax.set_xlim(left=0)
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    if drawn:
        ax.legend(fontsize=7, loc="upper right")
        ax.set_title("capacity curves [C8.7.1.3], [C8.7.1.4]", fontsize=10)
    else:
        ax.text(0.5, 0.5, "no finite kinematics:\nno capacity curve", ha="center",
                va="center", transform=ax.transAxes)
        ax.set_title("capacity curve", fontsize=10)
    nonlinear = [(d, d.nonlinear) for d in result.directions if d.nonlinear is not None]
    periods = [c.period for _, c in nonlinear]
    top = max([2.5, *(1.3 * t for t in periods)])
    ts = np.linspace(0.0, top, 300)
    site = result.site
    demand = np.array([site.displacement_demand(t, g) for t in ts])
    where = "ground S_De" if site.building is None else \
        f"floor at z = {site.element_height:g} m [C8.7.1.12]"
    bx.plot(ts, demand * 100, color="k", lw=1.8, label=f"demand, {where}, ξ = 8 %")
    for d, label in _distinct(result):
        chk = d.nonlinear
        if chk is None:
            continue
        bx.plot([chk.period], [chk.capacity * 100], "o", color=_COLORS[d.direction], ms=7,
                label=f"loads {label}: d_SLV at T_SLV ({'pass' if chk.passed else 'fail'})")
    bx.set_xlabel("period T (s)")
    bx.set_ylabel("displacement (cm)")
    bx.set_xlim(0, top)
    bx.set_ylim(bottom=0)
    bx.grid(alpha=0.3)
    bx.legend(fontsize=7, loc="upper left")
    bx.set_title(f"a_g = {site.ag:g} g, soil {site.soil}, {site.topography}", fontsize=10)
    fig.suptitle(f"{result.scenario.name}: NTC 2018 kinematic check", fontsize=11)
    path.parent.mkdir(parents=True, exist_ok=True)
    FigureCanvasAgg(fig)
    fig.savefig(path, dpi=_DPI)
    return path


def summary_lines(result: CodeCheckResult) -> list[str]:
    """A few lines for the terminal: the verdict per direction and check."""
    g = result.scenario.g
    lines = [f"{result.scenario.name}: design PGA at the base {result.design_pga:.3f} m/s² "
             f"({result.design_pga / g:.3f} g), z = {result.site.element_height:g} m"]
    for d in result.directions:
        if d.kinematics is None:
            lines.append(f"  loads {d.label}: {d.note}")
            continue
        k = d.kinematics
        lines.append(f"  loads {d.label}: α0 = {k.load_factor:.4f}, "
                     f"a0* = {k.spectral_acceleration:.3f} m/s²")
        if d.linear is not None:
            c = d.linear
            lines.append(f"    linear     {'pass' if c.passed else 'FAIL'}  ratio {c.ratio:.3f}"
                         f"  capacity PGA {c.capacity_pga:.3f} m/s²")
        if d.nonlinear is not None:
            n = d.nonlinear
            lines.append(f"    non-linear {'pass' if n.passed else 'FAIL'}  ratio {n.ratio:.3f}"
                         f"  capacity PGA {n.capacity_pga:.3f} m/s²"
                         f"  (d_SLV {n.capacity * 100:.3g} cm vs {n.demand * 100:.3g} cm)")
        else:
            lines.append("    non-linear not done: no finite kinematics")
    lines.append(f"  overall: {'pass' if result.passed else 'FAIL'}")
    e = result.ec8
    if e is not None:
        lines.append(f"Eurocode 8 (EN 1998-1 §4.3.5.2): S_a = {e.coefficient:.3f} g, "
                     f"γ_a = {e.importance:g}, q_a = {e.qa:g}: {'pass' if e.passed else 'FAIL'} "
                     f" ratio {e.ratio:.3f}  capacity PGA {e.capacity_pga:.3f} m/s²")
    return lines


def _direction_section(d: DirectionCheck, g: float) -> list[str]:
    out = [f"### Loads toward {d.label}", ""]
    lim = d.limit
    if d.kinematics is None:
        out += [f"Limit analysis: {lim.status}. {d.note}.", ""]
        return out
    k = d.kinematics
    out += [
        f"Mechanism ({lim.governing_mode}), moving blocks: {', '.join(map(str, k.moving_blocks))}; "
        f"control point: centre of gravity of block {k.control_block} at "
        f"({k.control_point[0]:.4g}, {k.control_point[1]:.4g}) m.",
        "",
        "| quantity | value | clause |",
        "|---|---|---|",
        f"| α₀ | {_fmt(k.load_factor)} | [C8.7.1.1], limit analysis |",
        f"| Σ P (moving blocks) | {_fmt(k.total_weight)} N | |",
        f"| M* | {_fmt(k.participating_mass)} kg | [C8.7.1.5] |",
        f"| e* | {_fmt(k.mass_fraction)} | [C8.7.1.5] |",
        f"| FC | {_fmt(k.confidence_factor)} | §C8.7.1.2.1.3 |",
        f"| a₀* = α₀ g/(e* FC) | {_fmt(k.spectral_acceleration)} m/s² "
        f"({_fmt(k.spectral_acceleration / g)} g) | [C8.7.1.3], [C8.7.1.8] |",
    ]
    if k.curve is not None:
        out += [
            f"| d₀ (α = 0 after a rotation of {_fmt(math.degrees(k.curve.rotation0))}°) | "
            f"{_fmt(k.d0 * 100)} cm | [C8.7.1.4] |",
            f"| d_SLV = 0.4 d₀ | {_fmt(k.d_slv * 100)} cm | §C8.7.1.2.1.6 |",
            f"| a(d_SLV) | {_fmt(k.a_slv)} m/s² | capacity curve |",
            f"| T_SLV = 1.68π √(d_SLV/a(d_SLV)) | {_fmt(k.period_slv)} s | [C8.7.1.10] |",
            f"| d_SLC = 0.6 d₀, T_SLC | {_fmt(k.d_slc * 100)} cm, {_fmt(k.period_slc)} s | "
            f"§C8.7.1.2.1.6, [C8.7.1.11] |",
            f"| Circolare 2009: d_u* = 0.4 d₀*, d_s* = 0.4 d_u*, a_s*, T_s | "
            f"{_fmt(k.du_2009 * 100)} cm, {_fmt(k.ds_2009 * 100)} cm, {_fmt(k.as_2009)} m/s², "
            f"{_fmt(k.secant_period_2009)} s | C8A.4.2.3 (reference only) |",
        ]
    out.append("")
    if d.linear is not None:
        c = d.linear
        out += [f"**Linear check** (§C8.7.1.2.1.7, q = {c.q:g}): a₀* = "
                f"{_fmt(c.spectral_acceleration)} m/s² against a_base/q = {_fmt(c.demand)} m/s²: "
                f"ratio {_fmt(c.ratio)}, {_verdict(c.passed)}; a_g,SLV = {_fmt(c.capacity_ag)} g, "
                f"capacity PGA at the base {_fmt(c.capacity_pga)} m/s².", ""]
    if d.nonlinear is not None:
        n = d.nonlinear
        gov = " (a_g,SLD governs: activation)" if n.governed_by_activation else ""
        out += [f"**Non-linear check** (§C8.7.1.2.1.8, ξ = {n.damping:g} %): d_SLV = "
                f"{_fmt(n.capacity * 100)} cm against a demand of {_fmt(n.demand * 100)} cm at "
                f"T_SLV = {_fmt(n.period)} s: ratio {_fmt(n.ratio)}{gov}, {_verdict(n.passed)}; "
                f"a_g,SLV = {_fmt(n.capacity_ag)} g, capacity PGA at the base "
                f"{_fmt(n.capacity_pga)} m/s².", ""]
    elif d.note:
        out += [f"*{d.note}.*", ""]
    return out


def _markdown(result: CodeCheckResult, command: str, figure: str) -> str:
    site, spec = result.site, result.site.spectrum
    g = result.scenario.g
    lines = [f"# Code check of {result.scenario.name}: NTC 2018 §8.7.1", ""]
    if command:
        lines += [f"`{command}`", ""]
    verdict = "passes every check" if result.passed else "fails"
    lines += [
        f"**Verdict: {result.scenario.name} {verdict}** (Circolare 2019 n. 7 §C8.7.1.2.1, SLV). "
        f"Design PGA at the element's base {result.design_pga:.3f} m/s² "
        f"({result.design_pga / g:.3f} g); smallest capacity PGA: linear "
        f"{_fmt(result.capacity_pga('linear'))} m/s², non-linear "
        f"{_fmt(result.capacity_pga('nonlinear'))} m/s².",
        "",
        "## Site and demand",
        "",
        f"a_g = {site.ag:g} g, F₀ = {site.F0:g}, T_C* = {site.TC_star:g} s, soil {site.soil}, "
        f"topography {site.topography}; q = {site.q:g}, FC = {site.confidence_factor:g}; "
        f"joint friction μ = {_fmt(result.friction)}"
        + (f" (site file `{site.source}`)" if site.source else "") + ".",
        "",
        f"NTC 2018 §3.2.3.2.1: S_S = {spec.SS:.4g}, S_T = {spec.ST:.4g}, S = {spec.S:.4g}, "
        f"C_C = {spec.CC:.4g}, T_B = {spec.TB:.4g} s, T_C = {spec.TC:.4g} s, "
        f"T_D = {spec.TD:.4g} s; plateau a_g S η F₀ = {spec.plateau:.4g} g; a_g S = "
        f"{spec.pga:.4g} g.",
        "",
    ]
    if site.building is not None:
        b = site.building
        how = ("first mode, [C7.2.7], [C7.2.8]" if site.floor_model == "modal"
               else "simplified floor spectrum [C7.2.11] at T_a = 0")
        lines += [f"The element stands at z = {b.element_height:g} m of a building H = "
                  f"{b.height:g} m, T₁ = {b.period:g} s, N = {b.storeys} storeys (γ₁ = "
                  f"{b.participation:.4g}, ψ₁ = {b.mode_shape:.4g}, ξ₁ = {b.damping:g} %): peak "
                  f"floor acceleration {result.design_pga / g:.4g} g ({how}; not below a_g S).",
                  ""]
    else:
        lines += ["The element stands on the ground: its base's peak acceleration is a_g S g.",
                  ""]
    lines += ["## Mechanism and checks", ""]
    for d in result.directions:
        lines += _direction_section(d, g)
    e = result.ec8
    if e is not None:
        lines += [
            "## Eurocode 8, beside it", "",
            f"EN 1998-1 §4.3.5.2 checks a non-structural element with a horizontal force "
            f"F_a = S_a W_a γ_a / q_a [4.24]. For a rigid element (T_a = 0) at this site (type 1 "
            f"soil factor of ground {site.soil} × S_T), S_a = {e.coefficient:.4g} g [4.25]; "
            f"γ_a = {e.importance:g}, q_a = {e.qa:g} (Tab. 4.4: 1.0 for cantilevering "
            f"parapets). The element resists up to α₀ = {e.alpha0:.4g} of its weight "
            f"(limit analysis, the weaker direction): ratio α₀ q_a / (S_a γ_a) = "
            f"{e.ratio:.3f}, **{'pass' if e.passed else 'FAIL'}**; design acceleration at "
            f"the base {e.design_pga:.3f} m/s², capacity {e.capacity_pga:.3f} m/s².", ""]
    lines += [
        "## Assumptions",
        "",
        "- Rigid blocks, no tension, infinite compressive strength; joints with the friction "
        "above (limit analysis of `rockbench.analytic.static_collapse`).",
        "- Rigid until the mechanism opens (T₀ = 0); an element free to vibrate would need "
        "its elastic period T₀ [C8.7.1.7].",
        "- The capacity curve follows the same kinematic chain to d₀ (finite rotations).",
        "- capacity_pga scales the demand with a_g at a fixed spectral shape (S, T_C, T_D of "
        "the site).",
        "",
        f"![capacity curves and displacement demand]({figure})",
        "",
        f"Code: {provenance.describe()}",
        "",
    ]
    return "\n".join(lines)


def write_code_check_report(out: Path, result: CodeCheckResult, command: str = ""
                            ) -> dict[str, Path]:
    """Write ``report.md``, ``check.json`` and ``figures/capacity.png`` under ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    fig = capacity_figure(out / "figures" / "capacity.png", result)
    md = out / "report.md"
    md.write_text(_markdown(result, command, "figures/capacity.png"), encoding="utf-8")
    js = out / "check.json"
    data = result.to_dict()
    if command:
        data["command"] = command
    js.write_text(json.dumps(data, indent=2, ensure_ascii=False) + "\n", encoding="utf-8")
    return {"report": md, "json": js, "figure": fig}
