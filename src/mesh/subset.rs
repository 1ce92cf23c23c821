//! One element set of a mesh file as a part's mesh: a file that holds more than the part
//! (other parts, or the rigid wall layers `alfe export` adds for CalculiX) gives only the
//! elements of the set named, their groups and faces renumbered; unused nodes are
//! dropped by the caller.

use super::Mesh;

/// Keep only the elements of element group `name` (any case).
pub fn keep_elem_group(mesh: &mut Mesh, name: &str) -> Result<(), String> {
    let Some(group) = mesh
        .elem_groups
        .iter()
        .find(|(k, _)| k.eq_ignore_ascii_case(name))
        .map(|(_, v)| v.clone())
    else {
        let names: Vec<&str> = mesh.elem_groups.keys().map(String::as_str).collect();
        return Err(format!(
            "no element set `{name}` in the file (it has {})",
            names.join(", ")
        ));
    };
    let mut map = vec![usize::MAX; mesh.n_elems()];
    for &e in &group {
        map[e] = 0;
    }
    let mut out = Mesh {
        coords: std::mem::take(&mut mesh.coords),
        offsets: vec![0],
        node_groups: std::mem::take(&mut mesh.node_groups),
        ..Default::default()
    };
    for (e, slot) in map.iter_mut().enumerate() {
        if *slot == usize::MAX {
            continue;
        }
        *slot = out.n_elems();
        out.kinds.push(mesh.kinds[e]);
        out.conn.extend_from_slice(mesh.elem_nodes(e));
        out.offsets.push(out.conn.len());
        out.elem_part.push(mesh.elem_part[e]);
    }
    for (k, v) in std::mem::take(&mut mesh.elem_groups) {
        let kept: Vec<usize> = v
            .iter()
            .filter(|&&e| map[e] != usize::MAX)
            .map(|&e| map[e])
            .collect();
        out.elem_groups.insert(k, kept);
    }
    for (k, v) in std::mem::take(&mut mesh.face_groups) {
        let kept = v
            .iter()
            .filter(|f| map[f.elem] != usize::MAX)
            .map(|f| super::FaceRef {
                elem: map[f.elem],
                ..*f
            })
            .collect();
        out.face_groups.insert(k, kept);
    }
    *mesh = out;
    Ok(())
}
