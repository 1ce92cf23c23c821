//! The few entry points of hypre (Debian's `libhypre-dev` 2.26, 32-bit `HYPRE_Int` and
//! `HYPRE_BigInt`, double precision, on the same Open MPI as rsmpi) that
//! [`super::amg::BoomerAmg`] needs: IJ matrices and vectors on ParCSR storage, and
//! BoomerAMG. Owned handles destroy themselves on drop; every call's error code becomes a
//! typed error naming the call.

#![allow(non_camel_case_types)]

use mpi::ffi::MPI_Comm;
use std::ffi::{c_char, c_int, c_void};
use std::ptr;

pub(crate) type HYPRE_Int = c_int;
pub(crate) type HYPRE_BigInt = c_int;

#[repr(C)]
pub(crate) struct Opaque {
    _p: [u8; 0],
}
type Handle = *mut Opaque;

/// `HYPRE_PARCSR` (HYPRE.h).
const HYPRE_PARCSR: HYPRE_Int = 5555;

#[link(name = "HYPRE")]
extern "C" {
    fn HYPRE_Init() -> HYPRE_Int;
    fn HYPRE_DescribeError(ierr: HYPRE_Int, descr: *mut c_char);
    fn HYPRE_ClearAllErrors() -> HYPRE_Int;

    fn HYPRE_IJMatrixCreate(
        comm: MPI_Comm,
        ilower: HYPRE_BigInt,
        iupper: HYPRE_BigInt,
        jlower: HYPRE_BigInt,
        jupper: HYPRE_BigInt,
        matrix: *mut Handle,
    ) -> HYPRE_Int;
    fn HYPRE_IJMatrixSetObjectType(matrix: Handle, t: HYPRE_Int) -> HYPRE_Int;
    fn HYPRE_IJMatrixSetDiagOffdSizes(
        matrix: Handle,
        diag: *const HYPRE_Int,
        offd: *const HYPRE_Int,
    ) -> HYPRE_Int;
    fn HYPRE_IJMatrixInitialize(matrix: Handle) -> HYPRE_Int;
    fn HYPRE_IJMatrixSetValues(
        matrix: Handle,
        nrows: HYPRE_Int,
        ncols: *mut HYPRE_Int,
        rows: *const HYPRE_BigInt,
        cols: *const HYPRE_BigInt,
        values: *const f64,
    ) -> HYPRE_Int;
    fn HYPRE_IJMatrixAssemble(matrix: Handle) -> HYPRE_Int;
    fn HYPRE_IJMatrixGetObject(matrix: Handle, object: *mut *mut c_void) -> HYPRE_Int;
    fn HYPRE_IJMatrixDestroy(matrix: Handle) -> HYPRE_Int;

    fn HYPRE_IJVectorCreate(
        comm: MPI_Comm,
        jlower: HYPRE_BigInt,
        jupper: HYPRE_BigInt,
        vector: *mut Handle,
    ) -> HYPRE_Int;
    fn HYPRE_IJVectorSetObjectType(vector: Handle, t: HYPRE_Int) -> HYPRE_Int;
    fn HYPRE_IJVectorInitialize(vector: Handle) -> HYPRE_Int;
    fn HYPRE_IJVectorSetValues(
        vector: Handle,
        n: HYPRE_Int,
        indices: *const HYPRE_BigInt,
        values: *const f64,
    ) -> HYPRE_Int;
    fn HYPRE_IJVectorGetValues(
        vector: Handle,
        n: HYPRE_Int,
        indices: *const HYPRE_BigInt,
        values: *mut f64,
    ) -> HYPRE_Int;
    fn HYPRE_IJVectorAssemble(vector: Handle) -> HYPRE_Int;
    fn HYPRE_IJVectorGetObject(vector: Handle, object: *mut *mut c_void) -> HYPRE_Int;
    fn HYPRE_IJVectorDestroy(vector: Handle) -> HYPRE_Int;

    fn HYPRE_BoomerAMGCreate(solver: *mut Handle) -> HYPRE_Int;
    fn HYPRE_BoomerAMGDestroy(solver: Handle) -> HYPRE_Int;
    fn HYPRE_BoomerAMGSetup(solver: Handle, a: Handle, b: Handle, x: Handle) -> HYPRE_Int;
    fn HYPRE_BoomerAMGSolve(solver: Handle, a: Handle, b: Handle, x: Handle) -> HYPRE_Int;
    fn HYPRE_BoomerAMGSetCoarsenType(solver: Handle, v: HYPRE_Int) -> HYPRE_Int;
    fn HYPRE_BoomerAMGSetAggNumLevels(solver: Handle, v: HYPRE_Int) -> HYPRE_Int;
    fn HYPRE_BoomerAMGSetRelaxType(solver: Handle, v: HYPRE_Int) -> HYPRE_Int;
    fn HYPRE_BoomerAMGSetNumSweeps(solver: Handle, v: HYPRE_Int) -> HYPRE_Int;
    fn HYPRE_BoomerAMGSetStrongThreshold(solver: Handle, v: f64) -> HYPRE_Int;
    fn HYPRE_BoomerAMGSetInterpType(solver: Handle, v: HYPRE_Int) -> HYPRE_Int;
    fn HYPRE_BoomerAMGSetPMaxElmts(solver: Handle, v: HYPRE_Int) -> HYPRE_Int;
    fn HYPRE_BoomerAMGSetPrintLevel(solver: Handle, v: HYPRE_Int) -> HYPRE_Int;
    fn HYPRE_BoomerAMGSetMaxLevels(solver: Handle, v: HYPRE_Int) -> HYPRE_Int;
    fn HYPRE_BoomerAMGSetMaxIter(solver: Handle, v: HYPRE_Int) -> HYPRE_Int;
    fn HYPRE_BoomerAMGSetTol(solver: Handle, v: f64) -> HYPRE_Int;
    fn HYPRE_BoomerAMGSetNumFunctions(solver: Handle, v: HYPRE_Int) -> HYPRE_Int;
    fn HYPRE_BoomerAMGSetNodal(solver: Handle, v: HYPRE_Int) -> HYPRE_Int;
    fn HYPRE_BoomerAMGSetNodalDiag(solver: Handle, v: HYPRE_Int) -> HYPRE_Int;
    fn HYPRE_BoomerAMGSetCycleRelaxType(solver: Handle, v: HYPRE_Int, k: HYPRE_Int) -> HYPRE_Int;
    fn HYPRE_BoomerAMGSetInterpVecVariant(solver: Handle, v: HYPRE_Int) -> HYPRE_Int;
    fn HYPRE_BoomerAMGSetInterpVecQMax(solver: Handle, v: HYPRE_Int) -> HYPRE_Int;
    fn HYPRE_BoomerAMGSetSmoothInterpVectors(solver: Handle, v: HYPRE_Int) -> HYPRE_Int;
    fn HYPRE_BoomerAMGSetInterpVectors(
        solver: Handle,
        n: HYPRE_Int,
        vectors: *mut Handle,
    ) -> HYPRE_Int;
}

#[link(name = "gomp")]
extern "C" {
    /// Debian's hypre is built with OpenMP; alfe runs one thread per MPI rank.
    fn omp_set_num_threads(n: c_int);
}

/// Initialize hypre once per process (one OpenMP thread per rank).
fn init() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| unsafe {
        omp_set_num_threads(1);
        HYPRE_Init();
    });
}

/// hypre's description of an error code.
fn describe(code: HYPRE_Int) -> String {
    let mut buf = [0 as c_char; 256];
    unsafe { HYPRE_DescribeError(code, buf.as_mut_ptr()) };
    let s = unsafe { std::ffi::CStr::from_ptr(buf.as_ptr()) };
    s.to_string_lossy().trim().to_string()
}

fn check(code: HYPRE_Int, call: &str) -> Result<(), String> {
    if code == 0 {
        return Ok(());
    }
    let what = describe(code);
    unsafe { HYPRE_ClearAllErrors() };
    Err(format!("hypre: {call} failed ({what})"))
}

/// A hypre index (32-bit in Debian's build): an error beyond 2³¹ unknowns.
pub(crate) fn big(i: usize) -> Result<HYPRE_BigInt, String> {
    HYPRE_BigInt::try_from(i).map_err(|_| {
        format!("hypre: index {i} exceeds the 32-bit HYPRE_BigInt of Debian's libhypre")
    })
}

/// A ParCSR matrix built through the IJ interface: rows `[lo, hi)` owned here.
pub(crate) struct IjMatrix {
    h: Handle,
    par: Handle,
}

impl IjMatrix {
    /// Collective. Rows `[lo, lo + n)` of the global scalar numbering, given in CSR: row
    /// `lo + i` has the global columns `cols[row_ptr[i]..row_ptr[i + 1]]` and their values, of
    /// which `diag[i]` are owned columns and the rest are not (hypre preallocates).
    pub(crate) fn new(
        comm: MPI_Comm,
        lo: usize,
        row_ptr: &[usize],
        cols: &[HYPRE_BigInt],
        vals: &[f64],
        diag: &[HYPRE_Int],
    ) -> Result<Self, String> {
        init();
        let n = row_ptr.len() - 1;
        let (l, u) = (big(lo)?, big(lo + n)? - 1);
        let mut ncols: Vec<HYPRE_Int> = row_ptr
            .windows(2)
            .map(|w| (w[1] - w[0]) as HYPRE_Int)
            .collect();
        let offd: Vec<HYPRE_Int> = ncols.iter().zip(diag).map(|(c, d)| c - d).collect();
        let rows: Vec<HYPRE_BigInt> = (l..=u).collect();
        let mut h: Handle = ptr::null_mut();
        check(
            unsafe { HYPRE_IJMatrixCreate(comm, l, u, l, u, &mut h) },
            "HYPRE_IJMatrixCreate",
        )?;
        let mut m = Self {
            h,
            par: ptr::null_mut(),
        };
        check(
            unsafe { HYPRE_IJMatrixSetObjectType(h, HYPRE_PARCSR) },
            "HYPRE_IJMatrixSetObjectType",
        )?;
        check(
            unsafe { HYPRE_IJMatrixSetDiagOffdSizes(h, diag.as_ptr(), offd.as_ptr()) },
            "HYPRE_IJMatrixSetDiagOffdSizes",
        )?;
        check(
            unsafe { HYPRE_IJMatrixInitialize(h) },
            "HYPRE_IJMatrixInitialize",
        )?;
        if n > 0 {
            check(
                unsafe {
                    HYPRE_IJMatrixSetValues(
                        h,
                        n as HYPRE_Int,
                        ncols.as_mut_ptr(),
                        rows.as_ptr(),
                        cols.as_ptr(),
                        vals.as_ptr(),
                    )
                },
                "HYPRE_IJMatrixSetValues",
            )?;
        }
        check(
            unsafe { HYPRE_IJMatrixAssemble(h) },
            "HYPRE_IJMatrixAssemble",
        )?;
        let mut obj: *mut c_void = ptr::null_mut();
        check(
            unsafe { HYPRE_IJMatrixGetObject(h, &mut obj) },
            "HYPRE_IJMatrixGetObject",
        )?;
        m.par = obj.cast();
        Ok(m)
    }
}

impl Drop for IjMatrix {
    fn drop(&mut self) {
        unsafe { HYPRE_IJMatrixDestroy(self.h) };
    }
}

/// A ParVector built through the IJ interface: entries `[lo, hi)` owned here.
pub(crate) struct IjVector {
    h: Handle,
    par: Handle,
    n: usize,
    /// The owned indices `lo..hi`, for reads.
    idx: Vec<HYPRE_BigInt>,
}

impl IjVector {
    /// Collective. A vector of owned entries `[lo, hi)` set to `values` (or zero).
    pub(crate) fn new(
        comm: MPI_Comm,
        lo: usize,
        hi: usize,
        values: Option<&[f64]>,
    ) -> Result<Self, String> {
        init();
        let (l, u) = (big(lo)?, big(hi)? - 1);
        let mut h: Handle = ptr::null_mut();
        check(
            unsafe { HYPRE_IJVectorCreate(comm, l, u, &mut h) },
            "HYPRE_IJVectorCreate",
        )?;
        let mut v = Self {
            h,
            par: ptr::null_mut(),
            n: hi - lo,
            idx: (l..=u).collect(),
        };
        check(
            unsafe { HYPRE_IJVectorSetObjectType(h, HYPRE_PARCSR) },
            "HYPRE_IJVectorSetObjectType",
        )?;
        check(
            unsafe { HYPRE_IJVectorInitialize(h) },
            "HYPRE_IJVectorInitialize",
        )?;
        let zeros;
        let vals = match values {
            Some(v) => v,
            None => {
                zeros = vec![0.0; hi - lo];
                &zeros
            }
        };
        v.set(vals)?;
        check(
            unsafe { HYPRE_IJVectorAssemble(h) },
            "HYPRE_IJVectorAssemble",
        )?;
        let mut obj: *mut c_void = ptr::null_mut();
        check(
            unsafe { HYPRE_IJVectorGetObject(h, &mut obj) },
            "HYPRE_IJVectorGetObject",
        )?;
        v.par = obj.cast();
        Ok(v)
    }

    /// Overwrite the owned entries (local, no communication).
    pub(crate) fn set(&self, vals: &[f64]) -> Result<(), String> {
        assert_eq!(vals.len(), self.n);
        if self.n == 0 {
            return Ok(());
        }
        check(
            unsafe {
                HYPRE_IJVectorSetValues(
                    self.h,
                    self.n as HYPRE_Int,
                    self.idx.as_ptr(),
                    vals.as_ptr(),
                )
            },
            "HYPRE_IJVectorSetValues",
        )
    }

    /// Read the owned entries.
    pub(crate) fn get(&self, out: &mut [f64]) -> Result<(), String> {
        assert_eq!(out.len(), self.n);
        if self.n == 0 {
            return Ok(());
        }
        check(
            unsafe {
                HYPRE_IJVectorGetValues(
                    self.h,
                    self.n as HYPRE_Int,
                    self.idx.as_ptr(),
                    out.as_mut_ptr(),
                )
            },
            "HYPRE_IJVectorGetValues",
        )
    }
}

impl Drop for IjVector {
    fn drop(&mut self) {
        unsafe { HYPRE_IJVectorDestroy(self.h) };
    }
}

/// BoomerAMG's strength threshold θ. MFEM's systems options take 0.5; on
/// `hertz-sphere`'s geometrically graded mesh (1.3 mm cells at the contact, 60 mm far
/// away) that gave 83 GMRES iterations per Newton iteration, 0.7 gave 75, **0.8 gave 25**
/// and 0.9 25 (penalty contact, 1 rank, rtol 10⁻¹⁰); on the uniform elastic block of
/// `alfe-bench linear --cells 36,36,36` 0.8 costs 18 iterations against 14 at 0.5.
const STRONG_THRESHOLD: f64 = 0.8;

/// BoomerAMG as a preconditioner (one V-cycle, zero tolerance) with the options MFEM's
/// `HypreBoomerAMG::SetElasticityOptions` uses for 3D elasticity: systems AMG with three
/// functions per node, nodal coarsening, and the GM-2 interpolation of the rigid-body
/// rotations (Baker, Kolev, Yang 2010).
pub(crate) struct Amg {
    h: Handle,
    /// The rotations given to hypre; it keeps their pointers, so they live as long.
    _rbms: Vec<IjVector>,
    _rbm_handles: Vec<Handle>,
}

impl Amg {
    /// Create and set up on `a` (b, x: work vectors of its size); `rbms` are the
    /// rotational rigid-body modes (none for scalar systems AMG).
    pub(crate) fn setup(
        a: &IjMatrix,
        b: &IjVector,
        x: &IjVector,
        rbms: Vec<IjVector>,
    ) -> Result<Self, String> {
        init();
        let mut h: Handle = ptr::null_mut();
        check(
            unsafe { HYPRE_BoomerAMGCreate(&mut h) },
            "HYPRE_BoomerAMGCreate",
        )?;
        let mut amg = Self {
            h,
            _rbm_handles: rbms.iter().map(|v| v.par).collect(),
            _rbms: rbms,
        };
        unsafe {
            // MFEM's defaults for CPUs (HMIS, ext+i interpolation, l1-GS smoothing).
            HYPRE_BoomerAMGSetCoarsenType(h, 10);
            HYPRE_BoomerAMGSetInterpType(h, 6);
            HYPRE_BoomerAMGSetPMaxElmts(h, 4);
            HYPRE_BoomerAMGSetRelaxType(h, 8);
            HYPRE_BoomerAMGSetNumSweeps(h, 1);
            HYPRE_BoomerAMGSetPrintLevel(h, 0);
            HYPRE_BoomerAMGSetMaxLevels(h, 25);
            HYPRE_BoomerAMGSetMaxIter(h, 1);
            HYPRE_BoomerAMGSetTol(h, 0.0);
            // Systems options: three unknowns per node, interleaved.
            HYPRE_BoomerAMGSetNumFunctions(h, 3);
            HYPRE_BoomerAMGSetAggNumLevels(h, 0);
            HYPRE_BoomerAMGSetStrongThreshold(h, STRONG_THRESHOLD);
            if !amg._rbm_handles.is_empty() {
                // Elasticity: nodal coarsening and the rigid-body rotations.
                HYPRE_BoomerAMGSetNodal(h, 4);
                HYPRE_BoomerAMGSetNodalDiag(h, 1);
                HYPRE_BoomerAMGSetCycleRelaxType(h, 8, 3);
                HYPRE_BoomerAMGSetInterpVecVariant(h, 2);
                HYPRE_BoomerAMGSetInterpVecQMax(h, 4);
                HYPRE_BoomerAMGSetSmoothInterpVectors(h, 1);
                HYPRE_BoomerAMGSetInterpVectors(
                    h,
                    amg._rbm_handles.len() as HYPRE_Int,
                    amg._rbm_handles.as_mut_ptr(),
                );
            }
        }
        // As MFEM does with these options, errors of the setup are not fatal (coarse
        // grids may be singular, which the solve handles); the solve's output is checked.
        unsafe {
            HYPRE_BoomerAMGSetup(h, a.par, b.par, x.par);
            HYPRE_ClearAllErrors();
        }
        Ok(amg)
    }

    /// One V-cycle: x ≈ A⁻¹ b (x is overwritten).
    pub(crate) fn solve(&self, a: &IjMatrix, b: &IjVector, x: &IjVector) {
        unsafe {
            HYPRE_BoomerAMGSolve(self.h, a.par, b.par, x.par);
            HYPRE_ClearAllErrors();
        }
    }
}

impl Drop for Amg {
    fn drop(&mut self) {
        unsafe { HYPRE_BoomerAMGDestroy(self.h) };
    }
}
