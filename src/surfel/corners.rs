//! Each vertex's corners of a triangle mesh, as compressed rows: vertex v's are
//! `corners[start[v]..start[v + 1]]`, each 3 t + k for corner k of triangle t, in
//! triangle order, so that a vertex gathers its terms in the order a pass over the
//! triangles would add them ([`super::ring`]).
//! They are grouped by a counting sort on every core ([`parallel::grouped`]).

use crate::io::parallel;

/// Each vertex's corners of a triangle mesh (see the module doc).
pub struct Rings {
    start: Vec<u32>,
    corners: Vec<u32>,
}

impl Rings {
    /// The rows of `triangles`' corners, for vertices `0..vertex_count`.
    pub fn of(vertex_count: usize, triangles: &[[u32; 3]]) -> Rings {
        assert!(triangles.len() < (u32::MAX / 3) as usize, "corners fit u32");
        let (start, corners) = corners_by_vertex(vertex_count, triangles);
        Rings { start, corners }
    }

    /// Vertex `v`'s corners, each 3 t + k for corner k of triangle t, in triangle order.
    pub fn of_vertex(&self, v: usize) -> &[u32] {
        &self.corners[self.start[v] as usize..self.start[v + 1] as usize]
    }

    /// Vertex `v`'s corners of `triangles` (those these rows were made of) as
    /// (triangle, its next vertex, its previous vertex), in triangle order.
    pub fn ring<'a>(
        &'a self,
        triangles: &'a [[u32; 3]],
        v: usize,
    ) -> impl Iterator<Item = (&'a [u32; 3], u32, u32)> + Clone {
        self.of_vertex(v).iter().map(|&c| {
            let (t, k) = (&triangles[c as usize / 3], c as usize % 3);
            (t, t[(k + 1) % 3], t[(k + 2) % 3])
        })
    }

    /// Vertex `v`'s neighbours, as runs of equal ends of its corners' edges in
    /// ascending order, sorted in `ends`: an edge (v, w) that one triangle of the ring
    /// holds (a border edge) makes a run of one.
    pub fn neighbour_runs<'e>(
        &self,
        triangles: &[[u32; 3]],
        v: usize,
        ends: &'e mut Vec<u32>,
    ) -> impl Iterator<Item = &'e [u32]> + 'e {
        ends.clear();
        let all = self
            .ring(triangles, v)
            .flat_map(|(_, next, previous)| [next, previous]);
        ends.extend(all);
        ends.sort_unstable();
        ends.chunk_by(|a, b| a == b)
    }
}

/// The rows of `triangles`' corners by vertex (see the module doc): `(start, corners)`,
/// `start` of length `vertex_count + 1`.
fn corners_by_vertex(vertex_count: usize, triangles: &[[u32; 3]]) -> (Vec<u32>, Vec<u32>) {
    let flat = triangles.as_flattened();
    parallel::grouped((vertex_count, flat.len()), |c| flat[c], |c| c as u32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rows as one pass over the triangles makes them.
    fn rows_in_one_pass(vertex_count: usize, triangles: &[[u32; 3]]) -> Vec<Vec<u32>> {
        let mut rows = vec![Vec::new(); vertex_count];
        for (c, &v) in triangles.as_flattened().iter().enumerate() {
            rows[v as usize].push(c as u32);
        }
        rows
    }

    #[test]
    fn rows_hold_each_vertex_corners_in_triangle_order_over_any_ranges() {
        let vertex_count = 1000;
        let triangles: Vec<[u32; 3]> = (0..3000u32)
            .map(|t| [t * 7 % 1000, (t * 13 + 5) % 997, (t * 31 + 11) % 1000])
            .collect();
        let expected = rows_in_one_pass(vertex_count, &triangles);
        for threads in [1, 3, 8] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let (start, corners) = pool.install(|| corners_by_vertex(vertex_count, &triangles));
            assert_eq!(start.len(), vertex_count + 1);
            for (v, row) in expected.iter().enumerate() {
                let got = &corners[start[v] as usize..start[v + 1] as usize];
                assert_eq!(got, row.as_slice(), "vertex {v}, {threads} ranges");
            }
        }
    }
}
