//! Quantities of interest (issue 17): a scene names its answers, each an expression over
//! its history columns taken at a time or over the run (the final wall force, the peak
//! force, a tip deflection, the largest penetration), with a reference value and a
//! tolerance where one exists (analytic or published). `alfe run` prints them and their
//! errors at the end and writes them to `summary.json`; `scripts/study` compares
//! configurations by them.
//!
//! Expressions: numbers, history column names (`indenter.fz`, `ball.pole.x`,
//! `max_penetration`; a name with other characters in backquotes), `+ - * / ^`,
//! parentheses and `abs`, `sqrt`, `hypot`, `min`, `max`.

use serde::{Deserialize, Serialize};

/// Where in the run a quantity is taken.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum When {
    /// At this time, interpolated linearly between the history rows around it.
    At(f64),
    /// The last row.
    Last,
    /// The largest, smallest or largest absolute value over the rows.
    Max,
    Min,
    MaxAbs,
}

/// An expression over history columns.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Expr {
    Num(f64),
    Col(String),
    Neg(Box<Expr>),
    Bin(char, Box<Expr>, Box<Expr>),
    Call(String, Vec<Expr>),
}

/// One quantity as a deck declares it (resolved).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct QuantityDef {
    pub name: String,
    /// The expression as written (for reports).
    pub text: String,
    pub expr: Expr,
    pub when: When,
    pub reference: Option<f64>,
    /// Relative tolerance |value − reference| / |reference| the answer should meet.
    pub tolerance: Option<f64>,
    pub description: String,
}

/// A quantity's value in a run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct QuantityValue {
    pub name: String,
    pub description: String,
    /// `None` where the run did not reach the time it is taken at.
    pub value: Option<f64>,
    pub reference: Option<f64>,
    /// (value − reference) / |reference|.
    pub error: Option<f64>,
    pub tolerance: Option<f64>,
    /// Whether |error| ≤ tolerance (both known).
    pub within: Option<bool>,
}

const FUNCTIONS: [(&str, usize, usize); 5] = [
    ("abs", 1, 1),
    ("sqrt", 1, 1),
    ("hypot", 2, 3),
    ("min", 2, 8),
    ("max", 2, 8),
];

/// Parse an expression; the error says where and what was expected.
pub fn parse(text: &str) -> Result<Expr, String> {
    let toks = lex(text)?;
    let mut p = Parser { toks: &toks, at: 0 };
    let e = p.sum()?;
    match p.toks.get(p.at) {
        None => Ok(e),
        Some(t) => Err(format!(
            "unexpected `{}` after a complete expression",
            t.show()
        )),
    }
}

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Num(f64),
    Name(String),
    Op(char),
}

impl Tok {
    fn show(&self) -> String {
        match self {
            Tok::Num(x) => x.to_string(),
            Tok::Name(n) => n.clone(),
            Tok::Op(c) => c.to_string(),
        }
    }
}

fn lex(text: &str) -> Result<Vec<Tok>, String> {
    let c: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < c.len() {
        let ch = c[i];
        if ch.is_whitespace() {
            i += 1;
        } else if ch.is_ascii_digit()
            || (ch == '.' && c.get(i + 1).is_some_and(|d| d.is_ascii_digit()))
        {
            let start = i;
            while i < c.len() && (c[i].is_ascii_digit() || c[i] == '.') {
                i += 1;
            }
            if i < c.len() && (c[i] == 'e' || c[i] == 'E') {
                let save = i;
                i += 1;
                if i < c.len() && (c[i] == '+' || c[i] == '-') {
                    i += 1;
                }
                if i < c.len() && c[i].is_ascii_digit() {
                    while i < c.len() && c[i].is_ascii_digit() {
                        i += 1;
                    }
                } else {
                    i = save;
                }
            }
            let s: String = c[start..i].iter().collect();
            let x: f64 = s.parse().map_err(|_| format!("`{s}` is not a number"))?;
            out.push(Tok::Num(x));
        } else if ch.is_alphabetic() || ch == '_' {
            let start = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_' || c[i] == '.') {
                i += 1;
            }
            out.push(Tok::Name(c[start..i].iter().collect()));
        } else if ch == '`' {
            // A column whose name has other characters: `my-wall.fx`.
            let end = c[i + 1..]
                .iter()
                .position(|&x| x == '`')
                .ok_or("a column name opened with ` is not closed")?;
            out.push(Tok::Name(c[i + 1..i + 1 + end].iter().collect()));
            i += end + 2;
        } else if "+-*/^(),".contains(ch) {
            out.push(Tok::Op(ch));
            i += 1;
        } else {
            return Err(format!("unexpected character `{ch}`"));
        }
    }
    if out.is_empty() {
        return Err("expected an expression".into());
    }
    Ok(out)
}

struct Parser<'a> {
    toks: &'a [Tok],
    at: usize,
}

impl Parser<'_> {
    fn peek(&self) -> Option<&Tok> {
        self.toks.get(self.at)
    }
    fn eat(&mut self, op: char) -> bool {
        if self.peek() == Some(&Tok::Op(op)) {
            self.at += 1;
            true
        } else {
            false
        }
    }
    fn sum(&mut self) -> Result<Expr, String> {
        let mut e = self.product()?;
        loop {
            let op = match self.peek() {
                Some(Tok::Op(c)) if *c == '+' || *c == '-' => *c,
                _ => return Ok(e),
            };
            self.at += 1;
            e = Expr::Bin(op, Box::new(e), Box::new(self.product()?));
        }
    }
    fn product(&mut self) -> Result<Expr, String> {
        let mut e = self.unary()?;
        loop {
            let op = match self.peek() {
                Some(Tok::Op(c)) if *c == '*' || *c == '/' => *c,
                _ => return Ok(e),
            };
            self.at += 1;
            e = Expr::Bin(op, Box::new(e), Box::new(self.unary()?));
        }
    }
    fn unary(&mut self) -> Result<Expr, String> {
        if self.eat('-') {
            return Ok(Expr::Neg(Box::new(self.unary()?)));
        }
        if self.eat('+') {
            return self.unary();
        }
        let base = self.atom()?;
        if self.eat('^') {
            return Ok(Expr::Bin('^', Box::new(base), Box::new(self.unary()?)));
        }
        Ok(base)
    }
    fn atom(&mut self) -> Result<Expr, String> {
        let t = self
            .peek()
            .cloned()
            .ok_or("the expression ends where a value is expected")?;
        self.at += 1;
        match t {
            Tok::Num(x) => Ok(Expr::Num(x)),
            Tok::Op('(') => {
                let e = self.sum()?;
                if !self.eat(')') {
                    return Err("expected `)`".into());
                }
                Ok(e)
            }
            Tok::Name(n) if self.peek() == Some(&Tok::Op('(')) => {
                self.at += 1;
                let Some(&(_, lo, hi)) = FUNCTIONS.iter().find(|f| f.0 == n) else {
                    return Err(format!(
                        "unknown function `{n}` (known: {})",
                        FUNCTIONS.map(|f| f.0).join(", ")
                    ));
                };
                let mut args = vec![self.sum()?];
                while self.eat(',') {
                    args.push(self.sum()?);
                }
                if !self.eat(')') {
                    return Err(format!("expected `)` closing `{n}(`"));
                }
                if args.len() < lo || args.len() > hi {
                    return Err(format!(
                        "`{n}` takes {lo}{} arguments, got {}",
                        if hi > lo {
                            format!(" to {hi}")
                        } else {
                            String::new()
                        },
                        args.len()
                    ));
                }
                Ok(Expr::Call(n, args))
            }
            Tok::Name(n) => Ok(Expr::Col(n)),
            Tok::Op(c) => Err(format!("unexpected `{c}` where a value is expected")),
        }
    }
}

impl Expr {
    /// The history columns it reads.
    pub fn columns(&self) -> Vec<&str> {
        let mut out = Vec::new();
        self.collect(&mut out);
        out
    }
    fn collect<'a>(&'a self, out: &mut Vec<&'a str>) {
        match self {
            Expr::Num(_) => {}
            Expr::Col(c) => out.push(c),
            Expr::Neg(e) => e.collect(out),
            Expr::Bin(_, a, b) => {
                a.collect(out);
                b.collect(out);
            }
            Expr::Call(_, args) => args.iter().for_each(|a| a.collect(out)),
        }
    }

    /// Its value with each column's value given by `col`.
    pub fn eval(&self, col: &dyn Fn(&str) -> f64) -> f64 {
        match self {
            Expr::Num(x) => *x,
            Expr::Col(c) => col(c),
            Expr::Neg(e) => -e.eval(col),
            Expr::Bin(op, a, b) => {
                let (x, y) = (a.eval(col), b.eval(col));
                match op {
                    '+' => x + y,
                    '-' => x - y,
                    '*' => x * y,
                    '/' => x / y,
                    _ => x.powf(y),
                }
            }
            Expr::Call(f, args) => {
                let v: Vec<f64> = args.iter().map(|a| a.eval(col)).collect();
                match f.as_str() {
                    "abs" => v[0].abs(),
                    "sqrt" => v[0].sqrt(),
                    "hypot" => v.iter().map(|x| x * x).sum::<f64>().sqrt(),
                    "min" => v.iter().copied().fold(f64::INFINITY, f64::min),
                    _ => v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                }
            }
        }
    }
}

/// The columns `defs` read that the history has not: `(quantity index, column)`.
pub fn missing_columns(defs: &[QuantityDef], header: &[String]) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for (i, d) in defs.iter().enumerate() {
        for c in d.expr.columns() {
            if !header.iter().any(|h| h == c) {
                out.push((i, c.to_string()));
            }
        }
    }
    out
}

/// Every quantity's value over the history `rows` (columns named by `header`; `time` is
/// one of them).
pub fn evaluate(defs: &[QuantityDef], header: &[String], rows: &[Vec<f64>]) -> Vec<QuantityValue> {
    let index = |name: &str| header.iter().position(|h| h == name);
    let t_col = index("time");
    defs.iter()
        .map(|d| {
            let at_row = |r: &[f64]| d.expr.eval(&|c| index(c).map_or(f64::NAN, |i| r[i]));
            let values = rows.iter().map(|r| at_row(r));
            let value = match d.when {
                When::Last => rows.last().map(|r| at_row(r)),
                When::Max => values.reduce(f64::max),
                When::Min => values.reduce(f64::min),
                When::MaxAbs => values.map(f64::abs).reduce(f64::max),
                When::At(t) => t_col.and_then(|ti| {
                    let k = rows
                        .iter()
                        .position(|r| r[ti] >= t - 1e-9 * t.abs().max(1e-300))?;
                    let v1 = at_row(&rows[k]);
                    if (rows[k][ti] - t).abs() <= 1e-9 * t.abs().max(1e-300) {
                        return Some(v1);
                    }
                    if k == 0 {
                        // Before the first row written: not in the history.
                        return None;
                    }
                    let (t0, t1) = (rows[k - 1][ti], rows[k][ti]);
                    let v0 = at_row(&rows[k - 1]);
                    Some(v0 + (v1 - v0) * (t - t0) / (t1 - t0))
                }),
            }
            .filter(|v| v.is_finite());
            let error = match (value, d.reference) {
                (Some(v), Some(r)) if r != 0.0 => Some((v - r) / r.abs()),
                (Some(v), Some(_)) => Some(v),
                _ => None,
            };
            QuantityValue {
                name: d.name.clone(),
                description: d.description.clone(),
                value,
                reference: d.reference,
                error,
                tolerance: d.tolerance,
                within: match (error, d.tolerance) {
                    (Some(e), Some(tol)) => Some(e.abs() <= tol),
                    _ => None,
                },
            }
        })
        .collect()
}

/// One line per quantity for the end of a run.
pub fn report(values: &[QuantityValue]) -> Vec<String> {
    values
        .iter()
        .map(|q| {
            let v = q.value.map_or("not reached".into(), |v| format!("{v:.6e}"));
            let mut s = format!("quantity {} = {v}", q.name);
            if let Some(r) = q.reference {
                s.push_str(&format!(" (reference {r:.6e}"));
                // Against a reference of 0 the error and the tolerance are absolute.
                let abs = r == 0.0;
                if let Some(e) = q.error {
                    s.push_str(&if abs {
                        format!(", error {e:.3e}")
                    } else {
                        format!(", error {} %", signed_percent(e))
                    });
                }
                if let Some(t) = q.tolerance {
                    s.push_str(&if abs {
                        format!(", tolerance {t:.1e}")
                    } else {
                        format!(", tolerance {} %", percent(t))
                    });
                }
                s.push(')');
                if let Some(w) = q.within {
                    s.push_str(if w {
                        ": within"
                    } else {
                        ": OUTSIDE the tolerance"
                    });
                }
            }
            s
        })
        .collect()
}

/// A tolerance as a percentage the way a person writes it: 0.01 %, 2.5 %, 1e-4 %
/// (not 0.00009999999999999999 %).
fn percent(t: f64) -> String {
    let p = 100.0 * t;
    if p != 0.0 && p.abs() < 1e-3 {
        return format!("{p:.0e}");
    }
    let s = format!("{p:.6}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// An error as a signed percentage: three decimals, or two digits of exponent below
/// 0.001 % (not "-0.000 %" for an error of 1e-9).
fn signed_percent(e: f64) -> String {
    let p = 100.0 * e;
    if p != 0.0 && p.abs() < 1e-3 {
        format!("{p:+.1e}")
    } else {
        format!("{p:+.3}")
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn errors_print_with_their_sign_and_size() {
        assert_eq!(super::signed_percent(-1.2e-9), "-1.2e-7");
        assert_eq!(super::signed_percent(0.01234), "+1.234");
        assert_eq!(super::signed_percent(0.0), "+0.000");
    }

    #[test]
    fn tolerances_print_as_written() {
        assert_eq!(super::percent(1e-6), "1e-4");
        assert_eq!(super::percent(0.01), "1");
        assert_eq!(super::percent(0.025), "2.5");
        assert_eq!(super::percent(1e-4), "0.01");
        assert_eq!(super::percent(0.0), "0");
    }

    use super::*;

    fn q(expr: &str, when: When, reference: Option<f64>, tol: Option<f64>) -> QuantityDef {
        QuantityDef {
            name: "q".into(),
            text: expr.into(),
            expr: parse(expr).unwrap(),
            when,
            reference,
            tolerance: tol,
            description: String::new(),
        }
    }

    #[test]
    fn expressions_parse_and_evaluate() {
        let vals = |c: &str| match c {
            "wall.fx" => 3.0,
            "wall.fz" => -4.0,
            "ball.pole.x" => 2.0,
            _ => f64::NAN,
        };
        for (text, want) in [
            ("-wall.fz", 4.0),
            ("hypot(wall.fx, wall.fz)", 5.0),
            ("abs(wall.fz) / wall.fx * 3", 4.0),
            ("2 ^ 3 ^ 2", 512.0),
            ("-(1 + 2) * 2", -6.0),
            ("max(1, ball.pole.x, 1.5e-1)", 2.0),
            ("sqrt(16) - min(3, 2)", 2.0),
            ("1e3 + .5", 1000.5),
            ("`wall.fx` * 2", 6.0),
        ] {
            let e = parse(text).unwrap_or_else(|e| panic!("{text}: {e}"));
            assert_eq!(e.eval(&vals), want, "{text}");
        }
        assert_eq!(parse("a.fx + 2 * b").unwrap().columns(), vec!["a.fx", "b"]);
        for (bad, says) in [
            ("", "expected an expression"),
            ("1 +", "ends where a value is expected"),
            ("(1", "expected `)`"),
            ("foo(1)", "unknown function `foo`"),
            ("hypot(1)", "takes 2 to 3 arguments"),
            ("1 2", "unexpected `2`"),
            ("a $ b", "unexpected character `$`"),
        ] {
            let e = parse(bad).unwrap_err();
            assert!(e.contains(says), "{bad}: {e}");
        }
    }

    #[test]
    fn quantities_at_a_time_and_over_the_run() {
        let header: Vec<String> = ["step", "time", "w.fz"].map(String::from).to_vec();
        let rows = vec![
            vec![1.0, 0.5, -1.0],
            vec![2.0, 1.0, -3.0],
            vec![3.0, 2.0, 2.0],
        ];
        let v = evaluate(
            &[
                q("-w.fz", When::At(0.75), Some(2.0), Some(0.01)),
                q("w.fz", When::Max, None, None),
                q("w.fz", When::MaxAbs, Some(3.3), Some(0.05)),
                q("w.fz", When::Last, None, None),
                q("w.fz", When::At(5.0), Some(1.0), None),
            ],
            &header,
            &rows,
        );
        assert_eq!(v[0].value, Some(2.0));
        assert_eq!(v[0].within, Some(true));
        assert_eq!(v[1].value, Some(2.0));
        assert_eq!(v[2].value, Some(3.0));
        assert!((v[2].error.unwrap() + 0.3 / 3.3).abs() < 1e-15);
        assert_eq!(v[2].within, Some(false));
        assert_eq!(v[3].value, Some(2.0));
        assert_eq!(v[4].value, None, "beyond the run");
        let before = evaluate(&[q("w.fz", When::At(0.1), None, None)], &header, &rows[1..]);
        assert_eq!(before[0].value, None, "before the first row");
        assert!(report(&v)[4].contains("not reached"));
        assert!(report(&v)[2].contains("OUTSIDE"));
        let missing = missing_columns(&[q("a.fz + w.fz", When::Last, None, None)], &header);
        assert_eq!(missing, vec![(0, "a.fz".to_string())]);
    }
}
