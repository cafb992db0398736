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
    /// The files (a map or an archive) of a `robot.py` written for the original task, to
    /// which the server adds its adapter ([`ORIGINAL_TASK_ADAPTER`], as
    /// [`ADAPTER_FILE`]) so that its author uploads only their own files.
    OriginalTask(Box<BotFiles>),
}

/// The adapter that runs an unchanged original-task `robot.py` as a protocol-v1 bot.
pub const ORIGINAL_TASK_ADAPTER: &str = include_str!("../../bots/python/udacity_adapter.py");

/// The adapter's file name in a bot's folder.
pub const ADAPTER_FILE: &str = "udacity_adapter.py";

/// The robot file an original-task upload must hold.
pub const ROBOT_FILE: &str = "robot.py";

/// Writes `files` into `dest` (checking every rule of [`crate::botfiles`]).
fn write_upload(files: &BotFiles, dest: &Path, limits: &BundleLimits) -> Result<BundleSummary> {
    Ok(match files {
        BotFiles::Map(map) => botfiles::write_files(map, dest, limits)?,
        BotFiles::Archive(bytes) => botfiles::unpack_archive(bytes, dest, limits)?,
        BotFiles::OriginalTask(inner) => {
            let summary = write_upload(inner, dest, limits)?;
            if !dest.join(ROBOT_FILE).is_file() {
                // An archive of the folder rather than of its files: say so.
                let nested = fs::read_dir(dest)
                    .into_iter()
                    .flatten()
                    .flatten()
                    .find(|e| e.path().join(ROBOT_FILE).is_file())
                    .map(|e| e.file_name().to_string_lossy().into_owned());
                return Err(RegistryError::Invalid(match nested {
                    Some(folder) => format!(
                        "{ROBOT_FILE} is inside the folder {folder:?} of the archive: archive \
                         the files themselves (robot.py at the top), not their folder"
                    ),
                    None => format!(
                        "an original-task robot needs a file named {ROBOT_FILE} at the top of \
                         its files (the upload has {} files, none of them {ROBOT_FILE})",
                        summary.files
                    ),
                }));
            }
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
            return Ok(summary);
        }
    })
}

/// Checks `files` (every rule of [`crate::botfiles`]), stores them as a bundle and
/// answers what was stored. `scratch` is a local folder for unpacking.
///
/// # Errors
/// [`RegistryError::Bundle`] for refused files; the database; the local disk.
pub async fn store_upload(
    storage: &Storage,
    files: BotFiles,
    scratch: &Path,
) -> Result<BundleSummary> {
    let scratch = scratch.to_path_buf();
    let packed = blocking(move || {
        let (_tmp, dest) = scratch_dir(&scratch)?;
        let limits = BundleLimits::default();
        let summary = write_upload(&files, &dest, &limits)?;
        let packed = botfiles::pack_dir(&dest, &limits, &skip_nothing)?;
        if !matches!(files, BotFiles::OriginalTask(_)) && packed.summary != summary {
            return Err(RegistryError::Internal(format!(
                "the files packed again give {:?}, not {summary:?}",
                packed.summary
            )));
        }
        Ok(packed)
    })
    .await??;
    put(storage, &packed).await?;
    Ok(packed.summary)
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
        let ok = store_upload(
            &db,
            BotFiles::OriginalTask(Box::new(files(&[
                ("robot.py", "class Robot: pass\n"),
                ("udacity_adapter.py", "print('not the adapter')\n"),
            ]))),
            scratch.path(),
        )
        .await
        .unwrap();
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
            ok.sha256, same.sha256,
            "the server's adapter, byte for byte"
        );
        let nested = store_upload(
            &db,
            BotFiles::OriginalTask(Box::new(files(&[("mine/robot.py", "x = 1\n")]))),
            scratch.path(),
        )
        .await
        .unwrap_err()
        .to_string();
        assert!(nested.contains("inside the folder \"mine\""), "{nested}");
        let none = store_upload(
            &db,
            BotFiles::OriginalTask(Box::new(files(&[("bot.py", "x = 1\n")]))),
            scratch.path(),
        )
        .await
        .unwrap_err()
        .to_string();
        assert!(none.contains("needs a file named robot.py"), "{none}");
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
            .unwrap();
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
            .unwrap();
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
