//! A worker's local cache of unpacked bundles: `ROOT/SHA256/` holds the files of the
//! bundle with that content hash, fetched from the database the first time a match
//! needs them and checked against the hash as they are unpacked (a bundle whose files
//! do not give its hash is refused, and nothing of it stays).
//!
//! Beside each entry, `SHA256.ready` (its size in bytes; its modification time is its
//! last use) says the entry is complete, and `SHA256.lock` is locked shared while a
//! match plays from the entry and exclusively while it is filled or evicted, so that
//! several match workers and several processes on one machine can share one cache.
//! When the entries pass the cache's size, the least recently used ones that nobody is
//! playing from are removed.

use std::fs::{self, File, OpenOptions};
use std::io;
use std::path::{Path, PathBuf};
use std::time::SystemTime;

use nix::fcntl::{Flock, FlockArg};

use super::bundles::blocking;
use super::{RegistryError, Result};
use crate::storage::Storage;

/// Default size of a cache: 2 GiB of unpacked files.
pub const DEFAULT_CACHE_BYTES: u64 = 2 << 30;

/// A local cache of unpacked bundles.
#[derive(Debug, Clone)]
pub struct BundleCache {
    root: PathBuf,
    max_bytes: u64,
}

/// An entry in use: its files stay until this is dropped.
#[derive(Debug)]
pub struct CachedBundle {
    /// The folder holding the bundle's files.
    pub dir: PathBuf,
    _in_use: Flock<File>,
}

impl BundleCache {
    /// A cache in `root` (created if missing) holding at most `max_bytes` of files
    /// beyond the entries in use.
    ///
    /// # Errors
    /// When `root` cannot be created.
    pub fn new(root: &Path, max_bytes: u64) -> Result<BundleCache> {
        fs::create_dir_all(root).map_err(|e| {
            RegistryError::Internal(format!("cannot create the cache {}: {e}", root.display()))
        })?;
        Ok(BundleCache {
            root: root.to_path_buf(),
            max_bytes,
        })
    }

    /// The folder of the bundle `sha256`, fetched from `storage` and unpacked first if
    /// it is not in the cache.
    ///
    /// # Errors
    /// A malformed hash, a bundle missing from the database, a bundle whose files do
    /// not give its hash, the database, the local disk.
    pub async fn get(&self, storage: &Storage, sha256: &str) -> Result<CachedBundle> {
        if sha256.len() != 64 || !sha256.bytes().all(|b| b.is_ascii_hexdigit()) {
            return Err(RegistryError::Invalid(format!(
                "{sha256:?} is not a bundle hash"
            )));
        }
        let sha = sha256.to_ascii_lowercase();
        loop {
            let cache = self.clone();
            let key = sha.clone();
            if let Some(found) = blocking(move || cache.use_ready(&key)).await?? {
                return Ok(found);
            }
            let cache = self.clone();
            let key = sha.clone();
            let filling = blocking(move || cache.lock(&key, FlockArg::LockExclusive)).await??;
            if !self.is_ready(&sha) {
                let archive = super::bundles::fetch(storage, &sha).await?;
                let cache = self.clone();
                let key = sha.clone();
                blocking(move || cache.fill(&key, &archive)).await??;
            }
            drop(filling);
        }
    }

    /// The entry, locked shared and marked used, if it is complete.
    fn use_ready(&self, sha: &str) -> Result<Option<CachedBundle>> {
        let lock = self.lock(sha, FlockArg::LockShared)?;
        if !self.is_ready(sha) {
            return Ok(None);
        }
        if let Ok(marker) = OpenOptions::new().write(true).open(self.ready_path(sha)) {
            let _ = marker.set_modified(SystemTime::now());
        }
        Ok(Some(CachedBundle {
            dir: self.root.join(sha),
            _in_use: lock,
        }))
    }

    /// Unpacks `archive` as entry `sha` (under its exclusive lock), checks its hash,
    /// marks it complete and evicts what no longer fits.
    fn fill(&self, sha: &str, archive: &[u8]) -> Result<()> {
        let dir = self.root.join(sha);
        let local = |what: &str, e: io::Error| {
            RegistryError::Internal(format!("cannot {what} {}: {e}", dir.display()))
        };
        if dir.exists() {
            fs::remove_dir_all(&dir).map_err(|e| local("clear", e))?;
        }
        fs::create_dir(&dir).map_err(|e| local("create", e))?;
        let summary = match super::bundles::unpack_checked(archive, &dir, sha) {
            Ok(s) => s,
            Err(e) => {
                let _ = fs::remove_dir_all(&dir);
                return Err(e);
            }
        };
        fs::write(self.ready_path(sha), summary.bytes.to_string())
            .map_err(|e| local("mark complete", e))?;
        self.evict(sha);
        Ok(())
    }

    /// Removes the least recently used complete entries, other than `keep` and those in
    /// use, until the cache holds at most its size.
    fn evict(&self, keep: &str) {
        let Ok(listing) = fs::read_dir(&self.root) else {
            return;
        };
        let mut entries: Vec<(SystemTime, u64, String)> = listing
            .flatten()
            .filter_map(|e| {
                let name = e.file_name().into_string().ok()?;
                let sha = name.strip_suffix(".ready")?.to_owned();
                let meta = e.metadata().ok()?;
                let size = fs::read_to_string(e.path()).ok()?.trim().parse().ok()?;
                Some((meta.modified().ok()?, size, sha))
            })
            .collect();
        let mut total: u64 = entries.iter().map(|e| e.1).sum();
        entries.sort();
        for (_, size, sha) in entries {
            if total <= self.max_bytes {
                break;
            }
            if sha == keep {
                continue;
            }
            let Ok(lock) = self.lock(&sha, FlockArg::LockExclusiveNonblock) else {
                continue; // in use
            };
            if fs::remove_file(self.ready_path(&sha)).is_ok() {
                let _ = fs::remove_dir_all(self.root.join(&sha));
                total = total.saturating_sub(size);
                tracing::info!(bundle = %sha, bytes = size, "evicted from the bundle cache");
            }
            drop(lock);
        }
    }

    fn is_ready(&self, sha: &str) -> bool {
        self.ready_path(sha).is_file() && self.root.join(sha).is_dir()
    }

    fn ready_path(&self, sha: &str) -> PathBuf {
        self.root.join(format!("{sha}.ready"))
    }

    fn lock(&self, sha: &str, how: FlockArg) -> Result<Flock<File>> {
        let path = self.root.join(format!("{sha}.lock"));
        let file = OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&path)
            .map_err(|e| RegistryError::Internal(format!("cannot open {}: {e}", path.display())))?;
        Flock::lock(file, how).map_err(|(_, errno)| {
            RegistryError::Internal(format!("cannot lock {}: {errno}", path.display()))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::botfiles::{BundleLimits, pack_dir, skip_nothing};
    use crate::storage::bundles::NewBundle;
    use crate::storage::test_support;

    /// A bundle of one file holding `content`, stored in `db`; its hash.
    async fn stored(db: &Storage, content: &str) -> String {
        let d = tempfile::tempdir().unwrap();
        fs::write(d.path().join("bot.py"), content).unwrap();
        let packed = pack_dir(d.path(), &BundleLimits::default(), &skip_nothing).unwrap();
        db.put_bundle(&NewBundle {
            sha256: &packed.summary.sha256,
            archive: &packed.archive,
            files: 1,
            bytes: content.len() as i64,
        })
        .await
        .unwrap();
        packed.summary.sha256
    }

    #[tokio::test]
    async fn bundles_are_fetched_once_verified_and_evicted_by_size() {
        let (db, _d) = test_support::fresh().await;
        let root = tempfile::tempdir().unwrap();
        let cache = BundleCache::new(root.path(), 250).unwrap();
        let a = stored(&db, &"a".repeat(100)).await;
        let b = stored(&db, &"b".repeat(100)).await;
        let c = stored(&db, &"c".repeat(100)).await;

        let got = cache.get(&db, &a).await.unwrap();
        assert_eq!(
            fs::read_to_string(got.dir.join("bot.py")).unwrap(),
            "a".repeat(100)
        );
        // A second use does not fetch it again: it still answers with the database gone.
        drop(got);
        let (empty, _e) = test_support::fresh().await;
        assert!(cache.get(&empty, &a).await.is_ok());

        // b fits beside a; c does not: a (least recently used, not in use) goes.
        let b_in_use = cache.get(&db, &b).await.unwrap();
        std::thread::sleep(std::time::Duration::from_millis(20));
        let _c = cache.get(&db, &c).await.unwrap();
        assert!(!root.path().join(&a).exists());
        assert!(b_in_use.dir.join("bot.py").is_file());
        // An entry in use is never evicted, even when the cache is over its size.
        let _a = cache.get(&db, &a).await.unwrap();
        assert!(b_in_use.dir.join("bot.py").is_file());

        // Unknown and malformed hashes.
        let err = cache.get(&db, &"0".repeat(64)).await.unwrap_err();
        assert!(matches!(err, RegistryError::NotFound(_)), "{err}");
        let err = cache.get(&db, "../../etc").await.unwrap_err();
        assert!(matches!(err, RegistryError::Invalid(_)), "{err}");
    }

    #[tokio::test]
    async fn a_bundle_whose_files_do_not_give_its_hash_is_refused() {
        let (db, _d) = test_support::fresh().await;
        let real = stored(&db, "print(1)\n").await;
        let archive = db.get_bundle(&real).await.unwrap().unwrap();
        let forged = "f".repeat(64);
        db.put_bundle(&NewBundle {
            sha256: &forged,
            archive: &archive,
            files: 1,
            bytes: 9,
        })
        .await
        .unwrap();
        let root = tempfile::tempdir().unwrap();
        let cache = BundleCache::new(root.path(), DEFAULT_CACHE_BYTES).unwrap();
        let err = cache.get(&db, &forged).await.unwrap_err();
        assert!(matches!(err, RegistryError::Corrupt(_)), "{err}");
        assert!(
            err.is_permanent() && err.to_string().contains("refused"),
            "{err}"
        );
        assert!(!root.path().join(&forged).exists());
        assert!(!root.path().join(format!("{forged}.ready")).exists());
    }
}
