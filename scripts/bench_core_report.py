#!/usr/bin/python3
"""Report of scripts/bench-core: medians over reps of alfe's and PETSc's runs.

Usage: bench_core_report.py META.json MANIFEST.tsv OUT_PREFIX   (writes OUT_PREFIX.md, .json)
       bench_core_report.py --from OUT_PREFIX.json OUT_PREFIX    (redo the table from the raw JSON)
MANIFEST.tsv rows: tool, ranks, rep, solver, json path, exit code, wall s, 1-min load before.
"""
import json
import statistics
import sys

TARGET_ASSEMBLY = 1.7
TARGET_SOLVE = 1.5
TARGET_RATIO = 1.2


def med(xs):
    xs = [x for x in xs if x is not None]
    return statistics.median(xs) if xs else None


def f(x, digits=3):
    if x is None:
        return "–"
    if isinstance(x, int):
        return f"{x:,}"
    if abs(x) >= 1e4:
        return f"{x:,.0f}"
    return f"{x:.{digits}g}"


def check(value, target, higher_is_better=True):
    if value is None:
        return "–"
    ok = value >= target if higher_is_better else value <= target
    return "met" if ok else "**not met**"


def main():
    if sys.argv[1] == "--from":
        raw = json.load(open(sys.argv[2]))
        meta, runs, out = raw["meta"], raw["runs"], sys.argv[3]
    else:
        meta_path, manifest, out = sys.argv[1:4]
        meta = json.load(open(meta_path))
        runs = []
        for line in open(manifest):
            tool, ranks, rep, solver, path, rc, wall, load = line.rstrip("\n").split("\t")
            rec = {"tool": tool, "ranks": int(ranks), "rep": int(rep), "solver": None if solver == "-" else solver,
                   "exit_code": int(rc), "wall_s": float(wall), "load1_before": float(load), "result": None}
            try:
                rec["result"] = json.load(open(path))
            except (OSError, ValueError):
                pass
            runs.append(rec)
    ranks = sorted({r["ranks"] for r in runs})

    # ---- alfe medians per rank count ---------------------------------------------------
    alfe = {}
    for p in ranks:
        rs = [r["result"] for r in runs if r["tool"] == "alfe" and r["ranks"] == p and r["result"]]
        if not rs:
            continue
        g = lambda k: med([x[k] for x in rs])  # noqa: E731
        alfe[p] = {
            "n": len(rs),
            "unknowns": rs[0]["unknowns"], "elements": rs[0]["elements"], "nnz": rs[0]["nnz"],
            "owned": rs[0].get("owned_dofs_per_rank"),
            "factorization": rs[0].get("factorization", "?"),
            "residual_s": g("residual_s"), "residual_rate": g("residual_elems_per_s_per_rank"),
            "jacobian_s": g("jacobian_s"), "jacobian_rate": g("jacobian_elems_per_s_per_rank"),
            "symbolic_s": med([max(x.get("symbolic_s_per_rank", [0])) for x in rs]),
            "factor_first_s": g("factor_first_s"), "refactor_s": g("refactor_s"),
            "gmres_s": g("gmres_s"), "its": sorted({x["gmres_iterations"] for x in rs}),
            "s_per_it": g("gmres_s_per_iteration"),
            "cold_s": med([x["factor_first_s"] + x["gmres_s"] for x in rs]),
            "warm_s": med([x["refactor_s"] + x["gmres_s"] for x in rs]),
            "true_rel": max(x["true_relative_residual"] for x in rs),
            "converged": all(x["gmres_converged"] for x in rs),
            "rss": med([max(x["peak_rss_mb_per_rank"]) for x in rs]),
            "h5_mb_s": g("h5_mb_per_s"),
            "setup_s": g("setup_s"),
        }

    # ---- PETSc medians per rank count and solver ---------------------------------------
    petsc = {}
    for p in ranks:
        for s in sorted({r["solver"] for r in runs if r["tool"] == "petsc" and r["ranks"] == p}):
            rs = [r["result"] for r in runs if r["tool"] == "petsc" and r["ranks"] == p and r["solver"] == s and r["result"]]
            failed = sum(1 for r in runs if r["tool"] == "petsc" and r["ranks"] == p and r["solver"] == s and r["exit_code"] != 0)
            if not rs:
                petsc[(p, s)] = {"n": 0, "failed": failed}
                continue
            g = lambda k: med([x[k] for x in rs])  # noqa: E731
            petsc[(p, s)] = {
                "n": len(rs), "failed": failed,
                "sub_solver": rs[0]["sub_solver"], "version": rs[0]["petsc_version"],
                "ordering": rs[0].get("mumps_ordering"),
                "setup_s": g("setup_s"), "solve_s": g("solve_s"), "refactor_s": g("refactor_s"),
                "solve2_s": g("solve2_s"),
                "its": sorted({x["iterations"] for x in rs}),
                "cold_s": g("time_to_tol_s"), "warm_s": g("time_to_tol_warm_s"),
                "true_rel": max(x["true_relative_residual"] for x in rs),
                "converged": all(x["converged"] for x in rs),
                "rss": med([max(x["peak_rss_mb_per_rank"]) for x in rs]),
                "factor_nnz": rs[0].get("factor_nnz_rank0"),
                "block_rows": rs[0].get("local_rows"),
            }
    best = {}
    for p in ranks:
        cands = [(v["cold_s"], s) for (q, s), v in petsc.items() if q == p and v["n"] and v["converged"]]
        if cands:
            best[p] = min(cands)[1]

    # ---- derived ------------------------------------------------------------------------
    summary = {}
    if 1 in alfe and 2 in alfe:
        a1, a2 = alfe[1], alfe[2]
        summary["speedup_residual"] = a1["residual_s"] / a2["residual_s"]
        summary["speedup_assembly"] = a1["jacobian_s"] / a2["jacobian_s"]
        summary["speedup_solve_cold"] = a1["cold_s"] / a2["cold_s"]
        summary["speedup_solve_warm"] = a1["warm_s"] / a2["warm_s"]
    for p in ranks:
        if p in alfe and p in best:
            b = petsc[(p, best[p])]
            summary[f"ratio_cold_r{p}"] = alfe[p]["cold_s"] / b["cold_s"]
            summary[f"ratio_warm_r{p}"] = alfe[p]["warm_s"] / b["warm_s"]
        for (q, s), v in petsc.items():
            if q == p and v["n"] and p in alfe:
                summary[f"ratio_cold_r{p}_{s}"] = alfe[p]["cold_s"] / v["cold_s"]

    # ---- markdown -----------------------------------------------------------------------
    a_any = next(iter(alfe.values()), None)
    L = []
    L.append("# alfe core benchmark: linear-elastic block, block-Jacobi GMRES vs PETSc\n")
    L.append(f"* Date: {meta['date']}")
    L.append(f"* Machine: {meta['nproc']} cores ({meta['cpu']}), {meta['mem_total']}; load average "
             f"(1/5/15 min) at start {meta['load_start']}, at end {meta['load_end']} (shared machine)")
    L.append(f"* Command: `{meta['command']}`")
    if a_any:
        L.append(f"* Problem: hex8 linear elastic, cells {meta['cells']}: {a_any['unknowns']:,} unknowns, "
                 f"{a_any['elements']:,} elements, {a_any['nnz']:,} matrix nonzeros; rtol {meta['rtol']} on the "
                 "true residual ‖b−Ax‖/‖b‖, atol 0, GMRES(60), right preconditioning")
    L.append(f"* alfe {meta['alfe_commit']} ({meta['rustc']}, faer {meta['faer']}), {meta['openmpi']}")
    L.append(f"* PETSc {next((v['version'] for v in petsc.values() if v.get('n')), '?')} (Debian {meta['petsc_pkg']}, "
             f"petsc4py {meta['petsc4py_pkg']}), MUMPS {meta['mumps_pkg']}, UMFPACK {meta['umfpack_pkg']}; "
             f"BLAS {meta['blas']}")
    if meta.get("available_solvers"):
        L.append(f"* PETSc factorization packages available: {meta['available_solvers']}; run here: {meta['solvers']}")
    L.append(f"* Threads: {meta['threads']}. Medians over {meta['reps']} interleaved rep(s) (alfe, then PETSc, "
             "per rank count, per rep).")
    L.append("")
    L.append("## Targets\n")
    L.append("| target | measured | |")
    L.append("|---|---|---|")
    if "speedup_assembly" in summary:
        L.append(f"| 2-rank speedup, tangent assembly ≥ {TARGET_ASSEMBLY}× | {summary['speedup_assembly']:.2f}× | "
                 f"{check(summary['speedup_assembly'], TARGET_ASSEMBLY)} |")
        L.append(f"| 2-rank speedup, residual evaluation ≥ {TARGET_ASSEMBLY}× | {summary['speedup_residual']:.2f}× | "
                 f"{check(summary['speedup_residual'], TARGET_ASSEMBLY)} |")
        L.append(f"| 2-rank speedup, linear solve (first factorization + GMRES) ≥ {TARGET_SOLVE}× | "
                 f"{summary['speedup_solve_cold']:.2f}× | {check(summary['speedup_solve_cold'], TARGET_SOLVE)} |")
        L.append(f"| 2-rank speedup, linear solve (numeric refactorization + GMRES) ≥ {TARGET_SOLVE}× | "
                 f"{summary['speedup_solve_warm']:.2f}× | {check(summary['speedup_solve_warm'], TARGET_SOLVE)} |")
    for p in ranks:
        if f"ratio_cold_r{p}" in summary:
            L.append(f"| alfe / PETSc ({best[p]}) time to rtol, {p} rank(s), first factorization + solve ≤ {TARGET_RATIO} | "
                     f"{summary[f'ratio_cold_r{p}']:.2f} | {check(summary[f'ratio_cold_r{p}'], TARGET_RATIO, False)} |")
            L.append(f"| alfe / PETSc ({best[p]}) time to rtol, {p} rank(s), numeric refactorization + solve ≤ {TARGET_RATIO} | "
                     f"{summary[f'ratio_warm_r{p}']:.2f} | {check(summary[f'ratio_warm_r{p}'], TARGET_RATIO, False)} |")
    L.append("")
    L.append("## alfe (`alfe-bench linear`)\n")
    L.append("| | " + " | ".join(f"{p} rank(s)" for p in alfe) + " |")
    L.append("|---|" + "---|" * len(alfe))
    rows = [
        ("runs", lambda a: str(a["n"])),
        ("owned unknowns per rank", lambda a: ", ".join(f"{int(v):,}" for v in a["owned"]) if a["owned"] else "?"),
        ("residual evaluation [s]", lambda a: f(a["residual_s"])),
        ("residual [elements/s per rank]", lambda a: f(a["residual_rate"])),
        ("tangent assembly [s]", lambda a: f(a["jacobian_s"])),
        ("tangent assembly [elements/s per rank]", lambda a: f(a["jacobian_rate"])),
        ("block-Jacobi factorization kind", lambda a: a["factorization"]),
        ("… symbolic (ordering) [s] (max over ranks)", lambda a: f(a["symbolic_s"])),
        ("… first factorization (symbolic + numeric) [s]", lambda a: f(a["factor_first_s"])),
        ("… numeric refactorization [s]", lambda a: f(a["refactor_s"])),
        ("GMRES iterations", lambda a: ", ".join(map(str, a["its"]))),
        ("GMRES [s]", lambda a: f(a["gmres_s"])),
        ("GMRES [s per iteration]", lambda a: f(a["s_per_it"])),
        ("**time to rtol, first factorization + GMRES [s]**", lambda a: f"**{f(a['cold_s'])}**"),
        ("time to rtol, refactorization + GMRES [s]", lambda a: f(a["warm_s"])),
        ("true relative residual (max over runs)", lambda a: f"{a['true_rel']:.2e}" + ("" if a["converged"] else " NOT CONVERGED")),
        ("peak RSS per rank, max over ranks [MiB]", lambda a: f(a["rss"], 4)),
        ("HDF5 collective write [MB/s]", lambda a: f(a["h5_mb_s"])),
    ]
    for name, fn in rows:
        L.append(f"| {name} | " + " | ".join(fn(alfe[p]) for p in alfe) + " |")
    L.append("")
    L.append("## PETSc (`scripts/petsc_bjacobi.py`: GMRES(60), right PC, bjacobi, sub preonly + LU)\n")
    keys = [k for k in sorted(petsc) if petsc[k]["n"]]
    L.append("| | " + " | ".join(f"{p} rank(s), {s}" + (" (fastest)" if best.get(p) == s else "") for p, s in keys) + " |")
    L.append("|---|" + "---|" * len(keys))
    prow = [
        ("runs (failed)", lambda v: f"{v['n']} ({v['failed']})"),
        ("sub-PC factorization package", lambda v: v["sub_solver"] + (f" (ordering {v['ordering']})" if v.get("ordering") else "")),
        ("block rows per rank", lambda v: ", ".join(f"{int(x):,}" for x in v["block_rows"] or [])),
        ("factor nonzeros, rank 0's block (as PETSc reports them)", lambda v: f(int(v["factor_nnz"])) if v["factor_nnz"] else "not reported"),
        ("setup = first factorization [s]", lambda v: f(v["setup_s"])),
        ("numeric refactorization [s]", lambda v: f(v["refactor_s"])),
        ("GMRES iterations", lambda v: ", ".join(map(str, v["its"]))),
        ("KSPSolve [s]", lambda v: f(v["solve_s"])),
        ("**time to rtol, setup + solve [s]**", lambda v: f"**{f(v['cold_s'])}**"),
        ("time to rtol, refactorization + solve [s]", lambda v: f(v["warm_s"])),
        ("true relative residual (max over runs)", lambda v: f"{v['true_rel']:.2e}" + ("" if v["converged"] else " NOT CONVERGED")),
        ("peak RSS per rank, max over ranks [MiB]", lambda v: f(v["rss"], 4)),
        ("alfe / this, time to rtol (first factorization)", lambda v: "–"),
    ]
    for name, fn in prow[:-1]:
        L.append(f"| {name} | " + " | ".join(fn(petsc[k]) for k in keys) + " |")
    L.append("| alfe / this, time to rtol (first factorization + solve) | " + " | ".join(
        f"{summary.get(f'ratio_cold_r{p}_{s}', float('nan')):.2f}" for p, s in keys) + " |")
    fails = [k for k in sorted(petsc) if not petsc[k]["n"]]
    if fails:
        L.append("")
        L.append("Failed PETSc configurations (no result): " + ", ".join(f"{p} rank(s) {s}" for p, s in fails))
    L.append("")
    L.append("## Runs\n")
    L.append("| rep | tool | ranks | sub-solver | exit | wall [s] | 1-min load before |")
    L.append("|---|---|---|---|---|---|---|")
    for r in runs:
        L.append(f"| {r['rep']} | {r['tool']} | {r['ranks']} | {r['solver'] or ''} | {r['exit_code']} | "
                 f"{r['wall_s']:.1f} | {r['load1_before']:.2f} |")
    L.append("")
    L.append("Definitions: *time to rtol, first factorization* = alfe `factor_first_s + gmres_s` "
             "(block-Jacobi construction incl. symbolic analysis, then GMRES from x = 0) vs PETSc "
             "`KSPSetUp + KSPSetUpOnBlocks` (symbolic + numeric LU) + `KSPSolve`; *refactorization* = "
             "numeric-only refactorization with the same pattern (alfe `refactor_s`, PETSc after a value "
             "change) + a solve. Speedups are 1-rank time / 2-rank time of the same problem. "
             "Raw per-run JSON: `" + out.split("/")[-1] + ".json`.")
    with open(out + ".md", "w") as fh:
        fh.write("\n".join(L) + "\n")
    with open(out + ".json", "w") as fh:
        json.dump({"meta": meta, "summary": summary, "best_petsc_solver": {str(k): v for k, v in best.items()},
                   "runs": runs}, fh, indent=1)
        fh.write("\n")


if __name__ == "__main__":
    main()
