//! Tests of the bot files' operations: unpacking, hashing, refusals, limits. The
//! helpers build archives entry by entry, including the malformed ones.

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

mod refusals;
mod round_trips;
