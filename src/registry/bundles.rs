//! Storing a bot's files as a content-addressed bundle in the database.
//!
//! A version's `files_sha256` always means one thing: the bundle hash of
//! [`crate::botfiles`] (files and links with their paths, contents and executable bits;
//! not timestamps, entry order or archive format). An upload, the same files in a
//! local folder and the bundle stored for them all give the same hash.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

use super::{RegistryError, Result};
use crate::botfiles::{self, BundleLimits, BundleSummary, Packed, skip_nothing};
use crate::storage::Storage;
use crate::storage::bundles::NewBundle;

/// A bot's files as sent: a map of names to texts, or an archive (`.tar.gz`, `.tar`,
/// `.zip`).
#[derive(Debug, Clone)]
pub enum BotFiles {
    /// File name -> UTF-8 content.
    Map(BTreeMap<String, String>),
    /// An archive's bytes.
    Archive(Vec<u8>),
    /// The files (a map or an archive) of a robot written for the original task, to
    /// which the server adds its adapter ([`ORIGINAL_TASK_ADAPTER`], as
    /// [`ADAPTER_FILE`]) so that its author uploads only their own files.
    OriginalTask {
        /// The author's files.
        files: Box<BotFiles>,
        /// The file (at the top, `.py`) that holds `class Robot`, as its author named
        /// it; none: `robot.py`, or else the only top-level `.py` file that defines
        /// `class Robot` ([`robot_file`]).
        robot: Option<String>,
    },
}

/// What [`store_upload`] stored: the bundle, and for an original-task robot the file
/// that holds its `class Robot`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Stored {
    /// The stored bundle.
    pub summary: BundleSummary,
    /// The robot's file (original-task uploads only).
    pub robot: Option<String>,
}

/// The adapter that runs an unchanged original-task `robot.py` as a protocol-v1 bot.
pub const ORIGINAL_TASK_ADAPTER: &str = include_str!("../../bots/python/udacity_adapter.py");

/// The adapter's file name in a bot's folder.
pub const ADAPTER_FILE: &str = "udacity_adapter.py";

/// The robot file an original-task upload holds unless its author names another.
pub const ROBOT_FILE: &str = "robot.py";

/// The command of an original-task robot whose `class Robot` is in `robot`: the
/// adapter run by `python3` (the system's), or by `python` when the bot chose a runtime
/// (`with_runtime`: a virtual environment has both names; a Python 2 one only
/// `python`).
pub fn original_task_command(with_runtime: bool, robot: &str) -> String {
    let python = if with_runtime { "python" } else { "python3" };
    format!("{python} {ADAPTER_FILE} {robot}")
}

/// Whether Python source `text` defines a top-level `class Robot` (a line that starts
/// with `class Robot` followed by `(` or `:`). Read as text, never run.
fn defines_robot(text: &str) -> bool {
    text.lines().any(|l| {
        l.strip_prefix("class Robot")
            .is_some_and(|rest| rest.trim_start().starts_with(['(', ':']))
    })
}

/// Checks the name of an original-task robot's file as its author gave it: a `.py`
/// file at the top of the files (letters, digits, `_`, `-`, `.`).
fn check_robot_name(name: &str) -> Result<()> {
    let ok = name.len() <= 100
        && name.ends_with(".py")
        && name.len() > 3
        && !name.starts_with(['.', '-'])
        && name
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b"_-.".contains(&b));
    if ok {
        Ok(())
    } else {
        Err(RegistryError::Invalid(format!(
            "the robot's file {name:?} is not a .py file at the top of the files (letters, \
             digits, _, - and . only)"
        )))
    }
}

/// The file of an original-task robot written into `dest`: `named` if its author
/// named one (it must be there), else [`ROBOT_FILE`] if it is there, else the only
/// top-level `.py` file that defines `class Robot`.
///
/// # Errors
/// [`RegistryError::Invalid`] saying what is there and how to name the file.
pub fn robot_file(dest: &Path, named: Option<&str>, files: usize) -> Result<String> {
    if let Some(name) = named.map(str::trim).filter(|n| !n.is_empty()) {
        check_robot_name(name)?;
        if fs::symlink_metadata(dest.join(name)).is_ok_and(|m| m.is_file()) {
            return Ok(name.to_string());
        }
        return Err(RegistryError::Invalid(format!(
            "the robot's file {name} is not among the uploaded files (at their top)"
        )));
    }
    if dest.join(ROBOT_FILE).is_file() {
        return Ok(ROBOT_FILE.to_string());
    }
    let mut python: Vec<String> = Vec::new();
    let mut robots: Vec<String> = Vec::new();
    let entries = fs::read_dir(dest)
        .map_err(|e| RegistryError::Internal(format!("cannot read the upload's folder: {e}")))?;
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let Ok(meta) = fs::symlink_metadata(entry.path()) else {
            continue;
        };
        if !meta.is_file() || !name.ends_with(".py") || name == ADAPTER_FILE {
            continue;
        }
        python.push(name.clone());
        // Files are at most a few MiB (the bundle's limits): read as text.
        let text = fs::read(entry.path()).unwrap_or_default();
        if defines_robot(&String::from_utf8_lossy(&text)) {
            robots.push(name);
        }
    }
    python.sort();
    robots.sort();
    match robots.as_slice() {
        [one] => Ok(one.clone()),
        [] => {
            // An archive of the folder rather than of its files: say so.
            let nested = fs::read_dir(dest)
                .into_iter()
                .flatten()
                .flatten()
                .find(|e| e.path().join(ROBOT_FILE).is_file())
                .map(|e| e.file_name().to_string_lossy().into_owned());
            Err(RegistryError::Invalid(match nested {
                Some(folder) => format!(
                    "{ROBOT_FILE} is inside the folder {folder:?} of the archive: archive \
                     the files themselves (robot.py at the top), not their folder"
                ),
                None if python.is_empty() => format!(
                    "an original-task robot needs the .py file that defines class Robot at \
                     the top of its files (the upload has {files} files, no .py file among them)"
                ),
                None => format!(
                    "an original-task robot needs the .py file that defines class Robot: none \
                     of {} does (at the start of a line: `class Robot(object):` or `class Robot:`)",
                    python.join(", ")
                ),
            }))
        }
        many => Err(RegistryError::Invalid(format!(
            "several files define class Robot ({}): name the robot's file (robot_file)",
            many.join(", ")
        ))),
    }
}

/// Writes `files` into `dest` (checking every rule of [`crate::botfiles`]); for an
/// original-task robot, the file that holds its `class Robot` too.
fn write_upload(
    files: &BotFiles,
    dest: &Path,
    limits: &BundleLimits,
) -> Result<(BundleSummary, Option<String>)> {
    Ok(match files {
        BotFiles::Map(map) => (botfiles::write_files(map, dest, limits)?, None),
        BotFiles::Archive(bytes) => (botfiles::unpack_archive(bytes, dest, limits)?, None),
        BotFiles::OriginalTask {
            files: inner,
            robot,
        } => {
            let (summary, _) = write_upload(inner, dest, limits)?;
            let robot = robot_file(dest, robot.as_deref(), summary.files)?;
            // The uploaded entry of that name (a file or a link) is replaced, never
            // written through: the new file is created where nothing is.
            let path = dest.join(ADAPTER_FILE);
            if let Ok(meta) = fs::symlink_metadata(&path) {
                if meta.is_dir() {
                    return Err(RegistryError::Invalid(format!(
                        "the upload has a folder named {ADAPTER_FILE}, the adapter's name"
                    )));
                }
                fs::remove_file(&path).map_err(|e| {
                    RegistryError::Internal(format!("cannot replace {ADAPTER_FILE}: {e}"))
                })?;
            }
            use std::io::Write;
            fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&path)
                .and_then(|mut f| f.write_all(ORIGINAL_TASK_ADAPTER.as_bytes()))
                .map_err(|e| RegistryError::Internal(format!("cannot add the adapter: {e}")))?;
            // The summary is the packed folder's, adapter included.
            (summary, Some(robot))
        }
    })
}

/// Checks `files` (every rule of [`crate::botfiles`]), stores them as a bundle and
/// answers what was stored. `scratch` is a local folder for unpacking.
///
/// # Errors
/// [`RegistryError::Bundle`] for refused files; the database; the local disk.
pub async fn store_upload(storage: &Storage, files: BotFiles, scratch: &Path) -> Result<Stored> {
    let scratch = scratch.to_path_buf();
    let (packed, robot) = blocking(move || {
        let (_tmp, dest) = scratch_dir(&scratch)?;
        let limits = BundleLimits::default();
        let (summary, robot) = write_upload(&files, &dest, &limits)?;
        let packed = botfiles::pack_dir(&dest, &limits, &skip_nothing)?;
        if !matches!(files, BotFiles::OriginalTask { .. }) && packed.summary != summary {
            return Err(RegistryError::Internal(format!(
                "the files packed again give {:?}, not {summary:?}",
                packed.summary
            )));
        }
        Ok((packed, robot))
    })
    .await??;
    put(storage, &packed).await?;
    Ok(Stored {
        summary: packed.summary,
        robot,
    })
}

/// Stores the folder `dir` (a bot's folder after its build, or an old data folder) as a
/// bundle: packed, then unpacked again in `scratch` to check it against every rule an
/// upload meets (links that stay inside, the limits) and its hash.
///
/// # Errors
/// [`RegistryError::Bundle`] when the folder cannot be a bundle; the database; the
/// local disk.
pub async fn store_dir(storage: &Storage, dir: &Path, scratch: &Path) -> Result<BundleSummary> {
    let (dir, scratch) = (dir.to_path_buf(), scratch.to_path_buf());
    let packed = blocking(move || {
        let limits = BundleLimits::default();
        let packed = botfiles::pack_dir(&dir, &limits, &skip_nothing)?;
        let (_tmp, dest) = scratch_dir(&scratch)?;
        let back = botfiles::unpack_archive(&packed.archive, &dest, &limits)?;
        if back != packed.summary {
            return Err(RegistryError::Internal(format!(
                "{} packed and unpacked gives {back:?}, not {:?}",
                dir.display(),
                packed.summary
            )));
        }
        Ok(packed)
    })
    .await??;
    put(storage, &packed).await?;
    Ok(packed.summary)
}

/// The stored archive of bundle `sha256`.
///
/// # Errors
/// [`RegistryError::NotFound`] when the database does not hold it; the database.
pub async fn fetch(storage: &Storage, sha256: &str) -> Result<Vec<u8>> {
    storage.get_bundle(sha256).await?.ok_or_else(|| {
        RegistryError::NotFound(format!("the bundle {sha256} is not in the database"))
    })
}

/// Unpacks the stored bundle `sha256` into `dest` (an existing empty folder), checking
/// its hash: for a build, which writes into its folder.
///
/// # Errors
/// A bundle missing from the database or whose files do not give its hash; the local
/// disk.
pub async fn unpack_stored(storage: &Storage, sha256: &str, dest: &Path) -> Result<BundleSummary> {
    let archive = fetch(storage, sha256).await?;
    let (dest, sha) = (dest.to_path_buf(), sha256.to_owned());
    blocking(move || unpack_checked(&archive, &dest, &sha)).await?
}

/// Unpacks a stored bundle's `archive` into `dest` (an existing empty folder) and
/// checks that its files give `sha256`: [`RegistryError::Corrupt`] when they do not or
/// the archive cannot be unpacked (`dest` is then left empty by the unpacker, or
/// holds the refused files for the caller to remove).
pub(super) fn unpack_checked(archive: &[u8], dest: &Path, sha256: &str) -> Result<BundleSummary> {
    let summary =
        botfiles::unpack_archive(archive, dest, &BundleLimits::default()).map_err(|e| {
            match e.is_client_error() {
                true => RegistryError::Corrupt(format!(
                    "the stored bundle {sha256} cannot be unpacked: {e}"
                )),
                false => e.into(),
            }
        })?;
    if summary.sha256 != sha256 {
        return Err(RegistryError::Corrupt(format!(
            "the stored bundle {sha256} holds files whose hash is {}: refused",
            summary.sha256
        )));
    }
    Ok(summary)
}

async fn put(storage: &Storage, packed: &Packed) -> Result<()> {
    storage
        .put_bundle(&NewBundle {
            sha256: &packed.summary.sha256,
            archive: &packed.archive,
            files: packed.summary.files as i64,
            bytes: packed.summary.bytes as i64,
        })
        .await?;
    Ok(())
}

/// A new temporary folder in `scratch` with an empty `bot` folder in it.
fn scratch_dir(scratch: &Path) -> Result<(tempfile::TempDir, PathBuf)> {
    let local = |e: std::io::Error| {
        RegistryError::Internal(format!("cannot unpack in {}: {e}", scratch.display()))
    };
    fs::create_dir_all(scratch).map_err(local)?;
    let tmp = tempfile::Builder::new()
        .prefix(".unpack-")
        .tempdir_in(scratch)
        .map_err(local)?;
    let dest = tmp.path().join("bot");
    fs::create_dir(&dest).map_err(local)?;
    Ok((tmp, dest))
}

pub(super) async fn blocking<T: Send + 'static>(
    f: impl FnOnce() -> T + Send + 'static,
) -> Result<T> {
    tokio::task::spawn_blocking(f)
        .await
        .map_err(|e| RegistryError::Internal(format!("a file task failed: {e}")))
}

#[cfg(test)]
mod tests {
    #[tokio::test]
    async fn an_original_task_upload_gets_the_adapter_and_needs_its_robot_at_the_top() {
        let (db, _d) = crate::storage::test_support::fresh().await;
        let scratch = tempfile::tempdir().unwrap();
        let files = |pairs: &[(&str, &str)]| {
            BotFiles::Map(
                pairs
                    .iter()
                    .map(|(k, v)| (k.to_string(), v.to_string()))
                    .collect(),
            )
        };
        let original = |pairs: &[(&str, &str)], robot: Option<&str>| BotFiles::OriginalTask {
            files: Box::new(files(pairs)),
            robot: robot.map(str::to_string),
        };
        let stored = store_upload(
            &db,
            original(
                &[
                    ("robot.py", "class Robot: pass\n"),
                    ("udacity_adapter.py", "print('not the adapter')\n"),
                ],
                None,
            ),
            scratch.path(),
        )
        .await
        .unwrap();
        assert_eq!(stored.robot.as_deref(), Some("robot.py"));
        let ok = stored.summary;
        assert_eq!(
            ok.files, 2,
            "the robot and the adapter, which replaced the upload's"
        );
        let same = store_upload(
            &db,
            files(&[
                ("robot.py", "class Robot: pass\n"),
                (ADAPTER_FILE, ORIGINAL_TASK_ADAPTER),
            ]),
            scratch.path(),
        )
        .await
        .unwrap();
        assert_eq!(
            ok.sha256, same.summary.sha256,
            "the server's adapter, byte for byte"
        );
        let refused = |pairs: &'static [(&'static str, &'static str)],
                       robot: Option<&'static str>| {
            let (db, scratch) = (&db, scratch.path());
            async move {
                store_upload(db, original(pairs, robot), scratch)
                    .await
                    .unwrap_err()
                    .to_string()
            }
        };
        let nested = refused(&[("mine/robot.py", "x = 1\n")], None).await;
        assert!(nested.contains("inside the folder \"mine\""), "{nested}");
        let none = refused(&[("bot.py", "x = 1\n")], None).await;
        assert!(
            none.contains("defines class Robot") && none.contains("bot.py"),
            "{none}"
        );
        let no_python = refused(&[("notes.txt", "x\n")], None).await;
        assert!(no_python.contains("no .py file"), "{no_python}");
        // Another name: the only file that defines class Robot, which may import its
        // helpers; or the one its author names.
        let found = store_upload(
            &db,
            original(
                &[
                    (
                        "robot_final.py",
                        "from astar_final import plan\n\nclass Robot(object):\n    pass\n",
                    ),
                    ("astar_final.py", "def plan():\n    return []\n"),
                ],
                None,
            ),
            scratch.path(),
        )
        .await
        .unwrap();
        assert_eq!(found.robot.as_deref(), Some("robot_final.py"));
        let two = &[
            ("a.py", "class Robot:\n    pass\n"),
            ("b.py", "class Robot (object):\n    pass\n"),
        ];
        let many = refused(two, None).await;
        assert!(
            many.contains("several files define class Robot (a.py, b.py)"),
            "{many}"
        );
        let named = store_upload(&db, original(two, Some("b.py")), scratch.path())
            .await
            .unwrap();
        assert_eq!(named.robot.as_deref(), Some("b.py"));
        let missing = refused(two, Some("c.py")).await;
        assert!(
            missing.contains("c.py is not among the uploaded files"),
            "{missing}"
        );
        for bad in ["../a.py", "a.txt", "sub/a.py", "-a.py"] {
            let e = store_upload(&db, original(two, Some(bad)), scratch.path())
                .await
                .unwrap_err()
                .to_string();
            assert!(e.contains("is not a .py file at the top"), "{bad}: {e}");
        }
    }

    #[test]
    fn a_robot_class_is_found_by_its_line_not_its_mention() {
        assert!(defines_robot("import x\nclass Robot(object):\n"));
        assert!(defines_robot("class Robot:\n"));
        assert!(!defines_robot("class RobotHelper(object):\n"));
        assert!(!defines_robot("# class Robot is in robot.py\n"));
        assert!(!defines_robot("    class Robot:\n"));
    }

    use super::*;
    use crate::storage::test_support;

    #[tokio::test]
    async fn an_upload_is_stored_once_under_its_content_hash_whatever_its_form() {
        let (db, _d) = test_support::fresh().await;
        let scratch = tempfile::tempdir().unwrap();
        let map: BTreeMap<String, String> = [("bot.py", "print(1)\n"), ("lib/x.py", "X = 2\n")]
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        let from_map = store_upload(&db, BotFiles::Map(map), scratch.path())
            .await
            .unwrap()
            .summary;
        // The same files as a .tar.gz (packed from a folder) give the same hash.
        let folder = tempfile::tempdir().unwrap();
        fs::create_dir(folder.path().join("lib")).unwrap();
        fs::write(folder.path().join("bot.py"), "print(1)\n").unwrap();
        fs::write(folder.path().join("lib/x.py"), "X = 2\n").unwrap();
        let tgz = botfiles::pack_dir(folder.path(), &BundleLimits::default(), &skip_nothing)
            .unwrap()
            .archive;
        let from_tgz = store_upload(&db, BotFiles::Archive(tgz), scratch.path())
            .await
            .unwrap()
            .summary;
        assert_eq!(from_map, from_tgz);
        assert_eq!((from_map.files, from_map.bytes), (2, 15));
        assert_eq!(db.bundle_totals().await.unwrap().0, 1);
        let from_dir = store_dir(&db, folder.path(), scratch.path()).await.unwrap();
        assert_eq!(from_dir, from_map);

        // Stored, it unpacks to the same files.
        let out = tempfile::tempdir().unwrap();
        let back = unpack_stored(&db, &from_map.sha256, out.path())
            .await
            .unwrap();
        assert_eq!(back, from_map);
        assert_eq!(
            fs::read_to_string(out.path().join("lib/x.py")).unwrap(),
            "X = 2\n"
        );

        // Refused files store nothing and leave nothing in the scratch folder.
        let err = store_upload(&db, BotFiles::Archive(b"junk".to_vec()), scratch.path())
            .await
            .unwrap_err();
        assert!(err.is_client_error(), "{err}");
        assert_eq!(fs::read_dir(scratch.path()).unwrap().count(), 0);
        assert_eq!(db.bundle_totals().await.unwrap().0, 1);

        // A folder with a link out of it cannot be a bundle.
        std::os::unix::fs::symlink("/etc/passwd", folder.path().join("out")).unwrap();
        let err = store_dir(&db, folder.path(), scratch.path())
            .await
            .unwrap_err();
        assert!(matches!(err, RegistryError::Bundle(_)), "{err}");
    }
}
