//! One HDF5 file per run, written collectively by all ranks (MPI-IO), over `hdf5-sys`.
//!
//! Why raw `hdf5-sys` and not the `hdf5` crate: its slice writes are independent I/O;
//! here every dataset write is one `H5Dwrite` per rank with a collective transfer
//! property list, each rank writing its own contiguous block of rows through a
//! hyperslab. Data is never gathered on one rank.
//!
//! Collective contract: every method (and `Drop`, which closes the file) must be
//! called by all ranks, in the same order, with the same paths, names, global shapes
//! and attribute values; only `row0` and `data` differ between ranks. Argument errors
//! (a `data` length that is not whole rows, rows outside the dataset) are agreed on by
//! all ranks before any HDF5 call, so every rank returns the same error. A failure
//! inside HDF5 itself is reported on the ranks where it happened; the caller should
//! treat any error from this module as fatal for the whole job.
//!
//! HDF5 is not thread-safe in Debian's parallel build: every call here holds
//! `hdf5_sys::LOCK` (in-process unit tests run on several threads).

use crate::parallel::Comm;
use crate::{Error, Result};
use hdf5_sys::h5::{herr_t, hsize_t, H5open};
use hdf5_sys::h5a::{H5Aclose, H5Acreate2, H5Adelete, H5Aexists, H5Awrite};
use hdf5_sys::h5d::{H5Dclose, H5Dcreate2, H5Dwrite};
use hdf5_sys::h5e::{
    H5E_error2_t, H5Eclear2, H5Eset_auto2, H5Ewalk2, H5E_DEFAULT, H5E_WALK_UPWARD,
};
use hdf5_sys::h5f::{H5F_scope_t, H5Fclose, H5Fcreate, H5Fflush, H5F_ACC_TRUNC};
use hdf5_sys::h5g::{H5Gclose, H5Gcreate2};
use hdf5_sys::h5i::hid_t;
use hdf5_sys::h5l::H5Lexists;
use hdf5_sys::h5o::{H5Oclose, H5Oopen};
use hdf5_sys::h5p::{
    H5FD_mpio_xfer_t, H5Pclose, H5Pcreate, H5Pset_create_intermediate_group, H5Pset_dxpl_mpio,
    H5Pset_fapl_mpio, H5P_CLS_DATASET_XFER, H5P_CLS_FILE_ACCESS, H5P_CLS_LINK_CREATE, H5P_DEFAULT,
};
use hdf5_sys::h5s::{
    H5S_class_t, H5S_seloper_t, H5Sclose, H5Screate, H5Screate_simple, H5Sselect_hyperslab,
    H5Sselect_none,
};
use hdf5_sys::h5t::{
    H5T_cset_t, H5T_str_t, H5Tclose, H5Tcopy, H5Tset_cset, H5Tset_size, H5Tset_strpad, H5T_C_S1,
    H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, H5T_NATIVE_INT32, H5T_NATIVE_INT64, H5T_STD_I32LE,
    H5T_STD_I64LE,
};
use std::cell::Cell;
use std::ffi::{c_char, c_int, c_uint, c_void, CStr, CString};
use std::path::{Path, PathBuf};
use std::sync::Once;

unsafe extern "C" {
    /// Not bound by hdf5-sys: how the last `H5Dwrite` with this transfer list was done
    /// (an `H5D_mpio_actual_io_mode_t`, a C enum).
    fn H5Pget_mpio_actual_io_mode(dxpl_id: hid_t, actual_io_mode: *mut c_int) -> herr_t;
}

/// `H5D_MPIO_CONTIGUOUS_COLLECTIVE`: what a collective write to a contiguous dataset reports.
const CONTIGUOUS_COLLECTIVE: c_int =
    hdf5_sys::h5d::H5D_mpio_actual_io_mode_t::H5D_MPIO_CONTIGUOUS_COLLECTIVE as c_int;

/// Initialise the library once per process and silence HDF5's own error printing:
/// failures come back as one-line [`Error`]s instead.
fn init() {
    static INIT: Once = Once::new();
    INIT.call_once(|| unsafe {
        let _g = hdf5_sys::LOCK.lock();
        H5open();
        H5Eset_auto2(H5E_DEFAULT, None, std::ptr::null_mut());
    });
}

/// The most specific message on HDF5's error stack (then cleared), e.g. "name already exists".
fn hdf5_detail() -> String {
    unsafe extern "C" fn first(_n: c_uint, e: *const H5E_error2_t, data: *mut c_void) -> herr_t {
        let out = &mut *(data as *mut Option<String>);
        if out.is_none() && !e.is_null() && !(*e).desc.is_null() {
            let d = CStr::from_ptr((*e).desc)
                .to_string_lossy()
                .trim()
                .to_string();
            if !d.is_empty() {
                *out = Some(d);
            }
        }
        0
    }
    let mut out: Option<String> = None;
    unsafe {
        H5Ewalk2(
            H5E_DEFAULT,
            H5E_WALK_UPWARD,
            Some(first),
            &mut out as *mut _ as *mut c_void,
        );
        H5Eclear2(H5E_DEFAULT);
    }
    out.unwrap_or_else(|| "no HDF5 detail".to_string())
}

/// An HDF5 handle closed on drop (so early returns leak nothing).
struct Handle {
    id: hid_t,
    close: unsafe extern "C" fn(hid_t) -> herr_t,
}

impl Drop for Handle {
    fn drop(&mut self) {
        unsafe {
            if (self.close)(self.id) < 0 {
                H5Eclear2(H5E_DEFAULT);
            }
        }
    }
}

/// Element types that can be written as dataset rows.
pub trait H5Elem: Copy {
    const NAME: &'static str;
    fn mem_type() -> hid_t;
    fn file_type() -> hid_t;
}

impl H5Elem for f64 {
    const NAME: &'static str = "f64";
    fn mem_type() -> hid_t {
        *H5T_NATIVE_DOUBLE
    }
    fn file_type() -> hid_t {
        *H5T_IEEE_F64LE
    }
}

impl H5Elem for i64 {
    const NAME: &'static str = "i64";
    fn mem_type() -> hid_t {
        *H5T_NATIVE_INT64
    }
    fn file_type() -> hid_t {
        *H5T_STD_I64LE
    }
}

impl H5Elem for i32 {
    const NAME: &'static str = "i32";
    fn mem_type() -> hid_t {
        *H5T_NATIVE_INT32
    }
    fn file_type() -> hid_t {
        *H5T_STD_I32LE
    }
}

/// One HDF5 file, open for writing by all ranks of a communicator.
///
/// Dropping it closes every handle (collectively under MPI): drop it on all ranks,
/// before the MPI `Universe`.
pub struct H5File {
    file: hid_t,
    /// Dataset transfer list: collective MPI-IO, or `H5P_DEFAULT` for a serial run.
    dxpl: hid_t,
    /// Link creation list that creates missing parent groups.
    lcpl: hid_t,
    /// Our own duplicate of the communicator, for agreeing on argument errors.
    comm: Option<mpi::ffi::MPI_Comm>,
    path: PathBuf,
    /// Dataset writes that HDF5 reports it did not do collectively (MPI runs only).
    not_collective: Cell<u64>,
    /// A collective operation failed: HDF5's ranks may no longer agree on the file's
    /// metadata, and a parallel H5Fclose can then wait for ever (measured on a full
    /// disk: one rank in a metadata-flush barrier, the other in the truncate's
    /// broadcast). Such a file is not closed; what the last flush wrote stays readable.
    poisoned: Cell<bool>,
}

/// Set when a parallel file was left open after a failed write: the process must end
/// with `MPI_Abort`, since `MPI_Finalize` would make HDF5 close it (and wait).
pub static LEFT_OPEN: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

fn cstring(what: &str, s: &str) -> Result<CString> {
    CString::new(s).map_err(|_| Error::runtime(format!("HDF5: {what} {s:?} contains a NUL byte")))
}

impl H5File {
    /// Collective create (truncating an existing file). With `comm.raw_mpi()` =
    /// `Some(c)` the file is opened with the MPI-IO driver on `c` (`MPI_INFO_NULL`);
    /// with `None`, the default sec2 driver (one process).
    pub fn create(comm: &dyn Comm, path: &Path) -> Result<Self> {
        init();
        let _g = hdf5_sys::LOCK.lock();
        let cpath = {
            use std::os::unix::ffi::OsStrExt;
            CString::new(path.as_os_str().as_bytes()).map_err(|_| {
                Error::runtime(format!(
                    "HDF5: file name {} contains a NUL byte",
                    path.display()
                ))
            })?
        };
        let fail = |what: &str| {
            Error::runtime(format!(
                "HDF5: cannot create file {}: {what}: {}",
                path.display(),
                hdf5_detail()
            ))
        };
        unsafe {
            let raw = comm.raw_mpi();
            let fapl = H5Pcreate(*H5P_CLS_FILE_ACCESS);
            if fapl < 0 {
                return Err(fail("H5Pcreate(file access)"));
            }
            let fapl = Handle {
                id: fapl,
                close: H5Pclose,
            };
            if let Some(c) = raw {
                if H5Pset_fapl_mpio(fapl.id, c, mpi::ffi::RSMPI_INFO_NULL) < 0 {
                    return Err(fail("H5Pset_fapl_mpio"));
                }
            }
            let file = H5Fcreate(cpath.as_ptr(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.id);
            if file < 0 {
                return Err(fail("H5Fcreate"));
            }
            let file = Handle {
                id: file,
                close: H5Fclose,
            };
            let dxpl = if raw.is_some() {
                let d = H5Pcreate(*H5P_CLS_DATASET_XFER);
                if d < 0 {
                    return Err(fail("H5Pcreate(dataset transfer)"));
                }
                let d = Handle {
                    id: d,
                    close: H5Pclose,
                };
                if H5Pset_dxpl_mpio(d.id, H5FD_mpio_xfer_t::H5FD_MPIO_COLLECTIVE) < 0 {
                    return Err(fail("H5Pset_dxpl_mpio(collective)"));
                }
                Some(d)
            } else {
                None
            };
            let lcpl = H5Pcreate(*H5P_CLS_LINK_CREATE);
            if lcpl < 0 {
                return Err(fail("H5Pcreate(link create)"));
            }
            let lcpl = Handle {
                id: lcpl,
                close: H5Pclose,
            };
            if H5Pset_create_intermediate_group(lcpl.id, 1) < 0 {
                return Err(fail("H5Pset_create_intermediate_group"));
            }
            let dup = match raw {
                Some(c) => {
                    let mut d: mpi::ffi::MPI_Comm = std::mem::zeroed();
                    if mpi::ffi::MPI_Comm_dup(c, &mut d) != 0 {
                        return Err(Error::runtime(format!(
                            "HDF5: cannot create file {}: MPI_Comm_dup failed",
                            path.display()
                        )));
                    }
                    Some(d)
                }
                None => None,
            };
            // Every handle is good: hand them to the struct, whose Drop closes them.
            let out = H5File {
                file: file.id,
                dxpl: dxpl.as_ref().map_or(H5P_DEFAULT, |d| d.id),
                lcpl: lcpl.id,
                comm: dup,
                path: path.to_path_buf(),
                not_collective: Cell::new(0),
                poisoned: Cell::new(false),
            };
            std::mem::forget(file);
            std::mem::forget(lcpl);
            if let Some(d) = dxpl {
                std::mem::forget(d);
            }
            Ok(out)
        }
    }

    /// The file's path as given to [`H5File::create`].
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn err(&self, what: String) -> Error {
        Error::runtime(format!(
            "HDF5 {}: {what}: {}",
            self.path.display(),
            hdf5_detail()
        ))
    }

    /// True on every rank iff `ok` on every rank (identity for a serial file).
    fn agree(&self, ok: bool) -> bool {
        match self.comm {
            None => ok,
            Some(c) => {
                let send: u64 = if ok { 0 } else { 1 };
                let mut recv: u64 = 0;
                unsafe {
                    mpi::ffi::MPI_Allreduce(
                        &send as *const u64 as *const c_void,
                        &mut recv as *mut u64 as *mut c_void,
                        1,
                        mpi::ffi::RSMPI_UINT64_T,
                        mpi::ffi::RSMPI_MAX,
                        c,
                    );
                }
                recv == 0
            }
        }
    }

    /// Every rank learns whether a collective operation failed on any rank (a full disk
    /// may fail one rank's part only): all return the error together, so none goes on
    /// to the next collective call and waits there for ever.
    fn agreed(&self, what: &str, r: Result<()>) -> Result<()> {
        let ok = self.agree(r.is_ok());
        if !ok {
            self.poisoned.set(true);
        }
        match (r, ok) {
            (Err(e), _) => Err(e),
            (Ok(()), false) => Err(Error::runtime(format!(
                "HDF5 {}: {what} failed on another rank",
                self.path.display()
            ))),
            (Ok(()), true) => Ok(()),
        }
    }

    /// Collective: create a group and any missing parents (e.g. "/steps/000003").
    /// A group that already exists is not an error.
    pub fn create_group(&self, path: &str) -> Result<()> {
        let r = self.create_group_here(path);
        self.agreed(&format!("group '{path}'"), r)
    }

    /// Collective: a scalar f64 attribute `name` on object `obj` ("/" for the file's
    /// root, a group or a dataset path), replacing any existing one. Same value on all ranks.
    pub fn write_attr_f64(&self, obj: &str, name: &str, v: f64) -> Result<()> {
        let r = self.write_attr_f64_here(obj, name, v);
        self.agreed(&format!("attribute '{name}' on '{obj}'"), r)
    }

    /// Collective: a scalar string attribute (fixed-length, UTF-8, NUL-terminated).
    pub fn write_attr_str(&self, obj: &str, name: &str, v: &str) -> Result<()> {
        let r = self.write_attr_str_here(obj, name, v);
        self.agreed(&format!("attribute '{name}' on '{obj}'"), r)
    }

    /// Collective flush of everything written so far to disk (survives a later failure).
    pub fn flush(&self) -> Result<()> {
        let r = self.flush_here();
        self.agreed("H5Fflush", r)
    }

    /// How many dataset writes on this rank HDF5 reports it did *not* do as one
    /// collective MPI-IO operation (always 0 for a serial file). A check for tests and
    /// logs: a type conversion or a chunked layout could make HDF5 fall back silently.
    pub fn independent_writes(&self) -> u64 {
        self.not_collective.get()
    }

    /// Collective: create a group and any missing parents (e.g. "/steps/000003").
    /// A group that already exists is not an error.
    fn create_group_here(&self, path: &str) -> Result<()> {
        let _g = hdf5_sys::LOCK.lock();
        let cpath = cstring("group path", path)?;
        if self.link_exists(path)? {
            return Ok(());
        }
        unsafe {
            let g = H5Gcreate2(
                self.file,
                cpath.as_ptr(),
                self.lcpl,
                H5P_DEFAULT,
                H5P_DEFAULT,
            );
            if g < 0 {
                return Err(self.err(format!("cannot create group '{path}'")));
            }
            if H5Gclose(g) < 0 {
                return Err(self.err(format!("cannot close group '{path}'")));
            }
        }
        Ok(())
    }

    /// Whether every component of `path` exists (checked one prefix at a time, as
    /// `H5Lexists` requires).
    fn link_exists(&self, path: &str) -> Result<bool> {
        let absolute = path.starts_with('/');
        let mut prefix = String::new();
        for comp in path.split('/').filter(|c| !c.is_empty()) {
            if absolute || !prefix.is_empty() {
                prefix.push('/');
            }
            prefix.push_str(comp);
            let c = cstring("path", &prefix)?;
            let e = unsafe { H5Lexists(self.file, c.as_ptr(), H5P_DEFAULT) };
            if e < 0 {
                return Err(self.err(format!("cannot look up '{prefix}'")));
            }
            if e == 0 {
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// Collective: create a dataset of global shape `(n_rows, n_cols)` (a 1-D dataset
    /// of `n_rows` when `n_cols == 1`; missing parent groups are created) and write
    /// this rank's rows `[row0, row0 + data.len() / n_cols)` with a collective
    /// hyperslab write. A rank with no rows passes an empty `data` (any `row0`).
    pub fn write_rows_f64(
        &self,
        path: &str,
        n_rows: u64,
        n_cols: u64,
        row0: u64,
        data: &[f64],
    ) -> Result<()> {
        self.write_rows(path, n_rows, n_cols, row0, data)
    }

    /// As [`H5File::write_rows_f64`], for 64-bit integers (ids, connectivity).
    pub fn write_rows_i64(
        &self,
        path: &str,
        n_rows: u64,
        n_cols: u64,
        row0: u64,
        data: &[i64],
    ) -> Result<()> {
        self.write_rows(path, n_rows, n_cols, row0, data)
    }

    /// As [`H5File::write_rows_f64`], for 32-bit integers (partition ids, flags).
    pub fn write_rows_i32(
        &self,
        path: &str,
        n_rows: u64,
        n_cols: u64,
        row0: u64,
        data: &[i32],
    ) -> Result<()> {
        self.write_rows(path, n_rows, n_cols, row0, data)
    }

    fn write_rows<T: H5Elem>(
        &self,
        path: &str,
        n_rows: u64,
        n_cols: u64,
        row0: u64,
        data: &[T],
    ) -> Result<()> {
        let rows = (data.len() as u64).checked_div(n_cols).unwrap_or(0);
        self.write_row_blocks(path, n_rows, n_cols, &[(row0, rows)], data)
    }

    /// Collective: as [`H5File::write_rows_f64`], but this rank's rows go to several
    /// blocks `(row0, rows)` of the dataset, in order (`data` holds them one after the
    /// other): a rank's elements of each part where the file keeps parts contiguous.
    pub fn write_row_blocks<T: H5Elem>(
        &self,
        path: &str,
        n_rows: u64,
        n_cols: u64,
        blocks: &[(u64, u64)],
        data: &[T],
    ) -> Result<()> {
        let r = self.write_rows_here(path, n_rows, n_cols, blocks, data);
        self.agreed(&format!("dataset '{path}'"), r)
    }

    fn write_rows_here<T: H5Elem>(
        &self,
        path: &str,
        n_rows: u64,
        n_cols: u64,
        blocks: &[(u64, u64)],
        data: &[T],
    ) -> Result<()> {
        let _g = hdf5_sys::LOCK.lock();
        // Check the arguments locally, then agree, so that a bad call on one rank
        // fails on every rank before any collective HDF5 call.
        let local_rows = (data.len() as u64).checked_div(n_cols).unwrap_or(0);
        let problem = if n_cols == 0 {
            Some("n_cols is 0".to_string())
        } else if !(data.len() as u64).is_multiple_of(n_cols) {
            Some(format!(
                "{} values are not whole rows of {n_cols}",
                data.len()
            ))
        } else if blocks.iter().map(|b| b.1).sum::<u64>() != local_rows {
            Some(format!(
                "{local_rows} rows of data for blocks of {} rows",
                blocks.iter().map(|b| b.1).sum::<u64>()
            ))
        } else if let Some((row0, rows)) = blocks
            .iter()
            .find(|&&(r0, k)| k > 0 && r0.checked_add(k).is_none_or(|e| e > n_rows))
        {
            Some(format!(
                "rows {row0}..{} outside 0..{n_rows}",
                row0.saturating_add(*rows)
            ))
        } else if path.is_empty() || path.contains('\0') {
            Some(format!("bad dataset path {path:?}"))
        } else {
            None
        };
        let all_ok = self.agree(problem.is_none());
        if let Some(p) = problem {
            return Err(Error::runtime(format!(
                "HDF5 {}: dataset '{path}' ({}): {p}",
                self.path.display(),
                T::NAME
            )));
        }
        if !all_ok {
            return Err(Error::runtime(format!(
                "HDF5 {}: dataset '{path}': bad arguments on another rank",
                self.path.display()
            )));
        }
        let cpath = cstring("dataset path", path)?;
        let (rank, file_dims, mem_dims): (i32, [hsize_t; 2], [hsize_t; 2]) = if n_cols == 1 {
            (1, [n_rows, 0], [local_rows.max(1), 0])
        } else {
            (2, [n_rows, n_cols], [local_rows.max(1), n_cols])
        };
        let ds = |what: &str| format!("dataset '{path}' {what}");
        unsafe {
            let fspace = H5Screate_simple(rank, file_dims.as_ptr(), std::ptr::null());
            if fspace < 0 {
                return Err(self.err(ds(&format!("H5Screate_simple({n_rows} x {n_cols})"))));
            }
            let fspace = Handle {
                id: fspace,
                close: H5Sclose,
            };
            let dset = H5Dcreate2(
                self.file,
                cpath.as_ptr(),
                T::file_type(),
                fspace.id,
                self.lcpl,
                H5P_DEFAULT,
                H5P_DEFAULT,
            );
            if dset < 0 {
                return Err(self.err(ds("H5Dcreate2")));
            }
            let dset = Handle {
                id: dset,
                close: H5Dclose,
            };
            let mspace = H5Screate_simple(rank, mem_dims.as_ptr(), std::ptr::null());
            if mspace < 0 {
                return Err(self.err(ds("H5Screate_simple(memory)")));
            }
            let mspace = Handle {
                id: mspace,
                close: H5Sclose,
            };
            if local_rows == 0 {
                if H5Sselect_none(fspace.id) < 0 || H5Sselect_none(mspace.id) < 0 {
                    return Err(self.err(ds("H5Sselect_none")));
                }
            } else {
                if H5Sselect_none(fspace.id) < 0 {
                    return Err(self.err(ds("H5Sselect_none")));
                }
                for &(row0, rows) in blocks.iter().filter(|b| b.1 > 0) {
                    let start: [hsize_t; 2] = [row0, 0];
                    let count: [hsize_t; 2] = [rows, n_cols];
                    if H5Sselect_hyperslab(
                        fspace.id,
                        H5S_seloper_t::H5S_SELECT_OR,
                        start.as_ptr(),
                        std::ptr::null(),
                        count.as_ptr(),
                        std::ptr::null(),
                    ) < 0
                    {
                        return Err(self.err(ds(&format!(
                            "H5Sselect_hyperslab(rows {row0}..{})",
                            row0 + rows
                        ))));
                    }
                }
            }
            // A rank with no rows still calls H5Dwrite (collective); its buffer is never read.
            let buf = if data.is_empty() {
                std::ptr::NonNull::<T>::dangling().as_ptr() as *const c_void
            } else {
                data.as_ptr() as *const c_void
            };
            if H5Dwrite(dset.id, T::mem_type(), mspace.id, fspace.id, self.dxpl, buf) < 0 {
                return Err(self.err(ds(&format!("H5Dwrite({local_rows} rows)"))));
            }
            if self.comm.is_some() {
                let mut mode: c_int = -1;
                if H5Pget_mpio_actual_io_mode(self.dxpl, &mut mode) < 0
                    || mode != CONTIGUOUS_COLLECTIVE
                {
                    H5Eclear2(H5E_DEFAULT);
                    self.not_collective.set(self.not_collective.get() + 1);
                }
            }
        }
        Ok(())
    }

    /// Open `obj`, replace attribute `name` with a scalar of `ftype`, write `buf` (of `mtype`).
    fn write_attr(
        &self,
        obj: &str,
        name: &str,
        ftype: hid_t,
        mtype: hid_t,
        buf: *const c_void,
    ) -> Result<()> {
        let cobj = cstring("object path", obj)?;
        let cname = cstring("attribute name", name)?;
        let at = |what: &str| format!("attribute '{name}' on '{obj}' {what}");
        unsafe {
            let o = H5Oopen(self.file, cobj.as_ptr(), H5P_DEFAULT);
            if o < 0 {
                return Err(self.err(at("H5Oopen")));
            }
            let o = Handle {
                id: o,
                close: H5Oclose,
            };
            let exists = H5Aexists(o.id, cname.as_ptr());
            if exists < 0 {
                return Err(self.err(at("H5Aexists")));
            }
            if exists > 0 && H5Adelete(o.id, cname.as_ptr()) < 0 {
                return Err(self.err(at("H5Adelete")));
            }
            let space = H5Screate(H5S_class_t::H5S_SCALAR);
            if space < 0 {
                return Err(self.err(at("H5Screate(scalar)")));
            }
            let space = Handle {
                id: space,
                close: H5Sclose,
            };
            let a = H5Acreate2(
                o.id,
                cname.as_ptr(),
                ftype,
                space.id,
                H5P_DEFAULT,
                H5P_DEFAULT,
            );
            if a < 0 {
                return Err(self.err(at("H5Acreate2")));
            }
            let a = Handle {
                id: a,
                close: H5Aclose,
            };
            if H5Awrite(a.id, mtype, buf) < 0 {
                return Err(self.err(at("H5Awrite")));
            }
        }
        Ok(())
    }

    /// Collective: a scalar f64 attribute `name` on object `obj` ("/" for the file's
    /// root, a group or a dataset path), replacing any existing one. Same value on all ranks.
    fn write_attr_f64_here(&self, obj: &str, name: &str, v: f64) -> Result<()> {
        let _g = hdf5_sys::LOCK.lock();
        self.write_attr(
            obj,
            name,
            *H5T_IEEE_F64LE,
            *H5T_NATIVE_DOUBLE,
            &v as *const f64 as *const c_void,
        )
    }

    /// Collective: a scalar string attribute (fixed-length, UTF-8, NUL-terminated).
    fn write_attr_str_here(&self, obj: &str, name: &str, v: &str) -> Result<()> {
        let _g = hdf5_sys::LOCK.lock();
        let cv = cstring("attribute value", v)?;
        let bytes = cv.as_bytes_with_nul();
        unsafe {
            let t = H5Tcopy(*H5T_C_S1);
            if t < 0 {
                return Err(self.err(format!("attribute '{name}' on '{obj}' H5Tcopy")));
            }
            let t = Handle {
                id: t,
                close: H5Tclose,
            };
            if H5Tset_size(t.id, bytes.len()) < 0
                || H5Tset_strpad(t.id, H5T_str_t::H5T_STR_NULLTERM) < 0
                || H5Tset_cset(t.id, H5T_cset_t::H5T_CSET_UTF8) < 0
            {
                return Err(self.err(format!("attribute '{name}' on '{obj}' string type")));
            }
            self.write_attr(
                obj,
                name,
                t.id,
                t.id,
                bytes.as_ptr() as *const c_char as *const c_void,
            )
        }
    }

    /// Collective flush of everything written so far to disk (survives a later failure).
    fn flush_here(&self) -> Result<()> {
        let _g = hdf5_sys::LOCK.lock();
        if unsafe { H5Fflush(self.file, H5F_scope_t::H5F_SCOPE_GLOBAL) } < 0 {
            return Err(self.err("H5Fflush".to_string()));
        }
        Ok(())
    }
}

impl Drop for H5File {
    fn drop(&mut self) {
        let _g = hdf5_sys::LOCK.lock();
        unsafe {
            if self.dxpl != H5P_DEFAULT {
                H5Pclose(self.dxpl);
            }
            H5Pclose(self.lcpl);
            if self.poisoned.get() && self.comm.is_some() {
                LEFT_OPEN.store(true, std::sync::atomic::Ordering::SeqCst);
                return;
            }
            if H5Fclose(self.file) < 0 {
                // Drop cannot return an error; say it once, on one line.
                eprintln!(
                    "alfe: warning: HDF5 {}: H5Fclose failed: {}",
                    self.path.display(),
                    hdf5_detail()
                );
            }
            if let Some(mut c) = self.comm.take() {
                mpi::ffi::MPI_Comm_free(&mut c);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::testutil::{python_json, temp_dir};
    use crate::parallel::SerialComm;

    /// Dump every dataset (shape, dtype, values) and attribute of an HDF5 file as JSON.
    const DUMP: &str = r#"
import sys, json, h5py, numpy as np
out = {}
def attrs(o):
    r = {}
    for k, v in o.attrs.items():
        if isinstance(v, bytes): v = v.decode()
        elif isinstance(v, np.generic): v = v.item()
        r[k] = v
    return r
def visit(name, o):
    d = {"attrs": attrs(o)}
    if isinstance(o, h5py.Dataset):
        d.update(shape=list(o.shape), dtype=str(o.dtype), data=o[()].tolist())
    else:
        d["group"] = True
    out["/" + name] = d
with h5py.File(sys.argv[1], "r") as f:
    out["/"] = {"attrs": attrs(f), "group": True}
    f.visititems(visit)
print(json.dumps(out))
"#;

    #[test]
    fn serial_datasets_and_attributes_round_trip() {
        let dir = temp_dir("h5-roundtrip");
        let path = dir.join("run.h5");
        {
            let f = H5File::create(&SerialComm, &path).unwrap();
            f.create_group("/steps/000001").unwrap();
            f.create_group("/steps/000001").unwrap(); // exists: fine
            f.create_group("/steps").unwrap();
            let coords: Vec<f64> = (0..12).map(|i| i as f64 * 0.5).collect();
            f.write_rows_f64("/mesh/coordinates", 4, 3, 0, &coords)
                .unwrap();
            let conn: Vec<i64> = (0..16).map(|i| (i * 3) % 11 + (1 << 40)).collect();
            f.write_rows_i64("/mesh/connectivity", 2, 8, 0, &conn)
                .unwrap();
            f.write_rows_i32("/mesh/partition", 2, 1, 0, &[0, -7])
                .unwrap();
            // Only rows 1..3 of 4 from this "rank": the others keep the fill value 0.
            f.write_rows_f64("/steps/000001/von_mises", 4, 1, 1, &[1.5, -2.25])
                .unwrap();
            // A dataset no rank has rows of.
            f.write_rows_f64("/steps/000001/contact", 0, 6, 0, &[])
                .unwrap();
            f.write_attr_f64("/steps/000001", "time", 0.125).unwrap();
            f.write_attr_f64("/steps/000001", "time", 0.25).unwrap(); // replaces
            f.write_attr_str("/", "program", "alfe \u{e9}").unwrap();
            f.write_attr_str("/mesh/coordinates", "units", "").unwrap();
            f.flush().unwrap();
        }
        let j = python_json(DUMP, &[path.to_str().unwrap()]);
        let c = &j["/mesh/coordinates"];
        assert_eq!(c["shape"], serde_json::json!([4, 3]));
        assert_eq!(c["dtype"], "float64");
        assert_eq!(c["data"][3][2], 5.5);
        assert_eq!(c["data"][1][0], 1.5);
        let k = &j["/mesh/connectivity"];
        assert_eq!(k["shape"], serde_json::json!([2, 8]));
        assert_eq!(k["dtype"], "int64");
        assert_eq!(k["data"][1][7], ((15 * 3) % 11 + (1i64 << 40)));
        let p = &j["/mesh/partition"];
        assert_eq!(p["shape"], serde_json::json!([2]));
        assert_eq!(p["dtype"], "int32");
        assert_eq!(p["data"], serde_json::json!([0, -7]));
        let v = &j["/steps/000001/von_mises"];
        assert_eq!(v["shape"], serde_json::json!([4]));
        assert_eq!(v["data"], serde_json::json!([0.0, 1.5, -2.25, 0.0]));
        assert_eq!(
            j["/steps/000001/contact"]["shape"],
            serde_json::json!([0, 6])
        );
        assert_eq!(j["/steps/000001"]["attrs"]["time"], 0.25);
        assert_eq!(j["/"]["attrs"]["program"], "alfe \u{e9}");
        assert_eq!(j["/mesh/coordinates"]["attrs"]["units"], "");
        assert_eq!(j["/steps"]["group"], true);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn failures_are_one_line_errors_naming_the_path() {
        let dir = temp_dir("h5-errors");
        let path = dir.join("e.h5");
        let f = H5File::create(&SerialComm, &path).unwrap();
        f.write_rows_f64("/a/x", 2, 1, 0, &[1.0, 2.0]).unwrap();

        let e = f.write_rows_f64("/a/x", 2, 1, 0, &[1.0, 2.0]).unwrap_err();
        assert_eq!(e.kind, crate::ErrorKind::Runtime);
        assert!(
            e.message.contains("'/a/x'") && e.message.contains("H5Dcreate2"),
            "{e}"
        );
        assert!(!e.message.contains('\n'), "{e}");

        let e = f.write_rows_f64("/a/y", 4, 3, 0, &[1.0, 2.0]).unwrap_err();
        assert!(
            e.message.contains("'/a/y'") && e.message.contains("whole rows"),
            "{e}"
        );
        let e = f
            .write_rows_i64("/a/z", 2, 2, 1, &[1, 2, 3, 4])
            .unwrap_err();
        assert!(
            e.message.contains("'/a/z'") && e.message.contains("outside"),
            "{e}"
        );
        let e = f.write_rows_i32("/a/w", 2, 0, 0, &[]).unwrap_err();
        assert!(e.message.contains("n_cols is 0"), "{e}");

        let e = f.write_attr_f64("/nope", "t", 1.0).unwrap_err();
        assert!(
            e.message.contains("'/nope'") && e.message.contains("H5Oopen"),
            "{e}"
        );

        // The file still works after errors (the HDF5 error stack was cleared).
        f.write_rows_f64("/a/ok", 1, 1, 0, &[3.0]).unwrap();
        drop(f);

        let e = H5File::create(&SerialComm, &dir.join("no/such/dir/f.h5"))
            .err()
            .unwrap();
        assert!(
            e.message.contains("no/such/dir/f.h5") && e.message.contains("H5Fcreate"),
            "{e}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
