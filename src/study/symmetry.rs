//! The mirror symmetries of a ply's drape problem: planes through the seed that map the tool,
//! gravity, the ply's extent and its mechanical model onto themselves. Where one holds, the
//! mirror image of a drape is a drape of the same ply (seen through a [`FabricImage`] of the
//! fabric coordinates), and a mechanical drape that broke the symmetry one way is as good an
//! answer as its image that broke it the other way: the speed-accuracy study measures each run
//! against the reference and its images ([`super::speed_accuracy`]).
//!
//! Two mirrors are considered, both through the seed and containing the tool's normal there:
//! the plane of the warp (fabric (u, v) -> (u, -v)) and the plane of the weft, the normal cross
//! the warp, as the fishnet orients it ((u, v) -> (-u, v)). What each needs:
//! - the tool: every vertex mirrored lies on the tool ([`TOOL_TOLERANCE_REL`]);
//! - gravity, and a flat start's sheet normal, in the plane ([`DIRECTION_TOLERANCE`]);
//! - the extent: a grid with its origin node in the middle across the plane, or an outline whose
//!   points mirror onto its points;
//! - no pre-shear (the mirror turns it into its opposite), no steered generator (its curve is
//!   not checked), no sheet features (reinforcements, seam, fold, cuts are not checked).
//!
//! The material needs nothing: a card's tension and bending are per fibre family, which each
//! mirror maps onto itself, and every shear law is odd in the angle ([`crate::material`]'s
//! `ShearLaw::eval`), so the energy of a mirrored drape is its image's. The mechanical stage
//! holds the seed's warp neighbour in the warp's plane: the warp mirror keeps that hold, the
//! weft mirror moves it to the other warp neighbour, an equivalent way to fix the ply's turn
//! about its seed.
use crate::geometry::{Point, ToolSurface, Vector};
use crate::kinematic::fabric_field::FabricImage;
use crate::kinematic::{Extent, GeneratorKind};
use crate::layup::stack::{resolve_warp, seed_normal};
use crate::layup::{Layup, Ply, Start};
use crate::mechanics::refine::RefineSettings;
use rayon::prelude::*;

/// A mirrored tool vertex further than this (times the tool's bounding diagonal) from the tool
/// breaks the symmetry: 10 um on a 1 m tool, far below any shape a drape at a spacing of 1e-3
/// of the tool can see, and above the rounding of coordinates written with 6 significant digits.
pub const TOOL_TOLERANCE_REL: f64 = 1e-5;
/// A direction (gravity, a flat start's normal) whose sine to the mirror plane is above this
/// breaks the symmetry. Directions averaged from symmetric facets lie in the plane to rounding
/// (1e-15); 1e-6 rad out of it moves nothing a drape can see.
pub const DIRECTION_TOLERANCE: f64 = 1e-6;

/// A plane a drape is mirrored in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MirrorPlane {
    /// A point of the plane (the seed on the tool).
    pub point: Point,
    /// Its unit normal.
    pub normal: Vector,
}

impl MirrorPlane {
    /// The mirror image of `p`.
    pub fn reflect(&self, p: &Point) -> Point {
        p - self.normal * (2.0 * self.normal.dot(&(p - self.point)))
    }
}

/// The plane of `mirror` (one of [`FabricImage::MIRRORS`]) for `ply` of `layup` on `tool`:
/// through the seed on the tool, containing the normal there and the warp (the warp mirror) or
/// the weft (the weft mirror). Err when the ply's warp cannot be resolved there, or `mirror` is
/// not a mirror.
pub fn mirror_plane(ply: &Ply, layup: &Layup, tool: &ToolSurface, mirror: FabricImage) -> Result<MirrorPlane, String> {
    let foot = tool.closest_point(&ply.settings.origin).point;
    let warp = resolve_warp(ply, &foot, &layup.reference, tool, layup.stack_side)?;
    let weft = seed_normal(tool, &foot).cross(&warp).normalize();
    let normal = match mirror {
        // The warp's plane is normal to the weft, and the weft's to the warp.
        FabricImage::WarpMirror => weft,
        FabricImage::WeftMirror => warp,
        FabricImage::AsIs | FabricImage::Rotated => return Err(format!("{} is not a mirror", mirror.name())),
    };
    Ok(MirrorPlane { point: foot, normal })
}

/// Whether `mirror` is a symmetry of the drape problem of `ply` of `layup` on `tool`: its plane,
/// or what breaks it.
pub fn check_mirror(ply: &Ply, layup: &Layup, tool: &ToolSurface, mirror: FabricImage) -> Result<MirrorPlane, String> {
    let plane = mirror_plane(ply, layup, tool, mirror)?;
    let s = &ply.settings;
    if s.pre_shear != 0.0 {
        return Err(format!("pre-shear {:.3} deg becomes its opposite in the mirror", s.pre_shear.to_degrees()));
    }
    if matches!(s.generators, GeneratorKind::Steer(_)) {
        return Err("the steered generator's curve is not checked for symmetry".into());
    }
    match &s.extent {
        Extent::Grid { nu, nv, origin_node } => {
            let o = origin_node.unwrap_or((nu / 2, nv / 2));
            // Nodes across the plane: along the weft for the warp mirror, along the warp for the
            // weft mirror.
            let (n, at) = if mirror == FabricImage::WarpMirror { (*nv, o.1) } else { (*nu, o.0) };
            if 2 * at + 1 != n {
                return Err(format!(
                    "the grid's origin node {at} is not in the middle of its {n} nodes across the plane"
                ));
            }
        }
        Extent::Outline(points) => {
            let tol = TOOL_TOLERANCE_REL * tool.diagonal();
            if let Some(k) = points.iter().position(|p| {
                let q = plane.reflect(p);
                !points.iter().any(|r| (r - q).norm() <= tol)
            }) {
                return Err(format!("outline point {} has no mirror image among the outline's points", k + 1));
            }
        }
    }
    let out_of_plane = |d: &Vector| d.normalize().dot(&plane.normal).abs() > DIRECTION_TOLERANCE;
    let refinement = ply.refinement.as_ref();
    // A ply without its own refinement gets the default pressed one: from the kinematic net, no
    // sheet features.
    if let Some(r) = refinement {
        if r.sheet != Default::default() {
            return Err("the sheet's features (reinforcements, seam, fold, cuts) are not checked for symmetry".into());
        }
        if let Start::Flat { normal } = r.start {
            if out_of_plane(&normal) {
                return Err("the flat start's sheet normal is not in the plane".into());
            }
        }
    }
    let gravity = refinement.map_or_else(|| RefineSettings::default().gravity, |r| r.settings().gravity);
    if out_of_plane(&gravity) {
        return Err("gravity is not in the plane".into());
    }
    let tol = TOOL_TOLERANCE_REL * tool.diagonal();
    let off = tool.vertices().par_iter().position_first(|v| tool.closest_point(&plane.reflect(v)).distance > tol);
    if let Some(k) = off {
        let v = tool.vertices()[k];
        let d = tool.closest_point(&plane.reflect(&v)).distance;
        return Err(format!("the tool's vertex {k} at {:?} mirrors {d:.3e} m off the tool", [v.x, v.y, v.z]));
    }
    Ok(plane)
}

/// The symmetries of the drape problem of `ply` of `layup` on `tool`, the identity left out:
/// the mirrors that hold ([`check_mirror`]) and the half turn when both do.
pub fn symmetries(ply: &Ply, layup: &Layup, tool: &ToolSurface) -> Vec<FabricImage> {
    let mirrors: Vec<FabricImage> =
        FabricImage::MIRRORS.into_iter().filter(|&m| check_mirror(ply, layup, tool, m).is_ok()).collect();
    FabricImage::group_of(&mirrors)
}
