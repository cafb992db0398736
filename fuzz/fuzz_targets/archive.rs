//! An uploaded bot archive (.tar.gz, .tar, .zip): any bytes are unpacked or refused,
//! never a panic; on success every file lies inside the destination and every symbolic
//! link points inside it; on refusal the destination is left empty.
#![no_main]

use libfuzzer_sys::fuzz_target;
use mazearena::botfiles::{BundleLimits, unpack_archive};

use std::path::Path;

/// Checks every entry below `dir`: inside `root`, and a symbolic link whose target
/// exists resolves inside `root` (the real resolution, through other links).
fn walk(dir: &Path, root: &Path) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        assert!(path.starts_with(root));
        let kind = std::fs::symlink_metadata(&path).unwrap().file_type();
        if kind.is_symlink() {
            let target = std::fs::read_link(&path).unwrap();
            assert!(target.is_relative(), "{}", path.display());
            if let Ok(real) = std::fs::canonicalize(&path) {
                assert!(
                    real.starts_with(root),
                    "{} -> {} leaves the bot",
                    path.display(),
                    target.display()
                );
            }
        } else if kind.is_dir() {
            walk(&path, root);
        }
    }
}

fuzz_target!(|data: &[u8]| {
    let tmp = tempfile::tempdir().unwrap();
    let dest = tmp.path().join("bot");
    std::fs::create_dir(&dest).unwrap();
    let limits = BundleLimits {
        max_total_bytes: 1 << 20,
        max_files: 64,
        ..BundleLimits::default()
    };
    match unpack_archive(data, &dest, &limits) {
        Ok(summary) => {
            let root = std::fs::canonicalize(&dest).unwrap();
            walk(&root, &root);
            assert_eq!(summary.sha256.len(), 64);
        }
        Err(_) => {
            let left = std::fs::read_dir(&dest).map(|d| d.count()).unwrap_or(0);
            assert_eq!(left, 0, "a refused archive left files");
        }
    }
});
