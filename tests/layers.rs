//! The folder layout is the data flow, and layers point one way: a module uses only
//! modules of lower layers (or itself). Nothing below `scene/` reads a deck type, the
//! physics kernels (`contact/`, `fem/`, `material/`, `mesh/`) and the parallel layer
//! know nothing of the model, the solvers or the output.

use std::path::Path;

/// Layers, bottom up; a module may use its own layer's modules only if listed before
/// it in the same row.
const LAYERS: &[&[&str]] = &[
    &["error", "curve", "parallel"],
    &["mesh", "material"],
    &["fem"],
    &["contact", "linalg", "partition"],
    &["model"],
    &["solve"],
    &["output"],
    &["scene"],
    &["app", "bench", "bench_residual"],
];

fn level(m: &str) -> Option<(usize, usize)> {
    LAYERS
        .iter()
        .enumerate()
        .find_map(|(i, row)| row.iter().position(|x| *x == m).map(|j| (i, j)))
}

fn files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

#[test]
fn layers_point_one_way() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut all = Vec::new();
    files(&src, &mut all);
    let mut bad = Vec::new();
    for f in &all {
        let rel = f.strip_prefix(&src).unwrap();
        let first = rel
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_string_lossy();
        let module = first.trim_end_matches(".rs").to_string();
        if module == "lib" || module == "main" {
            continue;
        }
        let (li, lj) = level(&module).unwrap_or_else(|| panic!("{module} has no layer"));
        let text = std::fs::read_to_string(f).unwrap();
        // Unit tests (at the end of a file) may use anything.
        for (n, line) in text
            .lines()
            .enumerate()
            .take_while(|(_, l)| l.trim() != "#[cfg(test)]")
        {
            for (pos, _) in line.match_indices("crate::") {
                let used: String = line[pos + 7..]
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                if used == module || used.is_empty() {
                    continue;
                }
                let Some((ui, uj)) = level(&used) else {
                    continue; // Error, Result, ... re-exported at the root
                };
                if ui > li || (ui == li && uj >= lj) {
                    bad.push(format!("{}:{}: {module} uses {used}", rel.display(), n + 1));
                }
            }
        }
    }
    assert!(bad.is_empty(), "layers pointing up:\n{}", bad.join("\n"));
}
