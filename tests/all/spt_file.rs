//! `.spt` files: they reopen with the same nodes; truncated, bit-flipped, newer-version
//! and foreign files get a clear error; a write that fails midway leaves no file under
//! the final name and an existing file there untouched.

use crate::common;

use std::io::Write;
use std::path::{Path, PathBuf};

use spt::io::PointAttributes;
use spt::io::atomic::{temporary_path, write_atomically};
use spt::io::ply::read_ply;
use spt::surfel::shape::SplatShape;
use spt::surfel::{NormalsTurned, leaf_surfels};
use spt::tree::report::Silent;
use spt::tree::select::PrefixIndex;
use spt::tree::spt_file::{SptError, SptFile, file_bytes, write_spt, write_to};
use spt::tree::spt_write::write_ordered;
use spt::tree::{NodeRecord, SequentialList, build_ordered, build_sequential_list};

fn default_list() -> SequentialList {
    build_sequential_list(leaf_surfels(
        &read_ply(&common::default_model()).unwrap().geometry,
    ))
}

#[test]
fn node_records_are_32_bytes() {
    assert_eq!(std::mem::size_of::<NodeRecord>(), 32);
}

#[test]
fn reopens_with_the_same_nodes() {
    let list = default_list();
    let dir = common::temp_dir();
    let path = dir.path().join("knot.spt");
    write_spt(&path, &list).unwrap();
    let file = SptFile::open(&path).unwrap();
    assert_eq!(file.meta, list.meta);
    assert_eq!(file.nodes(), &list.nodes[..]);
    assert_eq!(file.parents(), &list.parents[..]);
    assert_eq!(file.to_list(), list);
    assert!(!temporary_path(&path).exists());
}

fn expect(bytes: &[u8], name: &str, check: impl Fn(&SptError) -> bool, words: &str) {
    let dir = common::temp_dir();
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).unwrap();
    let err = SptFile::open(&path)
        .err()
        .unwrap_or_else(|| panic!("{name} opened"));
    assert!(check(&err), "{name}: {err:?}");
    let text = err.to_string();
    assert!(
        text.contains(name) && text.contains(words),
        "{name}: {text}"
    );
    // The command line says the same and exits 1.
    let (code, _, stderr) = common::run_spt(&["info".as_ref(), path.as_os_str()]);
    assert_eq!(code, Some(1), "{name}: {stderr}");
    assert!(
        stderr.contains(words) && !stderr.contains("panicked"),
        "{name}: {stderr}"
    );
}

#[test]
fn damaged_files_get_clear_errors() {
    let list = default_list();
    let mut good = Vec::new();
    write_to(&mut good, &list).unwrap();
    expect(
        &good[..good.len() - 100],
        "truncated.spt",
        |e| matches!(e, SptError::Truncated { .. }),
        "truncated",
    );
    expect(
        &good[..100],
        "header_only.spt",
        |e| matches!(e, SptError::Truncated { .. }),
        "truncated",
    );
    let mut flipped = good.clone();
    flipped[good.len() / 2] ^= 0x10;
    expect(
        &flipped,
        "bit_flip.spt",
        |e| matches!(e, SptError::Checksum { .. }),
        "checksum mismatch",
    );
    let mut origin = good.clone();
    origin[45] ^= 1; // a bit of the origin: only the checksum can tell
    expect(
        &origin,
        "origin_flip.spt",
        |e| matches!(e, SptError::Checksum { .. }),
        "checksum mismatch",
    );
    let mut newer = good.clone();
    newer[8..12].copy_from_slice(&(spt::tree::spt_file::VERSION + 1).to_le_bytes());
    expect(
        &newer,
        "newer.spt",
        |e| matches!(e, SptError::NewerVersion { version, .. } if *version == spt::tree::spt_file::VERSION + 1),
        "newer spt",
    );
    // Version 1 had no shapes section: it is named, with what to do.
    let mut older = good.clone();
    older[8..12].copy_from_slice(&1u32.to_le_bytes());
    expect(
        &older,
        "older.spt",
        |e| matches!(e, SptError::OlderVersion { version: 1, .. }),
        "convert the model again",
    );
    let mut counts = good.clone();
    counts[32] ^= 0x40; // node count
    expect(
        &counts,
        "counts.spt",
        |e| matches!(e, SptError::BadHeader { .. }),
        "corrupt header",
    );
}

#[test]
fn chunks_that_misstate_their_least_error_are_refused() {
    // The prefix search skips a chunk whose least error is above what the frame draws
    // at its distance: one stated above a node's own error (or NaN) would hide nodes.
    let list = default_list();
    let last = list.chunks.len() - 1;
    let least = list.chunks[last].error_min;
    for (name, error_min) in [
        ("nan_error.spt", f32::NAN),
        ("high_error.spt", least * 2.0 + 1.0),
    ] {
        let mut bad = list.clone();
        bad.chunks[last].error_min = error_min;
        let mut bytes = Vec::new();
        write_to(&mut bytes, &bad).unwrap();
        expect(
            &bytes,
            name,
            |e| matches!(e, SptError::Invalid { .. }),
            "least error",
        );
    }
}

/// A writer that fails after `left` bytes, like a full disk.
struct FailAfter<'a> {
    inner: &'a mut dyn Write,
    left: usize,
}

impl Write for FailAfter<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.left == 0 {
            return Err(std::io::Error::other("injected failure: disk full"));
        }
        let n = buf.len().min(self.left);
        self.left -= n;
        self.inner.write(&buf[..n])
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

#[test]
fn a_failed_write_leaves_no_file_and_keeps_the_old_one() {
    let list = default_list();
    let dir = common::temp_dir();
    let path = dir.path().join("out.spt");
    let fail = |path: &std::path::Path| {
        write_atomically(path, |w| {
            write_to(
                &mut FailAfter {
                    inner: w,
                    left: 1_000_000,
                },
                &list,
            )
        })
        .expect_err("the injected failure")
    };
    // No file before: none after, and no temporary left behind.
    // The error names the file it was writing, and keeps its cause.
    let err = fail(&path);
    let message = err.to_string();
    assert!(message.contains("injected"), "{message}");
    assert!(message.contains(&path.display().to_string()), "{message}");
    assert!(!path.exists() && !temporary_path(&path).exists());
    // An existing file: untouched.
    std::fs::write(&path, b"the previous version").unwrap();
    fail(&path);
    assert_eq!(std::fs::read(&path).unwrap(), b"the previous version");
    assert!(!temporary_path(&path).exists());
}

#[test]
fn a_write_into_a_missing_folder_names_the_file() {
    let dir = common::temp_dir();
    let path = dir.path().join("no such folder").join("out.spt");
    let err = write_spt(&path, &default_list()).expect_err("no folder to write in");
    let message = err.to_string();
    assert!(message.contains(&path.display().to_string()), "{message}");
    assert_eq!(err.kind(), std::io::ErrorKind::NotFound, "{message}");
}

#[test]
fn spt_convert_then_info() {
    let dir = common::temp_dir();
    let out = dir.path().join("knot.spt");
    let model = common::default_model();
    let (code, stdout, stderr) =
        common::run_spt(&["convert".as_ref(), model.as_os_str(), out.as_os_str()]);
    assert_eq!(code, Some(0), "{stderr}");
    for stage in [
        "load",
        "surfels",
        "tree",
        "errors",
        "sort",
        "write",
        "nodes (",
        "bytes per node",
    ] {
        assert!(stdout.contains(stage), "no '{stage}' in:\n{stdout}");
    }
    let (code, stdout, _) = common::run_spt(&["info".as_ref(), "--json".as_ref(), out.as_os_str()]);
    assert_eq!(code, Some(0));
    let json: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(json["checksum_ok"], true);
    assert_eq!(json["leaf_count"], 50_000);
    // A bad input fails cleanly and writes nothing.
    let bad = dir.path().join("bad.ply");
    std::fs::write(&bad, b"not a ply").unwrap();
    let out2 = dir.path().join("bad.spt");
    let (code, _, _) = common::run_spt(&["convert".as_ref(), bad.as_os_str(), out2.as_os_str()]);
    assert_eq!(code, Some(1));
    assert!(!out2.exists());
}

#[test]
fn version_2_files_read_as_files_without_attributes() {
    let list = default_list();
    let mut bytes = Vec::new();
    write_to(&mut bytes, &list).unwrap();
    // A model without LiDAR attributes pays nothing for them: header, three sections,
    // the chunk table, the δ suffix maxima and the block heads (2 bytes each per block
    // of 64 nodes).
    let n = list.nodes.len();
    let blocks: usize = list
        .chunks
        .iter()
        .map(|c| (c.count as usize).div_ceil(64))
        .sum();
    let tail = list.chunks.len() * 48 + 4 * blocks;
    assert_eq!(bytes.len(), 256 + n * (32 + 4 + 24) + tail);
    assert_eq!(
        bytes.len() as u64,
        file_bytes(&list.meta, &list.chunks),
        "the size convert reports"
    );
    // Version 2: 16-byte shapes, no attributes section, no chunk table.
    let mut bytes = narrowed(&bytes);
    let size = 256 + n * (32 + 4 + 16);
    assert_eq!(bytes.len(), size + tail);
    bytes.truncate(size);
    bytes[8..12].copy_from_slice(&2u32.to_le_bytes());
    bytes[160..168].copy_from_slice(&(size as u64).to_le_bytes());
    bytes[188..224].fill(0);
    assert!(spt::tree::spt_file::reseal(&mut bytes));
    let dir = common::temp_dir();
    let path = dir.path().join("v2.spt");
    std::fs::write(&path, &bytes).unwrap();
    let file = SptFile::open(&path).unwrap();
    assert_eq!(file.version, 2);
    // Read as one chunk over the whole list, the shapes with a zero colour field.
    let back = file.to_list();
    let without_color: Vec<SplatShape> = list
        .shapes
        .iter()
        .map(|s| SplatShape {
            color: [0; 2],
            ..*s
        })
        .collect();
    assert_eq!(
        (back.nodes, back.shapes, back.parents),
        (list.nodes, without_color, list.parents)
    );
    assert_eq!(back.chunks.len(), 1);
    assert_eq!(back.chunks[0].count as usize, n);
}

/// A terrain whose box one stray return makes tall: the builder turns its normals up
/// (decided on the core box), the file keeps that, and a version 7 file, which did not
/// store it, is read as its leaf box tells, as the renderer read it then.
#[test]
fn a_terrain_s_up_turned_normals_survive_the_file() {
    let mut points: Vec<[f64; 3]> = (0..10_000)
        .map(|i| {
            let (x, y) = ((i % 100) as f64, (i / 100) as f64);
            [x, y, 0.5 * (0.1 * x).sin()]
        })
        .collect();
    points.push([50.0, 50.0, 2_000.0]);
    let list = build_sequential_list(leaf_surfels(&common::geometry_of(&points)));
    assert_eq!(list.meta.normals_turned, NormalsTurned::Up);
    assert_eq!(list.meta.normals_turned_by_leaf_box(), NormalsTurned::No);
    let mut bytes = Vec::new();
    write_to(&mut bytes, &list).unwrap();
    let dir = common::temp_dir();
    let path = dir.path().join("tile.spt");
    std::fs::write(&path, &bytes).unwrap();
    assert_eq!(SptFile::open(&path).unwrap().meta, list.meta);
    // The same image as version 7 wrote it: flags 8 and 16 unused.
    bytes[8..12].copy_from_slice(&7u32.to_le_bytes());
    bytes[16] &= !(8 | 16);
    assert!(spt::tree::spt_file::reseal(&mut bytes));
    std::fs::write(&path, &bytes).unwrap();
    let file = SptFile::open(&path).unwrap();
    assert_eq!(
        (file.version, file.meta.normals_turned),
        (7, NormalsTurned::No)
    );
    // Turned both up and toward the origin: no builder writes that, and no reader guesses.
    bytes[8..12].copy_from_slice(&8u32.to_le_bytes());
    bytes[16] |= 8 | 16;
    assert!(spt::tree::spt_file::reseal(&mut bytes));
    std::fs::write(&path, &bytes).unwrap();
    let error = SptFile::open(&path).err().unwrap().to_string();
    assert!(
        error.contains("tile.spt") && error.contains("both up (8) and toward the origin (16)"),
        "{error}"
    );
}

#[test]
fn lidar_attributes_survive_the_file() {
    let dir = common::temp_dir();
    let las = dir.path().join("tile.laz");
    std::fs::write(&las, common::las_files::sample(2000, true)).unwrap();
    let model = spt::io::las::read_las(&las).unwrap();
    let list = spt::tree::build_sequential_list(spt::surfel::leaf_surfels(&model.geometry));
    assert!(list.meta.has_attributes);
    assert_eq!(list.attributes.len(), list.nodes.len());
    // Leaves keep their own class (ground or water); inner nodes take one of those.
    assert!(list.attributes.iter().all(|a| a.class == 2 || a.class == 9));
    let path = dir.path().join("tile.spt");
    write_spt(&path, &list).unwrap();
    let file = SptFile::open(&path).unwrap();
    assert_eq!(file.attributes(), &list.attributes[..]);
    assert_eq!(file.to_list(), list);
}

/// `bytes` (a version 8 image of a mesh) as version 6 wrote it: 16-byte shapes, without their
/// colour field, the sections after them moved up.
fn narrowed(bytes: &[u8]) -> Vec<u8> {
    let u64_at = |at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap());
    let (n, shapes_at) = (u64_at(32) as usize, u64_at(176) as usize);
    let mut old = bytes[..shapes_at].to_vec();
    for k in 0..n {
        old.extend_from_slice(&bytes[shapes_at + 24 * k..][..16]);
    }
    old.extend_from_slice(&bytes[shapes_at + 24 * n..]);
    // File size, then the offsets of the attributes, the chunk table and the suffixes.
    for at in [160, 188, 204, 224] {
        old[at..at + 8].copy_from_slice(&(u64_at(at) - 8 * n as u64).to_le_bytes());
    }
    old[184..188].copy_from_slice(&16u32.to_le_bytes());
    old[8..12].copy_from_slice(&6u32.to_le_bytes());
    assert!(spt::tree::spt_file::reseal(&mut old));
    old
}

/// `bytes` (a version 6 image) cut to `end` and marked `version` (its header's block
/// fields zeroed before version 5), resealed and written to `name` in `dir`.
fn older(bytes: &[u8], (version, end): (u32, usize), dir: &Path, name: &str) -> PathBuf {
    let mut old = bytes[..end].to_vec();
    old[8..12].copy_from_slice(&version.to_le_bytes());
    old[160..168].copy_from_slice(&(end as u64).to_le_bytes());
    if version < 5 {
        old[224..240].fill(0);
    }
    assert!(spt::tree::spt_file::reseal(&mut old));
    let path = dir.join(name);
    std::fs::write(&path, &old).unwrap();
    path
}

#[test]
fn older_files_build_the_index_version_6_files_store_it() {
    let list = default_list();
    let mut bytes = Vec::new();
    write_to(&mut bytes, &list).unwrap();
    let dir = common::temp_dir();
    let path = dir.path().join("v8.spt");
    std::fs::write(&path, &bytes).unwrap();
    let built = PrefixIndex::new(&list.meta, &list.chunks, &list.nodes);
    // Streaming opens read the stored index, the same as the one built from the nodes.
    let (file, stored) = SptFile::open_for_streaming(&path).unwrap();
    assert_eq!(file.version, 8);
    assert_eq!(stored, built);
    // Version 6: 16-byte shapes, read with a zero colour field; the same index.
    let v6 = narrowed(&bytes);
    let path = dir.path().join("v6.spt");
    std::fs::write(&path, &v6).unwrap();
    let (file, stored) = SptFile::open_for_streaming(&path).unwrap();
    assert_eq!((file.version, file.shapes().len()), (6, list.nodes.len()));
    assert_eq!(stored, built);
    // Version 5: the same file without the block heads; version 4 without the δ suffix
    // maxima either. What they lack is built.
    let blocks = built.block_heads().len();
    let table_end = 256 + list.nodes.len() * 52 + list.chunks.len() * 48;
    let v5 = older(&v6, (5, table_end + 2 * blocks), dir.path(), "v5.spt");
    let file = SptFile::open(&v5).unwrap();
    assert_eq!((file.version, file.block_heads()), (5, None));
    assert_eq!(file.delta_suffix(), Some(built.delta_suffix()));
    assert_eq!(file.prefix_index().unwrap(), built);
    let v4 = older(&v6, (4, table_end), dir.path(), "v4.spt");
    let file = SptFile::open(&v4).unwrap();
    assert_eq!((file.version, file.delta_suffix()), (4, None));
    assert_eq!(file.prefix_index().unwrap(), built);
    // A stored maximum below a node's δ, or a head below a block's parent error, would
    // cut prefixes short: the full check refuses them, naming the file.
    let table_end = table_end + 8 * list.nodes.len(); // in the version 8 image
    for (at, name, what) in [
        (table_end, "bad_suffix.spt", "suffix"),
        (table_end + 2 * blocks, "bad_head.spt", "heads"),
    ] {
        let mut bad = bytes.clone();
        bad[at..at + 2].copy_from_slice(&0u16.to_le_bytes());
        assert!(spt::tree::spt_file::reseal(&mut bad));
        let corrupt = dir.path().join(name);
        std::fs::write(&corrupt, &bad).unwrap();
        let err = SptFile::open(&corrupt).err().expect("refused").to_string();
        assert!(err.contains(name) && err.contains(what), "{err}");
    }
}

/// `spt convert` writes the list without sorting it in memory (`write_ordered`): the
/// same bytes as the sorted list written whole, for a mesh with colours (the default
/// model) and for a cloud with LiDAR attributes, in several slabs' worth of chunks.
#[test]
fn a_list_written_in_id_order_is_the_sorted_list_s_file() {
    let mesh = read_ply(&common::default_model()).unwrap().geometry;
    let grid: Vec<[f64; 3]> = (0..40_000)
        .map(|i| {
            let (x, y) = ((i % 200) as f64, (i / 200) as f64);
            [x, y, (0.05 * x).sin() + (0.07 * y).cos()]
        })
        .collect();
    let mut cloud = common::geometry_of(&grid);
    cloud.attributes = Some(
        (0..grid.len())
            .map(|i| PointAttributes::new((i % 1000) as u16, 2 + (i % 3) as u8, 1, 1))
            .collect(),
    );
    let dir = common::temp_dir();
    for (name, geometry) in [("mesh", mesh), ("cloud", cloud)] {
        let set = build_ordered(leaf_surfels(&geometry), &Silent);
        let streamed = dir.path().join(format!("{name}.spt"));
        let written = std::sync::atomic::AtomicU64::new(0);
        write_ordered(&streamed, &set, &|n| {
            written.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
        })
        .unwrap();
        let list = set.gather();
        assert!(
            list.chunks.len() > 1,
            "{name}: {} chunks",
            list.chunks.len()
        );
        let mut whole = Vec::new();
        write_to(&mut whole, &list).unwrap();
        let streamed = std::fs::read(&streamed).unwrap();
        assert_eq!(
            written.into_inner(),
            streamed.len() as u64,
            "{name}: progress"
        );
        assert_eq!(streamed.len(), whole.len(), "{name}");
        assert!(streamed == whole, "{name}: the files differ");
    }
}
