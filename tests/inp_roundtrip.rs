//! Abaqus/CalculiX input files both ways with alfe's notes (issue 36): `alfe export`
//! writes a scene as an `.inp` whose `** alfe` notes carry what the keywords cannot
//! (walls, entities, formulations, analysis), `alfe import` rebuilds the deck from them
//! and drops the rigid layers CalculiX needs. A wall scene (hertz-sphere, coarser) and a small
//! contact-entity scene (sphere-roll, coarser and shorter) come back with the same walls
//! and entities, field for field, and the same history.

mod common;
use alfe::model::def::ContributionDef;
use alfe::scene::Scene;
use common::*;

/// Export `deck` to an `.inp` and import it; (the original scene, the imported one,
/// the imported deck's path).
fn round_trip(name: &str, deck: &str) -> (Scene, Scene, std::path::PathBuf) {
    let dir = temp_dir(name);
    let src = dir.join("original.toml");
    std::fs::write(&src, deck).unwrap();
    let inp = dir.join(format!("{name}.inp"));
    alfe::app::export::export(src.to_str().unwrap(), &inp).unwrap();
    let back = dir.join("back.toml");
    let r = alfe::app::import::import(&inp, &back).unwrap();
    // Nothing of the rigid layers is reported as not translated.
    assert!(
        r.untranslated.iter().all(|u| !u.contains("W_")),
        "{:?}",
        r.untranslated
    );
    let read = |p: &std::path::Path| {
        alfe::scene::read(&alfe::scene::load(p.to_str().unwrap()).unwrap()).unwrap()
    };
    (read(&src), read(&back), back)
}

/// Walls and entities as JSON (shape, motion, friction, method, body, tracked nodes).
fn walls(s: &Scene) -> Vec<serde_json::Value> {
    s.model
        .contributions
        .iter()
        .filter_map(|c| match c {
            ContributionDef::Wall(w) => Some(serde_json::to_value(w).unwrap()),
            _ => None,
        })
        .collect()
}

fn same_history(name: &str, deck: &str, back: &std::path::Path, columns: &[&str]) {
    let a = run_deck(&format!("{name}-a"), deck);
    let b = run_deck_file(&format!("{name}-b"), back);
    assert_eq!(a.steps.len(), b.steps.len());
    for c in columns {
        let (x, y) = (column(&a, c), column(&b, c));
        let scale = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let worst = x
            .iter()
            .zip(&y)
            .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
        assert!(
            scale > 0.0 && worst <= 1e-9 * scale,
            "{name} {c}: {worst} of {scale}"
        );
    }
}

#[test]
fn a_wall_scene_round_trips_through_an_inp_with_notes() {
    let deck = edit(
        &builtin("hertz-sphere"),
        "cells = [20, 20, 20]",
        "cells = [8, 8, 8]",
    );
    let (a, b, back) = round_trip("inp-hertz", &deck);
    let (wa, wb) = (walls(&a), walls(&b));
    assert!(!wa.is_empty());
    assert_eq!(wa, wb);
    assert_eq!(a.model.mesh.n_elems(), b.model.mesh.n_elems());
    assert_eq!(a.model.part_formulation, b.model.part_formulation);
    same_history("inp-hertz", &deck, &back, &["sphere.fz"]);
}

#[test]
fn a_contact_entity_round_trips_through_an_inp_with_notes() {
    let deck = edit(
        &edit(
            &builtin("sphere-roll"),
            "cells = [12, 12, 6]",
            "cells = [6, 6, 3]",
        ),
        "end_time = 2.0",
        "end_time = 0.2",
    );
    let (a, b, back) = round_trip("inp-entity", &deck);
    let (wa, wb) = (walls(&a), walls(&b));
    assert!(wa.iter().any(|w| !w["body"].is_null()));
    assert_eq!(wa, wb);
    same_history("inp-entity", &deck, &back, &["sphere.fz", "sphere.uz"]);
}
