//! `alfe schema` (issue 38): the deck's JSON Schema, generated from the deck types,
//! validates every built-in scene and every deck under `tests/`, and rejects what the
//! parser rejects for a misspelt key, a wrong type, a missing table or an unknown
//! choice (checked with Python's `jsonschema`, Debian's python3-jsonschema, on the TOML
//! read by `tomllib`: what an editor with a JSON Schema for TOML does).

mod common;
use common::*;
use std::path::Path;

#[test]
fn the_schema_validates_every_built_in_scene_and_test_deck() {
    let dir = temp_dir("schema-ok");
    let mut decks = Vec::new();
    for (name, _, text) in alfe::scene::BUILTIN {
        let p = dir.join(format!("{name}.toml"));
        std::fs::write(&p, text).unwrap();
        decks.push(p);
    }
    let tests = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    for e in std::fs::read_dir(&tests).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "toml") {
            decks.push(p);
        }
    }
    assert!(decks.len() > 25, "{} decks", decks.len());
    for (d, v) in decks.iter().zip(schema_verdicts(&dir, &decks)) {
        assert!(v == Ok(()), "{}: {v:?}", d.display());
    }
}

#[test]
fn the_schema_rejects_what_the_parser_rejects() {
    let dir = temp_dir("schema-bad");
    let deck = builtin("sliding-block");
    let mutations = [
        ("end_time = ", "end_tme = "),
        ("friction = 0.3", "friction = \"0.3\""),
        ("[analysis]", "[analysis_typo]"),
        ("shape = \"plane\"", "shape = \"plain\""),
        ("units = \"mm-t-s\"", "units = \"mm-kg-s\""),
    ];
    let mut decks = Vec::new();
    for (i, (from, to)) in mutations.iter().enumerate() {
        assert!(deck.contains(from), "{from}");
        let p = dir.join(format!("m{i}.toml"));
        std::fs::write(&p, deck.replacen(from, to, 1)).unwrap();
        let parsed = alfe::app::check(p.to_str().unwrap(), 1, &Default::default());
        assert!(parsed.is_err(), "the parser took `{to}`");
        decks.push(p);
    }
    for ((_, to), v) in mutations.iter().zip(schema_verdicts(&dir, &decks)) {
        assert!(v.is_err(), "the schema took `{to}`");
    }
}
