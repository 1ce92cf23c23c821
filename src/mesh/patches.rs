//! Patches of elements: small connected groups of tets that share one volume ratio (the
//! F-bar-patch tet4, `fem::patch`). They are formed once on the whole mesh, before it is
//! partitioned, so the discrete problem does not depend on the rank count, and the
//! partition keeps every patch on one rank (`partition::keep_groups_whole`).
//!
//! METIS k-way on the face graph of each part's patched elements, with contiguous parts
//! and `n / size` of them, gives connected patches of about `size` elements; a patch
//! METIS leaves with fewer than [`MIN_PATCH`] elements joins its smallest neighbour
//! (one tet alone would be a locking standard tet4).

use super::Mesh;
use std::collections::{BTreeMap, HashMap};

/// Elements per patch. A tet mesh has about 5–6 tets per node, so patches of 8 leave
/// about four times as many displacement unknowns as volume constraints. Measured on the
/// seal (tet4 16×8×8, force at 5 mm / drag against hex8 converged): 4 tets +5.1 % /
/// +11.4 %, 6 tets +3.5 % / +7.5 %, 8 tets +2.8 % / +6.9 %; Cook's membrane 16×16×4:
/// 7.83, 7.92, 7.97 at 6, 8, 12 (scripts/results/elements/patch-size.md).
pub const PATCH_ELEMENTS: usize = 8;

/// Patches smaller than this join a neighbour.
pub const MIN_PATCH: usize = 3;

/// No patch: the element is evaluated alone.
pub const NO_PATCH: u32 = u32::MAX;

/// Element → patch number (dense from 0, [`NO_PATCH`] for elements not in `member`),
/// patches of about `size` face-connected elements within each part.
pub fn form(mesh: &Mesh, member: &[bool], size: usize) -> Result<Vec<u32>, String> {
    let mut by_part: BTreeMap<u32, Vec<usize>> = BTreeMap::new();
    for e in (0..mesh.n_elems()).filter(|&e| member[e]) {
        by_part.entry(mesh.elem_part[e]).or_default().push(e);
    }
    let mut patch = vec![NO_PATCH; mesh.n_elems()];
    let mut next = 0u32;
    for elems in by_part.values() {
        let (xadj, adjncy) = face_graph(mesh, elems);
        let local = split(&xadj, &adjncy, size)?;
        let local = merge_small(&xadj, &adjncy, local);
        let count = local.iter().max().map_or(0, |&m| m + 1);
        for (&e, &p) in elems.iter().zip(&local) {
            patch[e] = next + p;
        }
        next += count;
    }
    Ok(patch)
}

/// The face graph of `elems` (CSR over their positions in `elems`).
fn face_graph(mesh: &Mesh, elems: &[usize]) -> (Vec<i32>, Vec<i32>) {
    let mut faces: HashMap<Vec<usize>, usize> = HashMap::new();
    let mut adj: Vec<Vec<i32>> = vec![Vec::new(); elems.len()];
    for (i, &e) in elems.iter().enumerate() {
        let nodes = mesh.elem_nodes(e);
        for face in mesh.kinds[e].faces() {
            // Corner nodes identify a face (a tet10's midside nodes follow them).
            let mut key: Vec<usize> = face.iter().take(3).map(|&a| nodes[a]).collect();
            key.sort_unstable();
            match faces.remove(&key) {
                Some(j) => {
                    adj[i].push(j as i32);
                    adj[j].push(i as i32);
                }
                None => {
                    faces.insert(key, i);
                }
            }
        }
    }
    let mut xadj = vec![0i32];
    let mut adjncy = Vec::new();
    for mut l in adj {
        l.sort_unstable();
        adjncy.extend(l);
        xadj.push(adjncy.len() as i32);
    }
    (xadj, adjncy)
}

/// METIS k-way into about n/size parts, contiguous where METIS can (it cannot on a
/// disconnected graph: then without), renumbered densely in order of first element.
fn split(xadj: &[i32], adjncy: &[i32], size: usize) -> Result<Vec<u32>, String> {
    let n = xadj.len() - 1;
    let nparts = (n + size / 2) / size.max(1);
    if nparts <= 1 {
        return Ok(vec![0; n]);
    }
    let run = |contig: bool| {
        let mut part = vec![0i32; n];
        metis::Graph::new(1, nparts as i32, xadj, adjncy)
            .map_err(|e| format!("METIS graph of patches: {e}"))?
            .set_option(metis::option::Seed(0))
            .set_option(metis::option::Contig(contig))
            .part_kway(&mut part)
            .map_err(|e| format!("METIS patches: {e}"))?;
        Ok::<_, String>(part)
    };
    let part = run(true).or_else(|_| run(false))?;
    let mut dense: HashMap<i32, u32> = HashMap::new();
    Ok(part
        .into_iter()
        .map(|p| {
            let k = dense.len() as u32;
            *dense.entry(p).or_insert(k)
        })
        .collect())
}

/// Patches below [`MIN_PATCH`] join their smallest face neighbour (one pass, smallest
/// first; an isolated element stays alone), then renumbered densely.
fn merge_small(xadj: &[i32], adjncy: &[i32], mut part: Vec<u32>) -> Vec<u32> {
    let np = part.iter().max().map_or(0, |&m| m as usize + 1);
    let mut size = vec![0usize; np];
    for &p in &part {
        size[p as usize] += 1;
    }
    let mut small: Vec<usize> = (0..np)
        .filter(|&p| size[p] > 0 && size[p] < MIN_PATCH)
        .collect();
    small.sort_by_key(|&p| (size[p], p));
    for p in small {
        if size[p] == 0 || size[p] >= MIN_PATCH {
            continue;
        }
        let members: Vec<usize> = (0..part.len()).filter(|&i| part[i] as usize == p).collect();
        let neighbour = members
            .iter()
            .flat_map(|&i| &adjncy[xadj[i] as usize..xadj[i + 1] as usize])
            .map(|&j| part[j as usize] as usize)
            .filter(|&q| q != p)
            .min_by_key(|&q| (size[q], q));
        if let Some(q) = neighbour {
            for &i in &members {
                part[i] = q as u32;
            }
            size[q] += size[p];
            size[p] = 0;
        }
    }
    let mut dense: HashMap<u32, u32> = HashMap::new();
    part.into_iter()
        .map(|p| {
            let k = dense.len() as u32;
            *dense.entry(p).or_insert(k)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::{box_mesh, BoxSpec};
    use crate::mesh::ElemKind;

    fn tets(cells: [usize; 3]) -> Mesh {
        let spec = BoxSpec {
            origin: [0.0; 3],
            size: [4.0, 2.0, 2.0],
            cells,
            grading: [1.0; 3],
            kind: ElemKind::Tet4,
        };
        box_mesh(&spec, 0)
    }

    #[test]
    fn patches_are_connected_sized_and_cover_the_members() {
        let mesh = tets([6, 3, 3]);
        let ne = mesh.n_elems();
        let member = vec![true; ne];
        let patch = form(&mesh, &member, PATCH_ELEMENTS).unwrap();
        assert!(patch.iter().all(|&p| p != NO_PATCH));
        let np = *patch.iter().max().unwrap() as usize + 1;
        let elems: Vec<usize> = (0..ne).collect();
        let (xadj, adjncy) = face_graph(&mesh, &elems);
        for p in 0..np as u32 {
            let members: Vec<usize> = (0..ne).filter(|&e| patch[e] == p).collect();
            assert!(members.len() >= MIN_PATCH, "patch {p}: {}", members.len());
            assert!(
                members.len() <= 3 * PATCH_ELEMENTS,
                "patch {p}: {}",
                members.len()
            );
            // Connected through faces within the patch.
            let mut seen = vec![members[0]];
            let mut k = 0;
            while k < seen.len() {
                let i = seen[k];
                for &j in &adjncy[xadj[i] as usize..xadj[i + 1] as usize] {
                    let j = j as usize;
                    if patch[j] == p && !seen.contains(&j) {
                        seen.push(j);
                    }
                }
                k += 1;
            }
            assert_eq!(seen.len(), members.len(), "patch {p} is not connected");
        }
        let mean = ne as f64 / np as f64;
        assert!((4.0..=8.0).contains(&mean), "mean patch size {mean}");
    }

    #[test]
    fn non_members_have_no_patch_and_parts_are_kept_apart() {
        let mut mesh = tets([4, 2, 2]);
        let ne = mesh.n_elems();
        for e in ne / 2..ne {
            mesh.elem_part[e] = 1;
        }
        let member: Vec<bool> = (0..ne).map(|e| e % 7 != 0).collect();
        let patch = form(&mesh, &member, PATCH_ELEMENTS).unwrap();
        for e in 0..ne {
            assert_eq!(patch[e] == NO_PATCH, !member[e]);
            for f in 0..ne {
                if patch[e] != NO_PATCH && patch[e] == patch[f] {
                    assert_eq!(mesh.elem_part[e], mesh.elem_part[f]);
                }
            }
        }
    }
}
