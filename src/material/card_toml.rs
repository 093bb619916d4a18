//! A material card's TOML: the schema below, read by [`MaterialCard::load`] with errors that name
//! the line and field, and written by [`MaterialCard::to_toml_string`] (with units and formulas as
//! comments) so that loading it back gives an equal card.
//!
//! Schema (SI units):
//!
//! ```toml
//! name = "glass-plain-weave"
//! areal_mass = 0.3          # kg/m^2
//! thickness = 5.0e-4        # m
//! source = "..."            # optional: where the numbers come from
//!
//! [tension]                 # per fibre family, per unit width
//! law = "linear"            # optional, default "linear": W = D e^2 / 2, D in N/m
//! compression_factor = 1.0  # optional, 0..1: the rigidity for e < 0 is scaled by it
//! warp = 2.0e5              # D, N/m
//! weft = 2.0e5
//!
//! [shear]                   # shear moment per unit area M(gamma), N/m; W = integral of M
//! law = "polynomial"        # M = c1 g + c3 g^3 + c5 g^5 + ...
//! coefficients = [0.5, 2.0] # [c1, c3, ...], N/m
//!
//! calibrated_max_deg = 35.0 # optional: the law was fitted to test data up to this angle;
//!                           # uses beyond it warn (written by `drape calibrate`)
//!
//! [bending]                 # flexural rigidity per unit width, N m
//! warp = 1.0e-7
//! weft = 1.0e-7
//!
//! [contact]                 # optional
//! friction = 0.25           # Coulomb's coefficient on a tool: the default of mechanical plies
//! ```
//!
//! The knit (strain-stiffening) tension law of seed 004, Supplementary Eq. 14, one table per
//! family: sigma(e) = C e + beta (1/(1 - alpha e)^2 - 1 - 2 alpha e), C and beta in N/m, alpha
//! dimensionless (1/alpha is the finite extensibility):
//! ```toml
//! [tension]
//! law = "knit"
//! compression_factor = 1.0  # optional
//! [tension.warp]
//! C = 500.0                 # N/m (`c` is accepted too)
//! beta = 10.0               # N/m
//! alpha = 2.5
//! [tension.weft]
//! C = 120.0
//! beta = 20.0
//! alpha = 1.2
//! ```
//!
//! The other shear laws:
//! ```toml
//! [shear]
//! law = "two-slope"         # M = g1 g up to the locking angle, then slope g2 (continuous, odd)
//! g1 = 2.0                  # N/m per rad
//! g2 = 200.0                # N/m per rad
//! locking_angle_deg = 35.0
//! ```
//! ```toml
//! [shear]
//! law = "table"             # M measured at angles; (0, 0) is implied
//! angles_deg = [10.0, 20.0, 30.0, 40.0, 50.0]
//! moments = [0.2, 0.5, 1.1, 3.0, 12.0]   # N/m, non-decreasing
//! ```
use super::card::{FlowProperties, MaterialCard, MaterialError};
use super::laws::{Bending, KnitParams, ShearLaw, ShearTable, Tension, TensionLaw};
use serde::de::{self, Deserializer, MapAccess, Visitor};
use serde::Deserialize;
use std::collections::HashMap;
use std::fmt::{self, Write as _};
use std::path::Path;
use toml::Spanned;

impl MaterialCard {
    /// Read and check a card file.
    pub fn load(path: &Path) -> Result<Self, MaterialError> {
        let text = std::fs::read_to_string(path).map_err(|e| {
            MaterialError::Invalid(format!("cannot read material card {}: {e}. Check the path.", path.display()))
        })?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Read and check a card from TOML text; `origin` names it in error messages.
    pub fn parse(text: &str, origin: &str) -> Result<Self, MaterialError> {
        let fail = |m: String| MaterialError::Invalid(format!("material card {origin}: {m}"));
        let raw: RawCard = toml::from_str(text).map_err(|e| fail(e.to_string().trim_end().to_string()))?;
        let mut lines = Lines { text, map: HashMap::new() };
        lines.note("name", raw.name.span());
        lines.note("areal_mass", raw.areal_mass.span());
        lines.note("thickness", raw.thickness.span());
        lines.note("tension", raw.tension.span());
        lines.note("shear", raw.shear.span());
        lines.note("bending", raw.bending.span());
        lines.note("bending.warp", raw.bending.get_ref().warp.span());
        lines.note("bending.weft", raw.bending.get_ref().weft.span());
        if let Some(f) = &raw.flow {
            lines.note("flow", f.span());
        }
        if let Some(c) = &raw.contact {
            lines.note("contact", c.span());
        }
        let at = |lines: &Lines, field: &str, m: String| {
            let section = field.split('.').next().unwrap_or(field);
            match lines.map.get(field).or_else(|| lines.map.get(section)) {
                Some(l) => fail(format!("line {l}, field `{field}`: {m}")),
                None => fail(format!("field `{field}`: {m}")),
            }
        };

        // [tension]
        let t = raw.tension.into_inner();
        if let Some(cf) = &t.compression_factor {
            lines.note("tension.compression_factor", cf.span());
        }
        if let Some(l) = &t.law {
            lines.note("tension.law", l.span());
        }
        lines.note("tension.warp", t.warp.span());
        lines.note("tension.weft", t.weft.span());
        let law_name = t.law.as_ref().map(|l| l.get_ref().as_str()).unwrap_or("linear");
        let law = match law_name {
            "linear" => {
                let rigidity = |d: &Spanned<RawDir>, fibre: &str| match d.get_ref() {
                    RawDir::Rigidity(v) => Ok(*v),
                    RawDir::Knit(_) => Err(at(
                        &lines,
                        &format!("tension.{fibre}"),
                        "the linear law takes one rigidity in N/m (a number); for C, beta, alpha set law = \"knit\""
                            .into(),
                    )),
                };
                TensionLaw::Linear { warp: rigidity(&t.warp, "warp")?, weft: rigidity(&t.weft, "weft")? }
            }
            "knit" => {
                let knit = |lines: &mut Lines, d: &Spanned<RawDir>, fibre: &str| match d.get_ref() {
                    RawDir::Knit(k) => {
                        lines.note(&format!("tension.{fibre}.C"), k.c.span());
                        lines.note(&format!("tension.{fibre}.beta"), k.beta.span());
                        lines.note(&format!("tension.{fibre}.alpha"), k.alpha.span());
                        Ok(KnitParams { c: *k.c.get_ref(), beta: *k.beta.get_ref(), alpha: *k.alpha.get_ref() })
                    }
                    RawDir::Rigidity(_) => Err((
                        format!("tension.{fibre}"),
                        format!("the knit law takes a table [tension.{fibre}] with C, beta and alpha, not a number"),
                    )),
                };
                let warp = knit(&mut lines, &t.warp, "warp");
                let weft = knit(&mut lines, &t.weft, "weft");
                match (warp, weft) {
                    (Ok(warp), Ok(weft)) => TensionLaw::Knit { warp, weft },
                    (Err((f, m)), _) | (_, Err((f, m))) => return Err(at(&lines, &f, m)),
                }
            }
            other => {
                return Err(at(&lines, "tension.law", format!("unknown law '{other}': use \"linear\" or \"knit\"")));
            }
        };
        let tension = Tension { law, compression_factor: t.compression_factor.map(|c| c.into_inner()).unwrap_or(1.0) };

        // [shear]
        let s = raw.shear.into_inner();
        lines.note("shear.law", s.law.span());
        for (f, sp) in [
            ("shear.coefficients", s.coefficients.as_ref().map(|v| v.span())),
            ("shear.g1", s.g1.as_ref().map(|v| v.span())),
            ("shear.g2", s.g2.as_ref().map(|v| v.span())),
            ("shear.locking_angle_deg", s.locking_angle_deg.as_ref().map(|v| v.span())),
            ("shear.angles_deg", s.angles_deg.as_ref().map(|v| v.span())),
            ("shear.moments", s.moments.as_ref().map(|v| v.span())),
            ("shear.calibrated_max_deg", s.calibrated_max_deg.as_ref().map(|v| v.span())),
        ] {
            if let Some(sp) = sp {
                lines.note(f, sp);
            }
        }
        let given: Vec<&str> = [
            ("coefficients", s.coefficients.is_some()),
            ("g1", s.g1.is_some()),
            ("g2", s.g2.is_some()),
            ("locking_angle_deg", s.locking_angle_deg.is_some()),
            ("angles_deg", s.angles_deg.is_some()),
            ("moments", s.moments.is_some()),
        ]
        .iter()
        .filter(|(_, g)| *g)
        .map(|(f, _)| *f)
        .collect();
        let fields_for = |law: &str| -> &'static [&'static str] {
            match law {
                "polynomial" => &["coefficients"],
                "two-slope" => &["g1", "g2", "locking_angle_deg"],
                "table" => &["angles_deg", "moments"],
                _ => &[],
            }
        };
        let shear_law = s.law.get_ref().as_str();
        let wanted = fields_for(shear_law);
        if wanted.is_empty() {
            return Err(at(
                &lines,
                "shear.law",
                format!("unknown law '{shear_law}': use \"polynomial\", \"two-slope\" or \"table\""),
            ));
        }
        if let Some(f) = given.iter().find(|f| !wanted.contains(f)) {
            return Err(at(
                &lines,
                &format!("shear.{f}"),
                format!("does not belong to law = \"{shear_law}\", which takes {}", wanted.join(", ")),
            ));
        }
        if let Some(f) = wanted.iter().find(|f| !given.contains(f)) {
            return Err(at(
                &lines,
                "shear",
                format!("law = \"{shear_law}\" needs `{f}` (it takes {})", wanted.join(", ")),
            ));
        }
        let shear = match shear_law {
            "polynomial" => ShearLaw::Polynomial { coefficients: s.coefficients.unwrap().into_inner() },
            "two-slope" => ShearLaw::TwoSlope {
                g1: s.g1.unwrap().into_inner(),
                g2: s.g2.unwrap().into_inner(),
                locking_angle_deg: s.locking_angle_deg.unwrap().into_inner(),
            },
            _ => ShearLaw::Table(
                ShearTable::new(s.angles_deg.unwrap().into_inner(), s.moments.unwrap().into_inner())
                    .map_err(|(f, m)| at(&lines, &f, m))?,
            ),
        };

        let b = raw.bending.into_inner();
        let card = MaterialCard {
            name: raw.name.into_inner(),
            areal_mass: raw.areal_mass.into_inner(),
            thickness: raw.thickness.into_inner(),
            source: raw.source,
            tension,
            shear,
            shear_calibrated_max_deg: s.calibrated_max_deg.map(Spanned::into_inner),
            bending: Bending { warp: b.warp.into_inner(), weft: b.weft.into_inner() },
            flow: raw.flow.map(|f| {
                let f = f.into_inner();
                FlowProperties { fibre_volume_fraction: f.fibre_volume_fraction, fibre_radius: f.fibre_radius }
            }),
            friction: raw.contact.map(|c| c.into_inner().friction),
        };
        card.check().map_err(|(f, m)| at(&lines, &f, m))?;
        Ok(card)
    }

    /// The card as TOML in the schema [`Self::load`] reads; loading it back gives an equal card.
    pub fn to_toml_string(&self) -> String {
        let mut s = String::new();
        let f = |v: f64| format!("{v:?}"); // shortest round-trip form, always a TOML float
        let list = |v: &[f64]| format!("[{}]", v.iter().map(|x| f(*x)).collect::<Vec<_>>().join(", "));
        let q = |t: &str| toml::Value::String(t.to_string()).to_string();
        let _ = writeln!(s, "name = {}", q(&self.name));
        let _ = writeln!(s, "areal_mass = {} # kg/m^2", f(self.areal_mass));
        let _ = writeln!(s, "thickness = {} # m", f(self.thickness));
        if let Some(src) = &self.source {
            let _ = writeln!(s, "source = {}", q(src));
        }
        s.push_str("\n[tension]\n");
        match self.tension.law {
            TensionLaw::Linear { warp, weft } => {
                s.push_str("law = \"linear\" # W = D e^2 / 2, D in N/m\n");
                let _ = writeln!(s, "compression_factor = {}", f(self.tension.compression_factor));
                let _ = writeln!(s, "warp = {}", f(warp));
                let _ = writeln!(s, "weft = {}", f(weft));
            }
            TensionLaw::Knit { warp, weft } => {
                s.push_str(
                    "law = \"knit\" # sigma = C e + beta (1/(1 - alpha e)^2 - 1 - 2 alpha e), C and beta in N/m\n",
                );
                let _ = writeln!(s, "compression_factor = {}", f(self.tension.compression_factor));
                for (fibre, k) in [("warp", warp), ("weft", weft)] {
                    let _ = writeln!(
                        s,
                        "\n[tension.{fibre}]\nC = {}\nbeta = {}\nalpha = {}",
                        f(k.c),
                        f(k.beta),
                        f(k.alpha)
                    );
                }
            }
        }
        s.push_str("\n[shear] # shear moment per unit area M(gamma), N/m\n");
        match &self.shear {
            ShearLaw::Polynomial { coefficients } => {
                s.push_str("law = \"polynomial\" # M = c1 g + c3 g^3 + ...\n");
                let _ = writeln!(s, "coefficients = {}", list(coefficients));
            }
            ShearLaw::TwoSlope { g1, g2, locking_angle_deg } => {
                s.push_str("law = \"two-slope\" # N/m per rad below / above the locking angle\n");
                let _ = writeln!(s, "g1 = {}\ng2 = {}\nlocking_angle_deg = {}", f(*g1), f(*g2), f(*locking_angle_deg));
            }
            ShearLaw::Table(t) => {
                s.push_str("law = \"table\" # monotone cubic through (0, 0) and these points\n");
                let _ = writeln!(s, "angles_deg = {}", list(t.angles_deg()));
                let _ = writeln!(s, "moments = {}", list(t.moments()));
            }
        }
        if let Some(a) = self.shear_calibrated_max_deg {
            let _ = writeln!(s, "calibrated_max_deg = {} # deg: the law was fitted to test data up to here", f(a));
        }
        s.push_str("\n[bending] # flexural rigidity per unit width, N m\n");
        let _ = writeln!(s, "warp = {}\nweft = {}", f(self.bending.warp), f(self.bending.weft));
        if let Some(flow) = &self.flow {
            s.push_str("\n[flow]\n");
            let _ = writeln!(s, "fibre_volume_fraction = {}", f(flow.fibre_volume_fraction));
            let _ = writeln!(s, "fibre_radius = {} # m", f(flow.fibre_radius));
        }
        if let Some(mu) = self.friction {
            s.push_str("\n[contact]\n");
            let _ = writeln!(s, "friction = {} # Coulomb's coefficient on a tool", f(mu));
        }
        s
    }
}

/// Line numbers of the fields of a card file, for error messages.
struct Lines<'a> {
    text: &'a str,
    map: HashMap<String, usize>,
}

impl Lines<'_> {
    fn note(&mut self, field: &str, span: std::ops::Range<usize>) {
        let line = 1 + self.text[..span.start.min(self.text.len())].matches('\n').count();
        self.map.insert(field.to_string(), line);
    }
}

// ---- the file as written -------------------------------------------------------------------

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCard {
    name: Spanned<String>,
    areal_mass: Spanned<f64>,
    thickness: Spanned<f64>,
    source: Option<String>,
    tension: Spanned<RawTension>,
    shear: Spanned<RawShear>,
    bending: Spanned<RawBending>,
    flow: Option<Spanned<RawFlow>>,
    contact: Option<Spanned<RawContact>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawContact {
    friction: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFlow {
    fibre_volume_fraction: f64,
    fibre_radius: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTension {
    law: Option<Spanned<String>>,
    compression_factor: Option<Spanned<f64>>,
    warp: Spanned<RawDir>,
    weft: Spanned<RawDir>,
}

/// A tension entry: a rigidity (linear law) or a knit table.
enum RawDir {
    Rigidity(f64),
    Knit(RawKnit),
}

impl<'de> Deserialize<'de> for RawDir {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RawDir;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a tensile rigidity in N/m (linear law) or a table with C, beta, alpha (knit law)")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<RawDir, E> {
                Ok(RawDir::Rigidity(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<RawDir, E> {
                Ok(RawDir::Rigidity(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<RawDir, E> {
                Ok(RawDir::Rigidity(v as f64))
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<RawDir, A::Error> {
                RawKnit::deserialize(de::value::MapAccessDeserializer::new(map)).map(RawDir::Knit)
            }
        }
        d.deserialize_any(V)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawKnit {
    #[serde(rename = "C", alias = "c")]
    c: Spanned<f64>,
    beta: Spanned<f64>,
    alpha: Spanned<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawShear {
    law: Spanned<String>,
    coefficients: Option<Spanned<Vec<f64>>>,
    g1: Option<Spanned<f64>>,
    g2: Option<Spanned<f64>>,
    locking_angle_deg: Option<Spanned<f64>>,
    angles_deg: Option<Spanned<Vec<f64>>>,
    moments: Option<Spanned<Vec<f64>>>,
    calibrated_max_deg: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBending {
    warp: Spanned<f64>,
    weft: Spanned<f64>,
}
