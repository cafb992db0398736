//! Reading a bot's directory back: its content hash ([`hash_dir`]) and a canonical
//! `.tar.gz` of it ([`pack_dir`]), the form in which bundles are stored.

use std::collections::BTreeMap;
use std::fs;
use std::io::{self, Read};
use std::os::unix::fs::{MetadataExt, OpenOptionsExt, PermissionsExt};
use std::path::Path;

use sha2::{Digest, Sha256};

use super::hash::Node;
use super::hash::content_hash;
use super::{BundleError, BundleLimits, BundleSummary};

/// A bundle packed from a directory: a `.tar.gz` that [`super::unpack_archive`] reads
/// back to the same files, and its summary (with the content hash).
#[derive(Debug, Clone)]
pub struct Packed {
    /// The archive's bytes (gzip-compressed tar).
    pub archive: Vec<u8>,
    /// Files, bytes and content hash of what it holds.
    pub summary: BundleSummary,
}

/// Which entries of a directory are left out (by name, at any depth).
pub type Skip<'a> = &'a dyn Fn(&str) -> bool;

/// Skips nothing.
pub fn skip_nothing(_: &str) -> bool {
    false
}

/// Skips what a local bot folder holds besides its sources: hidden entries and the
/// usual build and cache folders (`target`, `node_modules`, `__pycache__`).
pub fn skip_build_outputs(name: &str) -> bool {
    name.starts_with('.') || ["target", "node_modules", "__pycache__"].contains(&name)
}

/// The content hash (and counts) of the files and links below `dir`, by the scheme of
/// the module docs of [`super`]: the hash an upload of the same files gets.
///
/// # Errors
/// Entries that cannot be part of a bundle (special files, names that are not UTF-8),
/// going over `limits`, and I/O failures.
pub fn hash_dir(
    dir: &Path,
    limits: &BundleLimits,
    skip: Skip,
) -> Result<BundleSummary, BundleError> {
    walk_dir(dir, limits, skip, None)
}

/// Packs the files, directories and links below `dir` into a canonical `.tar.gz`
/// (sorted entries, no owners or timestamps, modes `0o755`/`0o644`).
///
/// # Errors
/// As [`hash_dir`].
pub fn pack_dir(dir: &Path, limits: &BundleLimits, skip: Skip) -> Result<Packed, BundleError> {
    let encoder = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    let mut builder = ::tar::Builder::new(encoder);
    let summary = walk_dir(dir, limits, skip, Some(&mut builder))?;
    let io = |e: io::Error| BundleError::Io {
        action: format!("pack {}", dir.display()),
        source: e,
    };
    let archive = builder.into_inner().map_err(io)?.finish().map_err(io)?;
    Ok(Packed { archive, summary })
}

type TarOut<'a> = Option<&'a mut ::tar::Builder<flate2::write::GzEncoder<Vec<u8>>>>;

fn walk_dir(
    root: &Path,
    limits: &BundleLimits,
    skip: Skip,
    mut out: TarOut,
) -> Result<BundleSummary, BundleError> {
    let mut nodes = BTreeMap::new();
    let mut total = 0u64;
    let mut stack = vec![String::new()];
    while let Some(rel) = stack.pop() {
        let dir = if rel.is_empty() {
            root.to_path_buf()
        } else {
            root.join(&rel)
        };
        let listing = fs::read_dir(&dir).map_err(io_err(&dir, "list"))?;
        let mut names = Vec::new();
        for entry in listing {
            let entry = entry.map_err(io_err(&dir, "list"))?;
            let name = entry
                .file_name()
                .into_string()
                .map_err(|raw| BundleError::InvalidName {
                    path: raw.to_string_lossy().into_owned(),
                    reason: "it is not UTF-8".to_owned(),
                })?;
            if !skip(&name) {
                names.push(name);
            }
        }
        names.sort();
        for name in names {
            let path = if rel.is_empty() {
                name.clone()
            } else {
                format!("{rel}/{name}")
            };
            let full = root.join(&path);
            if nodes.len() >= limits.max_files {
                return Err(BundleError::TooManyFiles {
                    limit: limits.max_files,
                    path,
                });
            }
            let meta = fs::symlink_metadata(&full).map_err(io_err(&full, "read"))?;
            let kind = meta.file_type();
            if kind.is_dir() {
                if let Some(tar) = out.as_deref_mut() {
                    append(
                        tar,
                        &path,
                        ::tar::EntryType::Directory,
                        0o755,
                        0,
                        io::empty(),
                        None,
                    )?;
                }
                nodes.insert(path.clone(), Node::Dir { explicit: true });
                stack.push(path);
            } else if kind.is_symlink() {
                let target = fs::read_link(&full).map_err(io_err(&full, "read the link"))?;
                let target = target.into_os_string().into_string().map_err(|_| {
                    BundleError::InvalidName {
                        path: path.clone(),
                        reason: "its link target is not UTF-8".to_owned(),
                    }
                })?;
                if let Some(tar) = out.as_deref_mut() {
                    append(
                        tar,
                        &path,
                        ::tar::EntryType::Symlink,
                        0o777,
                        0,
                        io::empty(),
                        Some(&target),
                    )?;
                }
                nodes.insert(path, Node::Symlink { target });
            } else if kind.is_file() {
                // Judged by its metadata before a byte is read: its size against what
                // is left, its holes, its setuid and setgid bits.
                let size = meta.len();
                let mode = meta.permissions().mode();
                if mode & 0o6000 != 0 {
                    return Err(super::format::special(&path, "a setuid or setgid file"));
                }
                total += size;
                if total > limits.max_total_bytes {
                    return Err(BundleError::TooLarge {
                        limit: limits.max_total_bytes,
                        path: Some(path),
                    });
                }
                if size.saturating_sub(meta.blocks().saturating_mul(512)) > MAX_HOLE_BYTES {
                    return Err(super::format::special(&path, "a sparse file (with holes)"));
                }
                let file = fs::OpenOptions::new()
                    .read(true)
                    .custom_flags(libc::O_NOFOLLOW)
                    .open(&full)
                    .map_err(io_err(&full, "read"))?;
                let mut reader = Hashing {
                    inner: file.take(size),
                    sha: Sha256::new(),
                    read: 0,
                };
                let exec = mode & 0o111 != 0;
                match out.as_deref_mut() {
                    Some(tar) => {
                        let mode = if exec { 0o755 } else { 0o644 };
                        append(
                            tar,
                            &path,
                            ::tar::EntryType::Regular,
                            mode,
                            size,
                            &mut reader,
                            None,
                        )?;
                    }
                    None => {
                        io::copy(&mut reader, &mut io::sink()).map_err(io_err(&full, "read"))?;
                    }
                }
                if reader.read != size {
                    return Err(BundleError::Io {
                        action: format!("read {}", full.display()),
                        source: io::Error::other("the file changed while it was read"),
                    });
                }
                let sha: [u8; 32] = reader.sha.finalize().into();
                nodes.insert(path, Node::File { exec, size, sha });
            } else {
                return Err(super::format::special(&path, "a special file"));
            }
        }
    }
    let files = nodes
        .values()
        .filter(|n| matches!(n, Node::File { .. }))
        .count();
    if files == 0 {
        return Err(BundleError::NoFiles);
    }
    Ok(BundleSummary {
        files,
        bytes: total,
        sha256: content_hash(&nodes),
    })
}

/// Holes a file may have before it counts as sparse and is refused (file systems
/// round and compress; a file with large holes would be read as its whole length).
const MAX_HOLE_BYTES: u64 = 1 << 20;

/// A reader that hashes what it reads and counts it.
struct Hashing<R> {
    inner: R,
    sha: Sha256,
    read: u64,
}

impl<R: Read> Read for Hashing<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.sha.update(&buf[..n]);
        self.read += n as u64;
        Ok(n)
    }
}

#[allow(clippy::too_many_arguments)]
fn append(
    tar: &mut ::tar::Builder<flate2::write::GzEncoder<Vec<u8>>>,
    path: &str,
    kind: ::tar::EntryType,
    mode: u32,
    size: u64,
    content: impl Read,
    link: Option<&str>,
) -> Result<(), BundleError> {
    let mut header = ::tar::Header::new_gnu();
    header.set_entry_type(kind);
    header.set_mode(mode);
    header.set_mtime(0);
    header.set_size(size);
    let io = |e: io::Error| BundleError::Io {
        action: format!("pack {path:?}"),
        source: e,
    };
    match link {
        Some(target) => tar.append_link(&mut header, path, target).map_err(io),
        None => tar.append_data(&mut header, path, content).map_err(io),
    }
}

fn io_err<'a>(path: &'a Path, action: &'a str) -> impl FnOnce(io::Error) -> BundleError + 'a {
    move |source| BundleError::Io {
        action: format!("{action} {}", path.display()),
        source,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::botfiles::{unpack_archive, write_files};

    fn files(pairs: &[(&str, &str)]) -> BTreeMap<String, String> {
        pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    }

    #[test]
    fn a_packed_directory_unpacks_to_the_same_hash_as_its_upload() {
        let limits = BundleLimits::default();
        let up = tempfile::tempdir().unwrap();
        let dest = up.path().join("bot");
        fs::create_dir(&dest).unwrap();
        let uploaded = write_files(
            &files(&[
                ("bot.py", "print(1)\n"),
                ("lib/a.py", "A = 1\n"),
                ("lib/b/c.txt", ""),
            ]),
            &dest,
            &limits,
        )
        .unwrap();
        std::os::unix::fs::symlink("lib/a.py", dest.join("link.py")).unwrap();
        fs::set_permissions(dest.join("bot.py"), fs::Permissions::from_mode(0o755)).unwrap();
        let hashed = hash_dir(&dest, &limits, &skip_nothing).unwrap();
        assert_ne!(
            hashed.sha256, uploaded.sha256,
            "a link and a mode were added"
        );
        let packed = pack_dir(&dest, &limits, &skip_nothing).unwrap();
        assert_eq!(packed.summary, hashed);

        let back = tempfile::tempdir().unwrap();
        let again = back.path().join("bot");
        fs::create_dir(&again).unwrap();
        let unpacked = unpack_archive(&packed.archive, &again, &limits).unwrap();
        assert_eq!(unpacked, hashed);
        assert_eq!(
            fs::read_link(again.join("link.py")).unwrap(),
            Path::new("lib/a.py")
        );
        assert_eq!(
            fs::metadata(again.join("bot.py"))
                .unwrap()
                .permissions()
                .mode()
                & 0o777,
            0o755
        );
        // Packing is canonical: the same files give the same bytes.
        assert_eq!(
            pack_dir(&again, &limits, &skip_nothing).unwrap().archive,
            packed.archive
        );
    }

    #[test]
    fn skipped_names_special_files_and_limits() {
        let d = tempfile::tempdir().unwrap();
        fs::write(d.path().join("bot.py"), "x").unwrap();
        let before = hash_dir(d.path(), &BundleLimits::default(), &skip_build_outputs).unwrap();
        fs::create_dir_all(d.path().join("target/release")).unwrap();
        fs::write(d.path().join("target/release/bot"), "binary").unwrap();
        fs::write(d.path().join(".hidden"), "x").unwrap();
        let after = hash_dir(d.path(), &BundleLimits::default(), &skip_build_outputs).unwrap();
        assert_eq!(before, after);
        let all = hash_dir(d.path(), &BundleLimits::default(), &skip_nothing).unwrap();
        assert_ne!(all.sha256, before.sha256);

        let small = BundleLimits {
            max_total_bytes: 3,
            max_files: 100,
        };
        let err = hash_dir(d.path(), &small, &skip_nothing).unwrap_err();
        assert!(matches!(err, BundleError::TooLarge { .. }), "{err:?}");

        nix::unistd::mkfifo(&d.path().join("pipe"), nix::sys::stat::Mode::S_IRWXU).unwrap();
        let err = pack_dir(d.path(), &BundleLimits::default(), &skip_nothing).unwrap_err();
        assert!(matches!(err, BundleError::SpecialFile { .. }), "{err:?}");

        let empty = tempfile::tempdir().unwrap();
        let err = hash_dir(empty.path(), &BundleLimits::default(), &skip_nothing).unwrap_err();
        assert!(matches!(err, BundleError::NoFiles), "{err:?}");
    }

    #[test]
    fn sparse_huge_and_setuid_files_are_refused_from_their_metadata() {
        let d = tempfile::tempdir().unwrap();
        fs::write(d.path().join("bot.py"), "x").unwrap();
        // 64 GiB of holes: refused at once, never read (reading it would take minutes
        // and, held in memory, 64 GiB).
        let huge = fs::File::create(d.path().join("holes")).unwrap();
        huge.set_len(64 << 30).unwrap();
        let started = std::time::Instant::now();
        let err = pack_dir(d.path(), &BundleLimits::default(), &skip_nothing).unwrap_err();
        assert!(matches!(err, BundleError::TooLarge { .. }), "{err:?}");
        assert!(started.elapsed() < std::time::Duration::from_secs(2));
        // Within the size limit but with holes: refused as sparse.
        huge.set_len(8 << 20).unwrap();
        let err = pack_dir(d.path(), &BundleLimits::default(), &skip_nothing).unwrap_err();
        assert!(
            matches!(&err, BundleError::SpecialFile { kind, .. } if kind.contains("sparse")),
            "{err:?}"
        );
        fs::remove_file(d.path().join("holes")).unwrap();
        let id = d.path().join("id");
        fs::write(&id, "ELF").unwrap();
        fs::set_permissions(&id, fs::Permissions::from_mode(0o4755)).unwrap();
        let err = pack_dir(d.path(), &BundleLimits::default(), &skip_nothing).unwrap_err();
        assert!(
            matches!(&err, BundleError::SpecialFile { kind, .. } if kind.contains("setuid")),
            "{err:?}"
        );
        fs::set_permissions(&id, fs::Permissions::from_mode(0o2755)).unwrap();
        assert!(pack_dir(d.path(), &BundleLimits::default(), &skip_nothing).is_err());
        fs::set_permissions(&id, fs::Permissions::from_mode(0o755)).unwrap();
        let packed = pack_dir(d.path(), &BundleLimits::default(), &skip_nothing).unwrap();
        assert_eq!(packed.summary.files, 2);
    }
}
