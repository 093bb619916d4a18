//! `drape calibrate`: fit a law of a material card to test data and write the updated card.
//!
//! ```text
//! drape calibrate picture-frame --data CSV --side L [--law polynomial:3|two-slope] --card BASE.toml --out NEW.toml
//! drape calibrate bias-extension --data CSV --length L --width W [--law ...] --card BASE.toml --out NEW.toml
//! drape calibrate knit --data CSV --direction warp|weft --card BASE.toml --out NEW.toml
//! ```
use super::{compute, input, Failure};
use crate::io::write_atomic;
use crate::material::calibrate::{
    fit_knit_uniaxial, fit_shear_bias_extension, fit_shear_picture_frame, parse_xy_csv, FitError, FitReport,
    ShearLawKind,
};
use crate::material::{Fibre, MaterialCard, ShearLaw};
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
    /// Two columns: crosshead displacement, force (N); an optional header line.
    #[arg(long)]
    pub data: PathBuf,
    /// Frame side L, hinge to hinge.
    #[arg(long)]
    pub side: f64,
    /// Shear law: polynomial:N (N odd-power terms c1 g + c3 g^3 + ...) or two-slope.
    #[arg(long, default_value = "polynomial:3")]
    pub law: ShearLawKind,
    /// Units of the displacements and of --side: m or mm (forces are in N).
    #[arg(long, default_value = "m")]
    pub units: String,
    #[command(flatten)]
    pub files: CardFiles,
}

/// Arguments of `drape calibrate bias-extension`.
#[derive(Debug, Args)]
pub struct BiasExtensionArgs {
    /// Two columns: elongation, force (N); an optional header line.
    #[arg(long)]
    pub data: PathBuf,
    /// Free specimen length L between the clamps (L >= 2 W).
    #[arg(long)]
    pub length: f64,
    /// Specimen width W.
    #[arg(long)]
    pub width: f64,
    /// Shear law: polynomial:N (N odd-power terms c1 g + c3 g^3 + ...) or two-slope.
    #[arg(long, default_value = "polynomial:3")]
    pub law: ShearLawKind,
    /// Units of the elongations, --length and --width: m or mm (forces are in N).
    #[arg(long, default_value = "m")]
    pub units: String,
    #[command(flatten)]
    pub files: CardFiles,
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
            let scale = unit_scale(&p.units).map_err(|m| input(anyhow!("--units: {m}")))?;
            let side = positive("--side", p.side)? * scale;
            let card = load_card(&p.files.card)?;
            let data = scaled(read_data(&p.data)?, scale);
            let (law, report) = fit_shear_picture_frame(&data, side, p.law).map_err(fit_failure)?;
            println!(
                "picture-frame fit of {} ({} points), residuals of the shear moment in N/m:",
                p.data.display(),
                report.points
            );
            finish_shear(card, law, report, "N/m", "picture-frame", &p.data, &p.files)
        }
        CalibrateTest::BiasExtension(b) => {
            let scale = unit_scale(&b.units).map_err(|m| input(anyhow!("--units: {m}")))?;
            let length = positive("--length", b.length)? * scale;
            let width = positive("--width", b.width)? * scale;
            if length < 2.0 * width {
                return Err(input(anyhow!(
                    "--length must be at least twice --width (the bias-extension zones need L >= 2 W), got {} and {}",
                    b.length,
                    b.width
                )));
            }
            let card = load_card(&b.files.card)?;
            let data = scaled(read_data(&b.data)?, scale);
            let (law, report) = fit_shear_bias_extension(&data, length, width, b.law).map_err(fit_failure)?;
            println!(
                "bias-extension fit of {} ({} points), residuals of the force in N:",
                b.data.display(),
                report.points
            );
            finish_shear(card, law, report, "N", "bias-extension", &b.data, &b.files)
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
            print_report(&report, "N/m");
            card.set_knit(fibre, p);
            let what = format!("{} knit tension fitted to uniaxial data {}", fibre.name(), k.data.display());
            finish(card, &what, &report, &k.files)
        }
    }
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

/// Scale the first column (lengths) to metres.
fn scaled(data: Vec<(f64, f64)>, scale: f64) -> Vec<(f64, f64)> {
    data.into_iter().map(|(x, y)| (x * scale, y)).collect()
}

fn fit_failure(e: FitError) -> Failure {
    match e {
        FitError::Data(m) => input(anyhow!("--data: {m}")),
        FitError::Fit(m) => compute(anyhow!("{m}")),
    }
}

fn print_report(r: &FitReport, unit: &str) {
    println!("  rms {:.4e} {unit}   R^2 {:.6}   max |residual| {:.4e} {unit}", r.rms, r.r_squared, r.max_abs_residual);
}

fn finish_shear(
    mut card: MaterialCard,
    law: ShearLaw,
    report: FitReport,
    unit: &str,
    test: &str,
    data: &Path,
    files: &CardFiles,
) -> Result<(), Failure> {
    match &law {
        ShearLaw::Polynomial { coefficients } => {
            let names: Vec<String> = (0..coefficients.len()).map(|j| format!("c{}", 2 * j + 1)).collect();
            let values: Vec<String> = coefficients.iter().map(|c| format!("{c:.6e}")).collect();
            println!("  polynomial [{}] = [{}] N/m", names.join(", "), values.join(", "));
            if coefficients.contains(&0.0) {
                println!("  (the unconstrained fit was not monotone: fitted with every coefficient >= 0)");
            }
        }
        ShearLaw::TwoSlope { g1, g2, locking_angle_deg } => {
            println!(
                "  two-slope g1 = {g1:.6e} N/m, g2 = {g2:.6e} N/m per rad, locking angle {locking_angle_deg:.3} deg"
            );
        }
        ShearLaw::Table(_) => {}
    }
    print_report(&report, unit);
    card.shear = law;
    let what = format!("shear ({}) fitted to {test} data {}", card.shear.law_name(), data.display());
    finish(card, &what, &report, files)
}

/// Record the fit in `source`, check the card and write it atomically.
fn finish(mut card: MaterialCard, what: &str, report: &FitReport, files: &CardFiles) -> Result<(), Failure> {
    if let Some(name) = &files.name {
        card.name = name.clone();
    }
    let note = format!("{what} by drape calibrate ({} points, R^2 = {:.6})", report.points, report.r_squared);
    card.add_source_note(note);
    card.validate().map_err(|e| compute(anyhow!("the fitted card is not valid: {e}")))?;
    let text = card.to_toml_string();
    write_atomic(&files.out, |w| w.write_all(text.as_bytes())).map_err(compute)?;
    println!("wrote {}", files.out.display());
    Ok(())
}
