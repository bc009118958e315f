//! Ellipses and normal fields of mesh vertices from their one-ring (docs/design.md §2).
//!
//! In the tangent frame (t₁, t₂) of vertex i, each neighbour j sharing a triangle adds
//! its offset d = (pⱼ − pᵢ)·(t₁, t₂) and normal change Δn = (nⱼ − nᵢ)·(t₁, t₂) to a
//! [`Fit`] (an edge counts once per triangle holding it):
//!
//! * the ellipse's axes are the principal axes of Σ d dᵀ, its ratio √(λ₂/λ₁) (at least
//!   [`MIN_RATIO`]);
//! * its size is the covering rule of `mesh.rs` taken in the ellipse's own metric: each
//!   incident triangle, mapped by (x, y, z) ↦ (x, y / ratio, z / ratio) in the frame
//!   (u, v, n), needs a circle of its covering radius ρ (circumradius if acute, half
//!   the longest edge otherwise) around the vertex; R = max ρ is the major semi-axis.
//!   For a round one-ring this is exactly the circle rule. Neighbours whose ellipses
//!   differ cover a triangle only approximately; the render tests measure holes.
//! * the normal field G is the least-squares fit of Δn ≈ G d, times R, where the
//!   ring spans no area for `field.rs`; elsewhere the drawn field (the splat's normal
//!   and G) is fitted to the triangles' interpolated normals over the ellipse;
//! * on the mesh's border the ellipse is clipped. Where the ring has one border edge
//!   out and one in, to the wedge of its fan ([`border_fan`], [`Clip::Wedge`]). Else
//!   by a line: in a triangle (i, j, k) vertex i has out-neighbour j and in-neighbour
//!   k, and the chord Σ d(out) − Σ d(in) over its triangles cancels where every edge
//!   has its twin; on the border it is the offset from the border's previous vertex to
//!   its next, with the triangles on its left seen from the normal (the chord is
//!   negated where the ring's triangles wind clockwise seen from it, Σ d(out) × d(in)
//!   < 0, as after `orient_outward` turned the normals). The clip line is ⟂ to the
//!   chord, outside every ring vertex (so it never cuts a triangle of the ring).

use glam::{DVec2, DVec3, Vec3};

use rayon::prelude::*;

use super::Surfel;
use super::corners::Rings;
use super::field::{fit_color_field, fit_field, unit_rgb};
use super::progress::Progress;
use super::shape::{Clip, Fit, MIN_RATIO, Shape, SplatShape, rotate_gradient, tangent_frame};
use super::triangle::{RADIUS_MARGIN, triangle_terms};

/// Vertex v's position, normal and tangent frame, made once per vertex: each of its
/// ring's vertices is seen from it two to four times.
struct RingFrame {
    at: DVec3,
    normal: DVec3,
    t1: DVec3,
    t2: DVec3,
}

impl RingFrame {
    fn of(p: &impl Fn(u32) -> DVec3, n: &impl Fn(u32) -> DVec3, v: u32) -> Self {
        let normal = n(v);
        let (t1, t2) = tangent_frame(normal);
        RingFrame {
            at: p(v),
            normal,
            t1,
            t2,
        }
    }

    /// A direction's coordinates in the tangent frame.
    fn project(&self, d: DVec3) -> DVec2 {
        DVec2::new(d.dot(self.t1), d.dot(self.t2))
    }

    /// The direction with tangent-frame coordinates `d`.
    fn unproject(&self, d: DVec2) -> DVec3 {
        self.t1 * d.x + self.t2 * d.y
    }

    /// Offset and normal change of vertex `w` in this frame.
    fn term(&self, p: &impl Fn(u32) -> DVec3, n: &impl Fn(u32) -> DVec3, w: u32) -> (DVec2, DVec2) {
        (self.offset(p, w), self.project(n(w) - self.normal))
    }

    /// The offset alone of vertex `w` ([`RingFrame::term`]).
    fn offset(&self, p: &impl Fn(u32) -> DVec3, w: u32) -> DVec2 {
        self.project(p(w) - self.at)
    }
}

/// The ellipse's frame and unscaled gradient from a vertex's fit; None when the ring
/// spans no area (no triangle, or all neighbours coincide).
fn oriented(frame: &RingFrame, fit: &Fit) -> Option<Shape> {
    let (dir, l1, l2) = fit.axes();
    if l1 <= 0.0 || !l1.is_finite() {
        return None;
    }
    Some(Shape {
        axis: frame.unproject(dir).normalize_or(frame.t1),
        ratio: (l2 / l1).sqrt().clamp(MIN_RATIO, 1.0),
        gradient: rotate_gradient(fit.gradient(), dir),
        clip: None,
        color: [DVec3::ZERO; 2],
    })
}

/// The border's outward direction at a vertex, in its tangent frame, from its chord
/// (see the module doc); zero inside the mesh, where the chord cancels to rounding.
fn border_normal(chord: DVec2, fit: &Fit) -> DVec2 {
    let spread = fit.moments[0] + fit.moments[2];
    if chord.length_squared() <= 1e-12 * spread {
        return DVec2::ZERO;
    }
    DVec2::new(chord.y, -chord.x).normalize_or_zero()
}

/// A tangent-frame direction of a vertex as plane coordinates of its ellipse (along u,
/// v), unit; None if it vanishes.
fn to_plane(frame: &RingFrame, d: DVec2, shape: &Shape) -> Option<DVec2> {
    shape
        .along_axes(frame.normal, frame.unproject(d))
        .try_normalize()
}

/// The clip of a border vertex (its `frame`) on an ellipse of major radius `r`: the wedge of its
/// fan where it has one ([`border_fan`]), else the line ⟂ `outward` (in its tangent
/// frame) at `reach`, the largest offset of a ring vertex along it.
fn border_clip(
    frame: &RingFrame,
    (outward, reach): (DVec2, f64),
    fan: Option<Fan>,
    shape: &Shape,
    r: f64,
) -> Option<Clip> {
    if let Some((start, end)) = fan {
        let (start, end) = (to_plane(frame, start, shape)?, to_plane(frame, end, shape)?);
        return Some(Clip::Wedge {
            start: start.to_angle(),
            end: end.to_angle(),
        });
    }
    if outward == DVec2::ZERO {
        return None;
    }
    Some(Clip::Line {
        normal: to_plane(frame, outward, shape)?,
        offset: reach.max(0.0) / r,
    })
}

/// A border vertex's fan: the directions of its first and last border edges, in its
/// tangent frame, the triangles sweeping counter-clockwise from one to the other.
type Fan = (DVec2, DVec2);

/// Largest disagreement (radians) between a fan's summed triangle angles and the
/// sweep between its border edges before its wedge is not trusted.
const FAN_TOLERANCE: f64 = 0.05;

/// The fan of border vertex `v` whose ring has exactly one border edge out (to a
/// `next` that is no triangle's `previous`) and one in: the directions of the two
/// border neighbours in its tangent frame, ordered so that the triangles sweep
/// counter-clockwise seen from the normal from the first to the second. Where the
/// sweep between the two directions differs from the triangles' angles at v, summed in
/// that sense (a ring folded over itself in the tangent plane), None.
fn border_fan(
    corners: impl Iterator<Item = (u32, u32)> + Clone,
    direction: impl Fn(u32) -> DVec2,
) -> Option<Fan> {
    // The one end of the first kind that no corner has as its second, if one only.
    let lone = |first: fn((u32, u32)) -> u32, second: fn((u32, u32)) -> u32| {
        let mut ends = corners.clone().map(first);
        let lone = |w: &u32| !corners.clone().any(|c| second(c) == *w);
        let found = ends.find(lone)?;
        ends.all(|w| !lone(&w)).then_some(found)
    };
    let (Some(w_out), Some(w_in)) = (lone(|c| c.0, |c| c.1), lone(|c| c.1, |c| c.0)) else {
        return None;
    };
    let (mut angle, mut winding) = (0.0, 0.0);
    for (next, previous) in corners {
        let (d_out, d_in) = (direction(next), direction(previous));
        angle += d_out.angle_to(d_in);
        winding += d_out.perp_dot(d_in);
    }
    let (a, b) = (direction(w_out), direction(w_in));
    let (start, end, angle) = if winding < 0.0 {
        (b, a, -angle)
    } else {
        (a, b, angle)
    };
    let (start, end) = (start.try_normalize()?, end.try_normalize()?);
    let sweep = Clip::sweep(start, end);
    ((sweep - angle).abs() <= FAN_TOLERANCE).then_some((start, end))
}

/// Covering radius of a triangle around the vertex of `frame` in the metric of
/// `shape` (minor axis `minor`): `corners` are the triangle's positions.
fn covering_radius(frame: &RingFrame, (shape, minor): (&Shape, DVec3), corners: [DVec3; 3]) -> f64 {
    let stretch = shape.ratio.recip();
    let map = |q: DVec3| {
        let d = q - frame.at;
        DVec3::new(
            d.dot(shape.axis),
            d.dot(minor) * stretch,
            d.dot(frame.normal) * stretch,
        )
    };
    let [a, b, c] = corners.map(map);
    triangle_terms(a, b, c).1
}

/// Replaces the radius of every vertex that a triangle holds by the major semi-axis of
/// its one-ring ellipse and sets its shape (see the module doc) and its normal, that of
/// its shading field ([`fit_field`]); other vertices get a circle. With `colored` (a
/// model with colours), also its colour field ([`fit_color_field`]).
/// `points` are the model's positions, `scale` its unit scale; the vertex normals are
/// read from `surfels`, and returned. Only the first `kept` surfels are shaped: the
/// rest (an out-of-core job's halo, dropped after its surfels are made) lend their
/// positions and normals to their neighbours' rings. Each vertex gathers over its own
/// corners (`rings`, of `triangles`), in parallel, and everything it needs is its own:
/// one pass, with no per-vertex temporaries (on the Lucy-size model they were 1.7 GB
/// of fresh pages to fault in). The shaped vertices are told to `progress`, a block
/// of [`SHAPE_BLOCK`] at a time.
pub fn ring_shapes(
    points: &[Vec3],
    scale: f32,
    (triangles, rings): (&[[u32; 3]], &Rings),
    (surfels, kept): (&mut [Surfel], usize),
    colored: bool,
    progress: Progress,
) -> Vec<Vec3> {
    let s = scale as f64;
    let p = |i: u32| points[i as usize].as_dvec3() * s;
    let normals: Vec<Vec3> = surfels.iter().map(|q| q.normal).collect();
    let n = |i: u32| normals[i as usize].as_dvec3();
    let colors: Vec<DVec3> = if colored {
        surfels.iter().map(|q| unit_rgb(q.color)).collect()
    } else {
        Vec::new()
    };
    let ring = |v: usize| rings.ring(triangles, v);
    let shape = |v: usize, surfel: &mut Surfel| match vertex_shape(&p, &n, v as u32, || ring(v)) {
        Some((r, shape)) => {
            let at = |w: u32| (p(w), n(w));
            let corners = ring(v).map(|(_, next, previous)| (next, previous));
            let (normal, shape) = fit_field(at(v as u32), (r, &shape), (at(v as u32), at), corners)
                .unwrap_or((n(v as u32), shape));
            let mut shape = shape;
            if colored {
                let at = |w: u32| (p(w), colors[w as usize]);
                let triangles =
                    ring(v).map(|(_, next, previous)| [at(v as u32), at(next), at(previous)]);
                if let Some((c0, field)) =
                    fit_color_field((p(v as u32), normal), (r, &shape), triangles)
                {
                    let [r, g, b] = (c0 * 255.0)
                        .to_array()
                        .map(|x| x.round().clamp(0.0, 255.0) as u8);
                    surfel.color = [r, g, b, surfel.color[3]];
                    shape.color = field;
                }
            }
            surfel.radius = (r / s) as f32;
            surfel.normal = normal.as_vec3();
            surfel.shape = shape.pack();
        }
        None => surfel.shape = SplatShape::circle(surfel.normal),
    };
    (surfels[..kept].par_chunks_mut(SHAPE_BLOCK).enumerate()).for_each(|(b, block)| {
        for (j, surfel) in block.iter_mut().enumerate() {
            shape(b * SHAPE_BLOCK + j, surfel);
        }
        progress.done(block.len());
    });
    normals
}

/// Vertices shaped in one job of [`ring_shapes`].
const SHAPE_BLOCK: usize = 1 << 12;

/// Vertex v's one-ring ellipse (see the module doc): its major semi-axis (unit-scaled)
/// and its shape, gradient scaled by it and clip set; None where the ring spans no
/// area. `ring` lists v's corners as (triangle, next vertex, previous vertex).
fn vertex_shape<'a, I>(
    p: &impl Fn(u32) -> DVec3,
    n: &impl Fn(u32) -> DVec3,
    v: u32,
    ring: impl Fn() -> I,
) -> Option<(f64, Shape)>
where
    I: Iterator<Item = (&'a [u32; 3], u32, u32)> + Clone,
{
    let frame = RingFrame::of(p, n, v);
    let (mut fit, mut chord, mut winding) = (Fit::default(), DVec2::ZERO, 0.0);
    for (_, next, previous) in ring() {
        let (d_out, dn_out) = frame.term(p, n, next);
        let (d_in, dn_in) = frame.term(p, n, previous);
        fit.add(d_out, dn_out);
        fit.add(d_in, dn_in);
        chord += d_out - d_in;
        winding += d_out.perp_dot(d_in);
    }
    // Triangles wound clockwise seen from the normal lie right of the chord.
    let chord = if winding < 0.0 { -chord } else { chord };
    let outward = border_normal(chord, &fit);
    let mut shape = oriented(&frame, &fit)?;
    let minor = shape.minor_axis(frame.normal);
    let (mut major, mut reach) = (0.0f64, 0.0f64);
    for (t, next, previous) in ring() {
        major = major.max(covering_radius(&frame, (&shape, minor), t.map(p)));
        if outward != DVec2::ZERO {
            for w in [next, previous] {
                reach = reach.max(outward.dot(frame.offset(p, w)));
            }
        }
    }
    if !(major > 0.0 && major.is_finite()) {
        return None;
    }
    let r = major * (1.0 + RADIUS_MARGIN);
    shape.gradient = shape.gradient.map(|g| g * r);
    let fan = (outward != DVec2::ZERO)
        .then(|| {
            let corners = ring().map(|(_, next, previous)| (next, previous));
            border_fan(corners, |w| frame.offset(p, w))
        })
        .flatten();
    shape.clip = border_clip(&frame, (outward, reach), fan, &shape, r);
    Some((r, shape))
}

/// Clips each splat of a vertex inside a mesh (`surfels`, one per point, sized by
/// [`ring_shapes`]) whose ring holds a border edge (an edge of one triangle only)
/// at that edge's line, and returns how many it clipped. A border vertex's splat ends
/// at its fan ([`border_fan`]), but its neighbour's ellipse, which covers the ring's
/// triangles, reaches past the border edge opposite it: along every hole and outline of
/// a sensor frame (`super::grid`) that made a rim a pixel wide that the reference leaves empty. Where a ring
/// holds several border edges, the nearest one's line clips (the first in triangle
/// order among equals). Each vertex reads its own ring (`rings`, of `triangles`), in
/// parallel, first to tell whether it is on the border (a neighbour that one triangle
/// of the ring holds), then, inside it, to find the border edges opposite it: an edge
/// (a, b) whose ends are both on the border and that one triangle of a's ring holds.
/// Only the first `kept` splats are clipped (as [`ring_shapes`] shapes them).
pub fn clip_at_border(
    points: &[Vec3],
    (triangles, rings): (&[[u32; 3]], &Rings),
    (surfels, kept): (&mut [Surfel], usize),
) -> u64 {
    let on_border: Vec<bool> = (0..surfels.len())
        .into_par_iter()
        .with_min_len(1 << 12)
        .map_init(Vec::new, |ends, v| {
            let mut runs = rings.neighbour_runs(triangles, v, ends);
            runs.any(|run| run.len() == 1)
        })
        .collect();
    let shared = |a: u32, b: u32| {
        let ring = rings.ring(triangles, a as usize);
        ring.filter(|&(_, next, previous)| next == b || previous == b)
            .count()
    };
    let border_edge =
        |a: u32, b: u32| on_border[a as usize] && on_border[b as usize] && shared(a, b) == 1;
    surfels[..kept]
        .par_iter_mut()
        .enumerate()
        .with_min_len(1 << 12)
        .map(|(v, s)| {
            if on_border[v] {
                return 0;
            }
            let offset = |c: &Option<Clip>| match c {
                Some(Clip::Line { offset, .. }) => *offset,
                _ => f64::INFINITY,
            };
            let mut nearest = None;
            for (_, a, b) in rings.ring(triangles, v) {
                if !border_edge(a, b) {
                    continue;
                }
                let line = edge_clip(s, points[a as usize], points[b as usize]);
                if offset(&line) < offset(&nearest) {
                    nearest = line;
                }
            }
            match nearest {
                Some(c @ Clip::Line { offset, .. }) if offset < 1.0 => {
                    s.shape.clip = Clip::pack(Some(c));
                    1
                }
                _ => 0,
            }
        })
        .sum()
}

/// The line through `a` and `b` as a clip of splat `s` (kept: its centre's side), in
/// its ellipse's plane coordinates ([`Clip::Line`]); `None` when the line is degenerate
/// or passes through the centre.
fn edge_clip(s: &Surfel, a: Vec3, b: Vec3) -> Option<Clip> {
    let n = s.normal.as_dvec3();
    let shape = s.shape.unpack(n);
    let r = s.radius as f64;
    let plane = |p: Vec3| shape.along_axes(n, (p - s.position).as_dvec3()) / r;
    Clip::line_through(plane(a), plane(b))
}

#[cfg(test)]
mod tests {
    use super::*;
    use bytemuck::Zeroable;

    /// A 3×3 grid of unit squares in the plane z = 0, two triangles each, wound
    /// counter-clockwise seen from +z.
    fn grid() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let points = (0..16)
            .map(|i| Vec3::new((i % 4) as f32, (i / 4) as f32, 0.0))
            .collect();
        let mut triangles = Vec::new();
        for y in 0..3u32 {
            for x in 0..3u32 {
                let i = 4 * y + x;
                triangles.push([i, i + 1, i + 5]);
                triangles.push([i, i + 5, i + 4]);
            }
        }
        (points, triangles)
    }

    #[test]
    fn only_the_kept_splats_are_shaped_and_clipped_and_as_over_all() {
        // The grid's first 10 vertices kept (a job's own), the other 6 its halo: the kept
        // ones get the shapes and clips of a pass over all, the halo's stay as given.
        let (points, triangles) = grid();
        let rings = Rings::of(points.len(), &triangles);
        let given: Vec<Surfel> = (points.iter())
            .map(|&p| Surfel {
                radius: 1.0,
                normal: Vec3::Z,
                ..Surfel::unsized_at(p)
            })
            .collect();
        let shaped = |kept: usize| {
            let mut surfels = given.clone();
            ring_shapes(
                &points,
                1.0,
                (&triangles, &rings),
                (&mut surfels, kept),
                false,
                Progress::NONE,
            );
            clip_at_border(&points, (&triangles, &rings), (&mut surfels, kept));
            surfels
        };
        let (all, some) = (shaped(16), shaped(10));
        assert_eq!(all[..10], some[..10]);
        assert_eq!(some[10..], given[10..]);
        assert_ne!(all[10..], given[10..]);
    }

    /// With the grid's winding, and with it reversed under the same +z normals (the
    /// triangles wound clockwise seen from the normal, as after `orient_outward`
    /// turned an inward-wound mesh's normals).
    #[test]
    fn border_splats_are_clipped_at_the_border_and_inner_ones_not() {
        let (points, triangles) = grid();
        let reversed: Vec<[u32; 3]> = triangles.iter().map(|&[a, b, c]| [a, c, b]).collect();
        for triangles in [triangles, reversed] {
            border_clips_on_the_grid(&points, &triangles);
        }
    }

    fn border_clips_on_the_grid(points: &[Vec3], triangles: &[[u32; 3]]) {
        let mut surfels: Vec<Surfel> = points
            .iter()
            .map(|&p| Surfel {
                position: p,
                normal: Vec3::Z,
                ..Surfel::zeroed()
            })
            .collect();
        let rings = Rings::of(points.len(), triangles);
        let all = surfels.len();
        ring_shapes(
            points,
            1.0,
            (triangles, &rings),
            (&mut surfels, all),
            false,
            Progress::NONE,
        );
        for (i, s) in surfels.iter().enumerate() {
            let (x, y) = ((i % 4) as f64, (i / 4) as f64);
            let border = x == 0.0 || x == 3.0 || y == 0.0 || y == 3.0;
            let shape = s.shape.unpack(DVec3::Z);
            assert_eq!(shape.clip.is_some(), border, "vertex {i}: {shape:?}");
            let Some(clip) = shape.clip else { continue };
            // One border edge in and one out: the fan's own wedge.
            assert!(matches!(clip, Clip::Wedge { .. }), "vertex {i}: {clip:?}");
            // Plane coordinates of a point, in major radii.
            let r = s.radius as f64;
            let at = |px: f64, py: f64| {
                let d = DVec3::new(px - x, py - y, 0.0);
                shape.along_axes(DVec3::Z, d) / r
            };
            let kept = |px, py| clip.keeps(at(px, py) * (1.0 - 1e-9));
            // Every point of the grid (so every triangle of the ring) is kept; a point
            // half a cell beyond the nearest border is cut away.
            for q in points {
                assert!(kept(q.x as f64, q.y as f64), "vertex {i} cuts {q}");
            }
            let (ox, oy) = (
                if x == 0.0 {
                    -0.5
                } else if x == 3.0 {
                    3.5
                } else {
                    x
                },
                if y == 0.0 {
                    -0.5
                } else if y == 3.0 {
                    3.5
                } else {
                    y
                },
            );
            assert!(!kept(ox, oy), "vertex {i} keeps ({ox}, {oy}): {clip:?}");
        }
    }

    #[test]
    fn an_inner_splat_is_clipped_at_the_border_edge_of_its_ring() {
        // Pixels of a 3 × 3 block, 1 apart: every edge of the centre's ring is on the
        // border. The centre's splat, a circle reaching 1.5 pixels, passes the border
        // edges (at 1) until it is clipped at the nearest one's line.
        let points: Vec<Vec3> = (0..9)
            .map(|i| Vec3::new((i % 3) as f32 - 1.0, (i / 3) as f32 - 1.0, 0.0))
            .collect();
        let triangles = [
            [0, 4, 1],
            [0, 3, 4],
            [1, 5, 2],
            [1, 4, 5],
            [3, 7, 4],
            [3, 6, 7],
        ];
        let triangles = [&triangles[..], &[[4, 8, 5], [4, 7, 8]]].concat();
        let mut surfels: Vec<Surfel> = points
            .iter()
            .map(|&position| Surfel {
                radius: 1.5,
                normal: Vec3::Z,
                shape: crate::surfel::shape::SplatShape::circle(Vec3::Z),
                ..Surfel::unsized_at(position)
            })
            .collect();
        assert!(surfels[4].covers(Vec3::new(1.25, 0.0, 0.0)));
        let rings = Rings::of(points.len(), &triangles);
        assert_eq!(
            clip_at_border(&points, (&triangles, &rings), (&mut surfels, 5)),
            1
        );
        let kept = |x: f32, y: f32| surfels[4].covers(Vec3::new(x, y, 0.0));
        assert!(kept(0.0, 0.0) && kept(0.9, 0.0) && kept(-0.9, 0.0) && kept(0.0, 0.9));
        let past = [(1.1, 0.0), (-1.1, 0.0), (0.0, 1.1), (0.0, -1.1)];
        assert_eq!(past.iter().filter(|&&(x, y)| kept(x, y)).count(), 3);
        // The border vertices keep their own clips (none here).
        assert!(
            surfels[..4]
                .iter()
                .all(|s| s.shape.clip == surfels[0].shape.clip)
        );
    }
}
