//! Each vertex's corners of a triangle mesh, as compressed rows: vertex v's are
//! `corners[start[v]..start[v + 1]]`, each 3 t + k for corner k of triangle t, in
//! triangle order, so that a vertex gathers its terms in the order a pass over the
//! triangles would add them ([`super::ring`]).
//!
//! A counting sort by vertex, in parallel over ranges of vertices: each range's rows
//! are a contiguous piece of `start` and of `corners`, so each task scans every corner
//! and counts, then places, only those of its own vertices. The scans are sequential
//! reads; the counts and placements, the random writes, are split between the tasks.
//! On the Lucy-size mesh (14 M vertices, 84 M corners) one pass on one thread took
//! 0.54–0.68 s of the surfels stage.

use rayon::prelude::*;

/// The most vertex ranges (one per thread up to this): few, since every range's task
/// reads all the corners.
const MAX_RANGES: usize = 8;

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

    /// Vertex `v`'s neighbours that `keep` passes, as runs of equal ends of its
    /// corners' edges in ascending order, sorted in `ends`: an edge (v, w) that one
    /// triangle of the ring holds (a border edge) makes a run of one.
    pub fn neighbour_runs<'e>(
        &self,
        triangles: &[[u32; 3]],
        v: usize,
        keep: impl Fn(u32) -> bool,
        ends: &'e mut Vec<u32>,
    ) -> impl Iterator<Item = &'e [u32]> + 'e {
        ends.clear();
        let all = self
            .ring(triangles, v)
            .flat_map(|(_, next, previous)| [next, previous]);
        ends.extend(all.filter(|&w| keep(w)));
        ends.sort_unstable();
        ends.chunk_by(|a, b| a == b)
    }
}

/// The rows of `triangles`' corners by vertex (see the module doc): `(start, corners)`,
/// `start` of length `vertex_count + 1`.
fn corners_by_vertex(vertex_count: usize, triangles: &[[u32; 3]]) -> (Vec<u32>, Vec<u32>) {
    let flat = triangles.as_flattened();
    let ranges = rayon::current_num_threads().clamp(1, MAX_RANGES);
    let bounds: Vec<usize> = (0..=ranges).map(|r| r * vertex_count / ranges).collect();
    // Each row's length, then (a running sum) its end.
    let mut start = vec![0u32; vertex_count + 1];
    split_at_bounds(&mut start[..vertex_count], &bounds)
        .into_par_iter()
        .for_each(|(lo, counts)| {
            for &v in flat {
                if let Some(count) = (v as usize).checked_sub(lo).and_then(|i| counts.get_mut(i)) {
                    *count += 1;
                }
            }
        });
    let mut total = 0;
    for end in &mut start[..vertex_count] {
        total += *end;
        *end = total;
    }
    start[vertex_count] = total;
    // The corners, placed last to first, each move their row's end down one, which
    // leaves it at the row's start. A range's rows span corners[first..last].
    let corner_bounds: Vec<usize> = bounds
        .iter()
        .map(|&b| if b == 0 { 0 } else { start[b - 1] as usize })
        .collect();
    let mut corners = vec![0u32; total as usize];
    let rows = split_at_bounds(&mut start[..vertex_count], &bounds);
    let slots = split_at_bounds(&mut corners, &corner_bounds);
    rows.into_par_iter()
        .zip(slots)
        .for_each(|((lo, ends), (first, out))| {
            for (c, &v) in flat.iter().enumerate().rev() {
                if let Some(end) = (v as usize).checked_sub(lo).and_then(|i| ends.get_mut(i)) {
                    *end -= 1;
                    out[*end as usize - first] = c as u32;
                }
            }
        });
    (start, corners)
}

/// `values` cut at `bounds` (ascending, from 0 to `values.len()`): each piece with the
/// index it starts at.
fn split_at_bounds<'a, T>(mut values: &'a mut [T], bounds: &[usize]) -> Vec<(usize, &'a mut [T])> {
    let mut pieces = Vec::with_capacity(bounds.len().saturating_sub(1));
    for pair in bounds.windows(2) {
        let (piece, rest) = values.split_at_mut(pair[1] - pair[0]);
        pieces.push((pair[0], piece));
        values = rest;
    }
    pieces
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
