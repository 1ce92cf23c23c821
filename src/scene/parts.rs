//! `[[materials]]` and `[[parts]]`: each part's material, element formulation and mesh
//! (generated, or read from a file), placed and checked element by element.

use super::check::err;
use super::deck::*;
use super::formulation::{fit_to_elements, part_formulation_of};
use crate::fem::element::Formulation;
use crate::fem::measure::check_reference;
use crate::material::Hardening;
use crate::mesh::cylinder::{cylinder_mesh, ring_mesh, CylinderSpec, RingSpec};
use crate::mesh::generate::{box_mesh, distort_interior, BoxSpec};
use crate::mesh::quadratic::tet4_to_tet10;
use crate::mesh::{gmsh, ElemKind, Mesh};
use crate::model::def::*;
use crate::Result;
use std::collections::BTreeSet;
use std::path::Path;

/// The parts' meshes appended into one, with each part's material, formulation and nodes.
pub(super) struct Parts {
    pub mesh: Mesh,
    /// Index into the materials, per part.
    pub material: Vec<usize>,
    pub formulation: Vec<Formulation>,
    /// The nodes of each part in the appended mesh.
    pub nodes: Vec<BTreeSet<usize>>,
    /// Per part, for `alfe check`: its element types and the formulation each gets
    /// (`block: 5128 tet4, standard (locks: nu = 0.4995 > 0.45)`).
    pub descriptions: Vec<String>,
    /// Choices known to lock, one line each (`alfe check`, and the log of `alfe run`).
    pub warnings: Vec<String>,
}

/// Every `[[materials]]` entry checked and resolved, in deck order.
pub(super) fn materials(deck: &Deck) -> Result<Vec<(String, MaterialDef)>> {
    let mut materials = Vec::new();
    for (i, m) in deck.materials.iter().enumerate() {
        materials.push((
            m.name.clone(),
            material_def(m, &format!("materials[{i}]"), deck)?,
        ));
    }
    Ok(materials)
}

/// Every `[[parts]]` entry: its material, formulation and mesh, placed, every element
/// valid in the reference configuration; the meshes appended in deck order.
pub(super) fn parts(
    deck: &Deck,
    materials: &[(String, MaterialDef)],
    deck_dir: &Path,
) -> Result<Parts> {
    if deck.parts.is_empty() {
        return Err(err("parts", "expected at least one [[parts]] entry"));
    }
    let mut out = Parts {
        mesh: Mesh::default(),
        material: Vec::new(),
        formulation: Vec::new(),
        nodes: Vec::new(),
        descriptions: Vec::new(),
        warnings: Vec::new(),
    };
    for (pi, p) in deck.parts.iter().enumerate() {
        let f = format!("parts[{pi}]");
        let Some(mi) = materials.iter().position(|(n, _)| *n == p.material) else {
            let names: Vec<&str> = materials.iter().map(|(n, _)| n.as_str()).collect();
            return Err(err(
                format!("{f}.material"),
                format!(
                    "unknown material `{}` (defined: {})",
                    p.material,
                    if names.is_empty() {
                        "none".into()
                    } else {
                        names.join(", ")
                    }
                ),
            ));
        };
        out.material.push(mi);
        let explicit = deck.analysis.kind == AnalysisKind::Explicit;
        let form = part_formulation_of(p, &materials[mi].1, &f, explicit)?;
        let mut pm = part_mesh(&p.mesh, &f, pi as u32, deck_dir)?;
        place(&mut pm, p, &f)?;
        check_elements(&pm, &f, &p.name)?;
        let fit = fit_to_elements(p, &f, form, &pm, &materials[mi].1, explicit)?;
        out.formulation.push(fit.formulation);
        out.descriptions.push(fit.description);
        out.warnings.extend(fit.warnings);
        let n0 = out.mesh.n_nodes();
        out.nodes.push((n0..n0 + pm.n_nodes()).collect());
        out.mesh.append(&pm);
    }
    Ok(out)
}

/// Reference-configuration validity of every element of a part's mesh.
fn check_elements(pm: &Mesh, f: &str, name: &str) -> Result<()> {
    for e in 0..pm.n_elems() {
        let x0: Vec<[f64; 3]> = pm.elem_nodes(e).iter().map(|&n| pm.coords[n]).collect();
        if let Err(why) = check_reference(pm.kinds[e], &x0) {
            return Err(err(
                format!("{f} `{name}`"),
                format!(
                    "element {e} ({}) is inverted or degenerate: {why}",
                    pm.kinds[e].name()
                ),
            ));
        }
    }
    Ok(())
}

/// The most elements a generated part may have (2e7: tens of GB before solving).
const MAX_ELEMENTS: f64 = 2e7;

/// Refuse a generated mesh of more than [`MAX_ELEMENTS`] before allocating it.
fn size_guard(field: &str, elements: f64) -> Result<()> {
    if elements > MAX_ELEMENTS {
        return Err(err(
            field,
            format!("makes {elements:.3e} elements; expected at most {MAX_ELEMENTS:.0e}"),
        ));
    }
    Ok(())
}

/// Rotate (Rodrigues) and translate a part's mesh as its deck says.
fn place(mesh: &mut Mesh, p: &PartDeck, f: &str) -> Result<()> {
    if let Some(r) = &p.rotate {
        let n = (r.axis.iter().map(|a| a * a).sum::<f64>()).sqrt();
        if !(n > 0.0 && n.is_finite()) {
            return Err(err(
                format!("{f}.rotate.axis"),
                format!("expected a non-zero finite vector, got {:?}", r.axis),
            ));
        }
        if !r.angle.is_finite() {
            return Err(err(
                format!("{f}.rotate.angle"),
                format!("expected a finite angle in degrees, got {}", r.angle),
            ));
        }
        let k = r.axis.map(|a| a / n);
        let (s, c) = r.angle.to_radians().sin_cos();
        for x in mesh.coords.iter_mut() {
            let kx = [
                k[1] * x[2] - k[2] * x[1],
                k[2] * x[0] - k[0] * x[2],
                k[0] * x[1] - k[1] * x[0],
            ];
            let kd = k[0] * x[0] + k[1] * x[1] + k[2] * x[2];
            *x = [0, 1, 2].map(|i| x[i] * c + kx[i] * s + k[i] * kd * (1.0 - c));
        }
    }
    if let Some(t) = p.translate {
        if t.iter().any(|v| !v.is_finite()) {
            return Err(err(
                format!("{f}.translate"),
                format!("expected a finite vector, got {t:?}"),
            ));
        }
        for x in mesh.coords.iter_mut() {
            *x = [0, 1, 2].map(|i| x[i] + t[i]);
        }
    }
    Ok(())
}

/// A part's mesh as its deck entry says: generated, or read from a file.
fn part_mesh(m: &MeshDeck, f: &str, part: u32, deck_dir: &Path) -> Result<Mesh> {
    match m {
        MeshDeck::Box { .. } => box_part(m, f, part),
        MeshDeck::ExtrudedQuad { .. } => extruded_quad_part(m, f, part),
        MeshDeck::Cylinder { .. } => cylinder_part(m, f, part),
        MeshDeck::Ring { .. } => ring_part(m, f, part),
        MeshDeck::Blocks { .. } => blocks_part(m, f, part),
        MeshDeck::Sheet { .. } => sheet_part(m, f, part, deck_dir),
        MeshDeck::Gmsh { file } => gmsh_part(file, f, part, deck_dir),
        MeshDeck::Abaqus { file, elset } => abaqus_part(file, elset.as_deref(), f, part, deck_dir),
        MeshDeck::LsDyna { file, pid } => lsdyna_part(file, *pid, f, part, deck_dir),
        MeshDeck::File { file } => match extension(file).as_deref() {
            Some("msh") => gmsh_part(file, f, part, deck_dir),
            Some("inp") => abaqus_part(file, None, f, part, deck_dir),
            Some("k" | "key" | "dyn") => lsdyna_part(file, None, f, part, deck_dir),
            _ => Err(err(
                format!("{f}.mesh.file"),
                format!(
                    "`{file}`: kind = \"file\" reads .msh (Gmsh), .inp (Abaqus, CalculiX) \
                         and .k, .key, .dyn (LS-DYNA) by their extension; name the kind \
                         (\"gmsh\", \"abaqus\", \"lsdyna\") for another"
                ),
            )),
        },
    }
}

/// A `Box` part mesh (see [`part_mesh`]).
fn box_part(m: &MeshDeck, f: &str, part: u32) -> Result<Mesh> {
    let MeshDeck::Box {
        origin,
        size,
        cells,
        grading,
        element,
        distort,
    } = m
    else {
        unreachable!("called on Box meshes only")
    };
    if origin.iter().any(|o| !o.is_finite()) {
        return Err(err(
            format!("{f}.mesh.origin"),
            format!("expected three finite coordinates, got {origin:?}"),
        ));
    }
    if size.iter().any(|&s| !(s > 0.0 && s.is_finite())) {
        return Err(err(
            format!("{f}.mesh.size"),
            format!("expected three positive lengths, got {size:?}"),
        ));
    }
    if cells.contains(&0) {
        return Err(err(
            format!("{f}.mesh.cells"),
            format!("expected three counts ≥ 1, got {cells:?}"),
        ));
    }
    size_guard(
        &format!("{f}.mesh.cells"),
        cells.iter().map(|&c| c as f64).product(),
    )?;
    if grading.iter().any(|&g| !(g > 0.0 && g.is_finite())) {
        return Err(err(
            format!("{f}.mesh.grading"),
            format!("expected positive ratios, got {grading:?}"),
        ));
    }
    if !(0.0..=0.3).contains(distort) {
        return Err(err(
            format!("{f}.mesh.distort"),
            format!("expected 0 ≤ distort ≤ 0.3, got {distort}"),
        ));
    }
    let kind = match element {
        ElementDeck::Hex8 => ElemKind::Hex8,
        ElementDeck::Tet4 | ElementDeck::Tet10 => ElemKind::Tet4,
        ElementDeck::Wedge6 => ElemKind::Wedge6,
    };
    let spec = BoxSpec {
        origin: *origin,
        size: *size,
        cells: *cells,
        grading: *grading,
        kind,
    };
    let mut mesh = box_mesh(&spec, part);
    if *distort > 0.0 {
        distort_interior(&mut mesh, *distort, 12345);
    }
    Ok(quadratic_if(*element, mesh))
}

/// A generated tet4 mesh as tet10 where the deck asks for it.
fn quadratic_if(element: ElementDeck, mesh: Mesh) -> Mesh {
    match element {
        ElementDeck::Tet10 => tet4_to_tet10(&mesh),
        _ => mesh,
    }
}

/// A `ExtrudedQuad` part mesh (see [`part_mesh`]).
fn extruded_quad_part(m: &MeshDeck, f: &str, part: u32) -> Result<Mesh> {
    let MeshDeck::ExtrudedQuad {
        corners,
        z0,
        thickness,
        cells,
        element,
    } = m
    else {
        unreachable!("called on ExtrudedQuad meshes only")
    };
    if !(*thickness > 0.0 && thickness.is_finite()) {
        return Err(err(
            format!("{f}.mesh.thickness"),
            format!("expected a positive length, got {thickness}"),
        ));
    }
    if cells.contains(&0) {
        return Err(err(
            format!("{f}.mesh.cells"),
            format!("expected three counts ≥ 1, got {cells:?}"),
        ));
    }
    size_guard(
        &format!("{f}.mesh.cells"),
        cells.iter().map(|&c| c as f64).product(),
    )?;
    // Convex and counter-clockwise: every corner turns left.
    for i in 0..4 {
        let (a, b, c) = (corners[i], corners[(i + 1) % 4], corners[(i + 2) % 4]);
        let cross = (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0]);
        if cross.is_nan() || cross <= 0.0 {
            return Err(err(
                format!("{f}.mesh.corners"),
                "expected a convex quadrilateral, corners counter-clockwise",
            ));
        }
    }
    let kind = match element {
        ElementDeck::Hex8 => ElemKind::Hex8,
        ElementDeck::Tet4 | ElementDeck::Tet10 => ElemKind::Tet4,
        ElementDeck::Wedge6 => ElemKind::Wedge6,
    };
    let spec = BoxSpec {
        origin: [0.0, 0.0, *z0],
        size: [1.0, 1.0, *thickness],
        cells: *cells,
        grading: [1.0; 3],
        kind,
    };
    // Midside nodes before the map, so they follow it.
    let mut mesh = quadratic_if(*element, box_mesh(&spec, part));
    // Bilinear map: corners 0..3 at (ξ, η) = (0,0), (1,0), (1,1), (0,1).
    for x in &mut mesh.coords {
        let (s, t) = (x[0], x[1]);
        let w = [(1.0 - s) * (1.0 - t), s * (1.0 - t), s * t, (1.0 - s) * t];
        x[0] = (0..4).map(|i| w[i] * corners[i][0]).sum();
        x[1] = (0..4).map(|i| w[i] * corners[i][1]).sum();
    }
    Ok(mesh)
}

/// A `Cylinder` part mesh (see [`part_mesh`]).
fn cylinder_part(m: &MeshDeck, f: &str, part: u32) -> Result<Mesh> {
    let MeshDeck::Cylinder {
        radius,
        length,
        z0,
        cells_radial,
        cells_axial,
        axial_grading,
        sector,
    } = m
    else {
        unreachable!("called on Cylinder meshes only")
    };
    let spec = CylinderSpec {
        radius: *radius,
        length: *length,
        z0: *z0,
        cells_radial: *cells_radial,
        cells_axial: *cells_axial,
        axial_grading: *axial_grading,
        quarter: *sector == SectorDeck::Quarter,
    };
    spec.check()
        .map_err(|(field, why)| err(format!("{f}.mesh.{field}"), why))?;
    // The butterfly section has about 3 cells_radial² cells.
    let section = 3.0 * (*cells_radial as f64).powi(2);
    size_guard(&format!("{f}.mesh.cells_radial"), section)?;
    size_guard(
        &format!("{f}.mesh.cells_axial"),
        section * *cells_axial as f64,
    )?;
    Ok(cylinder_mesh(&spec, part))
}

/// A `Ring` part mesh (see [`part_mesh`]).
fn ring_part(m: &MeshDeck, f: &str, part: u32) -> Result<Mesh> {
    let MeshDeck::Ring {
        inner_radius,
        outer_radius,
        thickness,
        z0,
        angles,
        cells,
        center,
    } = m
    else {
        unreachable!("called on Ring meshes only")
    };
    let spec = RingSpec {
        inner_radius: *inner_radius,
        outer_radius: *outer_radius,
        thickness: *thickness,
        z0: *z0,
        angles: *angles,
        cells: *cells,
        center: *center,
    };
    spec.check()
        .map_err(|(field, why)| err(format!("{f}.mesh.{field}"), why))?;
    size_guard(
        &format!("{f}.mesh.cells"),
        cells.iter().map(|&c| c as f64).product(),
    )?;
    Ok(ring_mesh(&spec, part))
}

/// A `Blocks` part mesh (see [`part_mesh`]).
fn blocks_part(m: &MeshDeck, f: &str, part: u32) -> Result<Mesh> {
    let MeshDeck::Blocks {
        solids,
        holes,
        cell_size,
        refine,
    } = m
    else {
        unreachable!("called on Blocks meshes only")
    };
    if solids.is_empty() {
        return Err(err(format!("{f}.mesh.solids"), "expected at least one box"));
    }
    for (what, list) in [("solids", solids), ("holes", holes)] {
        for (i, b) in list.iter().enumerate() {
            if (0..3).any(|a| !(b[0][a] < b[1][a] && b[0][a].is_finite() && b[1][a].is_finite())) {
                return Err(err(
                    format!("{f}.mesh.{what}[{i}]"),
                    format!("expected [[min x, y, z], [max x, y, z]] with min < max, got {b:?}"),
                ));
            }
        }
    }
    if !(*cell_size > 0.0 && cell_size.is_finite()) {
        return Err(err(
            format!("{f}.mesh.cell_size"),
            format!("expected a positive length, got {cell_size}"),
        ));
    }
    for (i, r) in refine.iter().enumerate() {
        if !(r.from < r.to && r.from.is_finite() && r.to.is_finite()) {
            return Err(err(
                format!("{f}.mesh.refine[{i}]"),
                format!(
                    "expected finite from < to, got from = {}, to = {}",
                    r.from, r.to
                ),
            ));
        }
        if !(r.cell_size > 0.0 && r.cell_size.is_finite()) {
            return Err(err(
                format!("{f}.mesh.refine[{i}].cell_size"),
                format!("expected a positive length, got {}", r.cell_size),
            ));
        }
    }
    let spec = crate::mesh::blocks::BlocksSpec {
        solids: solids.clone(),
        holes: holes.clone(),
        cell_size: *cell_size,
        refine: refine
            .iter()
            .map(|r| crate::mesh::blocks::Slab {
                axis: r.axis as usize,
                range: [r.from, r.to],
                cell_size: r.cell_size,
            })
            .collect(),
    };
    let n = crate::mesh::blocks::lattice_cells(&spec);
    if n > MAX_ELEMENTS {
        return Err(err(
            format!("{f}.mesh.cell_size"),
            format!(
                "{cell_size} makes a lattice of {n:.3e} cells; expected at most {MAX_ELEMENTS:.0e}"
            ),
        ));
    }
    let mesh = crate::mesh::blocks::blocks_mesh(&spec, part);
    if mesh.n_elems() == 0 {
        return Err(err(
            format!("{f}.mesh.solids"),
            "no cell lies in a solid and outside every hole",
        ));
    }
    Ok(mesh)
}

/// A `Sheet` part mesh (see [`part_mesh`]).
fn sheet_part(m: &MeshDeck, f: &str, part: u32, deck_dir: &Path) -> Result<Mesh> {
    let MeshDeck::Sheet {
        file,
        thickness,
        layers,
        offset,
    } = m
    else {
        unreachable!("called on Sheet meshes only")
    };
    if !(*thickness > 0.0 && thickness.is_finite()) {
        return Err(err(
            format!("{f}.mesh.thickness"),
            format!("expected a positive length, got {thickness}"),
        ));
    }
    if !(1..=64).contains(layers) {
        return Err(err(
            format!("{f}.mesh.layers"),
            format!("expected 1 to 64 elements through the thickness, got {layers}"),
        ));
    }
    let ext = extension(file);
    let is_k = matches!(ext.as_deref(), Some("k" | "key" | "dyn"));
    let (path, surface) = if ext.as_deref() == Some("inp") {
        // An Abaqus/CalculiX shell mesh: its errors name the file and line themselves.
        let path = deck_dir.join(file);
        let s = crate::mesh::abaqus::read_surface_inp(&path, &read_text)
            .map_err(|e| err(format!("{f}.mesh.file"), e))?;
        (path, s)
    } else if is_k {
        // An LS-DYNA shell mesh: its errors name the file and line themselves.
        let path = deck_dir.join(file);
        let s = crate::mesh::lsdyna::read_surface_k(&path, &read_text)
            .map_err(|e| err(format!("{f}.mesh.file"), e))?;
        (path, s)
    } else {
        let (path, bytes) = read_mesh_file(file, f, deck_dir)?;
        let s = gmsh::read_surface_bytes(&bytes).map_err(|e| {
            err(
                format!("{f}.mesh.file"),
                format!("`{}`: {e}", path.display()),
            )
        })?;
        (path, s)
    };
    let in_file = |e: String| {
        err(
            format!("{f}.mesh.file"),
            format!("`{}`: {e}", path.display()),
        )
    };
    let spec = crate::mesh::sheet::SheetSpec {
        thickness: *thickness,
        layers: *layers,
        offset: match offset {
            SheetOffsetDeck::Middle => crate::mesh::sheet::Offset::Middle,
            SheetOffsetDeck::AlongNormal => crate::mesh::sheet::Offset::AlongNormal,
            SheetOffsetDeck::AgainstNormal => crate::mesh::sheet::Offset::AgainstNormal,
        },
    };
    crate::mesh::sheet::extrude(&surface, &spec, part).map_err(in_file)
}

/// An Abaqus/CalculiX `.inp` part mesh (see [`part_mesh`]); its includes are read
/// relative to the including file.
fn abaqus_part(
    file: &str,
    elset: Option<&str>,
    f: &str,
    part: u32,
    deck_dir: &Path,
) -> Result<Mesh> {
    let path = deck_dir.join(file);
    let mut mesh = crate::mesh::abaqus::read_inp(&path, part, &read_text)
        .map_err(|e| err(format!("{f}.mesh.file"), e))?;
    if let Some(name) = elset {
        crate::mesh::subset::keep_elem_group(&mut mesh, name)
            .map_err(|e| err(format!("{f}.mesh.elset"), format!("`{file}`: {e}")))?;
    }
    compact_unused_nodes(&mut mesh);
    Ok(mesh)
}

/// A mesh file's extension, lower case: what `kind = "file"` and sheets dispatch on.
fn extension(file: &str) -> Option<String> {
    Path::new(file)
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
}

/// The loader of included files for the keyword readers.
fn read_text(p: &Path) -> std::result::Result<String, String> {
    std::fs::read_to_string(p).map_err(|e| format!("cannot read `{}`: {e}", p.display()))
}

/// An LS-DYNA `.k` part mesh (see [`part_mesh`]).
fn lsdyna_part(file: &str, pid: Option<i64>, f: &str, part: u32, deck_dir: &Path) -> Result<Mesh> {
    let mut mesh = crate::mesh::lsdyna::read_k(&deck_dir.join(file), part, pid, &read_text)
        .map_err(|e| err(format!("{f}.mesh.file"), e))?;
    compact_unused_nodes(&mut mesh);
    Ok(mesh)
}

/// A `Gmsh` part mesh (see [`part_mesh`]).
fn gmsh_part(file: &str, f: &str, part: u32, deck_dir: &Path) -> Result<Mesh> {
    let (path, bytes) = read_mesh_file(file, f, deck_dir)?;
    let mut mesh = gmsh::read_msh_bytes(&bytes, part).map_err(|e| {
        err(
            format!("{f}.mesh.file"),
            format!("`{}`: {e}", path.display()),
        )
    })?;
    compact_unused_nodes(&mut mesh);
    if mesh.n_elems() == 0 {
        return Err(err(
            format!("{f}.mesh.file"),
            format!(
                "`{}` has no hex8, tet4, tet10 or wedge6 elements",
                path.display()
            ),
        ));
    }
    Ok(mesh)
}

/// A mesh file's path (relative to the deck's directory) and bytes: a Gmsh file may be
/// binary, which the reader tells from its header.
fn read_mesh_file(file: &str, f: &str, deck_dir: &Path) -> Result<(std::path::PathBuf, Vec<u8>)> {
    let path = if Path::new(file).is_absolute() {
        Path::new(file).to_path_buf()
    } else {
        deck_dir.join(file)
    };
    let bytes = std::fs::read(&path).map_err(|e| {
        err(
            format!("{f}.mesh.file"),
            format!("cannot read `{}`: {e}", path.display()),
        )
    })?;
    Ok((path, bytes))
}

/// Drop nodes that no element uses (geometry points in Gmsh files): they would carry
/// no stiffness and make the system singular.
fn compact_unused_nodes(mesh: &mut Mesh) {
    let mut used = vec![false; mesh.n_nodes()];
    for &n in &mesh.conn {
        used[n] = true;
    }
    if used.iter().all(|&u| u) {
        return;
    }
    let mut map = vec![usize::MAX; used.len()];
    let mut coords = Vec::new();
    for (i, &u) in used.iter().enumerate() {
        if u {
            map[i] = coords.len();
            coords.push(mesh.coords[i]);
        }
    }
    mesh.coords = coords;
    for n in mesh.conn.iter_mut() {
        *n = map[*n];
    }
    for v in mesh.node_groups.values_mut() {
        *v = v
            .iter()
            .filter(|&&n| map[n] != usize::MAX)
            .map(|&n| map[n])
            .collect();
    }
}

/// A material deck entry → its definition, checking the fields its model needs and
/// refusing the ones it does not use.
fn material_def(m: &MaterialDeck, f: &str, deck: &Deck) -> Result<MaterialDef> {
    let model = m.model.name();
    let positive = |name: &str, v: Option<f64>| -> Result<f64> {
        match v {
            None => Err(err(
                format!("{f}.{name}"),
                format!("model `{model}` needs {name}"),
            )),
            Some(v) if v > 0.0 && v.is_finite() => Ok(v),
            Some(v) => Err(err(
                format!("{f}.{name}"),
                format!("expected a positive value, got {v}"),
            )),
        }
    };
    let unused = |name: &str, given: bool| -> Result<()> {
        if given {
            Err(err(
                format!("{f}.{name}"),
                format!("is not a parameter of model `{model}`"),
            ))
        } else {
            Ok(())
        }
    };
    let nu = m.nu;
    if !(nu > -1.0 && nu < 0.5) {
        return Err(err(
            format!("{f}.nu"),
            format!("expected -1 < nu < 0.5, got {nu}"),
        ));
    }
    if !(m.density >= 0.0 && m.density.is_finite()) {
        return Err(err(
            format!("{f}.density"),
            format!("expected ≥ 0, got {}", m.density),
        ));
    }
    let density = m.density;
    let plastic_unused = || -> Result<()> {
        unused("yield_stress", m.yield_stress.is_some())?;
        unused("hardening", m.hardening.is_some())
    };
    Ok(match m.model {
        MaterialModel::LinearElastic | MaterialModel::NeoHookean => {
            let e = positive("E", m.e)?;
            unused("C10", m.c10.is_some())?;
            unused("C01", m.c01.is_some())?;
            plastic_unused()?;
            if m.model == MaterialModel::LinearElastic {
                MaterialDef::LinearElastic { e, nu, density }
            } else {
                MaterialDef::NeoHookean { e, nu, density }
            }
        }
        MaterialModel::MooneyRivlin => {
            unused("E", m.e.is_some())?;
            plastic_unused()?;
            let c10 = m
                .c10
                .ok_or_else(|| err(format!("{f}.C10"), "model `mooney-rivlin` needs C10"))?;
            let c01 = m.c01.unwrap_or(0.0);
            if !(c10.is_finite() && c01.is_finite() && c10 + c01 > 0.0 && c10 >= 0.0 && c01 >= 0.0)
            {
                return Err(err(
                    format!("{f}.C10"),
                    format!(
                        "expected C10 ≥ 0, C01 ≥ 0 and C10 + C01 > 0, got C10 = {c10}, C01 = {c01}"
                    ),
                ));
            }
            MaterialDef::MooneyRivlin {
                c10,
                c01,
                nu,
                density,
            }
        }
        MaterialModel::J2 => {
            let e = positive("E", m.e)?;
            unused("C10", m.c10.is_some())?;
            unused("C01", m.c01.is_some())?;
            let sigma_y0 = positive("yield_stress", m.yield_stress)?;
            let hf = format!("{f}.hardening");
            let hardening = match &m.hardening {
                None => Hardening::Linear { sigma_y0, h: 0.0 },
                Some(HardeningDeck::Linear { modulus }) => Hardening::Linear {
                    sigma_y0,
                    h: *modulus,
                },
                Some(HardeningDeck::Power { k, n }) => Hardening::Power {
                    sigma_y0,
                    k: *k,
                    n: *n,
                },
                Some(HardeningDeck::Table { points, curve }) => {
                    let pts = match (points, curve) {
                        (Some(p), None) => p.clone(),
                        (None, Some(name)) => deck
                            .curves
                            .iter()
                            .find(|c| &c.name == name)
                            .map(|c| c.points.clone())
                            .ok_or_else(|| {
                                err(format!("{hf}.curve"), format!("unknown curve `{name}`"))
                            })?,
                        _ => {
                            return Err(err(
                                &hf,
                                "a table needs exactly one of `points` or `curve`",
                            ))
                        }
                    };
                    if let Some(first) = pts.first() {
                        if (first[1] - sigma_y0).abs() > 1e-12 * sigma_y0 {
                            return Err(err(
                                &hf,
                                format!(
                                    "the table starts at σ_y = {} but yield_stress is {sigma_y0}",
                                    first[1]
                                ),
                            ));
                        }
                    }
                    Hardening::Tabulated { points: pts }
                }
            };
            hardening.validate().map_err(|why| err(&hf, why))?;
            MaterialDef::J2 {
                e,
                nu,
                hardening,
                density,
            }
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A part of 2 × 2 × 2 hex8 and, beside it, 6 × 8 tet4 (as a Gmsh file may mix them).
    fn mixed() -> Mesh {
        let spec = |origin: [f64; 3], kind| BoxSpec {
            origin,
            size: [1.0; 3],
            cells: [2, 2, 2],
            grading: [1.0; 3],
            kind,
        };
        let mut m = box_mesh(&spec([0.0; 3], ElemKind::Hex8), 0);
        m.append(&box_mesh(&spec([2.0, 0.0, 0.0], ElemKind::Tet4), 0));
        m
    }

    fn part(formulation: &str) -> PartDeck {
        toml::from_str(&format!(
            "name = \"b\"\nmaterial = \"m\"\nformulation = \"{formulation}\"\nmesh = {{ kind = \"box\", size = [1, 1, 1], cells = [1, 1, 1] }}"
        ))
        .unwrap()
    }

    /// A mixed hex8/tet4 part: `auto` gives its hex8 auto's choice (hybrid) and its tet4
    /// the hybrid F-bar patch, and says so; `standard` warns on both; a formulation named
    /// in the deck that does not apply to its tet4 is an error naming the share of them.
    #[test]
    fn a_mixed_part_says_what_each_element_type_gets() {
        let rubber = MaterialDef::NeoHookean {
            e: 3.0,
            nu: 0.4995,
            density: 0.0,
        };
        let (m, p) = (mixed(), part("auto"));
        let form = part_formulation_of(&p, &rubber, "parts[0]", false).unwrap();
        let fit = fit_to_elements(&p, "parts[0]", form, &m, &rubber, false).unwrap();
        assert!(fit.formulation.is_hybrid());
        assert_eq!(
            fit.description,
            "b: 8 hex8 hybrid, 48 tet4 hybrid F-bar patch (8 tets share one volume ratio and a pressure unknown)"
        );
        assert!(fit.warnings.is_empty(), "{:?}", fit.warnings);
        let p = part("standard");
        let form = part_formulation_of(&p, &rubber, "parts[0]", false).unwrap();
        let fit = fit_to_elements(&p, "parts[0]", form, &m, &rubber, false).unwrap();
        assert_eq!(fit.warnings.len(), 2, "{:?}", fit.warnings);
        assert!(fit.warnings[1].starts_with("part `b` (parts[0]): 48 tet4 with the standard"));
        let p = part("reduced");
        let form = part_formulation_of(&p, &rubber, "parts[0]", false).unwrap();
        let e = fit_to_elements(&p, "parts[0]", form, &m, &rubber, false)
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.contains("parts[0].formulation: \"reduced\" does not apply to tet4 elements (part `b`: 48 of its 56 elements are tet4)"),
            "{e}"
        );
    }
}
