//! An uncompressed LAS file's points decoded on several threads and handed on in file
//! order, cut into the batches one reader cuts them into ([`LasBatches`]).
//!
//! A LAS record lies at an offset known from its row, so the rows are cut into blocks
//! of [`BLOCK`] rows, a whole number of batches, and worker w of W reads blocks w,
//! w + W, w + 2W, … with a reader of its own. Each hands its batches on through a
//! channel of its own, at most [`AHEAD`] ahead, then a mark at the block's end; the
//! caller takes block b's from worker b mod W. So the caller sees every batch, in file
//! order, as a single reader would hand them: a pass's results do not depend on how
//! many workers decoded it. A worker stops at the file's end (a block it finds empty or
//! short), at an error, or when the caller stops taking; the caller stops at the first
//! block that ends without its mark, and the error of the worker that failed there, if
//! one did, is returned.

use std::path::Path;
use std::sync::mpsc::{Receiver, Sender, SyncSender, channel, sync_channel};

use super::{BATCH, LasBatches, LasError};
use crate::io::format::PointBatch;

/// Rows per block: 2 batches.
pub const BLOCK: u64 = 2 * BATCH;

/// What each worker holds decoded ahead of the caller: a whole block and its mark, so
/// that it decodes its next block while the caller takes the others' (with less, the
/// workers took turns: on the 200 M-point tile, 2 of them kept 1.4 cores busy).
const AHEAD: usize = (BLOCK / BATCH) as usize + 1;

/// What a worker hands on: a batch, or the end of its block.
enum Handed {
    Batch(PointBatch),
    BlockEnd,
}

/// One worker's ends of its channels, as the caller holds them.
struct Lane {
    handed: Receiver<Handed>,
    used: Sender<PointBatch>,
}

/// Calls `f` on every batch of the uncompressed LAS file at `path`, in file order,
/// decoded by `workers` threads in blocks of `block` rows (a whole number of batches).
pub fn points_in_order(
    path: &Path,
    (workers, block): (usize, u64),
    f: &mut dyn FnMut(&PointBatch),
) -> Result<(), LasError> {
    let workers = workers.max(1);
    std::thread::scope(|scope| {
        let mut lanes = Vec::with_capacity(workers);
        let mut threads = Vec::with_capacity(workers);
        for first in 0..workers {
            let (hand, handed) = sync_channel(AHEAD);
            let (used, recycled) = channel();
            lanes.push(Lane { handed, used });
            let blocks = (first as u64.., workers as u64);
            threads.push(scope.spawn(move || decode_blocks(path, blocks, block, hand, recycled)));
        }
        let stopped_at = take_in_order(&lanes, f);
        // Workers still decoding find no one taking and stop.
        drop(lanes);
        let results: Vec<Result<(), LasError>> = (threads.into_iter())
            .map(|t| t.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
            .collect();
        let first_error = |k: usize| results[k].clone().err();
        match (0..workers).find_map(|k| first_error((stopped_at + k) % workers)) {
            Some(e) => Err(e),
            None => Ok(()),
        }
    })
}

/// Hands `f` each block's batches from its lane, in block order, until a lane closes
/// before its block's end; returns that lane.
fn take_in_order(lanes: &[Lane], f: &mut dyn FnMut(&PointBatch)) -> usize {
    let mut lane = 0;
    loop {
        let Lane { handed, used } = &lanes[lane];
        loop {
            match handed.recv() {
                Ok(Handed::Batch(batch)) => {
                    f(&batch);
                    let _ = used.send(batch);
                }
                Ok(Handed::BlockEnd) => break,
                Err(_) => return lane,
            }
        }
        lane = (lane + 1) % lanes.len();
    }
}

/// A worker: decodes blocks `first`, `first + step`, … of `block` rows each and hands
/// their batches on, reusing those `recycled`.
fn decode_blocks(
    path: &Path,
    (first, step): (std::ops::RangeFrom<u64>, u64),
    block: u64,
    hand: SyncSender<Handed>,
    recycled: Receiver<PointBatch>,
) -> Result<(), LasError> {
    let mut reader = LasBatches::open(path)?;
    for b in first.step_by(step as usize) {
        let start = b.saturating_mul(block);
        if start >= reader.point_count() {
            return Ok(());
        }
        reader.seek_rows(start..start.saturating_add(block))?;
        let mut rows = 0;
        loop {
            let mut batch = recycled.try_recv().unwrap_or_default();
            if !reader.next_batch(&mut batch)? {
                break;
            }
            rows += batch.xyz.len() as u64;
            if hand.send(Handed::Batch(batch)).is_err() {
                return Ok(());
            }
        }
        // A short block is the file's end: its lane closes without a mark.
        if rows < block.min(reader.point_count() - start) || hand.send(Handed::BlockEnd).is_err() {
            return Ok(());
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use las::{Builder, Color, Point, Writer, point::Format};

    /// A LAS file of point format 2 (RGB) holding `n` points, each of its own
    /// position, colour and intensity.
    fn las_file(dir: &Path, n: usize) -> std::path::PathBuf {
        let mut builder = Builder::from((1, 2));
        builder.point_format = Format::new(2).unwrap();
        for t in [&mut builder.transforms.x, &mut builder.transforms.y] {
            t.scale = 0.01;
        }
        let path = dir.join("rows.las");
        let file = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
        let mut writer = Writer::new(file, builder.into_header().unwrap()).unwrap();
        for i in 0..n {
            writer
                .write_point(Point {
                    x: (i % 1000) as f64,
                    y: (i / 1000) as f64,
                    z: i as f64 * 0.5,
                    intensity: i as u16,
                    color: Some(Color::new(i as u16, (i >> 16) as u16, 7)),
                    ..Default::default()
                })
                .unwrap();
        }
        writer.close().unwrap();
        path
    }

    /// Every batch of a pass: its positions, colours and attributes.
    fn pass(read: impl FnOnce(&mut dyn FnMut(&PointBatch))) -> Vec<PointBatch> {
        let mut batches = Vec::new();
        read(&mut |b: &PointBatch| batches.push(b.clone()));
        batches
    }

    fn same(a: &[PointBatch], b: &[PointBatch]) -> bool {
        a.len() == b.len()
            && a.iter()
                .zip(b)
                .all(|(a, b)| a.xyz == b.xyz && a.rgb == b.rgb && a.attributes == b.attributes)
    }

    #[test]
    fn any_number_of_workers_hands_on_the_batches_of_one_reader() {
        let dir = tempfile::tempdir().unwrap();
        // Three whole blocks of one batch and a short one.
        let n = 3 * BATCH as usize + 1234;
        let path = las_file(dir.path(), n);
        let one = pass(|f| {
            let mut reader = LasBatches::open(&path).unwrap();
            let mut batch = PointBatch::default();
            while reader.next_batch(&mut batch).unwrap() {
                f(&batch);
            }
        });
        assert_eq!(one.iter().map(|b| b.xyz.len()).sum::<usize>(), n);
        for workers in [1, 2, 3, 5] {
            let many = pass(|f| points_in_order(&path, (workers, BATCH), f).unwrap());
            assert!(same(&one, &many), "{workers} workers");
        }
        let two_batch_blocks = pass(|f| points_in_order(&path, (2, BLOCK), f).unwrap());
        assert!(same(&one, &two_batch_blocks));
    }

    #[test]
    fn a_file_cut_short_is_an_error_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let path = las_file(dir.path(), 2 * BATCH as usize + 10);
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() - 20 * 26]).unwrap();
        let e = points_in_order(&path, (2, BATCH), &mut |_| {}).unwrap_err();
        assert!(e.to_string().contains("rows.las"), "{e}");
    }
}
