//! `alfe schema`: the JSON Schema of the deck, generated from the deck types (one source
//! of truth: the doc comments become the descriptions). An editor that reads JSON Schema
//! for TOML (Taplo, "Even Better TOML") completes and checks a deck with it.

/// The deck's JSON Schema (draft 2020-12), pretty-printed.
pub fn deck_schema() -> String {
    let schema = schemars::schema_for!(crate::scene::deck::Deck);
    serde_json::to_string_pretty(&schema).expect("a schema serializes")
}

#[cfg(test)]
mod tests {
    /// Every property of every deck table has a description.
    #[test]
    fn every_field_is_described() {
        let s: serde_json::Value = serde_json::from_str(&super::deck_schema()).unwrap();
        let mut missing = Vec::new();
        let mut tables = vec![("Deck".to_string(), &s)];
        if let Some(defs) = s["$defs"].as_object() {
            tables.extend(defs.iter().map(|(k, v)| (k.clone(), v)));
        }
        for (name, t) in tables {
            for (field, p) in t["properties"].as_object().into_iter().flatten() {
                if p.get("description").is_none() && p.get("$ref").is_none() {
                    missing.push(format!("{name}.{field}"));
                }
            }
        }
        assert!(missing.is_empty(), "no description: {missing:?}");
    }
}
