//! SIGINT and SIGTERM (Ctrl-C, `kill`, a batch scheduler's time limit) end a run at its
//! next converged step, as `--stop-after` does: that step's fields and restart file,
//! the history, `iterations.csv` and `summary.json` are written and the HDF5 file is
//! closed, so everything so far is readable and the run can go on with `--restart`.
//! The exit status is then 128 + the signal's number, as a shell reports a killed
//! command. A second signal ends the process at once (same status).
//!
//! Ranks agree at every converged step (one max-reduction of the signal number), so a
//! signal that reaches only some ranks stops all of them at the same step. Under
//! `mpirun`, Open MPI forwards SIGINT/SIGTERM to the ranks but kills them a few seconds
//! later; a step that takes longer than that is not waited for.

use crate::parallel::Comm;
use signal_hook::consts::{SIGINT, SIGTERM};
use signal_hook::flag;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// The last signal received (0: none).
static SIGNAL: AtomicUsize = AtomicUsize::new(0);
/// Set by the first signal: the next one ends the process.
static ARMED: AtomicBool = AtomicBool::new(false);

/// Install the handlers (once, at start-up). An error leaves the default action.
pub fn install() -> std::io::Result<()> {
    for sig in [SIGINT, SIGTERM] {
        // Registration order matters: the shutdown checks ARMED before it is set.
        flag::register_conditional_shutdown(sig, 128 + sig, &ARMED)?;
        flag::register_usize(sig, &SIGNAL, sig as usize)?;
        flag::register(sig, &ARMED)?;
    }
    Ok(())
}

/// The signal any rank received, agreed over ranks (collective); `None` if none.
pub(super) fn agreed(comm: &dyn Comm) -> Option<i32> {
    let mut v = [SIGNAL.load(Ordering::Relaxed) as u64];
    comm.allreduce_max_u64(&mut v);
    (v[0] > 0).then_some(v[0] as i32)
}

/// The signal's name, for messages.
pub fn name(sig: i32) -> String {
    match sig {
        SIGINT => "SIGINT".into(),
        SIGTERM => "SIGTERM".into(),
        s => format!("signal {s}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names() {
        assert_eq!(name(SIGINT), "SIGINT");
        assert_eq!(name(SIGTERM), "SIGTERM");
        assert_eq!(name(10), "signal 10");
    }
}
