//! The command-line applications built on the library.

/// `println!` that ignores a failed write: a reader that closes the pipe early (`spt
/// bench … | head -3`) loses the rest of the report, not the work, and nothing panics.
/// Defined before the modules below, which see it by textual scope.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

/// `text` on standard output as it is, a failed write ignored (as `say!`).
pub(crate) fn say_text(text: &str) {
    use std::io::Write as _;
    let _ = std::io::stdout().write_all(text.as_bytes());
}

pub mod bench;
pub mod cloud_quality;
pub mod convert;
pub mod convert_large;
pub mod disk;
pub mod frame_args;
pub mod info;
pub mod info_scene;
pub mod jobs;
pub mod progress;
pub mod render;
pub mod render_scene;
pub mod scatter;
pub mod stats;
pub mod text;
pub mod view;
