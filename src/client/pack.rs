//! A bot's folder packed for upload: its files as a `.tar.gz`, in a fixed order with
//! fixed times (the same folder gives the same archive), leaving out what `.gitignore`
//! files name (the folder's and those of the folders above it, in or out of a git
//! checkout), hidden files and folders (`.git`, `.venv`...), and anything but regular
//! files. Executable bits are kept; the server stores the files, not the archive.

use std::io::Write;
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};

/// A packed folder.
#[derive(Debug)]
pub struct Packed {
    /// The `.tar.gz` archive.
    pub archive: Vec<u8>,
    /// The files in it, relative to the folder, in order.
    pub files: Vec<PathBuf>,
    /// What was left out because it is not a regular file (links, sockets...).
    pub skipped: Vec<PathBuf>,
}

/// Packs `dir`.
///
/// # Errors
/// A folder or file that cannot be read.
pub fn pack(dir: &Path) -> anyhow::Result<Packed> {
    let mut files = Vec::new();
    let mut skipped = Vec::new();
    let walk = ignore::WalkBuilder::new(dir)
        .hidden(true)
        .git_ignore(true)
        .git_global(false)
        .git_exclude(false)
        .require_git(false)
        .parents(true)
        .ignore(false)
        .follow_links(false)
        .build();
    for entry in walk {
        let entry = entry.map_err(|e| anyhow::anyhow!("cannot read {}: {e}", dir.display()))?;
        let Some(kind) = entry.file_type() else {
            continue;
        };
        if kind.is_dir() {
            continue;
        }
        let rel = entry
            .path()
            .strip_prefix(dir)
            .unwrap_or(entry.path())
            .to_path_buf();
        if kind.is_file() {
            files.push(rel);
        } else {
            skipped.push(rel);
        }
    }
    files.sort();
    let gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    let mut tar = tar::Builder::new(gz);
    for rel in &files {
        let full = dir.join(rel);
        let meta = std::fs::metadata(&full)
            .map_err(|e| anyhow::anyhow!("cannot read {}: {e}", full.display()))?;
        let mut header = tar::Header::new_gnu();
        header.set_size(meta.len());
        header.set_mode(if meta.permissions().mode() & 0o111 != 0 {
            0o755
        } else {
            0o644
        });
        header.set_mtime(0);
        header.set_entry_type(tar::EntryType::Regular);
        let file = std::fs::File::open(&full)
            .map_err(|e| anyhow::anyhow!("cannot read {}: {e}", full.display()))?;
        tar.append_data(&mut header, rel, file)
            .map_err(|e| anyhow::anyhow!("cannot pack {}: {e}", full.display()))?;
    }
    let mut gz = tar.into_inner()?;
    gz.flush()?;
    Ok(Packed {
        archive: gz.finish()?,
        files,
        skipped,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_is_packed_without_what_gitignore_names_and_with_its_modes() {
        let dir = tempfile::tempdir().unwrap();
        let bot = dir.path().join("bot");
        std::fs::create_dir_all(bot.join("src/minimal_bot")).unwrap();
        std::fs::create_dir_all(bot.join(".git")).unwrap();
        std::fs::create_dir_all(bot.join("classes")).unwrap();
        std::fs::write(dir.path().join(".gitignore"), "*.o\n").unwrap();
        std::fs::write(bot.join(".gitignore"), "/minimal_bot\nclasses/\n").unwrap();
        for f in [
            "bot.toml",
            "src/minimal_bot/main.c",
            "minimal_bot",
            "x.o",
            ".git/HEAD",
            "classes/A.class",
        ] {
            std::fs::write(bot.join(f), f).unwrap();
        }
        std::fs::write(bot.join("run.sh"), "#!/bin/sh\n").unwrap();
        std::fs::set_permissions(bot.join("run.sh"), std::fs::Permissions::from_mode(0o700))
            .unwrap();
        std::os::unix::fs::symlink("/etc/passwd", bot.join("link")).unwrap();
        let p = pack(&bot).unwrap();
        let names: Vec<String> = p.files.iter().map(|f| f.display().to_string()).collect();
        // The kit's `/minimal_bot` (a build) is left out, its source folder of the same
        // name is not; so are the parent's `*.o`, hidden files and classes/.
        assert_eq!(names, vec!["bot.toml", "run.sh", "src/minimal_bot/main.c"]);
        assert_eq!(p.skipped, vec![PathBuf::from("link")]);
        let mut archive = tar::Archive::new(flate2::read::GzDecoder::new(&p.archive[..]));
        let modes: Vec<(String, u32)> = archive
            .entries()
            .unwrap()
            .map(|e| {
                let e = e.unwrap();
                (
                    e.path().unwrap().display().to_string(),
                    e.header().mode().unwrap(),
                )
            })
            .collect();
        assert!(modes.contains(&("run.sh".into(), 0o755)), "{modes:?}");
        assert!(modes.contains(&("bot.toml".into(), 0o644)), "{modes:?}");
        // The same folder, the same archive.
        assert_eq!(pack(&bot).unwrap().archive, p.archive);
    }
}
