//! Checking and normalising entry names.

use super::{BundleError, MAX_NAME_BYTES, MAX_PATH_BYTES};

/// Checks an entry name and returns its normalised form (components joined by
/// `/`, without `.` and empty components; `""` for the bot's directory itself)
/// and whether the name ended with `/`.
pub(super) fn parse_path(raw: &str) -> Result<(String, bool), BundleError> {
    let invalid = |reason: &str| BundleError::InvalidName {
        path: raw.to_owned(),
        reason: reason.to_owned(),
    };
    if raw.is_empty() {
        return Err(BundleError::EmptyName);
    }
    if raw.contains('\0') {
        return Err(invalid("it contains a NUL byte"));
    }
    if raw.contains('\\') {
        return Err(invalid(
            "it contains a backslash (use / between directories)",
        ));
    }
    if raw.starts_with('/') {
        return Err(BundleError::AbsolutePath {
            path: raw.to_owned(),
        });
    }
    if has_drive_prefix(raw) {
        return Err(invalid("it starts with a Windows drive letter"));
    }
    let mut parts: Vec<&str> = Vec::new();
    for part in raw.split('/') {
        match part {
            "" | "." => {}
            ".." => {
                return Err(BundleError::PathEscapes {
                    path: raw.to_owned(),
                });
            }
            part if part.len() > MAX_NAME_BYTES => {
                return Err(invalid(&format!(
                    "a component is longer than {MAX_NAME_BYTES} bytes"
                )));
            }
            part => parts.push(part),
        }
    }
    let path = parts.join("/");
    if path.len() > MAX_PATH_BYTES {
        return Err(invalid(&format!(
            "it is longer than {MAX_PATH_BYTES} bytes"
        )));
    }
    Ok((path, raw.ends_with('/')))
}

pub(super) fn has_drive_prefix(s: &str) -> bool {
    let b = s.as_bytes();
    b.len() >= 2 && b[0].is_ascii_alphabetic() && b[1] == b':'
}

/// The parent directories of a normalised path, outermost first (`a`, `a/b` for `a/b/c`).
pub(super) fn parents(path: &str) -> impl Iterator<Item = &str> {
    path.match_indices('/').map(move |(i, _)| &path[..i])
}
