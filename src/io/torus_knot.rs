//! The project's generated test model: a bumpy, coloured (2,3) torus knot tube, the
//! default model of `data/` (`tools/gen_model.rs` writes it). Being analytic, it can be
//! sampled as densely as a test needs: a denser sampling is the surface that the
//! default model's triangles approximate.
//!
//! The tube has `segments` rings of `sides` vertices; each quad of the grid is split in
//! two triangles and the grid wraps both ways, so the mesh is closed:
//! vertices = segments · sides, triangles = 2 · vertices.

use std::f64::consts::TAU;

use glam::DVec3;

use crate::io::ply::{FaceList, PolyMesh};

/// Centre line of the (p, q) = (2, 3) torus knot.
fn knot(t: f64) -> DVec3 {
    let r = 2.0 + (3.0 * t).cos();
    DVec3::new(r * (2.0 * t).cos(), r * (2.0 * t).sin(), -(3.0 * t).sin())
}

/// HSV (h in turns) to 8-bit RGB.
fn hsv(h: f64, s: f64, v: f64) -> [u8; 3] {
    let f = |n: f64| {
        let k = (n + h * 6.0).rem_euclid(6.0);
        v - v * s * k.min(4.0 - k).clamp(0.0, 1.0)
    };
    [f(5.0), f(3.0), f(1.0)].map(|c| (c * 255.0).round() as u8)
}

/// The closed mesh of `segments` rings of `sides` vertices round the bumpy tube (see
/// the module doc), with colours if asked.
pub fn torus_knot(segments: u32, sides: u32, colors: bool) -> PolyMesh {
    let (nu, nv) = (segments as usize, sides as usize);
    let mut positions = Vec::with_capacity(nu * nv);
    let mut rgb = Vec::with_capacity(if colors { nu * nv } else { 0 });
    let h = 1e-4;
    for i in 0..nu {
        let u = i as f64 / nu as f64;
        let t = u * TAU;
        let c = knot(t);
        // Frenet frame from central differences: the knot's curvature never vanishes.
        // (x / |x| rather than glam's x · (1 / |x|): data/torus_knot.ply keeps its bytes.)
        let unit = |x: DVec3| x / x.length();
        let tangent = unit(knot(t + h) - knot(t - h));
        let accel = (knot(t + h) - c) - (c - knot(t - h));
        let binormal = unit(tangent.cross(accel));
        let normal = binormal.cross(tangent);
        for j in 0..nv {
            let v = j as f64 / nv as f64;
            let a = v * TAU;
            // Tube radius with bumps: 12 × 60 bumps over the surface.
            let bump = (a * 6.0).sin() * (t * 60.0).sin();
            let radius = 0.45 * (1.0 + 0.12 * bump);
            let (ca, sa) = (a.cos(), a.sin());
            positions.push((c + radius * (ca * normal + sa * binormal)).to_array());
            if colors {
                rgb.push(hsv(u * 3.0, 0.55 + 0.25 * bump, 0.75 + 0.2 * bump));
            }
        }
    }
    let mut faces = FaceList::default();
    for i in 0..nu {
        for j in 0..nv {
            let at = |di: usize, dj: usize| (((i + di) % nu) * nv + (j + dj) % nv) as u32;
            faces.push(&[at(0, 0), at(1, 0), at(1, 1)]);
            faces.push(&[at(0, 0), at(1, 1), at(0, 1)]);
        }
    }
    PolyMesh {
        positions,
        normals: None,
        colors: colors.then_some(rgb),
        faces,
    }
}
