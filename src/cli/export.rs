//! `drape export --net NET.drape.json --mesh FLOW --format F --out PATH`: fibre orientations,
//! shear, thickness and fibre volume fraction of one net on the user's resin-flow mesh.
use super::{input, Failure};
use crate::io::flow::{check_flow, write_flow_with, FlowFormat, FlowOptions};
use crate::io::vtk::VtuEncoding;
use crate::io::{read_flow_mesh, read_net};
use crate::mapping::{map_plies, PlyMap, PlyToMap};
use crate::material::flow::{Cavity, PermeabilityModel, VF_CAP};
use crate::material::MaterialCard;
use crate::pipeline::unit_scale;
use clap::{Args, ValueEnum};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Cavity on the command line.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum CavityArg {
    /// Closed mould: thickness fixed, Vf = Vf0 / cos(shear).
    Fixed,
    /// Free thickness: t = t0 / cos(shear), Vf = Vf0.
    Free,
}

/// Arguments of `drape export`.
#[derive(Debug, Args)]
pub struct ExportArgs {
    /// Draped net (`<ply>.drape.json` from `drape run`, `drape kinematic` or `drape refine`).
    #[arg(long)]
    pub net: PathBuf,
    /// Resin-flow shell mesh: Nastran (.bdf .nas .dat .fem), Abaqus (.inp), OBJ or Gmsh 4 (.msh).
    #[arg(long)]
    pub mesh: PathBuf,
    /// Output format: vtu, nastran, abaqus, calculix, optistruct, rtmsim or csv.
    #[arg(long)]
    pub format: String,
    /// Output file (formats that need two files put the second beside it).
    #[arg(long)]
    pub out: PathBuf,
    /// Units of the flow mesh: m or mm.
    #[arg(long, default_value = "m")]
    pub mesh_units: String,
    /// Material card for the ply's thickness, Vf and fibre radius, and the MAT8 of the Nastran
    /// and OptiStruct decks (default: the card the net records, if any).
    #[arg(long)]
    pub material: Option<PathBuf>,
    /// Ply thickness as laid flat, m (overrides the card's).
    #[arg(long)]
    pub thickness: Option<f64>,
    /// What shear does to thickness and fibre volume fraction.
    #[arg(long, value_enum, default_value = "fixed")]
    pub cavity: CavityArg,
    /// Also write permeability tensors (Gebart's model on the fibre directions; needs a fibre
    /// radius from the card's [flow] section or --fibre-radius).
    #[arg(long)]
    pub permeability: bool,
    /// Fibre radius, m, for --permeability.
    #[arg(long)]
    pub fibre_radius: Option<f64>,
    /// The material the CalculiX deck's shell sections refer to (you define it).
    #[arg(long, default_value = crate::io::calculix::DEFAULT_MATERIAL)]
    pub material_name: String,
    /// VTU encoding: auto (binary from 50k elements on), ascii, or binary (zlib-compressed,
    /// appended).
    #[arg(long, default_value = "auto")]
    pub vtu: String,
}

pub fn run(a: ExportArgs) -> Result<(), Failure> {
    let format: FlowFormat = a.format.parse().map_err(|m| input(anyhow::anyhow!("--format: {m}")))?;
    let vtu: VtuEncoding = a.vtu.parse().map_err(|m| input(anyhow::anyhow!("--vtu: {m}")))?;
    let scale = unit_scale(&a.mesh_units).map_err(|m| input(anyhow::anyhow!("--mesh-units: {m}")))?;
    if let Some(t) = a.thickness {
        if !(t.is_finite() && t > 0.0) {
            return Err(input(anyhow::anyhow!("--thickness must be a positive length in metres, got {t}")));
        }
    }
    crate::io::calculix::check_material_name(&a.material_name)
        .map_err(|m| input(anyhow::anyhow!("--material-name: {m}")))?;
    check_out_file(&a.out)?;
    let net = read_net(&a.net).map_err(input)?;
    let card_path = a.material.clone().or_else(|| net.meta.material.as_ref().map(PathBuf::from));
    let card = match &card_path {
        Some(p) => Some(MaterialCard::load(p).map_err(|e| {
            input(anyhow::anyhow!(
                "{e}{}",
                if a.material.is_none() { " (the card the net records; give --material)" } else { "" }
            ))
        })?),
        None => None,
    };
    let permeability = if a.permeability {
        let radius = a.fibre_radius.or(card.as_ref().and_then(|c| c.flow).map(|f| f.fibre_radius)).ok_or_else(|| {
            input(anyhow::anyhow!(
                "--permeability needs a fibre radius: give --fibre-radius R (m) or a --material card with a [flow] section"
            ))
        })?;
        if !(radius.is_finite() && radius > 0.0) {
            return Err(input(anyhow::anyhow!("--fibre-radius must be a positive length in metres, got {radius}")));
        }
        Some(PermeabilityModel { fibre_radius: radius })
    } else {
        None
    };
    let cavity = match a.cavity {
        CavityArg::Fixed => Cavity::Fixed,
        CavityArg::Free => Cavity::Free,
    };
    let t = Instant::now();
    let mesh = read_flow_mesh(&a.mesh, scale).map_err(input)?;
    let read_ms = t.elapsed().as_secs_f64() * 1e3;
    let ply = PlyToMap { net: &net, card: card.as_ref(), thickness: a.thickness, permeability };
    let t = Instant::now();
    let map = map_plies(&mesh, &[ply], cavity, false, &mut |n| eprintln!("note: {n}")).map_err(input)?;
    let map_ms = t.elapsed().as_secs_f64() * 1e3;
    println!(
        "flow mesh {}: {} nodes, {} elements (read in {read_ms:.1} ms)",
        a.mesh.display(),
        mesh.nodes.len(),
        mesh.elements.len()
    );
    println!("{}", coverage_line(&map.plies[0]));
    println!("  mapped in {map_ms:.1} ms");
    let options = FlowOptions { material_name: a.material_name.clone(), vtu };
    for n in check_flow(&mesh, &map, format, &a.out, &options).map_err(super::write_failure)? {
        eprintln!("note: {n}");
    }
    let written = write_flow_with(&mesh, &map, format, &a.out, &options).map_err(super::write_failure)?;
    for p in written {
        println!("  wrote {}", p.display());
    }
    Ok(())
}

/// Check `--out` before anything is read: a file name (not a folder) whose folder is created
/// like `drape run` creates its folder, and can be written.
fn check_out_file(out: &Path) -> Result<(), Failure> {
    let bad = |why: String| input(anyhow::anyhow!("--out {}: {why}", out.display()));
    if out.is_dir() {
        return Err(bad("is a folder: give a file name, like flow.vtu".into()));
    }
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(parent).map_err(|e| {
        bad(format!("cannot create its folder {} ({e}): give a path you can write to", parent.display()))
    })?;
    let probe = parent.join(format!(".drape-probe-{}", std::process::id()));
    let probed = std::fs::write(&probe, b"");
    let _ = std::fs::remove_file(&probe);
    probed.map_err(|e| bad(format!("cannot write into {} ({e}): give a folder you can write to", parent.display())))
}

/// One line on a mapped ply: elements covered and their shear.
pub(crate) fn coverage_line(ply: &PlyMap) -> String {
    let c = ply.coverage();
    let share = 100.0 * c.covered as f64 / c.elements.max(1) as f64;
    let mut line = format!(
        "  ply {}: covers {} of {} elements ({share:.1}%); |shear| max {:.2} deg, mean {:.2} deg",
        ply.ply, c.covered, c.elements, c.max_abs_shear_deg, c.mean_abs_shear_deg
    );
    if c.covered < c.elements {
        line += &format!(
            "; note: the ply covers only part of the flow mesh, {} element(s) lie outside it and carry no fibre data",
            c.elements - c.covered
        );
    }
    if c.capped > 0 {
        line += &format!(
            "; Vf0 / cos(shear) passes the fibre packing limit in {} elements: Vf written as {VF_CAP:.4} there (the fabric locks before that)",
            c.capped
        );
    }
    line
}
