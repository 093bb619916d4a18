//! `drape run SCENE --out DIR`: every ply of a scene.
use super::kinematic::print_tool_report;
use crate::kinematic::fishnet::check_settings;
use super::summary::summary;
use super::{compute, input, Failure};
use crate::export::{write_net, Format};
use crate::geometry::ToolSurface;
use crate::kinematic::drape;
use crate::layup::Scene;
use crate::mechanics::refine::{refine, RefineSettings};
use super::refine::{annotate, print_solver};
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `drape run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// Scene file (TOML): the tool and the plies.
    pub scene: PathBuf,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
    /// Output formats: comma-separated json,vtu,csv, or none.
    #[arg(long, default_value = "json,vtu,csv")]
    pub format: String,
}

pub fn run(a: RunArgs) -> Result<(), Failure> {
    let formats = Format::parse_list(&a.format).map_err(|m| input(anyhow::anyhow!("--format: {m}")))?;
    let scene = Scene::load(&a.scene).map_err(input)?;
    for ply in &scene.plies {
        check_settings(&ply.settings)
            .map_err(|e| input(anyhow::anyhow!("scene {}: ply '{}' (line {}): {e}", a.scene.display(), ply.settings.name, ply.line)))?;
    }
    let t_load = Instant::now();
    let tool = ToolSurface::from_obj_scaled(&scene.tool, scene.scale).map_err(input)?;
    let load_ms = t_load.elapsed().as_secs_f64() * 1e3;
    print_tool_report(&scene.tool, &tool);
    // Drape every ply first, so a bad ply is reported before any file is written.
    let mut nets = Vec::new();
    let mut unconverged = Vec::new();
    for ply in &scene.plies {
        let mut net = drape(&tool, &ply.settings).map_err(|e| {
            input(anyhow::anyhow!("scene {}: ply '{}' (line {}): {e}", a.scene.display(), ply.settings.name, ply.line))
        })?;
        net.timing.load_ms = load_ms;
        net.meta.insert("tool".into(), serde_json::json!(scene.tool.display().to_string()));
        net.meta.insert("scene".into(), serde_json::json!(a.scene.display().to_string()));
        if let Some(r) = &ply.refinement {
            let settings = RefineSettings { mode: r.mode, ..RefineSettings::default() };
            let t = Instant::now();
            let refined = refine(&net, &tool, &r.material, &settings).map_err(input)?;
            let mut out = refined.net.clone();
            annotate(&mut out, &net, &refined, &r.material_path);
            out.timing.load_ms = load_ms;
            out.timing.generators_ms = 0.0;
            out.timing.fill_ms = t.elapsed().as_secs_f64() * 1e3;
            if !refined.ok() {
                unconverged.push(format!("ply '{}' ({:?})", ply.settings.name, refined.outcome()));
            }
            nets.push((out, ply.locking_angle, Some(refined)));
        } else {
            nets.push((net, ply.locking_angle, None));
        }
    }
    for (net, locking, refined) in &nets {
        let t_write = Instant::now();
        let written = write_net(net, &a.out, &formats).map_err(compute)?;
        println!("{}", summary(net, *locking, load_ms, t_write.elapsed().as_secs_f64() * 1e3));
        if let Some(r) = refined {
            print_solver(r);
        }
        for p in written {
            println!("  wrote {}", p.display());
        }
    }
    if !unconverged.is_empty() {
        return Err(compute(anyhow::anyhow!(
            "the mechanical solver stopped without equilibrium for {}; the last accepted states were written",
            unconverged.join(", ")
        )));
    }
    Ok(())
}
