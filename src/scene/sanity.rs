//! Abaqus's data check, in spirit: a deck can be valid and still not mean what its
//! author meant. These are warnings with the numbers that raised them, not errors (a
//! user can mean it): material constants implausible in the deck's unit system, a model
//! whose size suggests another length unit, motions that end after the analysis, and
//! a static model with rigid-body modes left free (before the first factorization
//! fails as "numerically singular").

use super::deck::{Deck, MaterialDeck, MaterialModel, Units};
use crate::mesh::Mesh;
use crate::model::def::Constraint;
use crate::model::walls::WallDef;
use crate::solve::AnalysisKind;
use std::collections::BTreeMap;

/// Every warning of the deck and its built mesh, supports resolved to their nodes.
pub(super) fn warnings(
    deck: &Deck,
    mesh: &Mesh,
    sets: &BTreeMap<String, Vec<usize>>,
    constraints: &[Constraint],
    walls: &[WallDef],
) -> Vec<String> {
    let units = deck.scene.units;
    let mut w: Vec<String> = deck
        .materials
        .iter()
        .enumerate()
        .flat_map(|(i, m)| material(i, m, units))
        .collect();
    w.extend(size(mesh, units));
    w.extend(motions_after_the_end(deck));
    if deck.analysis.kind == AnalysisKind::Static {
        // Walls (not free entities) that touch at t = 0 hold the model along their normal.
        let contact: Vec<(usize, [f64; 3])> = walls
            .iter()
            .filter(|w| w.body.is_none())
            .flat_map(|w| w.touching_at_start(&mesh.coords))
            .collect();
        w.extend(rigid_body_modes(deck, mesh, sets, constraints, &contact));
    }
    w
}

/// Stress and density of the unit system in Pa and kg/m³, its length in m.
fn si(units: Units) -> (f64, f64, f64) {
    match units {
        Units::MKgS => (1.0, 1.0, 1.0),
        Units::MmTS => (1e6, 1e12, 1e-3),
        Units::MmKgMs => (1e9, 1e9, 1e-3),
        Units::MmGMs => (1e6, 1e6, 1e-3),
    }
}

/// What a value looks like in SI: "5e11 Pa".
fn show(v: f64, unit: &str) -> String {
    format!("{v:.3e} {unit}")
}

/// Plausible ranges in SI: rubbers' shear moduli (gels to hard rubber), Young's moduli
/// of solids (soft foams to diamond), of metals and polymers that yield, yield
/// stresses, densities (foams to osmium).
const RUBBER_SHEAR_PA: (f64, f64) = (1e3, 1e9);
const YOUNG_PA: (f64, f64) = (1e4, 2e12);
const YIELDING_YOUNG_PA: (f64, f64) = (1e8, 2e12);
const YIELD_PA: (f64, f64) = (1e5, 1e10);
const DENSITY_KG_M3: (f64, f64) = (1.0, 3e4);

fn material(i: usize, m: &MaterialDeck, units: Units) -> Vec<String> {
    let (stress, density, _) = si(units);
    let field = |f: &str| format!("materials[{i}].{f} (`{}`)", m.name);
    let mut w = Vec::new();
    let mut range = |f: &str, v: f64, scale: f64, (lo, hi): (f64, f64), unit: &str, what: &str| {
        let x = v * scale;
        if v > 0.0 && !(lo..=hi).contains(&x) {
            w.push(format!(
                "{} = {v} is {} in the deck's units ({}), outside {} to {} for {what}: \
                 is it in another unit?",
                field(f),
                show(x, unit),
                units.describe(),
                show(lo, unit),
                show(hi, unit)
            ));
        }
    };
    match m.model {
        MaterialModel::MooneyRivlin => {
            let g = 2.0 * (m.c10.unwrap_or(0.0) + m.c01.unwrap_or(0.0));
            let f = if m.c01.is_some_and(|c| c != 0.0) {
                "C10 + C01"
            } else {
                "C10"
            };
            range(
                f,
                g / 2.0,
                2.0 * stress,
                RUBBER_SHEAR_PA,
                "Pa",
                "a rubber's shear modulus 2(C10 + C01)",
            );
        }
        MaterialModel::J2 => {
            range(
                "E",
                m.e.unwrap_or(0.0),
                stress,
                YIELDING_YOUNG_PA,
                "Pa",
                "a metal's or polymer's Young's modulus",
            );
            range(
                "yield_stress",
                m.yield_stress.unwrap_or(0.0),
                stress,
                YIELD_PA,
                "Pa",
                "a yield stress",
            );
        }
        _ => range(
            "E",
            m.e.unwrap_or(0.0),
            stress,
            YOUNG_PA,
            "Pa",
            "a solid's Young's modulus",
        ),
    }
    range(
        "density",
        m.density,
        density,
        DENSITY_KG_M3,
        "kg/m³",
        "a solid's density",
    );
    if let (MaterialModel::J2, Some(e), Some(y)) = (m.model, m.e, m.yield_stress) {
        if e > 0.0 && !(1e-5..=0.1).contains(&(y / e)) {
            w.push(format!(
                "{} / E = {y} / {e} = {:.3e}, outside 1e-5 to 0.1 for a material that yields: are they in the same unit?",
                field("yield_stress"),
                y / e
            ));
        }
    }
    w
}

/// Plausible model sizes (bounding-box diagonal): a 0.1 mm part to a 1 km structure.
const SIZE_M: (f64, f64) = (1e-4, 1e3);

fn size(mesh: &Mesh, units: Units) -> Option<String> {
    let (lo, hi) = crate::mesh::select::bounding_box(mesh);
    let diag = (0..3).map(|i| (hi[i] - lo[i]).powi(2)).sum::<f64>().sqrt();
    let m = diag * si(units).2;
    (mesh.n_nodes() > 0 && !(SIZE_M.0..=SIZE_M.1).contains(&m)).then(|| {
        format!(
            "the model's bounding box diagonal is {diag:.4e} in the deck's length unit ({}), {} m, outside {:e} to {:e} m: is the geometry in another length unit?",
            units.describe(),
            show(m, "").trim(),
            SIZE_M.0,
            SIZE_M.1
        )
    })
}

/// Motion segments of walls and entities that end after the analysis does.
fn motions_after_the_end(deck: &Deck) -> Vec<String> {
    let end = deck.analysis.end_time;
    let mut w = Vec::new();
    for (what, walls) in [("walls", &deck.walls), ("entities", &deck.entities)] {
        for (i, wall) in walls.iter().enumerate() {
            let Some(segs) = wall.motion.as_ref().and_then(|m| m.segments.as_ref()) else {
                continue;
            };
            let mut from = 0.0;
            for (k, s) in segs.iter().enumerate() {
                if s.to > end * (1.0 + 1e-9) {
                    let done = ((end - from) / (s.to - from)).clamp(0.0, 1.0);
                    w.push(format!(
                        "{what}[{i}].motion.segments[{k}].to = {} is after analysis.end_time = {end} (`{}`): the run ends with {:.0} % of this segment done",
                        s.to,
                        wall.name,
                        100.0 * done
                    ));
                }
                from = s.to;
            }
        }
    }
    w
}

/// A static model's rigid-body modes that no support and no wall touching at t = 0
/// holds: the null space of Σ g gᵀ over the supported (node, direction) pairs and the
/// touching (node, wall normal) pairs, g the six rigid modes' values there (rotations
/// about the model's centre, scaled by its size).
fn rigid_body_modes(
    deck: &Deck,
    mesh: &Mesh,
    sets: &BTreeMap<String, Vec<usize>>,
    constraints: &[Constraint],
    contact: &[(usize, [f64; 3])],
) -> Option<String> {
    let (lo, hi) = crate::mesh::select::bounding_box(mesh);
    let c: [f64; 3] = std::array::from_fn(|i| 0.5 * (lo[i] + hi[i]));
    let size = (0..3)
        .map(|i| (hi[i] - lo[i]).powi(2))
        .sum::<f64>()
        .sqrt()
        .max(1e-300);
    let mut g = nalgebra::Matrix6::<f64>::zeros();
    for con in constraints {
        for &n in sets.get(&con.set).map(Vec::as_slice).unwrap_or(&[]) {
            let x: [f64; 3] = std::array::from_fn(|i| (mesh.coords[n][i] - c[i]) / size);
            for d in (0..3).filter(|&d| con.comps[d]) {
                g += {
                    let v = mode_values(x, d);
                    v * v.transpose()
                };
            }
        }
    }
    for &(n, normal) in contact {
        let x: [f64; 3] = std::array::from_fn(|i| (mesh.coords[n][i] - c[i]) / size);
        let v: nalgebra::Vector6<f64> = (0..3).map(|d| normal[d] * mode_values(x, d)).sum();
        g += v * v.transpose();
    }
    let eig = nalgebra::SymmetricEigen::new(g);
    let scale = eig.eigenvalues.max().max(1e-300);
    let free: Vec<usize> = (0..6)
        .filter(|&k| eig.eigenvalues[k] <= 1e-10 * scale || g.trace() == 0.0)
        .collect();
    if free.is_empty() {
        return None;
    }
    const NAMES: [&str; 6] = [
        "translation x",
        "translation y",
        "translation z",
        "rotation about x",
        "rotation about y",
        "rotation about z",
    ];
    let names: Vec<String> = free
        .iter()
        .map(|&k| {
            let v = eig.eigenvectors.column(k);
            let j = v.iamax();
            if v[j].abs() > 0.95 {
                NAMES[j].to_string()
            } else {
                "a combination of them".into()
            }
        })
        .collect();
    let held = ["walls", "entities", "pairs", "bolts"]
        .iter()
        .zip([
            deck.walls.len(),
            deck.entities.len(),
            deck.pairs.len(),
            deck.bolts.len(),
        ])
        .filter(|(_, n)| *n > 0)
        .map(|(w, _)| *w)
        .collect::<Vec<_>>();
    let unless = if held.is_empty() {
        String::new()
    } else {
        format!(" unless contact ({}) closes first", held.join(", "))
    };
    Some(format!(
        "supports: {} support(s), and the walls touching at t = 0, leave {} rigid-body mode(s) of this static model free ({}); its stiffness is singular{unless}: add supports ([[boundary]]) or run implicit dynamics",
        constraints.len(),
        free.len(),
        names.join(", ")
    ))
}

/// The six rigid modes' components in direction `d` at the scaled point `x`:
/// translations e_k, rotations e_k × x.
fn mode_values(x: [f64; 3], d: usize) -> nalgebra::Vector6<f64> {
    let mut v = nalgebra::Vector6::zeros();
    v[d] = 1.0;
    for k in 0..3 {
        // (e_k × x)_d = ε_{d k j} x_j
        let (a, b) = ((k + 1) % 3, (k + 2) % 3);
        v[3 + k] = if d == a {
            -x[b]
        } else if d == b {
            x[a]
        } else {
            0.0
        };
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_modes_are_cross_products() {
        // e_z × (1, 0, 0) = (0, 1, 0): rotation about z moves x-axis points along y.
        let x = [1.0, 0.0, 0.0];
        assert_eq!(mode_values(x, 1)[5], 1.0);
        assert_eq!(mode_values(x, 0)[5], 0.0);
        // e_x × (0, 1, 0) = (0, 0, 1).
        assert_eq!(mode_values([0.0, 1.0, 0.0], 2)[3], 1.0);
        // e_y × (0, 0, 1) = (1, 0, 0).
        assert_eq!(mode_values([0.0, 0.0, 1.0], 0)[4], 1.0);
    }
}
