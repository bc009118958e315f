//! The out-of-core build's steps run apart (`spt jobs plan|build|join`, and the library
//! functions under them): the same file as one process, byte for byte, whatever the
//! order of the jobs; a job run twice writes the same bytes; a truncated part is refused
//! by the join and built again; a damaged job input is refused by its checksum; a join
//! that needs another error scale asks for the parts again (exit 3). `spt convert`
//! removes each job's inputs as its part is built, and its parts as the join reads them.

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::common;

use spt::tree::out_of_core::checksums::Check;
use spt::tree::out_of_core::join::{Joined, join};
use spt::tree::out_of_core::manifest::Manifest;
use spt::tree::out_of_core::plan::{Planned, plan};
use spt::tree::out_of_core::run_job::{Ran, run};
use spt::tree::out_of_core::{AfterRead, Options, Progress, build_file};

struct Quiet;

impl Progress for Quiet {
    fn stage(&self, _: &'static str, _: u64) {}
    fn advance(&self, _: u64) {}
}

fn options(dir: &Path) -> Options {
    Options {
        job_points: 3000,
        spill_buffers: 1 << 20,
        temp_dir: dir.to_owned(),
    }
}

/// Each stage heard, with its total and the points counted in it.
#[derive(Default)]
struct Stages(Mutex<Vec<(&'static str, u64, u64)>>);

impl Progress for Stages {
    fn stage(&self, name: &'static str, total: u64) {
        self.0.lock().unwrap().push((name, total, 0));
    }
    fn advance(&self, n: u64) {
        self.0.lock().unwrap().last_mut().unwrap().2 += n;
    }
}

/// A LAS tile of 25,600 points, planned into `dir/jobs` in jobs of 3,000 points; each of
/// the plan's passes counts every point of the file, as its bar's total says.
fn planned(dir: &Path) -> (PathBuf, PathBuf, Manifest) {
    let input = dir.join("tile.las");
    std::fs::write(&input, common::las_files::sample(64 * 400, false)).unwrap();
    let jobs = dir.join("jobs");
    let stages = Stages::default();
    let planned = plan(&input, &jobs, &options(dir), &stages).unwrap();
    let Planned::New(m) = planned else {
        panic!("a fresh directory holds no plan")
    };
    assert!(m.jobs.len() >= 8, "{} jobs", m.jobs.len());
    let heard = stages.0.into_inner().unwrap();
    let names: Vec<&str> = heard.iter().map(|s| s.0).collect();
    assert_eq!(names, ["scan", "count", "spill"]);
    assert!(
        heard.iter().all(|s| s.1 == 64 * 400 && s.2 == s.1),
        "{heard:?}"
    );
    (input, jobs, m)
}

/// Hears the join's write: the size it announces and the bytes it counts after.
#[derive(Default)]
struct Written {
    announced: AtomicU64,
    counted: AtomicU64,
}

impl Progress for Written {
    fn stage(&self, _: &'static str, _: u64) {}
    fn advance(&self, n: u64) {
        self.counted.fetch_add(n, Ordering::Relaxed);
    }
    fn writing(&self, bytes: u64) {
        self.announced.store(bytes, Ordering::Relaxed);
        self.counted.store(0, Ordering::Relaxed);
    }
}

/// The file the join writes, the parts' bytes kept or freed once read (`after`); it
/// tells its size first and then every byte.
fn joined_then(jobs: &Path, output: &Path, after: AfterRead) -> Vec<u8> {
    let written = Written::default();
    match join(jobs, output, (Check::Checksums, after), &written).unwrap() {
        Joined::Written(_) => {
            let file = std::fs::read(output).unwrap();
            let size = file.len() as u64;
            assert_eq!(written.announced.load(Ordering::Relaxed), size);
            assert_eq!(written.counted.load(Ordering::Relaxed), size);
            file
        }
        Joined::Rebuild(why) => panic!("asked for the parts again: {why}"),
    }
}

/// The file the join writes, the parts kept.
fn joined(jobs: &Path, output: &Path) -> Vec<u8> {
    joined_then(jobs, output, AfterRead::Keep)
}

#[test]
fn steps_run_apart_in_any_order_give_the_file_of_one_process() {
    let dir = common::temp_dir();
    let (input, jobs, m) = planned(dir.path());
    let one_process = dir.path().join("one.spt");
    build_file(&input, &one_process, &options(dir.path()), &Quiet).unwrap();
    for j in (0..m.jobs.len()).rev() {
        assert!(matches!(
            run(&jobs, &m, j, Check::Checksums).unwrap(),
            Ran::Built(_)
        ));
    }
    let apart = joined(&jobs, &dir.path().join("apart.spt"));
    assert_eq!(apart, std::fs::read(&one_process).unwrap());
    // Planned again: the plan is kept, and so is every part.
    let again = plan(&input, &jobs, &options(dir.path()), &Quiet).unwrap();
    assert!(matches!(again, Planned::Kept(_)));
    assert!(matches!(
        run(&jobs, &m, 0, Check::Checksums).unwrap(),
        Ran::Kept(_)
    ));
    // A job run again from scratch writes the same bytes.
    let part = jobs.join("job3.part");
    let first = std::fs::read(&part).unwrap();
    std::fs::remove_file(jobs.join("job3.part.json")).unwrap();
    assert!(matches!(
        run(&jobs, &m, 3, Check::Checksums).unwrap(),
        Ran::Built(_)
    ));
    assert_eq!(std::fs::read(&part).unwrap(), first);
}

#[test]
fn a_truncated_part_is_refused_by_the_join_and_built_again() {
    let dir = common::temp_dir();
    let (_, jobs, m) = planned(dir.path());
    for j in 0..m.jobs.len() {
        run(&jobs, &m, j, Check::Checksums).unwrap();
    }
    let output = dir.path().join("out.spt");
    let whole = joined(&jobs, &output);
    let part = jobs.join("job2.part");
    let bytes = std::fs::read(&part).unwrap();
    std::fs::write(&part, &bytes[..bytes.len() / 2]).unwrap();
    let refused = join(&jobs, &output, (Check::Checksums, AfterRead::Keep), &Quiet)
        .unwrap_err()
        .to_string();
    assert!(
        refused.contains("job2.part") && refused.contains("truncated"),
        "{refused}"
    );
    // The file already there is untouched.
    assert_eq!(std::fs::read(&output).unwrap(), whole);
    let ran: Vec<bool> = (0..m.jobs.len())
        .map(|j| matches!(run(&jobs, &m, j, Check::Checksums).unwrap(), Ran::Built(_)))
        .collect();
    assert_eq!(ran.iter().filter(|&&b| b).count(), 1, "{ran:?}");
    assert!(ran[2]);
    assert_eq!(joined(&jobs, &output), whole);
}

#[test]
fn a_damaged_job_input_is_refused_by_its_checksum() {
    let dir = common::temp_dir();
    let (_, jobs, m) = planned(dir.path());
    let own = jobs.join(&m.jobs[1].files[0].name);
    let mut bytes = std::fs::read(&own).unwrap();
    bytes[100] ^= 0x10;
    std::fs::write(&own, &bytes).unwrap();
    let refused = format!("{:#}", run(&jobs, &m, 1, Check::Checksums).unwrap_err());
    assert!(
        refused.contains(&*own.to_string_lossy()) && refused.contains("damaged"),
        "{refused}"
    );
    assert!(!jobs.join("job1.part").exists());
}

/// An edit of a manifest.
type Lie = Box<dyn Fn(&mut Manifest)>;

#[test]
fn a_manifest_that_lies_is_refused_with_its_path() {
    let dir = common::temp_dir();
    let (_, jobs, m) = planned(dir.path());
    let cases: [(&str, Lie); 3] = [
        (
            "twice",
            Box::new(|m| {
                let first = m.split.iter().position(|&c| c >= 0).unwrap();
                m.split[first] = m.split[first + 1];
            }),
        ),
        (
            "not a plain name",
            Box::new(|m| m.jobs[0].files[0].name = "../x".into()),
        ),
        (
            "ends early",
            Box::new(|m| {
                m.split.pop();
            }),
        ),
    ];
    for (says, lie) in cases {
        let mut bad = m.clone();
        lie(&mut bad);
        let text = serde_json::to_string(&bad).unwrap();
        std::fs::write(Manifest::path(&jobs), text).unwrap();
        let e = Manifest::read(&jobs).unwrap_err().to_string();
        assert!(e.contains("manifest.json") && e.contains(says), "{e}");
    }
    std::fs::write(Manifest::path(&jobs), "{\"format\": 1").unwrap();
    let e = Manifest::read(&jobs).unwrap_err().to_string();
    assert!(e.contains("not a job manifest"), "{e}");
}

#[test]
fn the_commands_ask_for_the_parts_again_when_the_join_needs_another_error_scale() {
    // The leaves' error scale is known only once they are built.
    let dir = common::temp_dir();
    let d = dir.path();
    let cloud = spt::io::ply::PolyMesh {
        positions: common::disks_dwarf_their_box(),
        normals: None,
        colors: None,
        faces: spt::io::ply::FaceList::default(),
    };
    let input = d.join("tiny.ply");
    common::write_double(&input, &cloud);
    let jobs = d.join("jobs");
    let spt = |args: &[&Path]| common::run_spt(args);
    let (plan, build, join) = (Path::new("plan"), Path::new("build"), Path::new("join"));
    let cmd = Path::new("jobs");
    let out = d.join("tiny.spt");
    let (status, _, err) = spt(&[cmd, join, &jobs, &out]);
    assert_eq!(status, Some(1), "{err}");
    assert!(err.contains("manifest.json"), "{err}");
    assert_eq!(spt(&[cmd, plan, &input, &jobs]).0, Some(0));
    let (status, _, err) = spt(&[cmd, join, &jobs, &out]);
    assert!(
        status == Some(1) && err.contains("job 0 has no part"),
        "{err}"
    );
    assert_eq!(spt(&[cmd, build, &jobs]).0, Some(0));
    let (status, _, err) = spt(&[cmd, join, &jobs, &out]);
    assert!(
        status == Some(3) && err.contains("error scale"),
        "{status:?} {err}"
    );
    assert!(!out.exists());
    assert_eq!(spt(&[cmd, build, &jobs]).0, Some(0));
    let clean = Path::new("--clean");
    let (status, _, err) = spt(&[cmd, join, &jobs, &out, clean]);
    assert_eq!(status, Some(0), "{err}");
    assert!(!jobs.exists(), "--clean leaves the job directory");
    let one = d.join("one.spt");
    let convert = Path::new("convert");
    let ooc = Path::new("--out-of-core");
    let (status, said, err) = spt(&[convert, &input, &one, ooc]);
    assert_eq!(status, Some(0), "{err}");
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&one).unwrap());
    // Each stage's line, the write's with the file, its size and rate; none with an
    // empty summary before its CPU time.
    let said = format!("{said}{err}");
    let mut writes = said.lines().filter(|l| l.trim_start().starts_with("write"));
    // This model's parts need another error scale: the first join writes nothing.
    let first = writes.next().unwrap_or_default();
    assert!(first.contains("not written: the leaves need"), "{said}");
    let write = writes.next();
    let written = format!("{} (", one.display());
    assert!(
        write.is_some_and(|l| l.contains(&written) && l.contains(" MB/s)")),
        "{said}"
    );
    assert!(!said.contains("s  ;"), "{said}");
}

/// Bytes the file system holds for `path` (its blocks, not its length).
#[cfg(unix)]
fn held_bytes(path: &Path) -> u64 {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(path).unwrap().blocks() * 512
}

#[test]
#[cfg(unix)]
fn a_join_that_frees_its_parts_writes_the_same_file_and_leaves_no_job_input() {
    let dir = common::temp_dir();
    let (_, jobs, m) = planned(dir.path());
    for j in 0..m.jobs.len() {
        run(&jobs, &m, j, Check::Checksums).unwrap();
    }
    let kept = joined(&jobs, &dir.path().join("kept.spt"));
    let parts: Vec<PathBuf> = (0..m.jobs.len())
        .map(|j| jobs.join(format!("job{j}.part")))
        .collect();
    let sizes: Vec<u64> = parts
        .iter()
        .map(|p| std::fs::metadata(p).unwrap().len())
        .collect();
    let before: u64 = parts.iter().map(|p| held_bytes(p)).sum();
    let freed = joined_then(&jobs, &dir.path().join("freed.spt"), AfterRead::Free);
    assert!(kept == freed, "the files differ");
    for f in m.jobs.iter().flat_map(|j| &j.files) {
        assert!(!jobs.join(&f.name).exists(), "{} is left", f.name);
    }
    let after: u64 = parts.iter().map(|p| held_bytes(p)).sum();
    let lengths: Vec<u64> = parts
        .iter()
        .map(|p| std::fs::metadata(p).unwrap().len())
        .collect();
    assert_eq!(lengths, sizes, "a part's length changed");
    // Whether this file system frees blocks at all: a file of its own freed whole.
    let probe = dir.path().join("probe");
    std::fs::write(&probe, vec![1u8; 1 << 20]).unwrap();
    let mut releaser = spt::io::release::Releaser::open(&probe).unwrap();
    releaser.mark_read(0..1 << 20);
    releaser.flush();
    println!("parts held {before} bytes before the join, {after} after");
    if releaser.freed == 0 {
        eprintln!("this file system frees no blocks: the parts' size is not checked");
        return;
    }
    assert!(after * 4 < before, "{after} of {before} bytes left");
}

/// The job inputs in the build directories under `dir` (`spt-build-*`): files named
/// `jobN.KIND` other than parts and their records.
fn job_inputs_under(dir: &Path) -> usize {
    let builds = std::fs::read_dir(dir).unwrap().flatten();
    let builds = builds.filter(|e| e.file_name().to_string_lossy().starts_with("spt-build-"));
    let files = builds.flat_map(|b| std::fs::read_dir(b.path()).unwrap().flatten());
    files
        .filter(|f| {
            let name = f.file_name().to_string_lossy().into_owned();
            name.starts_with("job") && !name.contains(".part")
        })
        .count()
}

/// Counts the job inputs left under `dir` each time a job of the build ends.
struct InputsLeft<'a> {
    dir: &'a Path,
    building: Mutex<bool>,
    left: Mutex<Vec<usize>>,
}

impl Progress for InputsLeft<'_> {
    fn stage(&self, name: &'static str, _: u64) {
        *self.building.lock().unwrap() = name == "build";
    }
    fn advance(&self, _: u64) {
        if *self.building.lock().unwrap() {
            self.left.lock().unwrap().push(job_inputs_under(self.dir));
        }
    }
}

#[test]
fn spt_convert_removes_each_job_s_inputs_once_its_part_is_built() {
    let dir = common::temp_dir();
    let input = dir.path().join("tile.las");
    std::fs::write(&input, common::las_files::sample(64 * 400, false)).unwrap();
    let temp = dir.path().join("temp");
    std::fs::create_dir(&temp).unwrap();
    let heard = InputsLeft {
        dir: &temp,
        building: Mutex::new(false),
        left: Mutex::new(Vec::new()),
    };
    let output = dir.path().join("tile.spt");
    build_file(&input, &output, &options(&temp), &heard).unwrap();
    let left = heard.left.into_inner().unwrap();
    // Each job's inputs are gone by the time it is told done (two run at once, so two
    // may go between two tellings): the count falls to none, from some left when the
    // first job ends.
    assert!(left.len() >= 8, "{} jobs", left.len());
    assert!(left.windows(2).all(|w| w[1] <= w[0]), "{left:?}");
    assert!(left[0] > 0 && *left.last().unwrap() == 0, "{left:?}");
}
