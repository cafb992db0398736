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
mod tests {
    use super::hash::hex;
    use super::zip::{S_IFCHR, S_IFIFO, S_IFSOCK};
    use super::*;
    use ::tar::EntryType;
    use ::zip::write::SimpleFileOptions;
    use flate2::Compression;
    use flate2::write::GzEncoder;
    use sha2::{Digest, Sha256};
    use std::fs;
    use std::io::Cursor;
    use std::io::Write;
    use std::os::unix::fs::PermissionsExt;

    // ----- helpers -------------------------------------------------------

    /// A temporary parent holding an empty `bot` directory to unpack into.
    struct Dest {
        parent: tempfile::TempDir,
        dest: PathBuf,
    }

    fn dest() -> Dest {
        let parent = tempfile::tempdir().unwrap();
        let dest = parent.path().join("bot");
        fs::create_dir(&dest).unwrap();
        Dest { parent, dest }
    }

    impl Dest {
        /// `dest` is still an empty directory and no staging directory is left.
        fn assert_untouched(&self) {
            assert!(fs::symlink_metadata(&self.dest).unwrap().is_dir());
            assert_eq!(
                fs::read_dir(&self.dest).unwrap().count(),
                0,
                "dest not empty"
            );
            let names: Vec<_> = fs::read_dir(self.parent.path())
                .unwrap()
                .map(|e| e.unwrap().file_name())
                .collect();
            assert_eq!(names, vec![std::ffi::OsString::from("bot")]);
        }

        fn read(&self, rel: &str) -> Vec<u8> {
            fs::read(self.dest.join(rel)).unwrap()
        }

        fn mode(&self, rel: &str) -> u32 {
            fs::symlink_metadata(self.dest.join(rel))
                .unwrap()
                .permissions()
                .mode()
                & 0o7777
        }
    }

    fn small() -> BundleLimits {
        BundleLimits {
            max_total_bytes: 1024 * 1024,
            max_files: 10,
        }
    }

    /// One raw tar entry; names and link targets are written verbatim.
    enum T<'a> {
        File(&'a str, u32, &'a [u8]),
        Dir(&'a str),
        Sym(&'a str, &'a str),
        Hard(&'a str, &'a str),
        /// Name, type, declared size, data actually written.
        Raw(&'a [u8], EntryType, u64, &'a [u8]),
    }

    fn header(name: &[u8], kind: EntryType, size: u64, mode: u32, link: &[u8]) -> ::tar::Header {
        let mut h = ::tar::Header::new_gnu();
        {
            let old = h.as_old_mut();
            old.name[..name.len()].copy_from_slice(name);
            old.linkname[..link.len()].copy_from_slice(link);
        }
        h.set_entry_type(kind);
        h.set_size(size);
        h.set_mode(mode);
        h.set_mtime(1_700_000_000);
        if kind == EntryType::GNUSparse {
            h.as_gnu_mut().unwrap().set_real_size(size);
        }
        h.set_cksum();
        h
    }

    fn tar(entries: &[T]) -> Vec<u8> {
        let mut out = Vec::new();
        for e in entries {
            let (h, data): (::tar::Header, &[u8]) = match *e {
                T::File(n, mode, data) => (
                    header(
                        n.as_bytes(),
                        EntryType::Regular,
                        data.len() as u64,
                        mode,
                        b"",
                    ),
                    data,
                ),
                T::Dir(n) => (
                    header(n.as_bytes(), EntryType::Directory, 0, 0o755, b""),
                    b"",
                ),
                T::Sym(n, t) => (
                    header(n.as_bytes(), EntryType::Symlink, 0, 0o777, t.as_bytes()),
                    b"",
                ),
                T::Hard(n, t) => (
                    header(n.as_bytes(), EntryType::Link, 0, 0o644, t.as_bytes()),
                    b"",
                ),
                T::Raw(n, kind, size, data) => (header(n, kind, size, 0o644, b""), data),
            };
            out.extend_from_slice(h.as_bytes());
            out.extend_from_slice(data);
            out.resize(out.len().next_multiple_of(512), 0);
        }
        out.resize(out.len() + 1024, 0);
        out
    }

    fn gz(bytes: &[u8]) -> Vec<u8> {
        let mut enc = GzEncoder::new(Vec::new(), Compression::fast());
        enc.write_all(bytes).unwrap();
        enc.finish().unwrap()
    }

    fn tgz(entries: &[T]) -> Vec<u8> {
        gz(&tar(entries))
    }

    /// One zip entry.
    enum Z<'a> {
        File(&'a str, u32, &'a [u8]),
        Dir(&'a str),
        Sym(&'a str, &'a str),
    }

    fn zip(entries: &[Z]) -> Vec<u8> {
        let mut w = ::zip::ZipWriter::new(Cursor::new(Vec::new()));
        for e in entries {
            match *e {
                Z::File(n, mode, data) => {
                    let opts = SimpleFileOptions::default().unix_permissions(mode);
                    w.start_file(n, opts).unwrap();
                    w.write_all(data).unwrap();
                }
                Z::Dir(n) => w.add_directory(n, SimpleFileOptions::default()).unwrap(),
                Z::Sym(n, t) => w.add_symlink(n, t, SimpleFileOptions::default()).unwrap(),
            }
        }
        w.finish().unwrap().into_inner()
    }

    fn unpack(bytes: &[u8], limits: &BundleLimits) -> (Dest, Result<BundleSummary, BundleError>) {
        let d = dest();
        let r = unpack_archive(bytes, &d.dest, limits);
        (d, r)
    }

    /// Unpacking fails, leaves dest untouched, and the error is the client's.
    fn refused(bytes: &[u8], limits: &BundleLimits) -> BundleError {
        let (d, r) = unpack(bytes, limits);
        let err = r.expect_err("the archive should have been refused");
        assert!(err.is_client_error(), "{err:?} should be a client error");
        d.assert_untouched();
        err
    }

    fn replace_all(bytes: &mut [u8], from: &[u8], to: &[u8]) {
        assert_eq!(from.len(), to.len());
        let mut i = 0;
        let mut found = false;
        while i + from.len() <= bytes.len() {
            if &bytes[i..i + from.len()] == from {
                bytes[i..i + from.len()].copy_from_slice(to);
                found = true;
            }
            i += 1;
        }
        assert!(found);
    }

    fn positions(bytes: &[u8], sig: &[u8]) -> Vec<usize> {
        (0..bytes.len().saturating_sub(sig.len() - 1))
            .filter(|&i| &bytes[i..i + sig.len()] == sig)
            .collect()
    }

    fn map(files: &[(&str, &str)]) -> BTreeMap<String, String> {
        files
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    }

    // ----- round trips ---------------------------------------------------

    #[test]
    fn tar_gz_round_trips_nested_dirs_and_exec_bit() {
        let bytes = tgz(&[
            T::Dir("./"),
            T::Dir("./src/"),
            T::File("./src/main.py", 0o644, b"print('hi')\n"),
            T::Dir("./bin/"),
            T::File("./bin/bot", 0o700, b"\x7fELF..."),
            T::File("./src/deep/er/data.txt", 0o664, b"nested"),
        ]);
        let (d, r) = unpack(&bytes, &BundleLimits::default());
        let s = r.unwrap();
        assert_eq!(s.files, 3);
        assert_eq!(s.bytes, 12 + 7 + 6);
        assert_eq!(s.sha256.len(), 64);
        assert_eq!(d.read("src/main.py"), b"print('hi')\n");
        assert_eq!(d.read("bin/bot"), b"\x7fELF...");
        assert_eq!(d.read("src/deep/er/data.txt"), b"nested");
        assert_eq!(d.mode("bin/bot"), 0o755);
        assert_eq!(d.mode("src/main.py"), 0o644);
        assert_eq!(d.mode("src/deep/er/data.txt"), 0o644);
        assert_eq!(d.mode("src/deep"), 0o755);
        // No staging directory left next to dest.
        assert_eq!(fs::read_dir(d.parent.path()).unwrap().count(), 1);
    }

    #[test]
    fn zip_round_trips_nested_dirs_and_exec_bit() {
        let bytes = zip(&[
            Z::Dir("src/"),
            Z::File("src/main.py", 0o644, b"print('hi')\n"),
            Z::File("bin/bot", 0o755, b"\x7fELF..."),
            Z::File("src/deep/er/data.txt", 0o600, b"nested"),
        ]);
        let (d, r) = unpack(&bytes, &BundleLimits::default());
        let s = r.unwrap();
        assert_eq!((s.files, s.bytes), (3, 25));
        assert_eq!(d.read("src/main.py"), b"print('hi')\n");
        assert_eq!(d.read("bin/bot"), b"\x7fELF...");
        assert_eq!(d.read("src/deep/er/data.txt"), b"nested");
        assert_eq!(d.mode("bin/bot"), 0o755);
        assert_eq!(d.mode("src/main.py"), 0o644);
        assert_eq!(d.mode("src/deep/er/data.txt"), 0o644);
    }

    #[test]
    fn plain_tar_is_accepted() {
        let bytes = tar(&[T::File("bot.py", 0o755, b"x")]);
        let (d, r) = unpack(&bytes, &BundleLimits::default());
        assert_eq!(r.unwrap().files, 1);
        assert_eq!(d.mode("bot.py"), 0o755);
    }

    #[test]
    fn pax_global_header_is_skipped() {
        // `git archive` starts with a pax global header holding the commit id.
        let pax = b"52 comment=0123456789012345678901234567890123456789\n";
        let bytes = tgz(&[
            T::Raw(
                b"pax_global_header",
                EntryType::XGlobalHeader,
                pax.len() as u64,
                pax,
            ),
            T::File("bot/run.sh", 0o755, b"#!/bin/sh\n"),
        ]);
        let (d, r) = unpack(&bytes, &BundleLimits::default());
        assert_eq!(r.unwrap().files, 1);
        assert_eq!(d.read("bot/run.sh"), b"#!/bin/sh\n");
    }

    #[test]
    fn destination_keeps_its_permissions() {
        let d = dest();
        fs::set_permissions(&d.dest, fs::Permissions::from_mode(0o750)).unwrap();
        unpack_archive(&tgz(&[T::File("a", 0o644, b"a")]), &d.dest, &small()).unwrap();
        assert_eq!(d.mode(""), 0o750);
    }

    // ----- hash ----------------------------------------------------------

    #[test]
    fn hash_is_independent_of_format_order_and_timestamps() {
        let files = [
            ("src/main.py", "print('hi')\n"),
            ("README", "bot"),
            ("src/a", ""),
        ];
        let json = {
            let d = dest();
            write_files(&map(&files), &d.dest, &small()).unwrap().sha256
        };
        let tar_gz = {
            let bytes = tgz(&[
                T::Dir("src/"),
                T::File("./src/main.py", 0o644, b"print('hi')\n"),
                T::File("README", 0o600, b"bot"),
                T::File("src/a", 0o644, b""),
            ]);
            unpack(&bytes, &small()).1.unwrap().sha256
        };
        let zip_reordered = {
            let bytes = zip(&[
                Z::File("src/a", 0o644, b""),
                Z::File("README", 0o644, b"bot"),
                Z::File("src/main.py", 0o644, b"print('hi')\n"),
            ]);
            unpack(&bytes, &small()).1.unwrap().sha256
        };
        assert_eq!(json, tar_gz);
        assert_eq!(json, zip_reordered);

        // One byte changed.
        let changed = {
            let files = [
                ("src/main.py", "print('hI')\n"),
                ("README", "bot"),
                ("src/a", ""),
            ];
            let d = dest();
            write_files(&map(&files), &d.dest, &small()).unwrap().sha256
        };
        assert_ne!(json, changed);

        // The executable bit counts.
        let exec = {
            let bytes = tgz(&[
                T::File("src/main.py", 0o755, b"print('hi')\n"),
                T::File("README", 0o644, b"bot"),
                T::File("src/a", 0o644, b""),
            ]);
            unpack(&bytes, &small()).1.unwrap().sha256
        };
        assert_ne!(json, exec);

        // A renamed file counts.
        let renamed = {
            let files = [
                ("src/main.py", "print('hi')\n"),
                ("README", "bot"),
                ("src/b", ""),
            ];
            let d = dest();
            write_files(&map(&files), &d.dest, &small()).unwrap().sha256
        };
        assert_ne!(json, renamed);
    }

    #[test]
    fn hash_follows_the_documented_scheme() {
        let d = dest();
        let s = write_files(&map(&[("a", "x")]), &d.dest, &small()).unwrap();
        let mut h = Sha256::new();
        h.update(b"mazearena-bundle-v1\n");
        h.update(b"F");
        h.update(1u64.to_be_bytes());
        h.update(b"a");
        h.update(1u64.to_be_bytes());
        h.update(Sha256::digest(b"x"));
        assert_eq!(s.sha256, hex(&h.finalize()));
    }

    // ----- names ---------------------------------------------------------

    #[test]
    fn absolute_paths_are_refused() {
        let err = refused(&tgz(&[T::File("/etc/x", 0o644, b"x")]), &small());
        assert!(matches!(err, BundleError::AbsolutePath { ref path } if path == "/etc/x"));
        let err = refused(&zip(&[Z::File("/etc/x", 0o644, b"x")]), &small());
        assert!(matches!(err, BundleError::AbsolutePath { .. }), "{err:?}");
    }

    #[test]
    fn parent_components_are_refused() {
        for name in ["../x", "a/../../x", "a/../b", "ok/.."] {
            let err = refused(&tgz(&[T::File(name, 0o644, b"x")]), &small());
            assert!(matches!(err, BundleError::PathEscapes { ref path } if path == name));
            assert_eq!(
                err.to_string(),
                format!("entry {name:?} leaves the bot's directory (paths may not contain \"..\")")
            );
        }
        let err = refused(&zip(&[Z::File("../x", 0o644, b"x")]), &small());
        assert!(matches!(err, BundleError::PathEscapes { .. }), "{err:?}");
    }

    #[test]
    fn windows_prefixes_backslashes_nul_and_empty_names_are_refused() {
        for name in ["C:/x", "c:x", "a\\b", "..\\x"] {
            let err = refused(&tgz(&[T::File(name, 0o644, b"x")]), &small());
            assert!(
                matches!(err, BundleError::InvalidName { .. }),
                "{name}: {err:?}"
            );
        }
        let err = refused(&zip(&[Z::File("..\\..\\x", 0o644, b"x")]), &small());
        assert!(matches!(err, BundleError::InvalidName { .. }), "{err:?}");
        // A tar header name stops at its first NUL; a JSON name can hold one.
        let d = dest();
        let err = write_files(&map(&[("a\0b", "x")]), &d.dest, &small()).unwrap_err();
        assert!(matches!(err, BundleError::InvalidName { .. }), "{err:?}");
        d.assert_untouched();
        // Empty names.
        let err = refused(&tgz(&[T::File("", 0o644, b"x")]), &small());
        assert!(matches!(err, BundleError::EmptyName), "{err:?}");
        let err = refused(&tgz(&[T::File("./", 0o644, b"")]), &small());
        assert!(matches!(err, BundleError::NoFiles), "{err:?}");
        let err = refused(
            &tgz(&[T::Sym(".", "x"), T::File("a", 0o644, b"")]),
            &small(),
        );
        assert!(matches!(err, BundleError::Duplicate { .. }), "{err:?}");
        let d = dest();
        let err = write_files(&map(&[("", "x")]), &d.dest, &small()).unwrap_err();
        assert!(matches!(err, BundleError::EmptyName), "{err:?}");
        // Non-UTF-8 names.
        let err = refused(
            &tgz(&[T::Raw(b"caf\xe9", EntryType::Regular, 1, b"x")]),
            &small(),
        );
        assert!(matches!(err, BundleError::InvalidName { .. }), "{err:?}");
        // Over-long names.
        let long = "a/".repeat(600) + "x";
        let d = dest();
        let err = write_files(&map(&[(&long, "x")]), &d.dest, &small()).unwrap_err();
        assert!(matches!(err, BundleError::InvalidName { .. }), "{err:?}");
    }

    // ----- links ---------------------------------------------------------

    #[test]
    fn relative_symlinks_inside_are_created() {
        let bytes = tgz(&[
            T::File("target/release/bot", 0o755, b"elf"),
            T::Sym("bin/run", "../target/release/bot"),
            T::Sym("here", "."),
            T::Sym("dangling", "not/yet/there"),
        ]);
        let (d, r) = unpack(&bytes, &small());
        let s = r.unwrap();
        assert_eq!(s.files, 1);
        let meta = fs::symlink_metadata(d.dest.join("bin/run")).unwrap();
        assert!(meta.file_type().is_symlink());
        assert_eq!(
            fs::read_link(d.dest.join("bin/run")).unwrap(),
            Path::new("../target/release/bot")
        );
        assert_eq!(d.read("bin/run"), b"elf");
        assert_eq!(d.read("here/target/release/bot"), b"elf");

        let zipped = zip(&[
            Z::File("target/release/bot", 0o755, b"elf"),
            Z::Sym("bin/run", "../target/release/bot"),
            Z::Sym("here", "."),
            Z::Sym("dangling", "not/yet/there"),
        ]);
        let (d2, r2) = unpack(&zipped, &small());
        assert_eq!(r2.unwrap().sha256, s.sha256, "links are part of the hash");
        assert_eq!(d2.read("bin/run"), b"elf");
    }

    #[test]
    fn absolute_symlinks_are_refused() {
        let err = refused(
            &tgz(&[T::Sym("d", "/tmp"), T::File("d/x", 0o644, b"x")]),
            &small(),
        );
        assert!(
            matches!(err, BundleError::AbsoluteLink { ref path, ref target } if path == "d" && target == "/tmp"),
            "{err:?}"
        );
        let err = refused(
            &zip(&[Z::File("a", 0o644, b"x"), Z::Sym("etc", "/etc/passwd")]),
            &small(),
        );
        assert!(matches!(err, BundleError::AbsoluteLink { .. }), "{err:?}");
    }

    #[test]
    fn symlinks_leaving_the_directory_are_refused() {
        for (name, target) in [
            ("l", ".."),
            ("l", "../x"),
            ("a/l", "../../x"),
            ("a/l", "./../b/../.."),
        ] {
            let err = refused(
                &tgz(&[T::File("f", 0o644, b"x"), T::Sym(name, target)]),
                &small(),
            );
            assert!(
                matches!(err, BundleError::LinkEscapes { .. }),
                "{target}: {err:?}"
            );
            assert!(err.to_string().contains("leaves the bot's directory"));
        }
        let err = refused(
            &zip(&[Z::File("f", 0o644, b"x"), Z::Sym("up", "../../etc")]),
            &small(),
        );
        assert!(matches!(err, BundleError::LinkEscapes { .. }), "{err:?}");
    }

    #[test]
    fn symlinks_escaping_through_other_links_are_refused_in_any_order() {
        // `x -> .` stays inside, but `l -> x/..` then leads to dest's parent.
        let a = [
            T::Sym("x", "."),
            T::Sym("l", "x/.."),
            T::File("f", 0o644, b"x"),
        ];
        let b = [
            T::File("f", 0o644, b"x"),
            T::Sym("l", "x/.."),
            T::Sym("x", "."),
        ];
        for entries in [&a[..], &b[..]] {
            let err = refused(&tgz(entries), &small());
            assert!(
                matches!(err, BundleError::LinkEscapes { ref path, .. } if path == "l"),
                "{err:?}"
            );
        }
        // A chain deeper than Linux follows, or a loop, is refused too.
        let err = refused(
            &tgz(&[
                T::Sym("a", "b"),
                T::Sym("b", "a/x"),
                T::File("f", 0o644, b""),
            ]),
            &small(),
        );
        assert!(matches!(err, BundleError::LinkEscapes { .. }), "{err:?}");
    }

    #[test]
    fn entries_below_a_link_or_a_file_are_refused() {
        // Parent is an (inside) link.
        let err = refused(
            &tgz(&[
                T::Dir("sub/"),
                T::Sym("d", "sub"),
                T::File("d/x", 0o644, b"x"),
            ]),
            &small(),
        );
        assert!(
            matches!(err, BundleError::NotADirectory { ref path, ref parent } if path == "d/x" && parent == "d"),
            "{err:?}"
        );
        // `link -> .` then `link/../../x`.
        let err = refused(
            &tgz(&[T::Sym("link", "."), T::File("link/../../x", 0o644, b"x")]),
            &small(),
        );
        assert!(matches!(err, BundleError::PathEscapes { .. }), "{err:?}");
        // Parent is a file.
        let err = refused(
            &tgz(&[T::File("a", 0o644, b"x"), T::File("a/b", 0o644, b"y")]),
            &small(),
        );
        assert!(matches!(err, BundleError::NotADirectory { .. }), "{err:?}");
        // Zip: a link then a file below it.
        let err = refused(
            &zip(&[Z::Sym("d", "."), Z::File("d/x", 0o644, b"x")]),
            &small(),
        );
        assert!(matches!(err, BundleError::NotADirectory { .. }), "{err:?}");
    }

    #[test]
    fn hard_links_inside_are_copied_and_others_refused() {
        let bytes = tgz(&[
            T::File("bin/bot", 0o755, b"elf"),
            T::Hard("bot2", "bin/bot"),
            T::Hard("again", "./bin//bot"),
        ]);
        let (d, r) = unpack(&bytes, &small());
        let s = r.unwrap();
        assert_eq!((s.files, s.bytes), (3, 9));
        assert_eq!(d.read("bot2"), b"elf");
        assert_eq!(d.mode("bot2"), 0o755);
        assert!(fs::symlink_metadata(d.dest.join("bot2")).unwrap().is_file());

        type Case<'a> = (&'a [T<'a>], fn(&BundleError) -> bool);
        let cases: [Case; 4] = [
            (&[T::File("a", 0o644, b"x"), T::Hard("l", "../x")], |e| {
                matches!(e, BundleError::LinkEscapes { .. })
            }),
            (
                &[T::File("a", 0o644, b"x"), T::Hard("l", "/etc/passwd")],
                |e| matches!(e, BundleError::AbsoluteLink { .. }),
            ),
            (&[T::File("a", 0o644, b"x"), T::Hard("l", "missing")], |e| {
                matches!(e, BundleError::LinkTargetMissing { .. })
            }),
            (
                &[T::Dir("d/"), T::File("a", 0o644, b"x"), T::Hard("l", "d")],
                |e| matches!(e, BundleError::LinkTargetMissing { .. }),
            ),
        ];
        for (entries, expected) in cases {
            let err = refused(&tgz(entries), &small());
            assert!(expected(&err), "{err:?}");
        }
        // Copies count towards the size limit.
        let limits = BundleLimits {
            max_total_bytes: 5,
            max_files: 10,
        };
        let err = refused(
            &tgz(&[T::File("a", 0o644, b"abc"), T::Hard("b", "a")]),
            &limits,
        );
        assert!(matches!(err, BundleError::TooLarge { .. }), "{err:?}");
    }

    // ----- special entries -----------------------------------------------

    #[test]
    fn devices_fifos_and_other_special_entries_are_refused() {
        for (kind, what) in [
            (EntryType::Char, "a device file"),
            (EntryType::Block, "a device file"),
            (EntryType::Fifo, "a named pipe (fifo)"),
            (EntryType::new(b'V'), "an entry of unknown type 'V'"),
        ] {
            let err = refused(
                &tgz(&[T::File("a", 0o644, b"x"), T::Raw(b"dev", kind, 0, b"")]),
                &small(),
            );
            assert!(
                matches!(err, BundleError::SpecialFile { ref path, ref kind } if path == "dev" && kind == what),
                "{err:?}"
            );
        }
        let err = refused(
            &tgz(&[T::Raw(b"sparse", EntryType::GNUSparse, 0, b"")]),
            &small(),
        );
        assert!(
            matches!(err, BundleError::Unsupported { ref feature, .. } if feature == "a sparse file"),
            "{err:?}"
        );

        // Zip: patch the file type in the external attributes of the central directory.
        for (ftype, what) in [
            (S_IFIFO, "a named pipe (fifo)"),
            (S_IFCHR, "a device file"),
            (S_IFSOCK, "a socket"),
        ] {
            let mut bytes = zip(&[Z::File("a", 0o644, b"x"), Z::File("p", 0o644, b"")]);
            let cd = positions(&bytes, b"PK\x01\x02");
            let at = cd[1] + 38;
            bytes[at..at + 4].copy_from_slice(&((ftype | 0o644) << 16).to_le_bytes());
            let err = refused(&bytes, &small());
            assert!(
                matches!(err, BundleError::SpecialFile { ref kind, .. } if kind == what),
                "{err:?}"
            );
        }
    }

    #[test]
    fn encrypted_zip_entries_are_refused() {
        let mut bytes = zip(&[Z::File("a", 0o644, b"secret")]);
        let local = positions(&bytes, b"PK\x03\x04")[0];
        bytes[local + 6] |= 1;
        let cd = positions(&bytes, b"PK\x01\x02")[0];
        bytes[cd + 8] |= 1;
        let err = refused(&bytes, &small());
        assert!(
            matches!(err, BundleError::Unsupported { ref feature, .. } if feature == "encryption"),
            "{err:?}"
        );
    }

    // ----- duplicates, empty, limits --------------------------------------

    #[test]
    fn duplicate_entries_are_refused() {
        let cases: [&[T]; 4] = [
            &[T::File("a", 0o644, b"1"), T::File("a", 0o644, b"2")],
            &[T::File("a", 0o644, b"1"), T::File("./a", 0o644, b"2")],
            &[T::Dir("d/"), T::Dir("d"), T::File("a", 0o644, b"1")],
            &[T::File("d/x", 0o644, b"1"), T::File("d", 0o644, b"2")],
        ];
        for entries in cases {
            let err = refused(&tgz(entries), &small());
            assert!(matches!(err, BundleError::Duplicate { .. }), "{err:?}");
        }
        // A directory entry after a file below it is fine.
        let (_d, r) = unpack(&tgz(&[T::File("d/x", 0o644, b"1"), T::Dir("d/")]), &small());
        r.unwrap();

        // Zip: the writer refuses duplicates, so rename "b.txt" to "a.txt".
        let mut bytes = zip(&[Z::File("a.txt", 0o644, b"1"), Z::File("b.txt", 0o644, b"2")]);
        replace_all(&mut bytes, b"b.txt", b"a.txt");
        let err = refused(&bytes, &small());
        assert!(
            matches!(err, BundleError::Duplicate { ref path } if path == "a.txt"),
            "{err:?}"
        );
        let err = refused(
            &zip(&[Z::File("a", 0o644, b"1"), Z::File("./a", 0o644, b"2")]),
            &small(),
        );
        assert!(matches!(err, BundleError::Duplicate { .. }), "{err:?}");

        // JSON: names that normalise to the same path.
        let d = dest();
        let err = write_files(&map(&[("a/b", "1"), ("a//b", "2")]), &d.dest, &small()).unwrap_err();
        assert!(matches!(err, BundleError::Duplicate { .. }), "{err:?}");
        d.assert_untouched();
    }

    #[test]
    fn empty_bundles_are_refused() {
        for bytes in [
            tgz(&[]),
            tar(&[]),
            tgz(&[T::Dir("./"), T::Dir("src/")]),
            zip(&[]),
            zip(&[Z::Dir("src/")]),
        ] {
            let err = refused(&bytes, &small());
            assert!(matches!(err, BundleError::NoFiles), "{err:?}");
            assert_eq!(err.to_string(), "the bot has no files");
        }
        assert!(zip(&[]).starts_with(b"PK\x05\x06"));
        let d = dest();
        let err = write_files(&BTreeMap::new(), &d.dest, &small()).unwrap_err();
        assert!(matches!(err, BundleError::NoFiles), "{err:?}");
        d.assert_untouched();
    }

    #[test]
    fn too_many_files_are_refused() {
        let limits = BundleLimits {
            max_total_bytes: 1024,
            max_files: 3,
        };
        let (_d, r) = unpack(
            &tgz(&[
                T::File("a", 0o644, b""),
                T::File("b", 0o644, b""),
                T::File("c", 0o644, b""),
            ]),
            &limits,
        );
        r.unwrap();
        let names: Vec<String> = (0..4).map(|i| format!("f{i}")).collect();
        let entries: Vec<T> = names.iter().map(|n| T::File(n, 0o644, b"")).collect();
        let err = refused(&tgz(&entries), &limits);
        assert!(
            matches!(err, BundleError::TooManyFiles { limit: 3, ref path } if path == "f3"),
            "{err:?}"
        );
        // Implicit parent directories count.
        let err = refused(&tgz(&[T::File("a/b/c/d", 0o644, b"")]), &limits);
        assert!(matches!(err, BundleError::TooManyFiles { .. }), "{err:?}");
        let zipped = zip(&[
            Z::File("a", 0o644, b""),
            Z::File("b", 0o644, b""),
            Z::Dir("c/"),
            Z::File("d", 0o644, b""),
        ]);
        let err = refused(&zipped, &limits);
        assert!(matches!(err, BundleError::TooManyFiles { .. }), "{err:?}");
        let d = dest();
        let many = map(&[("a", ""), ("b", ""), ("c", ""), ("d", "")]);
        let err = write_files(&many, &d.dest, &limits).unwrap_err();
        assert!(matches!(err, BundleError::TooManyFiles { .. }), "{err:?}");
        d.assert_untouched();
    }

    #[test]
    fn declared_size_over_the_limit_is_refused_before_reading() {
        // The header claims 1 GiB; no data follows (so reading it would say "truncated").
        let bytes = tgz(&[T::Raw(b"big", EntryType::Regular, 1 << 30, b"")]);
        let err = refused(&bytes, &BundleLimits::default());
        assert!(
            matches!(err, BundleError::TooLarge { ref path, .. } if path.as_deref() == Some("big")),
            "{err:?}"
        );
        // Within the limit on its own, but not together with what came before.
        let limits = BundleLimits {
            max_total_bytes: 10,
            max_files: 10,
        };
        let err = refused(
            &tgz(&[
                T::File("a", 0o644, b"123456"),
                T::File("b", 0o644, b"12345"),
            ]),
            &limits,
        );
        assert!(matches!(err, BundleError::TooLarge { .. }), "{err:?}");
        let err = refused(
            &zip(&[
                Z::File("a", 0o644, b"123456"),
                Z::File("b", 0o644, b"12345"),
            ]),
            &limits,
        );
        assert!(matches!(err, BundleError::TooLarge { .. }), "{err:?}");
        let d = dest();
        let err =
            write_files(&map(&[("a", "123456"), ("b", "12345")]), &d.dest, &limits).unwrap_err();
        assert!(matches!(err, BundleError::TooLarge { .. }), "{err:?}");
        d.assert_untouched();
    }

    #[test]
    fn gzip_bomb_is_refused_without_being_unpacked() {
        // 16 MiB of zeros compress to ~16 KiB; the limit is 1 MiB.
        let zeros = vec![0u8; 16 << 20];
        let bytes = tgz(&[T::File("zeros", 0o644, &zeros)]);
        assert!(bytes.len() < 100_000);
        let err = refused(&bytes, &small());
        assert!(matches!(err, BundleError::TooLarge { .. }), "{err:?}");
        // The same zeros hidden as "data" of a directory entry, which is
        // skipped rather than written: the decompressed stream is capped.
        let bytes = tgz(&[
            T::Raw(b"dir/", EntryType::Directory, zeros.len() as u64, &zeros),
            T::File("a", 0o644, b"x"),
        ]);
        let err = refused(&bytes, &small());
        assert!(matches!(err, BundleError::TooLarge { .. }), "{err:?}");
        // And as trailing padding after the end of the archive.
        let mut inner = tar(&[T::File("a", 0o644, b"x")]);
        inner.extend_from_slice(&zeros);
        let err = refused(&gz(&inner), &small());
        assert!(matches!(err, BundleError::TooLarge { .. }), "{err:?}");
    }

    #[test]
    fn zip_entry_larger_than_declared_is_refused() {
        // 2 MiB of zeros, but both headers claim 1000 bytes; the limit is 1 MiB.
        let zeros = vec![0u8; 2 << 20];
        let mut bytes = zip(&[Z::File("bomb", 0o644, &zeros)]);
        let local = positions(&bytes, b"PK\x03\x04")[0];
        bytes[local + 22..local + 26].copy_from_slice(&1000u32.to_le_bytes());
        let cd = positions(&bytes, b"PK\x01\x02")[0];
        bytes[cd + 24..cd + 28].copy_from_slice(&1000u32.to_le_bytes());
        let err = refused(&bytes, &small());
        assert!(
            matches!(
                err,
                BundleError::TooLarge { .. } | BundleError::Corrupt { .. }
            ),
            "{err:?}"
        );
        // With a roomy limit, the lie itself is caught.
        let err = refused(&bytes, &BundleLimits::default());
        assert!(matches!(err, BundleError::Corrupt { .. }), "{err:?}");
    }

    // ----- garbage, truncation --------------------------------------------

    #[test]
    fn garbage_is_refused_naming_the_accepted_formats() {
        for bytes in [
            &b""[..],
            b"hello world",
            b"\x7fELF\x02\x01\x01",
            &[0u8; 600],
        ] {
            let err = refused(bytes, &small());
            assert!(matches!(err, BundleError::UnrecognisedFormat), "{err:?}");
            let msg = err.to_string();
            for fmt in [".tar.gz", ".tar", ".zip"] {
                assert!(msg.contains(fmt), "{msg}");
            }
        }
        // Right magic, wrong insides.
        let err = refused(b"\x1f\x8bthis is not deflate data at all", &small());
        assert!(
            matches!(
                err,
                BundleError::Corrupt { .. } | BundleError::Truncated { .. }
            ),
            "{err:?}"
        );
        let err = refused(
            &gz(b"not a tar archive, just text that is long enough"),
            &small(),
        );
        assert!(
            matches!(
                err,
                BundleError::Truncated { .. } | BundleError::Corrupt { .. }
            ),
            "{err:?}"
        );
        let err = refused(&gz(&[7u8; 4096]), &small());
        assert!(matches!(err, BundleError::Corrupt { .. }), "{err:?}");
        let err = refused(b"PK\x03\x04garbage", &small());
        assert!(matches!(err, BundleError::Corrupt { .. }), "{err:?}");
    }

    #[test]
    fn truncated_archives_are_refused() {
        let data: Vec<u8> = (0..200_000u32).map(|i| (i * 7919 % 251) as u8).collect();
        let full = tgz(&[T::File("a", 0o644, b"x"), T::File("big", 0o644, &data)]);
        for cut in [full.len() / 2, full.len() - 4, 20] {
            let err = refused(&full[..cut], &BundleLimits::default());
            assert!(
                matches!(
                    err,
                    BundleError::Truncated {
                        format: ".tar.gz",
                        ..
                    }
                ),
                "{cut}: {err:?}"
            );
            assert!(
                err.to_string()
                    .starts_with("the .tar.gz archive is truncated")
            );
        }
        let plain = tar(&[T::File("a", 0o644, b"x"), T::File("big", 0o644, &data)]);
        let err = refused(&plain[..plain.len() / 2], &BundleLimits::default());
        assert!(
            matches!(err, BundleError::Truncated { format: ".tar", ref entry } if entry.as_deref() == Some("big")),
            "{err:?}"
        );
        let zipped = zip(&[Z::File("a", 0o644, &data)]);
        let err = refused(&zipped[..zipped.len() - 10], &BundleLimits::default());
        assert!(
            matches!(
                err,
                BundleError::Corrupt { .. } | BundleError::Truncated { .. }
            ),
            "{err:?}"
        );
    }

    // ----- write_files, destination, error mapping -------------------------

    #[test]
    fn write_files_creates_nested_files() {
        let d = dest();
        let files = map(&[
            ("bot.py", "import sys\n"),
            ("lib/util.py", "X = 1\n"),
            ("./lib/x/y.txt", ""),
        ]);
        let s = write_files(&files, &d.dest, &BundleLimits::default()).unwrap();
        assert_eq!((s.files, s.bytes), (3, 17));
        assert_eq!(d.read("lib/util.py"), b"X = 1\n");
        assert_eq!(d.read("lib/x/y.txt"), b"");
        assert_eq!(d.mode("bot.py"), 0o644);
        assert_eq!(d.mode("lib/x"), 0o755);

        for bad in ["../x", "/abs", "dir/", "a\\b"] {
            let d = dest();
            let err = write_files(&map(&[("ok", "1"), (bad, "2")]), &d.dest, &small()).unwrap_err();
            assert!(err.is_client_error(), "{err:?}");
            d.assert_untouched();
        }
    }

    #[test]
    fn destination_must_be_an_existing_empty_directory() {
        let bytes = tgz(&[T::File("a", 0o644, b"x")]);
        let d = dest();
        fs::write(d.dest.join("old"), b"old").unwrap();
        let err = unpack_archive(&bytes, &d.dest, &small()).unwrap_err();
        assert!(matches!(err, BundleError::Destination { .. }), "{err:?}");
        assert!(!err.is_client_error());
        assert_eq!(d.read("old"), b"old");

        let missing = d.parent.path().join("missing");
        let err = unpack_archive(&bytes, &missing, &small()).unwrap_err();
        assert!(matches!(err, BundleError::Destination { .. }), "{err:?}");
        assert!(!missing.exists());

        let link = d.parent.path().join("link");
        let empty = d.parent.path().join("empty");
        fs::create_dir(&empty).unwrap();
        std::os::unix::fs::symlink(&empty, &link).unwrap();
        let err = unpack_archive(&bytes, &link, &small()).unwrap_err();
        assert!(matches!(err, BundleError::Destination { .. }), "{err:?}");
        assert_eq!(fs::read_dir(&empty).unwrap().count(), 0);
    }

    #[test]
    fn only_io_and_destination_errors_are_server_errors() {
        let io = BundleError::Io {
            action: "write file".into(),
            source: io::Error::other("disk full"),
        };
        assert!(!io.is_client_error());
        assert_eq!(io.to_string(), "could not write file: disk full");
        assert!(BundleError::NoFiles.is_client_error());
        assert!(BundleError::UnrecognisedFormat.is_client_error());
        assert!(
            BundleError::TooLarge {
                limit: 1,
                path: None
            }
            .is_client_error()
        );
    }
}
