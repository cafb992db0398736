//! Entrants (a person or a team, with an API key that acts for all their bots) and the
//! server's registration mode.

use sqlx::FromRow;

use super::{Result, Storage, StorageError, is_unique_violation, now_ms};

/// An entrant, without its key.
#[derive(Debug, Clone, PartialEq, FromRow)]
pub struct EntrantRow {
    /// Id.
    pub entrant_id: i64,
    /// Unique display name.
    pub name: String,
    /// The members' names, a JSON array of strings.
    pub members: String,
    /// When it registered (unix ms).
    pub created_at: i64,
    /// When its key was last replaced (unix ms).
    pub key_rotated_at: Option<i64>,
}

/// Who may become an entrant.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Registration {
    /// Anyone.
    Open,
    /// No one but through the admin.
    Closed,
    /// Whoever gives the invite code whose SHA-256 (hex) this is.
    Invite(String),
}

/// The columns of an [`EntrantRow`].
const COLUMNS: &str = "entrant_id, name, members, created_at, key_rotated_at";

impl Storage {
    /// Registers an entrant whose key has SHA-256 `key_hash` (through the invite code of
    /// competition `registered_through`, if given).
    ///
    /// # Errors
    /// [`StorageError::Conflict`] when the name is taken; database failures.
    pub async fn create_entrant(
        &self,
        name: &str,
        members_json: &str,
        key_hash: &str,
        registered_through: Option<i64>,
    ) -> Result<EntrantRow> {
        let _turn = self.write_turn().await;
        sqlx::query_as(&format!(
            "insert into entrant (name, members, key_hash, created_at, registered_through)
             values ($1, $2, $3, $4, $5) returning {COLUMNS}"
        ))
        .bind(name)
        .bind(members_json)
        .bind(key_hash)
        .bind(now_ms())
        .bind(registered_through)
        .fetch_one(self.pool())
        .await
        .map_err(|e| {
            if is_unique_violation(&e) {
                StorageError::Conflict(format!("an entrant named {name:?} exists already (names that differ only in case are one name)"))
            } else {
                e.into()
            }
        })
    }

    /// The entrant `entrant_id`.
    ///
    /// # Errors
    /// Database failures.
    pub async fn get_entrant(&self, entrant_id: i64) -> Result<Option<EntrantRow>> {
        Ok(sqlx::query_as(&format!(
            "select {COLUMNS} from entrant where entrant_id = $1"
        ))
        .bind(entrant_id)
        .fetch_optional(self.pool())
        .await?)
    }

    /// The entrant whose key has SHA-256 `key_hash`.
    ///
    /// # Errors
    /// Database failures.
    pub async fn entrant_by_key(&self, key_hash: &str) -> Result<Option<EntrantRow>> {
        Ok(sqlx::query_as(&format!(
            "select {COLUMNS} from entrant where key_hash = $1"
        ))
        .bind(key_hash)
        .fetch_optional(self.pool())
        .await?)
    }

    /// Replaces entrant `entrant_id`'s key (the old one stops working at once) and
    /// revokes the owner token of every bot of the entrant (a token given when a bot was
    /// registered, maybe with the old key): from then on the new key alone acts for them.
    ///
    /// # Errors
    /// Database failures.
    pub async fn rotate_entrant_key(&self, entrant_id: i64, key_hash: &str) -> Result<()> {
        let _turn = self.write_turn().await;
        let mut tx = self.begin_write().await?;
        // The browser sessions opened with the old key or with its bots' owner tokens
        // end with them.
        sqlx::query(
            "delete from web_session where key_hash in (
                 select key_hash from entrant where entrant_id = $1
                 union all
                 select owner_token_hash from bot where entrant_id = $1)",
        )
        .bind(entrant_id)
        .execute(&mut *tx)
        .await?;
        sqlx::query("update entrant set key_hash = $1, key_rotated_at = $2 where entrant_id = $3")
            .bind(key_hash)
            .bind(now_ms())
            .bind(entrant_id)
            .execute(&mut *tx)
            .await?;
        // No SHA-256 in hex is ever this: the token matches nothing.
        sqlx::query(
            "update bot set owner_token_hash = 'revoked:' || cast(bot_id as text) where entrant_id = $1",
        )
        .bind(entrant_id)
        .execute(&mut *tx)
        .await?;
        tx.commit().await?;
        Ok(())
    }

    /// Entrants whose name or members' names hold `search` (any case; empty: all), by
    /// name, at most `limit`; and how many match in all.
    ///
    /// # Errors
    /// Database failures.
    pub async fn find_entrants(&self, search: &str, limit: i64) -> Result<(Vec<EntrantRow>, i64)> {
        let pattern = like_pattern(search);
        let filter = "lower(name) like $1 escape '\\' or lower(members) like $1 escape '\\'";
        let rows = sqlx::query_as(&format!(
            "select {COLUMNS} from entrant where {filter} order by lower(name) limit $2"
        ))
        .bind(&pattern)
        .bind(limit)
        .fetch_all(self.pool())
        .await?;
        let total: i64 =
            sqlx::query_scalar(&format!("select count(*) from entrant where {filter}"))
                .bind(&pattern)
                .fetch_one(self.pool())
                .await?;
        Ok((rows, total))
    }

    /// The entrants that registered with competition `competition_id`'s invite code and
    /// have no bot in it yet: id and name, by name.
    ///
    /// # Errors
    /// Database failures.
    pub async fn registered_without_entry(
        &self,
        competition_id: i64,
    ) -> Result<Vec<(i64, String)>> {
        Ok(sqlx::query_as(
            "select entrant_id, name from entrant
             where registered_through = $1
               and entrant_id not in (select entrant_id from competition_entry where competition_id = $1)
             order by lower(name)",
        )
        .bind(competition_id)
        .fetch_all(self.pool())
        .await?)
    }

    /// The competitions entrant `entrant_id` has a bot in, or registered through (its
    /// invite code): each one's organiser (none: the admin's).
    ///
    /// # Errors
    /// Database failures.
    pub async fn organisers_of_entrant(&self, entrant_id: i64) -> Result<Vec<Option<i64>>> {
        Ok(sqlx::query_scalar(
            "select c.organiser_id from competition c
             where c.competition_id in (select competition_id from competition_entry where entrant_id = $1)
                or c.competition_id = (select registered_through from entrant where entrant_id = $1)",
        )
        .bind(entrant_id)
        .fetch_all(self.pool())
        .await?)
    }

    /// The bots of entrant `entrant_id`: id and name, oldest first.
    ///
    /// # Errors
    /// Database failures.
    pub async fn bots_of_entrant(&self, entrant_id: i64) -> Result<Vec<(i64, String)>> {
        Ok(
            sqlx::query_as("select bot_id, name from bot where entrant_id = $1 order by bot_id")
                .bind(entrant_id)
                .fetch_all(self.pool())
                .await?,
        )
    }

    /// Gives bot `bot_id` to entrant `entrant_id`.
    ///
    /// # Errors
    /// Database failures.
    pub async fn set_bot_entrant(&self, bot_id: i64, entrant_id: i64) -> Result<()> {
        let _turn = self.write_turn().await;
        sqlx::query("update bot set entrant_id = $1 where bot_id = $2")
            .bind(entrant_id)
            .bind(bot_id)
            .execute(self.pool())
            .await?;
        Ok(())
    }

    /// The registration mode.
    ///
    /// # Errors
    /// Database failures.
    pub async fn registration(&self) -> Result<Registration> {
        let (mode, invite): (String, Option<String>) =
            sqlx::query_as("select mode, invite_hash from registration where registration_id = 1")
                .fetch_one(self.pool())
                .await?;
        Ok(match (mode.as_str(), invite) {
            ("open", _) => Registration::Open,
            ("invite", Some(hash)) => Registration::Invite(hash),
            _ => Registration::Closed,
        })
    }

    /// Sets the registration mode.
    ///
    /// # Errors
    /// Database failures.
    pub async fn set_registration(&self, registration: &Registration) -> Result<()> {
        let (mode, invite) = match registration {
            Registration::Open => ("open", None),
            Registration::Closed => ("closed", None),
            Registration::Invite(hash) => ("invite", Some(hash.as_str())),
        };
        let _turn = self.write_turn().await;
        sqlx::query(
            "update registration set mode = $1, invite_hash = $2 where registration_id = 1",
        )
        .bind(mode)
        .bind(invite)
        .execute(self.pool())
        .await?;
        Ok(())
    }
}

/// `search` as a LIKE pattern that matches it anywhere, in lower case, its own `%`, `_`
/// and `\` taken literally (with `escape '\'`).
fn like_pattern(search: &str) -> String {
    let mut p = String::from("%");
    for c in search.trim().to_lowercase().chars() {
        if matches!(c, '%' | '_' | '\\') {
            p.push('\\');
        }
        p.push(c);
    }
    p.push('%');
    p
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::storage::test_support::{backends, plain_version};

    #[tokio::test]
    async fn an_entrants_key_acts_for_its_bots_and_a_rotated_key_no_longer_does() {
        for (db, _guard) in backends().await {
            let e = db
                .create_entrant("team", r#"["ada"]"#, "k1", None)
                .await
                .unwrap();
            assert!(matches!(
                db.create_entrant("team", "[]", "k2", None).await,
                Err(StorageError::Conflict(_))
            ));
            assert!(
                matches!(
                    db.create_entrant("TeAm", "[]", "k3", None).await,
                    Err(StorageError::Conflict(_))
                ),
                "names that differ only in case are one name"
            );
            // Found by name or member, in any case; a search's `%` and `_` are literal.
            let (found, total) = db.find_entrants("ADA", 10).await.unwrap();
            assert_eq!((found.len(), total, found[0].name.as_str()), (1, 1, "team"));
            assert_eq!(db.find_entrants("", 10).await.unwrap().1, 1);
            assert_eq!(db.find_entrants("t%m", 10).await.unwrap().1, 0);
            assert_eq!(db.find_entrants("t_am", 10).await.unwrap().1, 0);
            let bot = db
                .create_bot("b", "own", &plain_version())
                .await
                .unwrap()
                .bot_id;
            assert!(!db.is_bot_owner(bot, "k1").await.unwrap());
            db.set_bot_entrant(bot, e.entrant_id).await.unwrap();
            assert!(db.is_bot_owner(bot, "k1").await.unwrap());
            assert!(
                db.is_bot_owner(bot, "own").await.unwrap(),
                "the bot's own token too"
            );
            assert_eq!(db.entrant_by_key("k1").await.unwrap().unwrap().name, "team");
            db.rotate_entrant_key(e.entrant_id, "k3").await.unwrap();
            assert!(!db.is_bot_owner(bot, "k1").await.unwrap());
            assert!(db.is_bot_owner(bot, "k3").await.unwrap());
            // The bot's own owner token is revoked with the old key.
            assert!(!db.is_bot_owner(bot, "own").await.unwrap());
            assert_eq!(
                db.bots_of_entrant(e.entrant_id).await.unwrap(),
                vec![(bot, "b".into())]
            );
            assert_eq!(db.registration().await.unwrap(), Registration::Open);
            db.set_registration(&Registration::Invite("h".into()))
                .await
                .unwrap();
            assert_eq!(
                db.registration().await.unwrap(),
                Registration::Invite("h".into())
            );
        }
    }
}
