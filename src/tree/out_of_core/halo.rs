//! A cloud job's halo: the points of the jobs around it that lie near its border, so
//! that the neighbourhoods, triangles and tops of its own points near the border see
//! past it as an in-memory build sees them.
//!
//! The halo reaches [`HALO_SPACINGS`] spacings of the sampling from each face of the
//! job's cells, and at most a cell (it is drawn from the cells across each face, edge
//! and corner alone). What a point's surfel reads lies within a few spacings of it: its
//! 24 nearest neighbours within about 3, its TIN's one-ring within 2, the rings of
//! those neighbours within 4. A reach counted in cells instead grows and shrinks with
//! the model's extent (the grid has 64 cells a side): a quarter cell was 1.8 spacings
//! of terrain_utm, whose jobs then differed from its in-memory build along their
//! borders, and 55 of a 4 km city tile of 200 M points, whose halos held 11 % as many
//! points as its jobs.
//!
//! The spacing is measured on the counting grid ([`spacing`]), before any point is
//! spilled.

use glam::DVec3;

/// How far a halo reaches from a face of its job's cells, in the sampling's spacing
/// ([`spacing`]). On the 20 M-point city slice (1.26 km, spacing 0.32 m by that
/// estimate, 0.28 m between its samples) that is 5.2 m; its jobs had reached a quarter
/// cell, 4.9 m, and drew as in memory but where a roof crossed their border
/// (docs/point-clouds.md).
pub const HALO_SPACINGS: f64 = 16.0;

/// A halo's reach from each face of a cell, along each axis, as a fraction of the
/// cell's size along it (at most 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Halo {
    pub reach: DVec3,
}

impl Halo {
    /// The halo of a model whose points are counted by `counts` per cell of the
    /// counting grid, of size `cell`:
    /// [`HALO_SPACINGS`] of its [`spacing`], held within a cell.
    pub fn of(counts: &[u64], cell: DVec3) -> Halo {
        let reach = HALO_SPACINGS * spacing(counts, cell);
        Halo {
            reach: (DVec3::splat(reach) / cell).min(DVec3::ONE),
        }
    }
}

/// The sampling's spacing, from the points' count per cell (`counts`, of size `cell`): the
/// median, over the points, of their cell's √(A / n), with n the cell's count and A
/// the area of its largest face, the spacing of n samples spread evenly over a surface
/// of that area. A surface that crosses part of its cell or runs through it at a slant
/// gives more than its spacing, which only widens the halo; one that folds within a
/// cell gives less. 0 for no point.
pub fn spacing(counts: &[u64], cell: DVec3) -> f64 {
    let c = cell;
    let face = (c.x * c.y).max(c.y * c.z).max(c.z * c.x);
    let mut cells: Vec<(f64, u64)> = (counts.iter())
        .filter(|&&n| n > 0)
        .map(|&n| ((face / n as f64).sqrt(), n))
        .collect();
    cells.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    let half = cells.iter().map(|c| c.1).sum::<u64>().div_ceil(2);
    let mut seen = 0;
    for (s, n) in cells {
        seen += n;
        if seen >= half {
            return s;
        }
    }
    0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_halo_reaches_its_spacings_within_a_cell() {
        // A tile sampled every 0.5 m over its ground, in cells of 100 × 100 × 1.5625 m
        // (a 6.4 km tile 100 m high on the 64³ grid), one layer of 64 × 64 of them holding
        // 40,000 samples each, the rest empty.
        let cell = DVec3::new(100.0, 100.0, 1.5625);
        let mut counts = vec![0; 4 * 64 * 64];
        counts[..64 * 64].fill(40_000);
        assert!((spacing(&counts, cell) - 0.5).abs() < 1e-9);
        let reach = Halo::of(&counts, cell).reach;
        assert!(
            (reach.x * cell.x - HALO_SPACINGS * 0.5).abs() < 1e-9,
            "{reach}"
        );
        assert!(
            (reach.y * cell.y - HALO_SPACINGS * 0.5).abs() < 1e-9,
            "{reach}"
        );
        // Along z the cell is thinner than the reach: the whole cell.
        assert_eq!(reach.z, 1.0);
        // The same tile sampled 100 times sparser: 5 m apart, a reach of 80 m.
        counts.iter_mut().for_each(|n| *n /= 100);
        let sparse = Halo::of(&counts, cell).reach;
        assert!((sparse.x - 0.8).abs() < 1e-9, "{sparse}");
        // 10,000 times sparser: a whole cell.
        counts.iter_mut().for_each(|n| *n /= 100);
        assert_eq!(Halo::of(&counts, cell).reach, DVec3::ONE);
        assert_eq!(spacing(&[0; 8], cell), 0.0);
    }

    #[test]
    fn the_spacing_is_the_median_over_the_points() {
        // Unit cells: 1 cell of 100 points (0.1 apart) and 3 of 4 (0.5 apart): most
        // points lie in the dense cell, whatever the count of sparse cells.
        let counts = [100, 4, 4, 4, 0];
        assert!((spacing(&counts, DVec3::ONE) - 0.1).abs() < 1e-12);
    }
}
