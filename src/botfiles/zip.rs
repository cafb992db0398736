//! Reading a `.zip` archive into a [`Bundle`].

use std::collections::HashSet;
use std::io::{self, Read};

use super::bundle::Bundle;
use super::format::{Format, special, stream_error};
use super::names::parse_path;
use super::{BundleError, MAX_PATH_BYTES};

const S_IFMT: u32 = 0o170000;
const S_IFREG: u32 = 0o100000;
const S_IFDIR: u32 = 0o040000;
const S_IFLNK: u32 = 0o120000;
pub(super) const S_IFCHR: u32 = 0o020000;
const S_IFBLK: u32 = 0o060000;
pub(super) const S_IFIFO: u32 = 0o010000;
pub(super) const S_IFSOCK: u32 = 0o140000;

fn zip_error(e: zip::result::ZipError, entry: Option<&str>) -> BundleError {
    use zip::result::ZipError;
    let format = Format::Zip.name();
    match e {
        ZipError::Io(e) => stream_error(e, Format::Zip, entry),
        ZipError::UnsupportedArchive(what) => match entry {
            Some(entry) => BundleError::Unsupported {
                path: entry.to_owned(),
                feature: if what == ZipError::PASSWORD_REQUIRED {
                    "encryption".to_owned()
                } else {
                    what.to_owned()
                },
            },
            None => BundleError::Corrupt {
                format,
                detail: format!("unsupported zip feature: {what}"),
            },
        },
        other => BundleError::Corrupt {
            format,
            detail: match entry {
                Some(entry) => format!("while reading entry {entry:?}: {other}"),
                None => other.to_string(),
            },
        },
    }
}

/// The zip reader keys entries by name and silently keeps only one of several
/// entries with the same name, so look for duplicates in the central directory
/// ourselves.
fn zip_duplicate(bytes: &[u8], start: u64) -> Option<String> {
    let mut pos = usize::try_from(start).ok()?;
    let mut seen: HashSet<&[u8]> = HashSet::new();
    loop {
        let header = bytes.get(pos..pos.checked_add(46)?)?;
        if &header[..4] != b"PK\x01\x02" {
            return None;
        }
        let u16_at = |i: usize| usize::from(u16::from_le_bytes([header[i], header[i + 1]]));
        let (name_len, extra_len, comment_len) = (u16_at(28), u16_at(30), u16_at(32));
        let name_start = pos + 46;
        let name = bytes.get(name_start..name_start.checked_add(name_len)?)?;
        if !seen.insert(name) {
            return Some(String::from_utf8_lossy(name).into_owned());
        }
        pos = name_start + name_len + extra_len + comment_len;
    }
}

pub(super) fn read_zip(bytes: &[u8], bundle: &mut Bundle) -> Result<(), BundleError> {
    let mut archive =
        zip::ZipArchive::new(io::Cursor::new(bytes)).map_err(|e| zip_error(e, None))?;
    if let Some(path) = zip_duplicate(bytes, archive.central_directory_start()) {
        return Err(BundleError::Duplicate { path });
    }
    for index in 0..archive.len() {
        let listed = archive.name_for_index(index).map(str::to_owned);
        let mut file = archive
            .by_index(index)
            .map_err(|e| zip_error(e, listed.as_deref()))?;
        let name = file.name().to_owned();
        if file.encrypted() {
            return Err(BundleError::Unsupported {
                path: name,
                feature: "encryption".to_owned(),
            });
        }
        let (path, trailing_slash) = parse_path(&name)?;
        let mode = file.unix_mode();
        let file_type = mode.map_or(0, |m| m & S_IFMT);
        let exec = mode.is_some_and(|m| m & 0o111 != 0);
        if trailing_slash || file_type == S_IFDIR {
            bundle.add_dir(&name, &path)?;
            continue;
        }
        match file_type {
            0 | S_IFREG => {
                if path.is_empty() {
                    return Err(BundleError::EmptyName);
                }
                let declared = file.size();
                bundle.add_file(&name, &path, exec, declared, &mut file, &|e, n| {
                    stream_error(e, Format::Zip, Some(n))
                })?;
            }
            S_IFLNK => {
                let mut target = Vec::new();
                (&mut file)
                    .take(MAX_PATH_BYTES as u64 + 1)
                    .read_to_end(&mut target)
                    .map_err(|e| stream_error(e, Format::Zip, Some(&name)))?;
                if target.len() > MAX_PATH_BYTES {
                    return Err(BundleError::InvalidName {
                        path: name,
                        reason: format!("its link target is longer than {MAX_PATH_BYTES} bytes"),
                    });
                }
                let target = String::from_utf8(target).map_err(|_| BundleError::InvalidName {
                    path: name.clone(),
                    reason: "its link target is not valid UTF-8".to_owned(),
                })?;
                bundle.add_symlink(&name, &path, &target)?;
            }
            S_IFCHR | S_IFBLK => return Err(special(&name, "a device file")),
            S_IFIFO => return Err(special(&name, "a named pipe (fifo)")),
            S_IFSOCK => return Err(special(&name, "a socket")),
            other => {
                return Err(special(
                    &name,
                    &format!("an entry of unknown file type {other:#o}"),
                ));
            }
        }
    }
    Ok(())
}
