//! Small numerical helpers shared by several stages.

/// The root of `a`'s set in a union-find forest (`parent[r] == r` at a root; a set is joined to
/// another by pointing its root at the other's), halving the path on the way: every node
/// visited then points to its grandparent, so later searches are short.
pub fn union_find_root(parent: &mut [usize], mut a: usize) -> usize {
    while parent[a] != a {
        parent[a] = parent[parent[a]];
        a = parent[a];
    }
    a
}

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

/// Order of convergence p observed from three solutions at spacings h1 > h2 > h3 with an
/// error C h^p: `d1` is the difference between the first two, `d2` between the last two,
/// `coarse_ratio` = h1 / h2, `fine_ratio` = h2 / h3. Then d1 / d2 = (c^p - 1) k^p / (k^p - 1),
/// which grows with p from ln c / ln k (equal ratios: d1 / d2 = k^p). `None` where d1 / d2 is
/// not above that (the difference does not fall with the spacing) or is not a number; at most
/// 16.
pub fn observed_order(d1: f64, d2: f64, coarse_ratio: f64, fine_ratio: f64) -> Option<f64> {
    let (c, k) = (coarse_ratio, fine_ratio);
    let ratio_at = |p: f64| (c.powf(p) - 1.0) * k.powf(p) / (k.powf(p) - 1.0);
    let wanted = d1 / d2;
    if !wanted.is_finite() || wanted <= c.ln() / k.ln() {
        return None;
    }
    // Bisection: the ratio is monotonic in p; 60 halvings reach f64's resolution.
    let (mut lo, mut hi) = (0.0, 16.0);
    if ratio_at(hi) <= wanted {
        return Some(hi);
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if ratio_at(mid) < wanted {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

#[cfg(test)]
mod tests {
    #[test]
    fn finds_the_minimum_of_a_parabola() {
        let (x, fx) = super::golden_section_min(|x| (x - 0.3) * (x - 0.3) + 1.0, -1.0, 2.0, 200, 1e-12);
        assert!((x - 0.3).abs() < 1e-6 && (fx - 1.0).abs() < 1e-12);
    }

    #[test]
    fn union_find_roots_name_the_components_and_shorten_the_paths() {
        use super::union_find_root;
        // A chain 9 -> 8 -> ... -> 0, and 10 -> 11 on its own.
        let mut parent: Vec<usize> = (0..12).map(|k| if k > 0 && k < 10 { k - 1 } else { k }).collect();
        parent[10] = 11;
        assert_eq!(union_find_root(&mut parent, 9), 0);
        // Halved: 9 -> 7 -> 5 -> 3 -> 1 -> 0, each visited node pointing two up the old chain.
        assert_eq!(&parent[..10], &[0, 0, 1, 1, 3, 3, 5, 5, 7, 7]);
        assert_eq!(union_find_root(&mut parent, 10), 11);
        let roots: Vec<usize> = (0..12).map(|k| union_find_root(&mut parent, k)).collect();
        assert_eq!(roots, [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 11, 11]);
    }
}
