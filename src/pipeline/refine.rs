//! A kinematic net refined mechanically from the options of `drape refine`, as library calls:
//! the command line and the Python package both come through here.
use super::failure::{compute, input, Failure};
use super::unit_scale;
use crate::geometry::{Point, ToolSurface, Vector};
use crate::kinematic::provenance::{FormingRecord, SheetFeature, StackSide};
use crate::kinematic::DrapeNet;
use crate::material::MaterialCard;
use crate::mechanics::forming::{die_facing, turned_over, Forming};
use crate::mechanics::refine::{annotate, refine, PressedSurface, RefineSettings, Refined};
use crate::mechanics::sheet::{check_blank, SheetFeatures};
use crate::mechanics::{ContactMode, SolverSettings};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// The options of `drape refine` besides its files. [`Default`] gives the command line's
/// defaults.
#[derive(Debug, Clone)]
pub struct RefineOptions {
    /// Contact with the tool: pressed (nodes slide on it) or free (gravity drape).
    pub mode: ContactMode,
    /// Unit of the tool file, `m` or `mm` (default: the one the net records, else m).
    pub units: Option<String>,
    /// Pressed nodes slide on the facets as given instead of the smooth patches.
    pub facets: bool,
    /// Gravity, m/s^2.
    pub gravity: [f64; 3],
    /// Gravity is applied in this many steps.
    pub load_steps: usize,
    /// Free drape: nodes the tool holds up stay where they touch.
    pub stick: bool,
    /// Coulomb's coefficient (default: the card's `[contact] friction`, else 0).
    pub friction: Option<f64>,
    /// Grid nodes held in place.
    pub holds: Vec<[usize; 2]>,
    /// Move off a saddle the stability check finds and iterate on.
    pub escape_saddles: bool,
    /// Solver iteration limit per load step.
    pub max_iterations: usize,
    /// The die a formed net (one that records `meta.forming`) was formed with, in the tool's
    /// units (default: the file the net records).
    pub die: Option<PathBuf>,
    /// The side of the tool the ply lies on (default: the side the net records, else the one
    /// the tool's facets' normals point to).
    pub stack_side: Option<StackSide>,
}

impl Default for RefineOptions {
    fn default() -> Self {
        RefineOptions {
            mode: ContactMode::Pressed,
            units: None,
            facets: false,
            gravity: [0.0, 0.0, -9.80665],
            load_steps: 1,
            stick: false,
            friction: None,
            holds: Vec::new(),
            escape_saddles: false,
            max_iterations: 100,
            die: None,
            stack_side: None,
        }
    }
}

/// A stacking side by name: `normal` or `opposite`.
pub fn parse_stack_side(s: &str) -> Result<StackSide, Failure> {
    match s.trim() {
        "normal" => Ok(StackSide::Normal),
        "opposite" => Ok(StackSide::Opposite),
        other => Err(input(anyhow::anyhow!(
            "--stack-side: unknown side '{other}': use normal (the side the tool's facets' normals point to) or opposite"
        ))),
    }
}

/// A contact mode by name: `pressed` or `free`.
pub fn parse_mode(s: &str) -> Result<ContactMode, Failure> {
    match s.trim() {
        "pressed" => Ok(ContactMode::Pressed),
        "free" => Ok(ContactMode::Free),
        other => Err(input(anyhow::anyhow!("--mode: unknown mode '{other}': use pressed or free"))),
    }
}

impl RefineOptions {
    /// The checks that need no file.
    pub fn check(&self) -> Result<(), Failure> {
        if self.load_steps == 0 {
            return Err(input(anyhow::anyhow!("--load-steps must be at least 1")));
        }
        Ok(())
    }

    /// The side of the tool `net` lies on: the options', else the one it records, else the
    /// normals' side.
    pub fn stack_side(&self, net: &DrapeNet) -> StackSide {
        self.stack_side.or(net.meta.stack_side).unwrap_or(StackSide::Normal)
    }

    /// Metres per unit of the tool file: the options' units, else the ones `net` records.
    pub fn tool_scale(&self, net: &DrapeNet) -> Result<f64, Failure> {
        match &self.units {
            Some(u) => unit_scale(u).map_err(|m| input(anyhow::anyhow!("--units: {m}"))),
            None => Ok(net.meta.tool_scale.filter(|s| s.is_finite() && *s > 0.0).unwrap_or(1.0)),
        }
    }

    /// The solver's settings for `net` under `material` (friction, holds as offsets from the
    /// seed node).
    pub fn settings(&self, net: &DrapeNet, material: &MaterialCard) -> Result<RefineSettings, Failure> {
        self.check()?;
        let friction = self.friction.or(material.friction).unwrap_or(0.0);
        if !(friction.is_finite() && friction >= 0.0) {
            return Err(input(anyhow::anyhow!("--friction must be a finite number >= 0, got {friction}")));
        }
        let (i0, j0) = net.origin_node;
        let forming = self.held_by_its_tools(net)?;
        // A formed blank cut to a shape is the fabric it was formed as.
        let blank = match net.meta.forming.as_ref().and_then(|f| f.blank_m.clone()) {
            Some(b) => {
                check_blank(&b).map_err(|e| input(anyhow::anyhow!("meta.forming.blank_m: {e}")))?;
                Some(b)
            }
            None => None,
        };
        // The sheet's features are its scene's, not the net's (a formed blank's outline aside):
        // refined without them, the sheet would be joined across its cuts and seams and lose its
        // folds, reinforcements or blank.
        let sheet = SheetFeatures { blank, ..Default::default() };
        let unknown: Vec<&str> = net
            .meta
            .sheet_features
            .iter()
            .filter(|f| !(**f == SheetFeature::Blank && sheet.blank.is_some()))
            .map(|f| f.name())
            .collect();
        if !unknown.is_empty() {
            return Err(input(anyhow::anyhow!(
                "ply '{}' was draped as a flat sheet with its scene's {} (meta.sheet_features), which the net does not \
                 record: refined here without them, the sheet would be joined across its cuts and seams and lose its \
                 folds, reinforcements or blank. Drape it again with its scene: drape run SCENE",
                net.name,
                unknown.join(", ")
            )));
        }
        Ok(RefineSettings {
            mode: self.mode,
            pressed_surface: if self.facets { PressedSurface::Facets } else { PressedSurface::Smooth },
            gravity: Vector::from(self.gravity),
            load_steps: self.load_steps,
            solver: SolverSettings::default().max_iterations(self.max_iterations).escape_saddles(self.escape_saddles),
            sheet,
            stick: self.stick,
            friction,
            holds: self
                .holds
                .iter()
                .map(|&[i, j]| [(i as f64 - i0 as f64) * net.spacing, (j as f64 - j0 as f64) * net.spacing])
                .collect(),
            plies_below: None,
            forming,
        })
    }

    /// A formed net (one that records `meta.forming`) is held by the tools that formed it,
    /// where its stroke left them: the punch (the tool given, where its file has it), the die
    /// (`--die`, else the file the net records) and the binder with its recorded opening and
    /// pressure, gripping in the blank's recorded plane (and its fabric is the blank it records,
    /// [`RefineOptions::settings`]). None for any other net.
    fn held_by_its_tools(&self, net: &DrapeNet) -> Result<Option<Forming>, Failure> {
        let Some(record) = &net.meta.forming else {
            return match &self.die {
                Some(d) => Err(input(anyhow::anyhow!(
                    "--die {}: the net records no forming process (meta.forming): only a formed ply is held by a die; leave --die out",
                    d.display()
                ))),
                None => Ok(None),
            };
        };
        let formed = format!(
            "the net was formed by a punch's stroke of ({:.1}, {:.1}, {:.1}) mm",
            record.stroke_m[0] * 1e3,
            record.stroke_m[1] * 1e3,
            record.stroke_m[2] * 1e3
        );
        if self.mode != ContactMode::Pressed {
            return Err(input(anyhow::anyhow!(
                "--mode free: {formed} and is refined held by its tools where the stroke ended, as it was formed: give --mode pressed"
            )));
        }
        if self.load_steps != 1 {
            return Err(input(anyhow::anyhow!(
                "--load-steps {}: {formed}; it is refined again in one increment with its load already on: leave --load-steps out",
                self.load_steps
            )));
        }
        let die = match (record.die, &self.die, &record.die_file) {
            (false, Some(d), _) => {
                return Err(input(anyhow::anyhow!(
                    "--die {}: {formed} without a die (meta.forming.die is false): leave --die out",
                    d.display()
                )))
            }
            (false, None, _) => None,
            (true, Some(d), _) => Some(self.read_die(d, net, record)?),
            (true, None, Some(f)) if Path::new(f).is_file() => Some(self.read_die(Path::new(f), net, record)?),
            (true, None, recorded) => {
                let where_ = match recorded {
                    Some(f) => format!("its file {f} is not found"),
                    None => "the net does not record its file".to_string(),
                };
                return Err(input(anyhow::anyhow!(
                    "{formed} with a die, and {where_}: give the die with --die FILE (in the tool's units)"
                )));
            }
        };
        let forming = Forming::at_end_of(record, die, (net.nu, net.nv))
            .map_err(|e| input(anyhow::anyhow!("meta.forming.{e}")))?;
        Ok(Some(forming))
    }

    /// The die at `path`, in the tool's units, facing the ply as the scene's did.
    fn read_die(&self, path: &Path, net: &DrapeNet, record: &FormingRecord) -> Result<Arc<ToolSurface>, Failure> {
        let scale = self.tool_scale(net)?;
        let named = |e: &dyn std::fmt::Display| input(anyhow::anyhow!("die {}: {e}", path.display()));
        let die = crate::io::read_tool(path, scale).map_err(|e| named(&e))?;
        // The blank's centre where the stroke ends (the flat blank's recorded origin).
        let stroke = Vector::from(record.stroke_m);
        let centre = match (&record.blank_plane, net.meta.origin) {
            (_, Some(o)) => Point::from(o),
            (Some(p), None) => Point::from(p.point_m) + stroke,
            (None, None) => net.positions[net.index(net.origin_node.0, net.origin_node.1)],
        };
        Ok(Arc::new(die_facing(die, &centre, &stroke).map_err(|e| named(&e))?))
    }
}

/// Refine `net` (called `label` in messages: its file) on `tool` under `material` (read from
/// `material_path`), lying on the tool's `side` (met turned over where that is the side its
/// normals do not point to): the refined net, annotated with its change from `net` and the
/// solver's record, its solve time in `timing.fill_ms`, and the solver's result.
pub fn refine_net(
    net: &DrapeNet,
    label: &str,
    tool: &ToolSurface,
    side: StackSide,
    material: &MaterialCard,
    material_path: &Path,
    settings: &RefineSettings,
) -> Result<(DrapeNet, Refined), Failure> {
    crate::kinematic::fishnet::check_spacing_on_tool(tool, net.spacing)
        .map_err(|e| input(anyhow::anyhow!("net {label}: {e}")))?;
    let t = Instant::now();
    // The mechanics keeps a ply on the side its tool's normals point to.
    let turned = match side {
        StackSide::Opposite => {
            Some(turned_over(tool).map_err(|e| input(anyhow::anyhow!("the tool turned over: {e}")))?)
        }
        StackSide::Normal => None,
    };
    let refined = refine(net, turned.as_ref().unwrap_or(tool), material, settings).map_err(input)?;
    let solve_ms = t.elapsed().as_secs_f64() * 1e3;
    let mut out = refined.net.clone();
    annotate(&mut out, net, &refined, material_path);
    // Wrinkles the net recorded were measured on its nodes before they moved: again, where
    // they are now.
    out.meta.wrinkles = Some(crate::layup::ply::wrinkles_of(
        &out,
        tool,
        Some(material.thickness),
        Some(material),
        Some(&settings.sheet),
    ));
    // A formed ply held again by its tools is still the ply its process formed: its record
    // stays; a refinement without them forms nothing, whatever the net was formed by.
    if settings.forming.is_none() {
        out.meta.forming = None;
    }
    out.meta.stack_side = (side == StackSide::Opposite).then_some(StackSide::Opposite);
    out.timing.generators_ms = 0.0;
    out.timing.fill_ms = solve_ms;
    out.timing.total_ms = solve_ms;
    Ok((out, refined))
}

/// A ply that slides or a solver that stopped short is a failed computation, reported after the
/// last state was written.
pub fn check_refined(refined: &Refined) -> Result<(), Failure> {
    if let Some(slide) = &refined.slide {
        return Err(compute(anyhow::anyhow!("{}; the last state was written", slide.describe())));
    }
    if !refined.ok() {
        return Err(compute(anyhow::anyhow!(
            "the mechanical solver stopped without equilibrium ({:?}); the last accepted state was written. Try more --load-steps or --max-iterations",
            refined.outcome()
        )));
    }
    Ok(())
}
