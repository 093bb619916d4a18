//! One net on a resin-flow mesh from the options of `drape export`, as library calls: the
//! options and the output path checked before anything is read ([`ExportOptions::check`]), then
//! the mapping and the writing ([`export_net`]). The command line and the Python package both
//! come through here.
use super::failure::{input, write_failure, Failure};
use super::unit_scale;
use crate::io::flow::{check_flow, write_flow_with, FlowFormat, FlowOptions};
use crate::io::read_flow_mesh;
use crate::io::vtk::VtuEncoding;
use crate::kinematic::DrapeNet;
use crate::mapping::{map_plies, FlowMesh, PlyMap, PlyToMap};
use crate::material::flow::{Cavity, PermeabilityModel};
use crate::material::MaterialCard;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The options of `drape export` besides its files and format. [`Default`] gives the command
/// line's defaults.
#[derive(Debug, Clone)]
pub struct ExportOptions {
    /// Unit of the flow mesh: `m` or `mm`.
    pub mesh_units: String,
    /// Material card (default: the one the net records, if any).
    pub material: Option<PathBuf>,
    /// Ply thickness as laid flat, m (overrides the card's).
    pub thickness: Option<f64>,
    /// What shear does to thickness and fibre volume fraction.
    pub cavity: Cavity,
    /// Also write Gebart's permeability on the fibre directions.
    pub permeability: bool,
    /// Fibre radius, m, for the permeability (default: the card's `[flow]`).
    pub fibre_radius: Option<f64>,
    /// The material the CalculiX deck's shell sections refer to.
    pub material_name: String,
    /// VTU encoding: `auto`, `ascii` or `binary`.
    pub vtu: String,
}

impl Default for ExportOptions {
    fn default() -> Self {
        ExportOptions {
            mesh_units: "m".into(),
            material: None,
            thickness: None,
            cavity: Cavity::Fixed,
            permeability: false,
            fibre_radius: None,
            material_name: crate::io::calculix::DEFAULT_MATERIAL.into(),
            vtu: "auto".into(),
        }
    }
}

/// A cavity by name: `fixed` or `free`.
pub fn parse_cavity(s: &str) -> Result<Cavity, Failure> {
    match s.trim() {
        "fixed" => Ok(Cavity::Fixed),
        "free" => Ok(Cavity::Free),
        other => Err(input(anyhow::anyhow!("--cavity: unknown cavity '{other}': use fixed or free"))),
    }
}

/// An export whose options and output path passed the checks.
#[derive(Debug)]
pub struct ExportPlan {
    format: FlowFormat,
    vtu: VtuEncoding,
    mesh_scale: f64,
}

/// What an export did.
#[derive(Debug)]
pub struct Exported {
    /// The flow mesh as read.
    pub mesh: FlowMesh,
    /// The ply on it.
    pub map: PlyMap,
    /// Time to read the mesh and to map the net, ms.
    pub read_ms: f64,
    /// Time to map the net, ms.
    pub map_ms: f64,
    /// The files written.
    pub files: Vec<PathBuf>,
}

impl ExportOptions {
    /// Check the options, `format` and the output file `out` before anything is read.
    pub fn check(&self, format: &str, out: &Path) -> Result<ExportPlan, Failure> {
        let bad = |m: String| input(anyhow::anyhow!(m));
        let format: FlowFormat = format.parse().map_err(|m| bad(format!("--format: {m}")))?;
        let vtu: VtuEncoding = self.vtu.parse().map_err(|m| bad(format!("--vtu: {m}")))?;
        let mesh_scale = unit_scale(&self.mesh_units).map_err(|m| bad(format!("--mesh-units: {m}")))?;
        if let Some(t) = self.thickness {
            if !(t.is_finite() && t > 0.0) {
                return Err(bad(format!("--thickness must be a positive length in metres, got {t}")));
            }
        }
        crate::io::calculix::check_material_name(&self.material_name)
            .map_err(|m| bad(format!("--material-name: {m}")))?;
        check_out_file(out)?;
        Ok(ExportPlan { format, vtu, mesh_scale })
    }
}

/// Map `net` onto the flow mesh `mesh` and write it to `out` as `plan` says; notes on the mesh
/// and the map go to `note`.
pub fn export_net(
    net: &DrapeNet,
    mesh: &Path,
    out: &Path,
    plan: &ExportPlan,
    options: &ExportOptions,
    note: &mut dyn FnMut(&str),
) -> Result<Exported, Failure> {
    let card_path = options.material.clone().or_else(|| net.meta.material.as_ref().map(PathBuf::from));
    let card = match &card_path {
        Some(p) => Some(MaterialCard::load(p).map_err(|e| {
            input(anyhow::anyhow!(
                "{e}{}",
                if options.material.is_none() { " (the card the net records; give --material)" } else { "" }
            ))
        })?),
        None => None,
    };
    let permeability = if options.permeability {
        let radius =
            options.fibre_radius.or(card.as_ref().and_then(|c| c.flow).map(|f| f.fibre_radius)).ok_or_else(|| {
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
    let t = Instant::now();
    let flow_mesh = read_flow_mesh(mesh, plan.mesh_scale).map_err(input)?;
    let read_ms = t.elapsed().as_secs_f64() * 1e3;
    let ply = PlyToMap { net, card: card.as_ref(), thickness: options.thickness, permeability };
    let t = Instant::now();
    let mut map = map_plies(&flow_mesh, &[ply], options.cavity, false, note).map_err(input)?;
    let map_ms = t.elapsed().as_secs_f64() * 1e3;
    let flow_options = FlowOptions { material_name: options.material_name.clone(), vtu: plan.vtu };
    for n in check_flow(&flow_mesh, &map, plan.format, out, &flow_options).map_err(write_failure)? {
        note(&n);
    }
    let files = write_flow_with(&flow_mesh, &map, plan.format, out, &flow_options).map_err(write_failure)?;
    let map = map.plies.swap_remove(0);
    Ok(Exported { mesh: flow_mesh, map, read_ms, map_ms, files })
}

/// Check the output file before anything is read: a file name (not a folder) whose folder is
/// created like `drape run` creates its folder, and can be written.
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
