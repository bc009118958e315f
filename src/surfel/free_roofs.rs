//! Tops that stand free of the ground: a slab that no sample shows a wall under, such as
//! a carport's roof on its posts, or a bridge deck in a file without classes; and lone
//! returns over the ground, on a trunk or a post.
//!
//! A TIN joins a roof's outline to the street below it with a wall, and a wall is what
//! a building has. The scanner sees part of a building's walls (the sides that face a
//! strip, at the scan angle there): samples between its top and the ground. Where no
//! sample stands there, none says that a wall is there: the pulses that passed the
//! roof's edges reached the ground beside it, or none looked at its sides. Such a top
//! is drawn as a bridge deck is ([`super::layers`]): a TIN of its own, the ground's
//! running on under it.
//!
//! In the samples' TIN (lengths in s, its median horizontal edge):
//! - an edge **drops** where its ends lie more than [`DROP_SPACINGS`] apart in height;
//! - a **top** is a set of samples that edges which do not drop join, with no drop from
//!   it up to a higher sample, at least one down, and none of its samples on the TIN's
//!   border (a plateau at a tile's edge, or a piece's, may rise beyond it), nor in an
//!   out-of-core piece's own samples and its halo both (see below);
//! - a top is a **slab** where [`ON_PLANE_SHARE`] of its samples lie within
//!   [`PLANAR_SPACINGS`] of the plane that fits them: a deck, a flat roof; not a
//!   pitched roof, a crown, a roof with structures on it;
//! - a sample **stands** under a top where an edge drops from the top to it and another
//!   from it further down: a wall's, a post's, a lower roof's;
//! - a top is **walled** where the samples standing under it, joined where they lie
//!   within [`JOIN_SPACINGS`] in x–y, make a run at least [`WALL_SPACINGS`] long. A
//!   post is a sample or two; a wall that faces a strip is sampled along its length.
//!
//! A slab that is not walled stands free. On the simulated scan (s = 0.5 m) that finds
//! the carport's roof (99.4 % of its samples on its plane; its posts' two samples make
//! no run) and, without classes, the bridge deck (99.2 %); its six buildings are
//! walled or pitched. On terrain_utm (s = 2.4 m) it finds four flat roofs of 23–63
//! samples that no pulse saw a wall of; autzen_trim's roofs are all walled or rough.
//!
//! An out-of-core piece sees a top that crosses its border only as far as its halo
//! reaches, and the piece across the border sees the rest of it that way. Were each to
//! judge its part, one could hold a roof free while the other joins it to the ground,
//! and neither would draw the TIN's triangles between them: a hole in the ground at
//! the roof's foot. So a top with both own and halo samples is held bordered, in
//! both pieces alike: the TIN joins it, as it joins a roof at the tile's edge.
//!
//! A top that stands and holds no triangle of the TIN of its own is **lone**, where no
//! drop from it lands on a sample standing over a further drop (a wall's samples stand
//! one under another, each its own top between drops): a trunk's or a post's return
//! or two, a wire's row. It is no surface, and a TIN would hang a tent from it to the
//! ground; it is drawn as vegetation is. On the simulated scan without classes that is
//! 7 of the 14 trunk returns that looked like ground; on terrain_utm 1,802 samples, on
//! autzen_trim 262, at the trees.

use std::collections::HashMap;

use glam::{DMat3, DVec3, Vec2, Vec3};
use rayon::prelude::*;

use super::sets::Sets;
use crate::io::delaunay::Unheld;
use crate::io::parallel;
use crate::io::triangulate::short_or_kept;

/// Height between an edge's ends, in spacings, beyond which it drops: 0.75 m at the
/// simulated scan's 0.5 m, a step no street or lawn takes between neighbours; the 1 m
/// step at the deck's end drops.
pub const DROP_SPACINGS: f32 = 1.5;

/// Height over a top's plane, in spacings, within which a sample lies on it: 5 cm at
/// 0.5 m, 2.5 times the simulated scan's range noise.
pub const PLANAR_SPACINGS: f32 = 0.1;

/// Share of a top's samples on its plane that makes it a slab. A post's sample or two
/// under a carport's roof lie off it, and so does a pitched roof's half.
pub const ON_PLANE_SHARE: f32 = 0.9;

/// Least samples of a slab. A plane fits three exactly, and a top of a few samples (a
/// car, a shed, a chimney) shows nothing of its sides; 16 make a slab 2 m square at
/// 0.5 m. terrain_utm had 80 tops of 3–15 samples on their planes.
pub const SLAB_SAMPLES: u32 = 16;

/// Two samples standing under a top this many spacings apart or less (in x–y) belong
/// to one run.
pub const JOIN_SPACINGS: f32 = 2.5;

/// Least length of a run of standing samples that makes a wall, in spacings: 2 m at
/// 0.5 m.
pub const WALL_SPACINGS: f32 = 4.0;

/// What a sample of the TIN stands on, by its top (the module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Standing {
    /// Ground, a walled or pitched roof, a wall: what the TIN keeps.
    Joined,
    /// A slab that stands free: drawn as a deck.
    Slab,
    /// A top that holds no triangle of its own: drawn as vegetation is.
    Lone,
}

/// What each of `positions` (the samples that one TIN holds: neither vegetation nor
/// deck; the first `own` the piece's own, the rest its halo) stands on (the module
/// doc), from `delaunay`, their Delaunay triangulation in x–y
/// ([`delaunay_xy`](crate::io::delaunay::delaunay_xy), long triangles kept).
pub fn free_standing(positions: &[Vec3], delaunay: &[[u32; 3]], own: usize) -> Vec<Standing> {
    let kept = short_or_kept(positions, delaunay, |_, _| false);
    let triangles: Vec<[u32; 3]> = (delaunay.iter().zip(&kept))
        .filter_map(|(t, &k)| k.then_some(*t))
        .collect();
    drop(kept);
    let (edges, border) = tin_edges(positions.len(), &triangles);
    let Some(spacing) = median_length(positions, &edges) else {
        return vec![Standing::Joined; positions.len()];
    };
    let fall = DROP_SPACINGS * spacing;
    let (down, level): (Vec<Edge>, Vec<Edge>) = (edges.iter())
        .map(|&(a, b)| {
            if positions[a as usize].z >= positions[b as usize].z {
                (a, b)
            } else {
                (b, a)
            }
        })
        .partition(|&(hi, lo)| positions[hi as usize].z - positions[lo as usize].z > fall);
    drop(edges);
    let (top, firsts) = tops_joined(positions, (&level, delaunay));
    drop(level);
    let top = |k: u32| top[k as usize] as usize;
    let mut tops = held_tops(positions, (&top, &firsts), PLANAR_SPACINGS * spacing);
    let mut above_a_drop = vec![false; positions.len()];
    for &(hi, lo) in &down {
        above_a_drop[hi as usize] = true;
        tops[top(hi)].drops = true;
        tops[top(lo)].rises = true;
    }
    for &(hi, lo) in &down {
        tops[top(hi)].steps |= above_a_drop[lo as usize];
    }
    for &(a, b) in &border {
        tops[top(a)].bordered = true;
        tops[top(b)].bordered = true;
    }
    let mut sides = vec![[false; 2]; tops.len()];
    for k in 0..positions.len() {
        sides[top(k as u32)][(k >= own) as usize] = true;
    }
    for (top, sides) in tops.iter_mut().zip(sides) {
        top.bordered |= sides == [true, true];
    }
    for t in &triangles {
        let [a, b, c] = t.map(top);
        if a == b && b == c {
            tops[a].surface = true;
        }
    }
    // Only the tops that would stand free unwalled are looked at.
    let standing: Vec<(usize, usize)> = (down.iter())
        .filter(|&&(hi, lo)| above_a_drop[lo as usize] && top(lo) != top(hi))
        .filter(|&&(hi, _)| tops[top(hi)].stands_free())
        .map(|&(hi, lo)| (top(hi), lo as usize))
        .collect();
    for t in walled_tops(positions, &standing, spacing) {
        tops[t].walled = true;
    }
    (0..positions.len() as u32)
        .map(|k| tops[top(k)].standing())
        .collect()
}

/// Each sample's top (numbered in the order of their least samples) and each top's
/// least sample: the sets that the `level` edges join, with the samples that share an
/// x–y joined. Of those `delaunay` holds at most one, so each such group has a sample
/// that no triangle holds: every sample is looked up among those alone (on a city
/// slice of 20 M samples, sorting all of them by x–y took 0.9 s of the 1.6 s here).
fn tops_joined(
    positions: &[Vec3],
    (level, delaunay): (&[Edge], &[[u32; 3]]),
) -> (Vec<u32>, Vec<u32>) {
    let sets = Sets::new(positions.len());
    (level.par_iter()).for_each(|&(a, b)| sets.join(a as usize, b as usize));
    // The x–y's bits as they are: −0 and +0 apart.
    let xy = |p: Vec3| ((p.x.to_bits() as u64) << 32) | p.y.to_bits() as u64;
    let unheld = Unheld::of(positions, delaunay, xy);
    if !unheld.is_empty() {
        (0..positions.len()).into_par_iter().for_each(|k| {
            if let Some(twin) = unheld.twin(xy(positions[k])) {
                sets.join(k, twin as usize);
            }
        });
    }
    sets.numbered()
}

/// The tops (each sample's `top` and each top's first sample), their samples held and
/// counted on their planes within `planar`.
fn held_tops(
    positions: &[Vec3],
    (top, firsts): (&impl Fn(u32) -> usize, &[u32]),
    planar: f32,
) -> Vec<Top> {
    let mut tops = vec![Top::default(); firsts.len()];
    let from_first =
        |k: u32| (positions[k as usize] - positions[firsts[top(k)] as usize]).as_dvec3();
    for k in 0..positions.len() as u32 {
        tops[top(k)].hold(from_first(k));
    }
    let planes: Vec<Option<DVec3>> = tops.iter().map(Top::plane).collect();
    for k in 0..positions.len() as u32 {
        let d = from_first(k);
        let off = |f: DVec3| (d.z - f.dot(DVec3::new(d.x, d.y, 1.0))).abs();
        if planes[top(k)].is_some_and(|f| off(f) <= planar as f64) {
            tops[top(k)].on_plane += 1;
        }
    }
    tops
}

/// What a top holds: its samples' moments about its first one (for the plane that
/// fits them), how many lie on that plane, and its drops.
#[derive(Clone, Copy, Default)]
struct Top {
    /// Σ (x, y, 1) ⊗ (x, y, 1) and Σ (x, y, 1)·z, in f64.
    xx: DMat3,
    xz: DVec3,
    samples: u32,
    on_plane: u32,
    drops: bool,
    rises: bool,
    /// Whether a sample of it lies on the TIN's border, where what lies beyond is not
    /// known.
    bordered: bool,
    /// Whether a triangle of the TIN has its three corners in it.
    surface: bool,
    /// Whether a drop from it lands on a sample over a further drop, as a wall's
    /// samples stand one under another.
    steps: bool,
    walled: bool,
}

impl Top {
    /// Holds a sample `d` from the top's first.
    fn hold(&mut self, d: DVec3) {
        let x = DVec3::new(d.x, d.y, 1.0);
        self.xx += DMat3::from_cols(x * x.x, x * x.y, x);
        self.xz += x * d.z;
        self.samples += 1;
    }

    /// The plane (a, b, c) that fits the samples least squares, z = a x + b y + c from
    /// the first; None where their x–y lie on a line.
    fn plane(&self) -> Option<DVec3> {
        let scale = self.xx.x_axis.x * self.xx.y_axis.y * self.xx.z_axis.z;
        (self.xx.determinant().abs() > 1e-9 * scale).then(|| self.xx.inverse() * self.xz)
    }

    /// Whether it lies inside the TIN's border and drops all round.
    fn stands(&self) -> bool {
        self.drops && !self.rises && !self.bordered
    }

    /// A top of [`SLAB_SAMPLES`] or more that stands, shows no wall, and has
    /// [`ON_PLANE_SHARE`] of its samples on its plane.
    fn stands_free(&self) -> bool {
        self.stands()
            && self.samples >= SLAB_SAMPLES
            && !self.walled
            && self.on_plane as f32 >= ON_PLANE_SHARE * self.samples as f32
    }

    fn standing(&self) -> Standing {
        if self.stands_free() {
            Standing::Slab
        } else if self.stands() && !self.surface && !self.steps {
            Standing::Lone
        } else {
            Standing::Joined
        }
    }
}

/// A TIN edge by its ends, the lesser first.
type Edge = (u32, u32);

/// The edges of the samples' TIN (`triangles`, long ones dropped, over `vertex_count`
/// samples), each once, lesser end first, in order; and those of its border (of one
/// triangle only: its hull, and around the holes where it left long triangles out).
/// Each triangle's edges are grouped under their lesser ends ([`parallel::grouped`]):
/// a vertex's row lists its greater neighbours, each once per triangle holding the
/// edge, and it sorts its own row, in parallel: a border edge's end appears once.
fn tin_edges(vertex_count: usize, triangles: &[[u32; 3]]) -> (Vec<Edge>, Vec<Edge>) {
    let flat = triangles.as_flattened();
    // Corner c's edge runs to the next corner of its triangle.
    let ends = |c: usize| (flat[c], flat[c - c % 3 + (c + 1) % 3]);
    let (start, greater) = parallel::grouped(
        (vertex_count, flat.len()),
        |c| ends(c).0.min(ends(c).1),
        |c| ends(c).0.max(ends(c).1),
    );
    let chunks: Vec<(Vec<Edge>, Vec<Edge>)> = (0..vertex_count)
        .into_par_iter()
        .chunks(1 << 12)
        .map(|vertices| {
            let (mut all, mut border, mut row) = (Vec::new(), Vec::new(), Vec::new());
            for v in vertices {
                row.clear();
                row.extend_from_slice(&greater[start[v] as usize..start[v + 1] as usize]);
                row.sort_unstable();
                for run in row.chunk_by(|a, b| a == b) {
                    all.push((v as u32, run[0]));
                    if run.len() == 1 {
                        border.push((v as u32, run[0]));
                    }
                }
            }
            (all, border)
        })
        .collect();
    let (all, border): (Vec<Vec<Edge>>, Vec<Vec<Edge>>) = chunks.into_iter().unzip();
    (parallel::concat(&all), parallel::concat(&border))
}

/// The median horizontal length of `edges`; None where there are none.
fn median_length(positions: &[Vec3], edges: &[Edge]) -> Option<f32> {
    let length = |&(a, b): &Edge| {
        (positions[a as usize].truncate() - positions[b as usize].truncate()).length()
    };
    let mut lengths: Vec<f32> = edges.par_iter().map(length).collect();
    let mid = lengths.len() / 2;
    (!lengths.is_empty()).then(|| *lengths.select_nth_unstable_by(mid, f32::total_cmp).1)
}

/// The tops among `standing` (each a top and a sample standing under it) whose
/// standing samples make a run of [`WALL_SPACINGS`] or more: the samples are joined
/// through a hash of x–y cells [`JOIN_SPACINGS`] wide, each to those in its own and the
/// eight cells around.
fn walled_tops(positions: &[Vec3], standing: &[(usize, usize)], spacing: f32) -> Vec<usize> {
    let mut standing = standing.to_vec();
    standing.sort_unstable();
    standing.dedup();
    let reach = JOIN_SPACINGS * spacing;
    let xy = |k: usize| positions[standing[k].1].truncate();
    // A sample's cell, with its top: runs stay under one top.
    let cell = |k: usize| {
        let p = xy(k) / reach;
        (standing[k].0, p.x.floor() as i64, p.y.floor() as i64)
    };
    let mut cells: HashMap<(usize, i64, i64), Vec<usize>> = HashMap::new();
    for k in 0..standing.len() {
        cells.entry(cell(k)).or_default().push(k);
    }
    let runs = Sets::new(standing.len());
    for k in 0..standing.len() {
        let (top, i, j) = cell(k);
        let around = (-1..=1).flat_map(|di| (-1..=1).map(move |dj| (top, i + di, j + dj)));
        for m in around.filter_map(|c| cells.get(&c)).flatten() {
            if xy(*m).distance(xy(k)) <= reach {
                runs.join(k, *m);
            }
        }
    }
    let mut boxes = vec![(Vec2::INFINITY, Vec2::NEG_INFINITY); standing.len()];
    for k in 0..standing.len() {
        let b = &mut boxes[runs.root(k)];
        *b = (b.0.min(xy(k)), b.1.max(xy(k)));
    }
    (0..standing.len())
        .filter(|&k| runs.root(k) == k)
        .filter(|&k| (boxes[k].1 - boxes[k].0).length() >= WALL_SPACINGS * spacing)
        .map(|k| standing[k].0)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::delaunay::delaunay_xy;

    /// Ground 0.5 m apart over 20 × 12 m, a roof 6 × 6 m at `x0` standing `height`
    /// over it, and `wall` samples down its west edge (one per scan row, 1 m down).
    fn scene(height: f32, wall: bool) -> (Vec<Vec3>, impl Fn(Vec3) -> bool) {
        let x0 = 6.0;
        let on_roof = move |p: Vec3| (x0..=x0 + 6.0).contains(&p.x) && (3.0..=9.0).contains(&p.y);
        let mut points = Vec::new();
        for i in 0..=40 {
            for j in 0..=24 {
                let (x, y) = (i as f32 * 0.5, j as f32 * 0.5);
                let z = if on_roof(Vec3::new(x, y, 0.0)) {
                    height
                } else {
                    0.01 * ((i * 7 + j * 3) % 5) as f32
                };
                points.push(Vec3::new(x, y, z));
                if wall && x == x0 && on_roof(Vec3::new(x, y, 0.0)) {
                    points.push(Vec3::new(x - 0.1, y, height - 1.0));
                }
            }
        }
        (points, move |p: Vec3| on_roof(p) && p.z == height)
    }

    fn standings(points: &[Vec3]) -> Vec<Standing> {
        free_standing(points, &delaunay_xy(points), points.len())
    }

    fn free_of(points: &[Vec3]) -> Vec<bool> {
        (standings(points).iter())
            .map(|&s| s == Standing::Slab)
            .collect()
    }

    #[test]
    fn a_roof_with_no_sample_under_it_stands_free_and_the_ground_does_not() {
        let (points, roof) = scene(2.6, false);
        let free = free_of(&points);
        for (p, f) in points.iter().zip(free) {
            assert_eq!(f, roof(*p), "at {p}");
        }
    }

    #[test]
    fn a_roof_with_a_sampled_wall_is_walled() {
        let (points, _) = scene(2.6, true);
        assert!(free_of(&points).iter().all(|&f| !f));
    }

    #[test]
    fn a_low_step_and_a_pitched_roof_do_not_stand_free() {
        // 0.5 m: no drop at s = 0.5 m, so the step is ground.
        let (points, _) = scene(0.5, false);
        assert!(free_of(&points).iter().all(|&f| !f));
        // A roof pitched 45°: 3 m deep over its 6 m.
        let (mut points, roof) = scene(6.0, false);
        for p in points.iter_mut().filter(|p| roof(**p)) {
            p.z += 3.0 - (p.y - 6.0).abs();
        }
        assert!(free_of(&points).iter().all(|&f| !f));
    }

    #[test]
    fn a_post_and_a_wire_stand_lone_and_a_roof_does_not() {
        // Ground with no roof, a post's sample 1.5 m up and a wire's row 5 m up.
        let (mut points, _) = scene(0.0, false);
        let ground = points.len();
        points.push(Vec3::new(3.1, 5.1, 1.5));
        points.extend((0..20).map(|k| Vec3::new(2.3 + 0.5 * k as f32, 8.3, 5.0)));
        let standing = standings(&points);
        assert!(standing[..ground].iter().all(|&s| s == Standing::Joined));
        assert!(standing[ground..].iter().all(|&s| s == Standing::Lone));
        // A wall's samples stand one under another: neither of two is lone.
        points.extend([Vec3::new(7.1, 2.1, 3.0), Vec3::new(7.101, 2.3, 1.5)]);
        let standing = standings(&points);
        assert!(
            standing[points.len() - 2..]
                .iter()
                .all(|&s| s == Standing::Joined)
        );
        // A roof holds triangles of its own: it is a slab, not lone.
        let (points, roof) = scene(2.6, false);
        for (p, s) in points.iter().zip(standings(&points)) {
            assert_ne!(s, Standing::Lone, "at {p}");
            assert_eq!(s == Standing::Slab, roof(*p), "at {p}");
        }
    }

    #[test]
    fn a_roof_cut_by_the_border_does_not_stand_free() {
        // The same roof, its samples south of y = 6 m left out: it reaches the border.
        let (mut points, _) = scene(2.6, false);
        points.retain(|p| p.y >= 6.0);
        assert!(free_of(&points).iter().all(|&f| !f));
    }

    #[test]
    fn a_roof_across_a_piece_s_border_does_not_stand_free() {
        // The free roof, its samples north of y = 6 m a piece's halo (listed last): it
        // is joined, as the ground is.
        let (points, roof) = scene(2.6, false);
        let (own, halo): (Vec<Vec3>, Vec<Vec3>) = points.iter().partition(|p| p.y < 6.0);
        let split = [&own[..], &halo[..]].concat();
        let standing = free_standing(&split, &delaunay_xy(&split), own.len());
        assert!(standing.iter().all(|&s| s == Standing::Joined));
        // Wholly own or wholly halo, it stands free as before.
        for own in [split.len(), 0] {
            let standing = free_standing(&split, &delaunay_xy(&split), own);
            for (p, s) in split.iter().zip(standing) {
                assert_eq!(s == Standing::Slab, roof(*p), "at {p}");
            }
        }
    }
}
