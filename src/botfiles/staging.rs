//! The destination directory and the staging directory the bundle is built in.

use std::fs;
use std::io;
use std::os::unix::fs::DirBuilderExt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use super::BundleError;

pub(super) fn io_err(action: impl FnOnce() -> String) -> impl FnOnce(io::Error) -> BundleError {
    move |source| BundleError::Io {
        action: action(),
        source,
    }
}

/// Checks that `dest` is an existing, empty, real directory; returns its permissions.
pub(super) fn check_dest(dest: &Path) -> Result<fs::Permissions, BundleError> {
    let bad = |reason: &str| BundleError::Destination {
        path: dest.to_owned(),
        reason: reason.to_owned(),
    };
    let meta = match fs::symlink_metadata(dest) {
        Ok(meta) => meta,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Err(bad("it does not exist")),
        Err(e) => return Err(io_err(|| format!("inspect {dest:?}"))(e)),
    };
    if !meta.file_type().is_dir() {
        return Err(bad("it is not a directory (or is a symbolic link)"));
    }
    let mut listing = fs::read_dir(dest).map_err(io_err(|| format!("list {dest:?}")))?;
    if listing.next().is_some() {
        return Err(bad("it is not empty"));
    }
    if dest.file_name().is_none() {
        return Err(bad("it has no final name component"));
    }
    Ok(meta.permissions())
}

/// A directory next to `dest` that is removed on drop unless committed.
pub(super) struct Staging {
    pub(super) path: PathBuf,
    committed: bool,
}

impl Staging {
    pub(super) fn create(dest: &Path) -> Result<Self, BundleError> {
        static COUNTER: AtomicU64 = AtomicU64::new(0);
        let parent = match dest.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        // Keep the staging name well under the 255-byte limit of a name.
        let base: String = dest
            .file_name()
            .map(|n| n.to_string_lossy().chars().take(64).collect())
            .unwrap_or_default();
        let mut attempts = 0;
        loop {
            let n = COUNTER.fetch_add(1, Ordering::Relaxed);
            let path = parent.join(format!(".{base}.staging-{}-{n}", std::process::id()));
            match fs::DirBuilder::new().mode(0o700).create(&path) {
                Ok(()) => {
                    return Ok(Self {
                        path,
                        committed: false,
                    });
                }
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists && attempts < 100 => {
                    attempts += 1;
                }
                Err(e) => return Err(io_err(|| format!("create staging directory {path:?}"))(e)),
            }
        }
    }

    pub(super) fn commit(mut self, dest: &Path, perms: fs::Permissions) -> Result<(), BundleError> {
        fs::set_permissions(&self.path, perms)
            .map_err(io_err(|| format!("set permissions of {:?}", self.path)))?;
        fs::rename(&self.path, dest)
            .map_err(io_err(|| format!("move {:?} to {dest:?}", self.path)))?;
        self.committed = true;
        Ok(())
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if !self.committed {
            // Does not follow symbolic links.
            let _ = fs::remove_dir_all(&self.path);
        }
    }
}
