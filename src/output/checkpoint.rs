//! Restart files (issue 16): each rank keeps the state of the run after its last written
//! step in `<out>/restart/step-NNNNNN.rank-R.bin`: the solution, every contribution's
//! committed state and where the stepping stands ([`Resume`]). `alfe run --restart DIR`
//! takes the newest step every rank has and goes on from there as if the run had not
//! stopped (the same rank count and the same deck: both are checked).
//!
//! Crash safety: a rank writes its file under a temporary name and renames it; older
//! steps are deleted only after every rank has its newer file. A run killed in between
//! leaves two steps, and the older one is common to all ranks.

use crate::parallel::Comm;
use crate::solve::stepping::Resume;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Bumped when the layout changes: an older file is refused, not misread. 3: penalty
/// contact carries its elastic slip (not its tangential force), pairs keep their
/// contact, stick and stick softening, and `solver = "auto"` its learned state. 4:
/// `auto`'s state lost its partition-dependent factor weight. 5: the line search's
/// memory (`ArmijoState`).
pub const FORMAT: u32 = 5;

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Checkpoint {
    pub format: u32,
    /// alfe's version and commit that wrote it.
    pub alfe: String,
    pub scene: String,
    /// FNV-1a of the deck as read (its echo): a restart needs the same deck.
    pub deck: u64,
    pub ranks: usize,
    pub rank: usize,
    /// This rank's first owned unknown and their count (the same partition).
    pub first_dof: usize,
    pub n_dofs: usize,
    pub step: usize,
    pub time: f64,
    pub u: Vec<f64>,
    /// [`crate::model::Model::saved_state`].
    pub model: Vec<Vec<f64>>,
    pub resume: Resume,
}

/// FNV-1a, 64 bits: a stable fingerprint of a deck's text.
pub fn fingerprint(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

fn file(dir: &Path, step: usize, rank: usize) -> PathBuf {
    dir.join("restart")
        .join(format!("step-{step:06}.rank-{rank}.bin"))
}

/// The steps this rank has files for in `dir`, ascending.
fn steps_on_disk(dir: &Path, rank: usize) -> Vec<usize> {
    let tail = format!(".rank-{rank}.bin");
    let mut v: Vec<usize> = std::fs::read_dir(dir.join("restart"))
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().to_string();
            name.strip_prefix("step-")?
                .strip_suffix(&tail)?
                .parse()
                .ok()
        })
        .collect();
    v.sort_unstable();
    v
}

/// Collective: every rank writes its checkpoint; once all have, the older steps go.
pub fn write(comm: &dyn Comm, dir: &Path, c: &Checkpoint) -> Result<()> {
    let path = file(dir, c.step, c.rank);
    let tmp = path.with_extension("tmp");
    let res = std::fs::create_dir_all(dir.join("restart"))
        .and_then(|_| {
            let bytes = bincode::serialize(c).map_err(std::io::Error::other)?;
            std::fs::write(&tmp, bytes)
        })
        .and_then(|_| std::fs::rename(&tmp, &path));
    if let Some(why) = comm.first_message(res.err().map(|e| format!("{}: {e}", path.display()))) {
        return Err(Error::runtime(format!(
            "cannot write the restart file {why}"
        )));
    }
    for s in steps_on_disk(dir, c.rank) {
        if s != c.step {
            let _ = std::fs::remove_file(file(dir, s, c.rank));
        }
    }
    Ok(())
}

/// Collective: this rank's checkpoint of the newest step every rank has in `dir`.
pub fn read(comm: &dyn Comm, dir: &Path) -> Result<Checkpoint> {
    let mine = steps_on_disk(dir, comm.rank());
    // The newest common step: the smallest of the ranks' newest (see the module doc).
    let mut newest = [u64::MAX - mine.last().map_or(0, |&s| s as u64 + 1)];
    comm.allreduce_max_u64(&mut newest);
    let newest = u64::MAX - newest[0];
    if newest == 0 {
        return Err(Error::input(format!(
            "--restart {}: no restart files for {} rank(s) there (a run writes them in its \
             output directory, restart/, at every step that writes fields)",
            dir.display(),
            comm.size()
        )));
    }
    let step = (newest - 1) as usize;
    let path = file(dir, step, comm.rank());
    let res = std::fs::read(&path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))
        .and_then(|b| {
            bincode::deserialize::<Checkpoint>(&b)
                .map_err(|e| format!("{} is not a restart file of this alfe: {e}", path.display()))
        })
        .and_then(|c| {
            if c.format != FORMAT {
                Err(format!(
                    "{} has restart format {}, this alfe reads {FORMAT}",
                    path.display(),
                    c.format
                ))
            } else if c.ranks != comm.size() || c.rank != comm.rank() {
                Err(format!(
                    "{} was written by rank {} of {}; restart on {} rank(s)",
                    path.display(),
                    c.rank,
                    c.ranks,
                    c.ranks
                ))
            } else {
                Ok(c)
            }
        });
    let why = comm.first_message(res.as_ref().err().cloned());
    match (res, why) {
        (Ok(c), None) => Ok(c),
        (_, Some(why)) => Err(Error::input(format!("--restart {}: {why}", dir.display()))),
        (Err(e), None) => Err(Error::input(e)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parallel::SerialComm;
    use crate::solve::control::ControlState;

    fn ck(step: usize) -> Checkpoint {
        Checkpoint {
            format: FORMAT,
            alfe: crate::VERSION.into(),
            scene: "s".into(),
            deck: fingerprint("deck"),
            ranks: 1,
            rank: 0,
            first_dof: 0,
            n_dofs: 2,
            step,
            time: 0.1 * step as f64,
            u: vec![1.0, step as f64],
            model: vec![vec![3.0]],
            resume: Resume {
                control: ControlState {
                    t_done: 0.1,
                    dt: 0.2,
                    steps: step,
                    stage: 0,
                },
                last_increment: None,
                dynamic: None,
                auto: None,
                armijo: Default::default(),
            },
        }
    }

    /// The newest step comes back; older ones are gone once a newer one is written; an
    /// empty directory is an input error that says where restart files come from.
    #[test]
    fn newest_step_round_trips() {
        let dir = crate::output::testutil::temp_dir("checkpoint");
        assert!(read(&SerialComm, &dir)
            .unwrap_err()
            .to_string()
            .contains("no restart files"));
        write(&SerialComm, &dir, &ck(3)).unwrap();
        write(&SerialComm, &dir, &ck(4)).unwrap();
        assert_eq!(steps_on_disk(&dir, 0), vec![4]);
        let c = read(&SerialComm, &dir).unwrap();
        assert_eq!((c.step, c.u.clone()), (4, vec![1.0, 4.0]));
        // A run killed between two ranks' writes: the older common step is taken.
        std::fs::copy(file(&dir, 4, 0), file(&dir, 2, 0)).unwrap();
        assert_eq!(steps_on_disk(&dir, 0), vec![2, 4]);
        assert_eq!(read(&SerialComm, &dir).unwrap().step, 4);
        assert_ne!(fingerprint("a = 1"), fingerprint("a = 2"));
    }
}
