#!/usr/bin/python3
"""PETSc peer for `alfe-bench linear`: block-Jacobi-preconditioned GMRES on an exported system.

Usage (Debian's petsc4py: run with /usr/bin/python3 and PETSC_DIR set, see SETUP.md):

    PETSC_DIR=/usr/lib/petscdir/petsc3.18/x86_64-linux-gnu-real \\
    mpirun -n R /usr/bin/python3 scripts/petsc_bjacobi.py A.petsc b.petsc \\
        [--solver mumps|umfpack|petsc] [--factor lu|cholesky] [--rtol 1e-8] \\
        [--local-rows N0,N1,...] [--refactor-reps 3] [--json OUT.json]
    /usr/bin/python3 scripts/petsc_bjacobi.py --list-solvers

Reads A and b written by `alfe-bench linear --export DIR` (PETSc binary, MatLoad/VecLoad),
optionally with alfe's row ownership (`--local-rows`, the `owned_dofs_per_rank` of alfe's
JSON) so each rank's block-Jacobi block is exactly alfe's. Then: KSP GMRES (restart 60),
right preconditioning (rtol measures the true, unpreconditioned residual, as alfe does),
atol 0, PC bjacobi with one block per rank, sub-KSP preonly, sub-PC LU (or Cholesky)
factored by the chosen package. Times, each between barriers:
  * setup_s:    first KSPSetUp + KSPSetUpOnBlocks (symbolic + numeric factorization),
  * solve_s:    KSPSolve from x = 0,
  * refactor_s: median numeric-only refactorization (same nonzero pattern, new values),
and checks the true relative residual ||b - A x|| / ||b||. Prints one JSON object (rank 0).
"""
import argparse
import json
import os
import re
import resource
import sys
import tempfile
import time

from petsc_system import load_system


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("A", nargs="?")
    ap.add_argument("b", nargs="?")
    ap.add_argument("--solver", default="mumps", help="sub-PC factorization package: mumps, umfpack, petsc, ...")
    ap.add_argument("--factor", default="lu", choices=["lu", "cholesky"])
    ap.add_argument("--rtol", type=float, default=1e-8)
    ap.add_argument("--restart", type=int, default=60)
    ap.add_argument("--max-it", type=int, default=5000)
    ap.add_argument("--local-rows", default=None, help="comma-separated rows owned per rank (alfe's layout)")
    ap.add_argument("--refactor-reps", type=int, default=3)
    ap.add_argument("--json", default=None)
    ap.add_argument("--list-solvers", action="store_true", help="print the factorization packages this PETSc has")
    args, petsc_args = ap.parse_known_args()

    import petsc4py

    petsc4py.init([sys.argv[0]] + petsc_args)
    from petsc4py import PETSc

    if args.list_solvers:
        # Solver types by the PETSc configure package that provides them.
        pkgs = {"mumps": ["mumps"], "suitesparse": ["umfpack", "cholmod", "klu"], "superlu": ["superlu"],
                "superlu_dist": ["superlu_dist"], "pastix": ["pastix"], "strumpack": ["strumpack"]}
        have = [s for p, ss in pkgs.items() if PETSc.Sys.hasExternalPackage(p) for s in ss]
        print(" ".join(have + ["petsc"]))
        return 0
    if not args.A or not args.b:
        ap.error("A and b are required")

    comm = PETSc.COMM_WORLD
    mpi = comm.tompi4py()
    rank, size = comm.getRank(), comm.getSize()

    def barrier_time():
        mpi.Barrier()
        return time.perf_counter()

    t0 = barrier_time()
    A, b, m, nnz = load_system(PETSc, comm, args.A, args.b, args.local_rows)
    load_s = barrier_time() - t0
    if args.factor == "cholesky":
        A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
        A.setOption(PETSc.Mat.Option.SPD, True)

    opts = PETSc.Options()
    opts["sub_ksp_type"] = "preonly"
    opts["sub_pc_type"] = args.factor
    opts["sub_pc_factor_mat_solver_type"] = args.solver
    ksp = PETSc.KSP().create(comm=comm)
    ksp.setOperators(A, A)
    ksp.setType(PETSc.KSP.Type.GMRES)
    ksp.setGMRESRestart(args.restart)
    ksp.setPCSide(PETSc.PC.Side.RIGHT)
    ksp.setNormType(PETSc.KSP.NormType.UNPRECONDITIONED)
    ksp.setTolerances(rtol=args.rtol, atol=0.0, max_it=args.max_it)
    ksp.setInitialGuessNonzero(False)
    ksp.getPC().setType(PETSc.PC.Type.BJACOBI)
    ksp.setFromOptions()  # picks up sub_* above and anything passed on the command line

    t0 = barrier_time()
    ksp.setUp()
    ksp.setUpOnBlocks()
    setup_s = barrier_time() - t0

    # petsc4py 3.18 has no PCBJacobiGetSubKSP: read the sub-solver back from KSPView
    # (it shows rank 0's block: its PC, factorization package and factor fill).
    view_path = os.path.join(tempfile.gettempdir(), "petsc_bjacobi_view_%d.txt" % mpi.bcast(os.getpid()))
    v = PETSc.Viewer().createASCII(view_path, comm=comm)
    ksp.view(v)
    v.destroy()
    mpi.Barrier()
    view = {"sub_pc": None, "sub_solver": None, "factor_nnz_rank0": None}
    if rank == 0:
        text = open(view_path).read()
        os.remove(view_path)
        sub_text = text.split("Local solver", 1)[-1]
        m_ = re.search(r"PC Object: \(sub_\) \d+ MPI process(?:es)?\s+type: (\w+)", sub_text)
        view["sub_pc"] = m_.group(1) if m_ else None
        m_ = re.search(r"package used to perform factorization: (\w+)", sub_text)
        view["sub_solver"] = m_.group(1) if m_ else None
        # The factored matrix's "total: nonzeros=" follows "Factored matrix follows".
        fm = sub_text.split("Factored matrix follows", 1)
        if len(fm) == 2:
            m_ = re.search(r"total: nonzeros=(\d+)", fm[1])
            view["factor_nnz_rank0"] = (int(m_.group(1)) or None) if m_ else None  # 0: not reported
        m_ = re.search(r"INFOG\(7\) \(ordering option effectively used after analysis\): (\d+)", sub_text)
        if m_:  # MUMPS: 0 AMD, 2 AMF, 3 SCOTCH, 4 PORD, 5 METIS, 6 QAMD
            code = int(m_.group(1))
            view["mumps_ordering"] = {0: "AMD", 2: "AMF", 3: "SCOTCH", 4: "PORD", 5: "METIS", 6: "QAMD"}.get(code, str(code))
        view["ksp_view"] = text
    view = mpi.bcast(view)
    if view["sub_solver"] not in (None, args.solver):
        raise SystemExit(f"asked for {args.solver}, PETSc used {view['sub_solver']}")

    x = b.duplicate()
    x.set(0.0)
    t0 = barrier_time()
    ksp.solve(b, x)
    solve_s = barrier_time() - t0
    its = ksp.getIterationNumber()
    reason = ksp.getConvergedReason()

    r = b.duplicate()
    A.mult(x, r)
    r.aypx(-1.0, b)  # r = b - A x
    bnorm = b.norm()
    true_rel = r.norm() / bnorm
    xnorm = x.norm()

    # Numeric-only refactorization: new values (A scaled by 2 then by 1/2: bit-identical),
    # same nonzero pattern, so PCSetUp reuses the symbolic factorization.
    refactor = []
    for _ in range(args.refactor_reps):
        A.scale(2.0)
        A.scale(0.5)
        ksp.setOperators(A, A)
        t0 = barrier_time()
        ksp.setUp()
        ksp.setUpOnBlocks()
        refactor.append(barrier_time() - t0)
    refactor.sort()
    refactor_s = refactor[len(refactor) // 2] if refactor else None
    # A second solve with the refactored preconditioner (the warm path alfe's `solve_s` measures).
    x.set(0.0)
    t0 = barrier_time()
    ksp.solve(b, x)
    solve2_s = barrier_time() - t0
    its2 = ksp.getIterationNumber()

    rss_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    rss = mpi.allgather(rss_mb)
    ver = PETSc.Sys.getVersion()
    out = {
        "ranks": size,
        "petsc_version": "%d.%d.%d" % ver,
        "petsc4py_version": petsc4py.__version__,
        "ksp": ksp.getType(),
        "restart": args.restart,
        "pc_side": "right",
        "pc": ksp.getPC().getType(),
        "sub_pc": view["sub_pc"],
        "sub_solver": view["sub_solver"],
        "mumps_ordering": view.get("mumps_ordering"),
        "unknowns": m,
        "nnz": nnz,
        "local_rows": mpi.allgather(A.getLocalSize()[0]),
        "factor_nnz_rank0": view["factor_nnz_rank0"],
        "load_s": load_s,
        "setup_s": setup_s,
        "solve_s": solve_s,
        "iterations": its,
        "converged_reason": int(reason),
        "converged": reason > 0,
        "rtol": args.rtol,
        "true_relative_residual": true_rel,
        "solution_norm": xnorm,
        "refactor_s": refactor_s,
        "refactor_all_s": refactor,
        "solve2_s": solve2_s,
        "iterations2": its2,
        "time_to_tol_s": setup_s + solve_s,
        "time_to_tol_warm_s": (refactor_s or 0.0) + solve2_s,
        "peak_rss_mb_per_rank": rss,
        "ksp_view": view.get("ksp_view"),
    }
    if rank == 0:
        print(json.dumps({k: v for k, v in out.items() if k != "ksp_view"}, indent=2))
        if args.json:
            with open(args.json, "w") as f:
                f.write(json.dumps(out, indent=2) + "\n")
    ok = reason > 0 and true_rel <= 10 * args.rtol
    return 0 if ok else 2


if __name__ == "__main__":
    sys.exit(main())
