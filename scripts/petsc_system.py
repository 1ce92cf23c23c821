"""Loading an `alfe-bench linear --export` system into PETSc, shared by the PETSc peers
(petsc_bjacobi.py, petsc_amg.py): A and b from PETSc binary files, optionally on alfe's
row ownership so that each rank holds exactly alfe's rows."""
import struct


def load_system(PETSc, comm, a_path, b_path, local_rows=None):
    """(A, b, m, nnz): the AIJ matrix, the right-hand side, the global size and nonzeros; `local_rows` is
    a comma-separated row count per rank (alfe's `owned_dofs_per_rank`)."""
    rank, size = comm.getRank(), comm.getSize()
    with open(a_path, "rb") as f:
        cookie, m, ncols, nnz = struct.unpack(">4i", f.read(16))
    if cookie != 1211216 or m != ncols:
        raise SystemExit(f"{a_path}: not a square PETSc binary matrix")
    nloc = PETSc.DECIDE
    if local_rows:
        rows = [int(float(v)) for v in local_rows.split(",")]
        if len(rows) != size or sum(rows) != m:
            raise SystemExit(f"--local-rows: {len(rows)} counts summing to {sum(rows)}; need {size} summing to {m}")
        nloc = rows[rank]
    viewer = PETSc.Viewer().createBinary(a_path, "r", comm=comm)
    A = PETSc.Mat().create(comm=comm)
    A.setType(PETSc.Mat.Type.AIJ)
    A.setSizes(((nloc, m), (nloc, m)))
    A.load(viewer)
    viewer.destroy()
    viewer = PETSc.Viewer().createBinary(b_path, "r", comm=comm)
    b = PETSc.Vec().create(comm=comm)
    b.setSizes((nloc, m))
    b.setType(PETSc.Vec.Type.STANDARD)
    b.load(viewer)
    viewer.destroy()
    return A, b, m, nnz
