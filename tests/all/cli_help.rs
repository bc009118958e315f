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
