//! Collective helpers the commands share: run a step on rank 0 and agree on its
//! outcome on every rank (so a bad deck stops all ranks together instead of leaving
//! them waiting), send rank 0's value to all, and the process's peak memory that runs
//! report per rank. They know nothing of what they move.

use super::Comm;
use crate::{Error, ErrorKind, Result};

/// Peak resident set size of this process in MB (Linux VmHWM).
pub fn peak_rss_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map(|kb| kb / 1024.0)
        .unwrap_or(0.0)
}

/// Run `f` on rank 0 only and let every rank know whether it failed (with the same
/// error), so that a bad deck stops all ranks together instead of leaving them waiting.
pub fn on_rank0<T>(comm: &dyn Comm, f: impl FnOnce() -> Result<T>) -> Result<Option<T>> {
    let (res, mut msg) = if comm.rank() == 0 {
        match f() {
            Ok(v) => (Some(v), vec![0u8]),
            Err(e) => {
                let code = match e.kind {
                    ErrorKind::Input => 1u8,
                    ErrorKind::Convergence => 2,
                    ErrorKind::Runtime | ErrorKind::Interrupted(_) => 3,
                };
                let mut m = vec![code];
                m.extend_from_slice(e.message.as_bytes());
                (None, m)
            }
        }
    } else {
        (None, Vec::new())
    };
    comm.broadcast_bytes(0, &mut msg);
    if msg[0] == 0 {
        return Ok(res);
    }
    let text = String::from_utf8_lossy(&msg[1..]).to_string();
    Err(match msg[0] {
        1 => Error::input(text),
        2 => Error::convergence(text),
        _ => Error::runtime(text),
    })
}

/// Collective: rank 0's outcome `r` of an action only it took (a file written) on every
/// rank, its error message included; the other ranks' `r` is ignored.
pub fn rank0_outcome(comm: &dyn Comm, r: Result<()>) -> Result<()> {
    on_rank0(comm, move || r).map(|_| ())
}

/// Collective: rank 0's value on every rank (serialised).
pub fn broadcast<T: serde::Serialize + serde::de::DeserializeOwned>(
    comm: &dyn Comm,
    value: Option<T>,
) -> Result<T> {
    let mut bytes = match &value {
        Some(v) if comm.rank() == 0 => bincode::serialize(v)
            .map_err(|e| Error::runtime(format!("serialising run settings: {e}")))?,
        _ => Vec::new(),
    };
    comm.broadcast_bytes(0, &mut bytes);
    bincode::deserialize(&bytes).map_err(|e| Error::runtime(format!("receiving run settings: {e}")))
}
