//! Bad files are refused with an error naming the file and the problem, and no
//! allocation grows with a header count that the file cannot hold. Each test runs
//! alone in its binary: the allocation counter sees every thread of the process.

use crate::common;

use crate::common::bad_files::fixtures;
use spt::io::ply::read_ply;

#[test]
fn bad_files_are_refused_with_a_clear_error_and_no_large_allocation() {
    let _alone = crate::alone();
    let dir = common::temp_dir();
    for f in fixtures(dir.path()) {
        let path = dir.path().join(f.name);
        std::fs::write(&path, &f.bytes).unwrap();
        crate::largest_allocation::reset();
        let err = read_ply(&path).expect_err(f.name).to_string();
        let largest = crate::largest_allocation::largest();
        // The test harness itself allocates a few KiB; a header count would take GBs.
        common::bad_files::check_refusal(f.name, &err, f.expect, largest, 1 << 20);
    }
}
