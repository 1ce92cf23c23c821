#!/usr/bin/python3
"""PETSc peers for alfe's domain-decomposition preconditioners, on a system written by
`alfe run --export-system DIR` (or `alfe-bench linear --export DIR`).

Usage (Debian's petsc4py: /usr/bin/python3 with PETSC_DIR set, see SETUP.md):

    PETSC_DIR=/usr/lib/petscdir/petsc3.18/x86_64-linux-gnu-real \\
    mpirun -n R /usr/bin/python3 scripts/petsc_dd.py DIR --pc asm|bddc|gamg|hpddm|mumps|bjacobi \\
        [--overlap K] [--solver mumps|umfpack] [--rtol 1e-10] [--json OUT.json] [-- PETSc options]

Rows are distributed as alfe distributed them (`system.json`'s `owned_dofs_per_rank`,
which needs R to be alfe's rank count; otherwise PETSc's even split). GMRES(60), right
preconditioning (rtol bounds the true residual, as alfe's), x0 = 0. The preconditioners:
  * asm:     restricted additive Schwarz, `--overlap` layers, exact LU sub-solves (`--solver`);
  * bjacobi: one block per rank, exact LU;
  * bddc:    PCBDDC on the matrix converted to MATIS (PETSc's algebraic subassembly of
             the assembled rows: PETSc's documented route for an assembled AIJ matrix),
             rigid-body modes from coords.petsc as near-null space;
  * gamg:    smoothed aggregation with the rigid-body near-null space;
  * hpddm:   PCHPDDM (GenEO) if this PETSc has it;
  * mumps:   a distributed direct solve (preonly + MUMPS LU).
Times between barriers: setup_s (KSPSetUp, the factorizations and coarse spaces), solve_s
(KSPSolve), and the true relative residual. Prints one JSON object (rank 0).
"""
import argparse
import json
import os
import resource
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from petsc_system import load_system  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dir")
    ap.add_argument("--pc", default="asm")
    ap.add_argument("--overlap", type=int, default=1)
    ap.add_argument("--solver", default="mumps")
    ap.add_argument("--rtol", type=float, default=1e-10)
    ap.add_argument("--restart", type=int, default=60)
    ap.add_argument("--max-it", type=int, default=5000)
    ap.add_argument("--even", action="store_true", help="PETSc's even row split instead of alfe's")
    ap.add_argument("--json", default=None)
    args, petsc_args = ap.parse_known_args()
    if petsc_args[:1] == ["--"]:
        petsc_args = petsc_args[1:]

    import petsc4py

    petsc4py.init([sys.argv[0]] + petsc_args)
    from petsc4py import PETSc

    comm = PETSc.COMM_WORLD
    mpi = comm.tompi4py()
    rank, size = comm.getRank(), comm.getSize()
    meta = json.load(open(os.path.join(args.dir, "system.json")))
    rows = meta["owned_dofs_per_rank"]
    local_rows = None if (args.even or len(rows) != size) else ",".join(str(r) for r in rows)

    def barrier_time():
        mpi.Barrier()
        return time.perf_counter()

    A, b, m, nnz = load_system(PETSc, comm, os.path.join(args.dir, "A.petsc"), os.path.join(args.dir, "b.petsc"), local_rows)
    coords = PETSc.Vec().create(comm=comm)
    coords.setSizes(b.getSizes())
    coords.setType(PETSc.Vec.Type.STANDARD)
    v = PETSc.Viewer().createBinary(os.path.join(args.dir, "coords.petsc"), "r", comm=comm)
    coords.load(v)
    v.destroy()
    A.setBlockSize(3)
    coords.setBlockSize(3)
    nullsp = PETSc.NullSpace().createRigidBody(coords)

    opts = PETSc.Options()
    ksp = PETSc.KSP().create(comm=comm)
    ksp.setType(PETSc.KSP.Type.GMRES)
    ksp.setGMRESRestart(args.restart)
    ksp.setPCSide(PETSc.PC.Side.RIGHT)
    ksp.setNormType(PETSc.KSP.NormType.UNPRECONDITIONED)
    ksp.setTolerances(rtol=args.rtol, atol=0.0, max_it=args.max_it)
    pc = ksp.getPC()
    op = A
    if args.pc == "asm":
        pc.setType(PETSc.PC.Type.ASM)
        pc.setASMOverlap(args.overlap)
        pc.setASMType(PETSc.PC.ASMType.RESTRICT)
        opts["sub_ksp_type"] = "preonly"
        opts["sub_pc_type"] = "lu"
        opts["sub_pc_factor_mat_solver_type"] = args.solver
    elif args.pc == "bjacobi":
        pc.setType(PETSc.PC.Type.BJACOBI)
        opts["sub_ksp_type"] = "preonly"
        opts["sub_pc_type"] = "lu"
        opts["sub_pc_factor_mat_solver_type"] = args.solver
    elif args.pc == "bddc":
        op = A.convert(PETSc.Mat.Type.IS)
        op.setNearNullSpace(nullsp)
        pc.setType(PETSc.PC.Type.BDDC)
        opts.setValue("pc_bddc_use_vertices", True)
        opts.setValue("pc_bddc_use_edges", True)
        opts.setValue("pc_bddc_use_faces", True)
    elif args.pc == "gamg":
        A.setNearNullSpace(nullsp)
        pc.setType(PETSc.PC.Type.GAMG)
    elif args.pc == "hpddm":
        pc.setType("hpddm")
    elif args.pc == "mumps":
        ksp.setType(PETSc.KSP.Type.PREONLY)
        pc.setType(PETSc.PC.Type.LU)
        pc.setFactorSolverType("mumps")
    else:
        raise SystemExit(f"unknown --pc {args.pc}")
    ksp.setOperators(op, op)
    ksp.setFromOptions()
    t0 = barrier_time()
    ksp.setUp()
    if args.pc in ("asm", "bjacobi"):
        ksp.setUpOnBlocks()
    setup_s = barrier_time() - t0
    x = b.duplicate()
    x.set(0.0)
    t0 = barrier_time()
    ksp.solve(b, x)
    solve_s = barrier_time() - t0
    r = b.duplicate()
    A.mult(x, r)
    r.aypx(-1.0, b)
    rss = mpi.allgather(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0)
    out = {
        "petsc_version": "%d.%d.%d" % PETSc.Sys.getVersion(),
        "ranks": size,
        "pc": args.pc,
        "overlap": args.overlap if args.pc == "asm" else None,
        "sub_solver": args.solver if args.pc in ("asm", "bjacobi") else None,
        "unknowns": m,
        "alfe_rows": local_rows is not None,
        "setup_s": setup_s,
        "solve_s": solve_s,
        "time_to_tol_s": setup_s + solve_s,
        "iterations": ksp.getIterationNumber(),
        "converged_reason": int(ksp.getConvergedReason()),
        "converged": ksp.getConvergedReason() > 0,
        "rtol": args.rtol,
        "true_relative_residual": r.norm() / b.norm(),
        "peak_rss_mb_per_rank": rss,
    }
    if rank == 0:
        text = json.dumps(out, indent=1)
        print(text)
        if args.json:
            with open(args.json, "w") as f:
                f.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
