#!/usr/bin/python3
"""PETSc peer for `alfe-bench linear --pc amg`: GMRES with hypre's BoomerAMG (through
PETSc's PCHYPRE) on a system exported by `alfe-bench linear --export DIR`.

    PETSC_DIR=/usr/lib/petscdir/petsc3.18/x86_64-linux-gnu-real \\
    mpirun -n R /usr/bin/python3 scripts/petsc_amg.py A.petsc b.petsc \\
        [--rtol 1e-8] [--local-rows N0,N1,...] [--reps 3] [--json OUT.json]

The same GMRES as alfe's (restart 60, right preconditioning so rtol bounds the true
residual, atol 0, x0 = 0) and the same BoomerAMG options as `src/linalg/hypre.rs`: one
V-cycle, HMIS coarsening, extended+i interpolation with at most 4 entries per row,
l1-scaled hybrid Gauss-Seidel (hypre relax type 8, on every level including the
coarsest, lexicographic order), strength threshold 0.8, no aggressive
coarsening, three functions per node. Debian's PETSc 3.18 links the same libHYPRE 2.26
as alfe, so the comparison measures the wrappers, GMRES and the matrix hand-over. Times
(medians of --reps, between barriers): setup_s (PCSetUp: hypre's matrix copy and AMG
setup, from a fresh PC each rep), solve_s (KSPSolve). Prints one JSON object (rank 0).
"""
import argparse
import json
import resource
import sys
import time

from petsc_system import load_system


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("A")
    ap.add_argument("b")
    ap.add_argument("--rtol", type=float, default=1e-8)
    ap.add_argument("--restart", type=int, default=60)
    ap.add_argument("--local-rows", default=None)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--json", default=None)
    args, petsc_args = ap.parse_known_args()

    import petsc4py
    petsc4py.init([sys.argv[0]] + petsc_args)
    from petsc4py import PETSc

    if not PETSc.Sys.hasExternalPackage("hypre"):
        raise SystemExit("this PETSc has no hypre")
    comm = PETSc.COMM_WORLD
    mpi = comm.tompi4py()
    rank, size = comm.getRank(), comm.getSize()

    def barrier_time():
        mpi.Barrier()
        return time.perf_counter()

    A, b, m, _ = load_system(PETSc, comm, args.A, args.b, args.local_rows)

    opts = PETSc.Options()
    for k, v in {
        "pc_hypre_type": "boomeramg",
        "pc_hypre_boomeramg_coarsen_type": "HMIS",
        "pc_hypre_boomeramg_interp_type": "ext+i",
        "pc_hypre_boomeramg_P_max": "4",
        "pc_hypre_boomeramg_relax_type_all": "l1scaled-SOR/Jacobi",
        "pc_hypre_boomeramg_relax_type_coarse": "l1scaled-SOR/Jacobi",  # hypre's SetRelaxType: all levels
        "pc_hypre_boomeramg_no_CF": "",  # hypre's default lexicographic relaxation order
        "pc_hypre_boomeramg_strong_threshold": "0.8",
        "pc_hypre_boomeramg_agg_nl": "0",
        "pc_hypre_boomeramg_numfunctions": "3",
        "pc_hypre_boomeramg_max_iter": "1",
        "pc_hypre_boomeramg_tol": "0.0",
        "pc_hypre_boomeramg_max_levels": "25",
    }.items():
        opts[k] = v

    def ksp_new():
        ksp = PETSc.KSP().create(comm=comm)
        ksp.setOperators(A, A)
        ksp.setType(PETSc.KSP.Type.GMRES)
        ksp.setGMRESRestart(args.restart)
        ksp.setPCSide(PETSc.PC.Side.RIGHT)
        ksp.setNormType(PETSc.KSP.NormType.UNPRECONDITIONED)
        ksp.setTolerances(rtol=args.rtol, atol=0.0, max_it=5000)
        ksp.getPC().setType(PETSc.PC.Type.HYPRE)
        ksp.setFromOptions()
        return ksp

    setups, solves, its = [], [], None
    x = b.duplicate()
    for _ in range(args.reps):
        ksp = ksp_new()
        t0 = barrier_time()
        ksp.setUp()
        setups.append(barrier_time() - t0)
        x.set(0.0)
        t0 = barrier_time()
        ksp.solve(b, x)
        solves.append(barrier_time() - t0)
        its = ksp.getIterationNumber()
        reason = ksp.getConvergedReason()
        ksp.destroy()
    r = b.duplicate()
    A.mult(x, r)
    r.aypx(-1.0, b)
    true_rel = r.norm() / b.norm()
    med = lambda v: sorted(v)[len(v) // 2]  # noqa: E731
    rss = mpi.allgather(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0)
    out = {
        "ranks": size,
        "petsc_version": "%d.%d.%d" % PETSc.Sys.getVersion(),
        "unknowns": m,
        "pc": "hypre boomeramg",
        "setup_s": med(setups),
        "solve_s": med(solves),
        "total_s": med(setups) + med(solves),
        "gmres_iterations": its,
        "converged_reason": reason,
        "true_relative_residual": true_rel,
        "peak_rss_mb_per_rank": rss,
    }
    if rank == 0:
        print(json.dumps(out, indent=1))
        if args.json:
            with open(args.json, "w") as f:
                json.dump(out, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
