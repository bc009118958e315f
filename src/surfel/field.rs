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
/// shape `shape`) over `triangles`, each as its three (position, normal) with the
/// splat's vertex first; returns the new normal and shape, or None where the fit is
/// undetermined (the one-ring fit stays). Positions and `r` in one unit.
pub fn fit_field(
    (at, normal): (DVec3, DVec3),
    (r, shape): (f64, &Shape),
    triangles: impl Iterator<Item = [(DVec3, DVec3); 3]>,
) -> Option<(DVec3, Shape)> {
    let (u, v) = (shape.axis, shape.minor_axis(normal));
    let mut fit = FieldFit::default();
    let splat = (at, r, shape.ratio, (u, v));
    for corners in triangles {
        add_lattice(&mut fit, splat, corners);
    }
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

/// Lanes of a triangle's lattice in columns ([`LATTICE_COLUMNS`]): its 10 points and
/// two of (0, 0, 0), three 4-wide vectors. In columns, a generated city tile of 20 M
/// samples (`gen_cloud --points 20000000 --size 1265`) took 32.0–32.4 s in the
/// surfels stage against 34.8–35.1 s a point at a time (2 cores, 2026-11-29,
/// alternated; the same sums in the same order, the same file).
const LANES: usize = 12;

/// [`LATTICE`] by barycentric coordinate, padded to [`LANES`] with (0, 0, 0): the
/// interpolated normal there has length 0, so that such a point never counts.
const LATTICE_COLUMNS: [[f64; LANES]; 3] = {
    let mut columns = [[0.0; LANES]; 3];
    let mut k = 0;
    while k < LATTICE.len() {
        let mut c = 0;
        while c < 3 {
            columns[c][k] = LATTICE[k][c];
            c += 1;
        }
        k += 1;
    }
    columns
};

/// Adds to `fit` the points of [`LATTICE`] in the triangle `corners` (position, vertex
/// normal) that the splat at `at` covers (major radius `r`, minor over major `ratio`,
/// axes `u`, `v`: ρ² = x² + y²/ratio² < 1 in major radii), each weighing the
/// triangle's area, with the tangential components of the interpolated normal there;
/// a point where the corners' normals cancel is left out. Worked out for all
/// [`LANES`] in columns, then added in the lattice's order.
fn add_lattice(
    fit: &mut FieldFit,
    (at, r, ratio, (u, v)): (DVec3, f64, f64, (DVec3, DVec3)),
    corners: [(DVec3, DVec3); 3],
) {
    let [(a, na), (b, nb), (c, nc)] = corners;
    let (area, plane) = projected((at, r, (u, v)), [a, b, c]);
    // Tangential normal components are linear in the barycentric coordinates; the
    // interpolated normal's length is √(λᵀ Gram λ).
    let tangential = [na, nb, nc].map(|n| DVec2::new(n.dot(u), n.dot(v)));
    let gram = [
        na.dot(na),
        nb.dot(nb),
        nc.dot(nc),
        na.dot(nb),
        na.dot(nc),
        nb.dot(nc),
    ];
    let inv_ratio2 = 1.0 / (ratio * ratio);
    let [l0, l1, l2] = &LATTICE_COLUMNS;
    let linear = |k: usize, f: &dyn Fn(DVec2) -> f64, at: &[DVec2; 3]| {
        l0[k] * f(at[0]) + l1[k] * f(at[1]) + l2[k] * f(at[2])
    };
    let (mut x, mut y, mut tx, mut ty, mut kept) = (
        [0.0; LANES],
        [0.0; LANES],
        [0.0; LANES],
        [0.0; LANES],
        [false; LANES],
    );
    for k in 0..LANES {
        x[k] = linear(k, &|p| p.x, &plane);
        y[k] = linear(k, &|p| p.y, &plane);
        let length2 = l0[k] * l0[k] * gram[0]
            + l1[k] * l1[k] * gram[1]
            + l2[k] * l2[k] * gram[2]
            + 2.0 * (l0[k] * l1[k] * gram[3] + l0[k] * l2[k] * gram[4] + l1[k] * l2[k] * gram[5]);
        let length = length2.sqrt();
        tx[k] = linear(k, &|t| t.x, &tangential) / length;
        ty[k] = linear(k, &|t| t.y, &tangential) / length;
        let covered = inside(DVec2::new(x[k], y[k]), inv_ratio2);
        // Only where the normals cancel (length 0) is a covered point left out.
        kept[k] = covered && (length2 > 0.0 || length2.is_nan());
    }
    for k in (0..LANES).filter(|&k| kept[k]) {
        fit.add_terms(&terms(
            DVec2::new(x[k], y[k]),
            DVec2::new(tx[k], ty[k]),
            area,
        ));
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

    /// A flat hexagonal one-ring of unit edges in the plane z = 0 around the origin, its
    /// vertex normals tilted by `tilt` (x, y ↦ tangential components).
    fn ring(tilt: impl Fn(DVec2) -> DVec2) -> Vec<[(DVec3, DVec3); 3]> {
        let at = |p: DVec2| {
            let t = tilt(p);
            (p.extend(0.0), DVec3::new(t.x, t.y, 1.0).normalize())
        };
        let corner = |k: usize| DVec2::from_angle(k as f64 * std::f64::consts::FRAC_PI_3);
        (0..6)
            .map(|k| [at(DVec2::ZERO), at(corner(k)), at(corner(k + 1))])
            .collect()
    }

    #[test]
    fn a_field_the_triangles_interpolate_is_kept_and_a_peak_is_lowered() {
        let shape = Shape::circle(DVec3::Z);
        let fitted = |tilt: &dyn Fn(DVec2) -> DVec2| {
            let triangles = ring(tilt);
            let centre = triangles[0][0];
            fit_field(centre, (1.0, &shape), triangles.into_iter()).unwrap()
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
