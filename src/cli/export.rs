//! `drape export --net NET.drape.json --mesh FLOW --format F --out PATH`: fibre orientations,
//! shear, thickness and fibre volume fraction of one net on the user's resin-flow mesh.
use super::{counted, input, Failure};
use crate::io::read_net;
use crate::mapping::PlyMap;
use crate::material::flow::{Cavity, COLLAPSED_SHEAR_DEG, VF_CAP};
use crate::pipeline::export::{export_net, ExportOptions};
use clap::{Args, ValueEnum};
use std::path::PathBuf;

/// Cavity on the command line.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum CavityArg {
    /// Closed mould: thickness fixed, Vf = Vf0 / cos(shear) (shear at most 75 deg, a collapsed cell).
    Fixed,
    /// Free thickness: t = t0 / cos(shear) (shear at most 75 deg, a collapsed cell), Vf = Vf0.
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
    /// Ply thickness as laid flat, in --units (overrides the card's).
    #[arg(long)]
    pub thickness: Option<f64>,
    /// Units of the lengths given here (--thickness, --fibre-radius): m or mm. The flow mesh's
    /// are --mesh-units.
    #[arg(long, default_value = "m")]
    pub units: String,
    /// What shear does to thickness and fibre volume fraction.
    #[arg(long, value_enum, default_value = "fixed")]
    pub cavity: CavityArg,
    /// Also write permeability tensors (Gebart's model on the fibre directions; needs a fibre
    /// radius from the card's [flow] section or --fibre-radius).
    #[arg(long)]
    pub permeability: bool,
    /// Fibre radius, in --units, for --permeability.
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
    let scale = crate::pipeline::unit_scale(&a.units).map_err(|m| input(anyhow::anyhow!("--units: {m}")))?;
    let options = ExportOptions {
        mesh_units: a.mesh_units,
        material: a.material,
        thickness: a.thickness.map(|t| t * scale),
        cavity: match a.cavity {
            CavityArg::Fixed => Cavity::Fixed,
            CavityArg::Free => Cavity::Free,
        },
        permeability: a.permeability,
        fibre_radius: a.fibre_radius.map(|r| r * scale),
        material_name: a.material_name,
        vtu: a.vtu,
    };
    let plan = options.check(&a.format, &a.out)?;
    let net = read_net(&a.net).map_err(input)?;
    let done = export_net(&net, &a.mesh, &a.out, &plan, &options, &mut |n| eprintln!("note: {n}"))?;
    println!(
        "flow mesh {}: {} nodes, {} (read in {:.1} ms)",
        a.mesh.display(),
        done.mesh.nodes.len(),
        counted(done.mesh.elements.len(), "element", "elements"),
        done.read_ms
    );
    println!("{}", coverage_line(&done.map));
    println!("  mapped in {:.1} ms", done.map_ms);
    for p in done.files {
        println!("  wrote {}", p.display());
    }
    Ok(())
}

/// One line on a mapped ply: elements covered and their shear.
pub(crate) fn coverage_line(ply: &PlyMap) -> String {
    let c = ply.coverage();
    let share = 100.0 * c.covered as f64 / c.elements.max(1) as f64;
    let mut line = format!(
        "  ply {}: covers {} of {} ({share:.1}%); |shear| max {:.2} deg, mean {:.2} deg",
        ply.ply,
        c.covered,
        counted(c.elements, "element", "elements"),
        c.max_abs_shear_deg,
        c.mean_abs_shear_deg
    );
    if c.covered < c.elements {
        line += &format!(
            "; note: the ply covers only part of the flow mesh, {} outside it carr{} no fibre data",
            counted(c.elements - c.covered, "element", "elements"),
            if c.elements - c.covered == 1 { "ies" } else { "y" }
        );
    }
    if c.collapsed > 0 {
        line += &format!(
            "; {} lie{} on cells of the drape sheared past {COLLAPSED_SHEAR_DEG} deg (collapsed or folded: the fabric bunches there): {} thickness and Vf are written as at {COLLAPSED_SHEAR_DEG} deg",
            counted(c.collapsed, "element", "elements"),
            if c.collapsed == 1 { "s" } else { "" },
            if c.collapsed == 1 { "its" } else { "their" }
        );
    }
    if c.capped > 0 {
        line += &format!(
            "; Vf0 / cos(shear) passes the fibre packing limit in {}: Vf written as {VF_CAP:.4} there (the fabric locks before that)",
            counted(c.capped, "element", "elements")
        );
    }
    line
}
