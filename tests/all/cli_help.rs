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

/// A reader that closes the pipe before spt prints (`spt info MODEL | head -0`) ends it
/// quietly: killed by SIGPIPE or finished, never a panic on the failed print.
#[cfg(target_os = "linux")]
#[test]
fn a_closed_pipe_ends_spt_quietly() {
    use std::os::unix::process::ExitStatusExt;
    use std::process::{Command, Stdio};
    let mut child = Command::new(env!("CARGO_BIN_EXE_spt"))
        .arg("info")
        .arg(common::default_model())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run spt");
    // Closed before spt has read the model, so its first print meets a closed pipe.
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("wait for spt");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(
        out.status.success() || out.status.signal() == Some(libc::SIGPIPE),
        "{:?}: {stderr}",
        out.status
    );
}
