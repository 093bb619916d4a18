//! `drape kinematic`: one ply from command-line arguments.
use super::summary::summary_with;
use super::{input, parse_pair, parse_vec3, Failure};
use crate::geometry::ToolSurface;
use crate::io::{write_net_shears, Format};
use crate::pipeline::ply::{check_converged, read_tool, PlyOptions};
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `drape kinematic`.
#[derive(Debug, Args)]
pub struct KinematicArgs {
    /// Tool surface: Wavefront OBJ, STL (ASCII or binary), or a shell mesh (Abaqus .inp, Nastran .bdf, Gmsh .msh).
    #[arg(long)]
    pub tool: PathBuf,
    /// Seed point X,Y,Z (projected onto the tool; must lie within one spacing of it).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub origin: [f64; 3],
    /// Warp direction DX,DY,DZ (projected onto the tangent plane at the origin).
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    pub warp: [f64; 3],
    /// Fibre segment length d.
    #[arg(long, allow_hyphen_values = true)]
    pub spacing: f64,
    /// Grid size NU,NV (nodes along warp, weft).
    #[arg(long, value_parser = parse_pair, required_unless_present = "outline", conflicts_with = "outline")]
    pub grid: Option<[usize; 2]>,
    /// Ply outline instead of a grid: a closed polyline on the tool, x,y,z per line.
    #[arg(long)]
    pub outline: Option<PathBuf>,
    /// Grid indices I,J of the origin node (default: the centre).
    #[arg(long, value_parser = parse_pair)]
    pub origin_node: Option<[usize; 2]>,
    /// Pre-shear in degrees: the generators meet at 90 - pre-shear.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub pre_shear: f64,
    /// Generators: geodesic, min-shear, or steer:FILE (warp follows the curve in FILE).
    #[arg(long, default_value = "geodesic")]
    pub generators: String,
    /// Shear (degrees) at which a node is refused as a collapsing cell.
    #[arg(long, default_value_t = crate::kinematic::DEFAULT_MAX_SHEAR_DEG)]
    pub max_shear: f64,
    /// The surface the net lies on: facets (the tool's facets as given) or smooth (the smooth
    /// surface over them, the one the pressed contact slides on).
    #[arg(long, default_value = "facets")]
    pub surface: String,
    /// Locking angle (degrees) for the summary's count of cells over it [default: the
    /// material card's two-slope locking angle, else 45].
    #[arg(long)]
    pub locking_angle: Option<f64>,
    /// kinematic, or auto: mechanics (pressed, with --material) runs only where the kinematic
    /// net is not within --tolerance of it; the choice and its reason are in the net's meta.
    #[arg(long, default_value = "kinematic")]
    pub method: String,
    /// Material card (TOML): needed by --method auto; gives the locking angle.
    #[arg(long)]
    pub material: Option<PathBuf>,
    /// --method auto: the largest cell-shear error accepted, degrees.
    #[arg(long)]
    pub tolerance: Option<f64>,
    /// Units of the OBJ and of the lengths given here: m or mm (output is always in metres).
    #[arg(long, default_value = "m")]
    pub units: String,
    /// Ply name (file names derive from it).
    #[arg(long, default_value = "ply")]
    pub name: String,
    /// Output formats: comma-separated json,vtu,csv, or none.
    #[arg(long, default_value = "json")]
    pub format: String,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
}

pub fn run(a: KinematicArgs) -> Result<(), Failure> {
    let formats = Format::parse_list(&a.format).map_err(|m| input(anyhow::anyhow!("--format: {m}")))?;
    let options = PlyOptions {
        origin: a.origin,
        warp: a.warp,
        spacing: a.spacing,
        grid: a.grid,
        outline: a.outline,
        origin_node: a.origin_node,
        pre_shear_deg: a.pre_shear,
        generators: a.generators,
        max_shear_deg: a.max_shear,
        surface: a.surface,
        locking_angle_deg: a.locking_angle,
        method: a.method,
        material: a.material,
        tolerance_deg: a.tolerance,
        units: a.units,
        name: a.name,
    };
    // Cheap argument checks come before the (possibly slow) tool load.
    let ply = options.prepare()?;
    let t_load = Instant::now();
    let tool = read_tool(&a.tool, ply.scale)?;
    let load_ms = t_load.elapsed().as_secs_f64() * 1e3;
    print_tool_report(&a.tool, &tool);
    let mut net = ply.drape(&tool)?;
    if let Some(choice) = &net.meta.method_choice {
        println!("auto: ran {}: {}", choice.headline(), choice.reason);
    }
    net.timing.load_ms = load_ms;
    net.meta.tool = Some(a.tool.display().to_string());
    net.meta.tool_scale = Some(ply.scale);
    let t_write = Instant::now();
    let (written, shears) = write_net_shears(&net, &a.out, &formats).map_err(super::write_failure)?;
    let write_ms = t_write.elapsed().as_secs_f64() * 1e3;
    let locking = ply.locking_angle_deg.to_radians();
    // The statistics from the shears the writer's checks computed (the same figures).
    let stats = match &shears {
        Some(s) => net.shear_stats_from(s, locking),
        None => net.shear_stats(locking),
    };
    println!("{}", summary_with(&net, &stats, locking, load_ms, write_ms));
    if let Some(line) = super::summary::wrinkles_line(&net.name, &net) {
        println!("{line}");
    }
    for p in written {
        println!("  wrote {}", p.display());
    }
    if let Some(w) = ply.shear_range_warning(stats.max_abs.to_degrees()) {
        println!("warning: ply '{}': {w}", net.name);
    }
    check_converged(&net)
}

/// One line on what the mesh checks found.
pub(crate) fn print_tool_report(path: &std::path::Path, tool: &ToolSurface) {
    let r = tool.report();
    let mut notes = Vec::new();
    for (n, what) in [
        (r.polygons_triangulated, "polygons triangulated"),
        (r.vertices_welded, "vertices welded"),
        (r.degenerate_faces_dropped, "degenerate faces dropped"),
        (r.duplicate_faces_dropped, "duplicate faces dropped"),
        (r.non_manifold_edges, "non-manifold edges"),
        (r.flipped_faces, "flipped faces turned over"),
    ] {
        if n > 0 {
            notes.push(format!("{n} {what}"));
        }
    }
    println!(
        "tool {}: {} triangles, {} vertices, {} boundary edges, {} component(s){}",
        path.display(),
        r.triangles,
        r.vertices,
        r.boundary_edges,
        r.components,
        if notes.is_empty() { String::new() } else { format!("; {}", notes.join(", ")) }
    );
}
