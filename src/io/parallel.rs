//! The large lists of a build (triangles, edges) gathered on every core: a serial
//! `collect` of a filter, or of rayon's per-thread pieces, copies every item on one
//! thread and faults in every page of the result there, while the other cores wait. On
//! a 20 M-point terrain tile such gathers kept one of two cores idle for about 7
//! CPU-seconds.
//!
//! A gather's output is allocated zeroed and filled in place, each piece by its own
//! task: an item type whose default is all zero bits (numbers, tuples and arrays of
//! them) is allocated without a pass of its own, its pages first written by the
//! fillers.

use rayon::prelude::*;

/// Items per piece of [`filtered`]: enough to amortise a task, few enough to balance.
const PIECE: usize = 1 << 14;

/// `parts` one after the other, each copied into its place by its own task.
pub fn concat<T: Copy + Default + Send + Sync>(parts: &[Vec<T>]) -> Vec<T> {
    let total = parts.iter().map(Vec::len).sum();
    let mut out = vec![T::default(); total];
    let mut places = Vec::with_capacity(parts.len());
    let mut rest = &mut out[..];
    for part in parts {
        let (place, tail) = rest.split_at_mut(part.len());
        places.push(place);
        rest = tail;
    }
    (places.into_par_iter().zip(parts)).for_each(|(place, part)| place.copy_from_slice(part));
    out
}

/// The items at the indices of `items` for which `keep(index)` holds, in order.
pub fn filtered<T: Copy + Default + Send + Sync>(
    items: &[T],
    keep: impl Fn(usize) -> bool + Sync,
) -> Vec<T> {
    let pieces: Vec<Vec<T>> = (items.par_chunks(PIECE).enumerate())
        .map(|(p, piece)| {
            let first = p * PIECE;
            (piece.iter().enumerate())
                .filter(|(k, _)| keep(first + k))
                .map(|(_, item)| *item)
                .collect()
        })
        .collect();
    concat(&pieces)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn concat_keeps_the_parts_order_and_empty_parts() {
        let parts = vec![vec![1u32, 2], vec![], vec![3], vec![4, 5, 6]];
        assert_eq!(concat(&parts), vec![1, 2, 3, 4, 5, 6]);
        assert!(concat::<u32>(&[]).is_empty());
    }

    #[test]
    fn filtered_is_the_serial_filter_across_pieces() {
        let items: Vec<(u32, u32)> = (0..3 * PIECE as u32 + 17).map(|i| (i, i / 7)).collect();
        let keep = |k: usize| k.is_multiple_of(3) || k % 11 == 5;
        let serial: Vec<(u32, u32)> = (items.iter().enumerate())
            .filter(|(k, _)| keep(*k))
            .map(|(_, t)| *t)
            .collect();
        assert_eq!(filtered(&items, keep), serial);
    }
}
