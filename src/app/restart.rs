//! Reading a run's restart files back (`alfe run --restart DIR`): the newest step every
//! rank has, refused for another deck, rank count or partition.

use crate::model::Model;
use crate::parallel::Comm;
use crate::scene::RunSettings;
use crate::solve::stepping::Resume;
use crate::{Error, Result};
use std::path::PathBuf;

/// Where a restarted run goes on from: the earlier run's directory, its last step and
/// time, and this rank's solution and stepping state (the model's state is restored).
pub(super) struct Restart {
    pub(super) dir: PathBuf,
    pub(super) step: usize,
    pub(super) time: f64,
    pub(super) u: Vec<f64>,
    pub(super) resume: Resume,
}

/// Collective: read this rank's restart file from `dir`, check it was written by this
/// deck on this partition, and restore the model's state from it.
pub(super) fn load_restart(
    comm: &dyn Comm,
    dir: &std::path::Path,
    model: &mut Model,
    settings: &RunSettings,
) -> Result<Restart> {
    let c = crate::output::checkpoint::read(comm, dir)?;
    let mine = if c.scene != settings.name
        || c.deck != crate::output::checkpoint::fingerprint(&settings.echo)
    {
        Some(format!(
            "the restart files were written by another deck (scene `{}`); a restart needs the \
             deck of the run, e.g. {}",
            c.scene,
            dir.join("deck.toml").display()
        ))
    } else if c.first_dof != model.dofs.dofs.start()
        || c.n_dofs != model.n_owned_dofs()
        || c.u.len() != c.n_dofs
    {
        Some("the restart files were written on another partition of the model".into())
    } else {
        model.restore_state(&c.model).err().map(|e| e.message)
    };
    if let Some(why) = comm.first_message(mine) {
        return Err(Error::input(format!("--restart {}: {why}", dir.display())));
    }
    Ok(Restart {
        dir: dir.to_path_buf(),
        step: c.step,
        time: c.time,
        u: c.u,
        resume: c.resume,
    })
}
