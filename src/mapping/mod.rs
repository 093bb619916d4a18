//! Mapping a draped net onto a resin-flow mesh: for every flow element, the warp and weft of each
//! ply projected into the element's plane, the shear angle, the thickness and fibre volume
//! fraction change and, on request, a permeability tensor (REFERENCES.md §5).
pub mod mesh;

use crate::geometry::{Point, Vector};
use crate::kinematic::sampler::NetSampler;
use crate::kinematic::DrapeNet;
pub use crate::material::flow::{collapsed, Cavity, PermeabilityModel, COLLAPSED_SHEAR_DEG, VF_CAP, VF_MAX_HEX};
pub use mesh::{Degeneracy, ElementShape, FlowElement, FlowMesh, MeshCard, MeshCards, DEGENERATE_RATIO};
use nalgebra::Matrix3;
use rayon::prelude::*;

/// The fibres of one ply in one flow element.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElementFibres {
    /// Warp direction projected into the element plane, unit.
    pub warp: Vector,
    /// Weft direction projected into the element plane, unit.
    pub weft: Vector,
    /// Unit element normal (right-handed over G1, G2, G3).
    pub normal: Vector,
    /// Shear angle, radians: pi/2 minus the angle between `warp` and `weft`.
    pub shear: f64,
    /// Angle from the element's first edge G1 -> G2 (projected) to `warp`, about `normal`,
    /// radians in (-pi, pi]: Nastran's material angle THETA.
    pub theta: f64,
    /// Angle from the ply's nominal fibre direction (its reference direction turned by the ply
    /// angle, projected into the element plane) to `warp`, about `normal`, radians in (-pi, pi]:
    /// the "angle variation" of OptiStruct's DRAPE.
    pub angle_change: f64,
    /// Ply thickness here, metres.
    pub thickness: f64,
    /// Ply thickness as laid flat (t0), metres; `thickness / nominal_thickness` is the
    /// thinning factor of OptiStruct's DRAPE.
    pub nominal_thickness: f64,
    /// Fibre volume fraction here.
    pub vf: f64,
    /// Permeability tensor in global coordinates (m^2), symmetric, principal directions along
    /// the bisectors of warp and weft and the element normal; `None` unless asked for.
    pub permeability: Option<Matrix3<f64>>,
}

/// One ply mapped onto a flow mesh: one entry per flow element, `None` where the ply does not
/// cover the element (marked, not guessed).
#[derive(Debug, Clone)]
pub struct PlyMap {
    /// Ply name.
    pub ply: String,
    /// One entry per flow element.
    pub elements: Vec<Option<ElementFibres>>,
    /// The ply's fabric as its material card gives it, `None` for a ply without a card.
    pub fabric: Option<PlyFabric>,
}

/// What a ply's material card says of the fabric in its plane, for the writers that give a
/// solver a material (the MAT8 of the Nastran and OptiStruct decks): the fibre families' tensile
/// rigidities at zero strain, the shear stiffness at zero shear and the areal mass, with the
/// ply's thickness as laid. The card models a pin-jointed net: the families do not couple (no
/// Poisson effect). These are the dry fabric's constants, not a cured laminate's.
#[derive(Debug, Clone, PartialEq)]
pub struct PlyFabric {
    /// The card's name.
    pub card: String,
    /// Warp tensile rigidity per unit width at zero strain, N/m.
    pub tension_warp: f64,
    /// Weft tensile rigidity per unit width at zero strain, N/m.
    pub tension_weft: f64,
    /// Shear stiffness dM/dg at zero shear, N/m per rad.
    pub shear: f64,
    /// Areal mass, kg/m^2.
    pub areal_mass: f64,
    /// The ply's thickness as laid flat (t0), m.
    pub thickness: f64,
}

/// The orthotropic constants of a ply of [`PlyFabric`], per unit volume (SI).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FabricModuli {
    /// E1 = warp rigidity / t0, Pa.
    pub e1: f64,
    /// E2 = weft rigidity / t0, Pa.
    pub e2: f64,
    /// G12 = shear stiffness / t0, Pa.
    pub g12: f64,
    /// NU12: 0 (the families do not couple).
    pub nu12: f64,
    /// Density = areal mass / t0, kg/m^3.
    pub density: f64,
}

impl PlyFabric {
    /// The fabric of `card` in a ply `thickness` (m) thick.
    pub fn new(card: &crate::material::MaterialCard, thickness: f64) -> PlyFabric {
        use crate::material::laws::Fibre;
        PlyFabric {
            card: card.name.clone(),
            tension_warp: card.tension(Fibre::Warp, 0.0).2,
            tension_weft: card.tension(Fibre::Weft, 0.0).2,
            shear: card.shear(0.0).2,
            areal_mass: card.areal_mass,
            thickness,
        }
    }

    /// Its constants per unit volume: the rigidities per unit width and the areal mass over the
    /// thickness, so that a shell of that thickness has the card's rigidities and mass.
    pub fn moduli(&self) -> FabricModuli {
        let t = self.thickness;
        FabricModuli {
            e1: self.tension_warp / t,
            e2: self.tension_weft / t,
            g12: self.shear / t,
            nu12: 0.0,
            density: self.areal_mass / t,
        }
    }
}

/// Every ply of a layup mapped onto one flow mesh, with laminate-level fields.
#[derive(Debug, Clone)]
pub struct LayupMap {
    /// Plies in stacking order.
    pub plies: Vec<PlyMap>,
    /// True when the map comes from a layup (field names get a `<ply>_` prefix), false for the
    /// export of one net (plain field names).
    pub layup: bool,
    /// Laminate thickness per element: the sum over the plies covering it (0 where none does).
    pub thickness: Vec<f64>,
    /// Thickness-weighted mean fibre volume fraction per element, `None` where no ply covers it.
    pub mean_vf: Vec<Option<f64>>,
    /// Laminate permeability per element (thickness-weighted mean of the plies' tensors), `None`
    /// where no ply covers it or permeability was not asked for.
    pub permeability: Vec<Option<Matrix3<f64>>>,
}

/// Fibre volume fraction assumed when a ply has no material card with a `[flow]` section (the
/// commands say so when they use it).
pub const DEFAULT_FIBRE_VOLUME_FRACTION: f64 = 0.5;
/// Ply thickness assumed when a ply has neither a material card nor a thickness, metres.
pub const DEFAULT_PLY_THICKNESS: f64 = 5.0e-4;

/// What a ply is made of and how it is mapped.
#[derive(Debug, Clone, PartialEq)]
pub struct PlyMapSettings {
    /// Ply thickness as laid flat, metres.
    pub thickness: f64,
    /// Fibre volume fraction as laid flat.
    pub vf: f64,
    /// What shear does to thickness and Vf.
    pub cavity: Cavity,
    /// Permeability tensors, when asked for.
    pub permeability: Option<PermeabilityModel>,
    /// The ply's nominal fibre direction in space (its reference direction turned by the ply
    /// angle at the seed); `angle_change` is measured from its projection into each element.
    pub nominal_warp: Vector,
    /// Largest distance (metres) from an element centroid to the net along its normal for the
    /// element to count as covered (the flow mesh may be the tool, the part's mid-surface or its
    /// outer surface, so the net may sit up to a laminate thickness away).
    pub max_distance: f64,
}

impl PlyMapSettings {
    /// Settings for `net` made of `card` (or the defaults when `None`; the returned notes say
    /// which were assumed), `thickness` overriding the card's. The nominal warp is the net's
    /// warp at its seed ([`crate::kinematic::Provenance::warp_direction`]); the search reaches a cell plus the net's stack
    /// offset plus its thickness off the net, which takes a flow mesh of the tool surface, the
    /// part's mid-surface or the outer surface.
    pub fn for_net(
        net: &DrapeNet,
        card: Option<&crate::material::MaterialCard>,
        thickness: Option<f64>,
        cavity: Cavity,
        permeability: Option<PermeabilityModel>,
    ) -> (PlyMapSettings, Vec<String>) {
        let mut notes = Vec::new();
        let recorded = net.meta.thickness_m.filter(|t| t.is_finite() && *t > 0.0);
        let thickness = thickness.or(recorded).or(card.map(|c| c.thickness)).unwrap_or_else(|| {
            notes.push(format!(
                "ply '{}': no material card or thickness: assumed t0 = {} mm",
                net.name,
                DEFAULT_PLY_THICKNESS * 1e3
            ));
            DEFAULT_PLY_THICKNESS
        });
        let vf = card.and_then(|c| c.flow).map(|f| f.fibre_volume_fraction).unwrap_or_else(|| {
            notes.push(format!(
                "ply '{}': no [flow] fibre_volume_fraction in a material card: assumed Vf0 = {DEFAULT_FIBRE_VOLUME_FRACTION}",
                net.name
            ));
            DEFAULT_FIBRE_VOLUME_FRACTION
        });
        let nominal_warp = net
            .meta
            .warp_direction
            .map(|w| Vector::new(w[0], w[1], w[2]))
            .filter(|w| w.norm() > 0.0 && w.iter().all(|x| x.is_finite()))
            .unwrap_or_else(Vector::zeros);
        let stack = net.meta.stack_offset_max_m.unwrap_or(0.0);
        let max_distance = net.spacing + stack + thickness;
        (PlyMapSettings { thickness, vf, cavity, permeability, nominal_warp, max_distance }, notes)
    }
}

/// Why a net could not be mapped.
#[derive(Debug, thiserror::Error)]
pub enum MapError {
    /// The net has no complete cell.
    #[error("ply '{ply}' has no complete cell to map; drape it again (is the seed on the tool?)")]
    EmptyNet {
        /// The ply.
        ply: String,
    },
    /// The ply covers no element of the flow mesh.
    #[error("ply '{ply}' covers none of the {elements} elements of flow mesh {path}: {cause}")]
    NotCovered {
        /// The ply.
        ply: String,
        /// The flow mesh.
        path: std::path::PathBuf,
        /// Its elements.
        elements: usize,
        /// The likely cause and the fix.
        cause: String,
    },
    /// The ply's thickness or fibre volume fraction is unusable.
    #[error("ply '{ply}': {message}")]
    Settings {
        /// The ply.
        ply: String,
        /// What is wrong.
        message: String,
    },
}

/// Signed angle from `from` to `to` about `axis` (all in one plane), radians in (-pi, pi].
fn signed_angle(from: &Vector, to: &Vector, axis: &Vector) -> f64 {
    axis.dot(&from.cross(to)).atan2(from.dot(to))
}

/// Unit projection of `v` into the plane with unit normal `n`, `None` if `v` is (nearly) normal.
fn in_plane(v: &Vector, n: &Vector) -> Option<Vector> {
    let p = v - n * n.dot(v);
    let len = p.norm();
    (len > 1e-12 * v.norm().max(f64::MIN_POSITIVE)).then(|| p / len)
}

/// Map one draped net onto a flow mesh: one entry per flow element, `None` where the ply does
/// not cover it (the element centroid's closest point on the net lies on the net's edge, or the
/// net is further than `settings.max_distance` from it) and where the element is degenerate
/// ([`FlowMesh::degeneracy`]: it has no frame to map into). Elements are independent, so the work
/// is spread over rayon's threads and the result does not depend on their number.
pub fn map_net(net: &DrapeNet, mesh: &FlowMesh, settings: &PlyMapSettings) -> Result<PlyMap, MapError> {
    let settings_error = |message: String| MapError::Settings { ply: net.name.clone(), message };
    if !(settings.thickness > 0.0 && settings.thickness.is_finite()) {
        return Err(settings_error(format!("ply thickness must be positive, got {}", settings.thickness)));
    }
    if !(settings.vf > 0.0 && settings.vf < VF_MAX_HEX) {
        return Err(settings_error(format!(
            "fibre volume fraction must lie in (0, {VF_MAX_HEX:.3}), got {}",
            settings.vf
        )));
    }
    let sampler = NetSampler::new(net).ok_or_else(|| MapError::EmptyNet { ply: net.name.clone() })?;
    let elements: Vec<Option<ElementFibres>> = (0..mesh.elements.len())
        .into_par_iter()
        .map(|e| {
            // A degenerate element has no frame: not covered ([`map_plies`] names it).
            if mesh.degeneracy(e).is_some() {
                return None;
            }
            let (Some(normal), Some(reference)) = (mesh.normal(e), mesh.first_edge(e)) else {
                return None;
            };
            let hit = sampler.cover(&mesh.centroid(e), settings.max_distance)?;
            let (w3, f3) = (hit.warp, hit.weft);
            // Angles are measured about the element's own normal (right-handed over G1, G2, G3),
            // as the solvers that read THETA measure them, whichever side the ply lies on.
            let (Some(warp), Some(weft)) = (in_plane(&w3, &normal), in_plane(&f3, &normal)) else {
                return None; // the element stands edge-on to the ply: not covered
            };
            let shear = crate::kinematic::net::corner_shear(&warp, &weft);
            let theta = signed_angle(&reference, &warp, &normal);
            let angle_change =
                in_plane(&settings.nominal_warp, &normal).map_or(0.0, |n| signed_angle(&n, &warp, &normal));
            let (thickness, vf) = settings.cavity.sheared(settings.thickness, settings.vf, shear);
            let permeability = settings.permeability.map(|m| m.tensor(vf, &warp, &weft, &normal));
            Some(ElementFibres {
                warp,
                weft,
                normal,
                shear,
                theta,
                angle_change,
                thickness,
                nominal_thickness: settings.thickness,
                vf,
                permeability,
            })
        })
        .collect();
    Ok(PlyMap { ply: net.name.clone(), elements, fabric: None })
}

/// One ply to map onto a flow mesh: its net and what it is made of.
#[derive(Debug, Clone, Copy)]
pub struct PlyToMap<'a> {
    /// The draped net.
    pub net: &'a DrapeNet,
    /// Its material card, if any (thickness, Vf0).
    pub card: Option<&'a crate::material::MaterialCard>,
    /// Thickness as laid flat overriding the card's, metres.
    pub thickness: Option<f64>,
    /// Permeability tensors, when asked for.
    pub permeability: Option<PermeabilityModel>,
}

/// Map every ply of `plies` (in stacking order) onto `mesh` and compute the laminate fields:
/// what `drape run` does with a scene's `[export]` and `drape export` with one net. `note` is
/// told every value that was assumed (a ply without a card or thickness). `layup`: field names
/// get a `<ply>_` prefix (see [`LayupMap::layup`]).
pub fn map_plies(
    mesh: &FlowMesh,
    plies: &[PlyToMap],
    cavity: Cavity,
    layup: bool,
    note: &mut dyn FnMut(&str),
) -> Result<LayupMap, MapError> {
    if let Some(n) = degenerate_note(mesh) {
        note(&n);
    }
    let mut maps = Vec::with_capacity(plies.len());
    for p in plies {
        let (settings, notes) = PlyMapSettings::for_net(p.net, p.card, p.thickness, cavity, p.permeability);
        notes.iter().for_each(|n| note(n));
        let mut map = map_net(p.net, mesh, &settings)?;
        map.fabric = p.card.map(|c| PlyFabric::new(c, settings.thickness));
        if !mesh.elements.is_empty() && map.elements.iter().all(Option::is_none) {
            return Err(MapError::NotCovered {
                ply: p.net.name.clone(),
                path: mesh.path.clone(),
                elements: mesh.elements.len(),
                cause: why_not_covered(p.net, mesh),
            });
        }
        maps.push(map);
    }
    Ok(LayupMap::new(maps, layup, mesh.elements.len()))
}

/// Degenerate elements named in a note, at most this many by id.
const DEGENERATE_LISTED: usize = 10;

/// The note on the mesh's degenerate elements (mapped as not covered), `None` when it has none.
fn degenerate_note(mesh: &FlowMesh) -> Option<String> {
    let bad: Vec<(u64, Degeneracy)> =
        (0..mesh.elements.len()).filter_map(|e| mesh.degeneracy(e).map(|d| (mesh.elements[e].id, d))).collect();
    let (first_id, first) = bad.first()?;
    let mut ids: Vec<String> = bad.iter().take(DEGENERATE_LISTED).map(|(id, _)| id.to_string()).collect();
    if bad.len() > DEGENERATE_LISTED {
        ids.push(format!("and {} more", bad.len() - DEGENERATE_LISTED));
    }
    Some(format!(
        "flow mesh {}: {} degenerate element(s) ({}) have no frame to map fibres into and are marked not covered; element {first_id}: {first}. Mend them in the mesh's pre-processor",
        mesh.path.display(),
        bad.len(),
        ids.join(", ")
    ))
}

/// A mesh this many times larger or smaller than the net (in size) is taken to be in other units.
const UNIT_MISMATCH_RATIO: f64 = 20.0;

/// The likely reason a ply covers no element of `mesh`, and the fix: the sizes of the mesh and
/// the net's boxes (another length unit when they differ by a factor of [`UNIT_MISMATCH_RATIO`]
/// or more), else how far apart they lie (another part, or the mesh placed elsewhere).
fn why_not_covered(net: &DrapeNet, mesh: &FlowMesh) -> String {
    let bounds = |points: &mut dyn Iterator<Item = Point>| {
        points.fold(None, |b: Option<(Point, Point)>, p| match b {
            None => Some((p, p)),
            Some((lo, hi)) => Some((lo.inf(&p), hi.sup(&p))),
        })
    };
    let net_box = bounds(
        &mut net
            .positions
            .iter()
            .zip(&net.status)
            .filter(|(_, s)| **s == crate::kinematic::NodeStatus::Placed)
            .map(|(p, _)| *p),
    );
    let mesh_box = bounds(&mut mesh.nodes.iter().copied());
    let (Some((nlo, nhi)), Some((mlo, mhi))) = (net_box, mesh_box) else {
        return "the net has no placed node".into();
    };
    let (net_size, mesh_size) = ((nhi - nlo).norm(), (mhi - mlo).norm());
    let ratio = mesh_size / net_size;
    if ratio >= UNIT_MISMATCH_RATIO {
        format!(
            "the mesh is {ratio:.0} times the net's size ({mesh_size:.4} against {net_size:.4} m across): it is likely in millimetres read as metres; give --mesh-units mm (drape export) or units = \"mm\" in the scene"
        )
    } else if ratio <= 1.0 / UNIT_MISMATCH_RATIO {
        format!(
            "the mesh is 1/{:.0} of the net's size ({mesh_size:.4} against {net_size:.4} m across): it is likely in metres read as millimetres; give --mesh-units m (drape export) or units = \"m\" in the scene",
            1.0 / ratio
        )
    } else {
        let gap = (mlo.coords - nhi.coords).sup(&(nlo.coords - mhi.coords)).sup(&Vector::zeros()).norm();
        format!(
            "the mesh (box from {:.4?} to {:.4?} m) and the net (box from {:.4?} to {:.4?} m) are of comparable size but lie {gap:.4} m apart or on different surfaces: is it the mesh of another part, or placed elsewhere? Give the flow mesh of the draped part, in the tool's position",
            mlo.coords.as_slice(),
            mhi.coords.as_slice(),
            nlo.coords.as_slice(),
            nhi.coords.as_slice()
        )
    }
}

/// How much of a flow mesh one ply covers and how it shears there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coverage {
    /// Elements the ply covers.
    pub covered: usize,
    /// Elements of the mesh.
    pub elements: usize,
    /// Largest and mean |shear| over the covered elements, degrees (0 when none is covered).
    pub max_abs_shear_deg: f64,
    /// Mean |shear| over the covered elements, degrees.
    pub mean_abs_shear_deg: f64,
    /// Covered elements whose Vf0 / cos(shear) reached the packing cap [`VF_CAP`].
    pub capped: usize,
    /// Covered elements sheared past [`COLLAPSED_SHEAR_DEG`] (collapsed cells of the drape): their
    /// thickness and Vf are those of that shear.
    pub collapsed: usize,
}

impl PlyMap {
    /// What the ply covers (see [`Coverage`]).
    pub fn coverage(&self) -> Coverage {
        let shears: Vec<f64> = self.elements.iter().flatten().map(|f| f.shear.abs().to_degrees()).collect();
        let max = shears.iter().cloned().fold(0.0, f64::max);
        let mean = if shears.is_empty() { 0.0 } else { shears.iter().sum::<f64>() / shears.len() as f64 };
        Coverage {
            covered: shears.len(),
            elements: self.elements.len(),
            max_abs_shear_deg: max,
            mean_abs_shear_deg: mean,
            capped: self.elements.iter().flatten().filter(|f| f.vf >= VF_CAP).count(),
            collapsed: self.elements.iter().flatten().filter(|f| collapsed(f.shear)).count(),
        }
    }
}

impl LayupMap {
    /// Gather mapped plies (in stacking order) and compute the laminate fields: thickness is the
    /// sum over the covering plies; Vf and permeability are thickness-weighted means (layers
    /// conduct in-plane flow in parallel).
    pub fn new(plies: Vec<PlyMap>, layup: bool, elements: usize) -> LayupMap {
        let mut thickness = vec![0.0; elements];
        let mut vf_sum = vec![0.0; elements];
        let mut k_sum: Vec<Option<Matrix3<f64>>> = vec![None; elements];
        let mut k_complete = vec![true; elements];
        for ply in &plies {
            for (e, f) in ply.elements.iter().enumerate() {
                let Some(f) = f else { continue };
                thickness[e] += f.thickness;
                vf_sum[e] += f.thickness * f.vf;
                match f.permeability {
                    Some(k) => *k_sum[e].get_or_insert_with(Matrix3::zeros) += k * f.thickness,
                    None => k_complete[e] = false,
                }
            }
        }
        let mean_vf = (0..elements).map(|e| (thickness[e] > 0.0).then(|| vf_sum[e] / thickness[e])).collect();
        let permeability = (0..elements)
            .map(|e| match (k_sum[e], k_complete[e] && thickness[e] > 0.0) {
                (Some(k), true) => Some(k / thickness[e]),
                _ => None,
            })
            .collect();
        LayupMap { plies, layup, thickness, mean_vf, permeability }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::shapes;
    use crate::geometry::Point;
    use crate::kinematic::{drape, KinematicSettings};

    /// Angles agree to this (radians): exact geometry on a plate, rounding only.
    const ANGLE_TOL: f64 = 1e-9;

    fn settings(cavity: Cavity) -> PlyMapSettings {
        PlyMapSettings {
            thickness: 3e-4,
            vf: 0.5,
            cavity,
            permeability: Some(PermeabilityModel { fibre_radius: 3.5e-6 }),
            nominal_warp: Vector::x(),
            max_distance: 1e-3,
        }
    }

    /// A grid of quads on z = 0, turned by `turn` about z, `n x n` cells of size `h` from `-n h / 2`.
    fn quad_mesh(n: usize, h: f64, turn: f64) -> FlowMesh {
        let (c, s) = (turn.cos(), turn.sin());
        let mut mesh = FlowMesh::default();
        for a in 0..=n {
            for b in 0..=n {
                let (x, y) = (a as f64 * h - n as f64 * h / 2.0, b as f64 * h - n as f64 * h / 2.0);
                mesh.nodes.push(Point::new(c * x - s * y, s * x + c * y, 0.0));
                mesh.node_ids.push((100 + a * (n + 1) + b) as u64);
            }
        }
        let id = |a: usize, b: usize| a * (n + 1) + b;
        for a in 0..n {
            for b in 0..n {
                mesh.elements.push(FlowElement {
                    id: (7 + 2 * mesh.elements.len()) as u64,
                    shape: ElementShape::Quad4,
                    nodes: vec![id(a, b), id(a + 1, b), id(a + 1, b + 1), id(a, b + 1)],
                    property: 1,
                });
            }
        }
        mesh
    }

    fn plate_net(pre_shear_deg: f64) -> DrapeNet {
        let tool = shapes::plate(0.4, 0.4, 8, 8).into_surface().unwrap();
        let mut s = KinematicSettings::grid("p", Point::new(0.0, 0.0, 0.0), Vector::x(), 0.01, 21, 21);
        s.pre_shear = pre_shear_deg.to_radians();
        drape(&tool, &s).unwrap()
    }

    #[test]
    fn a_pre_sheared_plate_ply_maps_its_shear_directions_and_volume_fraction() {
        let net = plate_net(20.0);
        let mesh = quad_mesh(10, 0.03, 0.3);
        let map = map_net(&net, &mesh, &settings(Cavity::Fixed)).unwrap();
        let gamma = 20f64.to_radians();
        let covered: Vec<_> = map.elements.iter().enumerate().filter_map(|(e, f)| f.map(|f| (e, f))).collect();
        assert!(covered.len() > 10 && covered.len() < mesh.elements.len(), "{} covered", covered.len());
        for (e, f) in covered {
            assert!((f.shear - gamma).abs() < ANGLE_TOL, "element {e}: shear {}", f.shear.to_degrees());
            assert!((f.warp.norm() - 1.0).abs() < ANGLE_TOL && (f.weft.norm() - 1.0).abs() < ANGLE_TOL);
            assert!(f.warp.dot(&f.normal).abs() < ANGLE_TOL && f.weft.dot(&f.normal).abs() < ANGLE_TOL);
            // The warp is the seed's warp on a plate; THETA turns the first edge onto it.
            assert!((f.warp - Vector::x()).norm() < ANGLE_TOL, "element {e}: warp {:?}", f.warp);
            let edge = mesh.first_edge(e).unwrap();
            let turned = nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(f.normal), f.theta) * edge;
            assert!((turned - f.warp).norm() < ANGLE_TOL);
            assert!((f.theta + 0.3).abs() < ANGLE_TOL, "theta {}", f.theta);
            assert!(f.angle_change.abs() < ANGLE_TOL);
            assert!((f.vf - 0.5 / gamma.cos()).abs() < 1e-12 && f.thickness == 3e-4);
        }
        let free = map_net(&net, &mesh, &settings(Cavity::Free)).unwrap();
        let f = free.elements.iter().flatten().next().unwrap();
        assert!((f.thickness - 3e-4 / gamma.cos()).abs() < 1e-15 && f.vf == 0.5);
    }

    #[test]
    fn elements_off_the_net_or_too_far_from_it_are_not_covered() {
        let net = plate_net(0.0); // covers [-0.1, 0.1]^2
        let mut mesh = quad_mesh(2, 0.05, 0.0); // [-0.05, 0.05]^2: all covered
        let map = map_net(&net, &mesh, &settings(Cavity::Fixed)).unwrap();
        assert!(map.elements.iter().all(Option::is_some));
        mesh.nodes.iter_mut().for_each(|p| p.x += 0.2); // now beside the net
        assert!(map_net(&net, &mesh, &settings(Cavity::Fixed)).unwrap().elements.iter().all(Option::is_none));
        mesh.nodes.iter_mut().for_each(|p| {
            p.x -= 0.2;
            p.z += 2e-3; // above the net by more than max_distance
        });
        assert!(map_net(&net, &mesh, &settings(Cavity::Fixed)).unwrap().elements.iter().all(Option::is_none));
    }

    #[test]
    fn permeability_is_isotropic_unsheared_and_turns_to_the_bisectors_when_sheared() {
        let m = PermeabilityModel { fibre_radius: 5e-6 };
        let n = Vector::z();
        let k = m.tensor(0.5, &Vector::x(), &Vector::y(), &n);
        assert!((k[(0, 0)] - k[(1, 1)]).abs() < 1e-12 * k[(0, 0)] && k[(0, 1)].abs() < 1e-12 * k[(0, 0)]);
        let g = 30f64.to_radians();
        let weft = Vector::new(g.sin(), g.cos(), 0.0); // 60 deg from the warp
        let k = m.tensor(0.5 / g.cos(), &Vector::x(), &weft, &n);
        assert!((k - k.transpose()).norm() < 1e-12 * k.norm());
        let acute = (Vector::x() + weft).normalize();
        let obtuse = (Vector::x() - weft).normalize();
        let (ka, ko) = ((k * acute).dot(&acute), (k * obtuse).dot(&obtuse));
        assert!(ka > ko, "the acute bisector conducts more: {ka} vs {ko}");
        assert!((k * acute - acute * ka).norm() < 1e-9 * ka, "acute bisector is principal");
        // Denser fabric, lower permeability.
        assert!(m.principal(0.6).0 < m.principal(0.5).0 && m.principal(0.6).1 < m.principal(0.5).1);
    }

    #[test]
    fn laminate_fields_are_thickness_weighted() {
        let f = |t: f64, vf: f64| ElementFibres {
            warp: Vector::x(),
            weft: Vector::y(),
            normal: Vector::z(),
            shear: 0.0,
            theta: 0.0,
            angle_change: 0.0,
            thickness: t,
            nominal_thickness: t,
            vf,
            permeability: None,
        };
        let a = PlyMap { ply: "a".into(), elements: vec![Some(f(1e-3, 0.5)), None], fabric: None };
        let b = PlyMap { ply: "b".into(), elements: vec![Some(f(3e-3, 0.6)), None], fabric: None };
        let m = LayupMap::new(vec![a, b], true, 2);
        assert!((m.thickness[0] - 4e-3).abs() < 1e-18 && m.thickness[1] == 0.0);
        assert!((m.mean_vf[0].unwrap() - 0.575).abs() < 1e-12 && m.mean_vf[1].is_none());
        assert!(m.permeability.iter().all(Option::is_none));
    }

    /// Elements with a repeated node, coincident corners or corners in a line: a named note, the
    /// element marked not covered, the rest mapped as before; a quad collapsed to a triangle away
    /// from G1-G2 keeps its frame and is mapped.
    #[test]
    fn degenerate_elements_are_named_and_skipped_and_the_rest_is_mapped() {
        let net = plate_net(0.0);
        for turn in [0.0, 0.4, -1.1] {
            let mut mesh = quad_mesh(4, 0.03, turn);
            let clean = map_net(&net, &mesh, &settings(Cavity::Fixed)).unwrap();
            let n = mesh.elements.len();
            assert!(clean.elements.iter().all(Option::is_some));
            // G1 = G2 (the panic of issue 34), G2 at G1's place, a triangle with a repeated
            // node, a quad whose opposite corners are one node, and a quad collapsed at G3 = G4.
            let nodes = |k: usize| mesh.elements[k].nodes.clone();
            let (a, b, c, d) = (nodes(0), nodes(1), nodes(2), nodes(3));
            mesh.elements[0].nodes = vec![a[0], a[0], a[2], a[3]];
            let moved = mesh.nodes.len();
            mesh.nodes.push(mesh.nodes[b[0]]);
            mesh.node_ids.push(9999);
            mesh.elements[1].nodes = vec![b[0], moved, b[2], b[3]];
            mesh.elements[2] =
                FlowElement { shape: ElementShape::Tria3, nodes: vec![c[0], c[1], c[0]], ..mesh.elements[2].clone() };
            mesh.elements[3].nodes = vec![d[0], d[1], d[0], d[3]];
            mesh.elements[4].nodes = vec![
                mesh.elements[4].nodes[0],
                mesh.elements[4].nodes[1],
                mesh.elements[4].nodes[2],
                mesh.elements[4].nodes[2],
            ];
            let ids: Vec<u64> = mesh.elements.iter().map(|e| e.id).collect();
            assert!(matches!(mesh.degeneracy(0), Some(Degeneracy::NoFirstEdge { g1, g2 }) if g1 == g2));
            assert!(matches!(mesh.degeneracy(1), Some(Degeneracy::NoFirstEdge { g1, g2 }) if g2 == 9999 && g1 != g2));
            assert!(matches!(mesh.degeneracy(2), Some(Degeneracy::ZeroArea { .. })));
            assert!(matches!(mesh.degeneracy(3), Some(Degeneracy::ZeroArea { .. })));
            assert_eq!(mesh.degeneracy(4), None, "a quad collapsed at G3 = G4 is a triangle");
            let mut notes = Vec::new();
            let card = None;
            let plies = [PlyToMap { net: &net, card, thickness: Some(3e-4), permeability: None }];
            let map = map_plies(&mesh, &plies, Cavity::Fixed, false, &mut |m| notes.push(m.to_string())).unwrap();
            let ply = &map.plies[0];
            assert!(ply.elements[..4].iter().all(Option::is_none));
            assert!(ply.elements[4..].iter().all(Option::is_some), "the rest is mapped");
            for e in 5..n {
                assert_eq!(ply.elements[e].map(|f| f.theta), clean.elements[e].map(|f| f.theta));
            }
            let degenerate: Vec<&String> = notes.iter().filter(|m| m.contains("degenerate")).collect();
            assert_eq!(degenerate.len(), 1, "{notes:?}");
            let listed = format!("({}, {}, {}, {})", ids[0], ids[1], ids[2], ids[3]);
            assert!(
                degenerate[0].contains("4 degenerate element(s)") && degenerate[0].contains(&listed),
                "{}",
                degenerate[0]
            );
            assert!(degenerate[0].contains("same node"), "{}", degenerate[0]);
        }
    }
}
