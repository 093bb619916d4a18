//! Nesting: flat patterns placed side by side on a roll of fabric.
//!
//! Roll frame: x runs along the roll (from 0 to the length used), y across it (0 to the roll
//! width). Each pattern is placed by its bounding box, whole (its regions keep their relative
//! positions), with a bottom-left skyline packer: pieces in order of decreasing length along the
//! roll, each put where its box reaches least far along the roll, then nearest the y = 0 edge.
//! Deterministic: the same patterns give the same nesting.
use super::flat::{FlatError, FlatPattern};

/// Whether a piece may be turned on the roll.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Rotation {
    /// Warp of every piece along the roll (+x): the usual choice for a woven fabric, whose warp
    /// is the roll direction.
    #[default]
    WarpAlongRoll,
    /// A piece may also be turned by +90 degrees (its warp then runs across the roll, +y), for a
    /// balanced fabric whose warp and weft are interchangeable.
    AllowQuarterTurn,
}

/// Where one pattern lies on the roll.
#[derive(Debug, Clone, PartialEq)]
pub struct Placement {
    /// Ply name.
    pub ply: String,
    /// Turned by +90 degrees (counter-clockwise): pattern (x, y) -> (-y, x) before the offset.
    pub rotated: bool,
    /// Added to the (turned) pattern coordinates to give roll coordinates (m).
    pub offset: [f64; 2],
    /// Lower-left corner of the piece's bounding box on the roll (m).
    pub min: [f64; 2],
    /// Upper-right corner of the piece's bounding box on the roll (m).
    pub max: [f64; 2],
}

impl Placement {
    /// Roll coordinates of a point given in the pattern's own frame.
    pub fn to_roll(&self, p: [f64; 2]) -> [f64; 2] {
        let q = if self.rotated { [-p[1], p[0]] } else { p };
        [q[0] + self.offset[0], q[1] + self.offset[1]]
    }

    /// Direction of the pattern's warp (+x of the pattern) on the roll.
    pub fn warp(&self) -> [f64; 2] {
        if self.rotated {
            [0.0, 1.0]
        } else {
            [1.0, 0.0]
        }
    }
}

/// A nesting of patterns on a roll, with the material used and wasted.
#[derive(Debug, Clone, PartialEq)]
pub struct Nesting {
    /// Roll width (m).
    pub roll_width: f64,
    /// Clearance kept between the bounding boxes of neighbouring pieces (m).
    pub gap: f64,
    /// Length of roll used (m): the farthest reach of any piece along x.
    pub length: f64,
    /// One placement per pattern, in the order the patterns were given.
    pub placements: Vec<Placement>,
    /// Sum of the pattern areas (m^2).
    pub pattern_area: f64,
    /// Material used, `roll_width * length` (m^2).
    pub used_area: f64,
    /// Material wasted, `used_area - pattern_area` (m^2).
    pub waste_area: f64,
    /// `waste_area / used_area` (0 when nothing was used).
    pub waste_fraction: f64,
}

/// One stretch `[y0, y1)` of the roll width and how far along the roll it is filled.
#[derive(Debug, Clone, Copy)]
struct Span {
    y0: f64,
    y1: f64,
    x: f64,
}

/// Place `patterns` on a roll `roll_width` wide, keeping `gap` between pieces (not from the roll
/// edges). Errors: a non-positive width, a negative gap, or a pattern wider than the roll in
/// every allowed orientation (naming the ply and by how much).
pub fn nest(patterns: &[FlatPattern], roll_width: f64, gap: f64, rotation: Rotation) -> Result<Nesting, FlatError> {
    if !(roll_width.is_finite() && roll_width > 0.0) {
        return Err(FlatError::BadNestParameter {
            field: "roll_width",
            value: roll_width,
            reason: "must be a positive length in metres",
        });
    }
    if !(gap.is_finite() && gap >= 0.0) {
        return Err(FlatError::BadNestParameter {
            field: "gap",
            value: gap,
            reason: "must be zero or a positive length in metres",
        });
    }
    // Every piece must fit across the roll in some allowed orientation.
    let turns: &[bool] = match rotation {
        Rotation::WarpAlongRoll => &[false],
        Rotation::AllowQuarterTurn => &[false, true],
    };
    let across = |p: &FlatPattern, turned: bool| if turned { p.size()[0] } else { p.size()[1] };
    for p in patterns {
        let (best, turned) = turns
            .iter()
            .map(|&t| (across(p, t), t))
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .expect("one orientation at least");
        if best > roll_width {
            let orientation = match (rotation, turned) {
                (Rotation::WarpAlongRoll, _) => "warp along the roll; turning is not allowed",
                _ => "in its narrower orientation",
            };
            return Err(FlatError::TooWide {
                ply: p.ply.clone(),
                across: best,
                roll_width,
                excess: best - roll_width,
                orientation,
            });
        }
    }

    // Longest pieces first; ties keep the given order (stable sort).
    let mut order: Vec<usize> = (0..patterns.len()).collect();
    let longest =
        |p: &FlatPattern| turns.iter().map(|&t| if t { p.size()[1] } else { p.size()[0] }).fold(0.0, f64::max);
    order.sort_by(|&a, &b| longest(&patterns[b]).total_cmp(&longest(&patterns[a])));

    let mut sky = vec![Span { y0: 0.0, y1: roll_width, x: 0.0 }];
    let mut placements: Vec<Option<Placement>> = vec![None; patterns.len()];
    for k in order {
        let p = &patterns[k];
        // Best (reach along the roll, x, y, turned) over orientations and skyline positions.
        let mut best: Option<(f64, f64, f64, bool)> = None;
        for &t in turns {
            let [along, wide] = if t { [p.size()[1], p.size()[0]] } else { p.size() };
            if wide > roll_width {
                continue;
            }
            for s in &sky {
                // The last stretch may start the piece lower.
                let y = s.y0.min(roll_width - wide);
                // The piece and its clearance on the +y side; pieces below keep theirs.
                let top = (y + wide + gap).min(roll_width);
                let x = sky.iter().filter(|o| o.y1 > y && o.y0 < top).map(|o| o.x).fold(0.0, f64::max);
                let cand = (x + along, x, y, t);
                let better = match best {
                    None => true,
                    Some(b) => (cand.0, cand.1, cand.2).partial_cmp(&(b.0, b.1, b.2)) == Some(std::cmp::Ordering::Less),
                };
                if better {
                    best = Some(cand);
                }
            }
        }
        let (reach, x, y, turned) = best.expect("fit across the roll was checked");
        let wide = if turned { p.size()[0] } else { p.size()[1] };
        raise(&mut sky, y, y + wide + gap, reach + gap);
        // The turned box's lower-left corner is (-max_y, min_x).
        let low = if turned { [-p.max[1], p.min[0]] } else { p.min };
        placements[k] = Some(Placement {
            ply: p.ply.clone(),
            rotated: turned,
            offset: [x - low[0], y - low[1]],
            min: [x, y],
            max: [reach, y + wide],
        });
    }
    let placements: Vec<Placement> = placements.into_iter().map(|p| p.expect("every pattern placed")).collect();
    let length = placements.iter().map(|p| p.max[0]).fold(0.0, f64::max);
    let pattern_area: f64 = patterns.iter().map(|p| p.area).sum();
    let used_area = roll_width * length;
    let waste_area = used_area - pattern_area;
    let waste_fraction = if used_area > 0.0 { waste_area / used_area } else { 0.0 };
    Ok(Nesting { roll_width, gap, length, placements, pattern_area, used_area, waste_area, waste_fraction })
}

/// Set the skyline to `x` over `[y0, y1)` (clipped to the roll), keeping the rest.
fn raise(sky: &mut Vec<Span>, y0: f64, y1: f64, x: f64) {
    let width = sky.last().map_or(0.0, |s| s.y1);
    let y1 = y1.min(width);
    let mut next = Vec::with_capacity(sky.len() + 2);
    for s in sky.iter() {
        if s.y1 <= y0 || s.y0 >= y1 {
            next.push(*s);
            continue;
        }
        if s.y0 < y0 {
            next.push(Span { y0: s.y0, y1: y0, x: s.x });
        }
        if s.y1 > y1 {
            next.push(Span { y0: y1, y1: s.y1, x: s.x });
        }
    }
    next.push(Span { y0, y1, x });
    next.sort_by(|a, b| a.y0.total_cmp(&b.y0));
    // Merge neighbours at the same reach so the candidate list stays short.
    let mut merged: Vec<Span> = Vec::with_capacity(next.len());
    for s in next {
        match merged.last_mut() {
            Some(m) if m.x == s.x && m.y1 == s.y0 => m.y1 = s.y1,
            _ => merged.push(s),
        }
    }
    *sky = merged;
}
