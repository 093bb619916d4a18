//! `method = "auto"`: the least model that keeps a ply's cell shear within its tolerance.
//!
//! The kinematic net is drawn first, as always. Three cheap measurements on it decide whether it
//! is the answer or mechanics must run, and at what spacing:
//! - **the model**: steps of the mechanical model (the ply's card, pressed) from the kinematic
//!   net until the nodes settle ([`PROBE_SETTLED_SHARE`]; two on a net near equilibrium, more
//!   where the way there is long: frictionless, gravity slid the cone's ply down the slant over
//!   seven). With the ply's friction, where nothing would hold the ply (it slides, or turns
//!   freely on a tool that lets it), the kinematic net is the ply held where it is laid, and
//!   the choice says NOT ASSURED. Their largest cell-shear change
//!   says in degrees how far equilibrium lies. Above the model's share of the tolerance (the
//!   tolerance less the spacing's estimated error below, which takes at most
//!   [`SPACING_SHARE`] of it), mechanics runs, going on from where the probe stopped;
//!   When the ply lies on the facets and that step is too large, the kinematic net on the smooth
//!   surface (the one pressed contact slides on) is weighed the same way, and kept if within:
//!   on a coarse tool most of the difference is the facets', not the model's;
//! - **locking**: the share of the draped area sheared past the locking angle is recorded, and
//!   the reason warns when it passes [`LOCKED_NOTE_SHARE`]: the fabric wrinkles there. It does not
//!   by itself call for mechanics: a pressed ply's shear is set by the tool's shape, and on the
//!   bundled hemisphere (17% past the glass card's 30 deg) the pressed drape moved the first
//!   ply's shear by 0.07 deg. Where locking does change the answer, the stiff shear shows in the
//!   step above.
//! - **the spacing**: the net at twice the spacing, compared at the same fabric points, gives
//!   the error of the ply's spacing by Richardson's estimate (difference over 2^p - 1, the
//!   fishnet being second order). Above the spacing's share of the tolerance a kinematic ply is
//!   draped again at a spacing d / k (k whole, so the grid keeps its nodes, at most
//!   [`MAX_REFINEMENT`]). A mechanical ply starts at its own spacing, and the spacing the
//!   kinematic net would need is reported.
//! - **the pressed drape's spacing**: where mechanics ran, the same estimate from the ply pressed
//!   at twice the spacing. Above the tolerance the ply is draped and pressed again at d / k,
//!   the least k the estimate says will do (at most [`MAX_REFINEMENT`]), within
//!   [`MECHANICAL_NODE_BUDGET`] (mechanics at d / k costs k^2 the nodes and more iterations),
//!   and that drape's own error is estimated against the one at d at the order of convergence
//!   the three drapes (2d, d, d / k) show, clamped to [[`MIN_TRUSTED_ORDER`], 2]. Once; the
//!   reason says NOT ASSURED (and [`MethodChoice::assured`] is false) where the last estimate
//!   is above the tolerance, the observed order is below [`MIN_TRUSTED_ORDER`], or the
//!   difference does not fall with the spacing (near locked corners the peak shear grows as the
//!   spacing resolves them: the hat box at 4 and 2 mm). Each estimate is also given over the
//!   cells below the locking angle.
//!
//! The choice, its reason and the measurements are recorded ([`MethodChoice`]) in the net's meta
//! and in `layup.json`, and shown in the layup table and the report.
use super::{AutoModel, Refinement};
use crate::geometry::smooth::SmoothSurface;
use crate::geometry::{Point, ToolSurface};
use crate::kinematic::fabric_field::ShearField;
use crate::kinematic::fishnet::{drape_on, drape_smooth, DrapeError};
use crate::kinematic::{ChoiceIndicators, DrapeNet, KinematicSettings, MethodChoice, SurfaceKind};
use crate::mechanics::refine::{cell_changes, refine_draped, refine_on, PressedSurface, RefineError, Refined};
use crate::mechanics::SolverSettings;
use std::cell::OnceCell;
use std::time::Instant;

/// Tolerance of `method = "auto"` when the ply gives none, degrees of cell shear.
pub const DEFAULT_TOLERANCE_DEG: f64 = 1.0;
/// Most of the tolerance the spacing may take (a larger estimated error is met by draping
/// finer); the model (the kinematic net's distance from mechanical equilibrium) gets the
/// tolerance less the spacing's estimated error.
pub const SPACING_SHARE: f64 = 0.5;
/// Share of the draped area past the locking angle above which the reason warns of it.
pub const LOCKED_NOTE_SHARE: f64 = 0.01;
/// Order of convergence of the fishnet in the spacing (observed 1.8 on the smooth sphere, the
/// formal order 2; see `study::speed_accuracy`).
pub const FISHNET_ORDER: f64 = 2.0;
/// Least order of convergence in the spacing at which Richardson's estimate from three drapes
/// is trusted: a lower observed order means the drapes are not yet where the error falls
/// steadily (and an estimate at that order blows the last difference up without bound).
pub const MIN_TRUSTED_ORDER: f64 = 1.0;
/// Most the spacing is divided by to meet the tolerance (the nodes grow by its square).
pub const MAX_REFINEMENT: usize = 4;

/// A ply draped by `method = "auto"` up to the choice: the kinematic net at the spacing chosen,
/// which the caller refines when `choice.chosen` is `mechanical`.
#[derive(Debug, Clone)]
pub struct AutoDrape {
    /// The kinematic net.
    pub net: DrapeNet,
    /// What was chosen and why.
    pub choice: MethodChoice,
    /// Where mechanics, when chosen, starts: the positions (one per node of `net`) at which the
    /// probe towards equilibrium stopped, so that its iterations are not done again.
    pub start: Option<Vec<Point>>,
}

impl AutoDrape {
    /// Whether mechanics must run.
    pub fn mechanical(&self) -> bool {
        self.choice.chosen == "mechanical"
    }
}

/// A ply's tool and its smooth surface, built the first time a step needs it and shared by
/// every drape and mechanical step after (the choice drapes up to four nets and takes up to
/// two steps on one tool).
///
/// The mechanics may meet the tool from its other side (`stack_side = "opposite"`): then it
/// presses onto `contact`, the tool turned over, with a smooth surface of its own, while the
/// kinematic drapes stay on the tool as the stack gives it.
pub struct Surfaces<'a> {
    tool: &'a ToolSurface,
    smooth: OnceCell<SmoothSurface<'a>>,
    contact: Option<(&'a ToolSurface, OnceCell<SmoothSurface<'a>>)>,
}

impl<'a> Surfaces<'a> {
    /// The tool, its smooth surface not yet built; the mechanics meets it as it is.
    pub fn new(tool: &'a ToolSurface) -> Self {
        Self { tool, smooth: OnceCell::new(), contact: None }
    }

    /// The tool for the kinematic drapes and `contact`, the surface the mechanics presses onto
    /// (the same tool turned over).
    pub fn with_contact(tool: &'a ToolSurface, contact: &'a ToolSurface) -> Self {
        Self { tool, smooth: OnceCell::new(), contact: Some((contact, OnceCell::new())) }
    }

    /// The tool's smooth surface (built on first use).
    pub fn smooth(&self) -> &SmoothSurface<'a> {
        self.smooth.get_or_init(|| SmoothSurface::new(self.tool))
    }

    /// The surface the mechanics presses onto.
    fn contact(&self) -> &'a ToolSurface {
        self.contact.as_ref().map_or(self.tool, |(c, _)| c)
    }

    /// The kinematic drape on the surface `settings` names.
    fn drape(&self, settings: &KinematicSettings) -> Result<DrapeNet, DrapeError> {
        match settings.surface {
            SurfaceKind::Facets => drape_on(self.tool, settings),
            SurfaceKind::Smooth => drape_smooth(self.smooth(), settings),
        }
    }

    /// The smooth surface where `r`'s pressed contact slides on it.
    fn for_refinement(&self, r: &Refinement) -> Option<&SmoothSurface<'a>> {
        (r.settings().pressed_surface == PressedSurface::Smooth).then(|| match &self.contact {
            Some((contact, smooth)) => smooth.get_or_init(|| SmoothSurface::new(contact)),
            None => self.smooth(),
        })
    }
}

/// What a ply with `method = "auto"` gives: the kinematic net the choice kept (or mechanics
/// started from), the refined net and the solver's record if mechanics ran, and the choice.
pub struct AutoResult {
    /// The kinematic net.
    pub kinematic: DrapeNet,
    /// The refined net and the solver's record, when mechanics was chosen.
    pub refined: Option<(DrapeNet, Refined)>,
    /// What was chosen and why.
    pub choice: MethodChoice,
}

/// Why an automatic ply could not be drawn.
#[derive(Debug, thiserror::Error)]
pub enum AutoError {
    /// The kinematic drape failed.
    #[error(transparent)]
    Drape(#[from] DrapeError),
    /// Mechanics was chosen and could not run.
    #[error("refinement: {0}")]
    Refine(#[from] RefineError),
}

/// Choose the ply's model ([`choose`]) and run mechanics if it was chosen, on one smooth surface;
/// the mechanics meets the tool as `contact` (the same tool, turned over where the plies lie on
/// the other side of it).
/// Where the pressed drape's own spacing error is estimated above the tolerance, the ply is
/// pressed again at the spacing the estimate asks for, within [`MECHANICAL_NODE_BUDGET`]
/// ([`press_finer`]).
pub fn drape_auto(
    surface: &ToolSurface,
    contact: &ToolSurface,
    settings: &KinematicSettings,
    refinement: &Refinement,
    locking_angle: f64,
    auto: AutoModel,
) -> Result<AutoResult, AutoError> {
    let surfaces = Surfaces::with_contact(surface, contact);
    let mut a = choose(&surfaces, settings, refinement, locking_angle, auto)?;
    if !a.mechanical() {
        return Ok(AutoResult { kinematic: a.net, refined: None, choice: a.choice });
    }
    let start = a.start.as_deref().unwrap_or(&a.net.positions);
    let refined = refinement.run_from(&a.net, start, surfaces.contact(), surfaces.for_refinement(refinement))?;
    let t = Instant::now();
    let estimate = weigh_mechanical_spacing(&surfaces, settings, refinement, &refined.0, locking_angle, &mut a.choice);
    a.choice.indicators.time_ms += t.elapsed().as_secs_f64() * 1e3;
    a.choice.assured =
        Some(refined.1.ok() && estimate.is_some_and(|e| e.largest(FISHNET_ORDER) <= a.choice.tolerance_deg));
    let (kinematic, refined) = match estimate {
        Some(e) if e.largest(FISHNET_ORDER) > a.choice.tolerance_deg => {
            press_finer(&surfaces, settings, refinement, locking_angle, e, (a.net, refined), &mut a.choice)
        }
        _ => (a.net, refined),
    };
    Ok(AutoResult { kinematic, refined: Some(refined), choice: a.choice })
}

/// Most nodes auto presses a ply with when it refines the pressed drape's spacing by itself
/// (the hat box at 2 mm, 43 537 nodes, presses in about 5 s in 9 iterations; the double dome's
/// +45 ply at 2.5 mm, 32 761 nodes, in about 3 minutes in 392: the solver's iterations, not
/// the nodes, set the cost). Past it, the reason gives the spacing that would do.
pub const MECHANICAL_NODE_BUDGET: usize = 50_000;

/// The pressed drape at the ply's spacing `d` is estimated to err by `estimate`, above the
/// tolerance: drape and press the ply again at d / k, k whole (so the grid keeps its nodes),
/// the least that the estimate (order 2) says meets the tolerance, at most [`MAX_REFINEMENT`]
/// and within [`MECHANICAL_NODE_BUDGET`]. The finer drape's own error is then estimated from
/// the one at `d` (Richardson with ratio k, at the order the drapes at 2d, d and d / k show),
/// at no further cost. Returns the kinematic and pressed nets that stand: the finer ones if
/// that drape converged, else those at `d` (also where the finer one could not be drawn: what
/// was computed is not lost).
fn press_finer(
    surfaces: &Surfaces,
    settings: &KinematicSettings,
    refinement: &Refinement,
    locking_angle: f64,
    estimate: SpacingError,
    at_d: (DrapeNet, (DrapeNet, Refined)),
    choice: &mut MethodChoice,
) -> (DrapeNet, (DrapeNet, Refined)) {
    let d = settings.spacing;
    let tolerance = choice.tolerance_deg;
    // Assured only where the finer drape is found within the tolerance below.
    choice.assured = Some(false);
    let needed = spacing_for(d, estimate.largest(FISHNET_ORDER), tolerance, FISHNET_ORDER);
    // The grid at d / k (an outline's grid scales the same way).
    let (nu, nv) = (at_d.0.nu, at_d.0.nv);
    let nodes = |k: usize| ((nu - 1) * k + 1) * ((nv - 1) * k + 1);
    let wanted = ((d / needed).ceil() as usize).clamp(2, MAX_REFINEMENT);
    let Some(k) = (2..=wanted).rev().find(|&k| nodes(k) <= MECHANICAL_NODE_BUDGET) else {
        choice.reason.push_str(&format!(
            "; NOT ASSURED at this spacing: auto does not press it finer by itself, for at d/2 the ply has {} nodes, more than its budget of {MECHANICAL_NODE_BUDGET}",
            nodes(2)
        ));
        return at_d;
    };
    let finer = settings.at_spacing(d / k as f64);
    let t = Instant::now();
    // The finer drape, pressed and weighed against the one at d; or why not, in which case the
    // drape at d stands (its time then counts with the indicators': nothing of it is kept).
    let weighed = (|| -> Result<_, String> {
        let drawn = surfaces.drape(&finer).map_err(AutoError::from).and_then(|kinematic| {
            let pressed =
                refinement.run_draped(&kinematic, surfaces.contact(), surfaces.for_refinement(refinement), &finer)?;
            Ok((kinematic, pressed))
        });
        let (kinematic, pressed) = drawn.map_err(|why| {
            format!("the ply could not be draped and pressed again at d/{k} = {:.4} m ({why})", finer.spacing)
        })?;
        if !pressed.1.ok() {
            return Err(format!(
                "pressed again at d/{k} = {:.4} m the ply did not converge ({})",
                finer.spacing,
                pressed.1.describe_failure()
            ));
        }
        let e = SpacingError::between(&pressed.0, &at_d.1 .0, k as f64, locking_angle).ok_or_else(|| {
            format!(
                "pressed again at d/{k} = {:.4} m its spacing error could not be estimated (no cell to compare with the drape at d)",
                finer.spacing
            )
        })?;
        Ok((kinematic, pressed, e))
    })();
    let (kinematic, pressed, e) = match weighed {
        Ok(weighed) => weighed,
        Err(why) => {
            choice.reason.push_str(&format!("; {why}: the drape at the ply's spacing stands, NOT ASSURED"));
            choice.indicators.time_ms += t.elapsed().as_secs_f64() * 1e3;
            return at_d;
        }
    };
    choice.spacing_m = finer.spacing;
    choice.reason.push_str(&format!(
        "; so the ply was draped and pressed again at d/{k} = {:.4} m ({} nodes{})",
        finer.spacing,
        nodes(k),
        if k < wanted {
            format!(", the finest within auto's budget of {MECHANICAL_NODE_BUDGET}")
        } else {
            String::new()
        },
    ));
    // Three drapes (2d, d, d/k) show the order at which the pressed drape converges where it
    // is worst; the estimate takes it, within [MIN_TRUSTED_ORDER, FISHNET_ORDER] (near locked
    // cells the shear converges more slowly than the fishnet's order 2, which there understated
    // the error 1.4-3 times).
    let order = observed_order(&estimate, &e, false);
    let unlocked_order = observed_order(&estimate, &e, true);
    let trusted = |p: f64| p.clamp(MIN_TRUSTED_ORDER, FISHNET_ORDER);
    choice.indicators.mechanical_observed_order = order;
    choice.indicators.mechanical_observed_order_unlocked = unlocked_order;
    choice.indicators.refined_mechanical_discretisation_deg = order.map(|p| e.largest(trusted(p)));
    let unlocked = unlocked_order.and_then(|p| e.unlocked(trusted(p)));
    choice.indicators.refined_mechanical_discretisation_unlocked_deg = unlocked;
    // Said only where the worst cells are locked ones: otherwise it repeats the figures above.
    let worst_unlocked =
        estimate.unlocked_difference == Some(estimate.difference) && e.unlocked_difference == Some(e.difference);
    let below_locking = match (unlocked_order, unlocked) {
        _ if worst_unlocked => String::new(),
        (Some(q), Some(u)) if q >= MIN_TRUSTED_ORDER => {
            format!("; below the locking angle it converges at order {q:.2} and errs by an estimated {u:.3} deg")
        }
        (Some(q), Some(u)) => format!(
            "; below the locking angle it converges only at order {q:.2}, and at order {MIN_TRUSTED_ORDER} its error there is estimated at {u:.3} deg, which may understate it"
        ),
        _ => "; below the locking angle its difference does not fall either".to_string(),
    };
    let Some(p) = order else {
        choice.reason.push_str(&format!(
            "; its largest cell-shear difference from the drape at the ply's spacing, {:.3} deg, is not below the one between d and 2d, {:.3} deg: the pressed drape does not converge with the spacing at its worst cells, and no error estimate holds there{below_locking}: NOT ASSURED",
            e.difference,
            estimate.difference,
        ));
        return (kinematic, pressed);
    };
    let largest = e.largest(trusted(p));
    choice.reason.push_str(&format!(
        ", whose own spacing error, against the drape at the ply's spacing at the order {p:.2} the three spacings show{}, is estimated at {largest:.3} deg{below_locking}",
        if trusted(p) != p { format!(" (taken as {})", trusted(p)) } else { String::new() },
    ));
    if p < MIN_TRUSTED_ORDER {
        choice.reason.push_str(&format!(
            ": NOT ASSURED (below order {MIN_TRUSTED_ORDER} the drapes are not yet where the error falls steadily, and the estimate may understate it)"
        ));
    } else if largest <= tolerance {
        choice.reason.push_str(": within the tolerance");
        choice.assured = Some(true);
    } else {
        choice.reason.push_str(&format!(
            ", above the {tolerance} deg tolerance: NOT ASSURED at this spacing (it would need spacing <= {:.4} m)",
            spacing_for(finer.spacing, largest, tolerance, trusted(p))
        ));
    }
    (kinematic, pressed)
}

/// Mechanics ran at the ply's spacing: estimates the pressed drape's own spacing error from the
/// same drape at twice the spacing (order 2, as the kinematic net's), records it in the choice
/// and says whether the tolerance holds. `None` when that drape did not converge or has no cell
/// to compare.
fn weigh_mechanical_spacing(
    surfaces: &Surfaces,
    settings: &KinematicSettings,
    refinement: &Refinement,
    refined: &DrapeNet,
    locking_angle: f64,
    choice: &mut MethodChoice,
) -> Option<SpacingError> {
    let tolerance = choice.tolerance_deg;
    // Only its positions count: no stability check and no record (the ply's other settings,
    // escapes included, kept so that it is the same drape at 2d).
    let mut solve = refinement.settings();
    solve.solver.stability_check = false;
    let draped = settings.at_spacing(2.0 * settings.spacing);
    let coarse = surfaces
        .drape(&draped)
        .ok()
        .and_then(|net| {
            let smooth = surfaces.for_refinement(refinement);
            refine_draped(&net, &draped, surfaces.contact(), smooth, &refinement.material, &solve).ok()
        })
        .filter(Refined::ok);
    let Some(e) = coarse.and_then(|r| SpacingError::between(refined, &r.net, 2.0, locking_angle)) else {
        choice.reason.push_str(
            "; the pressed drape's own spacing error could not be estimated (the pressed drape at twice the spacing did not converge or has no cell to compare)",
        );
        return None;
    };
    choice.indicators.mechanical_discretisation_deg = Some(e.largest(FISHNET_ORDER));
    choice.indicators.mechanical_discretisation_unlocked_deg = e.unlocked(FISHNET_ORDER);
    choice.reason.push_str(&format!(
        "; the pressed drape's own spacing error, against the same drape at twice the spacing, is estimated at {}",
        e.describe(FISHNET_ORDER)
    ));
    if e.largest(FISHNET_ORDER) <= tolerance {
        choice.reason.push_str(": within the tolerance");
    } else {
        let needed = spacing_for(settings.spacing, e.largest(FISHNET_ORDER), tolerance, FISHNET_ORDER);
        choice.indicators.mechanical_spacing_needed_m = Some(needed);
        choice.reason.push_str(&format!(", above the {tolerance} deg tolerance: it asks for spacing <= {needed:.4} m"));
    }
    Some(e)
}

/// How two drapes of a ply at different spacings differ: the ground of Richardson's estimate
/// of the finer one's cell-shear error, over all their cells and over those below the locking
/// angle.
#[derive(Debug, Clone, Copy)]
struct SpacingError {
    /// Largest cell-shear difference at the finer drape's complete cell centres, degrees.
    difference: f64,
    /// The same over the cells below the locking angle in both drapes, degrees (`None` when
    /// none is).
    unlocked_difference: Option<f64>,
    /// The coarser drape's spacing over the finer one's.
    ratio: f64,
}

impl SpacingError {
    /// `fine` against `coarse`, the same drape at `ratio` times the spacing, compared at
    /// `fine`'s complete cell centres; `locking_angle` in radians.
    fn between(fine: &DrapeNet, coarse: &DrapeNet, ratio: f64, locking_angle: f64) -> Option<Self> {
        let (fine, coarse) = (ShearField::of(fine), ShearField::of(coarse));
        let locking = locking_angle.to_degrees();
        let mut difference: Option<f64> = None;
        let mut unlocked_difference: Option<f64> = None;
        for (u, v) in fine.complete_cell_centres() {
            let (Some(a), Some(b)) = (fine.at(u, v), coarse.at(u, v)) else { continue };
            let e = (a - b).abs();
            difference = Some(difference.map_or(e, |m| m.max(e)));
            if a.abs() < locking && b.abs() < locking {
                unlocked_difference = Some(unlocked_difference.map_or(e, |m| m.max(e)));
            }
        }
        Some(Self { difference: difference?, unlocked_difference, ratio })
    }

    /// Richardson's estimate of the finer drape's largest error at order `p`, degrees: the
    /// difference over ratio^p - 1.
    fn largest(&self, p: f64) -> f64 {
        self.difference / (self.ratio.powf(p) - 1.0)
    }

    /// The same over the cells below the locking angle.
    fn unlocked(&self, p: f64) -> Option<f64> {
        self.unlocked_difference.map(|u| u / (self.ratio.powf(p) - 1.0))
    }

    /// The estimate at order `p` in words: the largest, and the one below the locking angle
    /// where it is less (said only where it tells something: the locked cells carry the
    /// largest error).
    fn describe(&self, p: f64) -> String {
        let largest = self.largest(p);
        match self.unlocked(p) {
            Some(u) if u < 0.95 * largest => {
                format!("{largest:.3} deg ({u:.3} deg in the cells below the locking angle)")
            }
            _ => format!("{largest:.3} deg"),
        }
    }
}

/// Order of convergence in the spacing observed from three drapes of a ply, at 2d, d and d / k:
/// `coarse` compares the ones at d and 2d, `fine` those at d / k and d (their largest
/// differences, over the same cells: all, or below the locking angle when `unlocked`); `None`
/// where the difference does not fall with the spacing ([`crate::numeric::observed_order`]).
fn observed_order(coarse: &SpacingError, fine: &SpacingError, unlocked: bool) -> Option<f64> {
    let (d1, d2) = if unlocked {
        (coarse.unlocked_difference?, fine.unlocked_difference?)
    } else {
        (coarse.difference, fine.difference)
    };
    crate::numeric::observed_order(d1, d2, coarse.ratio, fine.ratio)
}

/// Drape `settings` on `surfaces` and choose its model (see the module doc). `refinement` is the
/// mechanical stage that runs if chosen (pressed), `locking_angle` the ply's, radians.
pub fn choose(
    surfaces: &Surfaces,
    settings: &KinematicSettings,
    refinement: &Refinement,
    locking_angle: f64,
    auto: AutoModel,
) -> Result<AutoDrape, DrapeError> {
    let t = Instant::now();
    let tolerance = auto.tolerance_deg;
    let spacing_budget = SPACING_SHARE * tolerance;
    let own = surfaces.drape(settings)?;
    let d = settings.spacing;
    // The spacing takes the share of the tolerance its estimated error needs (at most
    // `spacing_budget`: a larger error is met by draping finer), the model the rest. On a
    // developable tool the spacing needs almost nothing, and a model change just under the
    // tolerance keeps the kinematic net (the cone: 0.87 deg from the probe, 0.78 deg from the
    // finest pressed drape, where mechanics at the ply's spacing erred by 1.2 deg).
    let own_discretisation = discretisation_error(surfaces, settings, &own);
    let model_budget = tolerance - own_discretisation.map_or(spacing_budget, |e| e.min(spacing_budget));
    let stats = own.shear_stats(locking_angle);
    let locking_share = if stats.area > 0.0 { stats.area_over_locking / stats.area } else { 0.0 };
    let step = equilibrium_probe(surfaces, &own, refinement);
    // Pressed mechanics slides on the smooth surface over the facets: on a coarse tool most of
    // the step from a net on the facets is the facets' own error, which the kinematic net on
    // the smooth surface does not have (double dome, d = 5 mm: 2.4 deg from the pressed drape
    // on the facets, 0.03 deg on the smooth surface). That net is the next model up.
    let mut smooth = None;
    if settings.surface == SurfaceKind::Facets && matches!(&step, Ok(p) if p.change_deg > model_budget) {
        let s = KinematicSettings { surface: SurfaceKind::Smooth, ..settings.clone() };
        if let Ok(net) = surfaces.drape(&s) {
            if let Ok(smooth_step) = equilibrium_probe(surfaces, &net, refinement) {
                smooth = Some((net, s, smooth_step));
            }
        }
    }
    let mut indicators = ChoiceIndicators {
        spacing_m: d,
        equilibrium_step_deg: step.as_ref().ok().map(|p| p.change_deg),
        residual_after_step: step.as_ref().ok().map(|p| p.residual),
        probe_iterations: step.as_ref().ok().map(|p| p.iterations),
        smooth_equilibrium_step_deg: smooth.as_ref().map(|s| s.2.change_deg),
        locking_share,
        ..ChoiceIndicators::default()
    };
    let locking_deg = locking_angle.to_degrees();
    let smooth_within = smooth.as_ref().is_some_and(|s| s.2.change_deg <= model_budget);
    let steps = |p: &Probe| match p.iterations {
        0 => "the kinematic net is in mechanical equilibrium already (no step taken); the model changes".to_string(),
        1 => "one step towards mechanical equilibrium changes".to_string(),
        n if p.unsettled => {
            format!("{n} steps towards mechanical equilibrium (the probe's limit, the nodes still moving) change")
        }
        n => format!("{n} steps towards mechanical equilibrium change"),
    };
    let (mechanical, mut reason) = match &step {
        Ok(p) if p.change_deg > model_budget && smooth_within => (
            false,
            format!(
                "{} the shear of the net on the facets by up to {:.2} deg, but of the net on the smooth surface by at most {:.3} deg (the model's share of the {tolerance} deg tolerance is {model_budget:.2} deg): the kinematic net on the smooth surface is kept",
                steps(p),
                p.change_deg,
                indicators.smooth_equilibrium_step_deg.unwrap_or_default()
            ),
        ),
        Ok(p) if p.change_deg > model_budget => (
            true,
            format!(
                "{} the shear by up to {:.2} deg{}, more than the model's {model_budget:.2} deg of the {tolerance} deg tolerance",
                steps(p),
                p.change_deg,
                indicators
                    .smooth_equilibrium_step_deg
                    .map_or(String::new(), |s| format!(" ({s:.2} deg from the net on the smooth surface)"))
            ),
        ),
        Ok(p) => (
            false,
            format!(
                "{} the shear by at most {:.3} deg (the model's share of the {tolerance} deg tolerance is {model_budget:.2} deg): the kinematic net is kept",
                steps(p),
                p.change_deg
            ),
        ),
        Err(why) => (false, format!("the mechanical model could not take a step from the kinematic net ({why}): the kinematic net is kept")),
    };
    if locking_share > LOCKED_NOTE_SHARE {
        reason.push_str(&format!(
            "; {:.1}% of the draped area is sheared past the {locking_deg:.0} deg locking angle: the fabric would wrinkle there, which neither model of a ply on the tool shows",
            100.0 * locking_share
        ));
    }
    // The kinematic net that stands (or that mechanics starts from: the ply's own).
    let (net, settings, discretisation) = match smooth {
        Some((net, s, _)) if smooth_within => {
            let e = discretisation_error(surfaces, &s, &net);
            (net, s, e)
        }
        _ => (own, settings.clone(), own_discretisation),
    };
    let settings = &settings;
    let spacing_needed =
        discretisation.filter(|e| *e > spacing_budget).map(|e| spacing_for(d, e, spacing_budget, FISHNET_ORDER));
    indicators.discretisation_deg = discretisation;
    indicators.spacing_needed_m = spacing_needed;
    let mut net = net;
    let mut spacing = d;
    // A kept kinematic net is assured when the model's step and the spacing's error were both
    // measured within their shares; a mechanical choice is weighed after mechanics ran.
    let mut assured = !mechanical && step.is_ok();
    if let Ok(Probe { slides: Some(why), .. }) = &step {
        // The kinematic net is the ply as laid and held there; the pressed model says nothing
        // holds it (frictionless on a tool it can slide or turn on, or friction too weak).
        assured = false;
        reason.push_str(&format!(
            "; NOT ASSURED: the pressed model {why}; the kinematic net is the ply held where it is laid"
        ));
    }
    if let (Some(needed), true) = (spacing_needed, mechanical) {
        // Mechanics at a finer spacing costs the square of the refinement in nodes and more
        // iterations: it starts at the ply's spacing, and `drape_auto` presses finer only where
        // the pressed drape's own estimate asks for it.
        reason.push_str(&format!(
            "; the kinematic net's spacing error is estimated at {:.3} deg (it would need d <= {needed:.4} m); mechanics starts at the ply's spacing",
            discretisation.unwrap_or_default()
        ));
    } else if let Some(needed) = spacing_needed {
        let k = ((d / needed).ceil() as usize).clamp(2, MAX_REFINEMENT);
        let finer = settings.at_spacing(d / k as f64);
        match surfaces.drape(&finer) {
            Ok(n) => {
                net = n;
                spacing = finer.spacing;
                assured &= d / k as f64 <= needed;
                reason.push_str(&format!(
                    "; the spacing's error is estimated at {:.3} deg, more than its {spacing_budget:.2} deg, so the ply was draped at d/{k} = {:.4} m{}",
                    discretisation.unwrap_or_default(),
                    spacing,
                    if d / k as f64 > needed { " (the finest allowed; still above the tolerance)" } else { "" }
                ));
            }
            Err(e) => {
                assured = false;
                reason.push_str(&format!(
                    "; the spacing's error is estimated at {:.3} deg and needs d <= {needed:.4} m, but the finer net could not be draped ({e}): the ply's spacing is kept",
                    discretisation.unwrap_or_default()
                ))
            }
        }
    } else if let Some(e) = discretisation {
        reason.push_str(&format!("; the spacing's error is estimated at {e:.3} deg (within {spacing_budget:.2} deg)"));
    } else {
        assured = false;
        reason.push_str(
            "; the spacing's error could not be estimated (the net at twice the spacing has no cell to compare)",
        );
    }
    indicators.time_ms = t.elapsed().as_secs_f64() * 1e3;
    let choice = MethodChoice {
        requested: "auto".into(),
        chosen: if mechanical { "mechanical" } else { "kinematic" }.into(),
        surface: settings.surface.name().into(),
        tolerance_deg: tolerance,
        spacing_m: spacing,
        assured: Some(assured),
        reason,
        indicators,
    };
    // Mechanics goes on from where the probe of `net` (the ply's own net: a mechanical choice
    // never keeps the smooth one or drapes anew) stopped.
    let start = if mechanical { step.ok().map(|p| p.state) } else { None };
    Ok(AutoDrape { net, choice, start })
}

/// The spacing at which a drape whose spacing error is `error` at spacing `d` errs by `target`,
/// the error falling as d^p.
fn spacing_for(d: f64, error: f64, target: f64, p: f64) -> f64 {
    d * (target / error).powf(1.0 / p)
}

/// Richardson's estimate of the largest cell-shear error of `net` (drawn with `settings`) from
/// its spacing, degrees: against the net at twice the spacing at `net`'s complete cell centres.
fn discretisation_error(surfaces: &Surfaces, settings: &KinematicSettings, net: &DrapeNet) -> Option<f64> {
    let coarse = surfaces.drape(&settings.at_spacing(2.0 * settings.spacing)).ok()?;
    richardson(net, &coarse)
}

/// Richardson's estimate of the largest cell-shear error of `fine` against `coarse`, the same
/// drape at twice the spacing, degrees ([`SpacingError::between`], every cell).
fn richardson(fine: &DrapeNet, coarse: &DrapeNet) -> Option<f64> {
    SpacingError::between(fine, coarse, 2.0, f64::INFINITY).map(|e| e.largest(FISHNET_ORDER))
}

/// Most iterations the probe takes before it calls the nodes settled.
pub const PROBE_MAX_ITERATIONS: usize = 20;
/// The probe stops once an iteration moves the nodes by at most this share of the largest move
/// of one iteration so far: the rest of the way is short. (Not the energy: the first iteration
/// relaxes the facets' strain and bending, a fall hundreds of times that of a slow slide.)
pub const PROBE_SETTLED_SHARE: f64 = 0.1;

/// What the probe towards mechanical equilibrium found.
struct Probe {
    /// Largest cell-shear change from the kinematic net, degrees.
    change_deg: f64,
    /// |F - P| / |P| at the end.
    residual: f64,
    /// Iterations taken.
    iterations: usize,
    /// Whether it stopped at the iteration limit before the nodes settled: its change is then
    /// a state on the way, not where the ply goes.
    unsettled: bool,
    /// The positions where it stopped, one per node of the net it started from.
    state: Vec<Point>,
    /// Where the pressed model finds that nothing holds the ply on the tool: why, in words.
    slides: Option<String>,
}

/// Steps of the mechanical model from `net` until the nodes settle (an iteration moves them by
/// at most [`PROBE_SETTLED_SHARE`] of the largest move so far), it converges, or
/// [`PROBE_MAX_ITERATIONS`] pass. One step is not enough where the way to equilibrium is long:
/// frictionless, gravity slid the cone's ply (held at its seed) down the slant over some ten
/// iterations, and the first moved the shear by 0.03 of the 0.78 deg it changed in all. Where
/// the kinematic net lies near equilibrium (the hemisphere) the second iteration moves the
/// nodes by 1/50 of the first and the probe ends there.
fn equilibrium_probe(surfaces: &Surfaces, net: &DrapeNet, r: &Refinement) -> Result<Probe, String> {
    let mut settings = r.settings();
    settings.load_steps = 1;
    settings.solver = SolverSettings {
        max_iterations: PROBE_MAX_ITERATIONS,
        settle_share: Some(PROBE_SETTLED_SHARE),
        // The solve that goes on from the probe's state checks its stability.
        stability_check: false,
        ..settings.solver
    };
    let refined = refine_on(net, surfaces.contact(), surfaces.for_refinement(r), &r.material, &settings)
        .map_err(|e| e.to_string())?;
    let report = refined.steps.last().ok_or("the mechanical model took no load step")?;
    let change_deg =
        cell_changes(net, &refined.net).into_iter().flatten().map(|(g, _)| g.abs().to_degrees()).fold(0.0, f64::max);
    Ok(Probe {
        change_deg,
        residual: report.residual,
        iterations: report.iterations.len(),
        unsettled: refined.outcome() == crate::mechanics::solver::Outcome::IterationLimit,
        slides: refined.slide.as_ref().map(|s| s.describe()),
        state: refined.net.positions,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The differences an error C h^p gives between drapes at 2d, d and d / k.
    fn differences(p: f64, k: f64) -> (SpacingError, SpacingError) {
        let (c, d) = (3.0, 0.004);
        let error = |h: f64| c * (h / d).powf(p);
        let coarse = SpacingError { difference: error(2.0 * d) - error(d), unlocked_difference: None, ratio: 2.0 };
        let fine = SpacingError { difference: error(d) - error(d / k), unlocked_difference: None, ratio: k };
        (coarse, fine)
    }

    #[test]
    fn the_observed_order_is_the_order_of_the_error_and_the_estimate_its_exact_value() {
        for k in [2.0, 3.0, 4.0] {
            for p in [0.5, 1.0, 1.5, 2.0, 3.0] {
                let (coarse, fine) = differences(p, k);
                let observed = observed_order(&coarse, &fine, false).unwrap();
                assert!((observed - p).abs() < 1e-9, "k = {k}: {observed} against {p}");
                // At the true order, Richardson's estimate is the error at d / k exactly.
                let exact = 3.0 * (1.0 / k).powf(p);
                assert!(
                    (fine.largest(observed) - exact).abs() < 1e-9 * exact,
                    "{} against {exact}",
                    fine.largest(observed)
                );
            }
        }
    }

    #[test]
    fn a_difference_that_does_not_fall_with_the_spacing_has_no_order() {
        let coarse = SpacingError { difference: 4.31, unlocked_difference: Some(4.31), ratio: 2.0 };
        let fine = SpacingError { difference: 4.76, unlocked_difference: Some(3.16), ratio: 2.0 };
        assert_eq!(observed_order(&coarse, &fine, false), None);
        let q = observed_order(&coarse, &fine, true).unwrap();
        assert!((q - (4.31f64 / 3.16).log2()).abs() < 1e-12, "{q}");
        // A coarser refinement can still show an order where the difference grows a little: at
        // k = 3 the finer step spans a larger ratio (D1 / D2 > ln 2 / ln 3 = 0.63 converges).
        let fine = SpacingError { ratio: 3.0, ..fine };
        assert!(observed_order(&coarse, &fine, false).is_some());
        assert_eq!(observed_order(&coarse, &SpacingError { difference: 7.0, ..fine }, false), None);
    }

    #[test]
    fn a_finer_drape_that_does_not_converge_leaves_the_drape_at_the_plys_spacing_standing() {
        use crate::geometry::shapes::hemisphere_with_triangles;
        use crate::geometry::{Point, Vector};
        use crate::material::MaterialCard;
        let mesh = hemisphere_with_triangles(0.1, 2000);
        let tool = ToolSurface::from_triangles(mesh.vertices, mesh.triangles).unwrap();
        let card_path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/glass-plain-weave.toml");
        let refinement = Refinement::pressed(MaterialCard::load(&card_path).unwrap(), card_path);
        let settings = KinematicSettings::grid("p0", Point::new(0.0, 0.0, 0.1), Vector::x(), 0.008, 21, 21);
        let surfaces = Surfaces::new(&tool);
        let kinematic = surfaces.drape(&settings).unwrap();
        let pressed =
            refinement.run_draped(&kinematic, &tool, surfaces.for_refinement(&refinement), &settings).unwrap();
        assert!(pressed.1.ok(), "the drape at the ply's spacing converges");
        // One iteration cannot bring the drape at d/2 to equilibrium.
        let starved = Refinement { max_iterations: 1, ..refinement };
        let mut choice = MethodChoice {
            requested: "auto".into(),
            chosen: "mechanical".into(),
            surface: "facets".into(),
            tolerance_deg: 0.001,
            spacing_m: settings.spacing,
            assured: Some(false),
            reason: "start".into(),
            indicators: ChoiceIndicators::default(),
        };
        let estimate = SpacingError { difference: 0.03, unlocked_difference: Some(0.03), ratio: 2.0 };
        let at_d = (kinematic.clone(), pressed.clone());
        let (kept, (refined, record)) =
            press_finer(&surfaces, &settings, &starved, 30f64.to_radians(), estimate, at_d, &mut choice);
        assert_eq!(kept.positions, kinematic.positions);
        assert_eq!(refined.positions, pressed.0.positions);
        assert!(record.ok());
        assert_eq!(choice.assured, Some(false));
        assert_eq!(choice.spacing_m, settings.spacing);
        assert!(
            choice.reason.contains("pressed again at d/4 = 0.0020 m the ply did not converge")
                && choice.reason.ends_with("the drape at the ply's spacing stands, NOT ASSURED"),
            "{}",
            choice.reason
        );
        assert!(choice.indicators.time_ms > 0.0);
    }
}
