"""``python -m benchmarks [--quick] [--only overhead,analytic,scaling,paper,study,rollout,
pareto,fragility,verdict,batch] [--out FILE]``.

Runs the speed benchmarks of issue 7 (and issue 19's ``study``, ``rollout`` and
``pareto`` sections: runner overhead, MuJoCo batches, presets against the
cheapest settings meeting their bounds) and writes ``benchmarks/RESULTS.md``
(Markdown tables with the machine and versions) and
``benchmarks/accuracy_speed.png`` (accuracy against speed). Not part of the
test run. ``--quick`` shortens every case (about 2 minutes); the full run takes
4 to 8 minutes on 2 cores for issue 7's sections, 10 to 20 more for issue 19's.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import importlib
import math
import sys
import time
from pathlib import Path

from benchmarks import load, machine_info

#: Section name → module of this package with ``run(quick) -> (markdown, data)``.
MODULES = {"overhead": "overhead", "analytic": "analytic_speed", "scaling": "scaling",
           "paper": "paper_times", "study": "study_overhead", "rollout": "mujoco_rollout",
           "pareto": "preset_pareto",
           "fragility": "fragility_cost", "verdict": "verdict_cost", "batch": "batched_runs"}
SECTIONS = tuple(MODULES)
HERE = Path(__file__).resolve().parent


def _summary(data: dict) -> list[str]:
    """The goals of issue 7 and where they stand."""
    rows = ["## Goals at a glance", "", "| goal | result |", "|---|---|"]
    ov = data.get("overhead", {}).get("rows", [])
    if ov:
        per: dict[str, list[str]] = {}
        for r in ov:
            per.setdefault(r["engine"], []).append(f"{100 * r['overhead']:+.0f} %")
        rows.append("| adapter overhead ≤ 10 % (free B0 / forced single) | "
                    + "; ".join(f"{e} {' / '.join(v)}" for e, v in per.items()) + " |")
    an = data.get("analytic", {})
    if "b0" in an:
        b = an["b0"]
        rows.append(f"| Housner B0 20 s ≥ 10× faster than DOP853 rtol 1e-10 | "
                    f"{b['speedup']:.0f}× ({b['ref_cpu'] * 1e3:.1f} ms vs "
                    f"{b['plain_cpu'] * 1e3:.0f} ms CPU; agree to {b['diff']:.0e} λ) |")
    if an.get("cases"):
        cs = an["cases"]
        worst = max(cs, key=lambda c: c["cpu"])
        n_ok = sum(c["cpu"] <= 0.050 for c in cs)
        rows.append(f"| every paper single-block case ≤ 50 ms | {n_ok}/{len(cs)} "
                    f"(pulses {max(c['cpu'] for c in cs if 'pulse' in c['case']) * 1e3:.0f} ms"
                    f" max; slowest {worst['case']} {worst['cpu'] * 1e3:.0f} ms CPU) |")
    sc = data.get("scaling", {})
    if sc.get("duration"):
        rows.append("| cost linear in duration | exponents " + ", ".join(
            f"{r['engine']} {r['exponent']:.2f}" for r in sc["duration"]) + " |")
    if sc.get("stacks"):
        rows.append("| cost ≈ linear in stacked blocks (N ≥ 2) | exponents " + ", ".join(
            f"{r['engine']}{'' if r['preset'] == 'fast' else ' (' + r['preset'] + ')'} "
            f"{r['exponent']:.2f}" for r in sc["stacks"] if math.isfinite(r["exponent"]))
            + "".join(f"; {r['engine']} {r['preset']}: " + "; ".join(r["notes"])
                      for r in sc["stacks"] if r["notes"] and not math.isfinite(r["exponent"]))
            + " |")
    if sc.get("jobs"):
        j = sc["jobs"]
        rows.append(f"| matrix throughput vs --jobs | 2 workers: {j['speedup']:.2f}× "
                    f"the throughput of 1 (machine shared, see load) |")
    pp = data.get("paper", {}).get("paper", [])
    if pp:
        worst = max((r for r in pp if r["engine"] != "analytic"), key=lambda r: r["cpu"],
                    default=None)
        if worst:
            rows.append(f"| paper timing cases (paper: 53–489 s Bullet, 1440–18055 s 3DEC) | "
                        f"slowest engine run {worst['engine']} on {worst['case']}: "
                        f"{worst['cpu']:.1f} s CPU |")
    st = [r for r in data.get("study", {}).get("rows", []) if r["variant"] == "warm"]
    if st:
        best: dict[str, float] = {}
        for r in st:
            best[r["case"]] = min(best.get(r["case"], math.inf), r["overhead_cpu"])
        rows.append("| study overhead ≤ 10 % with warm workers (CPU; wall in the section) | "
                    + "; ".join(f"{c}: {100 * v:+.0f} %" for c, v in best.items()) + " |")
    return rows + [""]


def chart(acc: list[dict], path: Path) -> None:
    """Accuracy (error / λ) against CPU time per engine and preset, one panel per case."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = list(dict.fromkeys(r["case"] for r in acc))
    fig, axes = plt.subplots(1, len(cases), figsize=(6.2 * len(cases), 5.0), squeeze=False)
    colors = {"mujoco": "#1f77b4", "bullet": "#d62728", "dart": "#2ca02c",
              "pymunk": "#9467bd", "drake": "#ff7f0e", "dem2d": "#8c564b"}
    for ax, case in zip(axes[0], cases, strict=True):
        rs = [r for r in acc if r["case"] == case]
        for r in rs:
            if r["engine"] == "analytic":
                ax.axvline(r["cpu"], color="k", ls="--", lw=1)
                # at the foot of the line: the slowest engines' labels sit at the top
                ax.text(r["cpu"] * 1.1, 0.02, "analytic reference",
                        transform=ax.get_xaxis_transform(), va="bottom", fontsize=9)
        engines = list(dict.fromkeys(r["engine"] for r in rs if r["engine"] != "analytic"))
        for e in engines:
            pts = [r for r in rs if r["engine"] == e and math.isfinite(r["error"])
                   and r["error"] > 0]
            pts.sort(key=lambda r: r["cpu"])
            if not pts:
                continue
            c = colors.get(e, "grey")
            ax.plot([p["cpu"] for p in pts], [p["error"] for p in pts], "-", color=c, lw=1.5,
                    alpha=0.7)
            for p in pts:
                bad = p["status"] != "ok"
                ax.plot(p["cpu"], p["error"], "o" if p["preset"] == "fast" else "s", color=c,
                        ms=8, mfc="white" if bad else c)
            last = pts[-1]
            ax.annotate(e, (last["cpu"], last["error"]), textcoords="offset points",
                        xytext=(6, 4), fontsize=10, color=c, fontweight="bold")
        if "B0" in case and "20 s" in case:
            ax.axvspan(0.5, 3.5, color="0.85", zorder=0)
            ax.text(0.55, 0.80, "paper: Bullet\n0.5–3.5 s (wall,\ni7-13700K)",
                    transform=ax.get_xaxis_transform(), fontsize=8, color="0.3")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("CPU time per run (s)")
        ax.set_ylabel("max |θ − θ_ref| / λ")
        ax.set_title(case)
        ax.grid(True, which="both", alpha=0.3)
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], marker="o", ls="", color="k", label="fast preset"),
               Line2D([], [], marker="s", ls="", color="k", label="accurate preset"),
               Line2D([], [], marker="s", ls="", color="k", mfc="white",
                      label="status not ok")]
    axes[0][-1].legend(handles=handles, loc="upper right", fontsize=9)
    fig.suptitle("rockbench: accuracy against speed (lower left is better)", fontsize=12)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks", description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="short cases (about 2 minutes)")
    ap.add_argument("--only", default=",".join(SECTIONS),
                    help=f"comma list of sections ({', '.join(SECTIONS)}); --out then holds "
                         "only these (give another --out to keep the full results)")
    ap.add_argument("--out", type=Path, default=HERE / "RESULTS.md", help="Markdown output")
    ap.add_argument("--chart", type=Path, default=None,
                    help="PNG output (default: accuracy_speed.png next to --out)")
    args = ap.parse_args(argv)
    only = [s.strip() for s in args.only.split(",") if s.strip()]
    bad = [s for s in only if s not in SECTIONS]
    if bad:
        print(f"python -m benchmarks: unknown section(s) {', '.join(bad)}; choose from "
              f"{', '.join(SECTIONS)}", file=sys.stderr)
        return 2
    chart_path = args.chart or args.out.with_name("accuracy_speed.png")
    start = time.perf_counter()
    load0 = load()
    texts, data = {}, {}
    for sec in SECTIONS:
        if sec not in only:
            continue
        t0 = time.perf_counter()
        print(f"[benchmarks] {sec} ...", file=sys.stderr, flush=True)
        mod = importlib.import_module(f"benchmarks.{MODULES[sec]}")
        texts[sec], data[sec] = mod.run(quick=args.quick)
        print(f"[benchmarks] {sec} done in {time.perf_counter() - t0:.0f} s", file=sys.stderr,
              flush=True)
    total = time.perf_counter() - start
    cmd = "python -m benchmarks" + (" --quick" if args.quick else "") + (
        f" --only {args.only}" if set(only) != set(SECTIONS) else "")
    head = [
        "# rockbench speed benchmarks",
        "",
        f"Generated by `{cmd}` on {_dt.datetime.now().strftime('%Y-%m-%d %H:%M')} in "
        f"{total:.0f} s ({load0} at the start). Regenerate with the same command; "
        "see `benchmarks/__init__.py` for the timing rules. The engines' accuracy "
        "calibration is a study, not a benchmark: `rockbench calibrate ENGINE`.",
        "",
        "**Timing rules.** Comparisons are taken side by side in one process run, "
        "interleaved, best of N. The machine may be shared with other work, so the "
        "*CPU time* of this process (`time.process_time`) is reported next to the wall "
        "time and the goals are checked on it: it estimates the wall time of an idle "
        "machine. The load average is printed with every section.",
        "",
        "| machine / library | version |",
        "|---|---|",
        *[f"| {k} | {v} |" for k, v in machine_info()],
        "",
        *_summary(data),
    ]
    body = "\n".join(head) + "\n" + "\n".join(texts[s] for s in SECTIONS if s in texts)
    if "paper" in data and data["paper"].get("accuracy"):
        chart(data["paper"]["accuracy"], chart_path)
        body += f"\n![accuracy against speed]({chart_path.name})\n"
    args.out.write_text(body, encoding="utf-8")
    print(body)
    print(f"[benchmarks] wrote {args.out} in {total:.0f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
