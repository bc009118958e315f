//! The covering ellipse of a cloud's sample among its neighbours (docs/design.md §2): the
//! splat that closes the gaps of the sampling around the point without growing into a
//! blob, however anisotropic the sampling (an RGB-D frame's depth steps, a LiDAR
//! swath's scan lines).
//!
//! With n the unit normal, (t₁, t₂) a tangent frame and o = q − p a neighbour's offset:
//!
//! * **axes**: the *ring* is the nearest distinct neighbour in each of [`SECTORS`] equal
//!   angular sectors of the tangent plane, a stand-in for a mesh's one-ring; the ellipse
//!   takes the principal axes of the ring's second moment Σ o oᵀ (projected): major u,
//!   ratio = √(λ₂/λ₁) clamped to [[`MIN_RATIO`], 1]. A sampling dense along its rows
//!   and sparse across them puts few ring members on the row, so u runs across the rows.
//!   A ring of fewer than [`MIN_RING`] sectors (the neighbourhood is one scan line, with
//!   nothing seen across it) says nothing of the other direction: the splat stays round.
//!   The sectors and distances are taken again in the metric of the last estimate, up
//!   to [`AXIS_ROUNDS`] times, which sharpens the ratio toward the sampling's own; a
//!   ring that repeats the one before has reached it.
//! * **size**: in the ellipse's metric m(o) = √((o·u)² + (o·v / ratio)² + (o·n)²)
//!   (v = n × u; the plain distance when ratio = 1), the *surrounding distance* r_s is
//!   the least m within which the distinct neighbours, taken nearest first, leave no
//!   angular gap (angles in the metric) wider than [`MAX_GAP`]. The major semi-axis is
//!   [`SURROUND_GROWTH`] · r_s. In the metric every triangle that the point makes with two
//!   angularly consecutive surrounding neighbours has a circumradius ≤ r_s (an angle
//!   ≤ 120° between sides ≤ r_s), so the ellipse covers every gap of the sampling (on a
//!   square grid of spacing h: a circle of radius h√2, through the diagonal neighbours).
//! * **scatter**: a neighbourhood that scatters in three dimensions samples no surface
//!   (sparse vegetation, a bush's twigs: its least principal variance more than
//!   [`SCATTER`] times the mean of the other two): the ring's axes are noise there, and
//!   the surrounding distance, stretched by their ratio, ran to several times the
//!   neighbourhood's size. Its point gets the circle a grid of its spacing would,
//!   √2 spacings (counted as capped).
//! * **cap**: a point that no neighbourhood surrounds (a boundary), whose nearest
//!   neighbour lies more than [`MAX_SPACINGS`] times the neighbourhood's spacing away (a
//!   stray sample), or that only an ellipse wider than [`MAX_GAP_SPACINGS`] spacings
//!   surrounds (√(major · minor), so that an anisotropic sampling's long axis is not
//!   held against it: a cluster of returns amid a scan gap or on water) closes no gap of
//!   its sampling; it gets a circle of the distance to its [`BOUNDARY_RANK`]-th distinct
//!   neighbour, capped at [`MAX_SPACINGS`] spacings (counted when the cap cuts it). The
//!   spacing is the median, over the neighbourhood's [`SPACING_MEMBERS`] nearest, of
//!   each member's distance to its second nearest other member: an airborne scanner's
//!   twin returns a centimetre apart would make the nearest one's a tenth of the
//!   sampling's.
//! * **open side**: a boundary's neighbours leave an angular gap wider than
//!   [`MAX_GAP`] at every distance; the middle of their widest gap is where the sampled
//!   surface ends ([`Covering::open`]), and the cloud's splat may be clipped there
//!   (`cloud::boundary_clip`).

mod axes;

use arrayvec::ArrayVec;
use glam::Vec3;

use super::{distance_rank, rank_parts};
use axes::{Columns, Mapped, Metric, axes};

/// Most neighbours a covering looks at (more are ignored): a cloud's neighbourhood
/// ([`crate::surfel::cloud::K`]) fits. The axes' columns and the rankings are held in
/// fixed arrays of this size, set up for every point.
pub const MAX_NEIGHBOURS: usize = 32;
/// Widest angular gap (radians) that the surrounding neighbours may leave: 120°.
pub const MAX_GAP: f32 = 2.0 * std::f32::consts::FRAC_PI_3;
/// Major semi-axis over the surrounding distance.
pub const SURROUND_GROWTH: f32 = std::f32::consts::SQRT_2;
/// Members of a neighbourhood, nearest first, whose spacing the cap takes
/// ([`median_spacing`], quadratic in their number).
pub const SPACING_MEMBERS: usize = 16;
/// Which distinct neighbour sets the radius of a mesh's isolated vertex
/// ([`RadiusRule::Ranked`]).
pub const RADIUS_RANK: usize = 6;
/// Which distinct neighbour sets the radius of a cloud's point that closes no gap. On a
/// boundary its neighbours fill a half-disc, whose 12th lies about 2 spacings out: two
/// facing boundaries then bridge a gap of about 4 spacings, as a triangulation that
/// drops edges over 4 median edges does (the references of docs/point-clouds.md); the 6th left the
/// tile's scan shadows open (holes 0.58 % against 0.47 %).
pub const BOUNDARY_RANK: usize = 12;
/// Largest radius of a point that closes no gap, in neighbourhood spacings.
pub const MAX_SPACINGS: f32 = 4.0;
/// Largest covering ellipse, as the radius √(major · minor) of the circle of its area,
/// in neighbourhood spacings: a point that only a larger one surrounds sits in a gap
/// far wider than its sampling (a cluster of returns amid a scan gap, water): capped.
pub const MAX_GAP_SPACINGS: f32 = 8.0;
/// Least-axis variance over the mean of the other two beyond which a neighbourhood
/// samples no surface ([`samples_no_surface`]).
pub const SCATTER: f64 = 0.2;
/// Angular sectors of the ring.
pub const SECTORS: usize = 6;
/// A ring whose axes differ by less than this ratio is taken as round.
pub const ROUND_ENOUGH: f32 = 0.9;
/// Fewest filled sectors of a ring whose axes are taken (fewer: a line, kept round).
pub const MIN_RING: usize = 5;
/// Most estimates of the axes, each in the metric of the one before.
pub const AXIS_ROUNDS: usize = 3;

/// How a covering is found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RadiusRule {
    /// A cloud's: the covering ellipse, or a capped ranked circle (module doc).
    Surrounding,
    /// A mesh's isolated vertices, which lie among the mesh's own vertices: a circle
    /// through the [`RADIUS_RANK`]-th distinct neighbour.
    Ranked,
}

/// A splat's ellipse in its tangent plane (by default: none, a zero radius).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Covering {
    /// The major semi-axis; 0 when every neighbour coincides with the point.
    pub radius: f32,
    /// The major axis: unit, ⟂ the normal.
    pub axis: Vec3,
    /// Minor over major semi-axis, in [[`MIN_RATIO`], 1].
    pub ratio: f32,
    /// Whether the radius was capped (a boundary or stray point).
    pub capped: bool,
    /// On a boundary (no distance at which the neighbours surround the point): the
    /// unit tangent direction of the middle of their widest angular gap, where the
    /// sampled surface ends. `None` elsewhere.
    pub open: Option<Vec3>,
    /// The neighbourhood's spacing ([`median_spacing`]) that the caps are counted in;
    /// 0 by [`RadiusRule::Ranked`] and where every neighbour coincides with the point.
    pub spacing: f32,
}

/// The covering of the point `p` of unit `normal` among its neighbours `near` (sorted
/// nearest first, `p` and its duplicates included; the first [`MAX_NEIGHBOURS`]) by
/// `rule` (see the module doc).
pub fn covering(p: Vec3, normal: Vec3, near: &[Vec3], rule: RadiusRule) -> Covering {
    let offsets: ArrayVec<Vec3, MAX_NEIGHBOURS> = near
        .iter()
        .map(|q| *q - p)
        .filter(|o| o.length_squared() > 0.0)
        .take(MAX_NEIGHBOURS)
        .collect();
    let circle = Metric::circle(normal);
    let round = |radius: f32, capped: bool, spacing: f32| Covering {
        radius,
        axis: circle.u,
        ratio: 1.0,
        capped,
        open: None,
        spacing,
    };
    let Some(nearest) = offsets.first().map(|o| o.length()) else {
        return round(0.0, false, 0.0);
    };
    let rank = |k: usize| offsets[k.min(offsets.len()) - 1].length();
    if rule == RadiusRule::Ranked {
        return round(rank(RADIUS_RANK), false, 0.0);
    }
    let ranked = rank(BOUNDARY_RANK);
    let spacing = median_spacing(near);
    if samples_no_surface(&offsets) {
        return round(SURROUND_GROWTH * spacing, true, spacing);
    }
    let cap = MAX_SPACINGS * spacing;
    let columns = Columns::of(&offsets);
    let (metric, mapped) = axes(&offsets, &columns, circle);
    let closes_a_gap =
        |r: &f32| SURROUND_GROWTH * r * metric.ratio.sqrt() <= MAX_GAP_SPACINGS * spacing;
    match (nearest <= cap).then(|| surrounding_distance(&mapped)) {
        Some(Ok(r)) if closes_a_gap(&r) => Covering {
            radius: SURROUND_GROWTH * r,
            axis: metric.u,
            ratio: metric.ratio,
            capped: false,
            open: None,
            spacing,
        },
        Some(Err((start, width))) => Covering {
            open: Some(metric.direction(start + 0.5 * width)),
            ..round(ranked.min(cap), ranked > cap, spacing)
        },
        _ => round(ranked.min(cap), ranked > cap, spacing),
    }
}

/// Whether the neighbourhood `offsets` scatters in three dimensions rather than lying
/// on a surface: the variance along its least principal axis is more than
/// [`SCATTER`] times the mean of the other two.
///
/// With λ₁ + λ₂ = trace − λ₀ and s = SCATTER / 2: λ₀ > s (trace − λ₀) ⇔ λ₀ > trace ·
/// s / (1 + s), a bound on the least eigenvalue ([`super::pca::eigenvalues_exceed`]).
pub fn samples_no_surface(offsets: &[Vec3]) -> bool {
    if offsets.len() < 3 {
        return false;
    }
    let Some(cov) = super::pca::scatter_matrix(offsets.iter().copied()) else {
        return false;
    };
    let trace = cov.x_axis.x + cov.y_axis.y + cov.z_axis.z;
    let s = 0.5 * SCATTER;
    super::pca::eigenvalues_exceed(cov, trace * s / (1.0 + s))
}

/// The least metric distance of the offsets (at least one; `lanes`, mapped by the
/// ellipse's metric) within which, taken nearest first, they leave no angular gap
/// wider than [`MAX_GAP`]; when even all of them do, their widest gap (its start,
/// counter-clockwise, and width; radians in the metric).
///
/// The offsets are taken nearest first by their ranks ([`distance_rank`]): each next
/// one is the least rank left, a lane-wise minimum over [`MAX_NEIGHBOURS`] ranks, its
/// place then set to the largest. Most neighbourhoods close within their 4 to 6
/// nearest (all of the Lucy-size cloud's that close; 88 % of the knot's vertices as a
/// cloud), where a sort of all of them was mispredicted about 7 times a point. Neither
/// result depends on how equal distances are ordered: the ring closes at the same
/// distance whichever of them comes first, and the widest gap is that of the same
/// angles.
fn surrounding_distance(lanes: &Mapped) -> Result<f32, (f32, f32)> {
    let mut ranks = [u64::MAX; MAX_NEIGHBOURS];
    for (k, rank) in ranks.iter_mut().enumerate().take(lanes.len) {
        *rank = distance_rank(lanes.get(k).0, k);
    }
    let mut gaps = Gaps::default();
    for _ in 0..lanes.len {
        let least = ranks.iter().fold(u64::MAX, |a, &b| a.min(b));
        let k = rank_parts(least).1;
        ranks[k] = u64::MAX;
        let (d2, xy) = lanes.get(k);
        if let Some(r) = gaps.add(d2, angle(xy.x, xy.y)) {
            return Ok(r);
        }
    }
    Err(gaps.widest())
}

/// The sorted angles of the neighbours taken so far, and their widest gap (its start,
/// counter-clockwise, and width) once three are in: an angle outside it leaves it
/// whole, so only one inside it can close the ring.
#[derive(Default)]
struct Gaps {
    angles: ArrayVec<f32, MAX_NEIGHBOURS>,
    widest: Option<(f32, f32)>,
}

impl Gaps {
    /// Takes the neighbour at squared metric distance `d2` and `angle` ([`angle`]); its
    /// distance when the neighbours taken leave no gap wider than [`MAX_GAP`].
    fn add(&mut self, d2: f32, angle: f32) -> Option<f32> {
        let at = self.angles.partition_point(|a| *a < angle);
        self.angles.insert(at, angle);
        let inside = self
            .widest
            .is_none_or(|(start, width)| turn(angle - start) < width);
        if self.angles.len() >= 3 && inside {
            let gap = widest_gap(&self.angles);
            if gap.1 <= MAX_GAP {
                return Some(d2.sqrt());
            }
            self.widest = Some(gap);
        }
        None
    }

    /// The widest gap of every neighbour taken (at least one).
    fn widest(&self) -> (f32, f32) {
        self.widest.unwrap_or_else(|| widest_gap(&self.angles))
    }
}

/// `x` in [0, 2π) for `x` in [−2π, 2π]: x mod 2π, as `rem_euclid` gives it (a libm
/// call, whose branches were mispredicted), up to the sign of a zero.
fn turn(x: f32) -> f32 {
    use std::f32::consts::TAU;
    let below = f32::from(u8::from(x < 0.0));
    let past = f32::from(u8::from(x >= TAU));
    x + TAU * (below - past)
}

/// The angle of (`x`, `y`) from the x axis, in [−π, π], within 10⁻⁵ rad (a polynomial
/// for atan on [0, 1], Abramowitz and Stegun 4.4.49 form): libm's `atan2` was a third of
/// the covering's time. Without branches: the directions' signs are a coin's toss.
fn angle(x: f32, y: f32) -> f32 {
    use std::f32::consts::{FRAC_PI_2, PI};
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = (ax.min(ay), ax.max(ay));
    let t = if hi == 0.0 { 0.0 } else { lo / hi };
    let t2 = t * t;
    let a = t
        * (0.999_866
            + t2 * (-0.330_299_5 + t2 * (0.180_141 + t2 * (-0.085_133 + t2 * 0.020_835_1))));
    let a = if ay > ax { FRAC_PI_2 - a } else { a };
    let a = if x < 0.0 { PI - a } else { a };
    // The sign bit flipped where y < 0: −a.
    f32::from_bits(a.to_bits() ^ (u32::from(y < 0.0) << 31))
}

/// The widest gap between consecutive sorted angles (radians in (−π, π]), around the
/// circle: the angle it starts at (counter-clockwise) and its width.
fn widest_gap(sorted: &[f32]) -> (f32, f32) {
    let last = sorted[sorted.len() - 1];
    let wrap = (last, sorted[0] + std::f32::consts::TAU - last);
    sorted
        .windows(2)
        .map(|w| (w[0], w[1] - w[0]))
        .fold(wrap, |a, b| if b.1 > a.1 { b } else { a })
}

/// The median, over `points` (the first [`SPACING_MEMBERS`]), of each one's distance to
/// its second nearest other distinct member (its nearest when it has one other): the
/// sampling's spacing there, which neither a stray sample beside it nor twin returns
/// change.
fn median_spacing(points: &[Vec3]) -> f32 {
    let points = &points[..points.len().min(SPACING_MEMBERS)];
    // Coordinates in columns, padded with far points: each member is a lane, and a
    // pass over the others keeps every lane's two least squared distances at once
    // (vectorised across the lanes; a reduction along each member's own row is a
    // chain of dependent minima that the CPU waits out).
    let mut columns = [[f32::INFINITY; SPACING_MEMBERS]; 3];
    for (j, q) in points.iter().enumerate() {
        for (axis, column) in columns.iter_mut().enumerate() {
            column[j] = q[axis];
        }
    }
    let [xs, ys, zs] = &columns;
    let mut least = [f32::INFINITY; SPACING_MEMBERS];
    let mut second = [f32::INFINITY; SPACING_MEMBERS];
    for q in points {
        for lane in 0..SPACING_MEMBERS {
            let d2 = (q.x - xs[lane]).powi(2) + (q.y - ys[lane]).powi(2) + (q.z - zs[lane]).powi(2);
            // The member itself (and a coinciding one) is at 0: not counted.
            let d = if d2 > 0.0 { d2 } else { f32::INFINITY };
            let above = if d > least[lane] { d } else { least[lane] };
            second[lane] = if above < second[lane] {
                above
            } else {
                second[lane]
            };
            least[lane] = if d < least[lane] { d } else { least[lane] };
        }
    }
    // The second least counts a tie with the least: twin returns give their distance.
    // Positive finite distances order as their bits do; the infinite ones (no other
    // member, or past the last) count as the largest integer.
    let nearest: [u32; SPACING_MEMBERS] = std::array::from_fn(|lane| {
        let d = if second[lane].is_finite() {
            second[lane]
        } else {
            least[lane]
        };
        if d.is_finite() { d.to_bits() } else { u32::MAX }
    });
    let count = nearest.iter().filter(|&&d| d != u32::MAX).count();
    if count == 0 {
        return 0.0;
    }
    f32::from_bits(at_place(&nearest, count / 2)).sqrt()
}

/// The value at place `at` of `values` sorted ascending, without a branch on them (a
/// sort of 16 was mispredicted about 14 times a point): each value's place is the
/// count of those less than it, and of its equals, those before it; exactly one value
/// has each place.
fn at_place(values: &[u32; SPACING_MEMBERS], at: usize) -> u32 {
    let mut place = [0u32; SPACING_MEMBERS];
    for (j, &v) in values.iter().enumerate() {
        for (i, place) in place.iter_mut().enumerate() {
            let before = (v < values[i]) | ((v == values[i]) & (j < i));
            *place += u32::from(before);
        }
    }
    let at = at as u32;
    (place.iter().zip(values))
        .map(|(&p, &v)| if p == at { v } else { u32::MAX })
        .fold(u32::MAX, u32::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(
        cols: std::ops::RangeInclusive<i32>,
        rows: std::ops::RangeInclusive<i32>,
        row_gap: f32,
    ) -> Vec<Vec3> {
        let mut near = Vec::new();
        for row in rows {
            for col in cols.clone() {
                near.push(Vec3::new(col as f32, row_gap * row as f32, 0.0));
            }
        }
        near.sort_by(|a, b| a.length().total_cmp(&b.length()));
        near
    }

    /// Whether the ellipse of `c` at the origin, normal +z, holds the in-plane point `q`.
    fn holds(c: &Covering, q: Vec3) -> bool {
        let v = Vec3::Z.cross(c.axis);
        let (x, y) = (q.dot(c.axis) / c.radius, q.dot(v) / (c.radius * c.ratio));
        x * x + y * y <= 1.0 + 1e-5
    }

    #[test]
    fn a_square_grid_point_gets_the_circle_through_its_diagonal_neighbours() {
        let c = covering(
            Vec3::ZERO,
            Vec3::Z,
            &grid(-1..=1, -1..=1, 1.0),
            RadiusRule::Surrounding,
        );
        assert!((c.radius - std::f32::consts::SQRT_2).abs() < 1e-5, "{c:?}");
        assert!(c.ratio > 0.99 && !c.capped, "{c:?}");
    }

    #[test]
    fn rows_sparser_than_columns_get_an_ellipse_across_the_rows() {
        // Columns 1 apart, rows 4 apart: the 25 nearest neighbours (within distance 5)
        // are mostly the point's own row.
        let near = grid(-6..=6, -1..=1, 4.0);
        let c = covering(Vec3::ZERO, Vec3::Z, &near[..25], RadiusRule::Surrounding);
        assert!(
            c.axis.y.abs() > 0.99 && !c.capped,
            "major axis across the rows: {c:?}"
        );
        assert!(
            holds(&c, Vec3::new(0.0, 4.0, 0.0)),
            "reaches the next row: {c:?}"
        );
        // Smaller than the circle that the same rule draws without the axes.
        let area = c.radius * c.radius * c.ratio;
        assert!(area < 0.5 * 2.0 * 16.0, "{c:?}");
    }

    #[test]
    fn a_neighbourhood_on_its_own_row_stays_round() {
        // The 16 nearest: the row and the next rows' nearest few, in 4 sectors of 6.
        let near = grid(-6..=6, -1..=1, 4.0);
        let c = covering(Vec3::ZERO, Vec3::Z, &near[..16], RadiusRule::Surrounding);
        assert!(c.ratio == 1.0 && c.radius >= 4.0, "{c:?}");
    }

    #[test]
    fn a_stray_sample_is_capped_at_four_spacings() {
        let mut near = vec![Vec3::ZERO];
        for x in 0..4 {
            for y in 0..4 {
                near.push(Vec3::new(100.0 + x as f32, y as f32, 0.0));
            }
        }
        let c = covering(Vec3::ZERO, Vec3::Z, &near, RadiusRule::Surrounding);
        assert!(c.capped && c.radius <= 4.0 && c.ratio == 1.0, "{c:?}");
    }

    #[test]
    fn a_cluster_amid_a_wide_gap_keeps_a_circle_of_its_spacing() {
        // Nine returns 0.1 apart at the origin, the nearest surface 10 away all round:
        // the cluster's corner is surrounded, but only by an ellipse a hundred spacings
        // wide.
        let mut near = grid(-1..=1, -1..=1, 1.0)
            .into_iter()
            .map(|q| q * 0.1)
            .collect::<Vec<_>>();
        for k in 0..12 {
            let t = k as f32 * std::f32::consts::TAU / 12.0;
            near.push(Vec3::new(t.cos(), t.sin(), 0.0) * 10.0);
        }
        let corner = Vec3::new(0.1, 0.1, 0.0);
        near.sort_by(|a, b| a.distance(corner).total_cmp(&b.distance(corner)));
        let c = covering(corner, Vec3::Z, &near, RadiusRule::Surrounding);
        assert!(c.radius <= 0.4 + 1e-6 && c.ratio == 1.0, "{c:?}");
    }

    #[test]
    fn twin_returns_do_not_shrink_the_spacing() {
        // A unit grid of points each doubled 0.01 above itself (two returns per pulse).
        let mut near = Vec::new();
        for q in grid(-2..=2, -2..=2, 1.0) {
            near.extend([q, q + Vec3::Z * 0.01]);
        }
        assert_eq!(median_spacing(&near), 1.0);
    }

    #[test]
    fn a_place_among_values_is_that_of_their_sort() {
        // Few distinct values (ties), in every order a multiplier makes, some padded
        // with the largest integer.
        for seed in 1..200u32 {
            let values: [u32; SPACING_MEMBERS] = std::array::from_fn(|k| {
                let padded = seed % 2 == 1 && k as u32 % 4 == seed % 4;
                if padded {
                    u32::MAX
                } else {
                    (k as u32 * seed + seed / 3) % 5 * 7
                }
            });
            let mut sorted = values;
            sorted.sort_unstable();
            for (at, &value) in sorted.iter().enumerate() {
                assert_eq!(at_place(&values, at), value, "{values:?} at {at}");
            }
        }
    }

    #[test]
    fn the_spacing_is_the_median_of_each_member_s_second_nearest_distinct_distance() {
        // Against the definition, row by row: members on a coarse lattice (ties),
        // with coinciding pairs, in neighbourhoods of 1 to 20 members (proptest's seeded
        // generator).
        use proptest::prelude::Rng;
        let mut rng = proptest::test_runner::TestRng::deterministic_rng(
            proptest::test_runner::RngAlgorithm::ChaCha,
        );
        let reference = |points: &[Vec3]| -> f32 {
            let points = &points[..points.len().min(SPACING_MEMBERS)];
            let mut nearest: Vec<f32> = points
                .iter()
                .filter_map(|a| {
                    let mut d: Vec<f32> = (points.iter())
                        .map(|q| (q.x - a.x).powi(2) + (q.y - a.y).powi(2) + (q.z - a.z).powi(2))
                        .filter(|&d2| d2 > 0.0)
                        .collect();
                    d.sort_by(f32::total_cmp);
                    d.get(1).or(d.first()).copied()
                })
                .collect();
            if nearest.is_empty() {
                return 0.0;
            }
            let mid = nearest.len() / 2;
            nearest.select_nth_unstable_by(mid, f32::total_cmp).1.sqrt()
        };
        for n in 1..=20 {
            for _ in 0..50 {
                let mut points: Vec<Vec3> = (0..n)
                    .map(|_| {
                        Vec3::new(
                            rng.random_range(0..4) as f32,
                            rng.random_range(0..3) as f32,
                            0.0,
                        )
                    })
                    .collect();
                points[0] = points[n - 1];
                assert_eq!(median_spacing(&points), reference(&points), "{points:?}");
            }
        }
    }

    #[test]
    fn a_boundary_point_keeps_a_circle_of_its_neighbours_spacing() {
        // A half-plane: every neighbour lies at x ≥ 0.
        let near: Vec<Vec3> = grid(0..=3, -2..=2, 1.0);
        let c = covering(Vec3::ZERO, Vec3::Z, &near[..16], RadiusRule::Surrounding);
        assert!(c.radius > 1.0 && c.radius <= 4.0 && c.ratio == 1.0, "{c:?}");
        // Its sampling ends toward −x, the middle of the neighbours' 180° gap.
        let open = c.open.expect("a boundary is open");
        assert!(open.dot(-Vec3::X) > 0.999, "{c:?}");
        // A point inside the same grid is surrounded: nothing open.
        let p = Vec3::new(2.0, 0.0, 0.0);
        let mut around = grid(0..=4, -2..=2, 1.0);
        around.sort_by(|a, b| a.distance(p).total_cmp(&b.distance(p)));
        let inner = covering(p, Vec3::Z, &around, RadiusRule::Surrounding);
        assert!(inner.open.is_none() && !inner.capped, "{inner:?}");
    }

    #[test]
    fn a_turn_is_the_euclidean_remainder() {
        use std::f32::consts::{PI, TAU};
        for k in -2000..=2000 {
            let x = k as f32 * (TAU / 2000.0);
            assert_eq!(turn(x), x.rem_euclid(TAU) + 0.0, "{x}");
        }
        for x in [-TAU, -PI - PI, PI - -PI, TAU, -0.0, 1e-9, -1e-9] {
            assert_eq!(turn(x), x.rem_euclid(TAU) + 0.0, "{x}");
        }
    }

    #[test]
    fn the_fast_angle_is_atan2() {
        for k in 0..3600 {
            let t = k as f32 * 0.1f32.to_radians() - std::f32::consts::PI;
            for r in [1e-3f32, 1.0, 7e4] {
                let xy = glam::Vec2::new(t.cos(), t.sin()) * r;
                let a = angle(xy.x, xy.y);
                assert!((a - xy.y.atan2(xy.x)).abs() < 2e-5, "{t}: {a}");
            }
        }
        assert_eq!(angle(0.0, 0.0), 0.0);
        assert_eq!(angle(-0.0, -0.0), 0.0);
    }

    #[test]
    fn coinciding_neighbours_give_no_radius() {
        let c = covering(Vec3::ONE, Vec3::Z, &[Vec3::ONE; 5], RadiusRule::Surrounding);
        assert_eq!(c.radius, 0.0);
    }
}
