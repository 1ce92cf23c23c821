//! A seeded mutation fuzzer over the built-in decks (issue 16): thousands of decks, each
//! a built-in scene with one mutation (a value replaced by an absurd one, a key dropped
//! or added, an array cut or grown, a line deleted, doubled or garbled), through what
//! `alfe check` does, in this process. Every deck is either accepted or refused with an
//! error that names where: a deck field's path or a line of the TOML. A panic fails the
//! test; an abort kills it. The seed and the number of cases can be set with
//! `ALFE_FUZZ_SEED` and `ALFE_FUZZ_CASES`; a failure prints the deck that caused it.

mod common;
use alfe::scene::{Source, BUILTIN};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;
use std::time::Instant;
use toml::Value;

/// splitmix64: a tiny seeded generator (no dependency).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn pick<'a, T>(&mut self, v: &'a [T]) -> &'a T {
        &v[self.below(v.len())]
    }
}

#[derive(Clone, Debug)]
enum Step {
    Key(String),
    Index(usize),
}

/// Every value's path in the deck (tables and arrays included).
fn paths(v: &Value, here: &mut Vec<Step>, out: &mut Vec<Vec<Step>>) {
    out.push(here.clone());
    match v {
        Value::Table(t) => {
            for (k, x) in t {
                here.push(Step::Key(k.clone()));
                paths(x, here, out);
                here.pop();
            }
        }
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                here.push(Step::Index(i));
                paths(x, here, out);
                here.pop();
            }
        }
        _ => {}
    }
}

fn at<'a>(v: &'a mut Value, path: &[Step]) -> &'a mut Value {
    path.iter().fold(v, |v, s| match s {
        Step::Key(k) => v.get_mut(k.as_str()).unwrap(),
        Step::Index(i) => v.get_mut(*i).unwrap(),
    })
}

/// An absurd or wrong value of any type.
fn absurd(r: &mut Rng) -> Value {
    let dt: toml::value::Datetime = "1979-05-27T07:32:00Z".parse().unwrap();
    let choices = [
        Value::Integer(0),
        Value::Integer(-1),
        Value::Integer(1),
        Value::Integer(4_611_686_018_427_387_904),
        Value::Integer(i64::MIN),
        Value::Float(0.0),
        Value::Float(-1.0),
        Value::Float(1e300),
        Value::Float(-1e300),
        Value::Float(1e-300),
        Value::Float(f64::NAN),
        Value::Float(f64::INFINITY),
        Value::Float(0.5),
        Value::String(String::new()),
        Value::String("../../etc/passwd".into()),
        Value::String("ü".repeat(300)),
        Value::String("nonexistent".into()),
        Value::Boolean(true),
        Value::Array(Vec::new()),
        Value::Array(vec![Value::Float(1.0); 5]),
        Value::Table(toml::Table::new()),
        Value::Datetime(dt),
    ];
    r.pick(&choices).clone()
}

/// One mutation of the deck's value tree.
fn mutate_value(deck: &mut Value, r: &mut Rng) {
    let mut all = Vec::new();
    paths(deck, &mut Vec::new(), &mut all);
    let path = r.pick(&all[1..]).clone();
    let (parent, last) = path.split_at(path.len() - 1);
    match r.below(7) {
        0 | 1 => *at(deck, &path) = absurd(r),
        2 => {
            // A number scaled (sizes, steps and moduli far from what was meant).
            let v = at(deck, &path);
            let f = *r.pick(&[10.0, 1000.0, 1e6, -1.0, 1e-6, 0.0]);
            match v {
                Value::Integer(i) => *i = (*i as f64 * f) as i64,
                Value::Float(x) => *x *= f,
                other => *other = absurd(r),
            }
        }
        3 => match (at(deck, parent), &last[0]) {
            (Value::Table(t), Step::Key(k)) => {
                t.remove(k);
            }
            (Value::Array(a), Step::Index(i)) => {
                a.remove(*i);
            }
            _ => {}
        },
        4 => {
            if let Value::Array(a) = at(deck, parent) {
                let extra = a[r.below(a.len())].clone();
                a.push(extra);
            } else if let Value::Table(t) = at(deck, parent) {
                t.insert("bogus".into(), Value::Integer(1));
            }
        }
        5 => {
            if let Value::Table(t) = at(deck, &path) {
                t.insert("bogus".into(), absurd(r));
            } else {
                *at(deck, &path) = absurd(r);
            }
        }
        _ => {
            // Swap two values of the same parent (a unit in the wrong place).
            if let Value::Table(t) = at(deck, parent) {
                let keys: Vec<String> = t.keys().cloned().collect();
                let (a, b) = (r.pick(&keys).clone(), r.pick(&keys).clone());
                let va = t[&a].clone();
                let vb = std::mem::replace(t.get_mut(&b).unwrap(), va);
                t.insert(a, vb);
            }
        }
    }
}

/// One mutation of the deck's text.
fn mutate_text(text: &str, r: &mut Rng) -> String {
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let n = lines.len().max(1);
    match r.below(5) {
        0 => {
            lines.remove(r.below(n).min(lines.len() - 1));
        }
        1 => {
            let i = r.below(n).min(lines.len() - 1);
            lines.insert(i, lines[i].clone());
        }
        2 => {
            let last = lines.len() - 1;
            let (a, b) = (r.below(n).min(last), r.below(n).min(last));
            lines.swap(a, b);
        }
        3 => {
            let i = r.below(n).min(lines.len() - 1);
            let junk = *r.pick(&[
                "\r",
                "[",
                "]]",
                "= =",
                "\"",
                "\u{0}",
                "#\r",
                "'''",
                "{",
                "1979-05-27",
                "x = 1",
            ]);
            let at = r.below(lines[i].len() + 1);
            let at = (0..=at)
                .rev()
                .find(|&k| lines[i].is_char_boundary(k))
                .unwrap_or(0);
            lines[i].insert_str(at, junk);
        }
        _ => {
            let keep = r.below(text.len());
            let keep = (0..=keep)
                .rev()
                .find(|&k| text.is_char_boundary(k))
                .unwrap_or(0);
            return text[..keep].to_string();
        }
    }
    lines.join("\n") + "\n"
}

/// A mutation of `deck`: seven in ten change one value, the rest garble its text.
fn mutated(deck: &Value, r: &mut Rng) -> String {
    if r.below(10) < 7 {
        let mut d = deck.clone();
        mutate_value(&mut d, r);
        toml::to_string(&d).unwrap_or_else(|_| String::from("not = [toml"))
    } else {
        mutate_text(&toml::to_string(deck).unwrap(), r)
    }
}

/// Where an error says the mistake is: a deck path (`parts[0].mesh.cells[1]: ...`) or
/// a TOML line (`... (line 12)`).
/// `keys` are the decks' top-level keys: a path must begin with one of them.
fn names_where(msg: &str, keys: &std::collections::BTreeSet<String>) -> bool {
    let body = msg.split_once(": ").map_or(msg, |(_, b)| b);
    let path_end = body.find(": ").unwrap_or(0);
    let path = &body[..path_end];
    let top = path.split(['.', '[']).next().unwrap_or("");
    let is_path = keys.contains(top)
        && path.split('.').all(|p| {
            let name = p.split('[').next().unwrap_or("");
            !name.is_empty()
                && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
                && p.matches('[').count() == p.matches(']').count()
        });
    is_path || msg.contains("(line ") || msg.contains(" line ")
}

#[test]
fn mutated_decks_are_refused_naming_where() {
    let seed: u64 = std::env::var("ALFE_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(20_261_125);
    let cases: usize = std::env::var("ALFE_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(2400);
    let mut r = Rng(seed);
    let started = Instant::now();
    let (mut accepted, mut refused) = (0, 0);
    let decks: Vec<(&str, Value)> = BUILTIN
        .iter()
        .map(|(n, _, t)| (*n, Value::Table(t.parse::<toml::Table>().unwrap())))
        .collect();
    let keys: std::collections::BTreeSet<String> = decks
        .iter()
        .flat_map(|(_, d)| d.as_table().unwrap().keys().cloned())
        .collect();
    for case in 0..cases {
        let (name, deck) = r.pick(&decks).clone();
        let text = mutated(&deck, &mut r);
        let src = Source {
            text: text.clone(),
            dir: PathBuf::from("."),
            label: format!("fuzz-{case}"),
        };
        let res = catch_unwind(AssertUnwindSafe(|| {
            alfe::app::check_source(&src, 1, &alfe::scene::Overrides::default())
        }));
        match res {
            Err(_) => {
                let keep = std::env::temp_dir().join(format!("alfe-fuzz-case-{case}.toml"));
                let _ = std::fs::write(&keep, &text);
                panic!(
                    "case {case} (seed {seed}, from {name}) panicked; the deck is in {}",
                    keep.display()
                )
            }
            Ok(Ok(_)) => accepted += 1,
            Ok(Err(e)) => {
                refused += 1;
                let msg = e.to_string();
                assert!(
                    names_where(&msg, &keys),
                    "case {case} (seed {seed}, from {name}): `{msg}` names no field or line; deck:\n{text}"
                );
            }
        }
    }
    let secs = started.elapsed().as_secs_f64();
    eprintln!("{cases} mutated decks in {secs:.1} s: {accepted} accepted, {refused} refused");
    assert!(
        refused > cases / 2,
        "the mutations should mostly be refused"
    );
}

/// The schema against the parser on the fuzzer's decks (issue 38): a deck the parser
/// takes is never refused by the schema (the schema is no stricter than alfe), and what
/// the schema lets through that the parser refuses is what only `check` sees (names that
/// refer to nothing, ranges, sizes): counted and printed. 600 decks, one Python process.
#[test]
fn the_schema_refuses_nothing_the_parser_takes() {
    let mut r = Rng(20_261_128);
    let dir = common::temp_dir("fuzz-schema");
    let decks: Vec<Value> = BUILTIN
        .iter()
        .map(|(_, _, t)| Value::Table(t.parse::<toml::Table>().unwrap()))
        .collect();
    let (mut files, mut parsed) = (Vec::new(), Vec::new());
    for case in 0..600 {
        let deck = r.pick(&decks).clone();
        let text = mutated(&deck, &mut r);
        let src = Source {
            text: text.clone(),
            dir: PathBuf::from("."),
            label: format!("fuzz-{case}"),
        };
        let p = dir.join(format!("case-{case}.toml"));
        std::fs::write(&p, &text).unwrap();
        files.push(p);
        parsed.push(alfe::app::check_source(&src, 1, &Default::default()).is_ok());
    }
    let verdicts = common::schema_verdicts(&dir, &files);
    let (mut both_ok, mut both_refuse, mut check_only, mut not_toml) = (0, 0, 0, 0);
    let mut stricter = Vec::new();
    for ((f, ok), v) in files.iter().zip(&parsed).zip(&verdicts) {
        match (ok, v) {
            (_, Err(e)) if e.starts_with("not TOML") => not_toml += 1,
            (true, Ok(())) => both_ok += 1,
            (false, Err(_)) => both_refuse += 1,
            (false, Ok(())) => check_only += 1,
            (true, Err(e)) => stricter.push(format!("{}: {e}", f.display())),
        }
    }
    eprintln!(
        "schema vs parser on 600 fuzzed decks: {both_ok} both accept, {both_refuse} both refuse, {check_only} only check refuses, {not_toml} not TOML to Python"
    );
    assert!(
        stricter.is_empty(),
        "the schema refuses decks alfe takes: {stricter:#?}"
    );
    assert!(both_refuse > 100, "{both_refuse} refused by both");
}
