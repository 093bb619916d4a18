//! `drape calibrate`: fit a law of a material card to test data and write the updated card.
//!
//! ```text
//! drape calibrate picture-frame --data CSV --side L [--data CSV --side L ...] [--law polynomial:3|two-slope]
//!       [--max-angle DEG] [--min-angle DEG] [--units m|mm] --card BASE.toml --out NEW.toml
//! drape calibrate bias-extension --data CSV --length L --width W [--data CSV --length L --width W ...] [--law ...]
//!       [--max-angle DEG] [--min-angle DEG] [--units m|mm] --card BASE.toml --out NEW.toml
//! drape calibrate knit --data CSV --direction warp|weft --card BASE.toml --out NEW.toml
//! ```
//!
//! A shear fit writes the card, and beside it `NEW.fit.png` (the data, the fit and each
//! sample's normalised curve) and `NEW.fit.json` (the fit report: parameters with their
//! uncertainties, R^2, the relative error per band of angle, each sample's force error, and for
//! several samples how a law fitted to one alone predicts the others).
use super::{compute, input, Failure};
use crate::io::write_atomic;
use crate::material::calibrate::{
    cross_predictions, default_max_angle_deg, fit_knit_uniaxial, fit_shear, parse_xy_csv, AngleRange, FitError,
    ShearLawKind, ShearSample, BAND_DEG,
};
use crate::material::test_kinematics::{BiasExtensionKinematics, PictureFrameKinematics, ShearRig};
use crate::material::{Fibre, MaterialCard};
use crate::pipeline::unit_scale;
use anyhow::anyhow;
use clap::{Args, Subcommand, ValueEnum};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `drape calibrate`.
#[derive(Debug, Args)]
pub struct CalibrateArgs {
    #[command(subcommand)]
    pub test: CalibrateTest,
}

/// The test the data come from.
#[derive(Debug, Subcommand)]
pub enum CalibrateTest {
    /// Fit the shear law to a picture-frame test (CSV: crosshead displacement, force in N).
    PictureFrame(PictureFrameArgs),
    /// Fit the shear law to a bias-extension test (CSV: elongation, force in N).
    BiasExtension(BiasExtensionArgs),
    /// Fit the knit tension law of one direction to a uniaxial test (CSV: strain, stress in N/m).
    Knit(KnitArgs),
}

/// The base card and where the fitted card goes.
#[derive(Debug, Args)]
pub struct CardFiles {
    /// Base material card: everything but the fitted law is kept.
    #[arg(long)]
    pub card: PathBuf,
    /// The new card (written whole or not at all).
    #[arg(long)]
    pub out: PathBuf,
    /// Name of the new card (default: the base card's).
    #[arg(long)]
    pub name: Option<String>,
}

/// Arguments of `drape calibrate picture-frame`.
#[derive(Debug, Args)]
pub struct PictureFrameArgs {
    /// Two columns: crosshead displacement, force (N); an optional header line. Repeat for
    /// tests of several frames: all are fitted together.
    #[arg(long, required = true)]
    pub data: Vec<PathBuf>,
    /// Frame side L, hinge to hinge: one for all the --data, or one per --data in their order.
    #[arg(long, required = true)]
    pub side: Vec<f64>,
    #[command(flatten)]
    pub fit: FitArgs,
    #[command(flatten)]
    pub files: CardFiles,
}

/// Arguments of `drape calibrate bias-extension`.
#[derive(Debug, Args)]
pub struct BiasExtensionArgs {
    /// Two columns: elongation, force (N); an optional header line. Repeat for tests of
    /// several sizes: all are fitted together.
    #[arg(long, required = true)]
    pub data: Vec<PathBuf>,
    /// Free specimen length L between the clamps (L >= 2 W): one for all the --data, or one per
    /// --data in their order.
    #[arg(long, required = true)]
    pub length: Vec<f64>,
    /// Specimen width W: one for all the --data, or one per --data.
    #[arg(long, required = true)]
    pub width: Vec<f64>,
    #[command(flatten)]
    pub fit: FitArgs,
    #[command(flatten)]
    pub files: CardFiles,
}

/// What the shear fits share.
#[derive(Debug, Args)]
pub struct FitArgs {
    /// Shear law: polynomial:N (N odd-power terms c1 g + c3 g^3 + ...) or two-slope.
    #[arg(long, default_value = "polynomial:3")]
    pub law: ShearLawKind,
    /// Largest shear angle fitted, deg (default: 35 for bias extension, where its three-zone
    /// kinematics hold; 90, every point, for the picture frame). The card records the range.
    #[arg(long)]
    pub max_angle: Option<f64>,
    /// Smallest shear angle fitted, deg (default 0): leaves out a toe region (slack clamps, a
    /// force offset, friction at the crossovers) that no law through (0, 0) follows.
    #[arg(long, default_value_t = 0.0)]
    pub min_angle: f64,
    /// Units of the displacements and of the sample's size: m or mm (forces are in N).
    #[arg(long, default_value = "m")]
    pub units: String,
}

/// A fibre family on the command line.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Direction {
    Warp,
    Weft,
}

/// Arguments of `drape calibrate knit`.
#[derive(Debug, Args)]
pub struct KnitArgs {
    /// Two columns: strain (dimensionless), stress per unit width (N/m); an optional header line.
    #[arg(long)]
    pub data: PathBuf,
    /// The fibre family the test stretched.
    #[arg(long, value_enum)]
    pub direction: Direction,
    #[command(flatten)]
    pub files: CardFiles,
}

pub fn run(a: CalibrateArgs) -> Result<(), Failure> {
    match a.test {
        CalibrateTest::PictureFrame(p) => {
            let scale = unit_scale(&p.fit.units).map_err(|m| input(anyhow!("--units: {m}")))?;
            let sides = per_sample("--side", &p.side, p.data.len())?;
            let mut samples = Vec::new();
            for (path, side) in p.data.iter().zip(sides) {
                let side = positive("--side", side)? * scale;
                let rig = ShearRig::PictureFrame(PictureFrameKinematics { side });
                samples.push(sample(path, rig, scale)?);
            }
            let card = load_card(&p.files.card)?;
            fit_and_write(card, &samples, &p.fit, "picture-frame", &p.files)
        }
        CalibrateTest::BiasExtension(b) => {
            let scale = unit_scale(&b.fit.units).map_err(|m| input(anyhow!("--units: {m}")))?;
            let lengths = per_sample("--length", &b.length, b.data.len())?;
            let widths = per_sample("--width", &b.width, b.data.len())?;
            let mut samples = Vec::new();
            for ((path, l), w) in b.data.iter().zip(lengths).zip(widths) {
                let (length, width) = (positive("--length", l)? * scale, positive("--width", w)? * scale);
                if length < 2.0 * width {
                    return Err(input(anyhow!(
                        "--length must be at least twice --width (the bias-extension zones need L >= 2 W), got {l} and {w} for {}",
                        path.display()
                    )));
                }
                let rig = ShearRig::BiasExtension(BiasExtensionKinematics { length, width });
                samples.push(sample(path, rig, scale)?);
            }
            let card = load_card(&b.files.card)?;
            fit_and_write(card, &samples, &b.fit, "bias-extension", &b.files)
        }
        CalibrateTest::Knit(k) => {
            let mut card = load_card(&k.files.card)?;
            let data = read_data(&k.data)?;
            let (p, report) = fit_knit_uniaxial(&data).map_err(fit_failure)?;
            let fibre = match k.direction {
                Direction::Warp => Fibre::Warp,
                Direction::Weft => Fibre::Weft,
            };
            println!("knit fit of {} ({} points), residuals of the stress in N/m:", k.data.display(), report.points);
            println!(
                "  {}: C = {:.6e} N/m, beta = {:.6e} N/m, alpha = {:.6e} (1/alpha = {:.4})",
                fibre.name(),
                p.c,
                p.beta,
                p.alpha,
                1.0 / p.alpha
            );
            println!(
                "  rms {:.4e} N/m   R^2 {:.6}   max |residual| {:.4e} N/m",
                report.rms, report.r_squared, report.max_abs_residual
            );
            card.set_knit(fibre, p);
            let note = format!(
                "{} knit tension fitted to uniaxial data {} by drape calibrate ({} points, R^2 = {:.6})",
                fibre.name(),
                k.data.display(),
                report.points,
                report.r_squared
            );
            card.add_source_note(note);
            write_card(card, &k.files)
        }
    }
}

/// One value per sample: a flag given once serves every --data.
fn per_sample(flag: &str, values: &[f64], samples: usize) -> Result<Vec<f64>, Failure> {
    match values.len() {
        1 => Ok(vec![values[0]; samples]),
        n if n == samples => Ok(values.to_vec()),
        n => Err(input(anyhow!(
            "{flag} is given {n} times for {samples} --data files: give it once (for every file) or once per --data, in the same order"
        ))),
    }
}

/// A sample from a data file (displacements scaled to metres).
fn sample(path: &Path, rig: ShearRig, scale: f64) -> Result<ShearSample, Failure> {
    let data = read_data(path)?.into_iter().map(|(x, y)| (x * scale, y)).collect();
    let name = path.file_name().map_or(path.display().to_string(), |n| n.to_string_lossy().into_owned());
    Ok(ShearSample { name, rig, data })
}

/// Fit the shear law, print the fit report, draw it beside the new card and write the card.
fn fit_and_write(
    mut card: MaterialCard,
    samples: &[ShearSample],
    f: &FitArgs,
    test: &str,
    files: &CardFiles,
) -> Result<(), Failure> {
    let default = default_max_angle_deg(&samples[0].rig);
    let max_angle = f.max_angle.unwrap_or(default);
    if !(max_angle > 0.0 && max_angle <= 90.0) {
        return Err(input(anyhow!("--max-angle must lie in (0, 90] degrees, got {max_angle}")));
    }
    if !(f.min_angle >= 0.0 && f.min_angle < max_angle) {
        return Err(input(anyhow!(
            "--min-angle must lie in [0, {max_angle}) degrees (below --max-angle), got {}",
            f.min_angle
        )));
    }
    let range = AngleRange { min_deg: f.min_angle, max_deg: max_angle };
    let fit = fit_shear(samples, f.law, range).map_err(fit_failure)?;
    let cross = cross_predictions(samples, f.law, range);
    // A length in the units given, without the rounding of the scaling (230, not 229.99999999999997).
    let unit = |m: f64| (m / unit_scale(&f.units).unwrap_or(1.0) * 1e9).round() / 1e9;
    println!(
        "{test} fit of {} sample{} from {} to {max_angle} deg of shear{}, in normalised shear force (N/m):",
        samples.len(),
        if samples.len() == 1 { "" } else { "s" },
        f.min_angle,
        if f.max_angle.is_none() {
            match samples[0].rig {
                ShearRig::BiasExtension(_) => {
                    " (the default: the three-zone kinematics hold to about 35 deg; --max-angle to change)"
                }
                ShearRig::PictureFrame(_) => " (the default: every point)",
            }
        } else {
            ""
        }
    );
    for s in samples {
        let size = match s.rig {
            ShearRig::PictureFrame(k) => format!("side {}", unit(k.side)),
            ShearRig::BiasExtension(k) => format!("{} x {}", unit(k.length), unit(k.width)),
        };
        println!("  {}: {size} {}, {} points", s.name, f.units, s.data.len());
    }
    println!(
        "  {} points fitted; left out: {} past {max_angle} deg, {} below {} deg, {} at no shear",
        fit.points, fit.beyond, fit.below, f.min_angle, fit.unsheared
    );
    println!("  {} law:", fit.law.law_name());
    for p in &fit.parameters {
        let sigma = p.sigma.map_or("(no uncertainty: too few points)".to_string(), |s| format!("+- {s:.3e}"));
        println!("    {:<18} = {:>13.6e} {sigma} {}", p.name, p.value, p.unit);
    }
    if let Some(c) = &fit.constraint {
        println!("  {c}");
    }
    println!(
        "  R^2 {:.6}   rms relative error {:.2}% (the mean over {BAND_DEG}-deg bands, which the fit minimises)",
        fit.r_squared,
        100.0 * fit.rms_relative
    );
    println!("  {:>10} {:>7} {:>16} {:>22}", "band, deg", "points", "rms rel. error", "law uncertainty (1 s)");
    for b in &fit.bands {
        let centre = 0.5 * (b.from_deg + b.to_deg);
        let u = fit
            .moment_uncertainty
            .iter()
            .find(|m| (m.at_deg - centre).abs() < 1e-9)
            .map_or("-".to_string(), |m| format!("{:.2}%", 100.0 * m.relative_sigma));
        println!(
            "  {:>10} {:>7} {:>15.2}% {:>22}",
            format!("{:.0}-{:.0}", b.from_deg, b.to_deg),
            b.points,
            100.0 * b.rms_relative,
            u
        );
    }
    for s in &fit.samples {
        println!("  {}: rms relative force error {:.2}% ({} points)", s.name, 100.0 * s.rms_relative, s.points);
    }
    for c in &cross {
        match (c.rms_relative, &c.note) {
            (Some(e), _) => println!(
                "  fitted to {} alone, the law predicts {} with an rms relative force error of {:.2}%",
                c.fitted_to,
                c.predicted,
                100.0 * e
            ),
            (None, note) => println!(
                "  fitted to {} alone: no law to predict {} ({})",
                c.fitted_to,
                c.predicted,
                note.as_deref().unwrap_or("")
            ),
        }
    }
    println!(
        "  calibrated range: {} to {:.2} deg; the card records the largest angle, uses past it warn{}",
        f.min_angle,
        fit.calibrated_max_deg,
        if f.min_angle > 0.0 {
            format!(" (below {} deg the law is extrapolated to 0)", f.min_angle)
        } else {
            String::new()
        }
    );

    let names: Vec<&str> = samples.iter().map(|s| s.name.as_str()).collect();
    card.shear = fit.law.clone();
    card.shear_calibrated_max_deg = Some(fit.calibrated_max_deg);
    card.add_source_note(format!(
        "shear ({}) fitted to {test} data {} up to {:.2} deg by drape calibrate ({} points, R^2 = {:.6}, rms relative error {:.2}%)",
        fit.law.law_name(),
        names.join(", "),
        fit.calibrated_max_deg,
        fit.points,
        fit.r_squared,
        100.0 * fit.rms_relative
    ));
    // The report beside the card: the picture and the numbers.
    let stem = files.out.with_extension("");
    let png = PathBuf::from(format!("{}.fit.png", stem.display()));
    let json = PathBuf::from(format!("{}.fit.json", stem.display()));
    card.validate().map_err(|e| compute(anyhow!("the fitted card is not valid: {e}")))?;
    let picture = crate::report::calibration::fit_png(&fit, samples).map_err(|m| compute(anyhow!(m)))?;
    let record = serde_json::json!({
        "test": test,
        "card": files.out.display().to_string(),
        "samples": samples.iter().map(|s| serde_json::json!({
            "name": s.name,
            "rig": s.rig.name(),
            "size_m": match s.rig {
                ShearRig::PictureFrame(k) => vec![k.side],
                ShearRig::BiasExtension(k) => vec![k.length, k.width],
            },
            "points": s.data.len(),
        })).collect::<Vec<_>>(),
        "fit": fit,
        "cross_predictions": cross,
    });
    let text = serde_json::to_string_pretty(&record).map_err(compute)? + "\n";
    write_card(card, files)?;
    write_atomic(&png, |w| w.write_all(&picture)).map_err(compute)?;
    write_atomic(&json, |w| w.write_all(text.as_bytes())).map_err(compute)?;
    println!("wrote {} and {}", png.display(), json.display());
    Ok(())
}

fn positive(flag: &str, v: f64) -> Result<f64, Failure> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(input(anyhow!("{flag} must be a positive length, got {v}")))
    }
}

fn load_card(path: &Path) -> Result<MaterialCard, Failure> {
    MaterialCard::load(path).map_err(|e| input(anyhow!("--card: {e}")))
}

fn read_data(path: &Path) -> Result<Vec<(f64, f64)>, Failure> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| input(anyhow!("--data: cannot read {}: {e}. Check the path.", path.display())))?;
    parse_xy_csv(&text).map_err(|m| input(anyhow!("--data {}: {m}", path.display())))
}

fn fit_failure(e: FitError) -> Failure {
    match e {
        FitError::Data(m) => input(anyhow!("--data: {m}")),
        FitError::Fit(m) => compute(anyhow!("{m}")),
    }
}

/// Check the card and write it atomically.
fn write_card(mut card: MaterialCard, files: &CardFiles) -> Result<(), Failure> {
    if let Some(name) = &files.name {
        card.name = name.clone();
    }
    card.validate().map_err(|e| compute(anyhow!("the fitted card is not valid: {e}")))?;
    let text = card.to_toml_string();
    write_atomic(&files.out, |w| w.write_all(text.as_bytes())).map_err(compute)?;
    println!("wrote {}", files.out.display());
    Ok(())
}
