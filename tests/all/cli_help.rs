//! Each subcommand's `--help` opens with its own description.

use crate::common;

#[test]
fn every_subcommand_explains_itself() {
    let openings = [
        ("info", "What a model file holds"),
        ("convert", "Builds the sequential point tree"),
        ("render", "Renders one frame"),
    ];
    for (command, opening) in openings {
        let (code, stdout, _) = common::run_spt(&[command, "--help"]);
        assert_eq!(code, Some(0), "{command}");
        assert!(
            stdout.starts_with(opening),
            "spt {command} --help opens with:\n{stdout}"
        );
        // One description only: no other subcommand's text leaked into it.
        let first = stdout.lines().next().unwrap();
        for (_, other) in openings {
            assert!(
                other == opening || !first.contains(other),
                "{command}: {first}"
            );
        }
    }
}

/// A reader that closes the pipe before spt prints (`spt convert IN OUT | head -0`)
/// loses the report, not the work: the file is written, spt succeeds, nothing panics.
#[test]
fn a_closed_pipe_loses_the_report_not_the_work() {
    use std::process::{Command, Stdio};
    let dir = common::temp_dir();
    let output = dir.path().join("knot.spt");
    let mut child = Command::new(env!("CARGO_BIN_EXE_spt"))
        .arg("convert")
        .arg(common::default_model())
        .arg(&output)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run spt");
    // Closed before spt has built the tree, so its first print meets a closed pipe.
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("wait for spt");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(out.status.success(), "{:?}: {stderr}", out.status);
    let (code, report, _) = common::run_spt(&[std::ffi::OsStr::new("info"), output.as_os_str()]);
    assert_eq!(code, Some(0), "spt info on the written file");
    assert!(report.contains("(holds)"), "{report}");
}
