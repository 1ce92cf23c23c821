//! A part's element formulation: the deck's choice or `auto`'s (from the material, the
//! analysis and whether the part is a sheet), checked against the element types of its
//! mesh (a formulation that does not apply is an error naming the part), described for
//! `alfe check`, and warned when it is known to lock (issue 35).

use super::check::err;
use super::deck::*;
use crate::fem::element::{applies, describe_for, for_kind, Formulation};
use crate::mesh::{ElemKind, Mesh};
use crate::model::def::*;
use crate::Result;

/// A part's element formulation with its hourglass coefficient; `hourglass` is refused
/// where no hourglass spring exists (standard hex8) and must be finite and ≥ 0.
///
/// `auto` takes the hybrid element for nearly incompressible hyperelastic parts in static
/// and implicit analyses (Newton converges there as on compressible solids: rubber-indent
/// newton 412 → 144 iterations, cook-membrane 83 → 16; README "Hybrid elements"), F-bar
/// for them in explicit runs and for plastic parts (J2 gains nothing from the pressure
/// unknown: plastic-bar 113 → 130 iterations), standard hex8 otherwise. A part meshed
/// as a sheet (`kind = "sheet"`, extruded from a surface) takes EAS whatever its material:
/// one or two elements through the thickness must bend (a 60 × 20 × 1 plate, 24 × 8
/// quads, one layer: standard 24 %, F-bar 27 %, reduced 25 % of beam theory, EAS
/// −0.03 %; `tests/element_choices.rs`). Which element types
/// the choice applies to is [`fit_to_elements`]'s business, once the mesh is known.
pub(super) fn part_formulation_of(
    p: &PartDeck,
    material: &MaterialDef,
    field: &str,
    explicit: bool,
) -> Result<Formulation> {
    let form = match p.formulation {
        FormulationDeck::Standard => Formulation::Standard,
        FormulationDeck::Fbar => Formulation::FBAR,
        FormulationDeck::Reduced => Formulation::REDUCED,
        FormulationDeck::Eas => Formulation::Eas,
        FormulationDeck::Hybrid => {
            if !material.has_volumetric_split() {
                return Err(err(
                    format!("{field}.formulation"),
                    "the hybrid element needs a finite-strain material with a volumetric \
                     part (neo-hookean, mooney-rivlin, j2); this part's is linear-elastic",
                ));
            }
            if explicit {
                return Err(err(
                    format!("{field}.formulation"),
                    "the hybrid element's pressure unknowns need a static or implicit \
                     analysis; an explicit run takes formulation = \"fbar\"",
                ));
            }
            Formulation::Hybrid { hourglass: 0.0 }
        }
        FormulationDeck::Auto if is_sheet(p) => Formulation::Eas,
        FormulationDeck::Auto if material.wants_hybrid() && !explicit => {
            Formulation::Hybrid { hourglass: 0.0 }
        }
        FormulationDeck::Auto if material.wants_fbar() => Formulation::FBAR,
        FormulationDeck::Auto => Formulation::Standard,
    };
    let Some(h) = p.hourglass else {
        return Ok(form);
    };
    if !(h.is_finite() && h >= 0.0) {
        return Err(err(
            format!("{field}.hourglass"),
            format!("expected a finite number ≥ 0, got {h}"),
        ));
    }
    match form {
        Formulation::FBar { .. } => Ok(Formulation::FBar { hourglass: h }),
        Formulation::Reduced { .. } => Ok(Formulation::Reduced { hourglass: h }),
        Formulation::Hybrid { .. } => Ok(Formulation::Hybrid { hourglass: h }),
        Formulation::Standard | Formulation::Eas => Err(err(
            format!("{field}.hourglass"),
            "only F-bar, hybrid and reduced hex8 have an hourglass spring; this part's \
             elements are standard or EAS (set formulation = \"fbar\", \"hybrid\" or \
             \"reduced\")",
        )),
    }
}

/// Whether the part is meshed as a sheet: a surface extruded through its thickness, one
/// or a few elements across it, which must bend.
fn is_sheet(p: &PartDeck) -> bool {
    matches!(p.mesh, MeshDeck::Sheet { .. })
}

/// A sheet whose wedges (its triangles) are more than 1 in this many of its elements
/// is warned: a few triangles in a recombined mesh cost little (Scordelis–Lo, 44
/// triangles among 756 facets: −1.4 %), many lock (README "Sheets of triangles").
const TRIANGLE_SHARE_WARNED: usize = 10;

/// Poisson's ratio above which the standard hex8 and tet4 lock (volumetric locking: the
/// constraint J = 1 at every point); `auto` leaves standard elements below it.
pub(crate) const LOCKING_NU: f64 = 0.45;

/// A part's formulation checked against its element types, what `alfe check` says of
/// it, and the warnings its choice earns.
pub(super) struct Fit {
    /// What the model stores for the part: `form`, or standard when `form` applies to
    /// none of its element types (a tet4 part under `auto`).
    pub formulation: Formulation,
    pub description: String,
    pub warnings: Vec<String>,
}

/// The formulations there are (for the list of those that apply to an element type).
const ALL_FORMULATIONS: [Formulation; 5] = [
    Formulation::Standard,
    Formulation::FBAR,
    Formulation::REDUCED,
    Formulation::Eas,
    Formulation::Hybrid { hourglass: 0.0 },
];

/// The part's element types with their counts, by name.
fn kind_counts(mesh: &Mesh) -> Vec<(ElemKind, usize)> {
    let mut counts: Vec<(ElemKind, usize)> = Vec::new();
    for &k in &mesh.kinds {
        match counts.iter_mut().find(|c| c.0 == k) {
            Some(c) => c.1 += 1,
            None => counts.push((k, 1)),
        }
    }
    counts.sort_by_key(|c| c.0.name());
    counts
}

/// A formulation the deck names must apply to every element type of the part: else an
/// error at `parts[i].formulation` naming the type, its share and what it has.
fn refuse_inapplicable(
    p: &PartDeck,
    f: &str,
    form: Formulation,
    mesh: &Mesh,
    counts: &[(ElemKind, usize)],
) -> Result<()> {
    let name = &p.name;
    let Some(&(k, n)) = counts.iter().find(|c| !applies(c.0, form)) else {
        return Ok(());
    };
    let of = ALL_FORMULATIONS
        .iter()
        .filter(|&&g| applies(k, g))
        .map(|g| g.deck_name())
        .collect::<Vec<_>>();
    let total = mesh.n_elems();
    let share = if n == total {
        format!("its {n} elements are {}", k.name())
    } else {
        format!("{n} of its {total} elements are {}", k.name())
    };
    Err(err(
        format!("{f}.formulation"),
        format!(
            "\"{}\" does not apply to {k} elements (part `{name}`: {share}); {k} has \
             only the {} formulation{}; set formulation = \"auto\" or \"{}\", or \
             mesh the part with hex8",
            form.deck_name(),
            of.join(", "),
            if of.len() == 1 { "" } else { "s" },
            of[0],
            k = k.name(),
        ),
    ))
}

/// Check `form` (the deck's choice, or `auto`'s) against the element types of the part's
/// mesh: a formulation the deck names that does not apply to one of them is an error at
/// `parts[i].formulation`; under `auto` an element type it does not apply to takes the
/// standard element. Then describe the part for `alfe check` and warn on a choice known to
/// lock: standard elements (tet4 always) with ν > [`LOCKING_NU`], a sheet of elements
/// that lock in bending (anything but EAS), and a sheet of many triangles.
pub(super) fn fit_to_elements(
    p: &PartDeck,
    f: &str,
    form: Formulation,
    mesh: &Mesh,
    material: &MaterialDef,
    explicit: bool,
) -> Result<Fit> {
    let name = &p.name;
    let counts = kind_counts(mesh);
    if p.formulation != FormulationDeck::Auto {
        refuse_inapplicable(p, f, form, mesh, &counts)?;
    }
    let stored = if counts.iter().any(|c| applies(c.0, form)) {
        form
    } else {
        counts.first().map_or(form, |c| for_kind(c.0, form))
    };
    // Only hex8 have an hourglass spring (F-bar, hybrid, reduced).
    let no_spring = stored != form || !counts.iter().any(|c| c.0 == ElemKind::Hex8);
    if no_spring && p.hourglass.is_some() {
        return Err(err(
            format!("{f}.hourglass"),
            format!(
                "part `{name}` has no element with an hourglass spring (only F-bar, hybrid \
                 and reduced hex8 have one; its elements are {})",
                counts
                    .iter()
                    .map(|c| c.0.name())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ));
    }
    // Each element type's formulation, and whether it locks.
    let nu = material.nu();
    let sheet = match p.mesh {
        MeshDeck::Sheet { layers, .. } => Some(layers),
        _ => None,
    };
    let mut warnings = Vec::new();
    let mut pieces = Vec::new();
    let what_auto = |k: ElemKind| -> String {
        let mut q = p.clone();
        q.formulation = FormulationDeck::Auto;
        q.hourglass = None;
        match part_formulation_of(&q, material, f, explicit) {
            Ok(g) if for_kind(k, g) != Formulation::Standard => {
                format!(
                    "formulation = \"auto\" (here {})",
                    describe_for(k, for_kind(k, g))
                )
            }
            _ if applies(k, Formulation::Hybrid { hourglass: 0.0 }) => {
                "formulation = \"fbar\" or \"hybrid\"".into()
            }
            _ => "formulation = \"fbar\"".into(),
        }
    };
    for &(k, n) in &counts {
        let g = for_kind(k, stored);
        let mut locks = Vec::new();
        if g == Formulation::Standard && nu > LOCKING_NU {
            locks.push(format!("nu = {nu} > {LOCKING_NU}"));
            let instead = format!("use {}", what_auto(k));
            warnings.push(format!(
                "part `{name}` ({f}): {n} {k} with the {g} formulation lock at nu = {nu} > \
                 {LOCKING_NU} (volumetric locking: forces and stiffness come out too high, \
                 several times over as nu nears 0.5); {instead}",
                k = k.name(),
                g = describe_for(k, g),
            ));
        }
        if let Some(layers) = sheet {
            if g != Formulation::Eas {
                locks.push("in bending, a sheet".into());
                warnings.push(format!(
                    "part `{name}` ({f}): a sheet of {n} {k} ({layers} through the thickness) \
                     with the {g} formulation locks in bending (a 60 x 20 x 1 plate under a tip load \
                     deflects a quarter of beam theory's answer with standard, F-bar or \
                     reduced hex8); use formulation = \"auto\" or \"eas\" (EAS, the \
                     solid-shell element: within 0.1 %)",
                    k = k.name(),
                    g = describe_for(k, g),
                ));
            }
        }
        if let (Some(_), ElemKind::Wedge6, Formulation::Eas) = (sheet, k, g) {
            let total = mesh.n_elems();
            if n * TRIANGLE_SHARE_WARNED > total {
                warnings.push(format!(
                    "part `{name}` ({f}): {n} of the sheet's {total} elements are wedge6 \
                     extruded from triangles; the solid-shell wedge is stiffer in bending \
                     than the EAS hex8 (the three-node triangle's transverse shear locking: \
                     a 60 x 20 x 1 plate of 384 triangles deflects 70 % of beam theory, an \
                     all-triangle Scordelis-Lo roof at 16 elements a side 23 % of the \
                     answer); recombine the surface into quads (Gmsh: Mesh.RecombineAll = 1) \
                     or refine"
                ));
            }
        }
        let locks = if locks.is_empty() {
            String::new()
        } else {
            format!(" (locks: {})", locks.join("; "))
        };
        pieces.push((format!("{n} {}", k.name()), describe_for(k, g), locks));
    }
    let kinds = pieces
        .iter()
        .map(|p| p.0.clone())
        .collect::<Vec<_>>()
        .join(", ");
    let sheet_note = match sheet {
        Some(l) => format!(" (sheet, {l} through the thickness)"),
        None => String::new(),
    };
    let description = if pieces.iter().all(|q| q.1 == pieces[0].1) {
        let locks: Vec<&str> = pieces
            .iter()
            .map(|q| q.2.as_str())
            .filter(|l| !l.is_empty())
            .collect();
        format!(
            "{name}: {kinds}{sheet_note}, {}{}",
            pieces[0].1,
            locks.first().copied().unwrap_or("")
        )
    } else {
        format!(
            "{name}: {}{sheet_note}",
            pieces
                .iter()
                .map(|q| format!("{} {}{}", q.0, q.1, q.2))
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    Ok(Fit {
        formulation: stored,
        description,
        warnings,
    })
}
