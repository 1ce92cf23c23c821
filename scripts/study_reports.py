"""The per-scene analyses of `scripts/study --plan NAME` (the plans in scripts/studies/).

A plan is data: the scene, its deck edits and the configurations to run. What each
scene's study measures from a run (the impactor's peak force, the bolt forces after
locking, the sphere's moment about its centre, the force error against the ALM run...)
and how it draws it is particular to the scene, so it lives here: one function per plan,
named by the plan's `report`, called with the finished runs. Each writes the tables, JSON
and chart the former `scripts/<scene>-study` wrote, under the same names.

A run (`Run` in scripts/study) has `cfg` (the plan's values for it, as written: solver,
contact, ranks, ...), `tag`, `code` (exit code, None on a timeout), `err` (alfe's last
error line), `summ` (summary.json) and `rows` (history.csv rows).
"""

import json
import os
import time

import alfe_run
from alfe_run import fmt, md_table


def _f(r, k):
    return float(r[k])


def _write(path, lines):
    with open(path, "w") as fh:
        fh.write("\n".join(lines) + "\n")
    print("\n".join(lines))


def _stopped(runs, label):
    return [f"\n{label(r)}: {r['failure']}" for r in runs if not r["finished"]]


# --- b-pillar (the paper's §3.4) --------------------------------------------------------------

def b_pillar(runs, out, ctx):
    recs = []
    for run in runs:
        summ, rows, code, err = run.summ, run.rows, run.code, run.err
        if not summ and rows:
            # Killed (a time limit) before it wrote its summary: the history's sums
            # (converged steps only: failed attempts are not in it).
            summ = {"steps": len(rows) - 1,
                    "nonlinear_iterations": sum(int(r["nonlinear_iterations"]) for r in rows),
                    "retries": sum(int(r["retries"]) for r in rows),
                    "linear_iterations": sum(int(r["linear_iterations"]) for r in rows),
                    "wall_time_s": sum(_f(r, "wall_time_s") for r in rows)}
            code, err = 3, err or "killed before it finished (time limit); counts from history.csv"
        d = [-_f(r, "impactor.uz") for r in rows]
        # The wall columns are the force the body exerts on the wall: up on the impactor.
        force = [4.0 * _f(r, "impactor.fz") for r in rows]
        k = max(range(len(force)), key=lambda i: force[i]) if force else None
        recs.append({
            "solver": run.cfg["solver"], "ranks": run.cfg["ranks"], "finished": code == 0,
            "failure": None if code == 0 else err,
            "reached_mm": d[-1] if d else 0.0, "increments": summ.get("steps", len(rows)),
            "iterations": summ.get("nonlinear_iterations"), "retries": summ.get("retries"),
            "gmres": summ.get("linear_iterations"), "wall_s": summ.get("wall_time_s"),
            "peak_force_N": force[k] if force else None, "peak_at_mm": d[k] if force else None,
            "trace": list(zip(d, force)),
        })
    with open(os.path.join(out, "b-pillar.json"), "w") as fh:
        json.dump(recs, fh, indent=1)
    lines = md_table(
        ["solver", "ranks", "reached mm (of 100)", "increments", "iterations", "retries", "GMRES",
         "wall s", "peak force kN (at mm)"],
        [[r["solver"], r["ranks"], f"{r['reached_mm']:.1f}" + ("" if r["finished"] else " (stopped)"),
          r["increments"], r["iterations"], r["retries"], r["gmres"], fmt(r["wall_s"], ".1f"),
          f"{fmt(r['peak_force_N'] and r['peak_force_N'] / 1e3, '.2f')} ({fmt(r['peak_at_mm'], '.1f')})"]
         for r in recs])
    lines += _stopped(recs, lambda r: r["solver"])
    _write(os.path.join(out, "b-pillar.md"), lines)
    plt = alfe_run.pyplot()
    if plt is None:
        return
    fig, ax = plt.subplots(figsize=(7, 5))
    for r in recs:
        if r["trace"]:
            ax.plot([p[0] for p in r["trace"]], [p[1] / 1e3 for p in r["trace"]], marker=".",
                    ms=3, label=r["solver"])
    ax.set_xlabel("impactor displacement (mm)")
    ax.set_ylabel("impactor force (kN, whole pillar)")
    ax.set_title("b-pillar three-point bending")
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(out, "b-pillar.png"), dpi=110)


# --- bolted-bracket (the paper's §3.7) --------------------------------------------------------

BOLTS = [f"bolt{i}" for i in range(1, 5)]


def bolted_bracket(runs, out, ctx):
    recs = []
    for run in runs:
        summ, rows, code, err = run.summ, run.rows, run.code, run.err
        t = [_f(r, "time") for r in rows]
        vm = [_f(r, "bracket.max_von_mises") for r in rows]
        k_peak = max(range(len(vm)), key=lambda k: vm[k]) if vm else None
        at_lock = next((r for r in rows if abs(_f(r, "time") - 1.0) < 1e-9), None)
        after = [r for r in rows if _f(r, "time") > 1.0 + 1e-9]
        recs.append({
            "solver": run.cfg["solver"], "contact": run.cfg["contact"], "ranks": run.cfg["ranks"],
            "finished": code == 0, "failure": None if code == 0 else err,
            "end_time": t[-1] if t else 0.0, "increments": len(rows),
            "iterations": summ.get("nonlinear_iterations"), "retries": summ.get("retries"),
            "gmres": summ.get("linear_iterations"), "wall_s": summ.get("wall_time_s"),
            "by_step": [{k: s.get(k) for k in ("name", "increments", "nonlinear_iterations",
                                                "retries", "linear_iterations", "completed")}
                        for s in summ.get("analysis_steps", [])],
            "peak_von_mises": vm[k_peak] if vm else None,
            "peak_at": t[k_peak] if vm else None,
            "bolt_force_at_lock": {b: _f(at_lock, f"{b}.force") for b in BOLTS} if at_lock else {},
            "bolt_force_after_lock": {b: [min(_f(r, f"{b}.force") for r in after),
                                          max(_f(r, f"{b}.force") for r in after)]
                                      for b in BOLTS} if after else {},
            "max_penetration": max((_f(r, "max_penetration") for r in rows), default=None),
            "joint_max_slip": max((_f(r, "joint.max_slip") for r in rows), default=None),
            "trace": [[_f(r, "time"), _f(r, "bracket.max_von_mises")]
                      + [_f(r, f"{b}.force") for b in BOLTS] for r in rows],
        })
    with open(os.path.join(out, "bolted-bracket.json"), "w") as fh:
        json.dump(recs, fh, indent=1)
    rows = []
    for r in recs:
        by = " / ".join(str(s["nonlinear_iterations"]) for s in r["by_step"])
        rows.append([
            r["solver"], r["contact"], r["ranks"],
            f"{r['end_time']:.3f}" + ("" if r["finished"] else " (stopped)"), r["increments"],
            f"{r['iterations']} ({by})", r["retries"], r["gmres"], fmt(r["wall_s"], ".1f"),
            f"{fmt(r['peak_von_mises'], '.2f')} ({fmt(r['peak_at'], '.3g')})",
            ", ".join(f"{v:.6f}" for v in r["bolt_force_at_lock"].values()),
            ", ".join(f"{lo:.0f}…{hi:.0f}" for lo, hi in r["bolt_force_after_lock"].values()),
            fmt(r["max_penetration"], ".1e"), fmt(r["joint_max_slip"], ".2e")])
    lines = md_table(["solver", "contact", "ranks", "reached t (of 3)", "increments",
                      "iterations (pretension / X / Y)", "retries", "GMRES", "wall s",
                      "peak von Mises MPa (t)", "bolt forces at lock N",
                      "bolt force range after lock N", "max penetration mm", "joint max slip mm"],
                     rows)
    lines += _stopped(recs, lambda r: f"{r['solver']}/{r['contact']} on {r['ranks']} rank(s)")
    # Rank independence: the deck's run on 1 rank against the same on the study's ranks
    # (those of the first configuration).
    many_ranks = recs[0]["ranks"] if recs else None
    one = next((r for r in recs if r["ranks"] == 1 and r["finished"]), None)
    # The 1-rank run's increments differ from the 2-rank run's where a step is cut on
    # one and not the other (JFNK's preconditioner depends on the partition); with
    # friction the answers then differ by the path, not by round-off.
    many = next((r for r in recs if r["ranks"] == many_ranks and r["solver"] == "jfnk"
                 and r["contact"] == "alm" and r["finished"]), None)
    if one and many:
        common = {p[0]: p for p in many["trace"]}
        diffs = [max(abs(p[k] - common[p[0]][k]) / max(abs(common[p[0]][k]), 1.0)
                     for k in range(1, 6)) for p in one["trace"] if p[0] in common]
        if diffs:
            lines.append(f"\n1 vs {many_ranks} ranks (jfnk, alm): {len(diffs)} common times, "
                         f"largest relative difference of the peak stress and bolt forces "
                         f"{max(diffs):.1e}")
    _write(os.path.join(out, "bolted-bracket.md"), lines)
    plt = alfe_run.pyplot()
    if plt is None:
        return
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 5))
    for r in recs:
        tr = r["trace"]
        if not tr or r["ranks"] != many_ranks:
            continue
        lab = f"{r['solver']}, {r['contact']}"
        ax2.plot([p[0] for p in tr], [p[1] for p in tr], "-" if r["contact"] == "alm" else "--",
                 marker=".", label=lab)
        if r["solver"] == "jfnk" and r["contact"] == "alm":
            for i, b in enumerate(BOLTS):
                ax1.plot([p[0] for p in tr], [p[2 + i] for p in tr], marker=".", label=b)
    for ax in (ax1, ax2):
        for x in (1.0, 2.0):
            ax.axvline(x, color="0.7", lw=0.8)
        ax.set_xlabel("t (pretension | load X out and back | load Y out and back)")
    ax1.set_ylabel("bolt force (N)"); ax1.set_title("bolt forces (jfnk, alm)"); ax1.legend(fontsize=7)
    ax2.set_ylabel("largest element von Mises stress in the bracket (MPa)")
    ax2.set_title("bracket peak stress"); ax2.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "bolted-bracket.png"), dpi=110)


# --- cylinder-press refined (issue 11) --------------------------------------------------------

def cylinder(runs, out, ctx):
    nx, ny, nz = ctx.plan["base_cells"]
    recs = []
    for run in runs:
        summ, rows, level = run.summ, run.rows, run.cfg["level"]
        last = rows[-1] if rows else {}
        recs.append({
            "level": level, "cells": [nx * level, ny, nz * level],
            "unknowns": summ.get("unknowns"), "solver": run.cfg["solver"],
            "ranks": run.cfg["ranks"], "finished": run.code == 0,
            "failure": None if run.code == 0 else run.err,
            "end_time": float(last["time"]) if last else 0.0,
            "force": float(last["roller.fz"]) if last else float("nan"),
            "max_penetration": max((float(r["max_penetration"]) for r in rows), default=float("nan")),
            "nonlinear_iterations": summ.get("nonlinear_iterations"),
            "retries": summ.get("retries"),
            "wall_s": summ.get("wall_time_s", run.elapsed),
        })
        r = recs[-1]
        print(f"level {level} ({'×'.join(map(str, r['cells']))}), {r['solver']}, {r['ranks']} "
              f"rank(s): " + (f"{r['force']:.4f} N/mm in {r['wall_s']:.1f} s" if r["finished"]
                              else f"stopped at t = {r['end_time']:.4g}: {r['failure']}"),
              flush=True)
    with open(os.path.join(out, "cylinder-study.json"), "w") as f:
        json.dump(recs, f, indent=1)
    rows, prev = [], {}
    for r in recs:
        key = (r["solver"], r["ranks"])
        change = ""
        if key in prev and r["finished"] and prev[key]["finished"]:
            change = "%+.3f %%" % (100 * (r["force"] / prev[key]["force"] - 1))
        prev[key] = r
        rows.append([r["level"], "×".join(map(str, r["cells"])), r["unknowns"],
                     r["solver"] + ("" if r["ranks"] == 1 else f" ({r['ranks']} ranks)"),
                     "yes" if r["finished"] else f"no: {r['failure']}", "%.4f" % r["force"],
                     change, "%.1e" % r["max_penetration"], r["nonlinear_iterations"],
                     r["retries"], "%.1f" % r["wall_s"]])
    lines = [f"# cylinder-press refined: force per mm by mesh and solver\n\n`{ctx.command}`\n"]
    lines += md_table(["level", "cells", "unknowns", "solver", "finished", "force (N/mm)",
                       "change", "max penetration (mm)", "iterations", "retries", "wall (s)"], rows)
    _write(os.path.join(out, "cylinder-study.md"), lines)


# --- rubber-indent (the paper's §3.3) ---------------------------------------------------------

def _interp(x, xs, ys):
    if not xs or x > xs[-1] + 1e-9:
        return None
    px, py = 0.0, 0.0
    for a, b in zip(xs, ys):
        if a >= x - 1e-12:
            return py + (b - py) * (x - px) / (a - px) if a > px else b
        px, py = a, b
    return None


def indent(runs, out, ctx):
    depth, marks = ctx.plan["depth_mm"], ctx.plan["marks_mm"]
    recs = []
    for run in runs:
        summ, rows, code = run.summ, run.rows, run.code
        c = run.cfg
        xs = [depth * float(r["time"]) for r in rows]
        fs = [float(r["indenter.fz"]) for r in rows]
        ok = summ.get("converged", code == 0)
        recs.append({
            "run": f"{c['contact']}:{c['solver']}:{c['ranks']}", "method": c["contact"],
            "solver": c["solver"], "ranks": int(c["ranks"]),
            "finished": bool(ok),
            "failure": (summ.get("message") or run.err) if not ok else None,
            "reached_mm": xs[-1] if xs else 0.0,
            "steps": len(rows),
            # summary.json counts failed attempts too (history rows only converged steps)
            **{k: summ.get(k, sum(int(r[k]) for r in rows)) for k in
               ("nonlinear_iterations", "linear_iterations", "retries", "factorizations")},
            "wall_s": summ.get("wall_time_s", run.elapsed),
            "max_penetration": max((float(r["max_penetration"]) for r in rows), default=None),
            "force": {str(m): _interp(m, xs, fs) for m in marks},
            "curve": [xs, fs],
        })
        r = recs[-1]
        print(f"{r['run']}: " + (f"finished in {fmt(r['wall_s'], '.1f', '?')} s, "
                                 f"{r['nonlinear_iterations']} iterations" if r["finished"] else
                                 f"stopped at {r['reached_mm']:.2f} mm: {r['failure']}"),
              flush=True)
    with open(os.path.join(out, "indent-study.json"), "w") as f:
        json.dump(recs, f, indent=1)
    rows = [[r["run"], f"{r['reached_mm']:.2f}", r["nonlinear_iterations"], r["linear_iterations"],
             r["retries"], r["factorizations"], fmt(r["wall_s"], ".0f", "–"),
             fmt(r["max_penetration"], ".1e", "–")]
            + [fmt(r["force"][str(m)], ".1f", "–") for m in marks] for r in recs]
    lines = [f"# rubber-indent: every solver, ALM and penalty\n\n`{ctx.command}`\n"]
    lines += md_table(["run", "reached (mm)", "iterations", "GMRES", "retries", "factorizations",
                       "wall (s)", "max penetration (mm)"] + [f"F at {m} mm (N)" for m in marks],
                      rows)
    _write(os.path.join(out, "indent-study.md"), lines)
    plt = alfe_run.pyplot()
    if plt is None:
        print("no chart: matplotlib is missing")
        return
    fig, ax = plt.subplots(figsize=(7, 4.5))
    styles = {"newton": "-", "bfgs": "--", "jfnk": ":", "auto": "-."}
    for r in recs:
        xs, fs = r["curve"]
        ax.plot(xs, fs, styles.get(r["solver"], "-"),
                color="tab:red" if r["method"] == "penalty" else
                ("tab:blue" if r["ranks"] == 1 else "tab:green"),
                marker="o" if r["method"] == "penalty" else None, markersize=3,
                label=f"{r['method']} {r['solver']} ({r['ranks']} rank{'s' if r['ranks'] > 1 else ''})")
    ax.set_xlabel("indentation (mm)")
    ax.set_ylabel("indenter force, quarter model (N)")
    ax.set_title("rubber-indent (paper §3.3): force against indentation")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "indent-study.png"), dpi=120)


# --- panel-dent (the paper's §3.6) ------------------------------------------------------------

def panel_dent(runs, out, ctx):
    recs = []
    for run in runs:
        summ, rows, code = run.summ, run.rows, run.code
        curve = [[-_f(r, "indenter.uy"), _f(r, "indenter.fy")] for r in rows]
        peak = max((p[1] for p in curve), default=None)
        k1 = max(range(len(curve)), key=lambda i: curve[i][0]) if curve else None
        release = next((curve[i][0] for i in range(k1, len(curve)) if curve[i][1] == 0.0),
                       None) if curve else None
        recs.append({
            "indenter": run.cfg["kind"], "solver": run.cfg["solver"], "ranks": run.cfg["ranks"],
            "finished": code == 0, "failure": None if code == 0 else run.err,
            "end_time": _f(rows[-1], "time") if rows else 0.0, "steps": len(rows),
            "iterations": summ.get("nonlinear_iterations"), "retries": summ.get("retries"),
            "gmres": summ.get("linear_iterations"), "wall_s": summ.get("wall_time_s"),
            "linear_s": sum(_f(r, "linear_s") for r in rows),
            "peak_force": peak, "release_at": release,
            "max_penetration": max((_f(r, "max_penetration") for r in rows), default=None),
            "curve": curve,
        })
    with open(os.path.join(out, "panel-dent.json"), "w") as fh:
        json.dump(recs, fh, indent=1)
    lines = md_table(
        ["indenter", "solver", "ranks", "reached t (of 2)", "steps", "iterations", "retries",
         "GMRES", "wall s", "linear s", "peak force N", "released at mm", "max penetration mm"],
        [[r["indenter"], r["solver"], r["ranks"],
          f"{r['end_time']:.3f}" + ("" if r["finished"] else " (stopped)"), r["steps"],
          r["iterations"], r["retries"], r["gmres"], fmt(r["wall_s"], ".1f"),
          fmt(r["linear_s"], ".1f"), fmt(r["peak_force"], ".1f"), fmt(r["release_at"], ".2f"),
          fmt(r["max_penetration"], ".1e")] for r in recs])
    lines += _stopped(recs, lambda r: f"{r['indenter']} {r['solver']} on {r['ranks']} rank(s)")
    _write(os.path.join(out, "panel-dent.md"), lines)
    plt = alfe_run.pyplot()
    if plt is None:
        return
    fig, ax = plt.subplots(figsize=(7, 5))
    for r in recs:
        if r["curve"]:
            ax.plot([p[0] for p in r["curve"]], [4 * p[1] for p in r["curve"]],
                    "-" if r["indenter"] == "entity" else "--",
                    label=f"{r['indenter']}, {r['solver']}, {r['ranks']} rank(s)")
    ax.set_xlabel("indentation (mm)")
    ax.set_ylabel("force on the indenter, whole panel (N)")
    ax.set_title("panel-dent: loading and unloading")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "panel-dent.png"), dpi=110)


# --- penalty against ALM (issue 11) -----------------------------------------------------------

def _force_error(f, ref):
    keys = sorted(ref)
    if not keys or any(k not in f for k in keys):
        return float("nan")
    d = sum((f[k] - ref[k]) ** 2 for k in keys) ** 0.5
    n = sum(ref[k] ** 2 for k in keys) ** 0.5
    return d / n if n > 0 else float("nan")


def penalty(runs, out, ctx):
    hertz = ctx.plan["hertz_quarter_N"]
    results, ref = [], None
    for run in runs:
        summ, rows, code = run.summ, run.rows, run.code
        scale = None if run.cfg["scale"] == "alm" else float(run.cfg["scale"])
        last = rows[-1] if rows else {}
        force = {k: float(v) for k, v in last.items()
                 if k.split(".")[-1] in ("fx", "fy", "fz") and k.split(".")[0] in summ.get("walls", {})}
        r = {
            "scene": run.cfg["scene"], "scale": scale, "solver": run.cfg["solver"],
            "converged": code == 0, "failure": None if code == 0 else run.err,
            "end_time": float(last["time"]) if last else 0.0,
            "steps": len(rows),
            "nonlinear_iterations": sum(int(r["nonlinear_iterations"]) for r in rows),
            "retries": sum(int(r["retries"]) for r in rows),
            "wall_s": summ.get("wall_time_s", run.elapsed),
            "max_penetration": max((float(r.get("max_penetration", 0) or 0) for r in rows),
                                   default=float("nan")),
            "force": force,
        }
        if scale is None:
            ref = r
            r["force_error"] = 0.0
            print(f"{r['scene']} alm: {r['wall_s']:.1f} s, F = {r['force']}", flush=True)
        else:
            r["force_error"] = _force_error(force, ref["force"]) \
                if r["converged"] and ref and ref["scene"] == r["scene"] else float("nan")
            print(f"{r['scene']} penalty {scale:g}: error {r['force_error']:.3e}, pen "
                  f"{r['max_penetration']:.3e}, {r['wall_s']:.1f} s, {r['nonlinear_iterations']} "
                  f"its, {r['retries']} retries"
                  f"{'' if r['converged'] else ' FAILED: ' + str(r['failure'])}", flush=True)
        results.append(r)
    solver = results[0]["solver"] if results else None
    with open(os.path.join(out, "penalty-study.json"), "w") as f:
        json.dump({"solver": solver, "command": ctx.command,
                   "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
                   "load": os.getloadavg(), "runs": results}, f, indent=1)
    rows = []
    for r in results:
        hz = ""
        if r["scene"] == "hertz-sphere" and r["converged"]:
            fz = abs(r["force"].get("sphere.fz", float("nan")))
            hz = f"{100 * (fz / hertz - 1):+.2f} %"
        rows.append([r["scene"], "alm" if r["scale"] is None else "penalty",
                     "" if r["scale"] is None else format(r["scale"], "g"),
                     "yes" if r["converged"] else "**no**", r["steps"], r["nonlinear_iterations"],
                     r["retries"], f"{r['wall_s']:.1f}", f"{r['max_penetration']:.2e}",
                     f"{r['force_error']:.2e}", hz])
    lines = [
        "# Penalty against ALM: force error, penetration and cost vs `penalty_scale`", "",
        f"- command: `{ctx.command}`; solver {solver}, 1 rank, one run each"
        f" (wall times indicative; load {os.getloadavg()[0]:.2f} at the end)",
        "- force error: ‖F − F_alm‖/‖F_alm‖ over every wall force component at the end;"
        f" hertz-sphere also vs Hertz ({hertz} N)", ""]
    lines += md_table(["scene", "contact", "scale", "converged", "steps", "its", "retries",
                       "wall s", "max pen. (mm)", "force error", "vs Hertz"], rows,
                      ["---", "---", "--:", ":-:", "--:", "--:", "--:", "--:", "--:", "--:", "--:"])
    with open(os.path.join(out, "penalty-study.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    plt = alfe_run.pyplot()
    if plt is None:
        return
    scenes = list(dict.fromkeys(r["scene"] for r in results))
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.5))
    for scene in scenes:
        pen = [r for r in results if r["scene"] == scene and r["scale"] is not None and r["converged"]]
        alm = [r for r in results if r["scene"] == scene and r["scale"] is None]
        ax[0].loglog([r["scale"] for r in pen], [r["force_error"] for r in pen], "o-", label=scene)
        ax[1].loglog([r["scale"] for r in pen], [r["max_penetration"] for r in pen], "o-", label=scene)
        line, = ax[2].loglog([r["wall_s"] for r in pen], [r["force_error"] for r in pen], "o-",
                             label=f"{scene} penalty")
        for r in pen:
            ax[2].annotate(f"{r['scale']:g}", (r["wall_s"], r["force_error"]), fontsize=7)
        if alm and alm[0]["converged"]:
            ax[2].axvline(alm[0]["wall_s"], color=line.get_color(), ls=":", label=f"{scene} ALM (error 0)")
    ax[0].set(xlabel="penalty_scale", ylabel="force error vs ALM", title="accuracy")
    ax[1].set(xlabel="penalty_scale", ylabel="max penetration (mm)", title="penetration (ALM: ~1e-12)")
    ax[2].set(xlabel="wall time (s)", ylabel="force error vs ALM", title="speed vs accuracy (labels: scale)")
    for a in ax:
        a.grid(True, which="both", alpha=0.3)
        a.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "penalty-study.png"), dpi=110)
    print(f"wrote {out}/penalty-study.{{md,json,png}}")


# --- sphere-roll (the paper's §3.5) -----------------------------------------------------------

def sphere_roll(runs, out, ctx):
    radius = ctx.plan["radius_mm"]
    recs = []
    for run in runs:
        summ, rows, code = run.summ, run.rows, run.code
        moment = max((max(abs(_f(r, m)) for m in ("sphere.mx", "sphere.my", "sphere.mz"))
                      / max(_f(r, "sphere.fz") * radius, 1e-300) for r in rows), default=None)
        last = rows[-1] if rows else {}
        recs.append({
            "solver": run.cfg["solver"], "ranks": run.cfg["ranks"], "finished": code == 0,
            "failure": None if code == 0 else run.err,
            "end_time": _f(last, "time") if rows else 0.0, "steps": len(rows),
            "iterations": summ.get("nonlinear_iterations"),
            "retries": summ.get("retries"), "gmres": summ.get("linear_iterations"),
            "wall_s": summ.get("wall_time_s"),
            "max_penetration": max((_f(r, "max_penetration") for r in rows), default=None),
            "max_moment_over_FR": moment,
            "final": {k: _f(last, k) for k in (
                "sphere.fx", "sphere.fy", "sphere.fz", "sphere.rx", "sphere.ry", "sphere.rz",
                "sphere.pole.x", "sphere.pole.y", "sphere.pole.z")} if rows else {},
            "trace": [[_f(r, "time"), _f(r, "sphere.ux"), _f(r, "sphere.uy"),
                       _f(r, "sphere.pole.x"), _f(r, "sphere.pole.y"), _f(r, "sphere.fx"),
                       _f(r, "sphere.fy"), _f(r, "sphere.fz")] for r in rows],
        })
    with open(os.path.join(out, "sphere-roll.json"), "w") as fh:
        json.dump(recs, fh, indent=1)
    rows = []
    for r in recs:
        fin = r["final"]
        rot = ", ".join(f"{fin[k]:.4f}" for k in ("sphere.rx", "sphere.ry", "sphere.rz")) if fin else ""
        pole = ", ".join(f"{fin[k]:.2f}" for k in ("sphere.pole.x", "sphere.pole.y", "sphere.pole.z")) if fin else ""
        rows.append([r["solver"], r["ranks"],
                     f"{r['end_time']:.3f}" + ("" if r["finished"] else " (stopped)"), r["steps"],
                     r["iterations"], r["retries"], r["gmres"], fmt(r["wall_s"], ".1f"),
                     fmt(r["max_penetration"], ".1e"), fmt(r["max_moment_over_FR"], ".1e"),
                     rot, pole])
    lines = md_table(["solver", "ranks", "reached t (of 2)", "steps", "iterations", "retries",
                      "GMRES", "wall s", "max penetration mm", "max moment / F R",
                      "final rotation (rx, ry, rz) rad", "final pole (x, y, z) mm"], rows)
    lines += _stopped(recs, lambda r: f"{r['solver']} on {r['ranks']} rank(s)")
    _write(os.path.join(out, "sphere-roll.md"), lines)
    plt = alfe_run.pyplot()
    if plt is None:
        return
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 5))
    for r in recs:
        tr = r["trace"]
        if not tr:
            continue
        lab = f"{r['solver']}, {r['ranks']} rank(s)"
        ax1.plot([p[3] for p in tr], [p[4] for p in tr], label=f"pole, {lab}")
        ax2.plot([p[0] for p in tr], [p[7] for p in tr], label=f"fz, {lab}")
        ax2.plot([p[0] for p in tr], [(p[5] ** 2 + p[6] ** 2) ** 0.5 for p in tr], "--",
                 label=f"|fxy|, {lab}")
    tr = next((r["trace"] for r in recs if r["finished"]), None)
    if tr:
        ax1.plot([p[1] for p in tr], [p[2] for p in tr], "k:", label="centre (prescribed)")
    ax1.set_xlabel("x (mm)"); ax1.set_ylabel("y (mm)"); ax1.set_aspect("equal")
    ax1.set_title("north pole trace (plan view)"); ax1.legend(fontsize=6)
    ax2.set_xlabel("t"); ax2.set_ylabel("force on the sphere (N)"); ax2.set_yscale("log")
    ax2.set_title("contact force"); ax2.legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "sphere-roll.png"), dpi=110)
