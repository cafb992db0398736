//! Organisers: their keys and names, and which competitions they organise.

use crate::storage::{Result, Storage, StorageError, is_unique_violation, now_ms};

impl Storage {
    /// Registers an organiser whose key has SHA-256 `key_hash`.
    ///
    /// # Errors
    /// [`StorageError::Conflict`] when the name is taken; database failures.
    pub async fn create_organiser(&self, name: &str, key_hash: &str) -> Result<i64> {
        let _turn = self.write_turn().await;
        sqlx::query_scalar(
            "insert into organiser (name, key_hash, created_at) values ($1, $2, $3) returning organiser_id",
        )
        .bind(name)
        .bind(key_hash)
        .bind(now_ms())
        .fetch_one(self.pool())
        .await
        .map_err(|e| {
            if is_unique_violation(&e) {
                StorageError::Conflict(format!("an organiser named {name:?} exists already (names that differ only in case are one name)"))
            } else {
                e.into()
            }
        })
    }

    /// The organiser whose key has SHA-256 `key_hash`.
    ///
    /// # Errors
    /// Database failures.
    pub async fn organiser_by_key(&self, key_hash: &str) -> Result<Option<i64>> {
        Ok(
            sqlx::query_scalar("select organiser_id from organiser where key_hash = $1")
                .bind(key_hash)
                .fetch_optional(self.pool())
                .await?,
        )
    }

    /// Replaces organiser `organiser_id`'s key (SHA-256 `key_hash`): the old key and
    /// every browser session opened with it stop working at once. Returns false if there
    /// is no such organiser.
    ///
    /// # Errors
    /// Database failures.
    pub async fn rotate_organiser_key(&self, organiser_id: i64, key_hash: &str) -> Result<bool> {
        let _turn = self.write_turn().await;
        let mut tx = self.begin_write().await?;
        sqlx::query(
            "delete from web_session where key_hash in (
                 select key_hash from organiser where organiser_id = $1)",
        )
        .bind(organiser_id)
        .execute(&mut *tx)
        .await?;
        let changed = sqlx::query("update organiser set key_hash = $1 where organiser_id = $2")
            .bind(key_hash)
            .bind(organiser_id)
            .execute(&mut *tx)
            .await?
            .rows_affected();
        tx.commit().await?;
        Ok(changed > 0)
    }

    /// Every organiser: id, name and when it was registered (unix ms), oldest first.
    ///
    /// # Errors
    /// Database failures.
    pub async fn list_organisers(&self) -> Result<Vec<(i64, String, i64)>> {
        Ok(sqlx::query_as(
            "select organiser_id, name, created_at from organiser order by organiser_id",
        )
        .fetch_all(self.pool())
        .await?)
    }

    /// The name of organiser `organiser_id`.
    ///
    /// # Errors
    /// Database failures.
    pub async fn organiser_name(&self, organiser_id: i64) -> Result<Option<String>> {
        Ok(
            sqlx::query_scalar("select name from organiser where organiser_id = $1")
                .bind(organiser_id)
                .fetch_optional(self.pool())
                .await?,
        )
    }

    /// The organiser named `name`.
    ///
    /// # Errors
    /// Database failures.
    pub async fn organiser_by_name(&self, name: &str) -> Result<Option<i64>> {
        Ok(
            sqlx::query_scalar("select organiser_id from organiser where name = $1")
                .bind(name)
                .fetch_optional(self.pool())
                .await?,
        )
    }

    /// Hands competition `competition_id` to organiser `organiser_id` (`None`: the
    /// admin's).
    ///
    /// # Errors
    /// Database failures.
    pub async fn set_competition_organiser(
        &self,
        competition_id: i64,
        organiser_id: Option<i64>,
    ) -> Result<()> {
        let _turn = self.write_turn().await;
        sqlx::query("update competition set organiser_id = $2 where competition_id = $1")
            .bind(competition_id)
            .bind(organiser_id)
            .execute(self.pool())
            .await?;
        Ok(())
    }

    /// Whether `key_hash` is an organiser's key's hash.
    ///
    /// # Errors
    /// Database failures.
    pub async fn is_organiser(&self, key_hash: &str) -> Result<bool> {
        let n: i64 = sqlx::query_scalar("select count(*) from organiser where key_hash = $1")
            .bind(key_hash)
            .fetch_one(self.pool())
            .await?;
        Ok(n > 0)
    }
}
