//! Local refinement: a compass (pattern) search over the seed's plane coordinates and the ply
//! angle. From the start it polls a step either way along each varied coordinate, moves to the
//! best poll that improves and halves the steps when none does, until the steps are small or
//! the evaluations run out. It needs no derivatives (the objective is a drape's largest shear,
//! which has kinks), and each round's polls are independent drapes evaluated together.
use std::collections::HashMap;

/// A poll must improve the objective by more than this (relative, with a floor of the same
/// absolute amount) to move the search: rounding does not move it.
const IMPROVEMENT: f64 = 1e-9;

/// What the search varies and how far.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pattern {
    /// The first steps along each coordinate (seed a, seed b in m; angle in degrees); a
    /// coordinate with a zero step is not varied.
    pub steps: [f64; 3],
    /// The search stops when every varied step is below its first step times this.
    pub shrink_to: f64,
    /// Most evaluations, the start's included.
    pub budget: usize,
}

/// Where a search ended.
#[derive(Debug, Clone, PartialEq)]
pub struct Refined {
    /// The best point found and its objective.
    pub best: ([f64; 3], f64),
    /// Every point evaluated and its objective (`None`: outside the region or no drape), in
    /// the order evaluated.
    pub trail: Vec<([f64; 3], Option<f64>)>,
}

/// Minimise from `start` (whose objective is `start_value`). `evaluate` gives the objectives of
/// a batch of points (`None` where a point is not a feasible placement), in order; it is asked
/// each point once.
pub fn pattern_search(
    start: [f64; 3],
    start_value: f64,
    p: &Pattern,
    mut evaluate: impl FnMut(&[[f64; 3]]) -> Vec<Option<f64>>,
) -> Refined {
    let key = |x: &[f64; 3]| x.map(f64::to_bits);
    let mut seen: HashMap<[u64; 3], Option<f64>> = HashMap::from([(key(&start), Some(start_value))]);
    let mut trail = vec![(start, Some(start_value))];
    let (mut x, mut fx) = (start, start_value);
    let mut steps = p.steps;
    let small = |s: &[f64; 3]| s.iter().zip(&p.steps).all(|(s, s0)| *s0 == 0.0 || *s < s0 * p.shrink_to);
    while !small(&steps) && trail.len() < p.budget {
        // Polls in a fixed order (+a, -a, +b, -b, +angle, -angle): ties go to the first.
        let polls: Vec<[f64; 3]> = (0..3)
            .filter(|k| p.steps[*k] > 0.0)
            .flat_map(|k| {
                [1.0, -1.0].map(|sign| {
                    let mut y = x;
                    y[k] += sign * steps[k];
                    y
                })
            })
            .collect();
        let fresh: Vec<[f64; 3]> = polls.iter().filter(|y| !seen.contains_key(&key(y))).copied().collect();
        let fresh: Vec<[f64; 3]> = fresh.into_iter().take(p.budget - trail.len()).collect();
        for (y, f) in fresh.iter().zip(evaluate(&fresh)) {
            seen.insert(key(y), f);
            trail.push((*y, f));
        }
        let best =
            polls
                .iter()
                .filter_map(|y| Some((*y, (*seen.get(&key(y))?)?)))
                .reduce(|a, b| if b.1 < a.1 { b } else { a });
        match best {
            Some((y, f)) if f < fx - IMPROVEMENT * fx.abs().max(1.0) => (x, fx) = (y, f),
            _ => steps = steps.map(|s| 0.5 * s),
        }
    }
    Refined { best: (x, fx), trail }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_minimum_of_a_kinked_bowl_within_its_last_step() {
        // |a - 0.3| + 2 |b + 0.2| + 0.1 |angle - 7|: a kink at the minimum, as a largest shear has.
        let f = |x: &[f64; 3]| (x[0] - 0.3).abs() + 2.0 * (x[1] + 0.2).abs() + 0.1 * (x[2] - 7.0).abs();
        let p = Pattern { steps: [0.25, 0.25, 10.0], shrink_to: 1.0 / 64.0, budget: 500 };
        let start = [0.0, 0.0, 0.0];
        let mut asked = Vec::new();
        let r = pattern_search(start, f(&start), &p, |xs| {
            asked.extend_from_slice(xs);
            xs.iter().map(|x| Some(f(x))).collect()
        });
        let (x, fx) = r.best;
        assert!((x[0] - 0.3).abs() <= 0.25 / 64.0 && (x[1] + 0.2).abs() <= 0.25 / 64.0, "{x:?}");
        assert!((x[2] - 7.0).abs() <= 10.0 / 64.0, "{x:?}");
        assert_eq!(fx, f(&x));
        // Each point asked once.
        let mut keys: Vec<[u64; 3]> = asked.iter().map(|x| x.map(f64::to_bits)).collect();
        keys.sort();
        keys.dedup();
        assert_eq!(keys.len(), asked.len());
        assert_eq!(r.trail.len(), asked.len() + 1);
    }

    #[test]
    fn keeps_to_the_feasible_points_its_budget_and_the_varied_coordinates() {
        // The minimum of a + b lies outside the feasible a, b >= 0: the search stops at the corner.
        let f = |x: &[f64; 3]| (x[0] >= 0.0 && x[1] >= 0.0).then(|| x[0] + x[1]);
        let p = Pattern { steps: [0.5, 0.5, 0.0], shrink_to: 1e-3, budget: 1000 };
        let r = pattern_search([1.0, 1.0, 3.0], 2.0, &p, |xs| xs.iter().map(f).collect());
        assert_eq!(r.best, ([0.0, 0.0, 3.0], 0.0));
        assert!(r.trail.iter().all(|(x, _)| x[2] == 3.0), "the angle is not varied");
        let p = Pattern { budget: 4, ..p };
        let r = pattern_search([1.0, 1.0, 3.0], 2.0, &p, |xs| xs.iter().map(f).collect());
        assert_eq!(r.trail.len(), 4);
    }
}
