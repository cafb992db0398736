//! Entering and quotas: what an entrant may upload and practise, and the refusals'
//! words.

use super::settings::phase;
use crate::competition::{DAY_MS, Limits, Quota, Timestamp};
use crate::registry::{RegistryError, Result};
use crate::storage::Storage;
use crate::storage::bots::VersionQuota;
use crate::storage::competitions::CompetitionRow;
use crate::storage::matches::queue::PracticeQuota;

/// An entrant's quota of versions in competition `c` at `now`.
///
/// # Errors
/// The database.
pub async fn version_quota(
    storage: &Storage,
    c: &CompetitionRow,
    entrant_id: i64,
    now: i64,
) -> Result<Quota> {
    let times = storage
        .counted_version_times(c, entrant_id, now - DAY_MS)
        .await?;
    Ok(Quota::at(
        &times,
        c.versions_per_day as u32,
        now,
        "versions",
    ))
}

/// An entrant's quota of practice matches in competition `c` at `now`.
///
/// # Errors
/// The database.
pub async fn practice_quota(
    storage: &Storage,
    c: &CompetitionRow,
    entrant_id: i64,
    now: i64,
) -> Result<Quota> {
    let times = storage
        .practice_times(c.competition_id, entrant_id, now - DAY_MS)
        .await?;
    Ok(Quota::at(
        &times,
        c.practice_per_day as u32,
        now,
        "practice matches",
    ))
}

/// Why bot `bot_id` may not get a new version at `now`: a competition it is entered in
/// has closed, or its entrant's quota there is used up.
#[derive(Debug, Clone, PartialEq)]
pub enum UploadRefusal {
    /// The competition closed at this time.
    Closed(String),
    /// The quota is used up (what it says, and when the next one comes).
    Quota(String, Quota),
}

/// Whether bot `bot_id` may get a new version at `now` (see [`UploadRefusal`]); if so,
/// the version quotas it must still hold, one for each competition it is entered in.
/// They go to [`crate::registry::bots::add_version`], which counts them again in the transaction
/// that adds the version: uploads sent at once all pass this check before any is added.
///
/// # Errors
/// The database.
pub async fn check_upload(
    storage: &Storage,
    bot_id: i64,
    now: i64,
) -> Result<std::result::Result<Vec<VersionQuota>, UploadRefusal>> {
    let mut quotas = Vec::new();
    for c in storage.competitions_of_bot(bot_id).await? {
        if phase(&c, now).is_closed() {
            return Ok(Err(UploadRefusal::Closed(format!(
                "competition {} closed at {}: no new versions",
                c.name,
                Timestamp(c.closes_at.unwrap_or(0)).words()
            ))));
        }
        if let Some(entrant_id) = storage.entrant_of_entry(c.competition_id, bot_id).await? {
            let quota = version_quota(storage, &c, entrant_id, now).await?;
            if !quota.allows_one_more() {
                return Ok(Err(UploadRefusal::Quota(
                    format!("competition {}: {}", c.name, quota.message),
                    quota,
                )));
            }
            quotas.push(VersionQuota {
                competition_id: c.competition_id,
                entrant_id,
                limit: c.versions_per_day,
                since: now - DAY_MS,
            });
        }
    }
    Ok(Ok(quotas))
}

/// The refusal of a version that quota `q` did not allow at `now` (found full when
/// the version was to be added).
///
/// # Errors
/// The database.
pub async fn quota_refusal(storage: &Storage, q: VersionQuota, now: i64) -> Result<RegistryError> {
    let c = storage
        .get_competition_by_id(q.competition_id)
        .await?
        .ok_or_else(|| RegistryError::Internal("a competition vanished".into()))?;
    let quota = version_quota(storage, &c, q.entrant_id, now).await?;
    Ok(RegistryError::Quota {
        message: format!("competition {}: {}", c.name, quota.message),
        retry_after_secs: quota.retry_after_secs(now),
    })
}

/// Whether bot `bot_id` may play one more practice match on maze `maze_id` at `now`:
/// the refusal (what it says, the quota) when the maze is a practice maze of a
/// competition the bot is entered in and its entrant's practice quota there is used up;
/// else the practice quotas the match must still hold, one for each such competition.
/// They go to [`Storage::queue_match_within`], which counts them again where the match
/// is queued: requests sent at once all pass this check before any is queued.
///
/// # Errors
/// The database.
pub async fn check_practice(
    storage: &Storage,
    bot_id: i64,
    maze_id: i64,
    now: i64,
) -> Result<std::result::Result<Vec<PracticeQuota>, (String, Quota)>> {
    let mut quotas = Vec::new();
    // Counted per entrant, all its bots together: a bot not entered plays the practice
    // mazes of its entrant's competitions on the same quota.
    let Some(entrant_id) = storage.entrant_of_bot(bot_id).await? else {
        return Ok(Ok(quotas));
    };
    for c in storage.competitions_of_entrant(entrant_id).await? {
        let practice = storage
            .competition_mazes(c.competition_id)
            .await?
            .iter()
            .any(|m| m.maze_id == maze_id && m.maze_set == "practice");
        if !practice {
            continue;
        }
        let quota = practice_quota(storage, &c, entrant_id, now).await?;
        if !quota.allows_one_more() {
            return Ok(Err((
                format!("competition {}: {}", c.name, quota.message),
                quota,
            )));
        }
        quotas.push(PracticeQuota {
            competition_id: c.competition_id,
            entrant_id,
            limit: c.practice_per_day,
            since: now - DAY_MS,
        });
    }
    Ok(Ok(quotas))
}

/// The limits a practice match of bot `bot_id` on maze `maze_id` plays under: those of
/// the competition whose practice maze it is, the one the bot is entered in first, else
/// the first of its entrant's (by id); `None` (the server's) for a maze that is no
/// practice maze of theirs, or a bot of no entrant.
///
/// # Errors
/// The database.
pub async fn practice_limits(
    storage: &Storage,
    bot_id: i64,
    maze_id: i64,
) -> Result<Option<Limits>> {
    let Some(entrant_id) = storage.entrant_of_bot(bot_id).await? else {
        return Ok(None);
    };
    let entered: Vec<i64> = storage
        .competitions_of_bot(bot_id)
        .await?
        .iter()
        .map(|c| c.competition_id)
        .collect();
    let mut theirs = storage.competitions_of_entrant(entrant_id).await?;
    theirs.sort_by_key(|c| (!entered.contains(&c.competition_id), c.competition_id));
    for c in theirs {
        let practice = storage
            .competition_mazes(c.competition_id)
            .await?
            .iter()
            .any(|m| m.maze_id == maze_id && m.maze_set == "practice");
        if practice {
            return Ok(Some(c.limit_set()));
        }
    }
    Ok(None)
}

/// What practice quota `q`, found used up when a match was to be queued, says at
/// `now`, and the quota.
///
/// # Errors
/// The database.
pub async fn practice_refusal(
    storage: &Storage,
    q: PracticeQuota,
    now: i64,
) -> Result<(String, Quota)> {
    let c = storage
        .get_competition_by_id(q.competition_id)
        .await?
        .ok_or_else(|| RegistryError::Internal("a competition vanished".into()))?;
    let quota = practice_quota(storage, &c, q.entrant_id, now).await?;
    Ok((format!("competition {}: {}", c.name, quota.message), quota))
}
