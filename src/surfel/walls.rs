//! A terrain's walls: surfels where an airborne scan has no samples (issue 13).
//!
//! An airborne tile is a height field. Its samples lie on roofs, streets and canopies,
//! and none on the walls between them, which the scanner sees edge-on or not at all.
//! The 2.5D triangulation of the same samples joins a roof's edge to the street below
//! with steep triangles, so its buildings stand on walls. Splats of the samples alone
//! leave each roof floating over its street, in the same shade (their normals all face
//! up): the buildings are hard to make out, and where a view looks under a roof's edge
//! it sees through to the background.
//!
//! So a sample p gets one wall surfel when, among its [`K`] nearest samples in x–y, a
//! sample q lies lower by more than [`WALL_SLOPE`] times their horizontal distance and
//! by more than the sampling's spacing s there (p's [`WIDTH_RANK`]-th nearest
//! horizontal distance), and p is the edge: no sample of the upper level (over the
//! drop's middle) lies nearer q. The wall stands under the steepest such drop dz: vertical,
//! facing from p toward q, centred midway between them in x–y and in height, with
//! semi-axes dz/2 down the drop and s along the edge (the thinner of the two at least
//! [`MIN_RATIO`] of the other), p's colour and attributes. Walls of neighbouring edge
//! samples, s apart, overlap. p's own splat is clipped where its wall stands
//! ([`Wall::clip_of`]), as the triangulation's roof ends at its edge.
//!
//! Trees make walls as well: a canopy's returns drop steeply to the ground, and the
//! triangulation draws those drops too.

use arrayvec::ArrayVec;
use glam::{DVec2, DVec3, Vec2, Vec3};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

use super::Surfel;
use super::clip::Clip;
use super::shape::{MIN_RATIO, Shape};

/// The horizontal neighbourhood a drop is looked for in, the sample itself included: as
/// many as the surfels' own neighbourhoods ([`super::cloud::K`]).
pub const K: usize = 24;

/// Least steepness (drop over horizontal distance) of a drop that a wall fills: about
/// 63°. Steeper limits (3, about 72°) and gentler ones (1, 45°) changed the tile's
/// FLIP by under 0.001.
pub const WALL_SLOPE: f32 = 2.0;

/// Which horizontal neighbour's distance is the sampling's spacing along an edge: the
/// 4th (about 1.2 spacings of an even sampling), so that walls of neighbouring edge
/// samples overlap.
pub const WIDTH_RANK: usize = 4;

/// A wall below a terrain sample's edge, in the unit-scaled coordinates of the search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wall {
    pub centre: Vec3,
    /// Horizontal, from the upper sample toward the lower.
    pub normal: Vec3,
    /// The ellipse's major axis: vertical, or along the edge for a drop lower than the
    /// spacing is wide.
    pub axis: Vec3,
    /// The major semi-axis.
    pub major: f32,
    /// Minor over major semi-axis, in [[`MIN_RATIO`], 1].
    pub ratio: f32,
}

impl Wall {
    /// The wall's surfel in model units (`scale` the search's unit scale), with the
    /// colour and attributes of `upper`, the sample whose edge it stands under.
    pub fn surfel(&self, scale: f32, upper: &Surfel) -> Surfel {
        let n = self.normal.as_dvec3();
        Surfel {
            position: self.centre / scale,
            radius: self.major / scale,
            normal: self.normal,
            color: upper.color,
            shape: Shape::ellipse(n, self.axis.as_dvec3(), self.ratio as f64).pack(),
            attributes: upper.attributes,
        }
    }

    /// Where the splat of the upper sample at `p` (unit-scaled; its `shape`, unit
    /// normal `n` and major radius `radius`, unit-scaled) ends: the line through the
    /// wall's foot in its plane, perpendicular to the direction toward the wall. `None`
    /// when that direction lies along the splat's normal.
    pub fn clip_of(&self, p: Vec3, (shape, n, radius): (&Shape, DVec3, f32)) -> Option<Clip> {
        let toward = (self.centre - p).truncate().extend(0.0).as_dvec3();
        let d = DVec2::new(toward.dot(shape.axis), toward.dot(shape.minor_axis(n)));
        let normal = d.try_normalize()?;
        Some(Clip::Line {
            normal,
            offset: d.length() / radius as f64,
        })
    }
}

/// The walls under `queries` (unit-scaled positions among `coords`, the distinct
/// positions of the cloud, unit-scaled), each with the index of the query it stands
/// under, ascending; a query where no drop calls for one has none.
pub fn terrain_walls(coords: &[[f32; 3]], queries: &[Vec3]) -> Vec<(usize, Wall)> {
    let xy: Vec<[f32; 2]> = coords.iter().map(|c| [c[0], c[1]]).collect();
    let Ok(tree) = ImmutableKdTree::<f32, 2>::new_from_slice(&xy) else {
        return Vec::new();
    };
    let n = std::num::NonZero::new(K.min(xy.len())).unwrap_or(std::num::NonZero::<usize>::MIN);
    queries
        .par_iter()
        .enumerate()
        .filter_map(|(k, &p)| {
            let near: ArrayVec<Vec3, K> = tree
                .query(&[p.x, p.y])
                .nearest_n::<SquaredEuclidean<f32>>(n)
                .execute()
                .iter()
                .map(|f| Vec3::from(coords[f.item as usize]))
                .collect();
            wall_below(p, &near).map(|w| (k, w))
        })
        .collect()
}

/// The wall under `p` given its horizontal neighbourhood `near` (the module doc).
fn wall_below(p: Vec3, near: &[Vec3]) -> Option<Wall> {
    let mut horizontal: ArrayVec<f32, K> = near
        .iter()
        .map(|q| (*q - p).truncate().length())
        .filter(|h| *h > 0.0)
        .collect();
    let rank = WIDTH_RANK.min(horizontal.len()).checked_sub(1)?;
    let spacing = *horizontal.select_nth_unstable_by(rank, f32::total_cmp).1;
    // A sample right below p (another return of the same pulse) faces no way.
    let steepness = |q: &Vec3| (p.z - q.z) / (*q - p).truncate().length();
    let q = *near
        .iter()
        .filter(|q| p.z - q.z > spacing && (*q - p).truncate() != Vec2::ZERO)
        .filter(|q| steepness(q) > WALL_SLOPE)
        .max_by(|a, b| steepness(a).total_cmp(&steepness(b)))?;
    let drop = p.z - q.z;
    // Not an edge where the upper level reaches nearer q than p does.
    let reach = (q - p).truncate().length();
    let upper = |r: &&Vec3| r.z > q.z + 0.5 * drop;
    if near
        .iter()
        .filter(upper)
        .any(|r| (*r - q).truncate().length() < reach)
    {
        return None;
    }
    // In f64: an f32 direction whose squares near f32's least normal is not unit.
    let out = (q - p).truncate().as_dvec2().try_normalize()?;
    let normal = out.as_vec2().extend(0.0);
    let (half_height, half_width) = (0.5 * drop, spacing);
    let (axis, major, minor) = if half_height >= half_width {
        (Vec3::Z, half_height, half_width)
    } else {
        (normal.cross(Vec3::Z), half_width, half_height)
    };
    let foot: Vec2 = 0.5 * (p.truncate() + q.truncate());
    Some(Wall {
        centre: foot.extend(p.z - half_height),
        normal,
        axis,
        major,
        ratio: (minor / major).max(MIN_RATIO as f32),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat roof 10 high on a street (samples 1 apart): every roof sample on the
    /// edge gets a wall down to the street, facing it; no other sample does.
    #[test]
    fn a_roof_s_edge_stands_on_walls_and_nothing_else_does() {
        let coords: Vec<[f32; 3]> = (0..40 * 40)
            .map(|i| {
                let (x, y) = ((i % 40) as f32, (i / 40) as f32);
                [x, y, if x < 20.0 { 10.0 } else { 0.0 }]
            })
            .collect();
        let queries: Vec<Vec3> = coords.iter().map(|c| Vec3::from(*c)).collect();
        let walls = terrain_walls(&coords, &queries);
        let under: Vec<usize> = walls.iter().map(|(k, _)| *k).collect();
        let edge: Vec<usize> = (0..queries.len())
            .filter(|&k| queries[k].x == 19.0)
            .collect();
        assert_eq!(under, edge, "walls under the edge row and nowhere else");
        for (k, w) in &walls {
            let p = queries[*k];
            assert_eq!((w.normal, w.axis), (Vec3::X, Vec3::Z), "under {p}");
            let centre = Vec3::new(19.5, p.y, 5.0);
            assert!(
                (w.centre - centre).length() < 1e-6 && w.major == 5.0,
                "{w:?}"
            );
            // A spacing 1 wide (√2 at the grid's corners) and 5 high.
            assert!((0.25..0.29).contains(&w.ratio), "{w:?}");
        }
        let wall_under = |walls: &[(usize, Wall)], k: usize| {
            walls.iter().find(|(j, _)| *j == k).map(|(_, w)| *w)
        };
        // A second return right below an edge sample leaves its wall as it was.
        let mut returns = coords.clone();
        returns.push([19.0, 20.0, 4.0]);
        let again = terrain_walls(&returns, &queries);
        let edge_sample = 20 * 40 + 19;
        assert_eq!(
            wall_under(&again, edge_sample),
            wall_under(&walls, edge_sample)
        );
        // The edge sample's splat ends at its wall's foot, half a spacing out.
        let p = Vec3::new(19.0, 20.0, 10.0);
        let w = wall_under(&walls, edge_sample).expect("a wall under the edge");
        let shape = Shape::ellipse(DVec3::Z, DVec3::X, 1.0);
        let Some(Clip::Line { normal, offset }) = w.clip_of(p, (&shape, DVec3::Z, 2.0)) else {
            panic!("no clip");
        };
        assert!((normal - DVec2::X).length() < 1e-9 && (offset - 0.25).abs() < 1e-9);
    }

    /// Drops to a sample 10⁻¹⁹ to 10⁻²¹ away in x (the fuzzer found such): their
    /// squares are at or below f32's least normal; the wall's normal is still unit.
    #[test]
    fn a_drop_to_a_sample_almost_below_faces_a_unit_way() {
        let p = Vec3::new(0.0, 0.0, 1.0);
        for dx in [1e-19, 3e-20, 1.3e-20, 1e-20, 3e-21] {
            let near = [
                p,
                Vec3::new(dx, 0.0, -9.0),
                Vec3::new(2.0, 0.0, 1.0),
                Vec3::new(0.0, 2.0, 1.0),
                Vec3::new(-2.0, 0.0, 1.0),
                Vec3::new(0.0, -2.0, 1.0),
            ];
            let w = wall_below(p, &near).expect("a wall");
            assert!((w.normal.length() - 1.0).abs() < 1e-6, "{dx}: {w:?}");
            assert!(w.major.is_finite() && w.major > 0.0, "{dx}: {w:?}");
        }
    }
}
