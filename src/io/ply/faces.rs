//! Face lists: validation of indices, fan triangulation of polygons and the triangles of
//! triangle strips, shared by both encodings.

use super::error::Problem;

/// Triangles from the face element, with indices into the vertex rows of the file.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Faces {
    pub triangles: Vec<[u32; 3]>,
    /// Face rows read.
    pub polygons: u64,
    /// Face rows with fewer than three indices, skipped.
    pub too_short: u64,
    /// Triangle-strip rows read (a `tristrips` element instead of `face`).
    pub strips: u64,
}

impl Faces {
    pub fn with_capacity(triangles: usize) -> Self {
        Faces {
            triangles: Vec::with_capacity(triangles),
            ..Faces::default()
        }
    }

    /// Adds one polygon, fan-triangulated around its first vertex: (i0, ik, ik+1).
    /// Every index must lie in `0..vertex_count`.
    pub fn push_polygon(
        &mut self,
        indices: &[i64],
        vertex_count: u64,
        row: u64,
    ) -> Result<(), Problem> {
        self.polygons += 1;
        for &i in indices {
            check_index(i, vertex_count, row)?;
        }
        if indices.len() < 3 {
            self.too_short += 1;
            return Ok(());
        }
        let first = indices[0] as u32;
        for pair in indices[1..].windows(2) {
            self.triangles.push([first, pair[0] as u32, pair[1] as u32]);
        }
        Ok(())
    }

    /// Adds the triangles of one row of triangle strips: −1 ends a strip and starts the
    /// next. In a strip s, triangle k is (s_k, s_k+1, s_k+2) for even k and
    /// (s_k+1, s_k, s_k+2) for odd k, so that all keep the first one's winding;
    /// triangles with a repeated vertex (the joins that strippers insert) are skipped.
    pub fn push_strips(
        &mut self,
        indices: &[i64],
        vertex_count: u64,
        row: u64,
    ) -> Result<(), Problem> {
        self.strips += 1;
        for strip in indices.split(|&i| i == -1) {
            for &i in strip {
                check_index(i, vertex_count, row)?;
            }
            for (k, w) in strip.windows(3).enumerate() {
                let [a, b, c] = [w[0] as u32, w[1] as u32, w[2] as u32];
                if a == b || b == c || a == c {
                    continue;
                }
                self.triangles
                    .push(if k % 2 == 0 { [a, b, c] } else { [b, a, c] });
            }
        }
        Ok(())
    }

    /// Adds one row of the face element: a polygon, or strips when `strips`.
    pub fn push_row(
        &mut self,
        strips: bool,
        indices: &[i64],
        vertex_count: u64,
        row: u64,
    ) -> Result<(), Problem> {
        if strips {
            self.push_strips(indices, vertex_count, row)
        } else {
            self.push_polygon(indices, vertex_count, row)
        }
    }
}

#[inline]
pub fn check_index(i: i64, vertex_count: u64, row: u64) -> Result<(), Problem> {
    if i < 0 || i as u64 >= vertex_count {
        return Err(Problem::row(
            "face",
            row,
            format!("vertex index {i} is out of range (the file has {vertex_count} vertices)"),
        ));
    }
    Ok(())
}
