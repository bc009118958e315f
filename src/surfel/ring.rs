//! Ellipses and normal fields of mesh vertices from their one-ring (DESIGN.md §2).
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
//! * the normal field G is the least-squares fit of Δn ≈ G d, times R.

use glam::{DVec2, DVec3, Vec3};

use super::Surfel;
use super::mesh::{RADIUS_MARGIN, triangle_terms};
use super::shape::{Fit, MIN_RATIO, Shape, SplatShape, rotate_gradient, tangent_frame};

/// Offset and normal change of vertex `w` seen from vertex `v`'s tangent frame.
fn ring_term(
    p: &impl Fn(u32) -> DVec3,
    n: &impl Fn(u32) -> DVec3,
    v: u32,
    w: u32,
) -> (DVec2, DVec2) {
    let (t1, t2) = tangent_frame(n(v));
    let d = p(w) - p(v);
    let dn = n(w) - n(v);
    (
        DVec2::new(d.dot(t1), d.dot(t2)),
        DVec2::new(dn.dot(t1), dn.dot(t2)),
    )
}

/// The ellipse's frame and unscaled gradient from a vertex's fit; None when the ring
/// spans no area (no triangle, or all neighbours coincide).
fn oriented(normal: DVec3, fit: &Fit) -> Option<Shape> {
    let (dir, l1, l2) = fit.axes();
    if l1 <= 0.0 || !l1.is_finite() {
        return None;
    }
    let (t1, t2) = tangent_frame(normal);
    Some(Shape {
        axis: (t1 * dir.x + t2 * dir.y).normalize_or(t1),
        ratio: (l2 / l1).sqrt().clamp(MIN_RATIO, 1.0),
        gradient: rotate_gradient(fit.gradient(), dir),
    })
}

/// Covering radius of triangle `t` around its vertex `v` (position `at`, normal
/// `normal`) in the metric of `shape`.
fn covering_radius(
    p: &impl Fn(u32) -> DVec3,
    at: DVec3,
    normal: DVec3,
    shape: &Shape,
    t: &[u32; 3],
) -> f64 {
    let minor = shape.minor_axis(normal);
    let map = |q: DVec3| {
        let d = q - at;
        DVec3::new(
            d.dot(shape.axis),
            d.dot(minor) / shape.ratio,
            d.dot(normal) / shape.ratio,
        )
    };
    let [a, b, c] = t.map(|i| map(p(i)));
    triangle_terms(a, b, c).1
}

/// Replaces the radius of every vertex that a triangle holds by the major semi-axis of
/// its one-ring ellipse and sets its shape (see the module doc); other vertices get a
/// circle. `points` are the model's positions, `scale` its unit scale; normals are read
/// from `surfels`.
pub fn ring_shapes(points: &[Vec3], scale: f32, triangles: &[[u32; 3]], surfels: &mut [Surfel]) {
    let s = scale as f64;
    let p = |i: u32| points[i as usize].as_dvec3() * s;
    let normals: Vec<Vec3> = surfels.iter().map(|q| q.normal).collect();
    let n = |i: u32| normals[i as usize].as_dvec3();
    let mut fits = vec![Fit::default(); points.len()];
    for t in triangles {
        for (k, &v) in t.iter().enumerate() {
            for w in [t[(k + 1) % 3], t[(k + 2) % 3]] {
                let (d, dn) = ring_term(&p, &n, v, w);
                fits[v as usize].add(d, dn);
            }
        }
    }
    let shapes: Vec<Option<Shape>> = fits
        .iter()
        .enumerate()
        .map(|(v, f)| oriented(n(v as u32), f))
        .collect();
    drop(fits);
    let mut major = vec![0.0f64; points.len()];
    for t in triangles {
        for &v in t {
            if let Some(shape) = &shapes[v as usize] {
                let r = covering_radius(&p, p(v), n(v), shape, t);
                major[v as usize] = major[v as usize].max(r);
            }
        }
    }
    for (v, shape) in shapes.into_iter().enumerate() {
        let surfel = &mut surfels[v];
        match shape.filter(|_| major[v] > 0.0 && major[v].is_finite()) {
            Some(mut shape) => {
                let r = major[v] * (1.0 + RADIUS_MARGIN);
                shape.gradient = shape.gradient.map(|g| g * r);
                surfel.radius = (r / s) as f32;
                surfel.shape = shape.pack();
            }
            None => surfel.shape = SplatShape::circle(surfel.normal),
        }
    }
}
