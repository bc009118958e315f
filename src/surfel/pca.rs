//! Principal axes of a point neighbourhood, for normals of point clouds.

use glam::{DMat3, DVec3, Vec3};

/// Eigen-decomposition of a symmetric 3×3 matrix by cyclic Jacobi rotations.
/// Returns (eigenvalues, eigenvectors as columns), unsorted. Exact for diagonal input,
/// converges for any finite symmetric input (including the zero matrix).
pub fn symmetric_eigen(m: DMat3) -> (DVec3, DMat3) {
    let mut a = m.to_cols_array_2d();
    let mut v = DMat3::IDENTITY.to_cols_array_2d();
    for _sweep in 0..32 {
        let off = a[0][1].powi(2) + a[0][2].powi(2) + a[1][2].powi(2);
        let diag = a[0][0].powi(2) + a[1][1].powi(2) + a[2][2].powi(2);
        if off <= 1e-30 * diag || off == 0.0 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            // Rotation angle that zeroes a[p][q]: tan(2θ) = 2 a_pq / (a_qq − a_pp).
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for row in &mut a {
                let (akp, akq) = (row[p], row[q]);
                row[p] = c * akp - s * akq;
                row[q] = s * akp + c * akq;
            }
            let (rp, rq) = (a[p], a[q]);
            a[p] = std::array::from_fn(|k| c * rp[k] - s * rq[k]);
            a[q] = std::array::from_fn(|k| s * rp[k] + c * rq[k]);
            for row in &mut v {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    // `v` was stored as rows of the column-major array: transpose back to columns.
    let vecs = DMat3::from_cols_array_2d(&v).transpose();
    (DVec3::new(a[0][0], a[1][1], a[2][2]), vecs)
}

/// The scatter matrix of `points` about their mean, Σ (p − p̄)(p − p̄)ᵀ, in f64 (their
/// covariance times their count); `None` for no point.
pub fn scatter_matrix(points: impl Iterator<Item = Vec3> + Clone) -> Option<DMat3> {
    let (sum, n) = points
        .clone()
        .fold((DVec3::ZERO, 0usize), |(s, n), p| (s + p.as_dvec3(), n + 1));
    if n == 0 {
        return None;
    }
    let mean = sum / n as f64;
    // The six distinct sums, each added point by point as the full matrix's entry
    // would be (products commute exactly): xx, xy, xz, yy, yz, zz.
    let mut s = [0.0; 6];
    for p in points {
        let d = p.as_dvec3() - mean;
        let products = [
            d.x * d.x,
            d.x * d.y,
            d.x * d.z,
            d.y * d.y,
            d.y * d.z,
            d.z * d.z,
        ];
        for (sum, product) in s.iter_mut().zip(products) {
            *sum += product;
        }
    }
    Some(DMat3::from_cols(
        DVec3::new(s[0], s[1], s[2]),
        DVec3::new(s[1], s[3], s[4]),
        DVec3::new(s[2], s[4], s[5]),
    ))
}

/// Unit normal of the best-fit plane of `points`: the eigenvector of the smallest
/// eigenvalue of their covariance. Any unit vector when the points do not span a plane
/// direction uniquely (e.g. all identical); never NaN.
pub fn plane_normal(points: impl Iterator<Item = Vec3> + Clone) -> Vec3 {
    let Some(cov) = scatter_matrix(points) else {
        return Vec3::Z;
    };
    let cov = unit_scaled(cov);
    if let Some(n) = least_axis(cov) {
        return n.as_vec3();
    }
    let (values, vectors) = symmetric_eigen(cov);
    let k = (0..3)
        .min_by(|&i, &j| values[i].total_cmp(&values[j]))
        .unwrap_or(2);
    vectors.col(k).as_vec3().try_normalize().unwrap_or(Vec3::Z)
}

/// `m` times the power of two that brings its largest entry's magnitude near 1 (in
/// [0.5, 4)): exact, so its eigenvectors are the same bits, while the products of
/// products that [`least_axis`] forms neither underflow nor overflow (a neighbourhood
/// 10⁻³⁹ across has a scatter of 10⁻⁷⁸ and rows' cross products of 10⁻³¹², below f64's
/// normal range, whose normalising then missed unit length by 0.5 %). Unchanged where
/// `m` is zero or not finite.
pub fn unit_scaled(m: DMat3) -> DMat3 {
    let largest = (m.to_cols_array().iter()).fold(0.0f64, |a, x| a.max(x.abs()));
    if !(largest > 0.0 && largest.is_finite()) {
        return m;
    }
    // In two factors: 2^e alone leaves f64's range where `largest` is subnormal.
    let e = -largest.log2().floor() as i32;
    m * 2f64.powi(e / 2) * 2f64.powi(e - e / 2)
}

/// Whether every eigenvalue of the symmetric `m` exceeds `t`: m − tI is positive
/// definite, which Sylvester's criterion reads from its leading principal minors
/// (no root, no trigonometry). False where m has a NaN.
pub fn eigenvalues_exceed(m: DMat3, t: f64) -> bool {
    let shifted = m - DMat3::from_diagonal(DVec3::splat(t));
    let (a, b) = (shifted.x_axis, shifted.y_axis);
    let leading = a.x * b.y - a.y * b.x;
    a.x > 0.0 && leading > 0.0 && shifted.determinant() > 0.0
}

/// The trigonometric solution of a symmetric 3×3 matrix's characteristic cubic (Smith
/// 1961): with q the mean of the diagonal and p² = ‖m − qI‖²_F / 6, the eigenvalues are
/// q + 2p cos(φ + 2πk/3), k = 0, 1, 2, with φ = acos(det((m − qI) / p) / 2) / 3; k = 1
/// gives the least.
struct Cubic {
    least: f64,
    /// ‖m − qI‖²_F = 6 p².
    p2: f64,
}

impl Cubic {
    /// None where p is 0 (m a multiple of I) or NaN.
    fn of(m: DMat3) -> Option<Cubic> {
        let (a, b, c) = (m.x_axis, m.y_axis, m.z_axis);
        let off = a.y * a.y + a.z * a.z + b.z * b.z;
        let q = (a.x + b.y + c.z) / 3.0;
        let p2 = (a.x - q).powi(2) + (b.y - q).powi(2) + (c.z - q).powi(2) + 2.0 * off;
        let p = (p2 / 6.0).sqrt();
        if p.is_nan() || p <= 0.0 {
            return None;
        }
        let shifted = (m - DMat3::from_diagonal(DVec3::splat(q))) * (1.0 / p);
        let phi = (shifted.determinant() / 2.0).clamp(-1.0, 1.0).acos() / 3.0;
        let least = q + 2.0 * p * (phi + 2.0 * std::f64::consts::FRAC_PI_3).cos();
        Some(Cubic { least, p2 })
    }
}

/// The unit eigenvector of the least eigenvalue of the symmetric `m` in closed form,
/// a quarter of [`symmetric_eigen`]'s time: λ from the trigonometric solution of the
/// characteristic cubic (Smith 1961), the vector as the longest cross product of two
/// rows of m − λI (their common orthogonal). `None` where that is ill-conditioned: the
/// least eigenvalue is (nearly) double, or m is (nearly) a multiple of I.
pub fn least_axis(m: DMat3) -> Option<DVec3> {
    let Cubic { least, p2 } = Cubic::of(m)?;
    // m is symmetric: the columns of m − λI are its rows.
    let rows = m - DMat3::from_diagonal(DVec3::splat(least));
    let (r0, r1, r2) = (rows.x_axis, rows.y_axis, rows.z_axis);
    let best = [r0.cross(r1), r0.cross(r2), r1.cross(r2)]
        .into_iter()
        .max_by(|x, y| x.length_squared().total_cmp(&y.length_squared()))?;
    // Rows of m − λI of rank 2 have a cross product of the order of p²; one of rank ≤ 1
    // (a double least eigenvalue) only rounding's.
    (best.length_squared() > 1e-16 * p2 * p2).then(|| best.normalize())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plane_of_tiny_or_huge_spacing_gets_a_unit_normal() {
        // A tilted square of points: a unit normal at every scale f32 holds, the same
        // one down to subnormal spacings (at 10⁻⁴⁴, three bits a coordinate, the
        // square's own tilt is rounded), and the scaling by a power of two changes no
        // bit of the fit.
        let square = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.5],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.5],
        ];
        let at = |s: f32| square.map(|p| Vec3::from_array(p) * s);
        let unit = plane_normal(at(1.0).into_iter());
        for s in [1e-44f32, 1e-39, 1e-30, 1e-10, 0.75, 1e10, 1e30] {
            let n = plane_normal(at(s).into_iter());
            assert!(
                (n.length() - 1.0).abs() < 1e-6,
                "scale {s}: {n} of length {}",
                n.length()
            );
            let same = n.abs_diff_eq(unit, 1e-6) || n.abs_diff_eq(-unit, 1e-6);
            assert!(same || s < 1e-40, "scale {s}: {n}");
        }
        // A fuzzed PLY's four samples (two at the origin), whose normal had length 0.995.
        let fuzzed = [
            [0.0; 3],
            [0.0; 3],
            [5.639e-39, 0.0, 0.0],
            [4.2e-45, 4.2e-45, 1.076e-42],
        ];
        let n = plane_normal(fuzzed.map(Vec3::from_array).into_iter());
        assert!(
            (n.length() - 1.0).abs() < 1e-6,
            "{n} of length {}",
            n.length()
        );
        let m = DMat3::from_cols_array_2d(&[[4.0, 1.0, -2.0], [1.0, 2.0, 0.5], [-2.0, 0.5, 3.0]]);
        for k in [-600, -3, 0, 5, 600] {
            let scaled = m * 2f64.powi(k / 2) * 2f64.powi(k - k / 2);
            assert_eq!(least_axis(unit_scaled(scaled)), least_axis(m), "2^{k}");
        }
    }

    #[test]
    fn eigenvalues_exceed_a_bound_as_jacobi_s_do() {
        let cases = [
            [[4.0, 1.0, -2.0], [1.0, 2.0, 0.5], [-2.0, 0.5, 3.0]],
            [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1e-9]],
            [[2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]],
            [[0.0; 3]; 3],
        ];
        for case in cases {
            let m = DMat3::from_cols_array_2d(&case);
            let least = symmetric_eigen(m).0.min_element();
            for t in [-1.0, 0.0, 0.5 * least, least - 1e-6, least + 1e-6, 10.0] {
                assert_eq!(eigenvalues_exceed(m, t), least > t, "{case:?} against {t}");
            }
        }
        assert!(!eigenvalues_exceed(
            DMat3::from_diagonal(DVec3::splat(f64::NAN)),
            0.0
        ));
    }

    #[test]
    fn eigen_reconstructs_matrix() {
        let m = DMat3::from_cols_array_2d(&[[4.0, 1.0, -2.0], [1.0, 2.0, 0.5], [-2.0, 0.5, 3.0]]);
        let (l, v) = symmetric_eigen(m);
        let back = v * DMat3::from_diagonal(l) * v.transpose();
        for (a, b) in back.to_cols_array().iter().zip(m.to_cols_array()) {
            assert!((a - b).abs() < 1e-9, "{back:?} != {m:?}");
        }
        assert!(
            (v.transpose() * v - DMat3::IDENTITY)
                .to_cols_array()
                .iter()
                .all(|x| x.abs() < 1e-12)
        );
    }

    #[test]
    fn the_closed_form_least_axis_is_jacobi_s() {
        // Random symmetric matrices (proptest's seeded generator), spectra from
        // isotropic to planar.
        use proptest::prelude::Rng;
        let mut rng = proptest::test_runner::TestRng::deterministic_rng(
            proptest::test_runner::RngAlgorithm::ChaCha,
        );
        let mut next = || rng.random::<f64>() - 0.5;
        let mut closed = 0;
        for flat in [1.0, 1e-3, 1e-9, 0.0] {
            for _ in 0..200 {
                let rot = glam::DQuat::from_scaled_axis(DVec3::new(next(), next(), next()) * 6.0);
                let r = DMat3::from_quat(rot);
                let l = DVec3::new(1.0 + next(), 0.5 + next() * 0.5, flat * (0.5 + next()));
                let m = r * DMat3::from_diagonal(l) * r.transpose();
                let (values, vectors) = symmetric_eigen(m);
                let k = (0..3)
                    .min_by(|&i, &j| values[i].total_cmp(&values[j]))
                    .unwrap();
                if let Some(n) = least_axis(m) {
                    closed += 1;
                    let dot = n.dot(vectors.col(k)).abs();
                    assert!(dot > 1.0 - 1e-9, "{m:?}: {n} vs {}", vectors.col(k));
                }
            }
        }
        assert!(closed > 790, "closed form used for {closed} of 800");
        // A double least eigenvalue has no unique axis: left to Jacobi.
        assert_eq!(
            least_axis(DMat3::from_diagonal(DVec3::new(2.0, 1.0, 1.0))),
            None
        );
        assert_eq!(least_axis(DMat3::IDENTITY), None);
        assert_eq!(least_axis(DMat3::ZERO), None);
    }

    #[test]
    fn plane_normal_of_tilted_plane() {
        let n = Vec3::new(1.0, 2.0, 2.0).normalize();
        let u = n.any_orthonormal_vector();
        let v = n.cross(u);
        let pts: Vec<Vec3> = (0..25)
            .map(|i| u * (i % 5) as f32 + v * (i / 5) as f32 + Vec3::splat(7.0))
            .collect();
        let got = plane_normal(pts.iter().copied());
        assert!(got.dot(n).abs() > 0.9999, "{got} vs {n}");
    }

    #[test]
    fn plane_normal_degenerate_inputs_are_unit() {
        for pts in [
            vec![],
            vec![Vec3::ONE; 10],
            vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0],
        ] {
            let n = plane_normal(pts.iter().copied());
            assert!((n.length() - 1.0).abs() < 1e-6 && n.is_finite());
        }
    }
}
