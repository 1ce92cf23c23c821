//! The binary sections of MSH 4.1 and 2.2: raw ints, size_ts and doubles in the byte
//! order the header's int 1 gives; every count is checked against the bytes left before
//! anything is allocated.

use super::*;

/// The rest of a binary `$MeshFormat`: the data size (MSH 4.1's size_t, 8 or 4; 2.2 has
/// no size_t and needs it 8, its doubles), then after the line the int 1 whose bytes
/// give the byte order of every raw field after it.
pub(super) fn binary_header(lx: &mut Lexer, v2: bool) -> Result<(), String> {
    let (size, at) = lx.tok("the data size")?;
    lx.size_t = match (size, v2) {
        ("8", _) => 8,
        ("4", false) => 4,
        _ => {
            return Err(format!(
                "{at}: data size {size} is not supported in a binary MSH {} file; alfe reads 8{}",
                if v2 { "2.2" } else { "4.1" },
                if v2 { "" } else { " or 4" }
            ))
        }
    };
    lx.line_end()?;
    let at = lx.pos;
    lx.big_endian = match lx.take(4, "the int 1 that gives the byte order")? {
        [1, 0, 0, 0] => false,
        [0, 0, 0, 1] => true,
        other => {
            return Err(format!(
                "byte {at}: expected the int 1 that gives a binary .msh file's byte order, found the bytes {other:02x?}"
            ))
        }
    };
    lx.binary = true;
    Ok(())
}

/// Binary MSH 4.1 `$Entities`: as [`entities`], with size_t counts and int tags.
pub(super) fn entities_bin(lx: &mut Lexer, raw: &mut Raw) -> Result<(), String> {
    let sz = lx.size_t;
    // Smallest entity: tag, coordinates (3 doubles for points, a 6-double box for the
    // rest), physical count and, but for points, bounding count.
    let point = 4 + 24 + sz;
    let other = 4 + 48 + 2 * sz;
    let counts = [
        lx.b_count("the number of points", point)?,
        lx.b_count("the number of curves", other)?,
        lx.b_count("the number of surfaces", other)?,
        lx.b_count("the number of volumes", other)?,
    ];
    for (dim, &n) in counts.iter().enumerate() {
        for _ in 0..n {
            let tag = lx.b_int("an entity tag")?;
            lx.take(if dim == 0 { 24 } else { 48 }, "an entity's coordinates")?;
            let np = lx.b_count("the number of physical tags", 4)?;
            let mut tags = Vec::with_capacity(np);
            for _ in 0..np {
                tags.push(lx.b_int("a physical tag")?.abs());
            }
            if dim > 0 {
                let nb = lx.b_count("the number of bounding entities", 4)?;
                lx.take(4 * nb, "the bounding entity tags")?;
            }
            if !tags.is_empty() {
                raw.entity_phys.insert((dim, tag), tags);
            }
        }
    }
    Ok(())
}

/// Binary MSH 4.1 `$Nodes`: as [`nodes`]; each block is its int entity dimension, tag
/// and parametric flag, size_t node count, the size_t node tags, then the coordinates
/// (x y z and, if parametric, one double per entity dimension).
pub(super) fn nodes_bin(
    lx: &mut Lexer,
    raw: &mut Raw,
    node_index: &mut HashMap<u64, usize>,
) -> Result<(), String> {
    let sz = lx.size_t;
    let blocks = lx.b_count("the number of node blocks", 12 + sz)?;
    let total = lx.b_count("the number of nodes", sz + 24)?;
    lx.b_size("the minimum node tag")?;
    lx.b_size("the maximum node tag")?;
    raw.coords.reserve(total);
    for _ in 0..blocks {
        let at = lx.pos;
        let edim = lx.b_int("an entity dimension")?;
        if !(0..=3).contains(&edim) {
            return Err(format!(
                "byte {at}: expected an entity dimension (0 to 3), found {edim}"
            ));
        }
        lx.b_int("an entity tag")?;
        let parametric = lx.b_int("the parametric flag")? != 0;
        let extra = if parametric { 8 * edim as usize } else { 0 };
        let n = lx.b_count("the number of nodes in the block", sz + 24 + extra)?;
        for k in 0..n {
            let at = Loc::Byte(lx.pos);
            let tag = lx.b_size("a node tag")?;
            new_node(node_index, tag, raw.coords.len() + k, at)?;
        }
        for _ in 0..n {
            raw.coords.push([
                lx.b_real("a node coordinate")?,
                lx.b_real("a node coordinate")?,
                lx.b_real("a node coordinate")?,
            ]);
            lx.take(extra, "parametric coordinates")?;
        }
    }
    Ok(())
}

/// Binary MSH 4.1 `$Elements`: as [`elements`]; each block is its int entity dimension,
/// tag and element type, size_t element count, then per element its size_t tag and node
/// tags.
pub(super) fn elements_bin(
    lx: &mut Lexer,
    raw: &mut Raw,
    node_index: &HashMap<u64, usize>,
    seen_nodes: bool,
) -> Result<(), String> {
    let sz = lx.size_t;
    let blocks = lx.b_count("the number of element blocks", 12 + sz)?;
    let header = lx.here();
    // The smallest element, a point, is its tag and one node.
    let total = lx.b_count("the number of elements", 2 * sz)?;
    lx.b_size("the minimum element tag")?;
    lx.b_size("the maximum element tag")?;
    let first = raw.elems.len();
    let mut tags = HashSet::new();
    for _ in 0..blocks {
        lx.b_int("an entity dimension")?;
        let entity = lx.b_int("an entity tag")?;
        let type_at = lx.here();
        let ty = lx.b_uint(4, "an element type")?;
        let Some((dim, nn)) = elem_type(ty) else {
            let n = lx.b_count("the number of elements in the block", 2 * sz)?;
            let (what, at) = match (n, lx.here()) {
                (1.., at) => (format!("element {} has", lx.b_size("an element tag")?), at),
                _ => ("an element block has".to_string(), type_at),
            };
            return Err(unsupported_type(at, &what, ty));
        };
        let n = lx.b_count("the number of elements in the block", (1 + nn) * sz)?;
        for _ in 0..n {
            let loc = lx.here();
            let etag = lx.b_size("an element tag")?;
            new_elem(&mut tags, etag, loc)?;
            let at = raw.conn.len();
            for _ in 0..nn {
                let l = lx.here();
                let ntag = lx.b_size("a node tag")?;
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

/// Binary MSH 2.2 `$Nodes`: an ASCII count line, then per node an int tag and x y z.
pub(super) fn nodes_v2_bin(
    lx: &mut Lexer,
    raw: &mut Raw,
    node_index: &mut HashMap<u64, usize>,
) -> Result<(), String> {
    let n = count_line(lx, "the number of nodes", 4 + 24)?;
    raw.coords.reserve(n);
    for _ in 0..n {
        let at = lx.here();
        let tag = lx.b_uint(4, "a node tag")?;
        new_node(node_index, tag, raw.coords.len(), at)?;
        raw.coords.push([
            lx.b_real("a node coordinate")?,
            lx.b_real("a node coordinate")?,
            lx.b_real("a node coordinate")?,
        ]);
    }
    Ok(())
}

/// Binary MSH 2.2 `$Elements`: an ASCII count line, then groups of elements of one type,
/// each an int header (type, number of elements, number of tags) and per element its int
/// tag, tags and node tags, until the count is reached. As in ASCII 2.2, the first tag
/// (the physical group) stands in for the entity.
pub(super) fn elements_v2_bin(
    lx: &mut Lexer,
    raw: &mut Raw,
    node_index: &HashMap<u64, usize>,
    seen_nodes: bool,
) -> Result<(), String> {
    // The smallest element, a point, is its tag and one node.
    let total = count_line(lx, "the number of elements", 8)?;
    let mut seen = HashSet::new();
    let mut read = 0;
    while read < total {
        let at = lx.pos;
        let ty = lx.b_uint(4, "an element type")?;
        let follow = lx.b_uint(4, "the number of elements that follow")?;
        let ntags = lx.b_uint(4, "the number of tags")? as usize;
        if follow == 0 || follow > (total - read) as u64 {
            return Err(format!(
                "byte {at}: an element header says {follow} elements follow; expected 1 to the {} left of the {total} in $Elements",
                total - read
            ));
        }
        let Some((dim, nn)) = elem_type(ty) else {
            let what = format!("element {} has", lx.b_uint(4, "an element tag")?);
            return Err(unsupported_type(Loc::Byte(at + 12), &what, ty));
        };
        let item = 4usize.saturating_mul((1 + nn).saturating_add(ntags));
        let follow = lx.room(
            follow,
            item,
            "the number of elements that follow",
            Loc::Byte(at + 4),
        )?;
        for _ in 0..follow {
            let loc = lx.here();
            let etag = lx.b_uint(4, "an element tag")?;
            new_elem(&mut seen, etag, loc)?;
            let mut physical = 0;
            for k in 0..ntags {
                let v = lx.b_int("an element tag value")?;
                if k == 0 {
                    physical = v.abs();
                }
            }
            if physical != 0 {
                raw.entity_phys.insert((dim, physical), vec![physical]);
            }
            let start = raw.conn.len();
            for _ in 0..nn {
                let l = lx.here();
                let ntag = lx.b_uint(4, "a node tag")?;
                raw.conn
                    .push(node_of(node_index, etag, ntag, l, seen_nodes)?);
            }
            raw.elems.push(RawElem {
                dim,
                entity: physical,
                tag: etag,
                loc,
                nn,
                at: start,
            });
        }
        read += follow;
    }
    Ok(())
}

/// The ASCII count line that opens a binary MSH 2.2 section, as a count of items of at
/// least `item` bytes that the rest of the file can hold.
pub(super) fn count_line(lx: &mut Lexer, what: &str, item: usize) -> Result<usize, String> {
    let (t, at) = lx.tok(what)?;
    let n: u64 = t
        .parse()
        .map_err(|_| format!("{at}: expected {what} (a non-negative integer), found \"{t}\""))?;
    lx.line_end()?;
    lx.room(n, item, what, at)
}
