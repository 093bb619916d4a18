//! `drape run SCENE --out DIR`: drape every ply of a layup, write the nets, the layup table and
//! (from the scene's `[export]`) the fibre data on the resin-flow mesh; this prints what
//! [`crate::pipeline::run::run`] reports.
use super::export::coverage_line;
use super::kinematic::print_tool_report;
use super::refine::print_solver;
use super::summary::summary;
use super::{compute, input, Failure};
use crate::io::Format;
use crate::kinematic::provenance::Stability;
use crate::layup::stack::PlyResult;
use crate::layup::table::{shear_range_warning, CoverageOf};
use crate::layup::{LockingSource, DEFAULT_LOCKING_ANGLE_DEG};
use crate::material::flow::COLLAPSED_SHEAR_DEG;
use crate::pipeline::run::{run as run_scene, Event, RunError};
use crate::pipeline::Scene;
use clap::Args;
use indicatif::ProgressBar;
use std::path::PathBuf;

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
    /// Remove nets (and their .vtu, .cells.csv, .svg) in the output folder that no earlier
    /// `drape run` into it wrote; without it the run refuses such a folder.
    #[arg(long)]
    pub replace: bool,
}

/// Run `drape run`.
pub fn run(a: RunArgs) -> Result<(), Failure> {
    let formats = Format::parse_list(&a.format).map_err(|m| input(anyhow::anyhow!("--format: {m}")))?;
    let scene = Scene::load(&a.scene).map_err(input)?;
    let mut bar: Option<ProgressBar> = None;
    run_scene(&scene, &a.out, &formats, a.replace, &mut |event| print(event, &mut bar)).map_err(|e: RunError| {
        if e.is_bad_input() {
            input(e)
        } else {
            compute(e)
        }
    })
}

/// Print one step of the run.
fn print(event: Event, bar: &mut Option<ProgressBar>) {
    match event {
        Event::ToolRead { path, tool } => print_tool_report(path, tool),
        Event::Draping { index, count, name } => {
            let bar = bar.get_or_insert_with(|| super::progress::bar(count as u64, "draping"));
            bar.set_position(index as u64);
            bar.set_message(name.to_string());
        }
        Event::Draped => {
            if let Some(bar) = bar.take() {
                bar.finish_and_clear();
            }
        }
        Event::PlyWritten { ply, result, files, load_ms, write_ms } => {
            let name = &ply.settings.name;
            if result.offset.relaxed > 0 {
                println!(
                    "ply '{name}': the plies below bridge concave corners tighter than their thickness ({} offset vertices moved off the normals)",
                    result.offset.relaxed
                );
            }
            if result.collapsed_below > 0 {
                println!(
                    "warning: ply '{name}': the plies below are sheared past {COLLAPSED_SHEAR_DEG} deg (collapsed or folded cells: the fabric bunches there) over {} tool vertices; the stack counts them at {COLLAPSED_SHEAR_DEG} deg",
                    result.collapsed_below
                );
            }
            if result.offset.folded > 0 {
                println!(
                    "warning: ply '{name}': the offset surface of the plies below folded over in {} triangles (a concave radius smaller than the stack); the ply was draped on it regardless",
                    result.offset.folded
                );
            }
            println!("{}", summary(&result.net, ply.locking_angle, load_ms, write_ms));
            if let Some(refined) = &result.refined {
                if let Some(levels) = result.net.meta.forming.as_ref().and_then(|f| f.levels_summary()) {
                    println!("  {levels}");
                }
                print_solver(refined);
            }
            for p in files {
                println!("  wrote {}", p.display());
            }
        }
        Event::Layup { scene, results } => println!("{}", layup_table(scene, results)),
        Event::NoPattern { ply } => println!("ply {ply}: no complete cell, no flat pattern"),
        Event::PatternWarning { ply, warning } => println!("warning: ply '{ply}': flat pattern: {warning}"),
        Event::RollWidthAssumed { width } => {
            println!("no roll_width in the scene: nesting on a roll {width:.3} m wide (the widest piece)")
        }
        Event::CuttingPlan { pieces, nesting, files } => {
            println!(
                "flat patterns: {}, {:.4} m^2 of fabric on {:.3} m of a {:.3} m roll ({:.4} m^2 used, {:.1}% waste)",
                super::counted(pieces, "piece", "pieces"),
                nesting.pattern_area,
                nesting.length,
                nesting.roll_width,
                nesting.used_area,
                100.0 * nesting.waste_fraction
            );
            for p in files {
                println!("  wrote {}", p.display());
            }
        }
        Event::TableWritten { path } => println!("wrote {}", path.display()),
        Event::FlowNote(n) => println!("note: {n}"),
        Event::FlowMapped { path, mesh, map, ms } => {
            println!(
                "flow mesh {}: {} nodes, {}; mapped {} in {:.1} ms",
                path.display(),
                mesh.nodes.len(),
                super::counted(mesh.elements.len(), "element", "elements"),
                super::counted(map.plies.len(), "ply", "plies"),
                ms
            );
            for ply in &map.plies {
                println!("{}", coverage_line(ply));
            }
        }
        Event::FlowWritten { files } => {
            for p in files {
                println!("  wrote {}", p.display());
            }
        }
        Event::Removed { files } => {
            for p in files {
                println!("removed {} (an earlier run's, not written by this one)", p.display());
            }
        }
    }
}

/// The layup table: one row per ply in stacking order.
fn layup_table(scene: &Scene, results: &[PlyResult]) -> String {
    let mut out = format!(
        "layup: {} plies on {}\n{:<12} {:>7} {:<20} {:<20} {:>7} {:>9} {:>9} {:>12} {:>12} {:>11} {:>9} {:>10} {:>9} {:>11}\n",
        scene.layup.plies.len(),
        scene.tool.display(),
        "ply",
        "angle",
        "method",
        "material",
        "locking",
        "max|g|",
        "mean|g|",
        "over lock",
        "coverage",
        "fabric",
        "mass",
        "offset",
        "draw-in",
        "wrinkled"
    );
    out += &format!(
        "{:<12} {:>7} {:<20} {:<20} {:>7} {:>9} {:>9} {:>12} {:>12} {:>11} {:>9} {:>10} {:>9} {:>11}\n",
        "", "deg", "", "", "deg", "deg", "deg", "m^2", "% of", "m^2", "kg", "mm", "mm", "m^2"
    );
    for (ply, r) in scene.layup.plies.iter().zip(results) {
        let s = &r.stats;
        out += &format!(
            "{:<12} {:>7} {:<20} {:<20} {:>7} {:>9.2} {:>9.2} {:>12.3e} {:>12} {:>11.4} {:>9} {:>10.3} {:>9} {:>11}\n",
            ply.settings.name,
            ply.angle_deg().map_or("warp".to_string(), |a| format!("{a:.1}")),
            format!(
                "{}{}{}",
                if r.choice.is_some() { "auto: " } else { "" },
                match &r.refined {
                    Some(refined) if refined.slide.is_some() => "SLIDES",
                    Some(refined) if !refined.ok() => "UNCONVERGED",
                    Some(refined) if refined.stability_verdict() == Some(Stability::Saddle) => "mechanical (saddle)",
                    Some(_) => "mechanical",
                    None => "kinematic",
                },
                if r.choice.as_ref().is_some_and(|c| c.not_assured()) { " NOT ASSURED" } else { "" }
            ),
            ply.material.as_ref().map_or("-", |m| m.name.as_str()),
            format!(
                "{:.1}{}",
                ply.locking_angle.to_degrees(),
                if ply.locking_source == LockingSource::Default { "*" } else { "" }
            ),
            s.max_abs_shear.to_degrees(),
            s.mean_abs_shear.to_degrees(),
            s.area_over_locking,
            format!("{:.1} {}", 100.0 * s.coverage.share(), CoverageOf::of(&s.coverage).name()),
            s.fabric_area,
            s.fabric_mass.map_or("-".to_string(), |m| format!("{m:.4}")),
            r.offset.max_distance * 1e3,
            r.net
                .meta
                .draw_in
                .as_ref()
                .and_then(|d| d.largest_overall())
                .map_or("-".to_string(), |e| format!("{:.2}", e.draw_in_m * 1e3)),
            r.net.meta.wrinkles.as_ref().map_or("-".to_string(), |w| format!("{:.3e}", w.summary.wrinkled_area_m2)),
        );
    }
    for (ply, r) in scene.layup.plies.iter().zip(results) {
        if let Some(line) = super::summary::wrinkles_line(&ply.settings.name, &r.net) {
            out += &line;
            out.push('\n');
        }
    }
    for (ply, r) in scene.layup.plies.iter().zip(results) {
        if let Some(d) = &r.net.meta.draw_in {
            out += &format!("draw-in: ply '{}': {}\n", ply.settings.name, d.describe());
        }
    }
    for (ply, r) in scene.layup.plies.iter().zip(results) {
        if let Some(refined) = &r.refined {
            out += &format!("contact: ply '{}': {}\n", ply.settings.name, refined.contact.summary().describe());
        }
    }
    for (ply, r) in scene.layup.plies.iter().zip(results) {
        if let Some(refined) = r.refined.as_ref().filter(|r| !r.ok()) {
            let what = if refined.slide.is_some() { "SLIDES" } else { "UNCONVERGED" };
            out += &format!(
                "{what}: ply '{}' is the solver's last accepted state, not an equilibrium: {}\n",
                ply.settings.name,
                refined.describe_failure()
            );
        }
    }
    for (ply, r) in scene.layup.plies.iter().zip(results) {
        if r.refined.as_ref().is_some_and(|f| f.ok() && f.stability_verdict() == Some(Stability::Saddle)) {
            out += &format!(
                "UNSTABLE: ply '{}' is an equilibrium but a saddle of the energy, not a minimum (the second-order check on its solver: line); the ply key escape_saddles = true tries to move it off (off by default: it can slide fabric past the tool's open edges)\n",
                ply.settings.name
            );
        }
    }
    for (ply, r) in scene.layup.plies.iter().zip(results) {
        if let Some(w) = shear_range_warning(ply, r) {
            out += &format!("warning: ply '{}': {w}\n", ply.settings.name);
        }
    }
    for (ply, r) in scene.layup.plies.iter().zip(results) {
        if let Some(c) = &r.choice {
            out += &format!("auto: ply '{}' ran {}: {}\n", ply.settings.name, c.headline(), c.reason);
        }
    }
    let defaults: Vec<&str> = scene
        .layup
        .plies
        .iter()
        .filter(|p| p.locking_source == LockingSource::Default)
        .map(|p| p.settings.name.as_str())
        .collect();
    if !defaults.is_empty() {
        out += &format!(
            "* locking angle: {} give(s) no locking_angle_deg and no material card with a two-slope shear law: the default {DEFAULT_LOCKING_ANGLE_DEG} deg is used; give locking_angle_deg in the scene\n",
            defaults.join(", ")
        );
    }
    out.trim_end().to_string()
}
