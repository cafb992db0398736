//! A bot's folder packed for upload: its files as a `.tar.gz`, in a fixed order with
//! fixed times (the same folder gives the same archive), leaving out what `.gitignore`
//! files name (the folder's and those of the folders above it, in or out of a git
//! checkout), every file or folder whose name starts with `.` (`.git`, `.venv`, `.env`...,
//! whatever a `.gitignore` says: a `!.env` there does not bring one back), and anything
//! but regular files. The one way to send a dot-file is to name it in `bot.toml`'s
//! `include` list ([`pack`]'s `include`). Executable bits are kept; the server stores the
//! files, not the archive.

use std::io::Write;
use std::os::unix::fs::PermissionsExt;
use std::path::{Component, Path, PathBuf};

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

/// Whether a name is a dot-file's or a dot-folder's (left out unless included).
fn is_dot(name: &std::ffi::OsStr) -> bool {
    name.as_encoded_bytes().starts_with(b".")
}

/// Packs `dir`, with the files `include` names (relative paths inside `dir`, from
/// `bot.toml`) added even when they are dot-files or a `.gitignore` names them.
///
/// # Errors
/// A folder or file that cannot be read; an `include` entry that is empty, absolute,
/// goes up with `..`, passes through a link, or is not a regular file.
pub fn pack(dir: &Path, include: &[String]) -> anyhow::Result<Packed> {
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
        // `hidden` alone gives way to a `.gitignore`'s `!.env`: a dot-name is left out
        // here whatever the ignore files say (the folder itself, depth 0, may be one).
        .filter_entry(|e| e.depth() == 0 || !is_dot(e.file_name()))
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
    for name in include {
        let rel = included(dir, name)?;
        if !files.contains(&rel) {
            files.push(rel);
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

/// The path an `include` entry names, relative to `dir`, checked: a relative path
/// without `..` whose folders are real folders (not links) inside `dir` and whose end
/// is a regular file.
fn included(dir: &Path, name: &str) -> anyhow::Result<PathBuf> {
    let refuse = |why: &str| {
        anyhow::anyhow!(
            "bot.toml's include {name:?}: {why} (name files inside {} by their relative \
             path, e.g. include = [\".env\"])",
            dir.display()
        )
    };
    let mut rel = PathBuf::new();
    for part in Path::new(name).components() {
        match part {
            Component::Normal(p) => rel.push(p),
            Component::CurDir => {}
            Component::ParentDir => return Err(refuse("`..` may not be used")),
            Component::RootDir | Component::Prefix(_) => {
                return Err(refuse("an absolute path may not be used"));
            }
        }
    }
    if rel.as_os_str().is_empty() {
        return Err(refuse("it names no file"));
    }
    let mut at = dir.to_path_buf();
    let parts: Vec<_> = rel.components().collect();
    for (i, part) in parts.iter().enumerate() {
        at.push(part);
        let meta = std::fs::symlink_metadata(&at).map_err(|e| match e.kind() {
            std::io::ErrorKind::NotFound => refuse("there is no such file"),
            _ => refuse(&format!("cannot read {}: {e}", at.display())),
        })?;
        let last = i + 1 == parts.len();
        if meta.file_type().is_symlink() {
            return Err(refuse("it is or passes through a symbolic link"));
        }
        if last && !meta.is_file() {
            return Err(refuse("it is not a regular file"));
        }
        if !last && !meta.is_dir() {
            return Err(refuse(&format!("{} is not a folder", at.display())));
        }
    }
    Ok(rel)
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
        let p = pack(&bot, &[]).unwrap();
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
        assert_eq!(pack(&bot, &[]).unwrap().archive, p.archive);
    }

    /// A bot folder under a parent whose `.gitignore` brings dot-files back.
    fn folder_with_dot_files() -> (tempfile::TempDir, PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join(".gitignore"), "!.env\n!.secrets/\n!.*\n").unwrap();
        let bot = dir.path().join("bot");
        std::fs::create_dir_all(bot.join(".secrets")).unwrap();
        std::fs::create_dir_all(bot.join("conf")).unwrap();
        for f in [
            "bot.toml",
            "bot.py",
            ".env",
            ".secrets/key",
            "conf/.local",
            "conf/a.txt",
        ] {
            std::fs::write(bot.join(f), f).unwrap();
        }
        (dir, bot)
    }

    fn names(p: &Packed) -> Vec<String> {
        p.files.iter().map(|f| f.display().to_string()).collect()
    }

    #[test]
    fn a_dot_file_is_left_out_whatever_a_gitignore_says() {
        let (_dir, bot) = folder_with_dot_files();
        let p = pack(&bot, &[]).unwrap();
        assert_eq!(names(&p), vec!["bot.py", "bot.toml", "conf/a.txt"]);
    }

    #[test]
    fn include_is_the_one_way_to_send_a_dot_file() {
        let (_dir, bot) = folder_with_dot_files();
        let include = [".env".to_string(), "./conf/.local".into(), "bot.py".into()];
        let p = pack(&bot, &include).unwrap();
        assert_eq!(
            names(&p),
            vec![".env", "bot.py", "bot.toml", "conf/.local", "conf/a.txt"]
        );
        let mut archive = tar::Archive::new(flate2::read::GzDecoder::new(&p.archive[..]));
        let packed: Vec<String> = archive
            .entries()
            .unwrap()
            .map(|e| e.unwrap().path().unwrap().display().to_string())
            .collect();
        assert_eq!(packed, names(&p));
    }

    #[test]
    fn include_names_regular_files_inside_the_folder_only() {
        let (dir, bot) = folder_with_dot_files();
        std::fs::write(dir.path().join("outside"), "x").unwrap();
        std::os::unix::fs::symlink(dir.path().join("outside"), bot.join(".link")).unwrap();
        std::os::unix::fs::symlink(bot.join(".secrets"), bot.join("linked")).unwrap();
        for (name, why) in [
            ("../outside", "`..` may not be used"),
            (".secrets/../.env", "`..` may not be used"),
            ("/etc/passwd", "an absolute path may not be used"),
            ("", "it names no file"),
            (".", "it names no file"),
            (".secrets", "it is not a regular file"),
            (".env/x", "is not a folder"),
            (".missing", "there is no such file"),
            (".link", "symbolic link"),
            ("linked/key", "symbolic link"),
        ] {
            let err = pack(&bot, &[name.to_string()]).unwrap_err().to_string();
            assert!(
                err.contains(why) && err.contains(&format!("include {name:?}")),
                "{name}: {err}"
            );
        }
    }
}
