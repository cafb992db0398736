//! Moving an older data folder into the database: before bundles were stored in the
//! database, an uploaded version's files lived in `DATA_DIR/bots/<random>/` and its
//! build ran in that folder. [`migrate_data_folder`] stores each such folder as a
//! bundle and points its version at it, so that workers on any machine can play it.
//! It is run when a server starts; a version moved once is never looked at again.

use std::path::{Path, PathBuf};

use super::Result;
use super::bundles::store_dir;
use crate::storage::Storage;
use crate::storage::bots::BotVersionRow;

/// What [`migrate_data_folder`] did.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Migration {
    /// Versions whose folder now is a bundle.
    pub moved: Vec<i64>,
    /// Versions left as they were, with why (their folder is missing or cannot be a
    /// bundle).
    pub left: Vec<(i64, String)>,
}

/// Stores the folders of the versions uploaded into `data_dir` as bundles.
///
/// A folder whose files still give the version's `files_sha256` becomes the version's
/// bundle (a version still waiting for its build is then built by a worker). A folder
/// that changed since its upload (a version built in its folder) becomes the version's
/// built bundle: it plays as it did. The old folders are not removed.
///
/// # Errors
/// The database. A folder that cannot be moved is reported in [`Migration::left`].
pub async fn migrate_data_folder(storage: &Storage, data_dir: &Path) -> Result<Migration> {
    let uploads = data_dir.join("bots");
    let uploads_real = std::fs::canonicalize(&uploads).ok();
    let scratch = data_dir.join("tmp");
    let mut done = Migration::default();
    for v in storage.versions_without_bundle().await? {
        let dir = PathBuf::from(&v.dir);
        let inside = dir.starts_with(&uploads)
            || uploads_real
                .as_ref()
                .is_some_and(|real| std::fs::canonicalize(&dir).is_ok_and(|d| d.starts_with(real)));
        if v.dir.is_empty() || !inside {
            continue; // a local folder of `mazearena tournament`: it stays where it is
        }
        match migrate_version(storage, &v, &dir, &scratch).await {
            Ok(()) => done.moved.push(v.bot_version_id),
            Err(why) => {
                tracing::warn!(bot_version_id = v.bot_version_id, dir = %v.dir, %why,
                    "could not move a bot version's folder into the database");
                done.left.push((v.bot_version_id, why));
            }
        }
    }
    if !done.moved.is_empty() {
        tracing::info!(
            versions = done.moved.len(),
            folder = %uploads.display(),
            "moved bot versions' files into the database; their old folders can be removed"
        );
    }
    Ok(done)
}

async fn migrate_version(
    storage: &Storage,
    v: &BotVersionRow,
    dir: &Path,
    scratch: &Path,
) -> std::result::Result<(), String> {
    if !dir.is_dir() {
        return Err(format!("its folder {} is missing", dir.display()));
    }
    let stored = store_dir(storage, dir, scratch)
        .await
        .map_err(|e| e.to_string())?;
    let (bundle, built) = if stored.sha256 == v.files_sha256 {
        (Some(stored.sha256.as_str()), None)
    } else {
        (None, Some(stored.sha256.as_str()))
    };
    storage
        .set_version_bundles(v.bot_version_id, bundle, built)
        .await
        .map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::botfiles::{BundleLimits, write_files};
    use crate::registry::cache::BundleCache;
    use crate::storage::bots::{NewVersion, build_status};
    use crate::storage::test_support;
    use std::collections::BTreeMap;
    use std::fs;

    /// A version stored the way servers stored uploads before bundles: files in
    /// `DATA/bots/<name>`, `dir` pointing there.
    async fn old_upload(
        db: &Storage,
        data: &Path,
        name: &str,
        build: Option<&str>,
    ) -> (BotVersionRow, PathBuf) {
        let dir = data.join("bots").join(name);
        fs::create_dir_all(&dir).unwrap();
        let files: BTreeMap<String, String> = [("bot.py", format!("print({name:?})\n"))]
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect();
        let summary = write_files(&files, &dir, &BundleLimits::default()).unwrap();
        let v = db
            .create_bot(
                name,
                "h",
                &NewVersion {
                    command: "python3 bot.py",
                    dir: &dir.display().to_string(),
                    files_sha256: &summary.sha256,
                    file_count: 1,
                    build_command: build,
                    ..test_support::plain_version()
                },
            )
            .await
            .unwrap();
        (v, dir)
    }

    #[tokio::test]
    async fn an_old_data_folder_moves_into_the_database() {
        for (db, _guard) in test_support::backends().await {
            let data = tempfile::tempdir().unwrap();
            let (plain, _) = old_upload(&db, data.path(), "plain", None).await;
            let (built, built_dir) = old_upload(&db, data.path(), "built", Some("make")).await;
            // Built in its folder, as servers did: the folder changed.
            fs::write(built_dir.join("bot"), "#!/bin/sh\n").unwrap();
            db.claim_build("old-server", 60_000).await.unwrap().unwrap();
            db.finish_build(
                built.bot_version_id,
                "old-server",
                build_status::READY,
                None,
                "ok",
                0,
            )
            .await
            .unwrap();
            let (waiting, _) = old_upload(&db, data.path(), "waiting", Some("make")).await;
            let (gone, gone_dir) = old_upload(&db, data.path(), "gone", None).await;
            fs::remove_dir_all(gone_dir).unwrap();
            // A local folder of `mazearena tournament` is not touched.
            let local = tempfile::tempdir().unwrap();
            fs::write(local.path().join("bot.py"), "x").unwrap();
            let local_v = db
                .create_bot(
                    "local",
                    "h",
                    &NewVersion {
                        command: "python3 bot.py",
                        dir: &local.path().display().to_string(),
                        files_sha256: "x",
                        file_count: 0,
                        build_command: None,
                        ..test_support::plain_version()
                    },
                )
                .await
                .unwrap();

            let m = migrate_data_folder(&db, data.path()).await.unwrap();
            assert_eq!(
                m.moved,
                vec![
                    plain.bot_version_id,
                    built.bot_version_id,
                    waiting.bot_version_id
                ]
            );
            assert_eq!(m.left.len(), 1);
            assert_eq!(m.left[0].0, gone.bot_version_id);
            assert!(m.left[0].1.contains("missing"), "{:?}", m.left);

            let get = |id| db.get_bot_version(id);
            let plain = get(plain.bot_version_id).await.unwrap().unwrap();
            assert_eq!(
                plain.bundle_sha256.as_deref(),
                Some(plain.files_sha256.as_str())
            );
            assert_eq!((plain.built_sha256, plain.dir.as_str()), (None, ""));
            let built = get(built.bot_version_id).await.unwrap().unwrap();
            assert_eq!(built.bundle_sha256, None);
            let built_sha = built.built_sha256.clone().unwrap();
            assert_ne!(built_sha, built.files_sha256);
            assert_eq!(built.build_status, build_status::READY);
            let waiting = get(waiting.bot_version_id).await.unwrap().unwrap();
            assert_eq!(
                waiting.bundle_sha256.as_deref(),
                Some(waiting.files_sha256.as_str())
            );
            assert_eq!(waiting.build_status, build_status::BUILDING);
            let local_v = get(local_v.bot_version_id).await.unwrap().unwrap();
            assert_eq!(local_v.dir, local.path().display().to_string());

            // The moved files play from any worker's cache, without the old folder.
            fs::remove_dir_all(data.path().join("bots")).unwrap();
            let cache_dir = tempfile::tempdir().unwrap();
            let cache = BundleCache::new(cache_dir.path(), 1 << 20).unwrap();
            let got = cache.get(&db, &built_sha).await.unwrap();
            assert_eq!(
                fs::read_to_string(got.dir.join("bot")).unwrap(),
                "#!/bin/sh\n"
            );
            assert_eq!(
                fs::read_to_string(got.dir.join("bot.py")).unwrap(),
                "print(\"built\")\n"
            );

            // Run again: nothing left to move.
            let again = migrate_data_folder(&db, data.path()).await.unwrap();
            assert!(again.moved.is_empty());
        }
    }
}
