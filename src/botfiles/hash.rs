//! The content hash of a bundle (the scheme is in the module docs of [`super`]).

use std::collections::BTreeMap;

use sha2::{Digest, Sha256};

/// The version tag at the start of the hashed byte string (see the module docs).
const HASH_DOMAIN: &[u8] = b"mazearena-bundle-v1\n";

/// The lowercase hex content hash of the bundle's files and symbolic links,
/// by normalised path (directories are skipped).
pub(super) fn content_hash(nodes: &BTreeMap<String, Node>) -> String {
    let mut hasher = Sha256::new();
    hasher.update(HASH_DOMAIN);
    for (path, node) in nodes {
        let (kind, size, sha): (u8, u64, [u8; 32]) = match node {
            Node::Dir { .. } => continue,
            Node::File { exec, size, sha } => (if *exec { b'X' } else { b'F' }, *size, *sha),
            Node::Symlink { target } => (
                b'L',
                target.len() as u64,
                Sha256::digest(target.as_bytes()).into(),
            ),
        };
        hasher.update([kind]);
        hasher.update((path.len() as u64).to_be_bytes());
        hasher.update(path.as_bytes());
        hasher.update(size.to_be_bytes());
        hasher.update(sha);
    }
    hex(&hasher.finalize())
}

pub(super) fn hex(bytes: &[u8]) -> String {
    const DIGITS: &[u8; 16] = b"0123456789abcdef";
    let mut s = String::with_capacity(bytes.len() * 2);
    for b in bytes {
        s.push(char::from(DIGITS[usize::from(b >> 4)]));
        s.push(char::from(DIGITS[usize::from(b & 0xf)]));
    }
    s
}

pub(super) enum Node {
    Dir {
        explicit: bool,
    },
    File {
        exec: bool,
        size: u64,
        sha: [u8; 32],
    },
    Symlink {
        target: String,
    },
}
