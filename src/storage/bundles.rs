//! Bot files in the database: bundles stored once by their content hash (the canonical
//! `.tar.gz` of `botfiles::pack_dir`), so that any worker on any machine can fetch the
//! files of the version it plays.

use super::bots::BotVersionRow;
use super::{Result, Storage, now_ms};

/// A bundle to store.
#[derive(Debug, Clone, Copy)]
pub struct NewBundle<'a> {
    /// Its content hash.
    pub sha256: &'a str,
    /// The canonical `.tar.gz`.
    pub archive: &'a [u8],
    /// Regular files it holds.
    pub files: i64,
    /// Bytes of content, unpacked.
    pub bytes: i64,
}

impl Storage {
    /// Stores a bundle; one stored already under the same hash is kept as it is.
    ///
    /// # Errors
    /// Database failures.
    pub async fn put_bundle(&self, bundle: &NewBundle<'_>) -> Result<()> {
        sqlx::query(
            "insert into bundle (sha256, archive, files, bytes, created_at)
             values ($1, $2, $3, $4, $5) on conflict (sha256) do nothing",
        )
        .bind(bundle.sha256)
        .bind(bundle.archive)
        .bind(bundle.files)
        .bind(bundle.bytes)
        .bind(now_ms())
        .execute(self.pool())
        .await?;
        Ok(())
    }

    /// The archive of a stored bundle.
    ///
    /// # Errors
    /// Database failures.
    pub async fn get_bundle(&self, sha256: &str) -> Result<Option<Vec<u8>>> {
        Ok(
            sqlx::query_scalar("select archive from bundle where sha256 = $1")
                .bind(sha256)
                .fetch_optional(self.pool())
                .await?,
        )
    }

    /// The number of stored bundles and their archives' total size in bytes.
    ///
    /// # Errors
    /// Database failures.
    pub async fn bundle_totals(&self) -> Result<(i64, i64)> {
        Ok(sqlx::query_as(
            "select cast(count(*) as bigint), cast(coalesce(sum(length(archive)), 0) as bigint)
             from bundle",
        )
        .fetch_one(self.pool())
        .await?)
    }

    /// Versions that play from a folder rather than a stored bundle, oldest first.
    ///
    /// # Errors
    /// Database failures.
    pub async fn versions_without_bundle(&self) -> Result<Vec<BotVersionRow>> {
        Ok(sqlx::query_as(
            "select * from bot_version where bundle_sha256 is null and built_sha256 is null
             order by bot_version_id",
        )
        .fetch_all(self.pool())
        .await?)
    }

    /// Points a version at its stored bundles (moving it off its folder): `bundle` its
    /// files as uploaded, `built` its folder after its build.
    ///
    /// # Errors
    /// Database failures.
    pub async fn set_version_bundles(
        &self,
        bot_version_id: i64,
        bundle: Option<&str>,
        built: Option<&str>,
    ) -> Result<()> {
        sqlx::query(
            "update bot_version set bundle_sha256 = $1, built_sha256 = $2, dir = ''
             where bot_version_id = $3",
        )
        .bind(bundle)
        .bind(built)
        .bind(bot_version_id)
        .execute(self.pool())
        .await?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::storage::test_support::backends;

    #[tokio::test]
    async fn bundles_are_stored_once_by_hash() {
        for (db, _guard) in backends().await {
            let archive = [0u8, 1, 2, 255, 0, 7];
            let new = NewBundle {
                sha256: "ab12",
                archive: &archive,
                files: 2,
                bytes: 10,
            };
            db.put_bundle(&new).await.unwrap();
            db.put_bundle(&NewBundle {
                archive: b"other",
                ..new
            })
            .await
            .unwrap();
            assert_eq!(db.get_bundle("ab12").await.unwrap().unwrap(), archive);
            assert!(db.get_bundle("cd34").await.unwrap().is_none());
            assert_eq!(db.bundle_totals().await.unwrap(), (1, 6));
        }
    }
}
