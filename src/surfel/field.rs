//! A mesh splat's shading normal field, fitted to the triangles' own (docs/design.md §2).
//!
//! Pass 2 blends the overlapping splats' fields, each weighted by its kernel; the mesh
//! shades with the barycentric blend of its vertex normals. A field anchored at the
//! vertex normal, its gradient the one-ring's least-squares [`Fit`],
//! matches the mesh at the vertex only: where the splat's weight lies (within about half
//! its radius) the mesh's field is piecewise linear, peaked at a scanner's striations,
//! and the blend of such fields was 0.99° from the mesh's normals on average over the
//! bunny's surface (a CPU model of the blend, 0.60° median).
//!
//! Here each splat's field is the least-squares fit, intercept included, of the
//! mesh's normal over the part of its one-ring that the splat covers: at the points of
//! a barycentric lattice of each triangle ([`LATTICE`]) within the ellipse (ρ² = x² +
//! y²/ratio² < 1), each weighing its triangle's area, the tangential components
//! (N·u, N·v) of the mesh's normal N = normalize(Σ λ nᵢ) ≈ (c₁ + a x + b y, c₂ + b x +
//! c y), with (x, y) the point's plane coordinates in major radii (x along u, y along
//! v). The splat's normal becomes normalize(n + c₁ u + c₂ v) and its gradient (a, b, c).
//!
//! Measured (`--example quality`, leaves only, 8 views, FLIP median; knot, bunny,
//! dragon): the one-ring fit 0.0701, 0.0281, 0.0294; this fit with points weighted by
//! the splat kernel 0.0592, 0.0207, 0.0239; unweighted within the ellipse, as here,
//! 0.0510, 0.0167, 0.0186 (the mesh at 1×: 0.0235, 0.0091, 0.0128). Lattices of degree
//! 2 and 6 changed the figures by under 3 %.
//!
//! Colours get a field the same way ([`fit_color_field`]): colour ≈ c₀ + cₓ x + c_y y
//! fitted to the mesh's interpolated colours over the same points; the splat's colour
//! becomes c₀. One colour per splat had flattened the mesh's ramps into steps a splat
//! wide, which pass 2's blend of constant colours cannot undo. Knot, 8 views: 0.0510
//! with the vertex colours; 0.0481 with the colours moved by two damped Jacobi steps of
//! the least squares of the modelled blend (no field, tried and replaced); 0.0421 with
//! the fields (those steps on top of the fields: 0.0429 on 2 views, against 0.0411).
//!
//! The normal also orients the splat's plane: it tilts by |c|, well under a degree on
//! scanned meshes, and its ellipse still covers the ring (the covering radius bounds
//! the 3D distance, which no tilt of the plane lengthens). The mesh pass keeps the
//! vertex normals (`LeafSurfels::vertex_normals`) and colours.

use arrayvec::ArrayVec;
use glam::{DVec2, DVec3};

use super::shape::{Fit, Shape};

/// Barycentric points of the fit in each triangle, vertex first: the degree-3 lattice
/// (i/3, j/3, k/3), i + j + k = 3.
pub const LATTICE: [[f64; 3]; 10] = {
    const T: f64 = 1.0 / 3.0;
    [
        [1.0, 0.0, 0.0],
        [2.0 * T, T, 0.0],
        [2.0 * T, 0.0, T],
        [T, 2.0 * T, 0.0],
        [T, T, T],
        [T, 0.0, 2.0 * T],
        [0.0, 1.0, 0.0],
        [0.0, 2.0 * T, T],
        [0.0, T, 2.0 * T],
        [0.0, 0.0, 1.0],
    ]
};

/// Weighted sums of a fit with intercept: t ≈ c + G d. Its least squares is the
/// intercept-free fit of the centred points, G = [`Fit::gradient`] of (d − d̄, t − t̄),
/// then c = t̄ − G d̄ (means weighted). The sums are one row of [`TERMS`] ([`terms`]),
/// which each point adds to term by term, in the order the points come.
#[derive(Default)]
pub struct FieldFit {
    sums: [f64; TERMS],
}

/// Sums of a [`FieldFit`]: Σ w, Σ w d (2), Σ w t (2), then Σ w d dᵀ and Σ w d tᵀ as
/// [`Fit`] holds them (uncentred, 3 each), and a zero that pads the row to three
/// 4-wide vectors.
const TERMS: usize = 12;

/// What a point at plane coordinates `d` whose mesh normal has tangential components
/// `t` adds to a [`FieldFit`]'s sums with weight `w`: w, w d, w t, (w d₁) d₁,
/// (w d₁) d₂, (w d₂) d₂, (w d₁) t₁, w (d₂ t₁ + d₁ t₂), (w d₂) t₂, 0 (each product as
/// [`Fit::add_weighted`] takes it).
fn terms(d: DVec2, t: DVec2, w: f64) -> [f64; TERMS] {
    let (wx, wy) = (w * d.x, w * d.y);
    [
        w,
        wx,
        wy,
        w * t.x,
        w * t.y,
        wx * d.x,
        wx * d.y,
        wy * d.y,
        wx * t.x,
        w * (d.y * t.x + d.x * t.y),
        wy * t.y,
        0.0,
    ]
}

impl FieldFit {
    /// Adds a point's [`terms`].
    fn add_terms(&mut self, row: &[f64; TERMS]) {
        for (sum, term) in self.sums.iter_mut().zip(row) {
            *sum += term;
        }
    }

    /// ((a, b, c), (c₁, c₂)), or None when no point weighs anything.
    pub fn solve(&self) -> Option<([f64; 3], DVec2)> {
        let [weight, dx, dy, tx, ty, s11, s12, s22, r1, r2, r3, _] = self.sums;
        if !(weight > 0.0 && weight.is_finite()) {
            return None;
        }
        let (d, t) = (DVec2::new(dx, dy) / weight, DVec2::new(tx, ty) / weight);
        let w = weight;
        let centred = Fit {
            moments: [
                s11 - w * d.x * d.x,
                s12 - w * d.x * d.y,
                s22 - w * d.y * d.y,
            ],
            rhs: [
                r1 - w * d.x * t.x,
                r2 - w * (d.y * t.x + d.x * t.y),
                r3 - w * d.y * t.y,
            ],
        };
        let [a, b, c] = centred.gradient();
        let offset = t - DVec2::new(a * d.x + b * d.y, b * d.x + c * d.y);
        offset.is_finite().then_some(([a, b, c], offset))
    }
}

/// Fits the shading field of the splat at `at` (normal `normal`, major radius `r`,
/// shape `shape`) over the fan of triangles around one vertex (`centre`: its position
/// and normal; a mesh vertex's splat is at its vertex): `corners` lists each triangle
/// by its two other vertices (next, previous), whose (position, normal) `vertex` gives.
/// Returns the new normal and shape, or None where the fit is undetermined (the
/// one-ring fit stays). Positions and `r` in one unit.
///
/// Each triangle's [`LATTICE`] points weigh its area. Neighbouring triangles share
/// lattice points: the vertex itself, and the three on each edge from it (at its
/// thirds and its far end). A shared point has one position and one interpolated
/// normal, so it is evaluated once, weighing the area of every triangle that holds it:
/// 1 + 3 per neighbour + 3 per triangle, 37 points for a ring of six instead of 60.
/// A fan of one triangle (a long triangle's splat) takes its 10 points.
pub fn fit_field(
    (at, normal): (DVec3, DVec3),
    (r, shape): (f64, &Shape),
    (centre, vertex): ((DVec3, DVec3), impl Fn(u32) -> (DVec3, DVec3)),
    corners: impl Iterator<Item = (u32, u32)>,
) -> Option<(DVec3, Shape)> {
    let (u, v) = (shape.axis, shape.minor_axis(normal));
    let splat = Splat::new((at, r, (u, v), shape.ratio), centre);
    let fit = splat.fan_sums(vertex, corners);
    let (gradient, offset) = fit.solve()?;
    let tilted = (normal + u * offset.x + v * offset.y).normalize_or(normal);
    let axis = (u - tilted * u.dot(tilted)).normalize_or(u);
    Some((
        tilted,
        Shape {
            axis,
            gradient,
            ..*shape
        },
    ))
}

/// Ring neighbours whose edge points [`fit_field`] shares between triangles; a larger
/// ring's further neighbours are evaluated once per triangle (the same sums).
const MAX_SPOKES: usize = 24;

/// The lattice's barycentric steps.
const THIRD: f64 = 1.0 / 3.0;
const TWO_THIRDS: f64 = 2.0 * THIRD;

/// The splat whose field [`fit_field`] fits, as its lattice points see it.
struct Splat {
    at: DVec3,
    r: f64,
    /// Its major and minor axes u, v.
    axes: (DVec3, DVec3),
    /// 1 / ratio²: the point at plane coordinates (x, y) is covered when x² + y² / ratio² < 1.
    inv_ratio2: f64,
    /// The fan's centre vertex.
    centre: Spoke,
}

/// A vertex w of the fan as the splat sees it: its position, plane coordinates in major radii,
/// its normal's tangential components, (n_w·n_w, n_c·n_w) with n_c the centre's normal
/// (an interpolated normal's squared length is λᵀ Gram λ), its normal, and the area
/// of the fan's triangles that hold the edge from the centre to it.
#[derive(Clone, Copy, Default)]
struct Spoke {
    id: u32,
    position: DVec3,
    plane: DVec2,
    tangential: DVec2,
    gram: (f64, f64),
    normal: DVec3,
    weight: f64,
}

impl Splat {
    /// The splat at `at` of major radius `r`, axes `u`, `v` and minor over major
    /// `ratio`, about the fan's centre vertex (position, normal).
    fn new(
        (at, r, (u, v), ratio): (DVec3, f64, (DVec3, DVec3), f64),
        centre: (DVec3, DVec3),
    ) -> Splat {
        let mut splat = Splat {
            at,
            r,
            axes: (u, v),
            inv_ratio2: 1.0 / (ratio * ratio),
            centre: Spoke::default(),
        };
        splat.centre = splat.seen((u32::MAX, centre), centre.1, 0.0);
        splat
    }

    /// The [`FieldFit`] sums of the lattice points of the fan `corners` (see
    /// [`fit_field`]).
    fn fan_sums(
        &self,
        vertex: impl Fn(u32) -> (DVec3, DVec3),
        corners: impl Iterator<Item = (u32, u32)>,
    ) -> FieldFit {
        let mut fit = FieldFit::default();
        let mut spokes: ArrayVec<Spoke, MAX_SPOKES> = ArrayVec::new();
        let mut total = 0.0;
        let centre = self.centre.position;
        for (next, previous) in corners {
            let (b, c) = (vertex(next), vertex(previous));
            let area = 0.5 * (b.0 - centre).cross(c.0 - centre).length();
            total += area;
            let b = self.spoke_of(&mut spokes, &mut fit, (next, b), area);
            let c = self.spoke_of(&mut spokes, &mut fit, (previous, c), area);
            self.add_inner(&mut fit, (&b, &c), area);
        }
        let c = &self.centre;
        self.add_point(&mut fit, (c.plane, c.tangential, c.gram.0), total);
        for spoke in &spokes {
            self.add_spoke(&mut fit, spoke, spoke.weight);
        }
        fit
    }

    /// Neighbour `id` at (position, normal), found among `spokes` and its weight grown
    /// by `area`, or added to them; where they are full, its edge's points go into
    /// `fit` at once, weighing `area`.
    fn spoke_of(
        &self,
        spokes: &mut ArrayVec<Spoke, MAX_SPOKES>,
        fit: &mut FieldFit,
        (id, (p, n)): (u32, (DVec3, DVec3)),
        area: f64,
    ) -> Spoke {
        if let Some(known) = spokes.iter_mut().find(|s| s.id == id) {
            known.weight += area;
            return *known;
        }
        let spoke = self.seen((id, (p, n)), self.centre.normal, area);
        if spokes.try_push(spoke).is_err() {
            self.add_spoke(fit, &spoke, area);
        }
        spoke
    }

    /// Vertex `id` at (position `p`, normal `n`) as the splat sees it, weighing `area`;
    /// `centre_normal` is the fan's centre's (its own, for the centre).
    fn seen(&self, (id, (p, n)): (u32, (DVec3, DVec3)), centre_normal: DVec3, area: f64) -> Spoke {
        let (u, v) = self.axes;
        let d = p - self.at;
        Spoke {
            id,
            position: p,
            plane: DVec2::new(d.dot(u), d.dot(v)) / self.r,
            tangential: DVec2::new(n.dot(u), n.dot(v)),
            gram: (n.dot(n), centre_normal.dot(n)),
            normal: n,
            weight: area,
        }
    }

    /// The points of the edge from the fan's centre to `spoke` (at its thirds and its
    /// far end), weighing `w`.
    fn add_spoke(&self, fit: &mut FieldFit, spoke: &Spoke, w: f64) {
        let c = &self.centre;
        let (g_ww, g_cw) = spoke.gram;
        for (lc, lw) in [(TWO_THIRDS, THIRD), (THIRD, TWO_THIRDS), (0.0, 1.0)] {
            let plane = c.plane * lc + spoke.plane * lw;
            let tangential = c.tangential * lc + spoke.tangential * lw;
            let length2 = lc * lc * c.gram.0 + lw * lw * g_ww + 2.0 * lc * lw * g_cw;
            self.add_point(fit, (plane, tangential, length2), w);
        }
    }

    /// The points of triangle (centre, `b`, `c`) that no other triangle of the fan
    /// holds: its centroid and the two on its far edge, weighing its `area`.
    fn add_inner(&self, fit: &mut FieldFit, (b, c): (&Spoke, &Spoke), area: f64) {
        let a = &self.centre;
        let g_bc = b.normal.dot(c.normal);
        let ((g_bb, g_ab), (g_cc, g_ac)) = (b.gram, c.gram);
        let centre = (
            (a.plane + b.plane + c.plane) * THIRD,
            (a.tangential + b.tangential + c.tangential) * THIRD,
            (a.gram.0 + g_bb + g_cc + 2.0 * (g_ab + g_ac + g_bc)) * (THIRD * THIRD),
        );
        self.add_point(fit, centre, area);
        for (lb, lc) in [(TWO_THIRDS, THIRD), (THIRD, TWO_THIRDS)] {
            let plane = b.plane * lb + c.plane * lc;
            let tangential = b.tangential * lb + c.tangential * lc;
            let length2 = lb * lb * g_bb + lc * lc * g_cc + 2.0 * lb * lc * g_bc;
            self.add_point(fit, (plane, tangential, length2), area);
        }
    }

    /// Adds the lattice point at plane coordinates `plane` whose interpolated normal
    /// has tangential components `tangential` and squared length `length2`, weighing
    /// `w`, where the splat covers it; a point where the corners' normals cancel
    /// (length 0) is left out.
    fn add_point(
        &self,
        fit: &mut FieldFit,
        (plane, tangential, length2): (DVec2, DVec2, f64),
        w: f64,
    ) {
        if !inside(plane, self.inv_ratio2) || length2 <= 0.0 {
            return;
        }
        let length = length2.sqrt();
        let t = DVec2::new(tangential.x / length, tangential.y / length);
        fit.add_terms(&terms(plane, t, w));
    }
}

/// Fits the colour field of the splat at `at` (major radius `r`, shape `shape`, normal
/// `normal`) over `triangles`, each as its three (position, RGB 0–1) with the splat's
/// vertex first, as [`fit_field`] fits the normals: [`color_field`] of the lattice
/// points inside the ellipse, each weighing its triangle's area.
pub fn fit_color_field(
    (at, normal): (DVec3, DVec3),
    (r, shape): (f64, &Shape),
    triangles: impl Iterator<Item = [(DVec3, DVec3); 3]>,
) -> Option<(DVec3, [DVec3; 2])> {
    let v = shape.minor_axis(normal);
    let points = triangles.flat_map(move |corners| {
        let [(_, ca), (_, cb), (_, cc)] = corners;
        covered_lattice((at, r, shape, v), corners.map(|c| c.0))
            .map(move |([l0, l1, l2], xy, area)| (xy, l0 * ca + l1 * cb + l2 * cc, area))
    });
    color_field(points)
}

/// The points of [`LATTICE`] in the triangle `corners` that the splat at `at` (major
/// radius `r`, `shape`, minor axis `v`) covers: (barycentric coordinates, plane
/// coordinates in major radii, the triangle's area as their weight). Plane coordinates
/// are linear in the barycentric ones, so only the corners are projected.
fn covered_lattice(
    (at, r, shape, v): (DVec3, f64, &Shape, DVec3),
    corners: [DVec3; 3],
) -> impl Iterator<Item = ([f64; 3], DVec2, f64)> + use<> {
    let (area, plane) = projected((at, r, (shape.axis, v)), corners);
    let inv_ratio2 = 1.0 / (shape.ratio * shape.ratio);
    LATTICE.into_iter().filter_map(move |l| {
        let xy = l[0] * plane[0] + l[1] * plane[1] + l[2] * plane[2];
        inside(xy, inv_ratio2).then_some((l, xy, area))
    })
}

/// The triangle `corners` as the splat at `at` (major radius `r`, axes `u`, `v`) sees
/// it: its area, and its corners' plane coordinates in major radii.
fn projected(
    (at, r, (u, v)): (DVec3, f64, (DVec3, DVec3)),
    corners: [DVec3; 3],
) -> (f64, [DVec2; 3]) {
    let [a, b, c] = corners;
    let area = 0.5 * (b - a).cross(c - a).length();
    let plane = corners.map(|p| DVec2::new((p - at).dot(u), (p - at).dot(v)) / r);
    (area, plane)
}

/// Whether the plane coordinates `xy` (in major radii) lie inside the ellipse of
/// minor over major 1/√`inv_ratio2`: x² + y² · inv_ratio2 < 1.
fn inside(xy: DVec2, inv_ratio2: f64) -> bool {
    xy.x * xy.x + xy.y * xy.y * inv_ratio2 < 1.0
}

/// An 8-bit RGBA colour's RGB as the fields see colours: 0–1.
pub fn unit_rgb(c: [u8; 4]) -> DVec3 {
    DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) / 255.0
}

/// The least squares of colour ≈ c₀ + cₓ x + c_y y over `points`, each (plane
/// coordinates in major radii, RGB, weight): (c₀, [cₓ, c_y]), or None where the points
/// do not span the plane.
pub fn color_field(
    points: impl Iterator<Item = (DVec2, DVec3, f64)>,
) -> Option<(DVec3, [DVec3; 2])> {
    // Σ w (1, x, y)ᵀ (1, x, y) and Σ w (1, x, y) colourᵀ.
    let (mut m, mut rhs) = (glam::DMat3::ZERO, glam::DMat3::ZERO);
    for (xy, colour, w) in points {
        let basis = DVec3::new(1.0, xy.x, xy.y) * w;
        m += glam::DMat3::from_cols(basis, basis * xy.x, basis * xy.y);
        rhs += glam::DMat3::from_cols(basis * colour.x, basis * colour.y, basis * colour.z);
    }
    let det = m.determinant();
    if det.abs() <= 1e-12 * m.x_axis.x.powi(3) || !det.is_finite() {
        return None;
    }
    // Column k of the solution holds (c₀, cₓ, c_y) of channel k.
    let sol = m.inverse() * rhs;
    let channel = |row: usize| DVec3::new(sol.x_axis[row], sol.y_axis[row], sol.z_axis[row]);
    let (c0, cx, cy) = (channel(0), channel(1), channel(2));
    (c0.is_finite() && cx.is_finite() && cy.is_finite()).then_some((c0, [cx, cy]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The field (c₁ + a x + b y, c₂ + b x + c y) at `d`.
    fn field(g: [f64; 3], c: DVec2, d: DVec2) -> DVec2 {
        c + DVec2::new(g[0] * d.x + g[1] * d.y, g[1] * d.x + g[2] * d.y)
    }

    #[test]
    fn the_fit_recovers_a_linear_field_and_its_intercept() {
        let (g, c) = ([0.3, -0.2, 0.7], DVec2::new(0.05, -0.02));
        let mut fit = FieldFit::default();
        for k in 0..40 {
            let d = DVec2::from_angle(k as f64 * 0.7) * (0.1 + 0.02 * k as f64);
            fit.add_terms(&terms(d, field(g, c, d), 1.0 + (k % 3) as f64));
        }
        let (got, offset) = fit.solve().unwrap();
        for k in 0..3 {
            assert!((got[k] - g[k]).abs() < 1e-5, "{got:?} against {g:?}");
        }
        assert!((offset - c).length() < 1e-6, "{offset} against {c}");
        assert!(FieldFit::default().solve().is_none());
    }

    /// A vertex's position and normal.
    type Vertex = (DVec3, DVec3);

    /// A flat hexagonal one-ring of unit edges in the plane z = 0 around the origin, its
    /// vertex normals tilted by `tilt` (x, y ↦ tangential components): its vertices
    /// (position, normal), the centre first, and its triangles' (next, previous).
    fn ring(tilt: impl Fn(DVec2) -> DVec2) -> (Vec<Vertex>, Vec<(u32, u32)>) {
        let at = |p: DVec2| {
            let t = tilt(p);
            (p.extend(0.0), DVec3::new(t.x, t.y, 1.0).normalize())
        };
        let corner = |k: usize| DVec2::from_angle(k as f64 * std::f64::consts::FRAC_PI_3);
        let vertices = std::iter::once(at(DVec2::ZERO))
            .chain((0..6).map(|k| at(corner(k))))
            .collect();
        let corners = (0..6).map(|k| (1 + k, 1 + (k + 1) % 6)).collect();
        (vertices, corners)
    }

    #[test]
    fn the_fan_s_shared_points_give_each_triangle_s_lattice_sums() {
        // Rings of 3 to 40 neighbours (more than the shared spokes hold), closed or
        // open, on a bumpy surface with scattered normals and ellipses that cover part
        // of them (proptest's seeded generator): the sums equal those of the ten
        // lattice points of every triangle, each weighing its area.
        use proptest::prelude::Rng;
        let mut rng = proptest::test_runner::TestRng::deterministic_rng(
            proptest::test_runner::RngAlgorithm::ChaCha,
        );
        let mut jitter = |scale: f64| (rng.random::<f64>() - 0.5) * scale;
        for count in 3..=40 {
            let closed = count % 3 != 0;
            let mut vertices: Vec<Vertex> = vec![(
                DVec3::new(jitter(0.1), jitter(0.1), jitter(0.1)),
                DVec3::new(jitter(0.4), jitter(0.4), 1.0).normalize(),
            )];
            for k in 0..count {
                let t = k as f64 * std::f64::consts::TAU / count as f64 + jitter(0.2);
                let p = DVec3::new(t.cos(), t.sin(), jitter(0.3)) * (1.0 + jitter(1.0));
                let n = DVec3::new(jitter(0.6), jitter(0.6), 1.0).normalize();
                vertices.push((p, n));
            }
            let triangles = if closed { count } else { count - 1 };
            let corners: Vec<(u32, u32)> = (0..triangles)
                .map(|k| (1 + k as u32, 1 + ((k + 1) % count) as u32))
                .collect();
            let shape = Shape::ellipse(
                DVec3::Z,
                DVec3::new(1.0, jitter(1.0), 0.0).normalize(),
                0.4 + jitter(0.4),
            );
            let (u, v) = (shape.axis, shape.minor_axis(DVec3::Z));
            let (at, r) = (DVec3::new(jitter(0.2), jitter(0.2), 0.0), 0.8 + jitter(0.6));
            let splat = Splat::new((at, r, (u, v), shape.ratio), vertices[0]);
            let at_vertex = |w: u32| vertices[w as usize];
            let shared = splat.fan_sums(at_vertex, corners.iter().copied());
            let mut each = FieldFit::default();
            let inv_ratio2 = 1.0 / (shape.ratio * shape.ratio);
            for &(b, c) in &corners {
                let fan = [vertices[0], at_vertex(b), at_vertex(c)];
                let (area, plane) = projected((at, r, (u, v)), fan.map(|q| q.0));
                for l in LATTICE {
                    let xy = l[0] * plane[0] + l[1] * plane[1] + l[2] * plane[2];
                    let n = l[0] * fan[0].1 + l[1] * fan[1].1 + l[2] * fan[2].1;
                    if inside(xy, inv_ratio2) {
                        let t = DVec2::new(n.dot(u), n.dot(v)) / n.length();
                        each.add_terms(&terms(xy, t, area));
                    }
                }
            }
            for (k, (a, b)) in shared.sums.iter().zip(&each.sums).enumerate() {
                let scale = each.sums[0].abs().max(1e-300);
                assert!(
                    (a - b).abs() <= 1e-12 * scale.max(b.abs()),
                    "{count} neighbours, sum {k}: {a} against {b}"
                );
            }
            assert!(each.sums[0] > 0.0, "some points are covered");
        }
    }

    #[test]
    fn a_field_the_triangles_interpolate_is_kept_and_a_peak_is_lowered() {
        let shape = Shape::circle(DVec3::Z);
        let fitted = |tilt: &dyn Fn(DVec2) -> DVec2| {
            let (vertices, corners) = ring(tilt);
            let at = |w: u32| vertices[w as usize];
            fit_field(at(0), (1.0, &shape), (at(0), at), corners.into_iter()).unwrap()
        };
        // Normals of a sphere of radius 50 seen near its pole: the fit keeps the
        // centre's normal and finds the shape operator 1/50 (per radius of 1).
        let (normal, s) = fitted(&|p| p / 50.0);
        assert!(normal.angle_between(DVec3::Z) < 1e-4, "{normal}");
        assert!((s.gradient[0] - 0.02).abs() < 1e-3 && s.gradient[1].abs() < 1e-3);
        // A vertex whose normal alone tilts (a scanner's ridge): the mesh blends it
        // away from the vertex, so the fitted centre tilts less than the vertex does.
        let (normal, _) = fitted(&|p| {
            if p == DVec2::ZERO {
                DVec2::new(0.1, 0.0)
            } else {
                DVec2::ZERO
            }
        });
        let (tilted, vertex) = (normal.x.atan2(normal.z), 0.1f64.atan());
        assert!(
            tilted > 0.0 && tilted < 0.6 * vertex,
            "{tilted} rad against {vertex}"
        );
    }
}
