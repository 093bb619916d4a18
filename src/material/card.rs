//! A material card: areal mass, thickness, the tension, shear and bending laws ([`super::laws`])
//! and the optional flow properties, with the physical checks every card passes. Cards are read
//! from and written to TOML by [`super::card_toml`].
use super::flow::VF_MAX_HEX;
use super::laws::{Bending, Fibre, KnitParams, ShearLaw, Tension, TensionLaw};

/// Shear past a card's calibrated range by less than this (deg) is within it: a drape or test
/// run to the calibrated angle itself lands a little past it.
pub const SHEAR_RANGE_TOLERANCE_DEG: f64 = 0.05;

/// Why a material card could not be read or used. The message names the card, the line and
/// the field at fault, and what is expected.
#[derive(Debug, thiserror::Error)]
pub enum MaterialError {
    /// What is wrong, naming the card, line and field.
    #[error("{0}")]
    Invalid(String),
}

/// A fabric material card (SI units).
#[derive(Debug, Clone, PartialEq)]
pub struct MaterialCard {
    /// The card's name.
    pub name: String,
    /// kg/m^2
    pub areal_mass: f64,
    /// m
    pub thickness: f64,
    /// Where the numbers come from (a citation, or the calibration that produced them).
    pub source: Option<String>,
    /// Fibre stretching, per family.
    pub tension: Tension,
    /// In-plane shear.
    pub shear: ShearLaw,
    /// The largest shear angle (deg) the shear law was calibrated to (`[shear]
    /// calibrated_max_deg`, written by `drape calibrate`): beyond it the law is extrapolated, and
    /// what uses it there says so ([`Self::shear_range_warning`]). `None`: not recorded.
    pub shear_calibrated_max_deg: Option<f64>,
    /// Flexural rigidities per unit width, N m.
    pub bending: Bending,
    /// What resin-flow exports need (optional `[flow]` section).
    pub flow: Option<FlowProperties>,
    /// Coulomb's coefficient of friction of the fabric on a tool (optional `[contact]`
    /// section, `friction = MU`): the default of mechanical plies made of it.
    pub friction: Option<f64>,
}

/// The optional `[flow]` section: what resin-flow exports need of the fabric.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlowProperties {
    /// Fibre volume fraction of the ply as laid flat at its `thickness`.
    pub fibre_volume_fraction: f64,
    /// Fibre (filament) radius, m, for the permeability model.
    pub fibre_radius: f64,
}

impl MaterialCard {
    /// Check a card built in code (the same physical checks as [`Self::load`]).
    pub fn validate(&self) -> Result<(), MaterialError> {
        self.check()
            .map_err(|(f, m)| MaterialError::Invalid(format!("material card '{}', field `{f}`: {m}", self.name)))
    }

    /// The physical checks. Err((field, message)).
    pub(crate) fn check(&self) -> Result<(), (String, String)> {
        let positive = |f: &str, v: f64, unit: &str| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err((f.to_string(), format!("must be positive ({unit}), got {v}")))
            }
        };
        if self.name.trim().is_empty() {
            return Err(("name".into(), "must not be empty".into()));
        }
        positive("areal_mass", self.areal_mass, "kg/m^2")?;
        positive("thickness", self.thickness, "m")?;
        if let Some(f) = &self.flow {
            let vf = f.fibre_volume_fraction;
            if !(vf > 0.0 && vf < VF_MAX_HEX) {
                return Err((
                    "flow.fibre_volume_fraction".into(),
                    format!("must lie between 0 and {:.4} (fibres touching), got {vf}", VF_MAX_HEX),
                ));
            }
            positive("flow.fibre_radius", f.fibre_radius, "m")?;
        }
        if let Some(mu) = self.friction {
            if !(mu.is_finite() && mu >= 0.0) {
                return Err(("contact.friction".into(), format!("must be a finite number >= 0, got {mu}")));
            }
        }
        let cf = self.tension.compression_factor;
        if !(cf.is_finite() && (0.0..=1.0).contains(&cf)) {
            return Err((
                "tension.compression_factor".into(),
                format!("must lie in [0, 1] (it scales the rigidity in compression), got {cf}"),
            ));
        }
        match self.tension.law {
            TensionLaw::Linear { warp, weft } => {
                positive("tension.warp", warp, "tensile rigidity, N/m")?;
                positive("tension.weft", weft, "tensile rigidity, N/m")?;
            }
            TensionLaw::Knit { warp, weft } => {
                for (fibre, k) in [("warp", warp), ("weft", weft)] {
                    positive(&format!("tension.{fibre}.C"), k.c, "low-strain rigidity, N/m")?;
                    for (f, v) in [("beta", k.beta), ("alpha", k.alpha)] {
                        if !(v.is_finite() && v >= 0.0) {
                            return Err((
                                format!("tension.{fibre}.{f}"),
                                format!("must be a finite number >= 0, got {v}"),
                            ));
                        }
                    }
                }
            }
        }
        self.shear.check()?;
        if let Some(a) = self.shear_calibrated_max_deg {
            if !(a > 0.0 && a <= 90.0) {
                return Err((
                    "shear.calibrated_max_deg".into(),
                    format!("must lie in (0, 90] degrees (the largest shear angle of the calibration), got {a}"),
                ));
            }
        }
        positive("bending.warp", self.bending.warp, "flexural rigidity, N m")?;
        positive("bending.weft", self.bending.weft, "flexural rigidity, N m")?;
        Ok(())
    }

    /// Stretch energy per unit reference length and unit width of a fibre family at Green strain
    /// `e`: (W, dW/de, d2W/de2), in N/m (dW/de is the fibre tension per unit width).
    pub fn tension(&self, fibre: Fibre, e: f64) -> (f64, f64, f64) {
        let cf = self.tension.compression_factor;
        let linear = |d: f64| {
            let d = if e < 0.0 { cf * d } else { d };
            (0.5 * d * e * e, d * e, d)
        };
        match (self.tension.law, fibre) {
            (TensionLaw::Linear { warp, .. }, Fibre::Warp) | (TensionLaw::Linear { weft: warp, .. }, Fibre::Weft) => {
                linear(warp)
            }
            (TensionLaw::Knit { warp: k, .. }, Fibre::Warp) | (TensionLaw::Knit { weft: k, .. }, Fibre::Weft) => {
                if e < 0.0 {
                    linear(k.c)
                } else {
                    k.stretch(e)
                }
            }
        }
    }

    /// In-plane shear energy per unit area at shear angle `g` (radians, signed):
    /// (W, M = dW/dg, dM/dg), W in J/m^2 and M the shear moment per unit area in N/m.
    pub fn shear(&self, g: f64) -> (f64, f64, f64) {
        self.shear.eval(g)
    }

    /// Give `fibre` the knit tension law `p`. A linear card becomes a knit card in which the other
    /// family keeps its rigidity (as C, with beta = 0).
    pub fn set_knit(&mut self, fibre: Fibre, p: KnitParams) {
        let (mut warp, mut weft) = match self.tension.law {
            TensionLaw::Knit { warp, weft } => (warp, weft),
            TensionLaw::Linear { warp, weft } => {
                (KnitParams { c: warp, beta: 0.0, alpha: 0.0 }, KnitParams { c: weft, beta: 0.0, alpha: 0.0 })
            }
        };
        match fibre {
            Fibre::Warp => warp = p,
            Fibre::Weft => weft = p,
        }
        self.tension.law = TensionLaw::Knit { warp, weft };
    }

    /// Add `note` (where a fitted law came from) to the card's source, after what it says.
    pub fn add_source_note(&mut self, note: String) {
        self.source = Some(match self.source.take() {
            Some(s) if !s.trim().is_empty() => format!("{s}; {note}"),
            _ => note,
        });
    }

    /// A warning when a use of the shear law reaches `max_shear_deg`, more than
    /// [`SHEAR_RANGE_TOLERANCE_DEG`] past the angle the law was calibrated to; `None` within it
    /// or when the card records no range.
    pub fn shear_range_warning(&self, max_shear_deg: f64) -> Option<String> {
        let cal = self.shear_calibrated_max_deg?;
        (max_shear_deg > cal + SHEAR_RANGE_TOLERANCE_DEG).then(|| {
            format!(
                "shear reaches {max_shear_deg:.1} deg, beyond the {cal:.1} deg that the shear law of material card '{}' was calibrated to: past it the law is an extrapolation",
                self.name
            )
        })
    }

    /// Flexural rigidity per unit width of a fibre family, N m.
    pub fn bending(&self, fibre: Fibre) -> f64 {
        match fibre {
            Fibre::Warp => self.bending.warp,
            Fibre::Weft => self.bending.weft,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::laws::ShearTable;
    use std::path::Path;

    /// 1 gf in newtons.
    const GF: f64 = 9.80665e-3;

    fn card_with(tension: &str, shear: &str) -> String {
        format!(
            "name = \"t\"\nareal_mass = 0.3\nthickness = 5.0e-4\n\n[tension]\n{tension}\n\n[shear]\n{shear}\n\n\
             [bending]\nwarp = 1.0e-7\nweft = 2.0e-7\n"
        )
    }

    fn parse(text: &str) -> Result<MaterialCard, String> {
        MaterialCard::parse(text, "test.toml").map_err(|e| e.to_string())
    }

    const LINEAR: &str = "law = \"linear\"\nwarp = 2.0e5\nweft = 1.0e5";
    const KNIT: &str = "law = \"knit\"\n[tension.warp]\nC = 500.0\nbeta = 10.0\nalpha = 2.5\n\
                        [tension.weft]\nc = 120\nbeta = 20.0\nalpha = 1.2";
    const POLY: &str = "law = \"polynomial\"\ncoefficients = [0.5, 2.0, 3.0]";
    const TWO: &str = "law = \"two-slope\"\ng1 = 2.0\ng2 = 200.0\nlocking_angle_deg = 35.0";
    const TABLE: &str =
        "law = \"table\"\nangles_deg = [10.0, 20.0, 30.0, 40.0, 50.0]\nmoments = [0.2, 0.5, 1.1, 3.0, 12.0]";

    fn all_cards() -> Vec<MaterialCard> {
        let mut v = Vec::new();
        for t in [LINEAR, KNIT, "law = \"linear\"\ncompression_factor = 0.05\nwarp = 3.0e5\nweft = 1.0e5"] {
            for s in [POLY, TWO, TABLE] {
                v.push(parse(&card_with(t, s)).unwrap());
            }
        }
        let mut k = parse(&card_with(KNIT, TWO)).unwrap();
        k.tension.compression_factor = 0.1;
        v.push(k);
        v
    }

    /// Central difference of f at x with step h.
    fn fd(f: impl Fn(f64) -> f64, x: f64, h: f64) -> f64 {
        (f(x + h) - f(x - h)) / (2.0 * h)
    }

    /// The integral of `f` from 0 to `end` by Simpson's rule on `n` (even) intervals.
    fn simpson(f: impl Fn(f64) -> f64, end: f64, n: usize) -> f64 {
        let h = end / n as f64;
        let weight = |i: usize| {
            if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            }
        };
        (0..=n).map(|i| weight(i) * f(i as f64 * h)).sum::<f64>() * h / 3.0
    }

    fn close(a: f64, b: f64, rel: f64, abs: f64) -> bool {
        (a - b).abs() <= rel * a.abs().max(b.abs()) + abs
    }

    #[test]
    fn tension_derivatives_are_exact() {
        for card in all_cards() {
            for fibre in [Fibre::Warp, Fibre::Weft] {
                let t = |e: f64| card.tension(fibre, e);
                let mut strains: Vec<f64> = (-40..=40).map(|i| i as f64 * 0.0095 + 0.0003).collect();
                if let TensionLaw::Knit { warp, weft } = card.tension.law {
                    let k = if fibre == Fibre::Warp { warp } else { weft };
                    let lim = k.stretch_limit();
                    // Near the singularity and on the continuation.
                    strains.extend([0.9, 0.99, 0.9985, 1.002, 1.5, 3.0].map(|s| s * lim));
                }
                let sing = match card.tension.law {
                    TensionLaw::Knit { warp, weft } => 1.0 / if fibre == Fibre::Warp { warp.alpha } else { weft.alpha },
                    _ => f64::INFINITY,
                };
                for &e in &strains {
                    let (w, dw, d2w) = t(e);
                    assert!(w.is_finite() && dw.is_finite() && d2w.is_finite());
                    // A step well inside the distance to 0 (the compression kink) and to 1/alpha.
                    let h = 1e-5 * e.abs().max(1e-3).min((sing - e).abs());
                    let fd1 = fd(|x| t(x).0, e, h);
                    let fd2 = fd(|x| t(x).1, e, h);
                    assert!(close(fd1, dw, 1e-6, 1e-12 * (1.0 + w.abs() / h)), "{fibre:?} e={e}: dW {fd1} vs {dw}");
                    assert!(close(fd2, d2w, 1e-6, 1e-12 * (1.0 + dw.abs() / h)), "{fibre:?} e={e}: d2W {fd2} vs {d2w}");
                }
                assert_eq!(t(0.0), (0.0, 0.0, t(0.0).2));
            }
        }
    }

    #[test]
    fn shear_derivatives_are_exact_and_odd() {
        for card in all_cards() {
            let kink = match &card.shear {
                ShearLaw::TwoSlope { locking_angle_deg, .. } => Some(locking_angle_deg.to_radians()),
                _ => None,
            };
            let knots: Vec<f64> = match &card.shear {
                ShearLaw::Table(t) => t.x.clone(),
                _ => vec![],
            };
            for i in -150..=150 {
                let g = i as f64 * 0.0105 + 0.0001;
                let h = 1e-6;
                // d2W (dM/dg) jumps at the two-slope kink and is only C0 at table knots: skip them.
                if kink.is_some_and(|k| (g.abs() - k).abs() < 3.0 * h)
                    || knots.iter().any(|k| (g.abs() - k).abs() < 3.0 * h)
                {
                    continue;
                }
                let (w, m, k) = card.shear(g);
                assert!(close(fd(|x| card.shear(x).0, g, h), m, 1e-7, 1e-9), "{} g={g}: M", card.shear.law_name());
                assert!(close(fd(|x| card.shear(x).1, g, h), k, 1e-6, 1e-8), "{} g={g}: dM", card.shear.law_name());
                let (w2, m2, k2) = card.shear(-g);
                assert!(close(w, w2, 1e-14, 0.0) && close(m, -m2, 1e-14, 0.0) && close(k, k2, 1e-14, 0.0));
                assert!(w >= 0.0 && m * g >= 0.0);
            }
            // Near the kink, on each side.
            if let Some(gl) = kink {
                for g in [gl - 1e-4, gl + 1e-4, gl - 1e-3, gl + 1e-3] {
                    let h = 1e-6;
                    let (_, m, k) = card.shear(g);
                    assert!(close(fd(|x| card.shear(x).0, g, h), m, 1e-7, 1e-9));
                    assert!(close(fd(|x| card.shear(x).1, g, h), k, 1e-6, 1e-8));
                }
                let (g1, g2) = match card.shear {
                    ShearLaw::TwoSlope { g1, g2, .. } => (g1, g2),
                    _ => unreachable!(),
                };
                assert_eq!(card.shear(gl - 1e-3).2, g1);
                assert_eq!(card.shear(gl + 1e-3).2, g2);
                assert!(close(card.shear(gl + 1e-12).1, g1 * gl, 1e-9, 0.0)); // continuous
            }
        }
    }

    #[test]
    fn shear_table_interpolates_monotonically() {
        let card = parse(&card_with(LINEAR, TABLE)).unwrap();
        let t = match &card.shear {
            ShearLaw::Table(t) => t.clone(),
            _ => unreachable!(),
        };
        for (a, m) in t.angles_deg().iter().zip(t.moments()) {
            assert!(close(card.shear(a.to_radians()).1, *m, 1e-13, 1e-14));
        }
        let mut last = -1.0;
        for i in 0..=800 {
            let g = (i as f64 * 0.1).to_radians();
            let (_, m, k) = card.shear(g);
            assert!(m >= last - 1e-14 && k >= 0.0, "not monotone at {g}");
            last = m;
        }
        // Linear beyond the table with the end slope.
        let (_, m1, k1) = card.shear(1.0);
        let (_, m2, k2) = card.shear(1.2);
        assert!(close(m2 - m1, 0.2 * k1, 1e-12, 0.0) && k1 == k2);
        // Continuous at the last knot.
        let xl = 50f64.to_radians();
        assert!(close(card.shear(xl - 1e-9).1, card.shear(xl + 1e-9).1, 1e-7, 0.0));
        // Energy is the integral of M (Simpson on a fine grid).
        let g_end = 1.1;
        assert!(close(card.shear(g_end).0, simpson(|g| card.shear(g).1, g_end, 2000), 1e-8, 0.0));
        // An explicit (0, 0) gives the same law.
        let t0 = ShearTable::new(vec![0.0, 10.0, 20.0, 30.0, 40.0, 50.0], vec![0.0, 0.2, 0.5, 1.1, 3.0, 12.0]).unwrap();
        for g in [0.1, 0.3, 0.7, 1.0] {
            assert_eq!(ShearLaw::Table(t0.clone()).eval(g), card.shear(g));
        }
    }

    #[test]
    fn knit_law_matches_seed_004_and_its_integral() {
        let k = KnitParams { c: 500.0, beta: 10.0, alpha: 2.5 };
        for e in [0.01, 0.1, 0.2, 0.3, 0.39] {
            let x: f64 = 2.5 * e;
            let sigma = 500.0 * e + 10.0 * (1.0 / (1.0 - x).powi(2) - 1.0 - 2.0 * x);
            assert!(close(k.stretch(e).1, sigma, 1e-12, 1e-12));
        }
        // W = integral of sigma, by Simpson.
        let e_end = 0.35;
        assert!(close(k.stretch(e_end).0, simpson(|e| k.stretch(e).1, e_end, 4000), 1e-9, 0.0));
        // Past the singularity: huge, finite, increasing.
        let (w, t, kk) = k.stretch(1.0);
        assert!(w.is_finite() && t > 1e6 * 10.0 && kk > 0.0);
        let (w2, t2, _) = k.stretch(1e6);
        assert!(w2.is_finite() && w2 > w && t2 > t);
        // Linear in compression with the compression factor.
        let card = {
            let mut c = parse(&card_with(KNIT, POLY)).unwrap();
            c.tension.compression_factor = 0.1;
            c
        };
        assert_eq!(card.tension(Fibre::Warp, -0.2), (0.5 * 50.0 * 0.04, 50.0 * -0.2, 50.0));
    }

    #[test]
    fn linear_tension_and_bending() {
        let card =
            parse(&card_with("law = \"linear\"\ncompression_factor = 0.5\nwarp = 2.0e5\nweft = 1.0e5", POLY)).unwrap();
        assert_eq!(card.tension(Fibre::Warp, 0.01), (0.5 * 2.0e5 * 1e-4, 2.0e3, 2.0e5));
        assert_eq!(card.tension(Fibre::Weft, -0.01), (0.5 * 0.5e5 * 1e-4, -0.5e3, 0.5e5));
        assert_eq!(card.bending(Fibre::Warp), 1.0e-7);
        assert_eq!(card.bending(Fibre::Weft), 2.0e-7);
        // law defaults to linear and compression_factor to 1.
        let card = parse(&card_with("warp = 200000\nweft = 1.0e5", POLY)).unwrap();
        assert_eq!(card.tension.compression_factor, 1.0);
        assert_eq!(card.tension.law, TensionLaw::Linear { warp: 2.0e5, weft: 1.0e5 });
    }

    #[test]
    fn round_trip_through_toml() {
        for (k, mut card) in all_cards().into_iter().enumerate() {
            // Every other card records the range its shear law was calibrated over.
            card.shear_calibrated_max_deg = (k % 2 == 0).then_some(34.471_234_5);
            card.source = Some("Someone et al. \"quoted\"\n2024, p. 3 \\ x".into());
            card.areal_mass = 0.1 + 0.2; // not a short decimal
            card.bending.warp = 1.0 / 3.0 * 1e-7;
            let text = card.to_toml_string();
            let back = parse(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
            assert_eq!(back, card, "{text}");
        }
    }

    #[test]
    fn errors_name_the_line_and_field() {
        let cases: Vec<(String, &str, usize)> = vec![
            (card_with(LINEAR, POLY).replace("areal_mass = 0.3", "areal_mass = -0.3"), "`areal_mass`", 2),
            (card_with(LINEAR, POLY).replace("thickness = 5.0e-4", "thickness = 0"), "`thickness`", 3),
            (card_with(LINEAR, POLY).replace("warp = 2.0e5", "warp = -2.0e5"), "`tension.warp`", 7),
            (card_with(LINEAR, POLY).replace("weft = 2.0e-7", "weft = 0.0"), "`bending.weft`", 16),
            (card_with(LINEAR, TWO).replace("g2 = 200.0", "g2 = -1.0"), "`shear.g2`", 13),
            (
                card_with(LINEAR, TWO).replace("locking_angle_deg = 35.0", "locking_angle_deg = 95.0"),
                "`shear.locking_angle_deg`",
                14,
            ),
            (card_with(LINEAR, TWO).replace("g1 = 2.0\n", ""), "needs `g1`", 10),
            (
                card_with(LINEAR, POLY).replace("coefficients = [0.5, 2.0, 3.0]", "coefficients = [0.5, -20.0]"),
                "positive and non-decreasing",
                12,
            ),
            (
                card_with(LINEAR, POLY).replace("coefficients = [0.5, 2.0, 3.0]", "coefficients = [0.5]\ng1 = 2.0"),
                "`shear.g1`",
                13,
            ),
            (card_with(LINEAR, POLY).replace("coefficients", "g1"), "expected f64", 12),
            (card_with(LINEAR, TABLE).replace("1.1, 3.0", "3.1, 3.0"), "non-decreasing", 13),
            (card_with(LINEAR, TABLE).replace("40.0, 50.0", "40.0, 40.0"), "strictly increasing", 12),
            (card_with(LINEAR, TABLE).replace(", 12.0]", "]"), "one moment per angle", 13),
            (card_with(KNIT, POLY).replace("beta = 10.0", "beta = -10.0"), "`tension.warp.beta`", 9),
            (card_with(KNIT, POLY).replace("alpha = 2.5", "gamma = 2.5"), "unknown field `gamma`", 10),
            (card_with(KNIT, POLY).replace("law = \"knit\"", "law = \"linear\""), "`tension.warp`", 7),
            (card_with(LINEAR, POLY).replace("law = \"linear\"", "law = \"knit\""), "`tension.warp`", 7),
            (
                card_with(LINEAR, POLY).replace("law = \"linear\"", "law = \"neo-hookean\""),
                "unknown law 'neo-hookean'",
                6,
            ),
            (card_with(LINEAR, POLY).replace("law = \"polynomial\"", "law = \"cubic\""), "unknown law 'cubic'", 11),
            (card_with(LINEAR, POLY).replace("thickness", "thicknes"), "unknown field `thicknes`", 3),
            (card_with(LINEAR, POLY).replace("areal_mass = 0.3", "areal_mass = \"heavy\""), "areal_mass", 2),
            (
                card_with(LINEAR, POLY).replace("weft = 1.0e5", "weft = 1.0e5\ncompression_factor = 2.0"),
                "`tension.compression_factor`",
                9,
            ),
            (card_with(LINEAR, POLY).replace("[bending]\nwarp = 1.0e-7\n", "[bending]\n"), "missing field `warp`", 14),
            (
                card_with(LINEAR, POLY).replace("3.0]", "3.0]\ncalibrated_max_deg = 95.0"),
                "`shear.calibrated_max_deg`",
                13,
            ),
            (card_with(LINEAR, TWO).replace("= 35.0", "= 35.0\ncalibrated_max_deg = -1"), "calibrated_max_deg", 15),
        ];
        let mut wrong = Vec::new();
        for (text, needle, line) in cases {
            let e = parse(&text).expect_err(&text);
            if !(e.contains(needle)
                && e.contains(&format!("line {line}"))
                && e.starts_with("material card test.toml: "))
            {
                wrong.push(format!("wanted '{needle}' at line {line}, got: {e}"));
            }
        }
        assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    }

    #[test]
    fn uses_past_the_calibrated_range_are_named() {
        let mut card = parse(&card_with(LINEAR, TWO)).unwrap();
        assert_eq!(card.shear_calibrated_max_deg, None);
        assert_eq!(card.shear_range_warning(80.0), None); // no range recorded: nothing to say
        let card2 = parse(&card_with(LINEAR, &format!("{TWO}\ncalibrated_max_deg = 35.0"))).unwrap();
        assert_eq!(card2.shear_calibrated_max_deg, Some(35.0));
        card.shear_calibrated_max_deg = Some(35.0);
        assert_eq!(card, card2);
        assert_eq!(card.shear_range_warning(35.0 + 0.5 * SHEAR_RANGE_TOLERANCE_DEG), None);
        let w = card.shear_range_warning(41.26).unwrap();
        assert!(w.contains("41.3 deg") && w.contains("35.0 deg") && w.contains("'t'"), "{w}");
    }

    fn materials_dir() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("materials")
    }

    #[test]
    fn bundled_cards_load() {
        let mut n = 0;
        for entry in std::fs::read_dir(materials_dir()).unwrap() {
            let p = entry.unwrap().path();
            if p.extension().is_some_and(|x| x == "toml") {
                let card = MaterialCard::load(&p).unwrap_or_else(|e| panic!("{e}"));
                assert!(card.source.is_some(), "{}: cite the source", p.display());
                assert_eq!(MaterialCard::parse(&card.to_toml_string(), "rt").unwrap(), card);
                n += 1;
            }
        }
        assert!(n >= 3);
    }

    #[test]
    fn sze_liu_table1_conversion() {
        let card = MaterialCard::load(&materials_dir().join("sze-liu-table1.toml")).unwrap();
        // gf/cm -> N/m; gf cm^2/cm = gf cm -> N m; gf/cm^2 weight -> g/cm^2 mass -> kg/m^2.
        let per_cm = GF / 1e-2;
        let rel = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs();
        match card.tension.law {
            TensionLaw::Linear { warp, weft } => {
                assert!(rel(warp, 1118.2 * per_cm) && rel(weft, 759.5 * per_cm), "{warp} {weft}");
            }
            _ => panic!("Table 1 is linear"),
        }
        assert_eq!(card.tension.compression_factor, 1.0);
        assert!(rel(card.bending(Fibre::Warp), 0.083 * GF * 1e-2));
        assert!(rel(card.bending(Fibre::Weft), 0.063 * GF * 1e-2));
        let (_, m, k) = card.shear(0.1);
        assert!(rel(k, 41.8 * per_cm) && rel(m, 0.1 * 41.8 * per_cm));
        assert!(rel(card.areal_mass, 0.019 * 1e-3 / 1e-4)); // 0.19 kg/m^2
        assert!(rel(card.areal_mass * 9.80665, 0.019 * GF / 1e-4)); // the weight, N/m^2
        assert!(rel(card.thickness, 0.0593e-2));
        // Sanity: the numbers in SI.
        assert!((card.bending.warp - 8.1395e-6).abs() < 1e-9);
        assert!((card.areal_mass - 0.19).abs() < 1e-12);
    }

    #[test]
    fn bundled_woven_cards_lock() {
        // (card, an angle below locking, an angle past it), degrees.
        for (file, below, past) in [("glass-plain-weave.toml", 25.0f64, 40.0f64), ("carbon-twill.toml", 25.0, 55.0)] {
            let card = MaterialCard::load(&materials_dir().join(file)).unwrap();
            // Steep rise: the tangent stiffness well past locking is far above the initial one.
            let k0 = card.shear(1e-3).2;
            let k_hi = card.shear(past.to_radians()).2;
            let k_lo = card.shear(below.to_radians()).2;
            assert!(k_hi > 20.0 * k0 && k_lo < 5.0 * k0, "{file}: {k0} {k_lo} {k_hi}");
        }
    }
}
