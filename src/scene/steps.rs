//! Analysis steps (`[[steps]]`, Abaqus `*STEP`): named intervals of the time line, in
//! order, each with its own increments. A load, prescribed motion, coupling load or bolt
//! that names a step follows its curve in that step's time (0 at the step's start) and
//! holds its last value afterwards, so "pretension, then load in X and back, then in Y
//! and back" is three steps and one curve per load, as analysts write it.
//!
//! [`Timeline`] resolves every curve a deck entry names against the steps and records
//! where the resolved curves change slope: those times and the steps' ends become the
//! stops the step controller lands on.

use super::check::{err, known, unique_names, MAX_STEPS};
use super::deck::Deck;
use crate::curve::Curve;
use crate::solve::Stage;
use crate::Result;
use std::cell::RefCell;
use std::collections::BTreeMap;

/// The deck with `analysis.end_time` filled in from its steps (their total duration),
/// checked against a given one.
pub fn with_end_time(deck: &Deck) -> Result<Deck> {
    let mut d = deck.clone();
    if deck.steps.is_empty() {
        return Ok(d);
    }
    for (i, s) in deck.steps.iter().enumerate() {
        if !(s.duration > 0.0 && s.duration.is_finite()) {
            return Err(err(
                format!("steps[{i}].duration"),
                format!("expected a positive time, got {}", s.duration),
            ));
        }
    }
    let total: f64 = deck.steps.iter().map(|s| s.duration).sum();
    let given = deck.analysis.end_time;
    if given == 0.0 {
        d.analysis.end_time = total;
    } else if (given - total).abs() > 1e-9 * total.abs().max(1.0) {
        return Err(err(
            "analysis.end_time",
            format!(
                "{given} differs from the steps' total duration {total}; leave it out with [[steps]]"
            ),
        ));
    }
    Ok(d)
}

/// The stages of the deck's steps, validated (empty without steps).
pub fn stages(deck: &Deck) -> Result<Vec<Stage>> {
    unique_names("steps", deck.steps.iter().map(|s| s.name.as_str()))?;
    let a = &deck.analysis;
    let mut start = 0.0;
    let mut out = Vec::new();
    for (i, s) in deck.steps.iter().enumerate() {
        let f = format!("steps[{i}]");
        if !(s.duration > 0.0 && s.duration.is_finite()) {
            return Err(err(
                format!("{f}.duration"),
                format!("expected a positive time, got {}", s.duration),
            ));
        }
        let step = s.step.unwrap_or(a.step);
        for (name, v) in [
            ("step", Some(step)),
            ("min_step", s.min_step),
            ("max_step", s.max_step),
        ] {
            if let Some(v) = v {
                if !(v > 0.0 && v.is_finite()) {
                    return Err(err(
                        format!("{f}.{name}"),
                        format!("expected a positive increment, got {v}"),
                    ));
                }
            }
        }
        if s.duration / step > MAX_STEPS {
            return Err(err(
                format!("{f}.step"),
                format!(
                    "{step:e} makes {:.3e} increments of the step's duration {:e}; expected at most {:.0e}",
                    s.duration / step,
                    s.duration,
                    MAX_STEPS
                ),
            ));
        }
        if s.output_every == Some(0) {
            return Err(err(format!("{f}.output_every"), "expected at least 1"));
        }
        let max_step = s.max_step.unwrap_or(step);
        let min_step = s.min_step.unwrap_or(a.min_step.unwrap_or(step * 1e-3));
        if min_step > step.min(max_step) {
            return Err(err(
                format!("{f}.min_step"),
                format!(
                    "{min_step} is above the step's increment {}",
                    step.min(max_step)
                ),
            ));
        }
        out.push(Stage {
            name: s.name.clone(),
            start,
            end: start + s.duration,
            step,
            min_step,
            max_step,
        });
        start += s.duration;
    }
    Ok(out)
}

/// Curves resolved against the steps; remembers the resolved curves' knots.
pub struct Timeline<'a> {
    pub stages: Vec<Stage>,
    curves: &'a BTreeMap<String, Curve>,
    end: f64,
    knots: RefCell<Vec<f64>>,
}

impl<'a> Timeline<'a> {
    pub fn new(stages: Vec<Stage>, curves: &'a BTreeMap<String, Curve>, end: f64) -> Self {
        Self {
            stages,
            curves,
            end,
            knots: RefCell::new(Vec::new()),
        }
    }

    /// The stage named by entry `f`'s `step` field.
    pub fn stage(&self, f: &str, name: &str) -> Result<&Stage> {
        self.stages.iter().find(|s| s.name == name).ok_or_else(|| {
            let known = if self.stages.is_empty() {
                "the deck has no [[steps]]".to_string()
            } else {
                format!(
                    "steps: {}",
                    self.stages
                        .iter()
                        .map(|s| s.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            };
            err(
                format!("{f}.step"),
                format!("unknown step `{name}` ({known})"),
            )
        })
    }

    /// The curve of entry `f` (its fields `f.curve`, `f.step`) on the analysis' time
    /// line: the named curve (default a ramp 0 → 1 over the step, or over the analysis
    /// without one), in the step's time if a step is named, held after it. A curve that
    /// starts a later step must start from 0: before its step the entry is absent.
    pub fn curve(&self, f: &str, name: &Option<String>, step: &Option<String>) -> Result<Curve> {
        let window = match step {
            Some(s) => {
                let st = self.stage(f, s)?;
                Some((st.start, st.end))
            }
            None => None,
        };
        let base = match name {
            None => Curve::ramp(window.map_or(self.end, |(a, b)| b - a)),
            Some(n) => self.lookup(&format!("{f}.curve"), n)?,
        };
        let Some((t0, t1)) = window else {
            self.record(base.points.iter().map(|p| p[0]));
            return Ok(base);
        };
        let v0 = base.eval(0.0);
        if t0 > 0.0 && v0 != 0.0 {
            return Err(err(
                format!("{f}.curve"),
                format!(
                    "the curve is {v0} at the start of step `{}`, and the entry is absent before it; start the curve from 0 (or name the first step)",
                    step.as_deref().unwrap_or_default()
                ),
            ));
        }
        let dur = t1 - t0;
        let mut taus: Vec<f64> = std::iter::once(0.0)
            .chain(
                base.points
                    .iter()
                    .map(|p| p[0])
                    .filter(|&x| x > 0.0 && x < dur),
            )
            .chain(std::iter::once(dur))
            .collect();
        taus.dedup();
        let points: Vec<[f64; 2]> = taus.iter().map(|&x| [t0 + x, base.eval(x)]).collect();
        self.record(points.iter().map(|p| p[0]));
        Ok(Curve { points })
    }

    /// The `[[curves]]` entry `name`, named at `field`, on the analysis' time line (for
    /// entries that take no step: walls' and entities' motions).
    pub fn named(&self, field: &str, name: &str) -> Result<Curve> {
        let c = self.lookup(field, name)?;
        self.record(c.points.iter().map(|p| p[0]));
        Ok(c)
    }

    fn lookup(&self, field: &str, name: &str) -> Result<Curve> {
        self.curves.get(name).cloned().ok_or_else(|| {
            err(
                field,
                format!("unknown curve `{name}` ({})", known(self.curves)),
            )
        })
    }

    /// The end of the step named by entry `f`'s field `f.step`.
    pub fn end_of(&self, f: &str, name: &str) -> Result<f64> {
        Ok(self.stage(f, name)?.end)
    }

    /// A time the steps must land on (a bolt's lock).
    pub fn mark(&self, t: f64) {
        self.knots.borrow_mut().push(t);
    }

    fn record(&self, t: impl Iterator<Item = f64>) {
        self.knots.borrow_mut().extend(t);
    }

    /// Times inside the run where a step ends or a resolved curve changes slope, sorted.
    pub fn stops(&self) -> Vec<f64> {
        let mut t: Vec<f64> = self
            .knots
            .borrow()
            .iter()
            .copied()
            .chain(self.stages.iter().map(|s| s.end))
            .filter(|&t| t > 0.0 && t < self.end && t.is_finite())
            .collect();
        t.sort_by(f64::total_cmp);
        t.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * self.end.abs().max(1.0));
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn timeline(curves: &BTreeMap<String, Curve>) -> Timeline<'_> {
        let st = |name: &str, start: f64, end: f64| Stage {
            name: name.into(),
            start,
            end,
            step: 0.5,
            min_step: 1e-3,
            max_step: 0.5,
        };
        Timeline::new(vec![st("pre", 0.0, 1.0), st("x", 1.0, 3.0)], curves, 3.0)
    }

    /// A curve named in a step runs in step time, is 0 before it and held after it; the
    /// default is a ramp over the step; the knots are stops.
    #[test]
    fn curves_run_in_their_steps_time() {
        let mut curves = BTreeMap::new();
        curves.insert(
            "updown".to_string(),
            Curve {
                points: vec![[0.0, 0.0], [1.0, 1.0], [2.0, 0.0], [5.0, 7.0]],
            },
        );
        let tl = timeline(&curves);
        let c = tl
            .curve("loads[0]", &Some("updown".into()), &Some("x".into()))
            .unwrap();
        for (t, want) in [
            (0.5, 0.0),
            (1.0, 0.0),
            (1.5, 0.5),
            (2.0, 1.0),
            (2.5, 0.5),
            (3.0, 0.0),
            (9.0, 0.0),
        ] {
            assert!((c.eval(t) - want).abs() < 1e-15, "t = {t}: {}", c.eval(t));
        }
        let r = tl.curve("loads[1]", &None, &Some("pre".into())).unwrap();
        assert_eq!((r.eval(0.5), r.eval(1.0), r.eval(2.0)), (0.5, 1.0, 1.0));
        let whole = tl.curve("loads[2]", &None, &None).unwrap();
        assert_eq!(whole.eval(1.5), 0.5);
        assert_eq!(tl.stops(), vec![1.0, 2.0]);
    }

    #[test]
    fn mistakes_name_their_field() {
        let mut curves = BTreeMap::new();
        curves.insert("one".to_string(), Curve::constant(1.0));
        let tl = timeline(&curves);
        let e = tl.curve("loads[3]", &None, &Some("y".into())).unwrap_err();
        assert!(
            e.to_string().contains("loads[3].step") && e.to_string().contains("pre, x"),
            "{e}"
        );
        let e = tl
            .curve("loads[4]", &Some("one".into()), &Some("x".into()))
            .unwrap_err();
        assert!(
            e.to_string().contains("loads[4].curve") && e.to_string().contains("from 0"),
            "{e}"
        );
        let e = tl
            .curve("loads[5]", &Some("none".into()), &None)
            .unwrap_err();
        assert!(e.to_string().contains("loads[5].curve"), "{e}");
        // In the first step a curve may start anywhere.
        assert!(tl
            .curve("loads[6]", &Some("one".into()), &Some("pre".into()))
            .is_ok());
    }
}
