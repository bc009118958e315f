//! Node disks and errors (docs/design.md §3–4; Dachsbacher, Vogelgsang, Stamminger 2003).
//!
//! For a node with children (pᵢ, nᵢ, rᵢ), area weights aᵢ = rᵢ²:
//!
//! * disk: p = Σ aᵢ pᵢ / Σ aᵢ; n = normalize(Σ aᵢ nᵢ) (if that vanishes, the normal of
//!   the children centres' best-fit plane); colour = Σ aᵢ cᵢ / Σ aᵢ;
//!   r = maxᵢ(|pᵢ − p| + rᵢ), so the disk reaches every child disk.
//!
//! The error terms see each child as its splat: the ellipse of major semi-axis rᵢ along
//! uᵢ (unit, ⟂ nᵢ) and minor semi-axis ratioᵢ rᵢ along vᵢ = nᵢ × uᵢ ([`Splat`]; the
//! disk when ratioᵢ = 1), whose half-width along a unit direction d (its support) is
//! hᵢ(d) = rᵢ √((uᵢ·d)² + ratioᵢ² (vᵢ·d)²), rᵢ √(1 − (nᵢ·d)²) for the disk.
//!
//! * perpendicular error: the thickness along n of the slab holding all child splats,
//!   e_p = maxᵢ[(pᵢ − p)·n + hᵢ(n)] − minᵢ[(pᵢ − p)·n − hᵢ(n)] (hᵢ(n) is how far a
//!   tilted child reaches out of its own plane along n).
//! * tangential error: how far the parent's splat (its ellipse, `parent_shape`)
//!   overhangs its children in its own plane, e_t = max(0, max_t [h(t) − maxᵢ((pᵢ −
//!   p)·t + hᵢ(t))]) over [`DIRECTIONS`] unit directions t of the tangent plane, from
//!   its major axis. Seen as disks, a fan of a terrain's needles from a tree's top
//!   (`surfel::terrain`) reached a crown's width sideways, and a parent as wide as the
//!   crown overhung them by nothing: level of detail drew blobs over the spires.
//! * e = √(e_p² + e_t²), then e = max(e, maxᵢ eᵢ): errors never shrink toward the root.
//!   Leaves have e = 0.
//!
//! Unoriented normals (point clouds) are first flipped to agree with the first child's,
//! so that opposite signs of one surface do not cancel.

use glam::{DVec2, DVec3, Vec3};

use crate::surfel::pca::plane_normal;

/// Tangent directions sampled for e_t: every 360°/16, which includes ±u, ±v and the
/// diagonals of the tangent basis (u = `n.any_orthonormal_vector()`, v = n × u).
pub const DIRECTIONS: usize = 16;

/// A disk as the error terms see it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Disk {
    pub p: DVec3,
    pub n: DVec3,
    pub r: f64,
}

/// The parent disk of `children` (area-weighted) and its averaged colour.
pub fn parent_disk(children: &[Disk], colors: &[[u8; 4]], oriented: bool) -> (Disk, [u8; 4]) {
    let n0 = children[0].n;
    let (mut wsum, mut psum, mut nsum, mut csum) = (0.0, DVec3::ZERO, DVec3::ZERO, [0.0f64; 4]);
    for (c, col) in children.iter().zip(colors) {
        let a = c.r * c.r;
        wsum += a;
        psum += c.p * a;
        let n = if !oriented && c.n.dot(n0) < 0.0 {
            -c.n
        } else {
            c.n
        };
        nsum += n * a;
        for k in 0..4 {
            csum[k] += col[k] as f64 * a;
        }
    }
    // Radii are > 0, so wsum > 0; guard anyway against a degenerate input.
    let w = if wsum > 0.0 { wsum } else { 1.0 };
    let p = if wsum > 0.0 {
        psum / w
    } else {
        children.iter().map(|c| c.p).sum::<DVec3>() / children.len() as f64
    };
    let n = nsum
        .try_normalize()
        .unwrap_or_else(|| plane_normal(children.iter().map(|c| c.p.as_vec3())).as_dvec3());
    let r = children
        .iter()
        .map(|c| (c.p - p).length() + c.r)
        .fold(0.0, f64::max);
    let color = csum.map(|s| (s / w).round().clamp(0.0, 255.0) as u8);
    (Disk { p, n, r }, color)
}

/// A node's splat as the error terms see it: its disk (the radius is the ellipse's
/// major semi-axis), the major axis (unit, ⟂ the disk's normal) and minor / major ratio.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Splat {
    pub disk: Disk,
    pub axis: DVec3,
    pub ratio: f64,
}

impl Splat {
    /// The splat that is its disk.
    pub fn round(disk: Disk) -> Splat {
        Splat {
            disk,
            axis: disk.n.any_orthonormal_vector(),
            ratio: 1.0,
        }
    }

    /// The major axis u and the minor one scaled by the ratio, ratio · (n × u): the
    /// support along d is r |(u·d, w·d)|.
    fn axes(&self) -> (DVec3, DVec3) {
        (self.axis, self.disk.n.cross(self.axis) * self.ratio)
    }

    /// Its half-width along the unit direction `d` (the module doc's hᵢ(d)).
    fn extent(&self, d: DVec3) -> f64 {
        let (u, w) = self.axes();
        self.disk.r * DVec2::new(u.dot(d), w.dot(d)).length()
    }
}

/// Perpendicular error e_p of `parent` over `children`.
pub fn perpendicular_error(parent: &Disk, children: &[Splat]) -> f64 {
    let (mut top, mut bottom) = (f64::NEG_INFINITY, f64::INFINITY);
    for c in children {
        let h = (c.disk.p - parent.p).dot(parent.n);
        let d = c.extent(parent.n);
        top = top.max(h + d);
        bottom = bottom.min(h - d);
    }
    (top - bottom).max(0.0)
}

/// Tangential error e_t of `parent` over `children`.
///
/// Each child's reach along the sampled directions is taken in columns, one lane per
/// direction: with a = (pᵢ − p), x = the major axis, y = the minor one scaled by the
/// ratio, all in the parent's tangent basis (u, v), its reach along t = u cos θ + v sin θ
/// is a·t + rᵢ |(x·t, y·t)|.
pub fn tangential_error(parent: &Splat, children: &[Splat]) -> f64 {
    let (u, v) = (parent.axis, parent.disk.n.cross(parent.axis));
    let basis = |d: DVec3| DVec2::new(d.dot(u), d.dot(v));
    let mut reach = [f64::NEG_INFINITY; DIRECTIONS];
    for c in children {
        let (major, minor) = c.axes();
        let (a, x, y) = (basis(c.disk.p - parent.disk.p), basis(major), basis(minor));
        for (t, reach) in reach.iter_mut().enumerate() {
            let (cos, sin) = (DIRECTION_COS[t], DIRECTION_SIN[t]);
            let (xt, yt) = (x.x * cos + x.y * sin, y.x * cos + y.y * sin);
            let along = a.x * cos + a.y * sin + c.disk.r * (xt * xt + yt * yt).sqrt();
            *reach = reach.max(along);
        }
    }
    // The parent's support along t: r |(cos θ, ratio sin θ)|.
    let (r, ratio) = (parent.disk.r, parent.ratio);
    let mut worst = 0.0f64;
    for (t, reach) in reach.iter().enumerate() {
        let (x, y) = (DIRECTION_COS[t], ratio * DIRECTION_SIN[t]);
        worst = worst.max(r * (x * x + y * y).sqrt() - reach);
    }
    worst
}

/// (cos θ, sin θ) of the sampled directions θ = k · 360° / [`DIRECTIONS`], exact at the
/// axes and diagonals.
const DIRECTION_TABLE: [(f64, f64); DIRECTIONS] = {
    const H: f64 = std::f64::consts::FRAC_1_SQRT_2;
    const C1: f64 = 0.923_879_532_511_286_7; // cos 22.5°
    const S1: f64 = 0.382_683_432_365_089_8; // sin 22.5°
    [
        (1.0, 0.0),
        (C1, S1),
        (H, H),
        (S1, C1),
        (0.0, 1.0),
        (-S1, C1),
        (-H, H),
        (-C1, S1),
        (-1.0, 0.0),
        (-C1, -S1),
        (-H, -H),
        (-S1, -C1),
        (0.0, -1.0),
        (S1, -C1),
        (H, -H),
        (C1, -S1),
    ]
};

/// The table's cosines, in a column.
pub(super) const DIRECTION_COS: [f64; DIRECTIONS] = direction_column(0);
/// The table's sines, in a column.
pub(super) const DIRECTION_SIN: [f64; DIRECTIONS] = direction_column(1);

/// Column `which` (0: cos, 1: sin) of [`DIRECTION_TABLE`].
const fn direction_column(which: usize) -> [f64; DIRECTIONS] {
    let mut column = [0.0; DIRECTIONS];
    let mut k = 0;
    while k < DIRECTIONS {
        let (cos, sin) = DIRECTION_TABLE[k];
        column[k] = if which == 0 { cos } else { sin };
        k += 1;
    }
    column
}

/// The node error before the max over children: √(e_p² + e_t²).
pub fn node_error(parent: &Splat, children: &[Splat]) -> f64 {
    let (p, t) = (
        perpendicular_error(&parent.disk, children),
        tangential_error(parent, children),
    );
    // Not f64::hypot (several times slower): the terms are far from overflow.
    (p * p + t * t).sqrt()
}

impl Disk {
    pub fn new(p: Vec3, n: Vec3, r: f32) -> Self {
        Disk {
            p: p.as_dvec3(),
            n: n.as_dvec3(),
            r: r as f64,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const Z: DVec3 = DVec3::Z;

    fn disk(p: [f64; 3], n: DVec3, r: f64) -> Disk {
        Disk {
            p: DVec3::from(p),
            n,
            r,
        }
    }

    fn round(disks: &[Disk]) -> Vec<Splat> {
        disks.iter().copied().map(Splat::round).collect()
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * (1.0 + a.abs().max(b.abs()))
    }

    #[test]
    fn coplanar_children_error_comes_from_tilt_only() {
        let parent = disk([0.0; 3], Z, 2.0);
        // Flat children in the parent plane: no thickness at all.
        let flat = [
            disk([-1.0, 0.0, 0.0], Z, 1.0),
            disk([1.0, 0.0, 0.0], Z, 1.0),
        ];
        assert_eq!(perpendicular_error(&parent, &round(&flat)), 0.0);
        // One child tilted by 30°: it reaches r sin 30° above and below the plane.
        let tilt = 30f64.to_radians();
        let tilted = DVec3::new(tilt.sin(), 0.0, tilt.cos());
        let children = [
            disk([-1.0, 0.0, 0.0], Z, 1.0),
            disk([1.0, 0.0, 0.0], tilted, 0.8),
        ];
        let want = 2.0 * 0.8 * tilt.sin();
        assert!(close(perpendicular_error(&parent, &round(&children)), want));
    }

    #[test]
    fn children_at_plus_minus_h_give_2h_plus_their_disk_terms() {
        let h = 0.25;
        let parent = disk([0.0; 3], Z, 2.0);
        let flat = [disk([0.0, -1.0, h], Z, 1.0), disk([0.0, 1.0, -h], Z, 1.0)];
        assert!(close(perpendicular_error(&parent, &round(&flat)), 2.0 * h));
        // Tilted children add d = r √(1 − (n·Z)²) above the upper and below the lower one.
        let a = 0.4f64;
        let n1 = DVec3::new(0.0, a.sin(), a.cos());
        let n2 = DVec3::new(a.sin(), 0.0, a.cos());
        let children = [disk([0.0, -1.0, h], n1, 1.0), disk([0.0, 1.0, -h], n2, 0.5)];
        let want = 2.0 * h + 1.0 * a.sin() + 0.5 * a.sin();
        assert!(close(perpendicular_error(&parent, &round(&children)), want));
    }

    #[test]
    fn parent_reaching_past_its_children_on_one_side_gives_that_overhang() {
        // Children span x ∈ [−2, 2] (and y ∈ [−1, 1]); a parent disk of radius 3 centred
        // at x = 0.5 reaches x = 3.5 on the +x side: 1.5 past the children. Along −x it
        // reaches −2.5, 0.5 past; along ±y it reaches 3 against 1. The worst is y: 2.
        let children = [
            disk([-1.0, 0.0, 0.0], Z, 1.0),
            disk([1.0, 0.0, 0.0], Z, 1.0),
        ];
        let parent = disk([0.5, 0.0, 0.0], Z, 3.0);
        assert!(close(
            tangential_error(&Splat::round(parent), &round(&children)),
            2.0
        ));
        // A parent that is exactly the children's hull along x and y: a long child and
        // a parent of its size, shifted by s along x: overhang s on one side only.
        let s = 0.3;
        let one = [disk([0.0, 0.0, 0.0], Z, 1.0)];
        let shifted = disk([s, 0.0, 0.0], Z, 1.0);
        // Sampled directions include ±x: the overhang along +x is exactly s.
        assert!(close(
            tangential_error(&Splat::round(shifted), &round(&one)),
            s
        ));
        // Five children (more than the hierarchy makes) take the general path.
        let five: Vec<Disk> = (0..5)
            .map(|i| disk([i as f64 - 2.0, 0.0, 0.0], Z, 0.5))
            .collect();
        let hull = disk([0.0, 0.0, 0.0], Z, 2.5);
        assert!(
            close(tangential_error(&Splat::round(hull), &round(&five)), 2.0),
            "along ±y: 2.5 − 0.5"
        );
        // And the same disk overhangs nothing.
        assert_eq!(tangential_error(&Splat::round(one[0]), &round(&one)), 0.0);
    }

    #[test]
    fn thin_children_leave_the_parent_s_overhang_across_them() {
        // Two needles along x, 0.1 wide, 4 long, end to end: a parent disk of radius 4
        // reaches ±4 along y, where they reach ±0.1 (as disks, ±2: overhang 2).
        let needle = |x: f64| Splat {
            disk: disk([x, 0.0, 0.0], Z, 2.0),
            axis: DVec3::X,
            ratio: 0.05,
        };
        let children = [needle(-2.0), needle(2.0)];
        let parent = disk([0.0; 3], Z, 4.0);
        assert!(close(
            tangential_error(&Splat::round(parent), &children),
            3.9
        ));
        let disks = children.map(|c| Splat::round(c.disk));
        assert!(close(tangential_error(&Splat::round(parent), &disks), 2.0));
        // Stood up about their axis (normal y), they are 0.1 thick along z, not 2.
        let standing = children.map(|c| Splat {
            disk: Disk {
                n: DVec3::Y,
                ..c.disk
            },
            ..c
        });
        assert!(close(perpendicular_error(&parent, &standing), 0.2));
        // A parent that is their ellipse, 0.1 wide: next to no overhang.
        let along = Splat {
            disk: parent,
            axis: DVec3::X,
            ratio: 0.025,
        };
        assert!(tangential_error(&along, &children) < 1e-3);
    }

    #[test]
    fn parent_disk_reaches_every_child_and_errors_are_finite() {
        let children = [
            disk([0.0, 0.0, 0.0], Z, 1.0),
            disk([3.0, 0.0, 0.1], DVec3::new(0.0, 0.6, 0.8), 0.5),
            disk([0.0, 2.0, -0.2], -Z, 0.25),
        ];
        let colors = [[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 255]];
        for oriented in [true, false] {
            let (p, _) = parent_disk(&children, &colors, oriented);
            for c in &children {
                assert!((c.p - p.p).length() + c.r <= p.r + 1e-12);
            }
            let e = node_error(&Splat::round(p), &round(&children));
            assert!(e.is_finite() && e >= 0.0);
        }
        // Oriented normals that cancel fall back to the centres' plane.
        let opposite = [
            disk([0.0, 0.0, 0.0], Z, 1.0),
            disk([1.0, 0.0, 0.0], -Z, 1.0),
        ];
        let (p, _) = parent_disk(&opposite, &colors[..2], true);
        assert!((p.n.length() - 1.0).abs() < 1e-9);
        let (p, _) = parent_disk(&opposite, &colors[..2], false);
        assert!(close(p.n.z.abs(), 1.0), "unoriented: flipped to agree");
    }
}
