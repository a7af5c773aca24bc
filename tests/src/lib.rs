//! Cross-crate tests live in `tests/`; this library holds what the tests of
//! several crates share (the cross-crate tests and the `slamlab` binary's).

use std::path::{Path, PathBuf};

/// `rel` under the shared data sets (`$SLAMLAB_SHARED_DATA`, else
/// `$SLAMLAB_SHARED/data`, else `../shared/data` beside the repository), or
/// `None` with a line saying that the test needing it skips.
pub fn shared_data(rel: &str) -> Option<PathBuf> {
    let root = if let Some(data) = std::env::var_os("SLAMLAB_SHARED_DATA") {
        PathBuf::from(data)
    } else if let Some(shared) = std::env::var_os("SLAMLAB_SHARED") {
        PathBuf::from(shared).join("data")
    } else {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data")
    };
    let path = root.join(rel);
    if path.exists() {
        Some(path)
    } else {
        eprintln!(
            "skipped: {} is absent (the shared data sit beside the repository, or set \
             SLAMLAB_SHARED_DATA or SLAMLAB_SHARED)",
            path.display()
        );
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_file_is_none() {
        assert_eq!(shared_data("no/such/file.txt"), None);
    }
}
