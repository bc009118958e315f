//! Face lists: validation of indices and fan triangulation, shared by both encodings.

use super::error::Problem;

/// Triangles from the face element, with indices into the vertex rows of the file.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Faces {
    pub triangles: Vec<[u32; 3]>,
    /// Face rows read.
    pub polygons: u64,
    /// Face rows with fewer than three indices, skipped.
    pub too_short: u64,
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
