//! LS-DYNA keyword files (`.k`) as meshes (issue 36): `*NODE`, `*ELEMENT_SOLID` (one
//! card, or the two-card "ten nodes" layout LS-PrePost writes), `*ELEMENT_SHELL` (for
//! sheets), `*PART`, `*SET_NODE_LIST`, `*SET_SEGMENT` (with their `_TITLE` forms),
//! `*INCLUDE`. Model keywords are skipped here.
//!
//! * Fields: comma-separated where a line has a comma, else fixed width: 8 characters
//!   (`*NODE`: 8 for the number, 16 for coordinates), or 20 for a keyword written with
//!   `+` (long format). `$` starts a comment line; keywords are case-insensitive.
//! * Solids: 8 distinct nodes → hex8; LS-DYNA's degenerate hexes → tet4
//!   (n4 = n5 = … = n8) and wedge6 (n5 = n6, n7 = n8: the triangles n1-n2-n5 and
//!   n4-n3-n6); 10 distinct nodes (two-card layout) → tet10, its midside nodes placed on
//!   their edges by position. Inverted elements are reordered, not refused: LS-DYNA
//!   accepts either orientation of a degenerate hex.
//! * Groups: each part's elements and nodes under its title (or `part-<pid>`), node sets
//!   under their title (or `set-<sid>`), segment sets as faces.
//!
//! Errors name the file, the line and the keyword.

use super::sheet::Surface;
use super::{ElemKind, FaceRef, Mesh, TET10_EDGES};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// A line with where it came from (comments dropped): the `.inp` reader's.
use super::abaqus::Line;
pub use super::abaqus::Loader;

/// The lines of `path` and its `*INCLUDE`s, comments dropped except `$alfe` lines: an
/// exported file keeps there the alfe choices LS-DYNA has no field for (LS-DYNA reads
/// them as comments; `alfe import` reads them; the mesh reader skips them).
pub fn read_lines_k(path: &Path, load: &Loader) -> Result<Vec<Line>, String> {
    let mut out = Vec::new();
    lines(path, load, 0, &mut out)?;
    Ok(out)
}

/// Whether a kept line is an `$alfe` note.
pub fn is_alfe_note(t: &str) -> bool {
    t.starts_with("$alfe")
}

fn lines(path: &Path, load: &Loader, depth: usize, out: &mut Vec<Line>) -> Result<(), String> {
    if depth > 16 {
        return Err(format!(
            "{}: *INCLUDE nested more than 16 deep",
            path.display()
        ));
    }
    let text = load(path)?;
    let file = std::rc::Rc::new(path.to_path_buf());
    let mut include_next = false;
    for (i, raw) in text.lines().enumerate() {
        let t = raw.trim_end();
        if t.trim().is_empty() || (t.starts_with('$') && !is_alfe_note(t)) {
            continue;
        }
        let line = Line {
            file: file.clone(),
            number: i + 1,
            text: t.to_string(),
        };
        if include_next {
            include_next = false;
            let inc = path.parent().unwrap_or(Path::new(".")).join(t.trim());
            lines(&inc, load, depth + 1, out)
                .map_err(|e| format!("{e} (included at {})", line.at()))?;
            continue;
        }
        if t.trim_start().to_ascii_uppercase().starts_with("*INCLUDE") {
            include_next = true;
            continue;
        }
        out.push(line);
    }
    Ok(())
}

/// A keyword line's name (upper case, without `*`, options and the `+`/`%` format marks).
pub fn keyword(t: &str) -> Option<(String, bool)> {
    let rest = t.trim_start().strip_prefix('*')?;
    let word = rest.split_whitespace().next().unwrap_or("");
    let long = word.ends_with('+') || rest.contains(" +");
    Some((
        word.trim_end_matches(['+', '%', '-']).to_ascii_uppercase(),
        long,
    ))
}

/// The fields of a data line: comma-separated, or fixed `widths` (the last repeated).
pub fn split<'a>(t: &'a str, widths: &[usize]) -> Vec<&'a str> {
    if t.contains(',') {
        return t.split(',').map(str::trim).collect();
    }
    let mut out = Vec::new();
    let mut pos = 0;
    let mut k = 0;
    while pos < t.len() {
        let w = widths[k.min(widths.len() - 1)];
        let end = t.floor_char_boundary((pos + w).min(t.len()));
        if end <= pos {
            break;
        }
        out.push(t[pos..end].trim());
        pos = end;
        k += 1;
    }
    out
}

/// An integer field (blank: 0).
pub fn int(s: &str, line: &Line, what: &str) -> Result<i64, String> {
    if s.is_empty() {
        return Ok(0);
    }
    s.parse().map_err(|_| {
        format!(
            "{}: expected {what}, got `{s}` in `{}`",
            line.at(),
            line.text.trim()
        )
    })
}

/// A real field (blank: 0; Fortran exponents `1.5-3` too).
pub fn real(s: &str, line: &Line) -> Result<f64, String> {
    if s.is_empty() {
        return Ok(0.0);
    }
    // Fortran exponents without `e` (1.0-3) are LS-DYNA's too.
    let v: f64 = s
        .parse()
        .or_else(|_| {
            let fixed = fortran_exponent(s);
            fixed.parse()
        })
        .map_err(|_| {
            format!(
                "{}: expected a number, got `{s}` in `{}`",
                line.at(),
                line.text.trim()
            )
        })?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("{}: `{s}` is not finite", line.at()))
    }
}

/// `1.5-3` → `1.5e-3` (an exponent sign after a digit, no `e`).
fn fortran_exponent(s: &str) -> String {
    let b = s.as_bytes();
    for i in 1..b.len() {
        if (b[i] == b'-' || b[i] == b'+') && b[i - 1].is_ascii_digit() {
            return format!("{}e{}", &s[..i], &s[i..]);
        }
    }
    s.to_string()
}

/// The keyword blocks LS-DYNA mesh files hold.
#[derive(Clone, Copy, PartialEq)]
enum Block {
    Node,
    Solid,
    Shell,
    Part,
    SetNode { title: bool },
    SetSegment { title: bool },
    Skip,
}

fn block_of(kw: &str) -> Block {
    match kw {
        "NODE" => Block::Node,
        "ELEMENT_SOLID" | "ELEMENT_SOLID_TET4TOTET10" => Block::Solid,
        "ELEMENT_SHELL" | "ELEMENT_SHELL_THICKNESS" => Block::Shell,
        "PART" => Block::Part,
        "SET_NODE_LIST" | "SET_NODE" => Block::SetNode { title: false },
        "SET_NODE_LIST_TITLE" | "SET_NODE_TITLE" => Block::SetNode { title: true },
        "SET_SEGMENT" => Block::SetSegment { title: false },
        "SET_SEGMENT_TITLE" => Block::SetSegment { title: true },
        _ => Block::Skip,
    }
}

/// What a file holds, as read: nodes, solids, shells, parts and sets by LS-DYNA number.
#[derive(Default)]
struct Raw {
    coords: Vec<[f64; 3]>,
    nodes: HashMap<i64, usize>,
    /// (eid, pid, nodes as numbers, line).
    solids: Vec<(i64, i64, Vec<i64>, String)>,
    shells: Vec<(i64, i64, Vec<i64>, String)>,
    part_titles: BTreeMap<i64, String>,
    node_sets: Vec<(String, Vec<i64>, String)>,
    segment_sets: Vec<(String, Vec<[i64; 4]>, String)>,
}

/// A `*NODE` card: number and coordinates.
fn node_card(raw: &mut Raw, line: &Line, long: bool) -> Result<(), String> {
    let t = &line.text;
    let f = if long {
        split(t, &[20])
    } else {
        split(t, &[8, 16, 16, 16, 8, 8])
    };
    let nid = int(f[0], line, "a node number")?;
    let x = [1, 2, 3].map(|k| f.get(k).copied().unwrap_or(""));
    let x = [real(x[0], line)?, real(x[1], line)?, real(x[2], line)?];
    if raw.nodes.insert(nid, raw.coords.len()).is_some() {
        return Err(format!("{}: node {nid} is defined twice", line.at()));
    }
    raw.coords.push(x);
    Ok(())
}

/// A set's header card: its number names it unless it has a title.
fn set_header(
    raw: &mut Raw,
    block: Block,
    line: &Line,
    title: Option<String>,
) -> Result<(), String> {
    let f = split(&line.text, &[10]);
    let sid = int(f[0], line, "a set number")?;
    let name = title
        .filter(|s| !s.is_empty())
        .unwrap_or(format!("set-{sid}"));
    if matches!(block, Block::SetNode { .. }) {
        raw.node_sets.push((name, Vec::new(), line.at()));
    } else {
        raw.segment_sets.push((name, Vec::new(), line.at()));
    }
    Ok(())
}

/// A set's data card: node numbers, or a segment's four.
fn set_card(raw: &mut Raw, block: Block, line: &Line) -> Result<(), String> {
    let f = split(&line.text, &[10]);
    let nums: Vec<i64> = f
        .iter()
        .map(|s| int(s, line, "a node number"))
        .collect::<Result<_, _>>()?;
    if matches!(block, Block::SetNode { .. }) {
        let s = raw.node_sets.last_mut().expect("header read");
        s.1.extend(nums.into_iter().filter(|&n| n != 0));
        return Ok(());
    }
    if nums.len() < 4 {
        return Err(format!(
            "{}: a segment is four node numbers: `{}`",
            line.at(),
            line.text.trim()
        ));
    }
    let s = raw.segment_sets.last_mut().expect("header read");
    s.1.push([nums[0], nums[1], nums[2], nums[3]]);
    Ok(())
}

/// Parse every block of `path` and its includes.
fn parse(path: &Path, load: &Loader) -> Result<Raw, String> {
    let all: Vec<Line> = read_lines_k(path, load)?
        .into_iter()
        .filter(|l| !is_alfe_note(&l.text))
        .collect();
    let mut raw = Raw::default();
    let mut block = Block::Skip;
    let mut long = false;
    // Multi-line records: a two-card solid, a part's title, a set's header.
    let mut pending: Option<(i64, i64, String)> = None;
    let mut part_title: Option<String> = None;
    let mut set_title: Option<String> = None;
    let mut set_open = false;
    let mut title_next = false;
    for line in &all {
        if let Some((kw, l)) = keyword(&line.text) {
            if let Some((eid, _, at)) = pending.take() {
                return Err(format!("{at}: solid {eid}: its node card is missing"));
            }
            block = block_of(&kw);
            long = l;
            part_title = None;
            set_title = None;
            set_open = false;
            title_next = matches!(
                block,
                Block::Part | Block::SetNode { title: true } | Block::SetSegment { title: true }
            );
            continue;
        }
        let w = if long { 20 } else { 8 };
        let t = &line.text;
        match block {
            Block::Skip => {}
            Block::Node => node_card(&mut raw, line, long)?,
            Block::Solid => {
                let f = split(t, &[w]);
                let nums: Vec<i64> = f
                    .iter()
                    .map(|s| int(s, line, "an integer"))
                    .collect::<Result<_, _>>()?;
                match pending.take() {
                    Some((eid, pid, at)) => raw.solids.push((
                        eid,
                        pid,
                        nums.into_iter().filter(|&n| n != 0).collect(),
                        at,
                    )),
                    None if nums.iter().filter(|&&n| n != 0).count() <= 2 => {
                        pending = Some((nums[0], nums.get(1).copied().unwrap_or(0), line.at()))
                    }
                    None => raw.solids.push((
                        nums[0],
                        nums[1],
                        nums[2..].iter().copied().filter(|&n| n != 0).collect(),
                        line.at(),
                    )),
                }
            }
            Block::Shell => {
                let f = split(t, &[w]);
                let nums: Vec<i64> = f
                    .iter()
                    .map(|s| int(s, line, "an integer"))
                    .collect::<Result<_, _>>()?;
                if nums.len() < 5 {
                    return Err(format!(
                        "{}: a shell card is `eid pid n1 n2 n3 n4`: `{}`",
                        line.at(),
                        t.trim()
                    ));
                }
                raw.shells.push((
                    nums[0],
                    nums[1],
                    nums[2..6.min(nums.len())].to_vec(),
                    line.at(),
                ));
            }
            Block::Part => {
                if title_next {
                    title_next = false;
                    part_title = Some(t.trim().to_string());
                    continue;
                }
                let f = split(t, &[10]);
                let pid = int(f[0], line, "a part number")?;
                if let Some(title) = part_title.take().filter(|s| !s.is_empty()) {
                    raw.part_titles.insert(pid, title);
                }
                title_next = true;
            }
            Block::SetNode { .. } | Block::SetSegment { .. } => {
                if title_next {
                    title_next = false;
                    set_title = Some(t.trim().to_string());
                } else if !set_open {
                    set_open = true;
                    set_header(&mut raw, block, line, set_title.take())?;
                } else {
                    set_card(&mut raw, block, line)?;
                }
            }
        }
    }
    if let Some((eid, _, at)) = pending {
        return Err(format!("{at}: solid {eid}: its node card is missing"));
    }
    Ok(raw)
}

fn node_index(raw: &Raw, n: i64, at: &str, what: &str) -> Result<usize, String> {
    raw.nodes
        .get(&n)
        .copied()
        .ok_or_else(|| format!("{at}: {what} uses node {n}, which no *NODE defines"))
}

/// An LS-DYNA solid's kind and alfe nodes (in alfe's order, right-handed).
fn solid(raw: &Raw, eid: i64, ns: &[i64], at: &str) -> Result<(ElemKind, Vec<usize>), String> {
    let idx: Vec<usize> = ns
        .iter()
        .map(|&n| node_index(raw, n, at, &format!("solid {eid}")))
        .collect::<Result<_, _>>()?;
    let distinct = {
        let mut d = idx.clone();
        d.sort_unstable();
        d.dedup();
        d.len()
    };
    let (kind, nodes) = match (idx.len(), distinct) {
        (8, 8) => (ElemKind::Hex8, idx),
        (8, 4) if idx[3..].iter().all(|&n| n == idx[3]) => (ElemKind::Tet4, idx[..4].to_vec()),
        (4, 4) => (ElemKind::Tet4, idx),
        (8, 6) if idx[4] == idx[5] && idx[6] == idx[7] => (
            ElemKind::Wedge6,
            vec![idx[0], idx[1], idx[4], idx[3], idx[2], idx[6]],
        ),
        (10, 10) => (ElemKind::Tet10, tet10_by_position(raw, &idx, eid, at)?),
        _ => {
            return Err(format!(
                "{at}: solid {eid} has {} node numbers, {distinct} distinct: not a hex8, a degenerate tet or wedge (n4 = … = n8; n5 = n6, n7 = n8) or a 10-node tet",
                idx.len()
            ))
        }
    };
    Ok((kind, nodes))
}

/// A 10-node tet's midside nodes on alfe's edges, by position (LS-DYNA and Abaqus order
/// them differently; the geometry does not lie).
fn tet10_by_position(raw: &Raw, idx: &[usize], eid: i64, at: &str) -> Result<Vec<usize>, String> {
    let x = |n: usize| raw.coords[n];
    let mut out = idx[..4].to_vec();
    let mut used = [false; 6];
    for [a, b] in TET10_EDGES {
        let m: [f64; 3] = std::array::from_fn(|k| 0.5 * (x(idx[a])[k] + x(idx[b])[k]));
        let (j, _) = (0..6)
            .filter(|&j| !used[j])
            .map(|j| {
                let p = x(idx[4 + j]);
                (j, (0..3).map(|k| (p[k] - m[k]).powi(2)).sum::<f64>())
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .ok_or_else(|| format!("{at}: solid {eid}: its midside nodes do not fit its edges"))?;
        used[j] = true;
        out.push(idx[4 + j]);
    }
    Ok(out)
}

/// Reverse an element's orientation (LS-DYNA accepts either; alfe wants right-handed).
fn flip(kind: ElemKind, n: &mut [usize]) {
    match kind {
        ElemKind::Hex8 => {
            n.swap(1, 3);
            n.swap(5, 7);
        }
        ElemKind::Tet4 => n.swap(1, 2),
        ElemKind::Tet10 => {
            n.swap(1, 2);
            // Edges 0-1 ↔ 0-2 (nodes 4, 6), 1-3 ↔ 2-3 (nodes 9, 8).
            n.swap(4, 6);
            n.swap(8, 9);
        }
        ElemKind::Wedge6 => {
            n.swap(1, 2);
            n.swap(4, 5);
        }
    }
}

/// Read `path` (with its includes) as the mesh of deck part `part`: its solids, or only
/// those of LS-DYNA part `pid` (one alfe part per LS-DYNA part, each with its own
/// material: node sets and segments then keep what lies in that part); shells are
/// refused here (a sheet reads them). Nodes no kept solid uses stay in the mesh (the
/// scene drops them).
pub fn read_k(path: &Path, part: u32, pid: Option<i64>, load: &Loader) -> Result<Mesh, String> {
    let mut raw = parse(path, load)?;
    if let Some(p) = pid {
        raw.solids.retain(|s| s.1 == p);
        if raw.solids.is_empty() {
            return Err(format!(
                "{}: no *ELEMENT_SOLID belongs to part {p}",
                path.display()
            ));
        }
    }
    if let Some((eid, _, _, at)) = raw.shells.first() {
        if raw.solids.is_empty() {
            return Err(format!(
                "{at}: shell {eid}: the file's elements are shells; read it as a sheet (kind = \"sheet\", file, thickness)"
            ));
        }
    }
    if raw.solids.is_empty() {
        return Err(format!(
            "{}: the file has no *ELEMENT_SOLID",
            path.display()
        ));
    }
    let mut mesh = Mesh {
        coords: raw.coords.clone(),
        offsets: vec![0],
        ..Default::default()
    };
    let mut elems: HashMap<i64, usize> = HashMap::new();
    for (eid, pid, ns, at) in &raw.solids {
        let (kind, mut nodes) = solid(&raw, *eid, ns, at)?;
        let e = mesh.n_elems();
        mesh.push_elem(kind, &nodes, part);
        if mesh.elem_volume(e) < 0.0 {
            flip(kind, &mut nodes);
            let start = mesh.offsets[e];
            mesh.conn[start..start + nodes.len()].copy_from_slice(&nodes);
        }
        if mesh.elem_volume(e) <= 0.0 {
            return Err(format!(
                "{at}: solid {eid} ({}) is degenerate: zero volume",
                kind.name()
            ));
        }
        if elems.insert(*eid, e).is_some() {
            return Err(format!("{at}: solid {eid} is defined twice"));
        }
        let name = raw
            .part_titles
            .get(pid)
            .cloned()
            .unwrap_or(format!("part-{pid}"));
        mesh.elem_groups.entry(name.clone()).or_default().push(e);
        mesh.node_groups.entry(name).or_default().extend(nodes);
    }
    for (name, ns, at) in &raw.node_sets {
        let v: Vec<usize> = ns
            .iter()
            .map(|&n| node_index(&raw, n, at, &format!("node set {name}")))
            .collect::<Result<_, _>>()?;
        mesh.node_groups.entry(name.clone()).or_default().extend(v);
    }
    let faces = face_index(&mesh);
    for (name, segs, at) in &raw.segment_sets {
        let mut fs = Vec::new();
        for s in segs {
            let mut key: Vec<usize> = s
                .iter()
                .map(|&n| node_index(&raw, n, at, &format!("segment set {name}")))
                .collect::<Result<_, _>>()?;
            key.sort_unstable();
            key.dedup();
            let Some(f) = faces.get(&key) else {
                if pid.is_some() {
                    continue; // a face of another part
                }
                return Err(format!(
                    "{at}: a segment of set {name} (nodes {s:?}) is not a face of any solid"
                ));
            };
            fs.push(*f);
            mesh.node_groups
                .entry(name.clone())
                .or_default()
                .extend(key);
        }
        mesh.face_groups.entry(name.clone()).or_default().extend(fs);
    }
    for v in mesh
        .node_groups
        .values_mut()
        .chain(mesh.elem_groups.values_mut())
    {
        v.sort_unstable();
        v.dedup();
    }
    // Faces keep the file's order (a surface's sums run in it: a model written by
    // `alfe export` comes back bit for bit), each once.
    for v in mesh.face_groups.values_mut() {
        let mut seen = std::collections::BTreeSet::new();
        v.retain(|f| seen.insert(*f));
    }
    Ok(mesh)
}

/// Every element face by its sorted corner nodes.
fn face_index(mesh: &Mesh) -> HashMap<Vec<usize>, FaceRef> {
    let mut out = HashMap::new();
    for e in 0..mesh.n_elems() {
        let kind = mesh.kinds[e];
        let en = mesh.elem_nodes(e);
        for fi in 0..kind.faces().len() {
            let mut key: Vec<usize> = kind.face_corners(fi).iter().map(|&k| en[k]).collect();
            key.sort_unstable();
            out.entry(key).or_insert(FaceRef {
                elem: e,
                face: fi as u8,
            });
        }
    }
    out
}

/// Read `path`'s shells as a sheet's surface: quads (n3 ≠ n4) and triangles (n3 = n4),
/// each part a group of facets under its title (or `part-<pid>`), node sets as point
/// groups.
pub fn read_surface_k(path: &Path, load: &Loader) -> Result<Surface, String> {
    let raw = parse(path, load)?;
    if raw.shells.is_empty() {
        return Err(format!(
            "{}: the file has no *ELEMENT_SHELL to extrude",
            path.display()
        ));
    }
    let mut s = Surface {
        coords: raw.coords.clone(),
        ..Default::default()
    };
    for (eid, pid, ns, at) in &raw.shells {
        let mut idx: Vec<usize> = ns
            .iter()
            .map(|&n| node_index(&raw, n, at, &format!("shell {eid}")))
            .collect::<Result<_, _>>()?;
        if idx.len() == 4 && idx[2] == idx[3] {
            idx.pop();
        }
        let q = s.quads.len();
        let line = at
            .rsplit(':')
            .next()
            .and_then(|l| l.parse().ok())
            .unwrap_or(0);
        s.quads.push(idx);
        s.quad_lines.push((line, *eid as u64));
        let name = raw
            .part_titles
            .get(pid)
            .cloned()
            .unwrap_or(format!("part-{pid}"));
        s.quad_groups.entry(name).or_default().push(q);
    }
    for (name, ns, at) in &raw.node_sets {
        let v: Vec<usize> = ns
            .iter()
            .map(|&n| node_index(&raw, n, at, &format!("node set {name}")))
            .collect::<Result<_, _>>()?;
        s.point_groups.entry(name.clone()).or_default().extend(v);
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(files: &[(&str, &str)]) -> Result<Mesh, String> {
        let load = |p: &Path| -> Result<String, String> {
            files
                .iter()
                .find(|(n, _)| Path::new(n) == p)
                .map(|(_, t)| t.to_string())
                .ok_or_else(|| format!("{}: no such file", p.display()))
        };
        read_k(Path::new(files[0].0), 1, None, &load)
    }

    /// A unit cube's corners (nodes 1–8) and a ninth node above it, fixed width.
    const NODES: &str = "*KEYWORD
$# comment
*NODE
$#   nid               x               y               z      tc      rc
       1             0.0             0.0             0.0       0       0
       2             1.0             0.0             0.0       0       0
       3             1.0             1.0             0.0       0       0
       4             0.0             1.0             0.0       0       0
       5             0.0             0.0             1.0       0       0
       6             1.0             0.0             1.0       0       0
       7             1.0             1.0             1.0       0       0
       8             0.0             1.0             1.0       0       0
       9             0.5             0.5           2.0-0       0       0
";

    #[test]
    fn reads_hexes_degenerate_solids_parts_and_sets() {
        let text = format!(
            "{NODES}*PART
cube
       1       1       1
*PART
apex
       2       1       1
*ELEMENT_SOLID
       1       1       1       2       3       4       5       6       7       8
       2       2       5       6       7       9       9       9       9       9
3, 2, 5,7,6,9,9,9,9,9
*SET_NODE_LIST_TITLE
bottom corners
         7
         1         2         3
         4
*SET_SEGMENT
         8
         5         6         7         8
*END
"
        );
        let m = read(&[("m.k", &text)]).unwrap();
        assert_eq!(
            m.kinds,
            vec![ElemKind::Hex8, ElemKind::Tet4, ElemKind::Tet4]
        );
        assert!((m.elem_volume(0) - 1.0).abs() < 1e-14);
        // The tet over face 5-6-7 with apex 9 (z = 2): 0.5 × 1 / 3; the second was
        // written inverted and is reordered.
        assert!(
            (m.elem_volume(1) - 1.0 / 6.0).abs() < 1e-14,
            "{}",
            m.elem_volume(1)
        );
        assert!(
            (m.elem_volume(2) - 1.0 / 6.0).abs() < 1e-14,
            "{}",
            m.elem_volume(2)
        );
        assert_eq!(m.elem_groups["cube"], vec![0]);
        assert_eq!(m.elem_groups["apex"], vec![1, 2]);
        assert_eq!(m.node_groups["bottom corners"], vec![0, 1, 2, 3]);
        // The segment 5-6-7-8 is the hex's top face (the tets share only triangles).
        let f = m.face_groups["set-8"][0];
        assert_eq!(f.elem, 0);
        assert!(m.face_nodes(f).iter().all(|&n| m.coords[n][2] == 1.0));
    }

    /// The two-card ("ten nodes") layout, a degenerate wedge, long format and a 10-node
    /// tet whose midside nodes are placed by position.
    #[test]
    fn reads_the_two_card_layout_wedges_and_tet10() {
        let text = format!(
            "{NODES}*ELEMENT_SOLID (ten nodes format)
       1       7
       1       2       3       4       5       5       8       8       0       0
"
        );
        let m = read(&[("w.k", &text)]).unwrap();
        assert_eq!(m.kinds, vec![ElemKind::Wedge6]);
        assert!(
            (m.elem_volume(0) - 0.5).abs() < 1e-14,
            "{}",
            m.elem_volume(0)
        );
        assert_eq!(m.elem_groups["part-7"], vec![0]);

        let c = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let mut t = String::from("*NODE +\n");
        let mut pts: Vec<[f64; 3]> = c.to_vec();
        // Midside nodes in a shuffled order.
        for [a, b] in [[2, 3], [0, 1], [1, 3], [1, 2], [0, 3], [2, 0]] {
            pts.push(std::array::from_fn(|k| 0.5 * (c[a][k] + c[b][k])));
        }
        for (i, p) in pts.iter().enumerate() {
            t += &format!("{:>20}{:>20}{:>20}{:>20}\n", i + 1, p[0], p[1], p[2]);
        }
        t += "*ELEMENT_SOLID\n       1       1\n       1       2       3       4       5       6       7       8       9      10\n";
        let m = read(&[("t.k", &t)]).unwrap();
        assert_eq!(m.kinds, vec![ElemKind::Tet10]);
        let en = m.elem_nodes(0);
        for (k, [a, b]) in TET10_EDGES.iter().enumerate() {
            let mid: Vec<f64> = (0..3).map(|i| 0.5 * (c[*a][i] + c[*b][i])).collect();
            assert_eq!(m.coords[en[4 + k]].to_vec(), mid);
        }
    }

    #[test]
    fn shells_are_a_surface_and_refusals_name_the_line() {
        let shells = format!(
            "{NODES}*ELEMENT_SHELL\n       1       3       1       2       3       4\n       2       3       5       6       9       9\n"
        );
        let s = read_surface_k(Path::new("s.k"), &|_: &Path| Ok(shells.clone())).unwrap();
        assert_eq!(s.quads, vec![vec![0, 1, 2, 3], vec![4, 5, 8]]);
        assert_eq!(s.quad_groups["part-3"], vec![0, 1]);
        let e = read(&[("s.k", &shells)]).unwrap_err();
        assert!(
            e.contains("s.k:15: shell 1: the file's elements are shells; read it as a sheet"),
            "{e}"
        );
        for (text, want) in [
            (format!("{NODES}*ELEMENT_SOLID\n       1       1       1       2       3      44       5       6       7       8\n"), "x.k:15: solid 1 uses node 44"),
            (format!("{NODES}*ELEMENT_SOLID\n       1       1       1       2       3       3       5       6       7       8\n"), "x.k:15: solid 1 has 8 node numbers, 7 distinct"),
            (NODES.replace("1.0             0.0             0.0       0", "1.0             0.x             0.0       0"), "x.k:6: expected a number, got `0.x`"),
            (format!("{NODES}*ELEMENT_SOLID\n       1       1\n"), "x.k:15: solid 1: its node card is missing"),
            (format!("{NODES}*INCLUDE\nmissing.k\n"), "missing.k: no such file (included at x.k:"),
        ] {
            let e = read(&[("x.k", &text)]).unwrap_err();
            assert!(e.contains(want), "want `{want}`, got {e}");
        }
    }
}
