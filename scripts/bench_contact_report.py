#!/usr/bin/python3
"""Report for scripts/bench-contact: reads the run directories it left in --work
(meta.env, runs.tsv, decks/<scene>.toml, runs/<scene>/<contact>/<solver>/out/{summary.json,
history.csv}) and writes into --out: <scene>.png (reaction force curves, ALM vs penalty, and
the explicit reference for taylor-bar), bench-contact.md (table) and bench-contact.json (raw)."""

import argparse
import csv
import json
import math
import os
import platform
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from alfe_run import alfe_info as _alfe_info, cpu_name, mpi_version  # noqa: E402
from alfe_run import read_history, read_meta  # noqa: E402,F401

try:
    import tomllib
except ImportError:  # Python < 3.11
    tomllib = None

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

SOLVER_ORDER = ["newton", "bfgs", "jfnk", "-"]
CONTACT_ORDER = ["alm", "penalty", "explicit", "-"]
COLORS = {"alm": "tab:blue", "penalty": "tab:red", "explicit": "0.25"}
STYLES = {"newton": dict(ls="-", lw=1.8), "bfgs": dict(ls="--", lw=1.2), "jfnk": dict(ls=":", lw=1.6)}
EXPLICIT_WINDOW = 0.5e-6  # s: the explicit wall force is averaged over windows this long


# --- what is plotted per scene ------------------------------------------------------------------
# Sign conventions (checked on the runs): `<wall>.f*` is the force the body exerts on the wall.
# taylor-bar: the bar pushes the wall towards -z (wall.fz < 0); rubber-indent: the block pushes
# the indenter up (indenter.fz > 0); clip-tensile: the ring holds the upper pin back
# (upper_pin.fy < 0); sliding-block: the floor moving +x is dragged back (floor.fx < 0) and
# pressed down (floor.fz < 0).
def col(row, key):
    v = row.get(key)
    return v if isinstance(v, (int, float)) else math.nan


SCENES = {
    "taylor-bar": dict(
        title="taylor-bar: copper bar at 227 m/s on a rigid wall (quarter model ×4)",
        xlabel="time (µs)",
        ylabel="wall force −4·wall.fz (kN)",
        x=lambda r: col(r, "time") * 1e6,
        y=lambda r: -4.0 * col(r, "wall.fz") / 1e3,
        unit="kN",
        x_unit="µs",
        zoom=(0.0, 12.0),
    ),
    "rubber-indent": dict(
        title="rubber-indent: prismatic indenter into Mooney–Rivlin block, μ = 0.1 (quarter model ×4)",
        xlabel="indentation −indenter.uz (mm)",
        ylabel="indentation force 4·indenter.fz (kN)",
        x=lambda r: -col(r, "indenter.uz"),
        y=lambda r: 4.0 * col(r, "indenter.fz") / 1e3,
        unit="kN",
        x_unit="mm",
    ),
    "clip-tensile": dict(
        title="clip-tensile: ring clip pulled by the upper pin, μ = 0.2 (quarter model ×4)",
        xlabel="pin displacement upper_pin.uy (mm)",
        ylabel="pulling force −4·upper_pin.fy (N)",
        x=lambda r: col(r, "upper_pin.uy"),
        y=lambda r: -4.0 * col(r, "upper_pin.fy"),
        unit="N",
        x_unit="mm",
    ),
    "sliding-block": dict(
        title="sliding-block: block dragged on a rigid floor (half model, y = 0 symmetry)",
        xlabel="floor displacement floor.ux (mm)",
        ylabel="force on the floor (N)",
        x=lambda r: col(r, "floor.ux"),
        y=lambda r: -col(r, "floor.fx"),
        unit="N",
        x_unit="mm",
        ylabel_short="−floor.fx",
        # second curve per run: the Coulomb limit mu·N
        y2=lambda r, mu: -mu * col(r, "floor.fz"),
        y2_label="−μ·floor.fz",
        wall="floor",
    ),
    "hertz-sphere": dict(
        title="hertz-sphere: rigid sphere pressed on an elastic body (raw wall force, no symmetry factor)",
        xlabel="sphere approach |sphere.uz| (mm)",
        ylabel="|sphere.fz| (N)",
        x=lambda r: abs(col(r, "sphere.uz")),
        y=lambda r: abs(col(r, "sphere.fz")),
        unit="N",
        x_unit="mm",
    ),
}


def generic_spec(scene, wall):
    """For a scene without a spec: |force| of its first wall vs time."""
    return dict(
        title=f"{scene}: |{wall} force| vs time (raw, no symmetry factor)",
        xlabel="time",
        ylabel=f"|{wall}.f| (N)",
        x=lambda r: col(r, "time"),
        y=lambda r: math.sqrt(sum(col(r, f"{wall}.f{c}") ** 2 for c in "xyz")),
        unit="N",
        x_unit="",
    )


# --- reading ------------------------------------------------------------------------------------
def read_deck(path):
    if tomllib is None or not os.path.exists(path):
        return None
    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except Exception:  # noqa: BLE001 - a deck we cannot parse only costs the extra notes
        return None


def wall_friction(deck, wall):
    for w in (deck or {}).get("walls", []):
        if w.get("name") == wall:
            return float(w.get("friction", 0.0))
    return None


def shorten(msg, n=90):
    if not msg:
        return ""
    m = re.match(r"step (\d+) \(t = ([0-9.eE+-]+)\) did not converge: ([^(;:]+)", msg)
    if m:
        return f"step {m.group(1)} (t = {float(m.group(2)):.4g}) did not converge: {m.group(3).strip()}"
    msg = " ".join(msg.split())
    return msg if len(msg) <= n else msg[: n - 1] + "…"


def last_line(path):
    try:
        with open(path) as f:
            lines = [ln.strip() for ln in f if ln.strip() and not ln.startswith("-")]
    except OSError:
        return ""
    alfe_lines = [ln for ln in lines if ln.startswith("alfe")]
    return (alfe_lines or lines or [""])[-1]


def collect(work, meta):
    runs = []
    with open(os.path.join(work, "runs.tsv"), newline="") as f:
        for r in csv.DictReader(f, delimiter="\t"):
            runs.append(r)
    decks = {}
    out = []
    timeout_s = meta.get("timeout_s", "?")
    for r in runs:
        scene = r["scene"]
        if scene not in decks:
            decks[scene] = read_deck(os.path.join(work, "decks", f"{scene}.toml"))
        run = {
            "scene": scene,
            "contact": r["contact"],
            "solver": r["solver"],
            "ranks": int(r["ranks"]),
            "status": r["status"],
            "exit_code": int(r["rc"]) if r["rc"] else None,
            "elapsed_s": float(r["elapsed_s"]) if r["elapsed_s"] else None,
            "load1_at_start": float(r["load1"]) if r["load1"] else None,
            "note": r.get("note") or "",
        }
        summary = history = None
        if r["dir"]:
            d = os.path.join(work, r["dir"])
            sp = os.path.join(d, "out", "summary.json")
            if os.path.exists(sp):
                with open(sp) as f:
                    summary = json.load(f)
            history = read_history(os.path.join(d, "out", "history.csv"))
            if run["status"] == "timeout":
                run["message"] = f"timed out after {timeout_s} s"
            elif summary is not None:
                run["message"] = summary.get("message", "")
            else:
                run["message"] = last_line(os.path.join(d, "stderr"))
        else:
            run["message"] = run["note"]
        run["summary"] = summary
        run["history"] = history
        out.append(run)
    return out, decks


# --- derived numbers ----------------------------------------------------------------------------
def spec_for(scene, runs):
    if scene in SCENES:
        return SCENES[scene]
    for r in runs:
        if r["summary"] and r["summary"].get("walls"):
            return generic_spec(scene, next(iter(r["summary"]["walls"])))
    return None


def curve(spec, hist, which="y", mu=None):
    xs, ys = [], []
    for row in hist or []:
        x = spec["x"](row)
        y = spec["y"](row) if which == "y" else spec["y2"](row, mu)
        if math.isfinite(x) and math.isfinite(y):
            xs.append(x)
            ys.append(y)
    return xs, ys


def window_average(xs, ys, width):
    """Means over consecutive windows of `width` (in x units); x = window centre."""
    bins = {}
    for x, y in zip(xs, ys):
        k = int(math.floor(x / width))
        bins.setdefault(k, []).append(y)
    ks = sorted(bins)
    return [(k + 0.5) * width for k in ks], [sum(bins[k]) / len(bins[k]) for k in ks]


def derive(run, spec, deck):
    s, h = run["summary"], run["history"]
    d = {}
    if s:
        for k in ("steps", "nonlinear_iterations", "linear_iterations", "retries", "wall_time_s",
                  "converged", "max_penetration", "analysis", "time_step", "unknowns"):
            d[k] = s.get(k)
    if h:
        if d.get("steps") is None:
            d["steps"] = sum(1 for row in h if row.get("step", 0) > 0)
            for k in ("nonlinear_iterations", "linear_iterations", "retries"):
                d[k] = int(sum(row.get(k, 0) for row in h if isinstance(row.get(k), float)))
            d["counts_from_history"] = True
        pens = [row["max_penetration"] for row in h if isinstance(row.get("max_penetration"), float)]
        if pens:
            d["max_penetration_history"] = max(pens)
        d["t_reached"] = h[-1].get("time")
        d["active_final"] = h[-1].get("contact_active")
    mp = [v for v in (d.get("max_penetration"), d.get("max_penetration_history")) if isinstance(v, (int, float))]
    d["max_penetration_run"] = max(mp) if mp else None
    if d.get("wall_time_s") is None and run.get("elapsed_s") is not None:
        d["wall_time_s"] = run["elapsed_s"]
        d["wall_is_elapsed"] = True
    if deck:
        d["end_time"] = deck.get("analysis", {}).get("end_time")
    if spec and h:
        xs, ys = curve(spec, h)
        if run["contact"] == "explicit" and xs:
            # the kinematic wall's force is m Δv/h per step: peak of the window average
            wt = EXPLICIT_WINDOW * 1e6 if spec is SCENES.get("taylor-bar") else None
            if wt:
                _, ya = window_average(xs, ys, wt)
                d["force_peak_averaged"] = max(ya, key=abs) if ya else None
        if ys:
            d["force_final"] = ys[-1]
            d["force_peak"] = max(ys, key=abs)
            d["x_final"] = xs[-1]
    return d


# --- output -------------------------------------------------------------------------------------
def machine_info(meta):
    return {
        "nproc": os.cpu_count(),
        "cpu": cpu_name(),
        "kernel": platform.release(),
        "mpi": mpi_version(),
        "uptime_start": meta.get("uptime_start", "").strip(),
        "uptime_end": meta.get("uptime_end", "").strip(),
    }


def alfe_info(meta):
    return _alfe_info(meta, head_time=False, dirty_default=0)


def fmt_num(v, digits=3):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "–"
    if isinstance(v, int) or (isinstance(v, float) and v.is_integer() and abs(v) < 1e9):
        return f"{int(v):,}"
    return f"{v:.{digits}g}"


def fmt_force(v, unit):
    if v is None:
        return "–"
    return f"{v:.4g} {unit}"


def sort_key(run):
    return (CONTACT_ORDER.index(run["contact"]) if run["contact"] in CONTACT_ORDER else 9,
            SOLVER_ORDER.index(run["solver"]) if run["solver"] in SOLVER_ORDER else 9)


def plot_scene(path, scene, spec, runs, decks):
    deck = decks.get(scene)
    two_panels = "y2" in spec
    zoom = spec.get("zoom")
    fig, axes = plt.subplots(1, 2 if (two_panels or zoom) else 1, figsize=(13 if (two_panels or zoom) else 8.5, 5.2))
    ax = axes[0] if (two_panels or zoom) else axes
    mu = wall_friction(deck, spec.get("wall")) if two_panels else None
    plotted = 0
    for target in [ax] + ([axes[1]] if zoom else []):
        plotted = 0
        for run in sorted(runs, key=sort_key):
            h = run["history"]
            if not h:
                continue
            xs, ys = curve(spec, h)
            if not xs:
                continue
            tag = {"ok": "", "not-converged": ", did not finish", "timeout": ", timed out",
                   "failed": ", failed"}.get(run["status"], f", {run['status']}")
            if run["contact"] == "explicit":
                target.plot(xs, ys, color=COLORS["explicit"], lw=0.5, alpha=0.25, label="explicit, raw per step")
                wt = EXPLICIT_WINDOW * 1e6 if spec is SCENES.get("taylor-bar") else None
                if wt:
                    xa, ya = window_average(xs, ys, wt)
                    target.plot(xa, ya, color="k", lw=1.8,
                                label=f"explicit, {EXPLICIT_WINDOW * 1e6:g} µs window mean{tag}")
                plotted += 1
                continue
            style = STYLES.get(run["solver"], dict(ls="-.", lw=1.0))
            color = COLORS.get(run["contact"], "tab:green")
            marker = "o" if (len(xs) <= 60 or target is not ax) and run["solver"] == "newton" else None
            target.plot(xs, ys, color=color, marker=marker, ms=3,
                        label=f"{spec['ylabel_short'] + ', ' if two_panels else ''}{run['contact'].upper()}, "
                              f"{run['solver']}{tag}", **style)
            if run["status"] != "ok":
                target.plot(xs[-1:], ys[-1:], "x", color=color, ms=10, mew=2)
            if two_panels and mu is not None:
                x2, y2 = curve(spec, h, "y2", mu)
                target.plot(x2, y2, color=color, alpha=0.45, lw=style["lw"], ls=style["ls"],
                            label=f"{spec['y2_label']} (μ = {mu:g}), {run['contact'].upper()}, {run['solver']}")
            plotted += 1
        target.set_xlabel(spec["xlabel"])
        target.set_ylabel(spec["ylabel"])
        if two_panels:
            target.set_ylabel(f"{spec['ylabel']}: {spec['ylabel_short']} (friction) and {spec['y2_label']}")
        target.grid(True, alpha=0.3)
        target.axhline(0, color="0.6", lw=0.6)
        if plotted:
            target.legend(fontsize=7.5, loc="best")
        else:
            target.text(0.5, 0.5, "no run produced a history", ha="center", transform=target.transAxes)
    if zoom:
        axes[1].set_xlim(*zoom)
        axes[1].set_title(f"zoom: {zoom[0]:g}–{zoom[1]:g} {spec['x_unit']} (implicit newton runs with markers at steps)",
                          fontsize=9)
        axes[1].get_legend().remove()
    if two_panels:
        # the same forces against time: the press phase (floor at rest) is invisible vs floor.ux
        ax2 = axes[1]
        for run in sorted(runs, key=sort_key):
            if not run["history"] or run["solver"] != "newton":
                continue
            color = COLORS.get(run["contact"], "tab:green")
            t = [row.get("time", math.nan) for row in run["history"]]
            _, ys = curve(spec, run["history"])
            _, y2 = curve(spec, run["history"], "y2", mu)
            if len(t) == len(ys) == len(y2):
                ax2.plot(t, ys, color=color, lw=1.8, label=f"{spec['ylabel_short']}, {run['contact'].upper()}, newton")
                ax2.plot(t, y2, color=color, lw=1.2, ls="--", alpha=0.6,
                         label=f"{spec['y2_label']}, {run['contact'].upper()}, newton")
        ax2.set_xlabel("pseudo-time t (press over 0–1, floor slides over 1–3)")
        ax2.set_ylabel("force on the floor (N)")
        ax2.grid(True, alpha=0.3)
        ax2.legend(fontsize=7.5, loc="best")
    fig.suptitle(spec["title"], fontsize=10.5)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def yesno(run, d):
    if run["status"] == "ok":
        return "yes"
    if run["status"] in ("skipped", "not-available"):
        return "–"
    return "**no**"


def outcome(run, d):
    st = run["status"]
    if st == "ok":
        return ""
    if st in ("skipped", "not-available"):
        return f"{st}: {run['note']}" if run["note"] else st
    msg = shorten(run.get("message", ""))
    t, te = d.get("t_reached"), d.get("end_time")
    reached = f"; reached t = {t:.4g} of {te:g}" if isinstance(t, float) and isinstance(te, (int, float)) else ""
    return f"{st}: {msg}{reached}"


def write_markdown(path, meta, machine, alfe, rows, scene_notes, pngs):
    L = []
    L.append("# Contact benchmark: ALM vs penalty walls, Newton / BFGS / JFNK")
    L.append("")
    L.append(f"- date: {meta.get('started', '?')} (finished {meta.get('finished', '?')}, "
             f"{meta.get('runs_seconds', '?')} s of runs)")
    L.append(f"- machine: {machine['nproc']} cores ({machine['cpu']}), {machine['mpi']}")
    L.append(f"- load (`uptime`) at the start: `{machine['uptime_start']}`")
    L.append(f"- load (`uptime`) at the end: `{machine['uptime_end']}`")
    c = alfe["commit"] or "?"
    note = f" ({alfe['commit_note']})" if alfe.get("commit_note") else ""
    L.append(f"- alfe: commit `{c}`{note}; binary sha256 `{alfe['binary_sha256_prefix']}…`")
    L.append(f"- command: `{meta.get('cmdline', '?')}`")
    L.append(f"- {meta.get('ranks', '?')} MPI rank(s); one run per configuration (no repetitions: wall times "
             f"on this shared machine are indicative); per-run timeout {meta.get('timeout_s', '?')} s; bfgs/jfnk "
             f"are dropped on a scene once one of its runs takes more than {meta.get('slow_s', '?')} s.")
    L.append("- columns: counts and `wall s` (alfe's `wall_time_s`) from summary.json — for a run that "
             "did not finish, the steps it converged; `max pen.` is the largest `max_penetration` over "
             "the run (history.csv and summary.json, mm); `force final / peak` is the plotted force "
             "(see each scene) at the last converged step and its largest magnitude. The explicit "
             "run has no nonlinear iterations: its `steps` are explicit time steps.")
    L.append("")
    L.append("| scene | contact | solver | converged | steps | nonlinear its | linear its | retries | wall s "
             "| max pen. (mm) | force final / peak | failure / note |")
    L.append("|---|---|---|:-:|--:|--:|--:|--:|--:|--:|--:|---|")
    for run, d, spec in rows:
        unit = spec["unit"] if spec else ""
        force = "–"
        if d.get("force_final") is not None:
            force = f"{fmt_force(d['force_final'], unit)} / {fmt_force(d['force_peak'], unit)}"
            if d.get("force_peak_averaged") is not None:
                force += f" (window mean peak {d['force_peak_averaged']:.4g} {unit})"
        wall = "–"
        if d.get("wall_time_s") is not None:
            wall = f"{d['wall_time_s']:.1f}" + (" (elapsed)" if d.get("wall_is_elapsed") else "")
        L.append("| " + " | ".join([
            run["scene"], run["contact"], run["solver"], yesno(run, d), fmt_num(d.get("steps")),
            fmt_num(d.get("nonlinear_iterations")), fmt_num(d.get("linear_iterations")),
            fmt_num(d.get("retries")), wall, fmt_num(d.get("max_penetration_run"), 2), force,
            outcome(run, d).replace("|", "/"),
        ]) + " |")
    L.append("")
    L.append("## Plots")
    L.append("")
    for scene, png in pngs:
        L.append(f"- `{scene}`: [{png}]({png})")
    if scene_notes:
        L.append("")
        L.append("## Notes (computed from the runs)")
        L.append("")
        for n in scene_notes:
            L.append(f"- {n}")
    L.append("")
    with open(path, "w") as f:
        f.write("\n".join(L))


def scene_observations(scene, runs, derived, decks):
    """Short, measured statements per scene (no judgement beyond the numbers)."""
    notes = []
    by = {(r["contact"], r["solver"]): derived[id(r)] for r in runs}
    spec = SCENES.get(scene)
    unit = spec["unit"] if spec else ""
    a, p = by.get(("alm", "newton"), {}), by.get(("penalty", "newton"), {})
    if a.get("force_peak") is not None and p.get("force_peak") is not None:
        notes.append(f"{scene}: newton peak force ALM {a['force_peak']:.4g} {unit}, penalty {p['force_peak']:.4g} {unit} "
                     f"({(p['force_peak'] / a['force_peak'] - 1) * 100:+.1f} %); final ALM {a['force_final']:.4g}, "
                     f"penalty {p['force_final']:.4g} {unit}; max penetration ALM "
                     f"{fmt_num(a.get('max_penetration_run'), 2)} mm, penalty {fmt_num(p.get('max_penetration_run'), 2)} mm.")
    if scene == "taylor-bar":
        for r in runs:
            d = derived[id(r)]
            h = r["history"]
            if h and isinstance(h[-1].get("top.uz"), float) and r["solver"] in ("newton", "-"):
                deck = decks.get(scene) or {}
                L0 = None
                for part in deck.get("parts", []):
                    L0 = part.get("mesh", {}).get("length", L0)
                if L0:
                    notes.append(f"taylor-bar {r['contact']}{'' if r['solver'] == '-' else ', ' + r['solver']}: "
                                 f"final L/L0 = {(L0 + h[-1]['top.uz']) / L0:.4f} from top.uz at t = "
                                 f"{h[-1]['time'] * 1e6:.1f} µs (the deck quotes 0.661–0.663 published)")
        e = by.get(("explicit", "-"), {})
        if e.get("force_peak_averaged") is not None and a.get("force_peak") is not None:
            notes.append(f"taylor-bar: peak wall force, implicit ALM newton {a['force_peak']:.4g} kN vs explicit "
                         f"{e['force_peak_averaged']:.4g} kN averaged over {EXPLICIT_WINDOW * 1e6:g} µs windows "
                         f"(raw per-step explicit peak {e['force_peak']:.4g} kN).")
    if scene == "sliding-block":
        mu = wall_friction(decks.get(scene), "floor")
        for r in runs:
            h = r["history"]
            if not h or mu is None or r["solver"] != "newton":
                continue
            last = h[-1]
            fx, fz = last.get("floor.fx"), last.get("floor.fz")
            if isinstance(fx, float) and isinstance(fz, float) and fz != 0:
                notes.append(f"sliding-block {r['contact']}, newton: final |floor.fx| / |floor.fz| = {abs(fx / fz):.4f} "
                             f"(μ = {mu:g}); contact_sticking at the end: {fmt_num(last.get('contact_sticking'))} of "
                             f"{fmt_num(last.get('contact_active'))} active nodes")
    return notes


def to_jsonable(run, d):
    out = {k: v for k, v in run.items() if k not in ("summary", "history")}
    out["derived"] = d
    s = run["summary"]
    if s:
        out["summary"] = {k: v for k, v in s.items() if k != "output_dir"}
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--work", required=True)
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    meta = read_meta(os.path.join(args.work, "meta.env"))
    runs, decks = collect(args.work, meta)
    machine = machine_info(meta)
    alfe = alfe_info(meta)
    scenes = []
    for r in runs:
        if r["scene"] not in scenes:
            scenes.append(r["scene"])
    rows, notes, pngs, curves = [], [], [], {}
    derived = {}
    for scene in scenes:
        sruns = sorted([r for r in runs if r["scene"] == scene], key=sort_key)
        spec = spec_for(scene, sruns)
        for r in sruns:
            d = derive(r, spec, decks.get(scene))
            derived[id(r)] = d
            rows.append((r, d, spec))
            if spec and r["history"]:
                xs, ys = curve(spec, r["history"])
                key = f"{scene}/{r['contact']}/{r['solver']}"
                if r["contact"] == "explicit" and scene == "taylor-bar":
                    xs, ys = window_average(xs, ys, EXPLICIT_WINDOW * 1e6)
                    key += f" ({EXPLICIT_WINDOW * 1e6:g} us window mean)"
                curves[key] = {"x": xs, "y": ys, "x_label": spec["xlabel"], "y_label": spec["ylabel"]}
        if spec and any(r["history"] for r in sruns):
            png = f"{scene}.png"
            plot_scene(os.path.join(args.out, png), scene, spec, sruns, decks)
            pngs.append((scene, png))
        notes += scene_observations(scene, sruns, derived, decks)
    write_markdown(os.path.join(args.out, "bench-contact.md"), meta, machine, alfe, rows, notes, pngs)
    with open(os.path.join(args.out, "bench-contact.json"), "w") as f:
        json.dump({"meta": meta, "machine": machine, "alfe": alfe,
                   "runs": [to_jsonable(r, derived[id(r)]) for r in runs],
                   "notes": notes, "curves": curves}, f, indent=1)
    print(f"bench-contact: wrote {args.out}/bench-contact.md, bench-contact.json and "
          f"{', '.join(p for _, p in pngs) or 'no plots'}")


if __name__ == "__main__":
    main()
