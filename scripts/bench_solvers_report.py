#!/usr/bin/python3
"""Report for scripts/bench-solvers: reads the run directories it left in --work
(meta.env, runs.tsv, runs/<scene>/<solver>/r<ranks>/rep<k>/out/{summary.json,history.csv})
and writes bench-solvers.md, bench-solvers.json and bench-solvers.png into --out."""

import argparse
import csv
import json
import os
import platform
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from alfe_run import alfe_info as _alfe_info, cpu_name, memory_gib, mpi_version  # noqa: E402
from alfe_run import read_history, read_meta  # noqa: E402,F401

# Counts that depend only on the algorithm: identical in every repetition of a configuration.
COUNT_KEYS = [
    "converged",
    "steps",
    "retries",
    "nonlinear_iterations",
    "linear_iterations",
    "residual_evaluations",
    "factorizations",
]
SPREAD_WARN = 0.10  # (max - min) / median of the wall time above which the report warns


def machine_info(meta):
    return {
        "nproc": os.cpu_count(),
        "cpu": cpu_name(),
        "memory_gib": memory_gib(),
        "kernel": platform.release(),
        "mpi": mpi_version(),
        "load_average_start": meta.get("load_start", ""),
        "load_average_end": meta.get("load_end", ""),
    }


def alfe_info(meta):
    return _alfe_info(meta, iso_fmt="%Y-%m-%d %H:%M:%SZ")


def collect(work):
    meta = read_meta(os.path.join(work, "meta.env"))
    with open(os.path.join(work, "runs.tsv"), newline="") as f:
        runs = list(csv.DictReader(f, delimiter="\t"))
    scenes = meta["scenes"].split(",")
    solvers = meta["solvers"].split(",")
    ranks = [int(r) for r in meta["ranks"].split(",")]
    unavailable = sorted({r["solver"] for r in runs if r["status"] == "not-available"})

    configs = []
    for scene in scenes:
        for solver in solvers:
            for nr in ranks:
                mine = [
                    r for r in runs if r["scene"] == scene and r["solver"] == solver and int(r["ranks"]) == nr
                ]
                cfg = {"scene": scene, "solver": solver, "ranks": nr, "reps": []}
                if solver in unavailable:
                    cfg["status"] = "not available"
                    configs.append(cfg)
                    continue
                for r in sorted(mine, key=lambda r: int(r["rep"])):
                    d = os.path.join(work, r["dir"])
                    rep = {
                        "rep": int(r["rep"]),
                        "status": r["status"],
                        "exit_code": int(r["rc"]),
                        "elapsed_s": float(r["elapsed_s"]),
                        "load1_at_start": float(r["load1"]),
                    }
                    sp = os.path.join(d, "out", "summary.json")
                    if os.path.exists(sp):
                        with open(sp) as f:
                            s = json.load(f)
                        s.pop("output_dir", None)
                        rep["summary"] = s
                        if rep["rep"] == min(int(x["rep"]) for x in mine):
                            rep["history"] = read_history(os.path.join(d, "out", "history.csv"))
                    if r["status"] in ("failed", "timeout"):
                        with open(os.path.join(d, "stderr"), errors="replace") as f:
                            rep["stderr_tail"] = f.read()[-2000:]
                    cfg["reps"].append(rep)
                summarize(cfg)
                configs.append(cfg)
    return meta, scenes, solvers, ranks, unavailable, configs


def summarize(cfg):
    good = [r for r in cfg["reps"] if "summary" in r]
    if not good:
        cfg["status"] = "failed" if cfg["reps"] else "not run"
        if cfg["reps"]:
            cfg["status"] = {"timeout": "timed out"}.get(cfg["reps"][0]["status"], "failed")
        return
    statuses = {r["status"] for r in cfg["reps"]}
    cfg["status"] = "ok" if statuses == {"ok"} else ", ".join(sorted(statuses))
    walls = [r["summary"]["wall_time_s"] for r in good]
    med = statistics.median(walls)
    cfg["wall_time_s"] = {
        "median": med,
        "min": min(walls),
        "max": max(walls),
        "all": walls,
        "spread": (max(walls) - min(walls)) / med if med > 0 else 0.0,
    }
    rss = [r["summary"].get("peak_rss_mb", float("nan")) for r in good]
    cfg["peak_rss_mb"] = statistics.median(rss)
    cfg["peak_rss_mb_all"] = rss
    phases = {}
    for k in good[0]["summary"].get("phases", {}):
        phases[k] = statistics.median(r["summary"]["phases"].get(k, 0.0) for r in good)
    cfg["phases_median_s"] = phases
    counts, inconsistent = {}, {}
    for k in COUNT_KEYS:
        vals = [r["summary"].get(k) for r in good]
        counts[k] = vals[0]
        if any(v != vals[0] for v in vals):
            inconsistent[k] = vals
    cfg["counts"] = counts
    cfg["inconsistent"] = inconsistent
    for k in ("nodes", "elements", "unknowns", "partition", "message"):
        if k in good[0]["summary"]:
            cfg[k] = good[0]["summary"][k]


def find(configs, scene, solver, nr):
    for c in configs:
        if c["scene"] == scene and c["solver"] == solver and c["ranks"] == nr:
            return c
    return None


def ratio_to_newton(configs, c):
    n = find(configs, c["scene"], "newton", c["ranks"])
    if not n or "wall_time_s" not in n or "wall_time_s" not in c:
        return None
    return c["wall_time_s"]["median"] / n["wall_time_s"]["median"]


def fmt_count(c, k):
    v = c["counts"][k]
    if k in c["inconsistent"]:
        vals = c["inconsistent"][k]
        if isinstance(v, bool):
            return "/".join("yes" if x else "no" for x in vals) + " ⚠"
        return f"{min(vals)}–{max(vals)} ⚠"
    if isinstance(v, bool):
        return "yes" if v else "**no**"
    return str(v)


def notes_for(meta, machine, unavailable, configs):
    notes = []
    for s in unavailable:
        notes.append(
            f"`{s}`: not available in this alfe binary (`alfe run --solver {s}` exits 2: "
            f"\"--solver: expected ...\"); shown as *not available*."
        )
    for c in configs:
        tag = f"{c['scene']} / {c['solver']} / {c['ranks']} rank(s)"
        if c["status"] in ("failed", "timed out", "not run"):
            rcs = sorted({r["exit_code"] for r in c["reps"]})
            if c["status"] == "timed out":
                notes.append(f"{tag}: **timed out** after {meta.get('timeout_s', '?')} s; not repeated.")
            else:
                notes.append(f"{tag}: **{c['status']}** (exit code {', '.join(map(str, rcs)) or '–'}).")
            continue
        if c["status"] == "not available":
            continue
        if c["counts"].get("converged") is False:
            notes.append(f"{tag}: did **not converge** ({c.get('message', '')}).")
        elif c["status"] != "ok":
            notes.append(f"{tag}: run statuses {c['status']}.")
        if c["counts"].get("retries"):
            notes.append(f"{tag}: {c['counts']['retries']} step retries (step cut back and redone).")
        for k, vals in c["inconsistent"].items():
            notes.append(f"{tag}: `{k}` differs between repetitions: {vals}.")
        w = c["wall_time_s"]
        if w["spread"] > SPREAD_WARN:
            notes.append(
                f"{tag}: wall time varies {100 * w['spread']:.0f}% between repetitions "
                f"({', '.join(f'{x:.2f}' for x in w['all'])} s)."
            )
    # Block Jacobi has one block per rank: exact (one GMRES iteration) on 1 rank, not on more.
    scenes_solvers = sorted({(c["scene"], c["solver"]) for c in configs})
    for scene, solver in scenes_solvers:
        by_rank = {
            c["ranks"]: c["counts"]
            for c in configs
            if c["scene"] == scene and c["solver"] == solver and "counts" in c
        }
        if len(by_rank) < 2:
            continue
        r0 = min(by_rank)
        for r, cnt in sorted(by_rank.items()):
            a, b = by_rank[r0]["linear_iterations"], cnt["linear_iterations"]
            if r > r0 and a and b > 3 * a:
                per_a = a / max(by_rank[r0]["nonlinear_iterations"], 1)
                per_b = b / max(cnt["nonlinear_iterations"], 1)
                notes.append(
                    f"{scene} / {solver}: {b / a:.0f}× the linear iterations on {r} ranks as on {r0} "
                    f"({per_b:.1f} vs {per_a:.1f} GMRES iterations per nonlinear iteration): the block-Jacobi "
                    f"preconditioner has one block per rank, so on one rank it solves exactly with the matrix it was built from, and on more ranks it "
                    f"drops the coupling between the ranks' blocks."
                )
    rss_var = []
    for c in configs:
        rss = c.get("peak_rss_mb_all") or []
        if len(rss) > 1 and max(rss) > 1.25 * min(rss):
            rss_var.append(f"{c['scene']}/{c['solver']}/{c['ranks']}: {min(rss):.0f}–{max(rss):.0f}")
    if rss_var:
        notes.append(
            "Peak RSS varies a lot between identical runs (MB, min–max: " + "; ".join(rss_var)
            + "): the table's median is a rough figure; compare memory only for large differences."
        )
    try:
        nproc = machine["nproc"] or 1
        loads = [float(x) for x in (machine["load_average_start"].split() + machine["load_average_end"].split())]
        if loads and max(loads) > 0.5 * nproc:
            notes.append(
                f"The machine was busy with other work (load average {machine['load_average_start']} at the "
                f"start, {machine['load_average_end']} at the end, on {nproc} cores): absolute times are "
                f"inflated and noisy; the medians and the interleaving keep the comparison fair, but "
                f"ratios within ~10–20% are within the noise."
            )
    except (ValueError, KeyError):
        pass
    return notes


def write_markdown(path, meta, machine, alfe, scenes, solvers, ranks, configs, notes, png_name):
    L = []
    L.append("# Nonlinear solver benchmark: Newton, BFGS, JFNK")
    L.append("")
    L.append(f"- date: {meta.get('started', '?')} (finished {meta.get('finished', '?')}, "
             f"{meta.get('runs_seconds', '?')} s of runs)")
    L.append(
        f"- machine: {machine['nproc']} cores ({machine['cpu']}), {machine['memory_gib']} GiB, "
        f"{machine['mpi']}; load average (1/5/15 min) {machine['load_average_start']} at the start, "
        f"{machine['load_average_end']} at the end"
    )
    c = alfe["commit"]
    line = f"- alfe: commit `{c[:10] if c else 'unknown'}`"
    if alfe.get("commit_note"):
        line += f" ({alfe['commit_note']})"
    line += f"; binary sha256 `{alfe['binary_sha256_prefix']}…`"
    L.append(line)
    L.append(f"- command: `{meta.get('cmdline', 'scripts/bench-solvers')}`")
    L.append(
        f"- method: each configuration run {meta['reps']} times, solvers interleaved within a repetition "
        f"(order rotated each repetition); **median** of alfe's own `wall_time_s` (summary.json; without "
        f"mpirun start-up); partitions computed beforehand and read from the cache; counts from "
        f"summary.json (checked identical across repetitions). `wall / Newton` is the ratio of median wall "
        f"times at the same rank count; `spread` is (max − min) / median over the repetitions; peak RSS is "
        f"the largest rank's."
    )
    L.append("")
    for scene in scenes:
        any_c = next((x for x in configs if x["scene"] == scene and "elements" in x), None)
        head = f"## {scene}"
        if any_c:
            head += f" ({any_c['elements']} elements, {any_c['unknowns']} unknowns)"
        L.append(head)
        L.append("")
        L.append(
            "| solver | ranks | converged | steps | retries | nonlinear its | linear its | residual evals "
            "| factorizations | median wall s | spread | peak RSS MB | wall / Newton |"
        )
        L.append("|---|--:|:-:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|")
        for nr in ranks:
            for solver in solvers:
                c = find(configs, scene, solver, nr)
                if c is None:
                    continue
                if "wall_time_s" not in c:
                    L.append(f"| {solver} | {nr} | *{c['status']}* |  |  |  |  |  |  |  |  |  |  |")
                    continue
                r = ratio_to_newton(configs, c)
                w = c["wall_time_s"]
                L.append(
                    f"| {solver} | {nr} | {fmt_count(c, 'converged')} | {fmt_count(c, 'steps')} | "
                    f"{fmt_count(c, 'retries')} | {fmt_count(c, 'nonlinear_iterations')} | "
                    f"{fmt_count(c, 'linear_iterations')} | {fmt_count(c, 'residual_evaluations')} | "
                    f"{fmt_count(c, 'factorizations')} | {w['median']:.2f} | {100 * w['spread']:.0f}% | "
                    f"{c['peak_rss_mb']:.0f} | {'–' if r is None else f'{r:.2f}'} |"
                )
        L.append("")
        # phase split, median seconds
        phase_keys = []
        for x in configs:
            if x["scene"] == scene:
                for k in x.get("phases_median_s", {}):
                    if k not in phase_keys:
                        phase_keys.append(k)
        if phase_keys:
            L.append("<details><summary>phases (median s)</summary>")
            L.append("")
            L.append("| solver | ranks | " + " | ".join(phase_keys) + " |")
            L.append("|---|--:|" + "--:|" * len(phase_keys))
            for nr in ranks:
                for solver in solvers:
                    c = find(configs, scene, solver, nr)
                    if c and "phases_median_s" in c:
                        L.append(
                            f"| {solver} | {nr} | "
                            + " | ".join(f"{c['phases_median_s'].get(k, 0.0):.2f}" for k in phase_keys)
                            + " |"
                        )
            L.append("")
            L.append("</details>")
            L.append("")
    L.append("## Notes")
    L.append("")
    if notes:
        L.extend(f"- {n}" for n in notes)
    else:
        L.append("- nothing unusual: all runs converged, counts identical across repetitions, spread ≤ 10%.")
    L.append("")
    L.append(f"![nonlinear iterations and wall time per solver]({png_name})")
    L.append("")
    L.append(f"Raw data (every repetition's summary.json, first repetition's history.csv): `{os.path.splitext(png_name)[0]}.json`.")
    L.append("")
    with open(path, "w") as f:
        f.write("\n".join(L))


def write_png(path, scenes, solvers, ranks, configs, alfe, meta):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colors = ["#4C72B0", "#DD8452", "#55A868", "#C44E52"]
    fig, axes = plt.subplots(len(scenes), 2, figsize=(12, 4.2 * len(scenes) + 0.8), squeeze=False)
    width = 0.8 / len(ranks)
    for si, scene in enumerate(scenes):
        for ai, (metric, ylabel) in enumerate(
            [("nonlinear_iterations", "nonlinear iterations (all steps)"), ("wall", "median wall time [s]")]
        ):
            ax = axes[si][ai]
            ymax = 0.0
            for ri, nr in enumerate(ranks):
                for xi, solver in enumerate(solvers):
                    c = find(configs, scene, solver, nr)
                    x = xi - 0.4 + width * (ri + 0.5)
                    if c is None or "wall_time_s" not in c:
                        continue
                    if metric == "wall":
                        w = c["wall_time_s"]
                        v = w["median"]
                        err = [[v - w["min"]], [w["max"] - v]] if len(w["all"]) > 1 else None
                        label = f"{v:.1f}" if v >= 10 else (f"{v:.2f}" if v >= 0.1 else f"{v:.3f}")
                        top = w["max"]
                    else:
                        v = c["counts"][metric]
                        err = None
                        label = str(v)
                        top = v
                    conv = c["counts"].get("converged") is not False
                    ax.bar(
                        x, v, width * 0.92, color=colors[ri % len(colors)], yerr=err, capsize=3,
                        hatch=None if conv else "//", edgecolor="black" if not conv else None,
                        error_kw={"elinewidth": 1, "ecolor": "#333333"},
                    )
                    if not conv:
                        label += "\nnot conv."
                    ax.annotate(label, (x, top), xytext=(0, 3), textcoords="offset points",
                                ha="center", va="bottom", fontsize=9)
                    ymax = max(ymax, top)
            ax.set_ylim(0, ymax * 1.22 if ymax > 0 else 1)
            for xi, solver in enumerate(solvers):
                missing = [find(configs, scene, solver, nr) for nr in ranks]
                if all(m is None or "wall_time_s" not in m for m in missing):
                    st = next((m["status"] for m in missing if m), "not run")
                    ax.text(xi, (ymax or 1) * 0.08, st, ha="center", va="bottom", fontsize=10,
                            color="#777777", rotation=90 if len(st) > 14 else 0)
            ax.set_xticks(range(len(solvers)))
            ax.set_xticklabels(solvers, fontsize=11)
            ax.set_xlim(-0.6, len(solvers) - 0.4)
            ax.set_ylabel(ylabel, fontsize=10)
            ax.set_title(f"{scene}: {'nonlinear iterations' if metric != 'wall' else 'wall time'}",
                         fontsize=12)
            ax.grid(axis="y", alpha=0.3)
            ax.set_axisbelow(True)
    from matplotlib.patches import Patch

    handles = [Patch(color=colors[i % len(colors)], label=f"{nr} rank{'s' if nr > 1 else ''}")
               for i, nr in enumerate(ranks)]
    fig.legend(handles=handles, loc="upper right", ncol=len(ranks), fontsize=10, frameon=False)
    commit = alfe["commit"][:10] if alfe["commit"] else "unknown"
    fig.suptitle(
        f"alfe nonlinear solvers — median of {meta['reps']} runs (error bars: min–max), "
        f"commit {commit}, {meta.get('started', '')[:10]}",
        fontsize=12, x=0.02, ha="left",
    )
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--work", required=True)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    meta, scenes, solvers, ranks, unavailable, configs = collect(a.work)
    machine = machine_info(meta)
    alfe = alfe_info(meta)
    notes = notes_for(meta, machine, unavailable, configs)
    os.makedirs(a.out, exist_ok=True)
    md = os.path.join(a.out, "bench-solvers.md")
    js = os.path.join(a.out, "bench-solvers.json")
    png = os.path.join(a.out, "bench-solvers.png")
    raw = {
        "command": meta.get("cmdline"),
        "started": meta.get("started"),
        "finished": meta.get("finished"),
        "runs_seconds": int(meta["runs_seconds"]) if meta.get("runs_seconds") else None,
        "reps": int(meta["reps"]),
        "machine": machine,
        "alfe": alfe,
        "scenes": scenes,
        "solvers": solvers,
        "ranks": ranks,
        "unavailable_solvers": unavailable,
        "notes": notes,
        "configs": configs,
    }
    with open(js, "w") as f:
        json.dump(raw, f, indent=1)
        f.write("\n")
    write_png(png, scenes, solvers, ranks, configs, alfe, meta)
    write_markdown(md, meta, machine, alfe, scenes, solvers, ranks, configs, notes, os.path.basename(png))
    print(f"bench-solvers: wrote {md}, {js}, {png}")
    for n in notes:
        print(f"bench-solvers: note: {n}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
