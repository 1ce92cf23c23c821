//! The ASCII sections of MSH 4.1 and 2.2 (and the `$MeshFormat` header both share).

use super::*;

/// `$MeshFormat`: version 4.1 or 2.2; whether it is 2.2. A binary file (file type 1) is
/// read only when `allow_binary` (text cannot hold its raw blocks).
pub(super) fn header(lx: &mut Lexer, allow_binary: bool) -> Result<bool, String> {
    match lx.next() {
        Some(("$MeshFormat", _)) => {}
        Some((t, at)) => {
            return Err(format!(
                "{at}: not a Gmsh .msh file: expected $MeshFormat, found \"{t}\""
            ))
        }
        None => return Err("empty mesh file: expected $MeshFormat".to_string()),
    }
    let (version, at) = lx.tok("the MSH version")?;
    let v2 = matches!(version, "2.2" | "2.1" | "2");
    if version != "4.1" && !v2 {
        return Err(format!(
            "{at}: MSH version {version} is not supported; alfe reads MSH 4.1 and 2.2 (gmsh -format msh41)"
        ));
    }
    let (file_type, at) = lx.tok("the file type (0 = ASCII, 1 = binary)")?;
    match (file_type, allow_binary) {
        ("0", _) => {
            lx.tok("the data size")?;
        }
        ("1", true) => binary_header(lx, v2)?,
        (_, false) => return Err(format!("{at}: binary .msh files are not supported when reading text; read the file's bytes (gmsh::read_msh_bytes, read_surface_bytes)")),
        (t, true) => {
            return Err(format!(
                "{at}: expected the file type 0 (ASCII) or 1 (binary), found \"{t}\""
            ))
        }
    }
    lx.end()?;
    Ok(v2)
}

/// MSH 2.2 `$Nodes`: a count, then `tag x y z` lines.
pub(super) fn nodes_v2(
    lx: &mut Lexer,
    raw: &mut Raw,
    node_index: &mut HashMap<u64, usize>,
) -> Result<(), String> {
    let n = lx.count("the number of nodes")?;
    raw.coords.reserve(n);
    for _ in 0..n {
        let (t, at) = lx.tok("a node tag")?;
        let tag: u64 = t.parse().map_err(|_| {
            format!("{at}: expected a node tag (a positive integer), found \"{t}\"")
        })?;
        new_node(node_index, tag, raw.coords.len(), at)?;
        raw.coords.push([
            lx.real("a node coordinate")?,
            lx.real("a node coordinate")?,
            lx.real("a node coordinate")?,
        ]);
    }
    Ok(())
}

/// MSH 2.2 `$Elements`: a count, then `tag type ntags tags... nodes...` lines; the first
/// tag is the physical group, which stands in for the entity (4.1's groups are by entity).
pub(super) fn elements_v2(
    lx: &mut Lexer,
    raw: &mut Raw,
    node_index: &HashMap<u64, usize>,
    seen_nodes: bool,
) -> Result<(), String> {
    let n = lx.count("the number of elements")?;
    let mut seen = HashSet::new();
    for _ in 0..n {
        let (t, loc) = lx.tok("an element tag")?;
        let etag: u64 = t.parse().map_err(|_| {
            format!("{loc}: expected an element tag (a positive integer), found \"{t}\"")
        })?;
        new_elem(&mut seen, etag, loc)?;
        let ty = lx.uint("an element type")?;
        let Some((dim, nn)) = elem_type(ty) else {
            return Err(unsupported_type(loc, &format!("element {etag} has"), ty));
        };
        let ntags = lx.count("the number of tags")?;
        let mut physical = 0;
        for k in 0..ntags {
            let v = lx.int("an element tag value")?;
            if k == 0 {
                physical = v.abs();
            }
        }
        if physical != 0 {
            raw.entity_phys.insert((dim, physical), vec![physical]);
        }
        let at = raw.conn.len();
        for _ in 0..nn {
            let (t, l) = lx.tok("a node tag")?;
            let ntag: u64 = t.parse().map_err(|_| {
                format!(
                    "{l}: element {etag}: expected a node tag (a positive integer), found \"{t}\""
                )
            })?;
            raw.conn
                .push(node_of(node_index, etag, ntag, l, seen_nodes)?);
        }
        raw.elems.push(RawElem {
            dim,
            entity: physical,
            tag: etag,
            loc,
            nn,
            at,
        });
    }
    Ok(())
}

/// `$PhysicalNames`: (dimension, tag) → name. ASCII in binary files too.
pub(super) fn physical_names(lx: &mut Lexer, raw: &mut Raw) -> Result<(), String> {
    let n = lx.count("the number of physical names")?;
    for _ in 0..n {
        let dim = lx.count("a physical group dimension")?;
        let tag = lx.int("a physical group tag")?;
        let (q, at) = lx.tok("a quoted physical group name")?;
        let Some(s) = q.strip_prefix('"').and_then(|s| s.strip_suffix('"')) else {
            return Err(format!(
                "{at}: expected a quoted physical group name, found {q}"
            ));
        };
        raw.phys_names.insert((dim, tag), s.to_string());
    }
    Ok(())
}

/// `$Entities`: each entity's physical tags (coordinates and bounding entities skipped).
pub(super) fn entities(lx: &mut Lexer, raw: &mut Raw) -> Result<(), String> {
    let counts = [
        lx.count("the number of points")?,
        lx.count("the number of curves")?,
        lx.count("the number of surfaces")?,
        lx.count("the number of volumes")?,
    ];
    for (dim, &n) in counts.iter().enumerate() {
        for _ in 0..n {
            let tag = lx.int("an entity tag")?;
            // Points: x y z; others: a bounding box.
            for _ in 0..if dim == 0 { 3 } else { 6 } {
                lx.real("an entity coordinate")?;
            }
            let np = lx.count("the number of physical tags")?;
            let mut tags = Vec::with_capacity(np);
            for _ in 0..np {
                tags.push(lx.int("a physical tag")?.abs());
            }
            if dim > 0 {
                let nb = lx.count("the number of bounding entities")?;
                lx.skip(nb, "a bounding entity tag")?;
            }
            if !tags.is_empty() {
                raw.entity_phys.insert((dim, tag), tags);
            }
        }
    }
    Ok(())
}

/// `$Nodes`: coordinates in order of appearance; `node_index` maps tags to indices.
pub(super) fn nodes(
    lx: &mut Lexer,
    raw: &mut Raw,
    node_index: &mut HashMap<u64, usize>,
) -> Result<(), String> {
    let blocks = lx.count("the number of node blocks")?;
    let total = lx.count("the number of nodes")?;
    lx.skip(2, "the min and max node tags")?;
    raw.coords.reserve(total);
    for _ in 0..blocks {
        let edim = lx.count("an entity dimension")?;
        lx.int("an entity tag")?;
        let parametric = lx.uint("the parametric flag")? != 0;
        let n = lx.count("the number of nodes in the block")?;
        for k in 0..n {
            let (t, at) = lx.tok("a node tag")?;
            let tag: u64 = t.parse().map_err(|_| {
                format!("{at}: expected a node tag (a positive integer), found \"{t}\"")
            })?;
            new_node(node_index, tag, raw.coords.len() + k, at)?;
        }
        for _ in 0..n {
            let x = [
                lx.real("a node coordinate")?,
                lx.real("a node coordinate")?,
                lx.real("a node coordinate")?,
            ];
            if parametric {
                lx.skip(edim, "a parametric coordinate")?;
            }
            raw.coords.push(x);
        }
    }
    Ok(())
}

/// `$Elements`: connectivity by node index, with each element's entity, tag and line.
pub(super) fn elements(
    lx: &mut Lexer,
    raw: &mut Raw,
    node_index: &HashMap<u64, usize>,
    seen_nodes: bool,
) -> Result<(), String> {
    let blocks = lx.count("the number of element blocks")?;
    let header = lx.here();
    let total = lx.count("the number of elements")?;
    lx.skip(2, "the min and max element tags")?;
    let first = raw.elems.len();
    let mut tags = HashSet::new();
    for _ in 0..blocks {
        lx.count("an entity dimension")?;
        let entity = lx.int("an entity tag")?;
        let (t, type_at) = lx.tok("an element type")?;
        let ty: u64 = t.parse().map_err(|_| {
            format!("{type_at}: expected an element type (an integer), found \"{t}\"")
        })?;
        let n = lx.count("the number of elements in the block")?;
        let Some((dim, nn)) = elem_type(ty) else {
            let (what, at) = match lx.next() {
                Some((t, l)) if n > 0 => (format!("element {t} has"), l),
                _ => ("an element block has".to_string(), type_at),
            };
            return Err(unsupported_type(at, &what, ty));
        };
        for _ in 0..n {
            let (t, loc) = lx.tok("an element tag")?;
            let etag: u64 = t.parse().map_err(|_| {
                format!("{loc}: expected an element tag (a positive integer), found \"{t}\"")
            })?;
            new_elem(&mut tags, etag, loc)?;
            let at = raw.conn.len();
            for _ in 0..nn {
                let (t, l) = lx.tok("a node tag")?;
                let ntag: u64 = t.parse().map_err(|_| {
                    format!("{l}: element {etag}: expected a node tag (a positive integer), found \"{t}\"")
                })?;
                raw.conn
                    .push(node_of(node_index, etag, ntag, l, seen_nodes)?);
            }
            raw.elems.push(RawElem {
                dim,
                entity,
                tag: etag,
                loc,
                nn,
                at,
            });
        }
    }
    block_total(header, total, raw.elems.len() - first)
}

/// The element count of a `$Elements` header (at `header`) against its blocks'.
pub(super) fn block_total(header: Loc, total: usize, read: usize) -> Result<(), String> {
    if read != total {
        return Err(format!(
            "{header}: $Elements says {total} elements, its blocks hold {read}"
        ));
    }
    Ok(())
}

/// A section alfe does not need, up to its `$End` line. In a binary file the raw data is
/// scanned as tokens too: Gmsh ends it with a newline, so `$End...` stays a token.
pub(super) fn skip_section(lx: &mut Lexer, name: &str) -> Result<(), String> {
    let want = format!("$End{name}");
    loop {
        match lx.next() {
            Some((t, _)) if t == want => return Ok(()),
            Some(_) => {}
            None => return Err(format!("end of file: ${name} is never closed by {want}")),
        }
    }
}
