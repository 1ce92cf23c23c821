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
    &["app"],
];

fn level(m: &str) -> Option<(usize, usize)> {
    LAYERS
        .iter()
        .enumerate()
        .find_map(|(i, row)| row.iter().position(|x| *x == m).map(|j| (i, j)))
}

/// The library's source files (`src/bin/`, the binaries' own crates, left out: they
/// reach the library only through `alfe::`, its public API).
fn files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.ends_with("src/bin") {
            continue;
        }
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

/// The module path of a source file (`scene/deck/mod.rs` → `["scene", "deck"]`).
fn module_path(rel: &Path) -> Vec<String> {
    let mut p: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().to_string())
        .collect();
    let last = p.pop().unwrap();
    let stem = last.trim_end_matches(".rs");
    if stem != "mod" && stem != "lib" && stem != "main" {
        p.push(stem.to_string());
    }
    p
}

/// The paths a file's code (tests excluded) names through `crate::`, `super::` or
/// `self::`, braces expanded one level: `use super::{a, b::C}` gives `super::a` and
/// `super::b::C`.
fn named_paths(text: &str) -> Vec<(String, Vec<String>)> {
    let code: String = text
        .lines()
        .take_while(|l| l.trim() != "#[cfg(test)]")
        .map(|l| l.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n");
    let ident = |c: char| c.is_ascii_alphanumeric() || c == '_';
    let mut out = Vec::new();
    for root in ["crate", "super", "self"] {
        for (pos, _) in code.match_indices(&format!("{root}::")) {
            if pos > 0 && code[..pos].chars().last().is_some_and(ident) {
                continue;
            }
            let rest = &code[pos + root.len() + 2..];
            let mut segs = Vec::new();
            let mut s = rest;
            loop {
                let id: String = s.chars().take_while(|&c| ident(c)).collect();
                if id.is_empty() {
                    break;
                }
                s = &s[id.len()..];
                segs.push(id);
                if let Some(t) = s.strip_prefix("::") {
                    s = t;
                } else {
                    break;
                }
            }
            if s.starts_with('{') {
                let inner = &s[1..s.find('}').unwrap_or(s.len())];
                for item in inner.split(',') {
                    let mut full = segs.clone();
                    full.extend(
                        item.split_whitespace()
                            .next()
                            .unwrap_or("")
                            .split("::")
                            .filter(|x| !x.is_empty() && *x != "self" && *x != "{")
                            .map(String::from),
                    );
                    out.push((root.to_string(), full));
                }
            } else {
                out.push((root.to_string(), segs));
            }
        }
    }
    out
}

/// Files that use each other, directly or round a longer circle, are one room split in
/// two: a circle between files is refused like an upward import (a parent module's
/// `pub use` of its children is not counted; children name their siblings directly).
#[test]
fn no_circles_between_files() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut all = Vec::new();
    files(&src, &mut all);
    let rels: Vec<std::path::PathBuf> = all
        .iter()
        .map(|f| f.strip_prefix(&src).unwrap().to_path_buf())
        .collect();
    let by_module: std::collections::BTreeMap<Vec<String>, usize> = rels
        .iter()
        .enumerate()
        .map(|(i, r)| (module_path(r), i))
        .collect();
    let resolve = |segs: &[String]| -> Option<usize> {
        (1..=segs.len())
            .rev()
            .find_map(|n| by_module.get(&segs[..n]).copied())
    };
    let mut edges: Vec<std::collections::BTreeSet<usize>> = vec![Default::default(); rels.len()];
    for (i, f) in all.iter().enumerate() {
        let me = module_path(&rels[i]);
        let text = std::fs::read_to_string(f).unwrap();
        for (root, segs) in named_paths(&text) {
            let full: Vec<String> = match root.as_str() {
                "crate" => segs,
                "super" => me[..me.len().saturating_sub(1)]
                    .iter()
                    .cloned()
                    .chain(segs)
                    .collect(),
                _ => me.iter().cloned().chain(segs).collect(),
            };
            if let Some(j) = resolve(&full) {
                if j != i {
                    edges[i].insert(j);
                }
            }
        }
    }
    // Strongly connected components (Tarjan); any with two files or more is a circle.
    struct Tarjan<'a> {
        edges: &'a [std::collections::BTreeSet<usize>],
        index: Vec<Option<usize>>,
        low: Vec<usize>,
        stack: Vec<usize>,
        on: Vec<bool>,
        next: usize,
        found: Vec<Vec<usize>>,
    }
    impl Tarjan<'_> {
        fn visit(&mut self, v: usize) {
            self.index[v] = Some(self.next);
            self.low[v] = self.next;
            self.next += 1;
            self.stack.push(v);
            self.on[v] = true;
            for &w in self.edges[v].clone().iter() {
                match self.index[w] {
                    None => {
                        self.visit(w);
                        self.low[v] = self.low[v].min(self.low[w]);
                    }
                    Some(iw) if self.on[w] => self.low[v] = self.low[v].min(iw),
                    _ => {}
                }
            }
            if Some(self.low[v]) == self.index[v] {
                let mut comp = Vec::new();
                loop {
                    let w = self.stack.pop().unwrap();
                    self.on[w] = false;
                    comp.push(w);
                    if w == v {
                        break;
                    }
                }
                if comp.len() > 1 {
                    self.found.push(comp);
                }
            }
        }
    }
    let n = rels.len();
    let mut t = Tarjan {
        edges: &edges,
        index: vec![None; n],
        low: vec![0; n],
        stack: Vec::new(),
        on: vec![false; n],
        next: 0,
        found: Vec::new(),
    };
    for v in 0..n {
        if t.index[v].is_none() {
            t.visit(v);
        }
    }
    let circles: Vec<String> = t
        .found
        .iter()
        .map(|c| {
            let mut names: Vec<String> = c.iter().map(|&i| rels[i].display().to_string()).collect();
            names.sort();
            names.join(" ↔ ")
        })
        .collect();
    assert!(
        circles.is_empty(),
        "circles between files:\n{}",
        circles.join("\n")
    );
}

/// The circle finder finds a circle (so a pass above means something).
#[test]
fn named_paths_reads_braces_and_super() {
    let p = named_paths("use super::{a, b::C};\nuse crate::x::y;\nfn f() { self::z::w(); }\n#[cfg(test)]\nuse crate::t;");
    let got: Vec<String> = p
        .iter()
        .map(|(r, s)| format!("{r}::{}", s.join("::")))
        .collect();
    assert_eq!(
        got,
        vec!["crate::x::y", "super::a", "super::b::C", "self::z::w"]
    );
}
