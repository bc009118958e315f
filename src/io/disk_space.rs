//! Free space on a file system, so that a command can say before a long build whether
//! what it will write fits.

use std::path::Path;

/// Bytes an unprivileged process may still write on the file system that holds `dir`
/// (`statvfs`: available blocks × fragment size); `None` where that is unknown.
#[cfg(target_os = "linux")]
pub fn available_bytes(dir: &Path) -> Option<u64> {
    use std::os::unix::ffi::OsStrExt;
    let path = std::ffi::CString::new(dir.as_os_str().as_bytes()).ok()?;
    // SAFETY: statvfs is plain old data, which zeroes are a valid value of.
    let mut s: libc::statvfs = unsafe { std::mem::zeroed() };
    // SAFETY: `path` is NUL-terminated and `s` a statvfs for the call to fill.
    let ok = unsafe { libc::statvfs(path.as_ptr(), &mut s) } == 0;
    ok.then(|| s.f_bavail as u64 * s.f_frsize as u64)
}

/// Bytes an unprivileged process may still write where `dir` is: unknown here.
#[cfg(not(target_os = "linux"))]
pub fn available_bytes(_dir: &Path) -> Option<u64> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_current_folder_has_a_size_and_a_missing_one_none() {
        if cfg!(target_os = "linux") {
            assert!(available_bytes(Path::new(".")).is_some());
            assert!(available_bytes(Path::new("/no/such/folder/here")).is_none());
        }
    }
}
