//! In-plane shear: per cell, at each of its four corners the shear angle
//! `gamma = pi/2 - angle(warp edge, weft edge)` with the edges oriented along +i and +j (the
//! convention of [`crate::kinematic::net::corner_shear`]), energy `(d^2 / 4) W(gamma)` per corner,
//! `(W, M, M') = shear(gamma)`.
//!
//! The angle is `theta = atan2(|u x v|, u . v)` (exact at large shear); with `a = |u|^2`,
//! `b = |v|^2`, `c = u . v`, `s = |u x v|`:
//! `d theta/du = (c/a u - v)/s`, `d theta/dv = (c/b v - u)/s`,
//! `d2 theta/du2 = (c/a) I/s + [b (u v^T + v u^T) + (2c^3/a^2 - 3bc/a) u u^T - c v v^T]/s^3`,
//! `d2 theta/dv2` likewise with u <-> v, and
//! `d2 theta/du dv = -I/s + [b u u^T + a v v^T - c (u v^T + v u^T)]/s^3`.
//! The angle is singular where the cell collapses (s = 0, shear +-90 deg).
//! Exact Hessian per corner: `(d^2/4)(M' grad gamma grad gamma^T + M hess gamma)`;
//! Convex keeps `(d^2/4) max(M', 0) grad gamma grad gamma^T` only.
use super::{EnergyTerm, Grid, HessianKind, Laws, Sink};
use crate::geometry::{Point, Vector};
use nalgebra::Matrix3;
use std::f64::consts::FRAC_PI_2;
use std::ops::Range;

/// The shear term.
pub struct Shear<'a, L: Laws + ?Sized> {
    /// The material whose shear law the term uses.
    pub material: &'a L,
}

impl<'a, L: Laws + ?Sized> Shear<'a, L> {
    /// The term for `material`.
    pub fn new(material: &'a L) -> Self {
        Shear { material }
    }
}

/// `atan2(y, x)` for `x >= 0` (the right half-plane), to within a few ulp: the Cephes `atan`
/// range reduction and rational approximation. Several times faster than libm's `atan2`.
#[inline]
#[allow(clippy::excessive_precision)]
pub fn atan2_right(y: f64, x: f64) -> f64 {
    const T3P8: f64 = 2.414_213_562_373_095_048_80; // tan(3 pi / 8)
    const MOREBITS: f64 = 6.123_233_995_736_765_886_130e-17;
    let t = y.abs();
    if t == 0.0 {
        return y; // atan2(+-0, x >= 0) = +-0
    }
    let (base, z, more) = if t > T3P8 * x {
        (FRAC_PI_2, -x / t, MOREBITS)
    } else if t <= 0.66 * x {
        (0.0, t / x, 0.0)
    } else {
        (std::f64::consts::FRAC_PI_4, (t - x) / (t + x), 0.5 * MOREBITS)
    };
    let z2 = z * z;
    let p = (((-8.750_608_600_031_904_122_785e-1 * z2 - 1.615_753_718_733_365_076_637e1) * z2
        - 7.500_855_792_314_704_667_340e1)
        * z2
        - 1.228_866_684_490_136_173_410e2)
        * z2
        - 6.485_021_904_942_025_371_773e1;
    let q = ((((z2 + 2.485_846_490_142_306_297_962e1) * z2 + 1.650_270_098_316_988_542_046e2) * z2
        + 4.328_810_604_912_902_668_951e2)
        * z2
        + 4.853_903_996_359_136_964_868e2)
        * z2
        + 1.945_506_571_482_613_964_425e2;
    let r = base + (z * (z2 * p / q) + z + more);
    if y < 0.0 {
        -r
    } else {
        r
    }
}

/// `alpha I + beta u u^T + delta v v^T + eps u v^T + zeta v u^T` from the precomputed products.
#[inline(always)]
fn combo(k: [f64; 5], uu: &Matrix3<f64>, vv: &Matrix3<f64>, uv: &Matrix3<f64>) -> Matrix3<f64> {
    let [alpha, beta, delta, eps, zeta] = k;
    let mut m = uu * beta + vv * delta + uv * eps + uv.transpose() * zeta;
    m[(0, 0)] += alpha;
    m[(1, 1)] += alpha;
    m[(2, 2)] += alpha;
    m
}

/// Position of the local block (p, q), p <= q, in the 10 upper blocks of a cell.
const UT: [[usize; 4]; 4] = [[0, 1, 2, 3], [1, 4, 5, 6], [2, 5, 7, 8], [3, 6, 8, 9]];

/// Adds `m` to the local block (p, q), or `m^T` to (q, p), keeping the upper block triangle.
#[inline(always)]
fn put(h: &mut [Matrix3<f64>; 10], p: usize, q: usize, m: &Matrix3<f64>) {
    if p <= q {
        h[UT[p][q]] += m;
    } else {
        h[UT[q][p]] += m.transpose();
    }
}

impl<'a, L: Laws + ?Sized> Shear<'a, L> {
    /// One corner of a cell over its local nodes [p00, p10, p01, p11]: the shared node `O`, the
    /// far ends `PU` of the warp edge and `PV` of the weft edge, with `u = su (x[PU] - x[O])` and
    /// `v = sv (x[PV] - x[O])` (edges oriented along +i and +j).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn corner<const O: usize, const PU: usize, const PV: usize>(
        &self,
        su: f64,
        sv: f64,
        p: &[Point; 4],
        w: f64,
        want_grad: bool,
        kind: Option<HessianKind>,
        energy: &mut f64,
        g: &mut [Vector; 4],
        h: &mut [Matrix3<f64>; 10],
    ) {
        let u = (p[PU] - p[O]) * su;
        let v = (p[PV] - p[O]) * sv;
        let a = u.norm_squared();
        let b = v.norm_squared();
        let c = u.dot(&v);
        let s = u.cross(&v).norm();
        // gamma = pi/2 - atan2(s, c) = atan2(c, s), s >= 0.
        let gamma = atan2_right(c, s);
        let (wg, m, m1) = self.material.shear(gamma);
        *energy += w * wg;
        if !(want_grad || kind.is_some()) || !(s > 1e-300 && a > 0.0 && b > 0.0) {
            return; // energy only, or a collapsed corner (no derivatives)
        }
        let t = 1.0 / s;
        let (ka, kb) = (c / a, c / b);
        // d gamma / du, d gamma / dv.
        let gu = (v - u * ka) * t;
        let gv = (u - v * kb) * t;
        if want_grad {
            let (fu, fv) = (gu * (w * m * su), gv * (w * m * sv));
            g[PU] += fu;
            g[PV] += fv;
            g[O] -= fu + fv;
        }
        let Some(kind) = kind else { return };
        let (o, pu, pv) = (O, PU, PV);
        let (c1, c0) = match kind {
            HessianKind::Exact => (w * m1, w * m),
            HessianKind::Convex => (w * m1.max(0.0), 0.0),
        };
        if c0 == 0.0 {
            // Rank one: c1 G G^T with G the gradient of gamma over (o, pu, pv).
            if c1 == 0.0 {
                return;
            }
            let (gpu, gpv) = (gu * su, gv * sv);
            let go = -(gpu + gpv);
            let (hu, hv, ho) = (gpu * c1, gpv * c1, go * c1);
            put(h, pu, pu, &(hu * gpu.transpose()));
            put(h, pv, pv, &(hv * gpv.transpose()));
            put(h, pu, pv, &(hu * gpv.transpose()));
            put(h, o, pu, &(ho * gpu.transpose()));
            put(h, o, pv, &(ho * gpv.transpose()));
            h[UT[o][o]] += ho * go.transpose();
            return;
        }
        // A = c1 grad gamma grad gamma^T + c0 hess gamma over (u, v), each block in
        // the basis (I, u u^T, v v^T, u v^T, v u^T).
        let (t2, t3) = (t * t, t * t * t);
        let au = [
            -c0 * ka * t,
            -c0 * (2.0 * c * c * c / (a * a) - 3.0 * b * c / a) * t3 + c1 * t2 * ka * ka,
            c0 * c * t3 + c1 * t2,
            -c0 * b * t3 - c1 * t2 * ka,
            -c0 * b * t3 - c1 * t2 * ka,
        ];
        let av = [
            -c0 * kb * t,
            c0 * c * t3 + c1 * t2,
            -c0 * (2.0 * c * c * c / (b * b) - 3.0 * a * c / b) * t3 + c1 * t2 * kb * kb,
            -c0 * a * t3 - c1 * t2 * kb,
            -c0 * a * t3 - c1 * t2 * kb,
        ];
        let sg = su * sv;
        let x = [
            sg * c0 * t,
            sg * (-c0 * b * t3 - c1 * t2 * ka),
            sg * (-c0 * a * t3 - c1 * t2 * kb),
            sg * (c0 * c * t3 + c1 * t2 * ka * kb),
            sg * (c0 * c * t3 + c1 * t2),
        ];
        let uu = u * u.transpose();
        let vv = v * v.transpose();
        let uv = u * v.transpose();
        let auu = combo(au, &uu, &vv, &uv);
        let avv = combo(av, &uu, &vv, &uv);
        let auv = combo(x, &uu, &vv, &uv); // sg * A_uv
        let auv_t = auv.transpose();
        let b_opu = -(auu + auv_t);
        let b_opv = -(avv + auv);
        put(h, pu, pu, &auu);
        put(h, pv, pv, &avv);
        put(h, pu, pv, &auv);
        put(h, o, pu, &b_opu);
        put(h, o, pv, &b_opv);
        h[UT[o][o]] -= b_opu + b_opv;
    }
}

impl<'a, L: Laws + ?Sized> EnergyTerm for Shear<'a, L> {
    fn name(&self) -> &'static str {
        "shear"
    }

    fn row_span(&self) -> usize {
        1
    }

    fn add(&self, grid: &Grid, x: &[Point], base: Range<usize>, sink: &mut Sink<'_>) {
        let (nu, nv) = (grid.nu, grid.nv);
        let quarter = 0.25 * grid.spacing * grid.spacing;
        let want_grad = sink.wants_gradient();
        let kind = sink.hessian_kind();
        for i in sink.element_rows(&base, 1, nu) {
            for j in 0..nv.saturating_sub(1) {
                let k = i * nv + j;
                let nodes = [k, k + nv, k + 1, k + nv + 1];
                if !grid.cell_active(i, j) {
                    continue;
                }
                let w = quarter * grid.cell_factors(i, j).shear;
                let p = [x[nodes[0]], x[nodes[1]], x[nodes[2]], x[nodes[3]]];
                let mut energy = 0.0;
                let mut g = [Vector::zeros(); 4];
                let mut h = [Matrix3::zeros(); 10];
                self.corner::<0, 1, 2>(1.0, 1.0, &p, w, want_grad, kind, &mut energy, &mut g, &mut h);
                self.corner::<1, 0, 3>(-1.0, 1.0, &p, w, want_grad, kind, &mut energy, &mut g, &mut h);
                self.corner::<2, 3, 0>(1.0, -1.0, &p, w, want_grad, kind, &mut energy, &mut g, &mut h);
                self.corner::<3, 2, 1>(-1.0, -1.0, &p, w, want_grad, kind, &mut energy, &mut g, &mut h);
                sink.add_energy(k, energy);
                if want_grad {
                    for (n, gn) in nodes.iter().zip(&g) {
                        sink.add_gradient(*n, gn);
                    }
                }
                if kind.is_some() {
                    for pa in 0..4 {
                        for pb in pa..4 {
                            sink.add_block(nodes[pa], nodes[pb], &h[UT[pa][pb]]);
                        }
                    }
                }
            }
        }
    }
}
