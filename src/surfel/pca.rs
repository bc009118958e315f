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

/// Unit normal of the best-fit plane of `points`: the eigenvector of the smallest
/// eigenvalue of their covariance. Any unit vector when the points do not span a plane
/// direction uniquely (e.g. all identical); never NaN.
pub fn plane_normal(points: impl Iterator<Item = Vec3> + Clone) -> Vec3 {
    let (sum, n) = points
        .clone()
        .fold((DVec3::ZERO, 0usize), |(s, n), p| (s + p.as_dvec3(), n + 1));
    if n == 0 {
        return Vec3::Z;
    }
    let mean = sum / n as f64;
    let mut cov = DMat3::ZERO;
    for p in points {
        let d = p.as_dvec3() - mean;
        cov += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
    }
    let (values, vectors) = symmetric_eigen(cov);
    let k = (0..3)
        .min_by(|&i, &j| values[i].total_cmp(&values[j]))
        .unwrap_or(2);
    vectors.col(k).as_vec3().try_normalize().unwrap_or(Vec3::Z)
}

#[cfg(test)]
mod tests {
    use super::*;

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
