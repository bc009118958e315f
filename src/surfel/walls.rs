//! A terrain's walls: surfels where an airborne scan has no samples.
//!
//! An airborne tile is a height field. Its samples lie on roofs, streets and canopies,
//! and none on the walls between them, which the scanner sees edge-on or not at all.
//! The 2.5D triangulation of the same samples joins a roof's edge to the street below
//! with steep triangles, so its buildings stand on walls. Splats of the samples alone
//! leave each roof floating over its street, in the same shade (their normals all face
//! up): the buildings are hard to make out, and where a view looks under a roof's edge
//! it sees through to the background.
//!
//! So a sample p gets a wall when, among its [`K`] nearest samples in x–y, a sample q
//! lies lower by more than [`WALL_SLOPE`] times their horizontal distance and by more
//! than the sampling's spacing s there (p's [`WIDTH_RANK`]-th nearest horizontal
//! distance). Of such drops the steepest, dz, says how high the wall is. The wall faces
//! across the edge, `out`: from the centroid (in x–y) of the neighbours above the
//! drop's middle toward that of those below it. p must be the edge: no neighbour of the
//! upper level lies further out than p by more than [`EDGE_SLACK`] s within s of p
//! along the edge. The wall is the slope from p's edge down to q's height, |pq| further
//! out (what a triangulation of p and q draws, the least a pair of samples says), 2s
//! wide along the edge, with p's colour and attributes: one ellipse, or where that would
//! be thinner than [`MIN_RATIO`] (a mast or a lone tall tree over the street) a stack
//! of ellipses as wide as the spacing, at most [`MAX_PIECES`]. Walls of neighbouring edge samples, s apart,
//! overlap. p's own splat is clipped where its wall stands ([`Wall::clip_of`]), as the
//! triangulation's roof ends at its edge; so is the splat of a sample behind the edge
//! over the same drop, where no wall stands (a tilted splat of a second row reached out
//! over the street as a dark lens tens of metres wide).
//!
//! Why not simpler. An airborne tile's samples lie in rows (the tile's: 0.5 m apart,
//! several metres between samples along a row), so the steepest drop from p often runs
//! nearly along the edge: walls facing it were seen edge-on, as dark specks (on the
//! tile, 43° from the direction of the triangulation's steep faces around p in the
//! median; the centroids', 19°). And an edge test on that drop ("no upper sample nearer
//! q than p") left whole stretches of edge bare. One ellipse [`MIN_RATIO`] thin under a
//! mast's tip was tens of metres wide. Tile FLIP (`cloud_quality --terrain`): 0.2153
//! with those, 0.2036 with the above, 0.2000 with the splats behind the edge clipped.
//! Tried and not kept: vertical walls (0.2057; the slope as twice |pq| out, 0.2036,
//! three times, 0.2065); ellipses hung from the edge's height,
//! cut flat there, reaching below the foot (0.2129: they show over the water, where no
//! street lies in front), or ending at it (0.2089).
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

/// How far out (in spacings) an upper neighbour beside p may lie with p still the edge:
/// the rows of the next scan line along a skew edge lie a little further out.
pub const EDGE_SLACK: f64 = 0.25;

/// How far each ellipse of a stacked wall reaches, in half pitches: its vertical
/// semi-axis over half the distance between centres, so that at a joint the wall is
/// still √(1 − 1/r²) of its width wide.
pub const PIECE_REACH: f32 = std::f32::consts::SQRT_2;

/// The most ellipses in a stack: past it they grow wider than the spacing (at
/// [`MIN_RATIO`]). Samples a few centimetres apart under a 100 m drop called for 287
/// on the tile, a fuzzed cloud for 10¹⁰; 8 draws the tile's FLIP of no limit with 99,076
/// wall splats instead of 128,670 (4: 0.0002 more).
pub const MAX_PIECES: u32 = 8;

/// A wall below a terrain sample's edge, in the unit-scaled coordinates of the search:
/// the slope from the edge down to the drop's foot, one ellipse or, where that would be
/// more than 1 / [`MIN_RATIO`] times as long as wide, a stack of them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wall {
    /// The wall's middle in x–y, at the edge's height.
    pub top: Vec3,
    /// Horizontal, unit, from the upper level toward the lower.
    pub out: Vec3,
    /// How far the foot lies out from the edge, horizontally.
    pub run: f32,
    /// Half the wall's width along the edge: the sampling's spacing there.
    pub half_width: f32,
    /// The drop from the edge to the foot.
    pub drop: f32,
    /// How many ellipses, centred one `pieces`-th of the slope apart.
    pub pieces: u32,
    /// Whether p is the edge, where the wall stands. Behind the edge (a roof's second
    /// row of samples over the same drop) no wall stands, but p's splat still ends
    /// where one would ([`Wall::clip_of`]) rather than reach out over the drop.
    pub edge: bool,
}

impl Wall {
    /// The wall down from `top` by `drop` and out by `run`, `2 half_width` wide.
    fn down(top: Vec3, out: Vec3, run: f32, (half_width, drop): (f32, f32)) -> Wall {
        let length_over_width = 0.5 * run.hypot(drop) / half_width;
        let pieces = (PIECE_REACH * MIN_RATIO as f32 * length_over_width)
            .ceil()
            .min(MAX_PIECES as f32);
        Wall {
            top,
            out,
            run,
            half_width,
            drop,
            // A zero width with no slope gives NaN, which `as` saturates to 0.
            pieces: (pieces as u32).max(1),
            edge: true,
        }
    }

    /// The unit normal: `out`, leant up by the slope.
    pub fn normal(&self) -> Vec3 {
        (self.out * self.drop + Vec3::Z * self.run).normalize()
    }

    /// Each ellipse's semi-axis down the slope: half the slope for one, and for a
    /// stack [`PIECE_REACH`] times half the pitch.
    pub fn reach(&self) -> f32 {
        let half_pitch = 0.5 * self.run.hypot(self.drop) / self.pieces as f32;
        if self.pieces > 1 {
            PIECE_REACH * half_pitch
        } else {
            half_pitch
        }
    }

    /// The wall's surfels in model units (`scale` the search's unit scale), with the
    /// colour and attributes of `upper`, the sample whose edge it stands under.
    pub fn surfels(&self, scale: f32, upper: &Surfel) -> impl Iterator<Item = Surfel> {
        let normal = self.normal();
        let (reach, width) = (self.reach(), self.half_width);
        let down = self.out * self.run - Vec3::Z * self.drop;
        let (axis, major, minor) = if reach >= width {
            (down.normalize(), reach, width)
        } else {
            (self.out.cross(Vec3::Z), width, reach)
        };
        let ratio = ((minor / major) as f64).max(MIN_RATIO);
        let shape = Shape::ellipse(normal.as_dvec3(), axis.as_dvec3(), ratio);
        let shape = shape.pack();
        let edge = self.top - 0.5 * self.out * self.run;
        let standing = if self.edge { self.pieces } else { 0 };
        (0..standing).map(move |j| Surfel {
            position: (edge + down * ((j as f32 + 0.5) / self.pieces as f32)) / scale,
            radius: major / scale,
            normal,
            color: upper.color,
            shape,
            attributes: upper.attributes,
        })
    }

    /// Where the splat of the upper sample at `p` (unit-scaled; its `shape`, unit
    /// normal `n` and major radius `radius`, unit-scaled) ends: the line in its plane
    /// through the wall's middle (`top`, halfway out), perpendicular to the direction
    /// toward it. `None` when that direction lies along the splat's normal.
    pub fn clip_of(&self, p: Vec3, (shape, n, radius): (&Shape, DVec3, f32)) -> Option<Clip> {
        let toward = (self.top - p).truncate().extend(0.0).as_dvec3();
        let d = shape.along_axes(n, toward);
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
    let across = (q - p).truncate().as_dvec2();
    let middle = q.z + 0.5 * drop;
    // In f64: an f32 direction whose squares near f32's least normal is not unit.
    let out = facing_across(p, near, middle).or_else(|| across.try_normalize())?;
    let edge = is_edge(p, near, middle, (out, spacing as f64));
    // From p's edge down to q's height as far out as q lies from p.
    let run = across.length();
    let mid = p.truncate() + (0.5 * run * out).as_vec2();
    let out = out.as_vec2().extend(0.0);
    let wall = Wall::down(mid.extend(p.z), out, run as f32, (spacing, drop));
    Some(Wall { edge, ..wall })
}

/// The unit direction across the edge at `p`, from the centroid in x–y of the
/// neighbours above `middle` (p among them) toward that of those below it (the
/// returns right below p left out: they would pull it back toward p).
fn facing_across(p: Vec3, near: &[Vec3], middle: f32) -> Option<DVec2> {
    let centroid = |level: &dyn Fn(&Vec3) -> bool| {
        let (sum, n) = near
            .iter()
            .filter(|r| level(r))
            .fold((DVec2::ZERO, 0.0), |(s, n), r| {
                (s + r.truncate().as_dvec2(), n + 1.0)
            });
        sum / n
    };
    let upper = centroid(&|r| r.z > middle);
    let lower = centroid(&|r| r.z < middle && (*r - p).truncate() != Vec2::ZERO);
    (lower - upper).try_normalize()
}

/// Whether `p` is the upper level's edge facing `out`: no neighbour above `middle`
/// within a `spacing` of p along the edge lies further out than [`EDGE_SLACK`]
/// spacings.
fn is_edge(p: Vec3, near: &[Vec3], middle: f32, (out, spacing): (DVec2, f64)) -> bool {
    let along = out.perp();
    !near.iter().filter(|r| r.z > middle).any(|r| {
        let d = (*r - p).truncate().as_dvec2();
        d.dot(out) > EDGE_SLACK * spacing && d.dot(along).abs() < spacing
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat roof 10 high on a street (samples 1 apart): every roof sample on the
    /// edge gets a wall down to the street, facing it; no other sample does, but the
    /// roof's samples within reach of the drop end where their walls would stand.
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
        let under: Vec<usize> = walls
            .iter()
            .filter(|(_, w)| w.edge)
            .map(|(k, _)| *k)
            .collect();
        let edge: Vec<usize> = (0..queries.len())
            .filter(|&k| queries[k].x == 19.0)
            .collect();
        assert_eq!(under, edge, "walls under the edge row and nowhere else");
        let behind = walls.iter().filter(|(_, w)| !w.edge);
        assert!(behind.clone().all(|(k, _)| queries[*k].x < 19.0));
        assert!(behind.clone().any(|(k, _)| queries[*k].x == 18.0));
        let roof = Surfel {
            shape: Shape::circle(DVec3::Z).pack(),
            normal: Vec3::Z,
            ..bytemuck::Zeroable::zeroed()
        };
        assert!(
            behind
                .clone()
                .all(|(_, w)| w.surfels(1.0, &roof).next().is_none())
        );
        for (k, w) in walls.iter().filter(|(_, w)| w.edge) {
            let p = queries[*k];
            // Across the edge, within what an uneven neighbourhood of ties turns it.
            assert!(w.out.dot(Vec3::X) > 0.99, "under {p}: {w:?}");
            assert!((w.top.x - 19.5).abs() < 0.01 && w.top.z == 10.0, "{w:?}");
            assert!((w.top.y - p.y).abs() < 0.1 && w.drop == 10.0, "{w:?}");
        }
        let wall_under = |walls: &[(usize, Wall)], k: usize| {
            walls.iter().find(|(j, _)| *j == k).map(|(_, w)| *w)
        };
        // A second return right below an edge sample leaves its wall as it was (but
        // for the neighbour it displaces from the neighbourhood).
        let mut returns = coords.clone();
        returns.push([19.0, 20.0, 4.0]);
        let again = terrain_walls(&returns, &queries);
        let edge_sample = 20 * 40 + 19;
        let (before, after) = (
            wall_under(&walls, edge_sample).expect("a wall"),
            wall_under(&again, edge_sample).expect("a wall"),
        );
        assert!(before.out.dot(after.out) > 0.995, "{before:?} {after:?}");
        assert_eq!((before.drop, before.pieces), (after.drop, after.pieces));
        // The edge sample's splat ends at its wall's foot, half a spacing out (turned
        // as the wall is by the neighbourhood's ties).
        let p = Vec3::new(19.0, 20.0, 10.0);
        let w = wall_under(&walls, edge_sample).expect("a wall under the edge");
        let shape = Shape::ellipse(DVec3::Z, DVec3::X, 1.0);
        let Some(Clip::Line { normal, offset }) = w.clip_of(p, (&shape, DVec3::Z, 2.0)) else {
            panic!("no clip");
        };
        assert!(
            normal.dot(DVec2::X) > 0.99 && (offset - 0.25).abs() < 1e-6,
            "{normal} {offset} {w:?}"
        );
    }

    /// Drops from an edge to a sample 10⁻¹⁹ to 10⁻²¹ away in x (the fuzzer found such):
    /// their squares are at or below f32's least normal; the wall's normal is still
    /// unit.
    #[test]
    fn a_drop_to_a_sample_almost_below_faces_a_unit_way() {
        let p = Vec3::new(0.0, 0.0, 1.0);
        for dx in [1e-19, 3e-20, 1.3e-20, 1e-20, 3e-21] {
            let near = [
                p,
                Vec3::new(dx, 0.0, -9.0),
                Vec3::new(2.0, 0.0, -9.0),
                Vec3::new(0.0, 2.0, 1.0),
                Vec3::new(-2.0, 0.0, 1.0),
                Vec3::new(0.0, -2.0, 1.0),
            ];
            let w = wall_below(p, &near).expect("a wall");
            assert!((w.out.length() - 1.0).abs() < 1e-6, "{dx}: {w:?}");
            assert!((w.normal().length() - 1.0).abs() < 1e-6, "{dx}: {w:?}");
            assert!(w.reach().is_finite() && w.reach() > 0.0, "{dx}: {w:?}");
        }
    }

    /// An edge sampled sparsely along its length: the steepest drop from p runs 71°
    /// off the way across, the wall still faces across (from the upper samples'
    /// centroid toward the lower's), and stands halfway to that drop's foot.
    #[test]
    fn a_wall_faces_across_its_edge_not_along_the_steepest_drop() {
        let p = Vec3::new(0.0, 0.0, 10.0);
        let mut near = vec![p];
        for y in [-4.0, 0.0, 4.0] {
            near.extend([Vec3::new(-1.0, y, 10.0), Vec3::new(2.5, y, 0.0)]);
        }
        near.extend([Vec3::new(0.0, 4.0, 10.0), Vec3::new(0.0, -4.0, 10.0)]);
        near.push(Vec3::new(0.5, 1.5, 0.0));
        let w = wall_below(p, &near).expect("a wall");
        let across = w.out.dot(Vec3::X);
        assert!(across > 15f32.to_radians().cos(), "{w:?}");
        let halfway = 0.5 * Vec2::new(0.5, 1.5).length();
        assert!((w.top.truncate().length() - halfway).abs() < 1e-5, "{w:?}");
    }

    /// A roof edge along an airborne scan's rows (rows 0.5 apart, samples 3 apart
    /// along a row at uneven offsets, the edge at 17° to the rows): the walls line the
    /// whole edge and face across it: their median turn is 7.7°. Walls facing the
    /// steepest drop turn 22°, and so do those the former edge test left ("no roof
    /// sample nearer that drop's foot").
    #[test]
    fn an_edge_along_scan_rows_is_walled_along_its_length() {
        let roof = |x: f32, y: f32| y + 0.3 * x < 30.0;
        let coords: Vec<[f32; 3]> = (0..120 * 20)
            .map(|i| {
                let (row, k) = (i / 20, i % 20);
                let y = 0.5 * row as f32;
                let x = 3.0 * k as f32 + (row * 7 % 11) as f32 * 0.27;
                [x, y, if roof(x, y) { 10.0 } else { 0.0 }]
            })
            .collect();
        let queries: Vec<Vec3> = coords.iter().map(|c| Vec3::from(*c)).collect();
        let walls = terrain_walls(&coords, &queries);
        let across = Vec2::new(0.3, 1.0).normalize();
        let walls: Vec<Wall> = walls
            .into_iter()
            .map(|(_, w)| w)
            .filter(|w| w.edge)
            .collect();
        let mut turned: Vec<f32> = walls
            .iter()
            .map(|w| {
                w.out
                    .truncate()
                    .dot(across)
                    .clamp(-1.0, 1.0)
                    .acos()
                    .to_degrees()
            })
            .collect();
        turned.sort_by(f32::total_cmp);
        assert!(
            turned[turned.len() / 2] < 15.0,
            "median turn {}°",
            turned[turned.len() / 2]
        );
        // Every metre of the edge, away from the tile's ends, has a wall within 2.
        for x in (10..50).map(|m| m as f32) {
            let on_edge = Vec2::new(x, 30.0 - 0.3 * x);
            assert!(
                walls
                    .iter()
                    .any(|w| (w.top.truncate() - on_edge).length() < 2.0),
                "no wall near {on_edge}"
            );
        }
    }

    /// A drop of 10⁶ under samples 10⁻²⁰ apart (the fuzzer's: 10¹⁰ ellipses, 257 GB)
    /// stands on [`MAX_PIECES`] finite ones, and so does a zero width.
    #[test]
    fn a_stack_is_bounded() {
        let top = Vec3::new(0.0, 0.0, 1e6);
        for (half_width, pieces) in [(1e-20, MAX_PIECES), (0.0, MAX_PIECES)] {
            let wall = Wall::down(top, Vec3::X, 0.0, (half_width, 1e6));
            let splats: Vec<Surfel> = wall.surfels(1.0, &bytemuck::Zeroable::zeroed()).collect();
            assert_eq!(splats.len() as u32, pieces, "{wall:?}");
            assert!(
                splats
                    .iter()
                    .all(|s| s.position.is_finite() && s.radius.is_finite())
            );
        }
    }

    /// A wall many times as long as wide (a mast's tip over the street) is a stack of
    /// ellipses no thinner than [`MIN_RATIO`] and as wide as the spacing, in the plane
    /// of the slope from the edge to the foot. Their union covers the wall's middle
    /// line from its edge to its foot, and between the first and last ellipses'
    /// centres at least 0.7 of its width.
    #[test]
    fn a_tall_wall_is_a_stack_as_wide_as_the_spacing() {
        let top = Vec3::new(0.0, 0.0, 40.0);
        let cases = [
            (1.0, 40.0, 0.0),
            (2.0, 10.0, 3.0),
            (1.0, 1.5, 0.2),
            (3.0, 3.5, 1.0),
        ];
        for (half_width, drop, run) in cases {
            let wall = Wall::down(top, Vec3::X, run, (half_width, drop));
            let splats: Vec<Surfel> = wall.surfels(1.0, &bytemuck::Zeroable::zeroed()).collect();
            assert_eq!(splats.len(), wall.pieces as usize);
            let shapes: Vec<Shape> = splats
                .iter()
                .map(|s| s.shape.unpack(s.normal.as_dvec3()))
                .collect();
            for (s, shape) in splats.iter().zip(&shapes) {
                assert!(shape.ratio >= MIN_RATIO - 1e-3, "{wall:?}: {shape:?}");
                let across_edge = shape.axis.y.abs() < 0.5;
                let width = s.radius * if across_edge { shape.ratio as f32 } else { 1.0 };
                assert!(
                    (width - half_width).abs() < 1e-2 * half_width,
                    "{wall:?}: {s:?}"
                );
            }
            // On the slope, `t` of the way down, `y` along the edge.
            let at = |t: f32, y: f32| Vec3::new(run * (t - 0.5), y, top.z - drop * t);
            let covered = |q: Vec3| {
                splats.iter().zip(&shapes).any(|(s, shape)| {
                    let (d, n) = ((q - s.position).as_dvec3(), s.normal.as_dvec3());
                    let [u, v] = shape.along_axes(n, d).to_array();
                    let r = s.radius as f64;
                    d.dot(n).abs() < 1e-4 * r
                        && (u / r).powi(2) + (v / (r * shape.ratio)).powi(2) <= 1.0 + 1e-4
                })
            };
            let n = splats.len() as f32;
            let (first, last) = (0.5 / n, 1.0 - 0.5 / n);
            for i in 0..=20 {
                let t = 0.02 + 0.96 * i as f32 / 20.0;
                assert!(covered(at(t, 0.0)), "{wall:?}: middle at {t} uncovered");
                let t = first + (last - first) * i as f32 / 20.0;
                for y in [-0.7 * half_width, 0.7 * half_width] {
                    assert!(covered(at(t, y)), "{wall:?}: ({t}, {y}) uncovered");
                }
            }
        }
    }
}
