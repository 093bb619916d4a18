//! What an optimisation minimises: a weighted sum of a placement's layup-table figures
//! ([`CaseStats`], the numbers `drape run` puts in its table), parsed from
//! `max-shear`, `max-shear:1,coverage:0.5` and the like.
use crate::study::case::CaseStats;
use serde::{Deserialize, Serialize};

/// One figure of a draped placement an objective can weigh. Every one is minimised.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Measure {
    /// The largest |cell shear|, degrees.
    MaxShear,
    /// The draped area sheared past the ply's locking angle, m^2.
    LockedArea,
    /// The mean |cell shear|, degrees.
    MeanShear,
    /// The share of the tool (or of the ply's outline) the ply leaves uncovered, 0 to 1: the
    /// coverage, maximised.
    Coverage,
}

impl Measure {
    /// Every measure, in the order the choices are listed.
    pub const ALL: [Measure; 4] = [Measure::MaxShear, Measure::LockedArea, Measure::MeanShear, Measure::Coverage];

    /// Its name in `--objective` and in files.
    pub fn name(self) -> &'static str {
        match self {
            Measure::MaxShear => "max-shear",
            Measure::LockedArea => "locked-area",
            Measure::MeanShear => "mean-shear",
            Measure::Coverage => "coverage",
        }
    }

    /// What it counts, with its unit.
    pub fn meaning(self) -> &'static str {
        match self {
            Measure::MaxShear => "largest |shear|, deg",
            Measure::LockedArea => "area past the locking angle, m^2",
            Measure::MeanShear => "mean |shear|, deg",
            Measure::Coverage => "uncovered share (1 - coverage)",
        }
    }

    /// Its value for a draped placement (smaller is better).
    pub fn value(self, s: &CaseStats) -> f64 {
        match self {
            Measure::MaxShear => s.max_abs_shear_deg,
            Measure::LockedArea => s.area_over_locking_m2,
            Measure::MeanShear => s.mean_abs_shear_deg,
            Measure::Coverage => 1.0 - s.coverage,
        }
    }
}

/// One weighted term of an objective.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Term {
    /// The figure.
    pub measure: Measure,
    /// Its weight (positive).
    pub weight: f64,
}

/// A weighted sum of measures, minimised.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Objective {
    /// The terms, as given.
    pub terms: Vec<Term>,
}

impl Objective {
    /// Parse `NAME[:WEIGHT],...` (a weight of 1 when none is given), each name once.
    pub fn parse(text: &str) -> Result<Objective, String> {
        let names: Vec<&str> = Measure::ALL.iter().map(|m| m.name()).collect();
        let mut terms: Vec<Term> = Vec::new();
        for part in text.split(',').map(str::trim) {
            let (name, weight) = match part.split_once(':') {
                Some((n, w)) => (n.trim(), Some(w.trim())),
                None => (part, None),
            };
            let measure = Measure::ALL.into_iter().find(|m| m.name() == name).ok_or_else(|| {
                format!(
                    "--objective: unknown measure '{name}': use {} or a weighted sum like max-shear:1,coverage:0.5",
                    names.join(", ")
                )
            })?;
            let weight = match weight {
                None => 1.0,
                Some(w) => match w.parse::<f64>() {
                    Ok(x) if x.is_finite() && x > 0.0 => x,
                    _ => return Err(format!("--objective: the weight of {name} must be a positive number, got '{w}'")),
                },
            };
            if terms.iter().any(|t| t.measure == measure) {
                return Err(format!("--objective: {name} is given twice: give each measure once"));
            }
            terms.push(Term { measure, weight });
        }
        Ok(Objective { terms })
    }

    /// The objective of a draped placement.
    pub fn value(&self, s: &CaseStats) -> f64 {
        self.terms.iter().map(|t| t.weight * t.measure.value(s)).sum()
    }

    /// The objective in words: `1 x largest |shear|, deg + 0.5 x uncovered share (1 - coverage)`.
    pub fn describe(&self) -> String {
        let parts: Vec<String> = self.terms.iter().map(|t| format!("{} x {}", t.weight, t.measure.meaning())).collect();
        parts.join(" + ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stats() -> CaseStats {
        CaseStats {
            max_abs_shear_deg: 20.0,
            mean_abs_shear_deg: 4.0,
            area_over_locking_m2: 0.01,
            coverage: 0.75,
            cells: 100,
        }
    }

    #[test]
    fn weighted_sums_add_their_terms() {
        let o = Objective::parse("max-shear:1,coverage:0.5").unwrap();
        assert_eq!(o.value(&stats()), 20.0 + 0.5 * 0.25);
        assert_eq!(Objective::parse("mean-shear").unwrap().value(&stats()), 4.0);
        assert_eq!(Objective::parse(" locked-area : 100 ").unwrap().value(&stats()), 1.0);
        assert!(o.describe().contains("uncovered share"), "{}", o.describe());
    }

    #[test]
    fn bad_objectives_say_what_to_give() {
        for (text, says) in [
            ("shear", "unknown measure 'shear'"),
            ("max-shear:-1", "positive number"),
            ("max-shear:x", "positive number"),
            ("coverage,coverage:2", "given twice"),
            ("", "unknown measure ''"),
        ] {
            let e = Objective::parse(text).unwrap_err();
            assert!(e.contains(says), "{text}: {e}");
        }
    }
}
