//! `drape run SCENE --out DIR`: drape every ply of a layup, write the nets, the layup table and
//! (from the scene's `[export]`) the fibre data on the resin-flow mesh.
use super::kinematic::print_tool_report;
use super::refine::print_solver;
use super::summary::summary;
use super::{compute, input, Failure};
use crate::io::drawing::write_cutting_plan;
use crate::io::flow::write_flow;
use crate::io::read_flow_mesh;
use crate::io::{write_atomic, write_net, Format};
use crate::kinematic::fishnet::check_settings;
use crate::layup::flat::{flat_pattern_with_margin, FlatError};
use crate::layup::nest::{nest, Nesting, Rotation};
use crate::layup::scene::SceneExport;
use crate::layup::stack::{drape_layup, PlyResult};
use crate::layup::Scene;
use crate::mapping::{map_net, LayupMap, PermeabilityModel, PlyMapSettings};
use clap::Args;
use std::path::{Path, PathBuf};
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
        check_settings(&ply.settings).map_err(|e| {
            input(anyhow::anyhow!("scene {}: ply '{}' (line {}): {e}", a.scene.display(), ply.settings.name, ply.line))
        })?;
    }
    let t_load = Instant::now();
    let tool = crate::layup::load_tool(&scene.tool, scene.scale).map_err(|m| input(anyhow::anyhow!(m)))?;
    let load_ms = t_load.elapsed().as_secs_f64() * 1e3;
    print_tool_report(&scene.tool, &tool);
    // Drape every ply first, so a bad ply is reported before any file is written.
    let bar = super::progress::bar(scene.plies.len() as u64, "draping");
    let mut results = drape_layup(&scene, &tool, |k, name| {
        bar.set_position(k as u64);
        bar.set_message(name.to_string());
    })
    .map_err(|e| input(anyhow::anyhow!("scene {}: {e}", a.scene.display())))?;
    bar.finish_and_clear();
    let mut unconverged = Vec::new();
    for (ply, r) in scene.plies.iter().zip(results.iter_mut()) {
        r.net.timing.load_ms = load_ms;
        r.net.meta.insert("tool".into(), serde_json::json!(scene.tool.display().to_string()));
        r.net.meta.insert("scene".into(), serde_json::json!(a.scene.display().to_string()));
        if let Some(refined) = &r.refined {
            if !refined.ok() {
                unconverged.push(format!("ply '{}' ({:?})", ply.settings.name, refined.outcome()));
            }
        }
    }
    for (ply, r) in scene.plies.iter().zip(&results) {
        if r.offset.relaxed > 0 {
            println!(
                "ply '{}': the plies below bridge concave corners tighter than their thickness ({} offset vertices moved off the normals)",
                ply.settings.name, r.offset.relaxed
            );
        }
        if r.offset.folded > 0 {
            println!(
                "warning: ply '{}': the offset surface of the plies below folded over in {} triangles (a concave radius smaller than the stack); the ply was draped on it regardless",
                ply.settings.name, r.offset.folded
            );
        }
        let t_write = Instant::now();
        let written = write_net(&r.net, &a.out, &formats).map_err(compute)?;
        println!("{}", summary(&r.net, ply.locking_angle, load_ms, t_write.elapsed().as_secs_f64() * 1e3));
        if let Some(refined) = &r.refined {
            print_solver(refined);
        }
        for p in written {
            println!("  wrote {}", p.display());
        }
    }
    println!("{}", layup_table(&scene, &results));
    let nesting = cutting_plan(&scene, &results, &a.out)?;
    let table = a.out.join("layup.json");
    let mut json = layup_json(&scene, &results);
    if let Some(n) = nesting {
        json["nesting"] = serde_json::json!({
            "roll_width_m": n.roll_width,
            "gap_m": n.gap,
            "length_m": n.length,
            "used_area_m2": n.used_area,
            "pattern_area_m2": n.pattern_area,
            "waste_area_m2": n.waste_area,
            "waste_fraction": n.waste_fraction,
        });
    }
    write_atomic(&table, |w| {
        serde_json::to_writer_pretty(&mut *w, &json)?;
        std::io::Write::write_all(w, b"\n")
    })
    .map_err(compute)?;
    println!("wrote {}", table.display());
    // Last, so that a bad flow mesh costs nothing already computed.
    if let Some(export) = &scene.export {
        export_flow(&scene, export, &results, &a.out)?;
    }
    if !unconverged.is_empty() {
        return Err(compute(anyhow::anyhow!(
            "the mechanical solver stopped without equilibrium for {}; the last accepted states were written",
            unconverged.join(", ")
        )));
    }
    Ok(())
}

/// Flat patterns of every ply, nested on the roll: `patterns.dxf`, `patterns.svg` and one SVG a
/// ply. Plies without a complete cell have no pattern and are named.
fn cutting_plan(scene: &Scene, results: &[PlyResult], out: &Path) -> Result<Option<Nesting>, Failure> {
    let mut patterns = Vec::new();
    for r in results {
        match flat_pattern_with_margin(&r.net, scene.cutting_margin) {
            Ok(p) => patterns.push(p),
            Err(FlatError::NoCells { ply }) => println!("ply {ply}: no complete cell, no flat pattern"),
            Err(e) => return Err(input(e)),
        }
    }
    if patterns.is_empty() {
        return Ok(None);
    }
    let rotation = if scene.rotate_patterns { Rotation::AllowQuarterTurn } else { Rotation::WarpAlongRoll };
    let roll_width = match scene.roll_width {
        Some(w) => w,
        None => {
            // Without a roll width the pieces go on a roll as wide as the widest of them.
            let w = patterns.iter().map(|p| p.size()[1]).fold(0.0, f64::max);
            println!("no roll_width in the scene: nesting on a roll {w:.3} m wide (the widest piece)");
            w
        }
    };
    let nesting = nest(&patterns, roll_width, scene.nesting_gap, rotation).map_err(input)?;
    let written = write_cutting_plan(&patterns, &nesting, out, "patterns").map_err(compute)?;
    println!(
        "flat patterns: {} pieces, {:.4} m^2 of fabric on {:.3} m of a {:.3} m roll ({:.4} m^2 used, {:.1}% waste)",
        patterns.len(),
        nesting.pattern_area,
        nesting.length,
        nesting.roll_width,
        nesting.used_area,
        100.0 * nesting.waste_fraction
    );
    for p in written {
        println!("  wrote {}", p.display());
    }
    Ok(Some(nesting))
}

/// Map every ply onto the scene's resin-flow mesh and write the formats it asks for as
/// `DIR/flow.<ext>` (`FlowFormat::scene_file`; field names prefixed by the ply).
fn export_flow(scene: &Scene, export: &SceneExport, results: &[PlyResult], out: &Path) -> Result<(), Failure> {
    let t = Instant::now();
    let mesh = read_flow_mesh(&export.mesh, scene.scale)
        .map_err(|e| input(anyhow::anyhow!("scene {}: [export] mesh: {e}", scene.path.display())))?;
    let mut plies = Vec::new();
    for (ply, r) in scene.plies.iter().zip(results) {
        let card = ply.material.as_ref().map(|m| &m.card);
        let permeability = if export.permeability {
            let radius = card.and_then(|c| c.flow).map(|f| f.fibre_radius).ok_or_else(|| {
                input(anyhow::anyhow!(
                    "scene {}: ply '{}' (line {}): [export] permeability = true needs a material card with a [flow] section (fibre_radius)",
                    scene.path.display(),
                    ply.settings.name,
                    ply.line
                ))
            })?;
            Some(PermeabilityModel { fibre_radius: radius })
        } else {
            None
        };
        let (settings, notes) = PlyMapSettings::for_net(&r.net, card, ply.thickness, export.cavity, permeability);
        for n in notes {
            println!("note: {n}");
        }
        plies.push(map_net(&r.net, &mesh, &settings).map_err(compute)?);
    }
    let map = LayupMap::new(plies, true, mesh.elements.len());
    println!(
        "flow mesh {}: {} nodes, {} elements; mapped {} plies in {:.1} ms",
        export.mesh.display(),
        mesh.nodes.len(),
        mesh.elements.len(),
        map.plies.len(),
        t.elapsed().as_secs_f64() * 1e3
    );
    for k in 0..map.plies.len() {
        println!("{}", super::export::coverage_line(&map, k));
    }
    for &format in &export.formats {
        let path = out.join(format.scene_file());
        for p in write_flow(&mesh, &map, format, &path).map_err(compute)? {
            println!("  wrote {}", p.display());
        }
    }
    Ok(())
}

/// The layup table: one row per ply in stacking order.
fn layup_table(scene: &Scene, results: &[PlyResult]) -> String {
    let mut out = format!(
        "layup: {} plies on {}\n{:<12} {:>7} {:<10} {:<20} {:>9} {:>9} {:>12} {:>8} {:>11} {:>9} {:>10}\n",
        scene.plies.len(),
        scene.tool.display(),
        "ply",
        "angle",
        "method",
        "material",
        "max|g|",
        "mean|g|",
        "over lock",
        "coverage",
        "fabric",
        "mass",
        "offset"
    );
    out += &format!(
        "{:<12} {:>7} {:<10} {:<20} {:>9} {:>9} {:>12} {:>8} {:>11} {:>9} {:>10}\n",
        "", "deg", "", "", "deg", "deg", "m^2", "%", "m^2", "kg", "mm"
    );
    for (ply, r) in scene.plies.iter().zip(results) {
        let s = &r.stats;
        out += &format!(
            "{:<12} {:>7} {:<10} {:<20} {:>9.2} {:>9.2} {:>12.3e} {:>8.1} {:>11.4} {:>9} {:>10.3}\n",
            ply.settings.name,
            ply.angle_deg().map_or("warp".to_string(), |a| format!("{a:.1}")),
            if ply.refinement.is_some() { "mechanical" } else { "kinematic" },
            ply.material.as_ref().map_or("-", |m| m.name.as_str()),
            s.max_abs_shear.to_degrees(),
            s.mean_abs_shear.to_degrees(),
            s.area_over_locking,
            100.0 * s.coverage,
            s.fabric_area,
            s.fabric_mass.map_or("-".to_string(), |m| format!("{m:.4}")),
            r.offset.max_distance * 1e3,
        );
    }
    out.trim_end().to_string()
}

/// `layup.json`: the layup table for reports and other tools.
fn layup_json(scene: &Scene, results: &[PlyResult]) -> serde_json::Value {
    let path = |p: &Path| p.display().to_string();
    let plies: Vec<serde_json::Value> = scene
        .plies
        .iter()
        .zip(results)
        .map(|(ply, r)| {
            let s = &r.stats;
            serde_json::json!({
                "name": ply.settings.name,
                "material": ply.material.as_ref().map(|m| m.name.clone()),
                "material_card": ply.material.as_ref().map(|m| path(&m.path)),
                "angle_deg": ply.angle_deg(),
                "warp": [r.warp.x, r.warp.y, r.warp.z],
                "method": if ply.refinement.is_some() { "mechanical" } else { "kinematic" },
                "thickness_m": ply.thickness,
                "locking_angle_deg": ply.locking_angle.to_degrees(),
                "max_abs_shear_deg": s.max_abs_shear.to_degrees(),
                "mean_abs_shear_deg": s.mean_abs_shear.to_degrees(),
                "area_over_locking_m2": s.area_over_locking,
                "coverage": s.coverage,
                "cells": s.cells,
                "draped_area_m2": s.draped_area,
                "fabric_area_m2": s.fabric_area,
                "fabric_mass_kg": s.fabric_mass,
                "offset_m": r.offset.max_distance,
                "offset_folded_triangles": r.offset.folded,
                "offset_bridged_vertices": r.offset.relaxed,
            })
        })
        .collect();
    serde_json::json!({
        "scene": path(&scene.path),
        "tool": path(&scene.tool),
        "plies": plies,
        "nesting": serde_json::Value::Null,
    })
}
