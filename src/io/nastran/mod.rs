//! Nastran bulk data: reading shell meshes ([`read()`]) and writing the fibre orientations of a
//! layup ([`mod@write`]); OptiStruct and RTMsim decks are Nastran bulk data too and share the
//! fields below. One parser reads a real field ([`parse_real`]), and the writers check every
//! number they write with it (`fit_real`).
pub(crate) mod cards;
pub mod read;
pub mod write;

pub use read::read;
pub(crate) use write::write_flow;

use std::io::{self, Write};

/// Nastran as a shell-mesh format.
pub const FORMAT: crate::io::MeshFormat = crate::io::MeshFormat { name: "Nastran", extensions: &["bdf", "nas", "dat", "fem", "blk"], read };

/// Width of a large field.
pub(crate) const LARGE: usize = 16;

/// Parse a Nastran real: `1.5`, `1.5E-3`, `1.5D-3`, `1.5-3` (= 1.5e-3), `-.5+2` (= -50), `7.`.
/// Returns `None` for a blank or malformed field. Infinite results (overflow) are returned as
/// they are: the caller refuses them with the line number.
pub fn parse_real(field: &str) -> Option<f64> {
    let t = field.trim();
    if t.is_empty() || t.len() > 64 {
        return None;
    }
    let mut buf = [0u8; 66];
    let mut n = 0;
    let mut has_exp = false;
    for (k, &c) in t.as_bytes().iter().enumerate() {
        let c = match c {
            b'd' | b'D' | b'e' | b'E' => {
                has_exp = true;
                b'E'
            }
            _ => c,
        };
        // A sign after the mantissa without a letter is Nastran's exponent shorthand.
        if (c == b'+' || c == b'-') && k > 0 && !has_exp {
            buf[n] = b'E';
            n += 1;
            has_exp = true;
        }
        buf[n] = c;
        n += 1;
    }
    let s = std::str::from_utf8(&buf[..n]).ok()?;
    // Reject words Rust would accept ("inf", "nan"): a Nastran real is digits, '.', signs, E.
    if !s.bytes().all(|c| c.is_ascii_digit() || matches!(c, b'.' | b'+' | b'-' | b'E')) {
        return None;
    }
    s.parse().ok()
}

/// The text of `x` that fits in `width` characters and reads back closest to `x`: plain
/// decimals (leading zero dropped, ".0123") or the Nastran exponent form without `E`
/// ("1.2345-7", "-2.5+12"), which Nastran, OptiStruct, pyNastran and RTMsim all accept.
/// `{:?}` (exact) is used whenever it fits. Always contains a decimal point, so it is never
/// read as an integer. `None` only for a non-finite `x` (checked earlier).
pub(crate) fn fit_real(x: f64, width: usize) -> Option<String> {
    if !x.is_finite() {
        return None;
    }
    if x == 0.0 {
        return Some("0.0".into());
    }
    let exact = nastran_style(&format!("{x:?}"));
    if exact.len() <= width {
        return Some(exact);
    }
    let mut best: Option<(f64, String)> = None;
    let mut consider = |s: String| {
        if s.len() <= width {
            if let Some(v) = parse_real(&s) {
                let err = (v - x).abs();
                if best.as_ref().is_none_or(|(e, _)| err < *e) {
                    best = Some((err, s));
                }
            }
        }
    };
    for p in (0..=17).rev() {
        let s = format!("{x:.p$}");
        let s = if p == 0 { format!("{s}.") } else { s };
        let s = s.replacen("0.", ".", if s.starts_with("0.") || s.starts_with("-0.") { 1 } else { 0 });
        // Trailing zeros after the point carry nothing ("250.25000000000" is "250.25").
        let s = if s.contains('.') { s.trim_end_matches('0').to_string() } else { s };
        if s.len() <= width {
            consider(s);
            break;
        }
    }
    for p in (0..=16).rev() {
        let s = nastran_style(&format!("{x:.p$e}"));
        let compact = s.replacen('e', "", 1);
        if compact.len() <= width {
            consider(compact);
            break;
        }
    }
    best.map(|(_, s)| s)
}

/// Rust float text to a Nastran-readable one: a decimal point in the mantissa and a signed
/// exponent ("1e-7" -> "1.e-7", "1e16" -> "1.e+16").
fn nastran_style(s: &str) -> String {
    let (mant, exp) = match s.split_once('e') {
        Some((m, e)) => (m, Some(e)),
        None => (s, None),
    };
    let mant = if mant.contains('.') { mant.to_string() } else { format!("{mant}.") };
    match exp {
        None => mant,
        Some(e) if e.starts_with('-') || e.starts_with('+') => format!("{mant}e{e}"),
        Some(e) => format!("{mant}e+{e}"),
    }
}

/// A real in a large field (checked finite before writing).
pub(crate) fn real(x: f64) -> String {
    // One character short of the field: a blank always separates neighbouring numbers.
    fit_real(x, LARGE - 1).expect("values are checked finite before writing")
}

/// One entry in large-field fixed format: `fields` are the entry's fields 2, 3, ... in
/// small-field numbering (8 per logical line); they go 4 per physical line, the first line
/// starting `NAME*`, continuation lines `*`.
pub(crate) fn large<W: Write>(w: &mut W, name: &str, fields: &[String]) -> io::Result<()> {
    let n_lines = fields.len().div_ceil(4).max(1);
    for line in 0..n_lines {
        let head = if line == 0 { format!("{name}*") } else { "*".to_string() };
        write!(w, "{head:<8}")?;
        let chunk = &fields[(4 * line).min(fields.len())..(4 * line + 4).min(fields.len())];
        let mut text = String::new();
        for f in chunk {
            debug_assert!(f.len() <= LARGE, "field {f:?} too long");
            text.push_str(&format!("{f:<16}"));
        }
        writeln!(w, "{}", text.trim_end())?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use super::parse_real as r;

    #[test]
    fn plain_reals() {
        assert_eq!(r("1.5"), Some(1.5));
        assert_eq!(r(" 7. "), Some(7.0));
        assert_eq!(r(".5"), Some(0.5));
        assert_eq!(r("-3"), Some(-3.0));
        assert_eq!(r("1.5E-3"), Some(1.5e-3));
        assert_eq!(r("1.5e+3"), Some(1.5e3));
    }

    #[test]
    fn exponent_without_letter() {
        assert_eq!(r("1.-3"), Some(1e-3));
        assert_eq!(r("-.5+2"), Some(-50.0));
        assert_eq!(r("+2.5-1"), Some(0.25));
        assert_eq!(r("-1.25+0"), Some(-1.25));
    }

    #[test]
    fn fortran_d_exponent() {
        assert_eq!(r("1.5D-3"), Some(1.5e-3));
        assert_eq!(r("2.d2"), Some(200.0));
    }

    #[test]
    fn malformed_and_blank() {
        assert_eq!(r(""), None);
        assert_eq!(r("   "), None);
        assert_eq!(r("abc"), None);
        assert_eq!(r("inf"), None);
        assert_eq!(r("nan"), None);
        assert_eq!(r("1.2.3"), None);
        assert_eq!(r("1.5E"), None);
    }

    #[test]
    fn overflow_is_infinite_not_an_error_here() {
        assert_eq!(r("1.+999"), Some(f64::INFINITY));
    }

    #[test]
    fn fit_real_fits_and_reads_back() {
        for &x in &[0.1, -0.1234567891234, 1.0e-7, -3.0e-12, 123456.789, 1.0e20, 0.0, 179.99999999999997, -2.5e-300] {
            for width in [8, 16] {
                let s = fit_real(x, width).unwrap();
                assert!(s.len() <= width && s.contains('.'), "{x} -> {s}");
                let back = parse_real(&s).unwrap();
                let rel = if x == 0.0 { back.abs() } else { ((back - x) / x).abs() };
                let tol = if width == 8 { 1e-3 } else { 1e-9 };
                assert!(rel <= tol, "{x} -> {s} -> {back}");
            }
        }
        assert_eq!(fit_real(0.5, 8).unwrap(), "0.5");
        assert_eq!(fit_real(250.25000000000003, 15).unwrap(), "250.25");
        assert_eq!(fit_real(-1500.0000000000002, 15).unwrap(), "-1500.");
        assert_eq!(fit_real(-1.0e-7, 8).unwrap(), "-1.e-7");
        assert_eq!(parse_real("1.5-3"), Some(1.5e-3));
        assert_eq!(parse_real("-.5+2"), Some(-50.0));
        assert!(fit_real(f64::NAN, 8).is_none());
    }
}
