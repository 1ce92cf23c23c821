//! The partition cache: `DIR/<scene>.<ranks>.<key>.part`, a small text file; `key` is the
//! hash of the mesh (with its couplings and the partition method), so editing a deck's
//! mesh, or two decks copied from one scene, never meet another mesh's file. The header
//! records the hash too: a file that does not match (edited by hand) is refused.

use super::Request;
use crate::{Error, Result};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The cache when `--partitions` does not name one: `$XDG_CACHE_HOME/alfe/partitions`,
/// else `$HOME/.cache/alfe/partitions` (the XDG convention: reused across runs and
/// output directories, never written into the working directory), else `partitions`.
pub fn default_dir() -> PathBuf {
    let var = |k: &str| {
        std::env::var_os(k)
            .filter(|v| !v.is_empty())
            .map(PathBuf::from)
    };
    var("XDG_CACHE_HOME")
        .or_else(|| var("HOME").map(|h| h.join(".cache")))
        .map_or_else(
            || PathBuf::from("partitions"),
            |d| d.join("alfe").join("partitions"),
        )
}

pub fn path(dir: &Path, scene: &str, ranks: usize, req: &Request) -> PathBuf {
    let safe: String = scene
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    dir.join(format!("{safe}.{ranks}.{:016x}.part", req.key()))
}

/// Write a partition file (creating `dir`).
pub fn write(file: &Path, req: &Request, ranks: usize, part: &[u32]) -> Result<()> {
    if let Some(d) = file.parent() {
        std::fs::create_dir_all(d)
            .map_err(|e| Error::runtime(format!("cannot create `{}`: {e}", d.display())))?;
    }
    let mut s = String::with_capacity(part.len() * 3 + 128);
    s.push_str(&format!(
        "alfe-partition 1\nranks {ranks}\nelements {}\nmesh-hash {:016x}\n",
        req.mesh.n_elems(),
        req.key()
    ));
    for p in part {
        s.push_str(&p.to_string());
        s.push('\n');
    }
    let tmp = file.with_extension("part.tmp");
    let mut f = std::fs::File::create(&tmp)
        .map_err(|e| Error::runtime(format!("cannot write `{}`: {e}", tmp.display())))?;
    f.write_all(s.as_bytes())?;
    std::fs::rename(&tmp, file)?;
    Ok(())
}

/// Read a partition file, refusing one made for another mesh or rank count.
pub fn read(file: &Path, req: &Request, ranks: usize) -> Result<Vec<u32>> {
    let mesh = req.mesh;
    // At most a header and one rank id (≤ 10 digits and a newline) per element: a file
    // that is larger, or not a regular file (a link to /dev/zero), is not read whole.
    let limit = 256 + 11 * mesh.n_elems() as u64;
    let cannot = |e: String| {
        Error::input(format!(
            "cannot read partition file `{}`: {e}",
            file.display()
        ))
    };
    let meta = std::fs::metadata(file).map_err(|e| cannot(e.to_string()))?;
    if !meta.is_file() {
        return Err(cannot("not a regular file".into()));
    }
    let mut text = String::new();
    std::io::Read::read_to_string(
        &mut std::io::Read::take(
            std::fs::File::open(file).map_err(|e| cannot(e.to_string()))?,
            limit + 1,
        ),
        &mut text,
    )
    .map_err(|e| cannot(e.to_string()))?;
    if text.len() as u64 > limit {
        return Err(cannot(format!(
            "larger than a partition of {} elements can be ({limit} bytes); delete it or rerun with --repartition",
            mesh.n_elems()
        )));
    }
    let bad = |why: String| {
        Error::input(format!(
            "partition file `{}` {why}; delete it or rerun with --repartition (or `alfe partition ... --ranks {ranks}`)",
            file.display()
        ))
    };
    let mut lines = text.lines();
    let mut header = |key: &str| -> Result<String> {
        let l = lines.next().unwrap_or("");
        l.strip_prefix(key)
            .map(|v| v.trim().to_string())
            .ok_or_else(|| {
                bad(format!(
                    "is not an alfe partition file (expected `{key}` header)"
                ))
            })
    };
    if header("alfe-partition")? != "1" {
        return Err(bad("has an unknown version".into()));
    }
    let r: usize = header("ranks")?
        .parse()
        .map_err(|_| bad("has an unreadable rank count".into()))?;
    let ne: usize = header("elements")?
        .parse()
        .map_err(|_| bad("has an unreadable element count".into()))?;
    let hash = header("mesh-hash")?;
    let want = format!("{:016x}", req.key());
    if r != ranks {
        return Err(bad(format!("is for {r} ranks, not {ranks}")));
    }
    if ne != mesh.n_elems() || hash != want {
        return Err(bad(format!(
            "is stale: made for a mesh with {ne} elements and hash {hash}, this mesh has {} elements and hash {want}",
            mesh.n_elems()
        )));
    }
    let part: Vec<u32> = lines
        .map(|l| l.trim().parse::<u32>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| bad("has an unreadable rank id".into()))?;
    if part.len() != ne || part.iter().any(|&p| p as usize >= ranks) {
        return Err(bad("is truncated or has rank ids out of range".into()));
    }
    Ok(part)
}

/// Where a partition came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Origin {
    Cache,
    Computed,
    Trivial,
}

/// Use the cached partition if there is one (refusing a stale one unless
/// `repartition`), otherwise compute it and cache it.
pub fn get(
    dir: &Path,
    scene: &str,
    req: &Request,
    ranks: usize,
    repartition: bool,
) -> Result<(Vec<u32>, Origin, PathBuf)> {
    let file = path(dir, scene, ranks, req);
    if ranks <= 1 {
        return Ok((vec![0; req.mesh.n_elems()], Origin::Trivial, file));
    }
    if file.exists() && !repartition {
        return Ok((read(&file, req, ranks)?, Origin::Cache, file));
    }
    let part = req.compute(ranks)?;
    write(&file, req, ranks, &part)?;
    Ok((part, Origin::Computed, file))
}
