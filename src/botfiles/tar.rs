//! Reading a `.tar` or `.tar.gz` stream into a [`Bundle`], with a cap on the
//! decompressed size.

use std::cell::Cell;
use std::io::{self, Read};

use super::bundle::Bundle;
use super::format::{Format, special, stream_error};
use super::names::parse_path;
use super::{BundleError, TAR_OVERHEAD_PER_ENTRY};

/// Reads at most `remaining` bytes from `inner`, then fails (and sets `tripped`).
struct CapReader<'a, R> {
    inner: R,
    remaining: u64,
    tripped: &'a Cell<bool>,
}

impl<R: Read> Read for CapReader<'_, R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if buf.is_empty() {
            return Ok(0);
        }
        if self.remaining == 0 {
            // Is there anything beyond the cap? Probe one byte.
            let mut probe = [0u8; 1];
            return match self.inner.read(&mut probe)? {
                0 => Ok(0),
                _ => {
                    self.tripped.set(true);
                    Err(io::Error::other(
                        "the archive unpacks to more than the size limit",
                    ))
                }
            };
        }
        let want = buf
            .len()
            .min(usize::try_from(self.remaining).unwrap_or(usize::MAX));
        let n = self.inner.read(&mut buf[..want])?;
        self.remaining -= n as u64;
        Ok(n)
    }
}

pub(super) fn read_tar<R: Read>(
    reader: R,
    format: Format,
    bundle: &mut Bundle,
) -> Result<(), BundleError> {
    let limits = bundle.limits;
    let tripped = Cell::new(false);
    let allowance = (limits.max_files as u64)
        .saturating_add(16)
        .saturating_mul(TAR_OVERHEAD_PER_ENTRY);
    let capped = CapReader {
        inner: reader,
        remaining: limits.max_total_bytes.saturating_add(allowance),
        tripped: &tripped,
    };
    let fail = |e: io::Error, entry: Option<&str>| -> BundleError {
        if tripped.get() {
            BundleError::TooLarge {
                limit: limits.max_total_bytes,
                path: entry.map(str::to_owned),
            }
        } else {
            stream_error(e, format, entry)
        }
    };

    let mut archive = tar::Archive::new(capped);
    {
        let entries = archive.entries().map_err(|e| fail(e, None))?;
        let mut previous: Option<String> = None;
        for entry in entries {
            let mut entry = entry.map_err(|e| {
                // A failure while looking for the next header: name the entry
                // whose data we just went past, if any.
                fail(e, previous.as_deref())
            })?;
            let entry_type = entry.header().entry_type();
            if entry_type.is_pax_global_extensions() {
                // Archive-wide metadata (e.g. from `git archive`): nothing to store.
                continue;
            }
            let raw = entry.path_bytes().into_owned();
            let name = match String::from_utf8(raw) {
                Ok(name) => name,
                Err(e) => {
                    return Err(BundleError::InvalidName {
                        path: String::from_utf8_lossy(e.as_bytes()).into_owned(),
                        reason: "it is not valid UTF-8".to_owned(),
                    });
                }
            };
            let (path, trailing_slash) = parse_path(&name)?;
            // A link's target; only read for link entries.
            let link = |entry: &tar::Entry<'_, _>| -> Result<String, BundleError> {
                let bytes = entry
                    .link_name_bytes()
                    .ok_or_else(|| BundleError::InvalidName {
                        path: name.clone(),
                        reason: "it is a link with an empty target".to_owned(),
                    })?;
                String::from_utf8(bytes.into_owned()).map_err(|_| BundleError::InvalidName {
                    path: name.clone(),
                    reason: "its link target is not valid UTF-8".to_owned(),
                })
            };

            let regular = entry_type.is_file() || entry_type.is_contiguous();
            if entry_type.is_dir() || (regular && trailing_slash) {
                bundle.add_dir(&name, &path)?;
            } else if regular {
                if path.is_empty() {
                    return Err(BundleError::EmptyName);
                }
                let mode = entry.header().mode().map_err(|e| BundleError::Corrupt {
                    format: format.name(),
                    detail: format!("entry {name:?} has an unreadable mode: {e}"),
                })?;
                let declared = entry.size();
                let exec = mode & 0o111 != 0;
                bundle.add_file(&name, &path, exec, declared, &mut entry, &|e, n| {
                    fail(e, Some(n))
                })?;
            } else if entry_type.is_symlink() {
                let target = link(&entry)?;
                bundle.add_symlink(&name, &path, &target)?;
            } else if entry_type.is_hard_link() {
                let target = link(&entry)?;
                bundle.add_hard_link(&name, &path, &target)?;
            } else if entry_type.is_character_special() || entry_type.is_block_special() {
                return Err(special(&name, "a device file"));
            } else if entry_type.is_fifo() {
                return Err(special(&name, "a named pipe (fifo)"));
            } else if entry_type.is_gnu_sparse() {
                return Err(BundleError::Unsupported {
                    path: name,
                    feature: "a sparse file".to_owned(),
                });
            } else {
                return Err(special(
                    &name,
                    &format!(
                        "an entry of unknown type {:?}",
                        char::from(entry_type.as_byte())
                    ),
                ));
            }
            previous = Some(name);
        }
    }
    // Read what is left (end-of-archive blocks, padding) so that a gzip stream
    // is checked to its end: its length and CRC are in its last 8 bytes.
    let mut rest = archive.into_inner();
    io::copy(&mut rest, &mut io::sink()).map_err(|e| fail(e, None))?;
    Ok(())
}
