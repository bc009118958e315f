//! The up axis: each file's default (a PLY model y, a PLY header's comment its axis,
//! LAS and LAZ z, a terrain z), kept in `.spt` files built in memory and out of core,
//! said by `spt info`, and `--up` turning the rendered image.

use std::path::Path;

use crate::common;
use spt::io::formats::read_model;
use spt::io::ply::{Encoding, PlyLayout, write_ply};
use spt::io::torus_knot::torus_knot;
use spt::io::up::UpAxis;
use spt::tree::scene::Scene;

/// The axis `spt info` prints for `path`.
fn info_up(path: &Path) -> String {
    let (code, stdout, stderr) = common::run_spt(&["info".as_ref(), path.as_os_str()]);
    assert_eq!(code, Some(0), "{stderr}");
    let line = stdout
        .lines()
        .find(|l| l.starts_with("up "))
        .expect("an up line");
    line.split_whitespace().nth(1).unwrap().to_owned()
}

/// The axis of the `.spt` file `spt convert [extra]` makes of `path`.
fn converted_up(path: &Path, extra: &[&str], dir: &Path) -> Option<UpAxis> {
    let out = dir.join("out.spt");
    let mut args = vec![
        std::ffi::OsStr::new("convert"),
        path.as_os_str(),
        out.as_os_str(),
    ];
    args.extend(extra.iter().map(std::ffi::OsStr::new));
    let (code, _, stderr) = common::run_spt(&args);
    assert_eq!(code, Some(0), "{stderr}");
    Scene::open(&out).unwrap().meta().up
}

#[test]
fn each_file_stands_on_its_default_axis_and_spt_files_keep_it() {
    let dir = common::temp_dir();
    let d = dir.path();
    let knot = torus_knot(60, 12, false);
    let plain = d.join("plain.ply");
    common::write_standard(&plain, &knot, Encoding::BinaryLittleEndian);
    let said = d.join("said.ply");
    let mut layout = PlyLayout::standard(Encoding::Ascii, &knot);
    layout.comments = vec!["exported Z-up".to_owned()];
    write_ply(&said, &knot, &layout).unwrap();
    // A flat sheet of 40 × 40 samples, 0.1 high: a terrain.
    let sheet: Vec<String> = (0..1600)
        .map(|i| format!("{} {} {}", i % 40, i / 40, ((i * 7) % 10) as f64 * 0.01))
        .collect();
    let terrain = d.join("terrain.ply");
    let header = "ply\nformat ascii 1.0\nelement vertex 1600\nproperty float x\n\
                  property float y\nproperty float z\nend_header\n";
    std::fs::write(&terrain, format!("{header}{}\n", sheet.join("\n"))).unwrap();
    let las = d.join("tile.las");
    std::fs::write(&las, common::las_files::sample(3000, false)).unwrap();
    assert_eq!(read_model(&las).unwrap().summary.up, Some(UpAxis::Z));
    assert_eq!(read_model(&plain).unwrap().summary.up, None);
    let (_, json, _) = common::run_spt(&["info".as_ref(), "--json".as_ref(), plain.as_os_str()]);
    assert!(json.contains("\"up\": \"y\""), "{json}");
    for (path, up) in [
        (&plain, UpAxis::Y),
        (&said, UpAxis::Z),
        (&terrain, UpAxis::Z),
        (&las, UpAxis::Z),
    ] {
        let name = path.file_name().unwrap().to_string_lossy();
        assert_eq!(info_up(path), up.name(), "{name}");
        assert_eq!(Scene::open(path).unwrap().meta().up, Some(up), "{name}");
        assert_eq!(converted_up(path, &[], d), Some(up), "{name}");
        let ooc = converted_up(path, &["--out-of-core"], d);
        assert_eq!(ooc, Some(up), "{name} out of core");
    }
}

#[test]
fn up_turns_the_rendered_image_and_the_default_is_the_file_s() {
    let dir = common::temp_dir();
    let plain = dir.path().join("plain.ply");
    common::write_standard(
        &plain,
        &torus_knot(60, 12, false),
        Encoding::BinaryLittleEndian,
    );
    let render = |name: &str, up: Option<&str>| {
        let png = dir.path().join(name);
        let mut args = vec![
            "render",
            plain.to_str().unwrap(),
            "-o",
            png.to_str().unwrap(),
        ];
        args.extend(["--size", "160x120", "--culling", "vertex"]);
        if let Some(up) = up {
            args.extend(["--up", up]);
        }
        let (code, _, stderr) = common::run_spt(&args);
        assert_eq!(code, Some(0), "{stderr}");
        image::open(&png).unwrap().to_rgba8().into_raw()
    };
    let default = render("default.png", None);
    let y = render("y.png", Some("y"));
    let z = render("z.png", Some("z"));
    let minus_y = render("-y.png", Some("-y"));
    let differ = |a: &[u8], b: &[u8]| a.iter().zip(b).filter(|(x, y)| x != y).count();
    assert_eq!(differ(&default, &y), 0, "the default of a plain PLY is y");
    // Other axes turn the model: a tenth of the bytes or more change.
    for (name, other) in [("z", &z), ("-y", &minus_y)] {
        let changed = differ(&default, other);
        eprintln!("--up {name}: {changed} of {} bytes differ", default.len());
        assert!(changed * 10 > default.len() / 10, "--up {name}: {changed}");
    }
}
