//! Bad scenes: each exits 1 with a message naming the file and the place at fault,
//! never a panic; an instance file whose header claims more rows than it holds is
//! refused before anything is allocated for them. `spt info` and `spt render` read
//! scenes the same way (`spt::tree::instances::read_scene`).

use std::path::Path;

use glam::{DQuat, DVec3};

use crate::common;
use spt::tree::instances::Instance;
use spt::tree::instances::table::write_instances;

/// `spt render SCENE` exits 1 with a message holding every one of `expect`.
fn refused(scene: &Path, expect: &[&str]) {
    let out = scene.with_extension("png");
    let (code, _, err) = common::run_spt(&[
        "render".as_ref(),
        scene.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "--size".as_ref(),
        "64x64".as_ref(),
    ]);
    assert_eq!(code, Some(1), "{}: {err}", scene.display());
    assert!(!err.contains("panicked"), "{err}");
    for e in expect {
        assert!(
            err.contains(e),
            "{}: expected '{e}' in: {err}",
            scene.display()
        );
    }
    assert!(!out.exists(), "no picture of a bad scene");
}

/// A scene file of `instances` (JSON entries) over the default model.
fn scene(dir: &Path, name: &str, models: &str, instances: &str) -> std::path::PathBuf {
    let path = dir.join(format!("{name}.json"));
    let text = format!(r#"{{"models": [{models}], "instances": [{instances}]}}"#);
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn bad_scenes_are_refused_with_the_file_and_the_place() {
    let dir = common::temp_dir();
    let d = dir.path();
    let knot = format!("{:?}", common::default_model().display().to_string());
    let cases: Vec<(std::path::PathBuf, Vec<&str>)> = vec![
        (
            scene(d, "missing", r#""no_such_model.ply""#, r#"{"model": 0}"#),
            vec!["missing.json", "no_such_model.ply"],
        ),
        (
            scene(d, "beyond", &knot, r#"{"model": 0}, {"model": 3}"#),
            vec![
                "beyond.json",
                "instances[1]",
                "model 3 is not among the scene's 1 models",
            ],
        ),
        (
            scene(d, "zero_scale", &knot, r#"{"model": 0, "scale": 0}"#),
            vec!["zero_scale.json", "instances[0]", "scale 0 is not positive"],
        ),
        (
            scene(d, "negative_scale", &knot, r#"{"model": 0, "scale": -2}"#),
            vec!["instances[0]", "scale -2 is not positive"],
        ),
        (
            scene(
                d,
                "huge",
                &knot,
                r#"{"model": 0, "translation": [1e999, 0, 0]}"#,
            ),
            vec!["huge.json", "line 1"],
        ),
        (
            scene(
                d,
                "no_rotation",
                &knot,
                r#"{"model": 0, "rotation": [0, 0, 0, 0]}"#,
            ),
            vec!["instances[0]", "is not a rotation"],
        ),
        (
            scene(d, "typo", &knot, r#"{"model": 0, "scael": 2}"#),
            vec!["typo.json", "line 1"],
        ),
        (
            scene(d, "none", &knot, ""),
            vec!["none.json", "places no instance"],
        ),
    ];
    for (path, expect) in &cases {
        refused(path, expect);
    }
}

/// An instance file with one instance of `Instance` fields edited by `edit` (on the
/// written bytes), in a scene over the default model.
fn instance_file(dir: &Path, name: &str, edit: impl Fn(&mut Vec<u8>, usize)) -> std::path::PathBuf {
    let table = dir.join(format!("{name}.instances.ply"));
    let good = Instance::checked(0, DVec3::new(1.0, 2.0, 3.0), DQuat::IDENTITY, 1.0, 1).unwrap();
    write_instances(&table, &[good, good]).unwrap();
    let mut bytes = std::fs::read(&table).unwrap();
    let payload = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    edit(&mut bytes, payload);
    std::fs::write(&table, bytes).unwrap();
    let knot = format!("{:?}", common::default_model().display().to_string());
    let file = format!(r#"{{"file": "{name}.instances.ply"}}"#);
    scene(dir, name, &knot, &file)
}

#[test]
fn bad_instance_files_are_refused_with_the_file_and_the_row() {
    let dir = common::temp_dir();
    let d = dir.path();
    // Row 1's x (the second row: 48 bytes a row) set to NaN; its scale to −1 (after
    // x y z as doubles); its model to 7; the header's count raised to 10⁹.
    let nan = instance_file(d, "nan", |b, at| {
        b[at + 48..at + 56].copy_from_slice(&f64::NAN.to_le_bytes())
    });
    refused(&nan, &["nan.instances.ply", "row 1", "not finite"]);
    let negative = instance_file(d, "negative", |b, at| {
        b[at + 72..at + 76].copy_from_slice(&(-1f32).to_le_bytes())
    });
    refused(
        &negative,
        &[
            "negative.instances.ply",
            "row 1",
            "scale -1 is not positive",
        ],
    );
    let model = instance_file(d, "model", |b, at| {
        b[at + 92..at + 96].copy_from_slice(&7u32.to_le_bytes())
    });
    refused(
        &model,
        &["model.instances.ply", "row 1", "model 7 is not among"],
    );
    let lying = instance_file(d, "lying", |b, _| {
        let (from, to): (&[u8], &[u8]) = (b"element vertex 2\n", b"element vertex 1000000000\n");
        let at = b.windows(from.len()).position(|w| w == from).unwrap();
        b.splice(at..at + from.len(), to.iter().copied());
    });
    refused(
        &lying,
        &[
            "lying.instances.ply",
            "the header says 1000000000 rows",
            "holds 2",
        ],
    );
    let missing = instance_file(d, "gone", |_, _| {});
    std::fs::remove_file(d.join("gone.instances.ply")).unwrap();
    refused(&missing, &["gone.instances.ply"]);
}
