//! Output: one HDF5 file per run written collectively by all ranks ([`h5`]), and the
//! XDMF3 description beside it that ParaView opens as a time series ([`xdmf`]).

pub mod cells;
pub mod checkpoint;
pub mod h5;
pub mod iterations;
pub mod lock;
pub mod log;
pub mod quantities;
pub mod record;
pub mod results;
pub mod schedule;
pub mod xdmf;

pub use h5::H5File;
pub use xdmf::{write_xdmf, AttrKind, Center, XdmfAttr, XdmfMesh, XdmfStep, XdmfTopology};

/// Helpers for the unit tests: a fresh temp dir, and Debian's h5py (SETUP pitfall 7:
/// `/usr/bin/python3`, not the `python3` first on PATH).
#[cfg(test)]
pub(crate) mod testutil {
    use std::path::PathBuf;
    use std::process::Command;

    /// A fresh, empty directory under the system temp dir, unique per test.
    pub fn temp_dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("alfe-output-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// Run a Python script with `/usr/bin/python3` (it must print one JSON value) and
    /// parse its output. Fails the test, with a clear message, if python or h5py is missing.
    pub fn python_json(script: &str, args: &[&str]) -> serde_json::Value {
        // Unit tests run on threads: a python child spawned by another test may inherit
        // (fork) an HDF5 descriptor of this test's file while it is still being written
        // and hold its flock, so the reader must not insist on locking.
        let out = Command::new("/usr/bin/python3")
            .env("HDF5_USE_FILE_LOCKING", "FALSE")
            .arg("-c")
            .arg(script)
            .args(args)
            .output()
            .expect("cannot run /usr/bin/python3 (needed to read HDF5 back; apt-get install python3-h5py)");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            !stderr.contains("No module named 'h5py'"),
            "h5py is missing for /usr/bin/python3: apt-get install python3-h5py"
        );
        assert!(out.status.success(), "python check failed:\n{stderr}");
        serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
            panic!(
                "python printed no JSON ({e}):\n{}",
                String::from_utf8_lossy(&out.stdout)
            )
        })
    }
}
