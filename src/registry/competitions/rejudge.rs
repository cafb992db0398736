//! Rejudges: a version's or a maze's ranking matches played again.

use crate::registry::{RegistryError, Result};
use crate::storage::Storage;
use crate::storage::competitions::CompetitionRow;

/// What a rejudge is asked to play again, and why.
#[derive(Debug, Clone, serde::Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct RejudgeRequest {
    /// Play again every ranking match of this bot version (its id) ...
    #[serde(default)]
    pub bot_version_id: Option<i64>,
    /// ... or every ranking match on this maze (one of the competition's).
    #[serde(default)]
    pub maze_id: Option<i64>,
    /// Why (kept with the rejudge; 1 to 500 characters).
    pub reason: String,
}

/// Plays again the ranking matches of competition `c` that `request` names (a version
/// entered in it, or one of its mazes), for `requested_by` (`admin` or
/// `organiser:ID`); the earlier records are kept, marked superseded, and the boards and
/// results are counted again as the matches are played.
///
/// # Errors
/// [`RegistryError::Invalid`] for a request naming neither or both, a version not in the
/// competition or a maze not in it, or no reason; the database.
pub async fn rejudge(
    storage: &Storage,
    c: &CompetitionRow,
    request: &RejudgeRequest,
    requested_by: &str,
) -> Result<crate::storage::rejudges::RejudgeRow> {
    use crate::storage::rejudges::RejudgeTarget;
    let reason = request.reason.trim();
    if reason.is_empty() || reason.chars().count() > 500 || reason.chars().any(char::is_control) {
        return Err(RegistryError::Invalid(
            "reason: 1 to 500 characters on one line (why the matches are played again)".into(),
        ));
    }
    if c.kind != "competition" {
        return Err(RegistryError::Conflict(
            "the default competition has no ranking matches to rejudge".into(),
        ));
    }
    let target = match (request.bot_version_id, request.maze_id) {
        (Some(v), None) => {
            let entered = storage.competition_entries(c.competition_id).await?;
            let version = storage.get_bot_version(v).await?;
            if !version.is_some_and(|row| entered.iter().any(|e| e.bot_id == row.bot_id)) {
                return Err(RegistryError::Invalid(format!(
                    "version id {v} is not a version of a bot entered in {}",
                    c.name
                )));
            }
            RejudgeTarget::Version(v)
        }
        (None, Some(m)) => {
            let mazes = storage.competition_mazes(c.competition_id).await?;
            if !mazes.iter().any(|x| x.maze_id == m) {
                return Err(RegistryError::Invalid(format!(
                    "maze {m} is not one of {}'s mazes",
                    c.name
                )));
            }
            RejudgeTarget::Maze(m)
        }
        _ => {
            return Err(RegistryError::Invalid(
                "name either a version (`bot_version_id`) or a maze (`maze_id`) to play again"
                    .into(),
            ));
        }
    };
    Ok(storage.rejudge(c, target, reason, requested_by).await?)
}
