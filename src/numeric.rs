//! Small numerical helpers shared by several stages.

/// Golden-section search for a minimum of `f` on `[lo, hi]`: at most `max_iterations` steps,
/// stopping early once the bracket is narrower than `rel_tol` times its upper end. Returns the
/// better of the final bracket's two interior points and its value.
pub fn golden_section_min(
    f: impl Fn(f64) -> f64,
    mut lo: f64,
    mut hi: f64,
    max_iterations: usize,
    rel_tol: f64,
) -> (f64, f64) {
    let r = 0.5 * (5f64.sqrt() - 1.0);
    let mut x1 = hi - r * (hi - lo);
    let mut x2 = lo + r * (hi - lo);
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..max_iterations {
        if hi - lo <= rel_tol * hi.abs().max(1e-300) {
            break;
        }
        if f1 <= f2 {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - r * (hi - lo);
            f1 = f(x1);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + r * (hi - lo);
            f2 = f(x2);
        }
    }
    if f1 <= f2 {
        (x1, f1)
    } else {
        (x2, f2)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn finds_the_minimum_of_a_parabola() {
        let (x, fx) = super::golden_section_min(|x| (x - 0.3) * (x - 0.3) + 1.0, -1.0, 2.0, 200, 1e-12);
        assert!((x - 0.3).abs() < 1e-6 && (fx - 1.0).abs() < 1e-12);
    }
}
