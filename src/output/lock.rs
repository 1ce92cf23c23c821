//! One run per output directory: a lock file `.alfe-lock` (pid and host of the run
//! holding it), created exclusively and removed when the run ends, however it ends. A
//! lock whose process is gone (a killed run on this host) is taken over.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

pub const LOCK_NAME: &str = ".alfe-lock";

/// Held for the run's lifetime; dropping it removes the lock file.
#[derive(Debug)]
pub struct OutLock {
    path: PathBuf,
}

/// This machine's host name (empty if unknown).
pub(crate) fn host() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|h| h.trim().to_string())
        .unwrap_or_default()
}

impl OutLock {
    /// Create `dir` if needed and take its lock, or say which run holds it.
    pub fn acquire(dir: &Path) -> Result<Self> {
        std::fs::create_dir_all(dir).map_err(|e| {
            Error::input(format!(
                "--out {}: cannot create the output directory: {e}",
                dir.display()
            ))
        })?;
        let path = dir.join(LOCK_NAME);
        for _ in 0..2 {
            match std::fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&path)
            {
                Ok(mut f) => {
                    let _ = writeln!(f, "{} {}", std::process::id(), host());
                    return Ok(Self { path });
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                    let text = std::fs::read_to_string(&path).unwrap_or_default();
                    let mut it = text.split_whitespace();
                    let pid: Option<u32> = it.next().and_then(|p| p.parse().ok());
                    let holder = it.next().unwrap_or("").to_string();
                    let gone = holder == host()
                        && pid.is_some_and(|p| !Path::new(&format!("/proc/{p}")).exists());
                    if gone {
                        let _ = std::fs::remove_file(&path);
                        continue;
                    }
                    return Err(Error::input(format!(
                        "--out {}: another alfe run ({}) is writing there; choose another --out, or delete {} if that run is gone",
                        dir.display(),
                        match pid {
                            Some(p) => format!("pid {p} on {}", if holder.is_empty() { "an unknown host" } else { &holder }),
                            None => "unknown".into(),
                        },
                        path.display()
                    )));
                }
                Err(e) => {
                    return Err(Error::input(format!(
                        "--out {}: cannot create {}: {e}",
                        dir.display(),
                        path.display()
                    )))
                }
            }
        }
        Err(Error::input(format!(
            "--out {}: cannot take {}",
            dir.display(),
            path.display()
        )))
    }
}

impl Drop for OutLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_holder_at_a_time_and_stale_locks_are_taken_over() {
        let dir = crate::output::testutil::temp_dir("lock");
        let a = OutLock::acquire(&dir).unwrap();
        let e = OutLock::acquire(&dir).unwrap_err();
        assert!(
            e.message.contains("another alfe run (pid") && e.message.contains(".alfe-lock"),
            "{}",
            e.message
        );
        drop(a);
        assert!(!dir.join(LOCK_NAME).exists());
        let b = OutLock::acquire(&dir).unwrap();
        drop(b);
        // A lock left by a process that is gone (pid beyond pid_max) on this host.
        std::fs::write(dir.join(LOCK_NAME), format!("4294967 {}\n", host())).unwrap();
        let c = OutLock::acquire(&dir).unwrap();
        drop(c);
        // Another host's lock is never taken over.
        std::fs::write(dir.join(LOCK_NAME), "1 elsewhere\n").unwrap();
        let e = OutLock::acquire(&dir).unwrap_err();
        assert!(e.message.contains("pid 1 on elsewhere"), "{}", e.message);
    }
}
