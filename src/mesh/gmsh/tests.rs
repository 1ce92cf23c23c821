use super::*;

const HEXES: &str = r#"$MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
3
0 3 "corner"
2 1 "bottom face"
3 2 "solid"
$EndPhysicalNames
$Comments
anything "quoted" here
$EndComments
$Entities
1 0 1 1
1 0 0 0 1 3
1 0 0 0 2 1 0 1 1 0
1 0 0 0 2 1 1 1 2 1 -1
$EndEntities
$Nodes
2 12 10 43
0 1 0 1
10
0 0 0
3 1 0 11
13
16
19
22
25
28
31
34
37
40
43
1.0e+00 0 0
2E0 0 0
0 1 0
1 1 0
2 1 0
0 0 1
1 0 1
2 0 1
0 1 1
1 1 1
2 1 1
$EndNodes
$Elements
3 5 1 5
0 1 15 1
1 10
2 1 3 2
2 10 19 22 13
3 13 22 25 16
3 1 5 2
4 10 13 22 19 28 31 40 37
5 13 16 25 22 31 34 43 40
$EndElements
"#;

const TETS: &str = r#"$MeshFormat
4.1 0 8
$EndMeshFormat
$Entities
0 0 2 1
1 0 0 0 1 1 0 1 7 0
2 0 0 0 1 1 1 1 8 0
3 0 0 0 1 1 1 1 9 0
$EndEntities
$Nodes
1 5 1 5
3 3 0 5
1
2
3
4
5
0 0 0
1 0 0
0 1 0
0 0 1
1 1 1
$EndNodes
$Elements
3 4 1 4
2 1 2 1
1 1 2 3
2 2 2 1
2 4 3 2
3 3 4 2
3 1 2 3 4
4 2 3 4 5
$EndElements
"#;

fn err(text: &str) -> String {
    read_msh(text, 0).expect_err("should fail")
}

#[test]
fn reads_hexes_with_groups() {
    let m = read_msh(HEXES, 3).unwrap();
    assert_eq!(m.n_nodes(), 12);
    assert_eq!(m.n_elems(), 2);
    assert_eq!(m.kinds, vec![ElemKind::Hex8; 2]);
    assert_eq!(m.elem_part, vec![3, 3]);
    assert_eq!(m.coords[0], [0.0; 3]);
    assert_eq!(m.coords[1], [1.0, 0.0, 0.0]);
    assert_eq!(m.coords[2], [2.0, 0.0, 0.0]);
    assert_eq!(m.elem_nodes(0), &[0, 1, 4, 3, 6, 7, 10, 9]);
    assert!((m.elem_volume(1) - 1.0).abs() < 1e-12);
    assert_eq!(m.elem_groups["solid"], vec![0, 1]);
    assert_eq!(m.node_groups["solid"], (0..12).collect::<Vec<_>>());
    assert_eq!(m.node_groups["corner"], vec![0]);
    assert_eq!(m.node_groups["bottom face"], vec![0, 1, 2, 3, 4, 5]);
    assert_eq!(
        m.face_groups["bottom face"],
        vec![FaceRef { elem: 0, face: 0 }, FaceRef { elem: 1, face: 0 }]
    );
    assert_eq!(m.face_groups.len(), 1);
    assert_eq!(m.elem_groups.len(), 1);
}

#[test]
fn reads_tets_with_unnamed_and_interior_surfaces() {
    let m = read_msh(TETS, 0).unwrap();
    assert_eq!(m.kinds, vec![ElemKind::Tet4; 2]);
    assert!(m.elem_volume(0) > 0.0 && m.elem_volume(1) > 0.0);
    let f = m.face_groups["group7"][0];
    let mut ns = m.face_nodes(f);
    ns.sort();
    assert_eq!((f.elem, ns), (0, vec![0, 1, 2]));
    assert_eq!(m.face_groups["group8"].len(), 1);
    assert_eq!(m.node_groups["group8"], vec![1, 2, 3]);
    assert_eq!(m.elem_groups["group9"], vec![0, 1]);
}

/// One tet10 (Gmsh node order, tags shuffled) with a tri6 physical surface on its
/// face 0-2-1 and a line3 physical curve.
const TET10: &str = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n3\n1 3 \"edge\"\n2 1 \"base\"\n3 2 \"body\"\n$EndPhysicalNames\n$Entities\n0 1 1 1\n1 0 0 0 1 0 0 1 3 0\n1 0 0 0 1 1 0 1 1 0\n1 0 0 0 1 1 1 1 2 0\n$EndEntities\n$Nodes\n1 10 1 10\n3 1 0 10\n1\n2\n3\n4\n5\n6\n7\n8\n9\n10\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n0.5 0 0\n0.5 0.5 0\n0 0.5 0\n0 0 0.5\n0 0.5 0.5\n0.5 0 0.5\n$EndNodes\n$Elements\n3 3 1 3\n1 1 8 1\n1 1 2 5\n2 1 9 1\n2 1 3 2 7 6 5\n3 1 11 1\n3 1 2 3 4 5 6 7 8 9 10\n$EndElements\n";

#[test]
fn reads_tet10_with_tri6_faces() {
    let m = read_msh(TET10, 0).unwrap();
    assert_eq!(m.kinds, vec![ElemKind::Tet10]);
    assert_eq!(m.elem_nodes(0), &[0, 1, 2, 3, 4, 5, 6, 7, 8, 9]);
    assert!((m.elem_volume(0) - 1.0 / 6.0).abs() < 1e-15);
    assert_eq!(m.face_groups["base"], vec![FaceRef { elem: 0, face: 0 }]);
    assert_eq!(
        m.face_nodes(m.face_groups["base"][0]),
        vec![0, 2, 1, 6, 5, 4]
    );
    assert_eq!(m.node_groups["edge"], vec![0, 1, 4]);
    assert_eq!(m.node_groups["body"].len(), 10);
    // Every face's midside nodes sit at the midpoints of its corners.
    for f in 0..4 {
        let ns = m.face_nodes(FaceRef { elem: 0, face: f });
        for k in 0..3 {
            let (a, b) = (m.coords[ns[k]], m.coords[ns[(k + 1) % 3]]);
            let mid = m.coords[ns[3 + k]];
            assert!((0..3).all(|c| (0.5 * (a[c] + b[c]) - mid[c]).abs() < 1e-15));
        }
    }
    assert_eq!(m.boundary_faces().len(), 4);
}

#[test]
fn reads_a_quad_surface_for_a_sheet() {
    let quads = HEXES
        .replace("$Elements\n3 5 1 5\n", "$Elements\n2 3 1 3\n")
        .replace(
            "3 1 5 2\n4 10 13 22 19 28 31 40 37\n5 13 16 25 22 31 34 43 40\n",
            "",
        );
    let s = read_surface(&quads).unwrap();
    assert_eq!(s.quads, vec![[0, 3, 4, 1], [1, 4, 5, 2]]);
    assert_eq!(s.quad_lines, vec![(53, 2), (54, 3)]);
    assert_eq!(s.quad_groups["bottom face"], vec![0, 1]);
    assert_eq!(s.point_groups["corner"], vec![0]);
    let e = read_msh(&quads, 0).unwrap_err();
    assert!(e.contains("read by kind = \"sheet\""), "{e}");
    let e = read_surface(HEXES).unwrap_err();
    assert!(e.contains("element 4 is a volume element"), "{e}");
    // Triangles are facets of a sheet too (they become wedges); tri6 is refused.
    let tris = read_surface(
        &quads
            .replace("2 1 3 2", "2 1 2 2")
            .replace("2 10 19 22 13", "2 10 19 22")
            .replace("3 13 22 25 16", "3 13 22 25"),
    )
    .unwrap();
    assert_eq!(tris.quads, vec![vec![0, 3, 4], vec![1, 4, 5]]);
    let e = read_surface(
        &quads
            .replace("2 1 3 2", "2 1 9 2")
            .replace("2 10 19 22 13", "2 10 19 22 13 16 25")
            .replace("3 13 22 25 16", "3 13 22 25 16 10 19"),
    )
    .unwrap_err();
    assert!(
        e.contains("element 2 is a surface element of 6 nodes"),
        "{e}"
    );
}

/// MSH 2.2 (Gmsh's legacy format, still what many tools write): a hex under a
/// physical volume, its bottom quad a physical surface, an unnamed physical curve.
#[test]
fn reads_msh_2_2() {
    let text = "$MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
2
2 1 \"bottom face\"
3 2 \"solid\"
$EndPhysicalNames
$Nodes
8
1 0 0 0
2 1 0 0
3 1 1 0
4 0 1 0
5 0 0 1
6 1 0 1
7 1 1 1
8 0 1 1
$EndNodes
$Elements
3
1 1 2 7 3 1 2
2 3 2 1 1 1 4 3 2
3 5 2 2 1 1 2 3 4 5 6 7 8
$EndElements
";
    let m = read_msh(text, 0).unwrap();
    assert_eq!((m.n_nodes(), m.n_elems()), (8, 1));
    assert_eq!(m.elem_groups["solid"], vec![0]);
    assert_eq!(m.face_groups["bottom face"].len(), 1);
    assert_eq!(m.node_groups["group7"], vec![0, 1]);
    let bad = text.replace("3 5 2 2 1 1 2 3 4 5 6 7 8", "3 5 2 2 1 1 2 3 4 5 6 7 9");
    let e = read_msh(&bad, 0).unwrap_err();
    assert!(
        e.contains("line 24: element 3 has node tag 9 that is not in $Nodes"),
        "{e}"
    );
}

#[test]
fn refuses_other_formats() {
    let e = err(&HEXES.replace("$Elements\n3 5 1 5", "$Elements\n3 4000000000000 1 5"));
    assert!(
        e.contains("4000000000000 is larger than the file could hold"),
        "{e}"
    );
    let e = err(&HEXES.replace("$Elements\n3 5 1 5", "$Elements\n3 6 1 5"));
    assert!(
        e.contains("$Elements says 6 elements, its blocks hold 5"),
        "{e}"
    );
    let e = err(&HEXES.replace("5 13 16 25 22 31 34 43 40", "4 13 16 25 22 31 34 43 40"));
    assert!(
        e.contains("element tag 4 appears twice in $Elements"),
        "{e}"
    );
    let e = err(&HEXES.replace("4.1 0 8", "3.0 0 8"));
    assert!(
        e.contains("line 2: MSH version 3.0 is not supported"),
        "{e}"
    );
    let e = err(&HEXES.replace("4.1 0 8", "4.1 1 8"));
    assert!(
        e.contains("line 2: binary .msh files are not supported"),
        "{e}"
    );
    let e = err("$Nodes\n");
    assert!(e.contains("not a Gmsh .msh file"), "{e}");
}

#[test]
fn malformed_files_name_the_problem() {
    let e = err(&HEXES.replace("$EndNodes\n", ""));
    assert!(e.contains("expected $EndNodes, found \"$Elements\""), "{e}");
    let e = err(&HEXES.replace("2E0 0 0", "2E0 0 0.0.1"));
    assert!(
        e.contains("line 37: expected a node coordinate (a finite number), found \"0.0.1\""),
        "{e}"
    );
    let e = err(&HEXES.replace("5 13 16 25", "5 13 99 25"));
    assert!(
        e.contains("element 5 has node tag 99 that is not in $Nodes"),
        "{e}"
    );
    let e = err(&HEXES.replace("3 1 5 2", "3 1 12 2"));
    assert!(
        e.contains("element 4 has type 12 (hex27), which alfe does not read"),
        "{e}"
    );
    let e = err(&HEXES.replace("3 1 5 2", "3 1 7 2"));
    assert!(e.contains("type 7 (pyramid5)"), "{e}");
    let e = err(&HEXES.replace("3 13 22 25 16", "3 13 22 40 16"));
    assert!(
        e.contains("element 3 of physical surface \"bottom face\" is not a face"),
        "{e}"
    );
    let e = err(&TETS.replace("3 1 2 3 4", "3 1 3 2 4"));
    assert!(
        e.contains("element 3 (tet4) has zero or negative volume"),
        "{e}"
    );
    let e = err(&HEXES[..HEXES.find("$EndElements").unwrap()]);
    assert!(e.contains("end of file: expected $EndElements"), "{e}");
    let e = err(&HEXES[..HEXES.find("31 34 43 40").unwrap()]);
    assert!(
        e.contains("end of file inside $Elements: expected a node tag"),
        "{e}"
    );
    let e = err(&TETS.replace("3 3 0 5", "3 3 0 x5"));
    assert!(
        e.contains(
            "expected the number of nodes in the block (a non-negative integer), found \"x5\""
        ),
        "{e}"
    );
    for e in [
        err(&HEXES.replace("3 1 5 2", "3 1 2 2")),
        err(&HEXES.replace(
            "$Elements\n3 5 1 5\n",
            "$Elements\n0 0 0 0\n$EndElements\n$Foo\n",
        )),
    ] {
        assert!(!e.contains('\n'), "one line: {e}");
    }
}

/// A binary .msh file written field by field: little- or big-endian, with a size_t of
/// `sz` bytes (the data size in its `$MeshFormat` line).
struct Bin {
    out: Vec<u8>,
    big: bool,
    sz: usize,
}

impl Bin {
    fn new(version: &str, big: bool, sz: usize) -> Bin {
        let mut b = Bin {
            out: Vec::new(),
            big,
            sz,
        };
        b.text(&format!("$MeshFormat\n{version} 1 {sz}\n"))
            .int(1)
            .text("\n$EndMeshFormat\n");
        b
    }
    fn text(&mut self, s: &str) -> &mut Self {
        self.out.extend_from_slice(s.as_bytes());
        self
    }
    fn uint(&mut self, v: u64, width: usize) -> &mut Self {
        let le = v.to_le_bytes();
        if self.big {
            self.out.extend(le[..width].iter().rev());
        } else {
            self.out.extend_from_slice(&le[..width]);
        }
        self
    }
    fn int(&mut self, v: i32) -> &mut Self {
        self.uint(v as u32 as u64, 4)
    }
    fn ints(&mut self, vs: &[i32]) -> &mut Self {
        for &v in vs {
            self.int(v);
        }
        self
    }
    fn sizes(&mut self, vs: &[u64]) -> &mut Self {
        for &v in vs {
            self.uint(v, self.sz);
        }
        self
    }
    fn reals(&mut self, vs: &[f64]) -> &mut Self {
        for &v in vs {
            self.uint(v.to_bits(), 8);
        }
        self
    }
}

/// [`HEXES`] by hand as binary MSH 4.1 (its physical names and comments stay ASCII);
/// without its hex block, the two quads alone (a sheet's surface).
fn hexes_binary(big: bool, sz: usize, hexes: bool) -> Vec<u8> {
    let mut b = Bin::new("4.1", big, sz);
    b.text("$PhysicalNames\n3\n0 3 \"corner\"\n2 1 \"bottom face\"\n3 2 \"solid\"\n")
        .text("$EndPhysicalNames\n$Comments\nanything \"quoted\" here\n$EndComments\n");
    // Point 1 in physical 3; surface 1 in physical 1; volume 1 in physical 2,
    // bounded by surface -1.
    b.text("$Entities\n").sizes(&[1, 0, 1, 1]);
    b.int(1).reals(&[0.0; 3]).sizes(&[1]).int(3);
    b.int(1).reals(&[0., 0., 0., 2., 1., 0.]).sizes(&[1]).int(1);
    b.sizes(&[0]);
    b.int(1).reals(&[0., 0., 0., 2., 1., 1.]).sizes(&[1]).int(2);
    b.sizes(&[1]).int(-1);
    b.text("\n$EndEntities\n$Nodes\n").sizes(&[2, 12, 10, 43]);
    b.ints(&[0, 1, 0]).sizes(&[1, 10]).reals(&[0.0; 3]);
    b.ints(&[3, 1, 0]).sizes(&[11]);
    b.sizes(&(13..=43).step_by(3).collect::<Vec<u64>>());
    for z in 0..2 {
        for y in 0..2 {
            for x in 0..3 {
                if (x, y, z) != (0, 0, 0) {
                    b.reals(&[x as f64, y as f64, z as f64]);
                }
            }
        }
    }
    let (blocks, n) = if hexes { (3, 5) } else { (2, 3) };
    b.text("\n$EndNodes\n$Elements\n").sizes(&[blocks, n, 1, n]);
    b.ints(&[0, 1, 15]).sizes(&[1, 1, 10]);
    b.ints(&[2, 1, 3])
        .sizes(&[2, 2, 10, 19, 22, 13, 3, 13, 22, 25, 16]);
    if hexes {
        b.ints(&[3, 1, 5])
            .sizes(&[2, 4, 10, 13, 22, 19, 28, 31, 40, 37]);
        b.sizes(&[5, 13, 16, 25, 22, 31, 34, 43, 40]);
    }
    b.text("\n$EndElements\n");
    b.out
}

fn assert_same_mesh(a: &Mesh, b: &Mesh) {
    assert_eq!(a.coords, b.coords);
    assert_eq!(a.kinds, b.kinds);
    assert_eq!(a.offsets, b.offsets);
    assert_eq!(a.conn, b.conn);
    assert_eq!(a.elem_part, b.elem_part);
    assert_eq!(a.node_groups, b.node_groups);
    assert_eq!(a.face_groups, b.face_groups);
    assert_eq!(a.elem_groups, b.elem_groups);
}

/// Binary MSH 4.1 gives the mesh of its ASCII twin, in either byte order and with a
/// 4-byte size_t (a 32-bit Gmsh); the byte entry point reads ASCII as the text one.
#[test]
fn reads_binary_msh_4_1_like_ascii() {
    let ascii = read_msh(HEXES, 3).unwrap();
    assert_same_mesh(&read_msh_bytes(HEXES.as_bytes(), 3).unwrap(), &ascii);
    for (big, sz) in [(false, 8), (true, 8), (false, 4)] {
        let m = read_msh_bytes(&hexes_binary(big, sz, true), 3)
            .unwrap_or_else(|e| panic!("big endian {big}, size_t {sz}: {e}"));
        assert_same_mesh(&m, &ascii);
    }
    let quads = HEXES
        .replace("$Elements\n3 5 1 5\n", "$Elements\n2 3 1 3\n")
        .replace(
            "3 1 5 2\n4 10 13 22 19 28 31 40 37\n5 13 16 25 22 31 34 43 40\n",
            "",
        );
    let (a, b) = (
        read_surface(&quads).unwrap(),
        read_surface_bytes(&hexes_binary(false, 8, false)).unwrap(),
    );
    assert_eq!((&b.coords, &b.quads), (&a.coords, &a.quads));
    assert_eq!(b.quad_groups, a.quad_groups);
    assert_eq!(b.point_groups, a.point_groups);
    // Binary facets have no line: 0, as `mesh::sheet` takes an unknown one.
    assert_eq!(b.quad_lines, vec![(0, 2), (0, 3)]);
    let e = read_surface_bytes(&hexes_binary(false, 8, true)).unwrap_err();
    assert!(
        e.starts_with("byte ") && e.contains("element 4 is a volume element"),
        "{e}"
    );
}

/// A binary file cut anywhere (before its last newline) is refused, and one with any
/// byte overwritten is read or refused, never a panic or a huge allocation.
#[test]
fn truncated_or_garbled_binary_is_an_error() {
    let bin = hexes_binary(false, 8, true);
    for k in 0..bin.len() - 1 {
        let e = read_msh_bytes(&bin[..k], 0).expect_err("a truncated file");
        assert!(!e.contains('\n'), "one line: {e}");
    }
    for i in 0..bin.len() {
        for v in [0x00, 0x7f, 0xff] {
            let mut b = bin.clone();
            b[i] = v;
            let _ = read_msh_bytes(&b, 0);
        }
    }
    // Cut inside a block: its count is more than the rest of the file holds.
    let e = read_msh_bytes(&bin[..find(&bin, b"\n$EndNodes") - 5], 0).unwrap_err();
    assert!(
        e.ends_with("the number of nodes in the block 11 is more than the 347 bytes left in the file could hold (a cut-short or garbled file)"),
        "{e}"
    );
    // Cut inside a field: the section, the field and its byte offset.
    let mut b = Bin::new("4.1", false, 8);
    b.text("$Entities\n").sizes(&[0, 0, 0]).int(0);
    let e = read_msh_bytes(&b.out, 0).unwrap_err();
    let want = "end of file inside $Entities: expected the number of volumes (8 bytes, 4 left)";
    assert_eq!(e, format!("byte {}: {want}", b.out.len() - 4));
}

fn find(data: &[u8], pattern: &[u8]) -> usize {
    data.windows(pattern.len())
        .position(|w| w == pattern)
        .expect("pattern in file")
}

/// Binary refusals name the byte offset of the field and what was expected.
#[test]
fn binary_refusals_name_the_byte() {
    let bin = hexes_binary(false, 8, true);
    let nodes = find(&bin, b"$Nodes\n") + 7;
    // Node count (the second size_t of $Nodes) garbled to 2^56.
    let mut b = bin.clone();
    b[nodes + 15] = 1;
    let e = read_msh_bytes(&b, 0).unwrap_err();
    assert!(
        e.starts_with(&format!(
            "byte {}: the number of nodes 72057594037927948 is more than the",
            nodes + 8
        )),
        "{e}"
    );
    // The last node tag of the second hex, 40, made 99.
    let at = bin.len() - "\n$EndElements\n".len() - 8;
    let mut b = bin.clone();
    b[at] = 99;
    let e = read_msh_bytes(&b, 0).unwrap_err();
    assert_eq!(
        e,
        format!("byte {at}: element 5 has node tag 99 that is not in $Nodes")
    );
    // The hex block's type made 12 (hex27): named with its first element.
    let block = find(&bin, &[3, 0, 0, 0, 1, 0, 0, 0, 5, 0, 0, 0]);
    let mut b = bin.clone();
    b[block + 8] = 12;
    let e = read_msh_bytes(&b, 0).unwrap_err();
    assert!(
        e.starts_with(&format!(
            "byte {}: element 4 has type 12 (hex27), which alfe does not read",
            block + 20
        )),
        "{e}"
    );
    let mut b = bin.clone();
    let one = find(&b, &[1, 0, 0, 0]);
    b[one] = 2;
    let e = read_msh_bytes(&b, 0).unwrap_err();
    assert!(
        e.starts_with(&format!("byte {one}: expected the int 1 that gives")),
        "{e}"
    );
    let e = read_msh_bytes(b"$MeshFormat\n4.1 1 2\n", 0).unwrap_err();
    assert!(
        e.contains("line 2: data size 2 is not supported in a binary MSH 4.1 file"),
        "{e}"
    );
    let e = read_msh_bytes(b"$MeshFormat\n4.1 3 8\n", 0).unwrap_err();
    assert!(
        e.contains("line 2: expected the file type 0 (ASCII) or 1 (binary), found \"3\""),
        "{e}"
    );
    let e = read_msh_bytes(b"\x89PNG\r\n\x1a\n\0\0", 0).unwrap_err();
    assert!(
        e.contains("line 1: not a Gmsh .msh file: expected $MeshFormat, found \"(binary data)\""),
        "{e}"
    );
    // Text cannot hold binary blocks: the text entry point refuses them.
    let e = read_msh(&String::from_utf8_lossy(&bin), 0).unwrap_err();
    assert!(
        e.contains("line 2: binary .msh files are not supported when reading text"),
        "{e}"
    );
}

/// The MSH 2.2 file of [`reads_msh_2_2`] as binary: ASCII count lines, int tags, and
/// elements in groups under one (type, count, number of tags) header each.
fn msh22_binary() -> Vec<u8> {
    let mut b = Bin::new("2.2", false, 8);
    b.text("$PhysicalNames\n2\n2 1 \"bottom face\"\n3 2 \"solid\"\n$EndPhysicalNames\n");
    b.text("$Nodes\n8\n");
    for (i, x) in [
        [0, 0, 0],
        [1, 0, 0],
        [1, 1, 0],
        [0, 1, 0],
        [0, 0, 1],
        [1, 0, 1],
        [1, 1, 1],
        [0, 1, 1],
    ]
    .iter()
    .enumerate()
    {
        b.int(i as i32 + 1).reals(&x.map(f64::from));
    }
    b.text("\n$EndNodes\n$Elements\n3\n");
    b.ints(&[1, 1, 2, 1, 7, 3, 1, 2]);
    b.ints(&[3, 1, 2, 2, 1, 1, 1, 4, 3, 2]);
    b.ints(&[5, 1, 2, 3, 2, 1, 1, 2, 3, 4, 5, 6, 7, 8]);
    b.text("\n$EndElements\n");
    b.out
}

/// Binary MSH 2.2 reads as its ASCII twin; truncation and bad headers are refused.
#[test]
fn reads_binary_msh_2_2() {
    let text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n2 1 \"bottom face\"\n3 2 \"solid\"\n$EndPhysicalNames\n$Nodes\n8\n1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n5 0 0 1\n6 1 0 1\n7 1 1 1\n8 0 1 1\n$EndNodes\n$Elements\n3\n1 1 2 7 3 1 2\n2 3 2 1 1 1 4 3 2\n3 5 2 2 1 1 2 3 4 5 6 7 8\n$EndElements\n";
    let bin = msh22_binary();
    assert_same_mesh(
        &read_msh_bytes(&bin, 0).unwrap(),
        &read_msh(text, 0).unwrap(),
    );
    for k in 0..bin.len() - 1 {
        read_msh_bytes(&bin[..k], 0).expect_err("a truncated file");
    }
    for i in 0..bin.len() {
        let mut b = bin.clone();
        b[i] ^= 0xff;
        let _ = read_msh_bytes(&b, 0);
    }
    // The first header says 4 elements follow, of 3 in all.
    let header = find(&bin, b"$Elements\n3\n") + 12;
    let mut b = bin.clone();
    b[header + 4] = 4;
    let e = read_msh_bytes(&b, 0).unwrap_err();
    assert!(
        e.starts_with(&format!(
            "byte {header}: an element header says 4 elements follow; expected 1 to the 3 left"
        )),
        "{e}"
    );
    let e = read_msh_bytes(b"$MeshFormat\n2.2 1 4\n", 0).unwrap_err();
    assert!(
        e.contains("data size 4 is not supported in a binary MSH 2.2 file"),
        "{e}"
    );
}
