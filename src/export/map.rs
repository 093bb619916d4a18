//! Mapping a draped net onto a resin-flow mesh: for every flow element, the warp and weft of each
//! ply projected into the element's plane, the shear angle, the thickness and fibre volume
//! fraction change and, on request, a permeability tensor (REFERENCES.md §5).
use super::flowmesh::FlowMesh;
use crate::geometry::surface::closest_point_on_triangle;
use crate::geometry::{Point, Vector};
use crate::kinematic::DrapeNet;
use nalgebra::Matrix3;
use rayon::prelude::*;
use std::collections::HashMap;

/// What happens to a sheared ply's thickness (REFERENCES.md §5).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cavity {
    /// Closed mould, cavity thickness fixed: t = t0, Vf = Vf0 / cos(gamma).
    Fixed,
    /// Free thickness: t = t0 / cos(gamma), Vf = Vf0.
    Free,
}

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
    pub ply: String,
    pub elements: Vec<Option<ElementFibres>>,
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

/// Gebart's constant c for the axial permeability of a hexagonal fibre packing (Gebart 1992).
const GEBART_C_HEX: f64 = 57.0;
/// Largest fibre volume fraction of a hexagonal packing, pi / (2 sqrt 3): fibres touch.
pub const VF_MAX_HEX: f64 = 0.906_899_682_117_108_9;
/// Fibre volume fractions are capped just below the packing limit (the fabric would have locked
/// long before; the cap keeps the permeability model finite); the commands count the elements
/// that reach it.
pub const VF_CAP: f64 = VF_MAX_HEX - 1e-6;
/// A centroid whose closest point on the net lies further than this (times the net spacing) from
/// it along the net's tangent plane is off the net's edge: the element is not covered.
const EDGE_TOLERANCE_REL: f64 = 1e-6;
/// Half-cells with less area than this (times d^2) are left out of the net's search mesh.
const MIN_TRIANGLE_AREA_REL: f64 = 1e-12;

/// Permeability model asked for with the mapping (REFERENCES.md §5): Gebart's (1992) axial and
/// transverse permeabilities of a hexagonal fibre packing, K_par = 8 r^2 / c (1 - Vf)^3 / Vf^2 and
/// K_perp = 16 / (9 pi sqrt 6) (sqrt(Vf_max / Vf) - 1)^(5/2) r^2, mixed over the ply's two fibre
/// directions: K = K_par A + K_perp (P - A) + K_perp n n^T with A = (w w^T + f f^T) / 2 and
/// P = I - n n^T. An unsheared balanced ply is isotropic in its plane; a sheared one has its
/// principal directions on the bisectors of warp and weft, the larger along the acute bisector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PermeabilityModel {
    /// Fibre radius, metres (carbon about 3.5e-6, glass about 8e-6).
    pub fibre_radius: f64,
}

impl PermeabilityModel {
    /// Axial and transverse permeabilities (m^2) at fibre volume fraction `vf`.
    pub fn principal(&self, vf: f64) -> (f64, f64) {
        let r2 = self.fibre_radius * self.fibre_radius;
        let vf = vf.clamp(1e-6, VF_CAP);
        let k_par = 8.0 * r2 / GEBART_C_HEX * (1.0 - vf).powi(3) / (vf * vf);
        let c1 = 16.0 / (9.0 * std::f64::consts::PI * 6f64.sqrt());
        let k_perp = c1 * ((VF_MAX_HEX / vf).sqrt() - 1.0).powf(2.5) * r2;
        (k_par, k_perp)
    }

    /// The tensor of a ply with in-plane unit fibre directions `warp`, `weft` and normal `normal`.
    pub fn tensor(&self, vf: f64, warp: &Vector, weft: &Vector, normal: &Vector) -> Matrix3<f64> {
        let (k_par, k_perp) = self.principal(vf);
        let a = (warp * warp.transpose() + weft * weft.transpose()) * 0.5;
        let nn = normal * normal.transpose();
        let p = Matrix3::identity() - nn;
        a * k_par + (p - a) * k_perp + nn * k_perp
    }
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
    /// warp at its seed (meta `warp_direction`); the search reaches a cell plus the net's stack
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
        let recorded = net.meta.get("thickness_m").and_then(|v| v.as_f64()).filter(|t| t.is_finite() && *t > 0.0);
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
            .get("warp_direction")
            .and_then(|v| serde_json::from_value::<[f64; 3]>(v.clone()).ok())
            .map(|w| Vector::new(w[0], w[1], w[2]))
            .filter(|w| w.norm() > 0.0 && w.iter().all(|x| x.is_finite()))
            .unwrap_or_else(Vector::zeros);
        let stack = net.meta.get("stack_offset_max_m").and_then(|v| v.as_f64()).unwrap_or(0.0);
        let max_distance = net.spacing + stack + thickness;
        (PlyMapSettings { thickness, vf, cavity, permeability, nominal_warp, max_distance }, notes)
    }
}

/// Why a net could not be mapped.
#[derive(Debug, thiserror::Error)]
pub enum MapError {
    #[error("ply '{ply}' has no complete cell to map; drape it again (is the seed on the tool?)")]
    EmptyNet { ply: String },
    #[error("flow mesh {path} element {id} is degenerate (zero area): mend the mesh in its pre-processor")]
    DegenerateElement { path: std::path::PathBuf, id: u64 },
    #[error("ply '{ply}': {message}")]
    Settings { ply: String, message: String },
}

/// Where a point lands on a net: the cell, the bilinear parameters in it, the closest point and
/// the fibre tangents there.
#[derive(Debug, Clone, Copy)]
pub struct NetSample {
    /// Cell (i, j) of the net.
    pub cell: (usize, usize),
    /// Bilinear parameters in the cell, along the warp (`s`) and the weft (`t`), in [0, 1].
    pub s: f64,
    pub t: f64,
    /// The closest point of the net.
    pub point: Point,
    /// Warp and weft tangents of the bilinear cell patch there (not normalised).
    pub warp: Vector,
    pub weft: Vector,
    /// Unit normal warp x weft.
    pub normal: Vector,
    /// Signed distance from the net to the query point along `normal`.
    pub normal_distance: f64,
    /// How far (metres, in the cell's parameters times d) the query point lies beyond the net's
    /// edge: 0 over the net.
    pub beyond_edge: f64,
}

impl NetSample {
    /// Shear of the patch here, radians.
    pub fn shear(&self) -> f64 {
        crate::kinematic::net::corner_shear(&self.warp, &self.weft)
    }
}

/// A net as triangles (two per complete cell) in a uniform hash grid of cell size 2d, for
/// closest-point queries near the net. (Our own grid rather than a BVH: nets are regular, their
/// triangles all about d in size, and collapsed or coincident cells of a locked net must not
/// upset the search structure.)
pub struct NetSampler<'a> {
    net: &'a DrapeNet,
    /// Triangle corners by node index, and the cell (i, j) and half (0: corners 00-10-11,
    /// 1: corners 00-11-01) of each triangle.
    triangles: Vec<([usize; 3], (usize, usize, u8))>,
    grid: HashMap<[i64; 3], Vec<u32>>,
    bin: f64,
}

impl<'a> NetSampler<'a> {
    /// `None` when the net has no complete cell.
    pub fn new(net: &'a DrapeNet) -> Option<Self> {
        let bin = 2.0 * net.spacing;
        let key = |p: &Point| [(p.x / bin).floor() as i64, (p.y / bin).floor() as i64, (p.z / bin).floor() as i64];
        let min_area = MIN_TRIANGLE_AREA_REL * net.spacing * net.spacing;
        let mut triangles = Vec::new();
        let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for i in 0..net.nu.saturating_sub(1) {
            for j in 0..net.nv.saturating_sub(1) {
                if net.cell_corners(i, j).is_none() {
                    continue;
                }
                let c = [net.index(i, j), net.index(i + 1, j), net.index(i + 1, j + 1), net.index(i, j + 1)];
                for (half, tri) in [(0u8, [c[0], c[1], c[2]]), (1, [c[0], c[2], c[3]])] {
                    let [a, b, d] = tri.map(|k| net.positions[k]);
                    // Collapsed halves (a folded or locked cell) carry no area to find.
                    if (b - a).cross(&(d - a)).norm() <= min_area {
                        continue;
                    }
                    let lo = key(&Point::from(a.coords.inf(&b.coords).inf(&d.coords)));
                    let hi = key(&Point::from(a.coords.sup(&b.coords).sup(&d.coords)));
                    for x in lo[0]..=hi[0] {
                        for y in lo[1]..=hi[1] {
                            for z in lo[2]..=hi[2] {
                                grid.entry([x, y, z]).or_default().push(triangles.len() as u32);
                            }
                        }
                    }
                    triangles.push((tri, (i, j, half)));
                }
            }
        }
        (!triangles.is_empty()).then_some(NetSampler { net, triangles, grid, bin })
    }

    /// The net at its closest point to `p`, if the net comes within `radius` of `p`.
    pub fn nearest_within(&self, p: &Point, radius: f64) -> Option<NetSample> {
        let net = self.net;
        let lo = ((p.coords - Vector::repeat(radius)) / self.bin).map(f64::floor);
        let hi = ((p.coords + Vector::repeat(radius)) / self.bin).map(f64::floor);
        let mut best: Option<(f64, u32, Point)> = None;
        for x in lo.x as i64..=hi.x as i64 {
            for y in lo.y as i64..=hi.y as i64 {
                for z in lo.z as i64..=hi.z as i64 {
                    for &t in self.grid.get(&[x, y, z]).map_or(&[][..], Vec::as_slice) {
                        let [a, b, c] = self.triangles[t as usize].0.map(|k| net.positions[k]);
                        let q = closest_point_on_triangle(p, &a, &b, &c);
                        let d2 = (q - p).norm_squared();
                        // Ties go to the lower triangle number, so the answer does not depend on
                        // the order the grid lists them in.
                        if best.is_none_or(|(bd, bt, _)| d2 < bd || (d2 == bd && t < bt)) {
                            best = Some((d2, t, q));
                        }
                    }
                }
            }
        }
        let (d2, t, x) = best?;
        if d2 > radius * radius {
            return None;
        }
        let ([k0, k1, k2], (i, j, half)) = self.triangles[t as usize];
        // Parameters of p's projection onto the triangle's plane, not clamped: a point over the
        // net lies inside its cell up to the kink between neighbouring facets; one beyond the
        // net's edge lies outside a cell that has no neighbour on that side.
        let l = barycentric(p, &net.positions[k0], &net.positions[k1], &net.positions[k2]);
        let (s, t) = if half == 0 { (l[1] + l[2], l[2]) } else { (l[1], l[1] + l[2]) };
        let complete = |a: isize, b: isize| {
            a >= 0
                && b >= 0
                && (a as usize) + 1 < net.nu
                && (b as usize) + 1 < net.nv
                && net.cell_corners(a as usize, b as usize).is_some()
        };
        let (ci, cj) = (i as isize, j as isize);
        let di = if s < 0.0 {
            -1
        } else if s > 1.0 {
            1
        } else {
            0
        };
        let dj = if t < 0.0 {
            -1
        } else if t > 1.0 {
            1
        } else {
            0
        };
        let over_s = if s < 0.0 { -s } else { (s - 1.0).max(0.0) };
        let over_t = if t < 0.0 { -t } else { (t - 1.0).max(0.0) };
        let mut beyond = 0.0f64;
        if di != 0 && !complete(ci + di, cj) {
            beyond = beyond.max(over_s);
        }
        if dj != 0 && !complete(ci, cj + dj) {
            beyond = beyond.max(over_t);
        }
        if di != 0 && dj != 0 && !complete(ci + di, cj + dj) {
            beyond = beyond.max(over_s.min(over_t));
        }
        let beyond_edge = beyond * net.spacing;
        let (s, t) = (s.clamp(0.0, 1.0), t.clamp(0.0, 1.0));
        let q = |a: usize, b: usize| net.positions[net.index(a, b)];
        let (p00, p10, p11, p01) = (q(i, j), q(i + 1, j), q(i + 1, j + 1), q(i, j + 1));
        let warp = (p10 - p00) * (1.0 - t) + (p11 - p01) * t;
        let weft = (p01 - p00) * (1.0 - s) + (p11 - p10) * s;
        let normal = warp.cross(&weft).normalize();
        let normal_distance = (p - x).dot(&normal);
        Some(NetSample { cell: (i, j), s, t, point: x, warp, weft, normal, normal_distance, beyond_edge })
    }

    /// The net under `p`, or `None` when `p` lies beyond the net's edge or further than
    /// `max_distance` from it along the normal.
    pub fn cover(&self, p: &Point, max_distance: f64) -> Option<NetSample> {
        let edge = EDGE_TOLERANCE_REL * self.net.spacing;
        let h = self.nearest_within(p, max_distance + edge)?;
        (h.beyond_edge <= edge && h.normal_distance.abs() <= max_distance).then_some(h)
    }
}

fn barycentric(p: &Point, a: &Point, b: &Point, c: &Point) -> [f64; 3] {
    let (e1, e2, w) = (b - a, c - a, p - a);
    let (d11, d12, d22) = (e1.dot(&e1), e1.dot(&e2), e2.dot(&e2));
    let den = d11 * d22 - d12 * d12;
    if den <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let (x, y) = (w.dot(&e1), w.dot(&e2));
    let l1 = (d22 * x - d12 * y) / den;
    let l2 = (d11 * y - d12 * x) / den;
    [1.0 - l1 - l2, l1, l2]
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
/// net is further than `settings.max_distance` from it). Elements are independent, so the work
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
    let elements: Result<Vec<Option<ElementFibres>>, MapError> = (0..mesh.elements.len())
        .into_par_iter()
        .map(|e| {
            let normal = mesh
                .normal(e)
                .ok_or_else(|| MapError::DegenerateElement { path: mesh.path.clone(), id: mesh.elements[e].id })?;
            let Some(hit) = sampler.cover(&mesh.centroid(e), settings.max_distance) else {
                return Ok(None);
            };
            let (w3, f3) = (hit.warp, hit.weft);
            // Angles are measured about the element's own normal (right-handed over G1, G2, G3),
            // as the solvers that read THETA measure them, whichever side the ply lies on.
            let (Some(warp), Some(weft)) = (in_plane(&w3, &normal), in_plane(&f3, &normal)) else {
                return Ok(None); // the element stands edge-on to the ply: not covered
            };
            let shear = crate::kinematic::net::corner_shear(&warp, &weft);
            let reference = mesh.first_edge(e).expect("a non-degenerate element has a first edge");
            let theta = signed_angle(&reference, &warp, &normal);
            let angle_change =
                in_plane(&settings.nominal_warp, &normal).map_or(0.0, |n| signed_angle(&n, &warp, &normal));
            let cos = shear.cos().max(f64::MIN_POSITIVE);
            let (thickness, vf) = match settings.cavity {
                Cavity::Fixed => (settings.thickness, (settings.vf / cos).min(VF_CAP)),
                Cavity::Free => (settings.thickness / cos, settings.vf),
            };
            let permeability = settings.permeability.map(|m| m.tensor(vf, &warp, &weft, &normal));
            Ok(Some(ElementFibres {
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
            }))
        })
        .collect();
    Ok(PlyMap { ply: net.name.clone(), elements: elements? })
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
    use crate::export::flowmesh::{ElementShape, FlowElement};
    use crate::geometry::shapes;
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
        let a = PlyMap { ply: "a".into(), elements: vec![Some(f(1e-3, 0.5)), None] };
        let b = PlyMap { ply: "b".into(), elements: vec![Some(f(3e-3, 0.6)), None] };
        let m = LayupMap::new(vec![a, b], true, 2);
        assert!((m.thickness[0] - 4e-3).abs() < 1e-18 && m.thickness[1] == 0.0);
        assert!((m.mean_vf[0].unwrap() - 0.575).abs() < 1e-12 && m.mean_vf[1].is_none());
        assert!(m.permeability.iter().all(Option::is_none));
    }
}
