//! The entrants as the admin finds them: searched by name or member, for the admin's
//! list (the API's `GET /api/entrants` and the admin page), where a lost key is
//! replaced.

use serde::Serialize;
use utoipa::ToSchema;

use super::Result;
use crate::storage::Storage;

/// An entrant as the admin lists it.
#[derive(Debug, Clone, Serialize, ToSchema)]
pub struct EntrantLine {
    /// Id.
    pub entrant_id: i64,
    /// Name.
    pub name: String,
    /// The members' names.
    pub members: Vec<String>,
    /// Registered at (unix ms).
    pub created_at: i64,
    /// When its key was last replaced (unix ms).
    pub key_rotated_at: Option<i64>,
}

/// A page of entrants and how many match.
#[derive(Debug, Clone, Serialize, ToSchema)]
pub struct EntrantList {
    /// The entrants, by name.
    pub items: Vec<EntrantLine>,
    /// How many match in all.
    pub total: i64,
}

/// The entrants whose name or members' names hold `search` (any case; empty: all), by
/// name, at most `limit`, and how many match in all.
///
/// # Errors
/// The database.
pub async fn find(storage: &Storage, search: &str, limit: i64) -> Result<EntrantList> {
    let (rows, total) = storage.find_entrants(search, limit).await?;
    Ok(EntrantList {
        items: rows
            .into_iter()
            .map(|e| EntrantLine {
                entrant_id: e.entrant_id,
                name: e.name,
                members: serde_json::from_str(&e.members).unwrap_or_default(),
                created_at: e.created_at,
                key_rotated_at: e.key_rotated_at,
            })
            .collect(),
        total,
    })
}
