//! Safe storage of a submitted bot's files on disk.
//!
//! A bot arrives either as an archive ([`unpack_archive`]: `.tar.gz`, `.tar` or
//! `.zip`, recognised by their magic bytes) or, for small bots, as a map of file
//! names to UTF-8 contents ([`write_files`]). Both write the files into a
//! directory given by the caller and return a [`BundleSummary`] with a content
//! hash that does not depend on the archive format, entry order or timestamps.
//!
//! # What is refused
//!
//! Everything the client could do wrong is a [`BundleError`] for which
//! [`BundleError::is_client_error`] is `true`:
//!
//! - names that are empty, absolute (`/etc/x`), hold a `..` component
//!   (`../x`, `a/../../x`), a backslash, a NUL byte or a Windows drive prefix
//!   (`C:`), are not UTF-8, or are too long ([`MAX_PATH_BYTES`],
//!   [`MAX_NAME_BYTES`]); `.` components and repeated `/` are ignored;
//! - symbolic links with an absolute target, or whose target, resolved through
//!   the other links of the bundle, would leave the bot's directory (a chain
//!   of more than 40 links, or a loop, is refused the same way); relative
//!   links that stay inside, even dangling ones, are created as symbolic links;
//! - hard links (tar only) whose target is not a regular file stored earlier
//!   in the same archive; an accepted hard link is stored as a *copy* of its
//!   target (it counts towards the size limit like any file);
//! - device files, fifos, sparse files and any other special entry;
//! - an entry below a path that is a file or a link (`d -> sub` then `d/x`);
//! - two entries for the same path, and a file whose path is also a directory;
//! - more than [`BundleLimits::max_files`] files, directories and links in
//!   total (parent directories created implicitly count too);
//! - more than [`BundleLimits::max_total_bytes`] of file content, checked on the
//!   size an entry *declares* before anything is written and on the bytes it
//!   *actually* produces while streaming; a `.tar.gz` is also cut off once the
//!   decompressed stream (metadata and skipped data included) exceeds the limit
//!   plus a fixed allowance per entry ([`TAR_OVERHEAD_PER_ENTRY`]), so a gzip
//!   bomb is never decompressed further than that;
//! - an archive or map without any regular file ("the bot has no files");
//! - bytes that are not a recognised archive, corrupt and truncated archives,
//!   encrypted zip entries and unsupported zip compression methods.
//!
//! An empty `.tar` (only end-of-archive blocks) and an empty `.zip` are
//! recognised, and refused as having no files. Archive-wide pax headers (as
//! written by `git archive`) and a `./` root entry are ignored.
//!
//! Directories are created with mode `0o755`, files with `0o755` if the entry
//! had any executable bit set and `0o644` otherwise (so compiled bots stay
//! runnable). Owners, timestamps and other mode bits are not kept.
//!
//! # How the files are written
//!
//! `dest` must be an existing, empty, real directory (not a symbolic link).
//! Nothing is written into it directly: the bundle is built in a new staging
//! directory next to it (`<parent of dest>/.<name of dest>.staging-<pid>-<n>`,
//! created with mode `0o700`), which on success gets `dest`'s permissions and
//! is then renamed over `dest` with `rename(2)` (which atomically replaces an
//! empty directory). On any error the staging directory is removed and `dest`
//! is left exactly as it was given. Note that `dest` is therefore a *new*
//! directory (inode) after a successful call.
//!
//! While building, no symbolic link exists on disk: files are created with
//! `create_new` (`O_CREAT | O_EXCL`, which never follows a link), every
//! directory is created by us and checked to be a real directory, the path of
//! every entry is checked against what the bundle already holds (so nothing is
//! ever written below a file or a link), and the symbolic links are only
//! created at the very end, after all of them have been checked together.
//!
//! Both functions do blocking file I/O and CPU work (decompression, hashing):
//! call them from `tokio::task::spawn_blocking`, not on an async worker thread.
//!
//! # The content hash
//!
//! [`BundleSummary::sha256`] is the lowercase hex SHA-256 of this byte string
//! (scheme version 1):
//!
//! ```text
//! "mazearena-bundle-v1\n"
//! then, for each regular file and symbolic link, sorted by the UTF-8 bytes of
//! its normalised path (components joined by "/", no leading "./", no
//! trailing "/"):
//!     kind          1 byte: 'F' file, 'X' file with the executable bit, 'L' link
//!     path length   8 bytes, unsigned big-endian
//!     path          the UTF-8 bytes of the path
//!     content size  8 bytes, unsigned big-endian (for a link: its target's length)
//!     content hash  32 bytes: SHA-256 of the content (for a link: of its target)
//! ```
//!
//! Directories are not part of the hash (an empty directory does not change
//! it), nor are timestamps, owners, entry order or the archive format: the same
//! files give the same hash whether sent as `.tar.gz`, `.zip` or a JSON map.

mod bundle;
mod format;
mod hash;
mod names;
mod pack;
mod staging;
mod tar;
mod zip;

use std::collections::BTreeMap;
use std::io;
use std::path::{Path, PathBuf};

use self::tar::read_tar;
use self::zip::read_zip;
use bundle::Bundle;
use format::{Format, detect_format};
use names::parse_path;
pub use pack::{Packed, Skip, hash_dir, pack_dir, skip_build_outputs, skip_nothing};
use staging::{Staging, check_dest};

/// Default for [`BundleLimits::max_total_bytes`]: 50 MiB of file content.
pub const DEFAULT_MAX_TOTAL_BYTES: u64 = 50 * 1024 * 1024;

/// Default for [`BundleLimits::max_files`]: 2000 files, directories and links.
pub const DEFAULT_MAX_FILES: usize = 2000;

/// Longest accepted path of an entry (or link target), in bytes, once normalised.
pub const MAX_PATH_BYTES: usize = 1024;

/// Longest accepted single component of a path, in bytes.
pub const MAX_NAME_BYTES: usize = 255;

/// Bytes of tar metadata and padding allowed per permitted entry on top of
/// [`BundleLimits::max_total_bytes`] when reading a tar stream; the decompressed
/// stream is cut off at `max_total_bytes + (max_files + 16) * TAR_OVERHEAD_PER_ENTRY`.
pub const TAR_OVERHEAD_PER_ENTRY: u64 = 8 * 1024;

/// Limits on what a bot upload may hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BundleLimits {
    /// Most bytes of file content in total, once unpacked (hard-link copies
    /// included; directory and link entries count as zero).
    pub max_total_bytes: u64,
    /// Most files, directories and links created in total, including parent
    /// directories that are created implicitly for an entry like `a/b/c`.
    pub max_files: usize,
}

impl Default for BundleLimits {
    /// 50 MiB unpacked in total ([`DEFAULT_MAX_TOTAL_BYTES`]) and 2000 entries
    /// ([`DEFAULT_MAX_FILES`]).
    fn default() -> Self {
        Self {
            max_total_bytes: DEFAULT_MAX_TOTAL_BYTES,
            max_files: DEFAULT_MAX_FILES,
        }
    }
}

/// What was stored.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BundleSummary {
    /// Number of regular files written (a tar hard link counts as a file, as it
    /// is stored as a copy); directories and symbolic links are not counted.
    pub files: usize,
    /// Total bytes of file content written.
    pub bytes: u64,
    /// Lowercase hex SHA-256 content hash of the bundle; see the module docs
    /// for the exact scheme.
    pub sha256: String,
}

/// Why a bundle was not stored.
///
/// Every variant except [`BundleError::Io`] and [`BundleError::Destination`]
/// describes something wrong with what the client sent (see
/// [`BundleError::is_client_error`]). Paths in messages are the names as the
/// client sent them, quoted and escaped.
#[derive(Debug, thiserror::Error)]
pub enum BundleError {
    /// The bytes are not a `.tar.gz`, `.tar` or `.zip` archive.
    #[error(
        "the upload is not a recognised archive: send a .tar.gz, .tar or .zip file \
         (or the files as a JSON map)"
    )]
    UnrecognisedFormat,
    /// The archive is damaged or not valid in its format.
    #[error("the {format} archive is corrupt: {detail}")]
    Corrupt {
        /// ".tar.gz", ".tar" or ".zip".
        format: &'static str,
        /// What was wrong, as far as known.
        detail: String,
    },
    /// The archive ends too early.
    #[error("the {format} archive is truncated{}", match entry {
        Some(e) => format!(": entry {e:?} is cut short"),
        None => String::new(),
    })]
    Truncated {
        /// ".tar.gz", ".tar" or ".zip".
        format: &'static str,
        /// The entry being read when the data ended, if any.
        entry: Option<String>,
    },
    /// An entry has an empty name.
    #[error("an entry has an empty name")]
    EmptyName,
    /// An entry's path is absolute.
    #[error("entry {path:?} has an absolute path; paths must be relative to the bot's directory")]
    AbsolutePath {
        /// The entry's name.
        path: String,
    },
    /// An entry's path has a `..` component.
    #[error("entry {path:?} leaves the bot's directory (paths may not contain \"..\")")]
    PathEscapes {
        /// The entry's name.
        path: String,
    },
    /// An entry's name (or link target) is not acceptable.
    #[error("entry {path:?} has an invalid name: {reason}")]
    InvalidName {
        /// The entry's name (lossily decoded if it is not UTF-8).
        path: String,
        /// Why, e.g. "it contains a backslash (use / between directories)".
        reason: String,
    },
    /// A symbolic or hard link has an absolute target.
    #[error(
        "link {path:?} has the absolute target {target:?}; only relative links \
         that stay inside the bot's directory are allowed"
    )]
    AbsoluteLink {
        /// The link's name.
        path: String,
        /// Its target.
        target: String,
    },
    /// A symbolic or hard link points outside the bot's directory.
    #[error("link {path:?} points to {target:?}, which leaves the bot's directory")]
    LinkEscapes {
        /// The link's name.
        path: String,
        /// Its target.
        target: String,
    },
    /// A hard link's target is not a regular file stored earlier in the archive.
    #[error(
        "hard link {path:?} points to {target:?}, which is not a regular file \
         stored earlier in the archive"
    )]
    LinkTargetMissing {
        /// The link's name.
        path: String,
        /// Its target.
        target: String,
    },
    /// A device file, fifo or other special entry.
    #[error("entry {path:?} is {kind}; only regular files, directories and links are allowed")]
    SpecialFile {
        /// The entry's name.
        path: String,
        /// What it is, e.g. "a device file".
        kind: String,
    },
    /// An entry uses an archive feature that is not supported.
    #[error("entry {path:?} cannot be read: {feature} is not supported")]
    Unsupported {
        /// The entry's name.
        path: String,
        /// What, e.g. "encryption".
        feature: String,
    },
    /// An entry lies below a path that is a file or a link.
    #[error("entry {path:?} lies inside {parent:?}, which is not a directory")]
    NotADirectory {
        /// The entry's name.
        path: String,
        /// The normalised path of the offending parent.
        parent: String,
    },
    /// Two entries for the same path.
    #[error(
        "the bot has more than one entry for {path:?} (each path may appear once, \
         and a file cannot have the same path as a directory)"
    )]
    Duplicate {
        /// The entry's name.
        path: String,
    },
    /// More than [`BundleLimits::max_files`] entries.
    #[error(
        "the bot has more than {limit} files, directories and links (the limit was \
         passed at entry {path:?})"
    )]
    TooManyFiles {
        /// The limit.
        limit: usize,
        /// The entry that passed it.
        path: String,
    },
    /// More than [`BundleLimits::max_total_bytes`] of content.
    #[error("the bot is larger than the limit of {limit} bytes unpacked{}", match path {
        Some(p) => format!(" (the limit was passed at entry {p:?})"),
        None => String::new(),
    })]
    TooLarge {
        /// The limit.
        limit: u64,
        /// The entry that passed it, if known.
        path: Option<String>,
    },
    /// The archive or map holds no regular file.
    #[error("the bot has no files")]
    NoFiles,
    /// `dest` was not an existing, empty, real directory (the caller's fault,
    /// not the client's).
    #[error("cannot store the bot in {path:?}: {reason}")]
    Destination {
        /// The directory given.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
    /// A failure of our own disk (the server's fault, not the client's).
    #[error("could not {action}: {source}")]
    Io {
        /// What was being done, e.g. "write file \"/srv/bots/.7.staging-1-0/a\"".
        action: String,
        /// The underlying error.
        #[source]
        source: io::Error,
    },
}

impl BundleError {
    /// `true` if the client sent something unacceptable (answer 4xx), `false`
    /// for a failure on our side ([`BundleError::Io`] and
    /// [`BundleError::Destination`]: answer 500).
    pub fn is_client_error(&self) -> bool {
        !matches!(
            self,
            BundleError::Io { .. } | BundleError::Destination { .. }
        )
    }
}

/// Detects the format by magic bytes (gzip `1f 8b` -> tar.gz; `PK\x03\x04` or
/// empty-zip `PK\x05\x06` -> zip; `ustar` at offset 257 -> plain tar)
/// and unpacks into `dest` (which must exist and be empty).
/// Input made only of zero 512-byte blocks (at least two) is taken as an empty
/// tar, so that it is refused with [`BundleError::NoFiles`].
///
/// See the module docs for what is refused, how `dest` is replaced on success
/// and left untouched on error, and how [`BundleSummary::sha256`] is computed.
pub fn unpack_archive(
    bytes: &[u8],
    dest: &Path,
    limits: &BundleLimits,
) -> Result<BundleSummary, BundleError> {
    let dest_perms = check_dest(dest)?;
    let format = detect_format(bytes)?;
    let staging = Staging::create(dest)?;
    let mut bundle = Bundle::new(staging.path.clone(), *limits);
    match format {
        Format::TarGz => read_tar(flate2::read::GzDecoder::new(bytes), format, &mut bundle)?,
        Format::Tar => read_tar(bytes, format, &mut bundle)?,
        Format::Zip => read_zip(bytes, &mut bundle)?,
    }
    let summary = bundle.finish()?;
    staging.commit(dest, dest_perms)?;
    Ok(summary)
}

/// Writes a map of relative file name -> UTF-8 content (small bots sent as JSON).
///
/// Names follow the same rules as archive entries (parent directories are
/// created as needed; a name ending in `/` is refused). Files get mode `0o644`.
/// `dest` must exist and be empty; it is replaced as described in the module
/// docs, and left untouched on error. The hash equals that of an archive holding
/// the same non-executable files.
pub fn write_files(
    files: &BTreeMap<String, String>,
    dest: &Path,
    limits: &BundleLimits,
) -> Result<BundleSummary, BundleError> {
    let dest_perms = check_dest(dest)?;
    if files.is_empty() {
        return Err(BundleError::NoFiles);
    }
    // Cheap checks on the whole map before touching the disk.
    let mut total: u64 = 0;
    for (name, content) in files {
        total = total.saturating_add(content.len() as u64);
        if total > limits.max_total_bytes {
            return Err(BundleError::TooLarge {
                limit: limits.max_total_bytes,
                path: Some(name.clone()),
            });
        }
    }
    if let Some((name, _)) = files.iter().nth(limits.max_files) {
        return Err(BundleError::TooManyFiles {
            limit: limits.max_files,
            path: name.clone(),
        });
    }
    let staging = Staging::create(dest)?;
    let mut bundle = Bundle::new(staging.path.clone(), *limits);
    for (name, content) in files {
        let (path, is_dir) = parse_path(name)?;
        if path.is_empty() {
            return Err(BundleError::EmptyName);
        }
        if is_dir {
            return Err(BundleError::InvalidName {
                path: name.clone(),
                reason: "a file name may not end with \"/\"".to_owned(),
            });
        }
        let data = content.as_bytes();
        let size = data.len() as u64;
        bundle.add_file(name, &path, false, size, &mut &data[..], &|e, entry| {
            // Reading from memory cannot fail; keep a sensible answer anyway.
            BundleError::Io {
                action: format!("read the content of {entry:?}"),
                source: e,
            }
        })?;
    }
    let summary = bundle.finish()?;
    staging.commit(dest, dest_perms)?;
    Ok(summary)
}

#[cfg(test)]
mod tests;
