//! Outputs that cannot be written: every command that writes a file refuses it with
//! exit code 1 and an error naming it, before it reads or builds anything, and never
//! replaces a file it reads.

use std::path::Path;

use crate::common;

/// Runs spt with `args` and asserts that it refused at once: exit code 1, an error
/// that names `written` and says `why`, and none of a build's stage lines printed.
fn refuses(args: &[&Path], written: &Path, why: &str) {
    let (code, stdout, stderr) = common::run_spt(args);
    let shown = format!("spt {args:?}: {stderr}");
    assert_eq!(code, Some(1), "{shown}");
    let named = format!("error: cannot write {}: ", written.display());
    assert!(
        stderr.starts_with(&named) && stderr.contains(why),
        "{shown}"
    );
    assert!(!stderr.contains("panicked"), "{shown}");
    assert!(
        !stdout.contains("surfels") && !stdout.contains("adapter"),
        "{shown}: {stdout}"
    );
}

#[test]
fn an_output_in_a_missing_folder_is_refused_before_any_work() {
    let dir = common::temp_dir();
    let model = dir.path().join("knot.ply");
    std::fs::copy(common::default_model(), &model).unwrap();
    let missing = dir.path().join("no such folder");
    let p = |s: &str| Path::new(s).to_path_buf();
    let spt = missing.join("knot.spt");
    let png = missing.join("knot.png");
    let scene = missing.join("forest.json");
    let cases = [
        vec![p("convert"), model.clone(), spt.clone()],
        vec![p("convert"), model.clone(), spt.clone(), p("--out-of-core")],
        vec![p("render"), model.clone(), p("-o"), png.clone()],
        vec![p("view"), model.clone(), p("--screenshot"), png.clone()],
        vec![p("jobs"), p("join"), dir.path().to_path_buf(), spt.clone()],
    ];
    for args in &cases {
        let written = args.iter().find(|a| a.starts_with(&missing)).unwrap();
        let args: Vec<&Path> = args.iter().map(|a| a.as_path()).collect();
        refuses(&args, written, "does not exist");
    }
    let scatter = [
        p("scatter"),
        model.clone(),
        model.clone(),
        p("-o"),
        scene.clone(),
    ];
    let args: Vec<&Path> = scatter.iter().map(|a| a.as_path()).collect();
    refuses(&args, &scene, "does not exist");
    let folder = [p("convert"), model.clone(), dir.path().to_path_buf()];
    let args: Vec<&Path> = folder.iter().map(|a| a.as_path()).collect();
    refuses(&args, dir.path(), "it is a directory");
}

#[test]
fn a_command_never_writes_over_its_input() {
    let dir = common::temp_dir();
    let model = dir.path().join("knot.ply");
    std::fs::copy(common::default_model(), &model).unwrap();
    let before = std::fs::read(&model).unwrap();
    // The same file under another name: through its folder's "..".
    let again = dir.path().join("sub/../knot.ply");
    std::fs::create_dir(dir.path().join("sub")).unwrap();
    let convert = ["convert".as_ref(), model.as_path(), again.as_path()];
    let render = [
        "render".as_ref(),
        model.as_path(),
        "-o".as_ref(),
        again.as_path(),
    ];
    refuses(&convert, &again, "it is the input");
    refuses(&render, &again, "it is the input");
    assert!(
        std::fs::read(&model).unwrap() == before,
        "the input changed"
    );
}

#[test]
fn the_disk_check_s_estimate_holds_the_file() {
    let dir = common::temp_dir();
    let las = dir.path().join("tile.las");
    std::fs::write(&las, common::las_files::sample(20_000, false)).unwrap();
    for (model, points) in [(common::default_model(), 50_000), (las, 20_000)] {
        let spt = dir.path().join("out.spt");
        let (code, _, stderr) =
            common::run_spt(&["convert".as_ref(), model.as_os_str(), spt.as_os_str()]);
        assert_eq!(code, Some(0), "{stderr}");
        let per_point = std::fs::metadata(&spt).unwrap().len() as f64 / points as f64;
        let estimate = spt::apps::disk::FILE_BYTES_PER_POINT as f64;
        println!(
            "{}: {per_point:.1} bytes a point, estimate {estimate}",
            model.display()
        );
        assert!(
            per_point <= estimate && per_point > 0.85 * estimate,
            "{}",
            model.display()
        );
    }
}
