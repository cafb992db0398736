//! Who is calling: an admin (the server's admin token), the holder of some bot's owner
//! token, or nobody. Tokens come as `Authorization: Bearer TOKEN` and are compared by
//! their SHA-256, the form in which owner tokens are stored.

use axum::extract::FromRequestParts;
use axum::http::header;
use axum::http::request::Parts;

use super::AppState;
use super::error::ApiError;

/// The caller of a request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Caller {
    /// No token.
    Anonymous,
    /// The admin token.
    Admin,
    /// An organiser's key (the organiser's id): makes competitions, and manages and
    /// sees what seals the ones it owns.
    Organiser(i64),
    /// Some other token (maybe a bot's owner token), by its hash.
    Token(String),
}

pub use crate::registry::tokens::{hash_token, new_token};

impl FromRequestParts<AppState> for Caller {
    type Rejection = ApiError;

    async fn from_request_parts(
        parts: &mut Parts,
        state: &AppState,
    ) -> Result<Self, Self::Rejection> {
        let Some(value) = parts.headers.get(header::AUTHORIZATION) else {
            return Ok(Caller::Anonymous);
        };
        let token = value
            .to_str()
            .ok()
            .and_then(|v| v.strip_prefix("Bearer "))
            .map(str::trim)
            .filter(|t| !t.is_empty())
            .ok_or_else(|| {
                ApiError::Unauthorized("the Authorization header must be `Bearer TOKEN`".into())
            })?;
        Caller::from_key_hash(state, hash_token(token)).await
    }
}

impl Caller {
    /// The caller a key with SHA-256 `hash` makes (a Bearer token, or the key a
    /// browser session was opened with).
    ///
    /// # Errors
    /// Database failures.
    pub async fn from_key_hash(state: &AppState, hash: String) -> Result<Caller, ApiError> {
        if hash == state.settings.admin_token_hash {
            Ok(Caller::Admin)
        } else if let Some(id) = state.storage.organiser_by_key(&hash).await? {
            Ok(Caller::Organiser(id))
        } else {
            Ok(Caller::Token(hash))
        }
    }

    /// Whether this is the admin.
    pub fn is_admin(&self) -> bool {
        matches!(self, Caller::Admin)
    }

    /// Whether this is the admin or an organiser: may make competitions.
    pub fn can_organise(&self) -> bool {
        matches!(self, Caller::Admin | Caller::Organiser(_))
    }

    /// Whether this is the admin or the organiser competition `c` belongs to: may
    /// change it and see what it seals (the final run before the results).
    pub fn organises(&self, c: &crate::storage::competitions::CompetitionRow) -> bool {
        match self {
            Caller::Admin => true,
            Caller::Organiser(id) => c.organiser_id == Some(*id),
            Caller::Anonymous | Caller::Token(_) => false,
        }
    }

    /// Tournament `id`, if the caller may see it ([`Caller::sees_tournament`]).
    ///
    /// # Errors
    /// No such tournament, or not open to the caller (the same 404: a sealed
    /// tournament's existence is not told); database failures.
    pub async fn tournament(
        &self,
        state: &AppState,
        id: i64,
    ) -> Result<crate::storage::tournaments::TournamentRow, ApiError> {
        match state.storage.get_tournament(id).await? {
            Some(t) if self.sees_tournament(state, &t).await? => Ok(t),
            _ => Err(ApiError::NotFound(format!("no tournament {id}"))),
        }
    }

    /// Whether the caller may see tournament `t`: any caller an unsealed one; a sealed one
    /// (a competition's, before its results) the admin and that competition's organiser.
    ///
    /// # Errors
    /// Database failures.
    pub async fn sees_tournament(
        &self,
        state: &AppState,
        t: &crate::storage::tournaments::TournamentRow,
    ) -> Result<bool, ApiError> {
        Ok(!t.sealed
            || self
                .organises_competition_of(state, t.competition_id)
                .await?)
    }

    /// Whether the caller is the admin or the organiser of competition `competition_id`
    /// (`None`: no competition, the admin only).
    ///
    /// # Errors
    /// Database failures.
    pub async fn organises_competition_of(
        &self,
        state: &AppState,
        competition_id: Option<i64>,
    ) -> Result<bool, ApiError> {
        Ok(match (self, competition_id) {
            (Caller::Admin, _) => true,
            (Caller::Organiser(_), Some(id)) => state
                .storage
                .get_competition_by_id(id)
                .await?
                .is_some_and(|c| self.organises(&c)),
            _ => false,
        })
    }

    /// Refuses anyone but the admin and the organiser competition `c` belongs to: 401
    /// without a token, 403 with another one (another organiser's included).
    ///
    /// # Errors
    /// As said.
    pub fn require_organiser_of(
        &self,
        c: &crate::storage::competitions::CompetitionRow,
    ) -> Result<(), ApiError> {
        if self.organises(c) {
            return Ok(());
        }
        Err(match self {
            Caller::Anonymous => ApiError::Unauthorized(format!(
                "this needs the key of competition {}'s organiser or the admin token (Authorization: Bearer TOKEN)",
                c.name
            )),
            _ => ApiError::Forbidden(format!(
                "competition {} belongs to another organiser: this needs its organiser's key or the admin token",
                c.name
            )),
        })
    }

    /// Refuses anyone but the admin and the organisers: 401 without a token, 403 with
    /// another one.
    ///
    /// # Errors
    /// As said.
    pub fn require_organiser(&self) -> Result<(), ApiError> {
        match self {
            Caller::Admin | Caller::Organiser(_) => Ok(()),
            Caller::Anonymous => Err(ApiError::Unauthorized(
                "this needs an organiser's key or the admin token (Authorization: Bearer TOKEN)"
                    .into(),
            )),
            Caller::Token(_) => Err(ApiError::Forbidden(
                "this needs an organiser's key or the admin token".into(),
            )),
        }
    }

    /// Refuses anyone but the admin: 401 without a token, 403 with another one.
    ///
    /// # Errors
    /// As said.
    pub fn require_admin(&self) -> Result<(), ApiError> {
        match self {
            Caller::Admin => Ok(()),
            Caller::Anonymous => Err(ApiError::Unauthorized(
                "this needs the admin token (Authorization: Bearer TOKEN)".into(),
            )),
            Caller::Token(_) | Caller::Organiser(_) => {
                Err(ApiError::Forbidden("this needs the admin token".into()))
            }
        }
    }

    /// Whether the caller is the admin or holds `bot_id`'s owner token.
    ///
    /// # Errors
    /// Database failures.
    pub async fn owns(&self, state: &AppState, bot_id: i64) -> Result<bool, ApiError> {
        Ok(match self {
            Caller::Admin => true,
            Caller::Anonymous | Caller::Organiser(_) => false,
            Caller::Token(hash) => state.storage.is_bot_owner(bot_id, hash).await?,
        })
    }

    /// Refuses anyone but the admin and `bot_id`'s owner: 401 without a token, 403
    /// with another one.
    ///
    /// # Errors
    /// As said, or database failures.
    pub async fn require_owner(&self, state: &AppState, bot_id: i64) -> Result<(), ApiError> {
        if self.owns(state, bot_id).await? {
            return Ok(());
        }
        Err(match self {
            Caller::Anonymous => ApiError::Unauthorized(format!(
                "this needs bot {bot_id}'s owner token or the admin token (Authorization: Bearer TOKEN)"
            )),
            _ => ApiError::Forbidden(format!("this token is not bot {bot_id}'s owner token")),
        })
    }
}
