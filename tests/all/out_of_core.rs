//! Out-of-core builds: a LAS cloud split into jobs, each built alone with
//! the points around its border, joined by a top tree and streamed to an `.spt` file.
//! The file opens and validates, its list is a tree whose chunks are each sorted, no
//! leaf is left uncovered on random views and no drawn node lies outside the CPU's
//! ranges, and it holds every point, as the in-memory build does.

use crate::common;

use spt::tree::out_of_core::{Built, Options, Progress, build_file};
use spt::tree::select::{TreeView, check_views, random_views};
use spt::tree::spt_file::SptFile;
use spt::tree::validate::check_structure;

struct Quiet;

impl Progress for Quiet {
    fn stage(&self, _: &'static str, _: u64) {}
    fn advance(&self, _: u64) {}
}

#[test]
fn a_cloud_built_in_jobs_is_one_hole_free_tree() {
    let dir = common::temp_dir();
    let input = dir.path().join("tile.las");
    std::fs::write(&input, common::las_files::sample(64 * 400, false)).unwrap();
    let (built, list) = build_in_jobs(&input, 3000, dir.path());
    assert!(built.jobs >= 8, "{} jobs", built.jobs);
    assert_eq!(list.meta.leaf_count, 64 * 400);
    check_structure(&list.meta, &list.nodes, &list.parents, &list.chunks).unwrap();
    common::assert_tree_invariants(&list, "out of core");
    let view = TreeView::new(&list.meta, &list.nodes, &list.chunks);
    let stats = check_views(
        &view,
        &list.parents,
        &random_views(&list.meta, 200, 1.0, 100.0, 11),
    );
    eprintln!(
        "{} jobs, {} chunks: {stats:?}",
        built.jobs,
        list.chunks.len()
    );
    assert_eq!((stats.holes, stats.past_prefix), (0, 0), "{stats:?}");
    // Only the file is left beside the input.
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(left.len(), 2, "{left:?}");
    // The in-memory build of the same file: the same leaves, about as many nodes.
    let memory = spt::tree::scene::Scene::open(&input).unwrap();
    assert_eq!(memory.meta().leaf_count, list.meta.leaf_count);
    let ratio = list.meta.node_count as f64 / memory.meta().node_count as f64;
    assert!((0.97..1.03).contains(&ratio), "{ratio}");
    // A flat tile: both turn its normals up.
    assert_eq!(list.meta.normals_turned, memory.meta().normals_turned);
    assert_eq!(list.meta.normals_turned, spt::surfel::NormalsTurned::Up);
    // The leaves carry the colours the in-memory reader gives the same points.
    let memory_list = match &memory.tree {
        spt::tree::scene::TreeSource::Memory(l) => l.clone(),
        spt::tree::scene::TreeSource::File(f) => f.to_list(),
    };
    assert_eq!(leaf_colors(&list), leaf_colors(&memory_list));
}

/// The colours of a list's leaves (the nodes no node has as parent), sorted.
fn leaf_colors(list: &spt::tree::SequentialList) -> Vec<[u8; 4]> {
    let mut parent = vec![false; list.nodes.len()];
    for &p in list.parents.iter().filter(|&&p| p != u32::MAX) {
        parent[p as usize] = true;
    }
    let mut colors: Vec<[u8; 4]> = (0..list.nodes.len())
        .filter(|&i| !parent[i])
        .map(|i| list.nodes[i].color)
        .collect();
    colors.sort_unstable();
    colors
}

/// `input` built out of core in jobs of at most `job_points`, in `dir`: what the build
/// says of itself, and the file's list.
fn build_in_jobs(
    input: &std::path::Path,
    job_points: u64,
    dir: &std::path::Path,
) -> (Built, spt::tree::SequentialList) {
    let output = dir.join("built.spt");
    let options = Options {
        job_points,
        spill_buffers: 1 << 20,
        temp_dir: dir.to_owned(),
    };
    let built = build_file(input, &output, &options, &Quiet).unwrap();
    (built, SptFile::open(&output).unwrap().to_list())
}

/// A face-less cloud of `positions` (f64 coordinates) written to `dir/name`.
fn write_cloud(dir: &std::path::Path, name: &str, positions: Vec<[f64; 3]>) -> std::path::PathBuf {
    let cloud = spt::io::ply::PolyMesh {
        positions,
        normals: None,
        colors: None,
        faces: spt::io::ply::FaceList::default(),
    };
    let path = dir.join(name);
    common::write_double(&path, &cloud);
    path
}

/// The in-memory build of `input`.
fn in_memory_list(input: &std::path::Path) -> spt::tree::SequentialList {
    match spt::tree::scene::Scene::open(input).unwrap().tree {
        spt::tree::scene::TreeSource::Memory(l) => l,
        spt::tree::scene::TreeSource::File(f) => f.to_list(),
    }
}

/// Each leaf's record and shape, keyed by its position's bits.
fn leaves_by_position(
    list: &spt::tree::SequentialList,
) -> std::collections::HashMap<[u32; 3], (spt::tree::NodeRecord, spt::surfel::shape::SplatShape)> {
    let mut parent = vec![false; list.nodes.len()];
    for &p in list.parents.iter().filter(|&&p| p != u32::MAX) {
        parent[p as usize] = true;
    }
    (0..list.nodes.len())
        .filter(|&i| !parent[i])
        .map(|i| (list.nodes[i].position, (list.nodes[i], list.shapes[i])))
        .collect()
}

#[test]
fn a_mesh_built_in_jobs_has_the_in_memory_build_s_leaves() {
    let dir = common::temp_dir();
    let input = common::default_model();
    let (built, list) = build_in_jobs(&input, 4000, dir.path());
    assert!(built.jobs >= 12, "{} jobs", built.jobs);
    check_structure(&list.meta, &list.nodes, &list.parents, &list.chunks).unwrap();
    common::assert_tree_invariants(&list, "mesh out of core");
    let view = TreeView::new(&list.meta, &list.nodes, &list.chunks);
    let views = random_views(&list.meta, 200, 1.0, 100.0, 5);
    let stats = check_views(&view, &list.parents, &views);
    assert_eq!((stats.holes, stats.past_prefix), (0, 0), "{stats:?}");
    assert!(list.meta.oriented_normals);
    let memory_list = in_memory_list(&input);
    // Every vertex's surfel is the one the whole mesh gives it: its one-ring and its
    // neighbours' normals crossed the jobs' borders.
    let (ours, theirs) = (leaves_by_position(&list), leaves_by_position(&memory_list));
    assert_eq!(ours.len(), theirs.len());
    let (mut same_shape, mut worst_normal) = (0, 1.0f32);
    for (at, (r, shape)) in &ours {
        let (m, memory_shape) = theirs.get(at).expect("the same vertex positions");
        let (a, b) = (f32::from_bits(r.radius), f32::from_bits(m.radius));
        assert!(
            (a - b).abs() <= 1e-5 * b,
            "radius at {at:?}: {a} against {b}"
        );
        assert_eq!(r.color, m.color);
        let dot = spt::surfel::octahedral::oct_decode(r.normal)
            .dot(spt::surfel::octahedral::oct_decode(m.normal));
        worst_normal = worst_normal.min(dot);
        same_shape += (shape == memory_shape) as usize;
    }
    let share = same_shape as f64 / ours.len() as f64;
    eprintln!(
        "{} jobs: worst normal cos {worst_normal}, {share:.4} of the shapes bit-identical",
        built.jobs
    );
    assert!(worst_normal > 0.9999, "{worst_normal}");
    assert!(share > 0.999, "{share}");
}

#[test]
fn a_ply_cloud_built_in_jobs_keeps_its_given_normals() {
    use spt::io::ply::{Encoding, FaceList, PolyMesh};
    // A wavy sheet with its exact normals, in file order row by row.
    let n = 120;
    let (mut positions, mut normals) = (Vec::new(), Vec::new());
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (i as f64 * 0.1, j as f64 * 0.1);
            let (fx, fy) = (0.3 * x.cos(), -0.2 * y.sin());
            positions.push([x, y, 0.3 * x.sin() + 0.2 * y.cos()]);
            let g = glam::DVec3::new(-fx, -fy, 1.0).normalize().as_vec3();
            normals.push(g.to_array());
        }
    }
    let cloud = PolyMesh {
        positions,
        normals: Some(normals),
        colors: None,
        faces: FaceList::default(),
    };
    let dir = common::temp_dir();
    let input = dir.path().join("sheet.ply");
    common::write_standard(&input, &cloud, Encoding::BinaryLittleEndian);
    let (built, list) = build_in_jobs(&input, 2000, dir.path());
    assert!(built.jobs >= 6, "{} jobs", built.jobs);
    assert!(list.meta.oriented_normals, "given normals are oriented");
    let memory_list = in_memory_list(&input);
    let (ours, theirs) = (leaves_by_position(&list), leaves_by_position(&memory_list));
    assert_eq!(ours.len(), n * n);
    for (at, (r, _)) in &ours {
        let (m, _) = theirs.get(at).expect("the same positions");
        assert_eq!(r.normal, m.normal, "the file's normal at {at:?}");
    }
    // Only the file is left beside the input.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
}

/// A UV sphere of `rings` × `sectors` around `centre`, its triangles wound outward or
/// inward.
fn sphere(mesh: &mut spt::io::ply::PolyMesh, centre: [f64; 3], radius: f64, outward: bool) {
    let (rings, sectors) = (60u32, 120u32);
    let base = mesh.positions.len() as u32;
    mesh.positions
        .push([centre[0], centre[1], centre[2] + radius]);
    for r in 1..rings {
        let theta = std::f64::consts::PI * r as f64 / rings as f64;
        for k in 0..sectors {
            let phi = std::f64::consts::TAU * k as f64 / sectors as f64;
            let d = [
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            ];
            mesh.positions
                .push([0, 1, 2].map(|a| centre[a] + radius * d[a]));
        }
    }
    mesh.positions
        .push([centre[0], centre[1], centre[2] - radius]);
    let at = |r: u32, k: u32| base + 1 + (r - 1) * sectors + k % sectors;
    let (top, bottom) = (base, base + 1 + (rings - 1) * sectors);
    let mut push = |t: [u32; 3]| {
        let t = if outward { t } else { [t[0], t[2], t[1]] };
        mesh.faces.push(&t);
    };
    for k in 0..sectors {
        push([top, at(1, k), at(1, k + 1)]);
        push([bottom, at(rings - 1, k + 1), at(rings - 1, k)]);
        for r in 1..rings - 1 {
            push([at(r, k), at(r + 1, k), at(r + 1, k + 1)]);
            push([at(r, k), at(r + 1, k + 1), at(r, k + 1)]);
        }
    }
}

#[test]
fn an_inward_wound_mesh_is_built_once_with_the_whole_model_s_vote() {
    // A sphere wound inward: each job, a part of it, looks open and alone would keep
    // its normals; the model, closed, turns them, and the plan's vote says so before
    // any job is built.
    let mut mesh = spt::io::ply::PolyMesh::default();
    sphere(&mut mesh, [-3.0, 0.0, 0.0], 2.0, false);
    let dir = common::temp_dir();
    let input = dir.path().join("sphere.ply");
    common::write_standard(&input, &mesh, spt::io::ply::Encoding::BinaryLittleEndian);
    let (built, list) = build_in_jobs(&input, 3000, dir.path());
    assert!(built.jobs > 1 && !built.rebuilt, "{} jobs", built.jobs);
    assert!(!list.meta.two_sided, "a closed sphere is drawn one-sided");
    let (ours, theirs) = (
        leaves_by_position(&list),
        leaves_by_position(&in_memory_list(&input)),
    );
    assert_eq!(ours.len(), theirs.len());
    for (at, (r, _)) in &ours {
        let m = theirs[at].0;
        let dot = spt::surfel::octahedral::oct_decode(r.normal)
            .dot(spt::surfel::octahedral::oct_decode(m.normal));
        assert!(dot > 0.999, "normal at {at:?}: cos {dot}");
    }
}

#[test]
fn stray_and_unstorable_points_are_dropped_or_kept_as_the_whole_file_reader_does() {
    // A 100 × 100 sheet, one stray sample 10⁶ away (an outlier, kept), one 10³⁰⁰
    // away and one NaN (both dropped: no f32 offset holds them).
    let mut positions: Vec<[f64; 3]> = (0..100 * 100)
        .map(|i| [(i % 100) as f64 * 0.01, (i / 100) as f64 * 0.01, 0.0])
        .collect();
    positions.extend([[1e6, 0.0, 0.0], [1e300, 0.0, 0.0], [f64::NAN, 0.0, 0.0]]);
    let dir = common::temp_dir();
    let input = write_cloud(dir.path(), "stray.ply", positions);
    let (built, list) = build_in_jobs(&input, 1500, dir.path());
    assert_eq!((built.dropped, built.outliers), (2, 1));
    // The grid spans the sheet, not the stray sample: the sheet is split.
    assert!(built.jobs >= 6, "{} jobs", built.jobs);
    let memory = in_memory_list(&input);
    assert_eq!(list.meta.leaf_count, memory.meta.leaf_count);
    assert_eq!(list.meta.leaf_count, 100 * 100 + 1);
}

#[test]
fn points_near_the_largest_double_build_in_jobs() {
    // Two points at 1.4 × 10³⁰⁸ (a LAZ tile's offset, rewritten by the fuzzer): their
    // coordinates' sum overflows, and the plan's mean, which its manifest stores, must
    // stay finite.
    let positions = vec![[1.4e308, 5e6, 100.0], [1.4e308, 5e6 + 0.5, 100.5]];
    let dir = common::temp_dir();
    let input = write_cloud(dir.path(), "far.ply", positions);
    let (built, list) = build_in_jobs(&input, 64, dir.path());
    assert_eq!(built.dropped, 0);
    assert_eq!(list.meta.leaf_count, in_memory_list(&input).meta.leaf_count);
}

#[test]
fn a_model_whose_disks_dwarf_its_points_box_gets_their_error_scale() {
    let positions = common::disks_dwarf_their_box();
    let dir = common::temp_dir();
    let input = write_cloud(dir.path(), "tiny.ply", positions);
    let (_, list) = build_in_jobs(&input, 64, dir.path());
    let memory = in_memory_list(&input);
    assert_eq!(list.meta.leaf_count, memory.meta.leaf_count);
    assert!(
        list.meta.error_scale >= memory.meta.error_scale / 64.0,
        "{:?}",
        list.meta
    );
    check_structure(&list.meta, &list.nodes, &list.parents, &list.chunks).unwrap();
}

#[test]
fn an_open_mesh_built_in_jobs_keeps_its_winding_and_is_drawn_two_sided() {
    // A 100 × 100 sheet bent into a trough (concave upward), wound to face up.
    let n = 100u32;
    let mut mesh = spt::io::ply::PolyMesh::default();
    for j in 0..n {
        for i in 0..n {
            let x = i as f64 / (n - 1) as f64 - 0.5;
            mesh.positions
                .push([x, j as f64 / (n - 1) as f64, 2.0 * x * x]);
        }
    }
    let at = |i: u32, j: u32| j * n + i;
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            mesh.faces.push(&[at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            mesh.faces.push(&[at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    let dir = common::temp_dir();
    let input = dir.path().join("trough.ply");
    common::write_standard(&input, &mesh, spt::io::ply::Encoding::BinaryLittleEndian);
    let (built, list) = build_in_jobs(&input, 3000, dir.path());
    assert!(built.jobs > 1 && !built.rebuilt);
    let memory = in_memory_list(&input);
    assert!(list.meta.two_sided && memory.meta.two_sided);
    for (_, (r, _)) in leaves_by_position(&list) {
        let up = spt::surfel::octahedral::oct_decode(r.normal).z;
        assert!(up > 0.0, "a normal turned down: {up}");
    }
}

#[test]
fn the_scan_s_strided_sample_is_every_stride_th_point() {
    // A LAS file's sampled rows are read each where its record lies, a LAZ file's in
    // its pass: both must be the rows a pass over every point strides to.
    use spt::io::formats::ModelStream;
    let dir = common::temp_dir();
    for compressed in [false, true] {
        let input = dir.path().join(if compressed { "s.laz" } else { "s.las" });
        std::fs::write(&input, common::las_files::sample(5000, compressed)).unwrap();
        let stream = ModelStream::open(&input).unwrap();
        let mut all = Vec::new();
        stream.points(|b| all.extend_from_slice(&b.xyz)).unwrap();
        assert_eq!(all.len(), 5000);
        for stride in [1, 7, 1000, 4999, 5000, 9000] {
            let mut sampled = Vec::new();
            stream
                .strided_positions(stride, |p| sampled.push(p))
                .unwrap();
            let every: Vec<[f64; 3]> = all.iter().copied().step_by(stride as usize).collect();
            assert_eq!(sampled, every, "stride {stride}, compressed {compressed}");
        }
    }
}

#[test]
fn a_pass_decoded_ahead_hands_the_same_rows_in_order() {
    // A LAS file's batches of 65,536 points and a LAZ file's one batch, cut for the
    // hand-over: the decoding thread recycles the batches its consumer is done with,
    // and no row may come out of order or changed.
    use spt::io::format::PointBatch;
    use spt::io::formats::{ModelStream, POINTS_AHEAD_BATCH};
    let dir = common::temp_dir();
    let rows = |batches: &[PointBatch]| {
        let mut all = PointBatch::default();
        for b in batches {
            all.xyz.extend_from_slice(&b.xyz);
            all.rgb.extend_from_slice(&b.rgb);
            all.normals.extend_from_slice(&b.normals);
            all.attributes.extend_from_slice(&b.attributes);
        }
        (all.xyz, all.rgb, all.normals, all.attributes)
    };
    for compressed in [false, true] {
        let input = dir.path().join(if compressed { "s.laz" } else { "s.las" });
        std::fs::write(&input, common::las_files::sample(4 * 65536 + 7, compressed)).unwrap();
        let stream = ModelStream::open(&input).unwrap();
        let (mut plain, mut ahead) = (Vec::new(), Vec::new());
        stream.points(|b| plain.push(b.clone())).unwrap();
        stream.points_ahead(|b| ahead.push(b.clone())).unwrap();
        assert_eq!(ahead.len(), 5, "compressed {compressed}");
        assert!(ahead.iter().all(|b| b.xyz.len() <= POINTS_AHEAD_BATCH));
        assert!(rows(&plain) == rows(&ahead), "compressed {compressed}");
        assert_eq!(rows(&plain).0.len(), 4 * 65536 + 7);
    }
    // A consumer that panics stops the pass: the panic comes through, nothing hangs.
    let stream = ModelStream::open(&dir.path().join("s.las")).unwrap();
    let stream = std::panic::AssertUnwindSafe(&stream);
    let stopped = std::panic::catch_unwind(|| stream.points_ahead(|_| panic!("stop")));
    assert!(stopped.is_err());
}
