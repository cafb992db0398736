//! Browser sessions: a session is the SHA-256 of the secret in its cookie, the hash of
//! the key that opened it, and when it ends.

use super::{Result, Storage, now_ms};

impl Storage {
    /// Opens a session whose cookie secret has SHA-256 `session_hash`, for the key with
    /// SHA-256 `key_hash`, ending at `expires_at` (unix ms). Ended sessions are swept
    /// on the way.
    ///
    /// # Errors
    /// Database failures.
    pub async fn create_session(
        &self,
        session_hash: &str,
        key_hash: &str,
        expires_at: i64,
    ) -> Result<()> {
        let _turn = self.write_turn().await;
        let now = now_ms();
        let mut tx = self.begin_write().await?;
        sqlx::query("delete from web_session where expires_at <= $1")
            .bind(now)
            .execute(&mut *tx)
            .await?;
        sqlx::query(
            "insert into web_session (session_hash, key_hash, created_at, expires_at)
             values ($1, $2, $3, $4)",
        )
        .bind(session_hash)
        .bind(key_hash)
        .bind(now)
        .bind(expires_at)
        .execute(&mut *tx)
        .await?;
        tx.commit().await?;
        Ok(())
    }

    /// The key hash of the live session `session_hash` (`None`: no such session, or it
    /// has ended).
    ///
    /// # Errors
    /// Database failures.
    pub async fn session_key(&self, session_hash: &str) -> Result<Option<String>> {
        Ok(sqlx::query_scalar(
            "select key_hash from web_session where session_hash = $1 and expires_at > $2",
        )
        .bind(session_hash)
        .bind(now_ms())
        .fetch_optional(self.pool())
        .await?)
    }

    /// Ends session `session_hash` (no error if there is none).
    ///
    /// # Errors
    /// Database failures.
    pub async fn end_session(&self, session_hash: &str) -> Result<()> {
        let _turn = self.write_turn().await;
        sqlx::query("delete from web_session where session_hash = $1")
            .bind(session_hash)
            .execute(self.pool())
            .await?;
        Ok(())
    }

    /// Ends every session opened with the key whose SHA-256 is `key_hash`; answers how
    /// many ended.
    ///
    /// # Errors
    /// Database failures.
    pub async fn end_sessions_of_key(&self, key_hash: &str) -> Result<u64> {
        let _turn = self.write_turn().await;
        Ok(sqlx::query("delete from web_session where key_hash = $1")
            .bind(key_hash)
            .execute(self.pool())
            .await?
            .rows_affected())
    }

    /// How many live sessions the key with SHA-256 `key_hash` has.
    ///
    /// # Errors
    /// Database failures.
    pub async fn sessions_of_key(&self, key_hash: &str) -> Result<i64> {
        Ok(sqlx::query_scalar(
            "select count(*) from web_session where key_hash = $1 and expires_at > $2",
        )
        .bind(key_hash)
        .bind(now_ms())
        .fetch_one(self.pool())
        .await?)
    }
}

#[cfg(test)]
mod tests {
    use crate::storage::test_support::backends;

    #[tokio::test]
    async fn a_session_lives_until_it_ends_or_its_key_is_rotated() {
        for (s, _dir) in backends().await {
            let far = crate::storage::now_ms() + 60_000;
            s.create_session("s1", "k1", far).await.unwrap();
            s.create_session("s2", "k1", far).await.unwrap();
            s.create_session("s3", "k2", far).await.unwrap();
            s.create_session("old", "k2", 1).await.unwrap();
            assert_eq!(s.session_key("s1").await.unwrap().as_deref(), Some("k1"));
            assert_eq!(
                s.session_key("old").await.unwrap(),
                None,
                "an ended session"
            );
            assert_eq!(s.session_key("nope").await.unwrap(), None);
            s.end_session("s1").await.unwrap();
            assert_eq!(s.session_key("s1").await.unwrap(), None);
            assert_eq!(s.end_sessions_of_key("k1").await.unwrap(), 1);
            assert_eq!(s.session_key("s2").await.unwrap(), None);
            assert_eq!(s.session_key("s3").await.unwrap().as_deref(), Some("k2"));
            assert_eq!(s.sessions_of_key("k2").await.unwrap(), 1);
        }
    }
}
