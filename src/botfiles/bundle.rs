//! The bundle being built in the staging directory: writing files,
//! directories and links safely, within the limits.

use std::collections::BTreeMap;
use std::fs::{self, File, OpenOptions};
use std::io::{self, Read, Write};
use std::os::unix::fs::{OpenOptionsExt, PermissionsExt};
use std::path::PathBuf;

use sha2::{Digest, Sha256};

use super::hash::{Node, content_hash};
use super::names::{has_drive_prefix, parents, parse_path};
use super::staging::io_err;
use super::{BundleError, BundleLimits, BundleSummary, MAX_PATH_BYTES};

/// Deepest chain of symbolic links followed when checking a link (as Linux).
const MAX_LINK_EXPANSIONS: usize = 40;

/// The bundle being built in the staging directory.
pub(super) struct Bundle {
    root: PathBuf,
    pub(super) limits: BundleLimits,
    /// Everything created, by normalised path.
    nodes: BTreeMap<String, Node>,
    /// Symbolic links to create at the end: (client's name, normalised path).
    links: Vec<(String, String)>,
    files: usize,
    bytes: u64,
    buf: Vec<u8>,
}

impl Bundle {
    pub(super) fn new(root: PathBuf, limits: BundleLimits) -> Self {
        Self {
            root,
            limits,
            nodes: BTreeMap::new(),
            links: Vec::new(),
            files: 0,
            bytes: 0,
            buf: vec![0; 64 * 1024],
        }
    }

    /// Counts one more node against `max_files`.
    fn count_node(&self, name: &str) -> Result<(), BundleError> {
        if self.nodes.len() >= self.limits.max_files {
            return Err(BundleError::TooManyFiles {
                limit: self.limits.max_files,
                path: name.to_owned(),
            });
        }
        Ok(())
    }

    /// Creates one directory (whose parent exists) and checks it is a real one.
    fn make_dir(&mut self, name: &str, path: &str, explicit: bool) -> Result<(), BundleError> {
        self.count_node(name)?;
        let full = self.root.join(path);
        fs::create_dir(&full).map_err(io_err(|| format!("create directory {full:?}")))?;
        let meta = fs::symlink_metadata(&full)
            .map_err(io_err(|| format!("inspect directory {full:?}")))?;
        if !meta.file_type().is_dir() {
            return Err(BundleError::Io {
                action: format!("create directory {full:?}"),
                source: io::Error::other("it is not a directory after creation"),
            });
        }
        fs::set_permissions(&full, fs::Permissions::from_mode(0o755))
            .map_err(io_err(|| format!("set permissions of {full:?}")))?;
        self.nodes.insert(path.to_owned(), Node::Dir { explicit });
        Ok(())
    }

    /// Makes sure every parent of `path` is a directory we created.
    fn ensure_parents(&mut self, name: &str, path: &str) -> Result<(), BundleError> {
        for parent in parents(path) {
            match self.nodes.get(parent) {
                Some(Node::Dir { .. }) => {}
                Some(Node::File { .. } | Node::Symlink { .. }) => {
                    return Err(BundleError::NotADirectory {
                        path: name.to_owned(),
                        parent: parent.to_owned(),
                    });
                }
                None => self.make_dir(name, parent, false)?,
            }
        }
        Ok(())
    }

    fn check_new(&self, name: &str, path: &str) -> Result<(), BundleError> {
        if path.is_empty() || self.nodes.contains_key(path) {
            return Err(BundleError::Duplicate {
                path: name.to_owned(),
            });
        }
        Ok(())
    }

    pub(super) fn add_dir(&mut self, name: &str, path: &str) -> Result<(), BundleError> {
        if path.is_empty() {
            // "./" or ".": the bot's directory itself.
            return Ok(());
        }
        match self.nodes.get_mut(path) {
            Some(Node::Dir { explicit }) if !*explicit => {
                // Created implicitly for an earlier entry below it.
                *explicit = true;
                Ok(())
            }
            Some(_) => Err(BundleError::Duplicate {
                path: name.to_owned(),
            }),
            None => {
                self.ensure_parents(name, path)?;
                self.make_dir(name, path, true)
            }
        }
    }

    fn check_budget(&self, name: &str, size: u64) -> Result<(), BundleError> {
        if size > self.limits.max_total_bytes.saturating_sub(self.bytes) {
            return Err(BundleError::TooLarge {
                limit: self.limits.max_total_bytes,
                path: Some(name.to_owned()),
            });
        }
        Ok(())
    }

    fn create_file(&self, path: &str) -> Result<(File, PathBuf), BundleError> {
        let full = self.root.join(path);
        let file = OpenOptions::new()
            .write(true)
            .create_new(true)
            .mode(0o600)
            .open(&full)
            .map_err(io_err(|| format!("create file {full:?}")))?;
        Ok((file, full))
    }

    /// Streams one file from `reader`, enforcing the declared and actual size.
    /// `read_error` turns a failure of `reader` into an error; it is also given
    /// an `UnexpectedEof` error if fewer bytes come than declared, and an
    /// `InvalidData` one if more come.
    pub(super) fn add_file(
        &mut self,
        name: &str,
        path: &str,
        exec: bool,
        declared: u64,
        reader: &mut dyn Read,
        read_error: &dyn Fn(io::Error, &str) -> BundleError,
    ) -> Result<(), BundleError> {
        self.check_new(name, path)?;
        self.check_budget(name, declared)?;
        self.ensure_parents(name, path)?;
        self.count_node(name)?;
        let (mut file, full) = self.create_file(path)?;
        let budget = self.limits.max_total_bytes.saturating_sub(self.bytes);
        let mut hasher = Sha256::new();
        let mut written: u64 = 0;
        loop {
            let n = match reader.read(&mut self.buf) {
                Ok(0) => break,
                Ok(n) => n,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(read_error(e, name)),
            };
            written += n as u64;
            if written > budget {
                return Err(BundleError::TooLarge {
                    limit: self.limits.max_total_bytes,
                    path: Some(name.to_owned()),
                });
            }
            let chunk = &self.buf[..n];
            hasher.update(chunk);
            file.write_all(chunk)
                .map_err(io_err(|| format!("write file {full:?}")))?;
        }
        if written < declared {
            // The data ended early: classified as truncation by `read_error`.
            return Err(read_error(io::ErrorKind::UnexpectedEof.into(), name));
        }
        if written > declared {
            let lie = format!("the entry declares {declared} bytes but holds more");
            return Err(read_error(
                io::Error::new(io::ErrorKind::InvalidData, lie),
                name,
            ));
        }
        let mode = if exec { 0o755 } else { 0o644 };
        file.set_permissions(fs::Permissions::from_mode(mode))
            .map_err(io_err(|| format!("set permissions of {full:?}")))?;
        self.nodes.insert(
            path.to_owned(),
            Node::File {
                exec,
                size: written,
                sha: hasher.finalize().into(),
            },
        );
        self.files += 1;
        self.bytes += written;
        Ok(())
    }

    /// Checks a link target's text (not where it leads).
    fn check_link_target(name: &str, target: &str) -> Result<(), BundleError> {
        let invalid = |reason: &str| BundleError::InvalidName {
            path: name.to_owned(),
            reason: reason.to_owned(),
        };
        if target.is_empty() {
            return Err(invalid("it is a link with an empty target"));
        }
        if target.starts_with('/') || has_drive_prefix(target) {
            return Err(BundleError::AbsoluteLink {
                path: name.to_owned(),
                target: target.to_owned(),
            });
        }
        if target.contains('\0') {
            return Err(invalid("its link target contains a NUL byte"));
        }
        if target.contains('\\') {
            return Err(invalid("its link target contains a backslash"));
        }
        if target.len() > MAX_PATH_BYTES {
            return Err(invalid(&format!(
                "its link target is longer than {MAX_PATH_BYTES} bytes"
            )));
        }
        Ok(())
    }

    /// Records a symbolic link; it is checked and created in [`Bundle::finish`].
    pub(super) fn add_symlink(
        &mut self,
        name: &str,
        path: &str,
        target: &str,
    ) -> Result<(), BundleError> {
        Self::check_link_target(name, target)?;
        self.check_new(name, path)?;
        self.ensure_parents(name, path)?;
        self.count_node(name)?;
        self.nodes.insert(
            path.to_owned(),
            Node::Symlink {
                target: target.to_owned(),
            },
        );
        self.links.push((name.to_owned(), path.to_owned()));
        Ok(())
    }

    /// A tar hard link: its target is a path from the archive's root, which
    /// must be a regular file stored earlier. Stored as a copy.
    pub(super) fn add_hard_link(
        &mut self,
        name: &str,
        path: &str,
        target: &str,
    ) -> Result<(), BundleError> {
        Self::check_link_target(name, target)?;
        let target_path = match parse_path(target) {
            Ok((p, _)) => p,
            Err(BundleError::PathEscapes { .. }) => {
                return Err(BundleError::LinkEscapes {
                    path: name.to_owned(),
                    target: target.to_owned(),
                });
            }
            Err(BundleError::AbsolutePath { .. }) => {
                return Err(BundleError::AbsoluteLink {
                    path: name.to_owned(),
                    target: target.to_owned(),
                });
            }
            Err(_) => {
                return Err(BundleError::InvalidName {
                    path: name.to_owned(),
                    reason: "its link target is not a valid name".to_owned(),
                });
            }
        };
        let (exec, size, sha) = match self.nodes.get(&target_path) {
            Some(Node::File { exec, size, sha }) => (*exec, *size, *sha),
            _ => {
                return Err(BundleError::LinkTargetMissing {
                    path: name.to_owned(),
                    target: target.to_owned(),
                });
            }
        };
        self.check_new(name, path)?;
        self.check_budget(name, size)?;
        self.ensure_parents(name, path)?;
        self.count_node(name)?;
        let source_path = self.root.join(&target_path);
        let mut source =
            File::open(&source_path).map_err(io_err(|| format!("open file {source_path:?}")))?;
        let (mut file, full) = self.create_file(path)?;
        let copied = io::copy(&mut source, &mut file)
            .map_err(io_err(|| format!("copy {source_path:?} to {full:?}")))?;
        if copied != size {
            return Err(BundleError::Io {
                action: format!("copy {source_path:?} to {full:?}"),
                source: io::Error::other(format!("copied {copied} bytes instead of {size}")),
            });
        }
        let mode = if exec { 0o755 } else { 0o644 };
        file.set_permissions(fs::Permissions::from_mode(mode))
            .map_err(io_err(|| format!("set permissions of {full:?}")))?;
        self.nodes
            .insert(path.to_owned(), Node::File { exec, size, sha });
        self.files += 1;
        self.bytes += size;
        Ok(())
    }

    /// Whether the symbolic link at `path` (with `target`) stays inside the
    /// bot's directory, following the bundle's other links. Components that
    /// are not links (or do not exist) are taken as they are written.
    fn link_stays_inside(&self, path: &str, target: &str) -> bool {
        let mut stack: Vec<&str> = parents(path)
            .map(|p| p.rsplit('/').next().unwrap_or(p))
            .collect();
        let mut pending: Vec<&str> = target.split('/').rev().collect();
        let mut expansions = 0;
        while let Some(part) = pending.pop() {
            match part {
                "" | "." => {}
                ".." => {
                    if stack.pop().is_none() {
                        return false;
                    }
                }
                part => {
                    stack.push(part);
                    let here = stack.join("/");
                    if let Some(Node::Symlink { target }) = self.nodes.get(&here) {
                        expansions += 1;
                        if expansions > MAX_LINK_EXPANSIONS || target.starts_with('/') {
                            return false;
                        }
                        stack.pop();
                        pending.extend(target.split('/').rev());
                    }
                }
            }
        }
        true
    }

    /// Checks and creates the links, then computes the summary.
    pub(super) fn finish(self) -> Result<BundleSummary, BundleError> {
        if self.files == 0 {
            return Err(BundleError::NoFiles);
        }
        for (name, path) in &self.links {
            if let Some(Node::Symlink { target }) = self.nodes.get(path)
                && !self.link_stays_inside(path, target)
            {
                return Err(BundleError::LinkEscapes {
                    path: name.clone(),
                    target: target.clone(),
                });
            }
        }
        for (_, path) in &self.links {
            if let Some(Node::Symlink { target }) = self.nodes.get(path) {
                let full = self.root.join(path);
                std::os::unix::fs::symlink(target, &full)
                    .map_err(io_err(|| format!("create symbolic link {full:?}")))?;
            }
        }
        Ok(BundleSummary {
            files: self.files,
            bytes: self.bytes,
            sha256: content_hash(&self.nodes),
        })
    }
}
