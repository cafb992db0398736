//! Recognising the archive format and classifying errors from reading it.

use std::io;

use super::BundleError;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Format {
    TarGz,
    Tar,
    Zip,
}

impl Format {
    pub(super) fn name(self) -> &'static str {
        match self {
            Format::TarGz => ".tar.gz",
            Format::Tar => ".tar",
            Format::Zip => ".zip",
        }
    }
}

pub(super) fn detect_format(bytes: &[u8]) -> Result<Format, BundleError> {
    if bytes.starts_with(&[0x1f, 0x8b]) {
        Ok(Format::TarGz)
    } else if bytes.starts_with(b"PK\x03\x04") || bytes.starts_with(b"PK\x05\x06") {
        Ok(Format::Zip)
    } else if bytes.get(257..262) == Some(b"ustar".as_slice()) {
        Ok(Format::Tar)
    } else if bytes.len() >= 1024
        && bytes.len().is_multiple_of(512)
        && bytes.iter().all(|&b| b == 0)
    {
        // Only end-of-archive blocks: an empty tar (refused later as having no files).
        Ok(Format::Tar)
    } else {
        Err(BundleError::UnrecognisedFormat)
    }
}

/// Classifies an error from reading an archive stream (always the client's data).
pub(super) fn stream_error(e: io::Error, format: Format, entry: Option<&str>) -> BundleError {
    let text = e.to_string();
    if e.kind() == io::ErrorKind::UnexpectedEof
        || text.contains("failed to read entire block")
        || text.contains("unexpected EOF")
    {
        BundleError::Truncated {
            format: format.name(),
            entry: entry.map(str::to_owned),
        }
    } else {
        // The tar crate reports bad headers as `Other` with terse texts such as
        // "numeric field was not a number:  when getting cksum for "; the
        // decompressor and the zip reader use other kinds with readable texts.
        let what = if format != Format::Zip && e.kind() == io::ErrorKind::Other {
            "it holds an invalid tar header".to_owned()
        } else {
            text
        };
        BundleError::Corrupt {
            format: format.name(),
            detail: match entry {
                Some(entry) => format!("{what} (at entry {entry:?})"),
                None => what,
            },
        }
    }
}

pub(super) fn special(name: &str, kind: &str) -> BundleError {
    BundleError::SpecialFile {
        path: name.to_owned(),
        kind: kind.to_owned(),
    }
}
