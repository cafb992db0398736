//! Competitions, the operations the API, the command line and the server's clock share:
//! creating one from its spec (admitting its mazes), editing it, entering a bot, the
//! quotas, the boards as each caller may see them, and the clock's work ([`tick`]):
//! ranking every new ready version automatically, and after the close the final
//! selection, the final run and the results (an immutable snapshot checked against a
//! recount of the match records).

use serde::Serialize;

use super::rankings;
use super::{RegistryError, Result};
use crate::competition::selection::{self, Candidate, Rule, VersionScore};
use crate::competition::spec::{self, check_schedule};
use crate::competition::{
    DAY_MS, Limits, MazeSets, MazeText, Phase, Quota, Spec, Timeline, Timestamp,
};
use crate::engine::mazefile;
use crate::ranking::Mean;
use crate::ranking::mean::ratio_3dp;
use crate::storage::Storage;
use crate::storage::bots::VersionQuota;
use crate::storage::competitions::{BoardRow, CompetitionMaze, CompetitionRow, ResultRow};
use crate::storage::leaderboard::Scope;
use crate::storage::matches::PracticeQuota;

/// Seeds drawn for every competition: enough for the most ranking and final repeats.
pub const SEEDS: usize = 70;

/// The competition's timeline (`None` for the default competition).
pub fn timeline(c: &CompetitionRow) -> Option<Timeline> {
    Some(Timeline {
        opens_at: c.opens_at?,
        closes_at: c.closes_at?,
        freeze_ms: c.freeze_ms,
    })
}

/// Its phase at `now` (the default competition is always open).
pub fn phase(c: &CompetitionRow, now: i64) -> Phase {
    if c.state.as_deref() == Some("final") {
        return Phase::Final;
    }
    timeline(c).map_or(Phase::Open, |t| t.phase(now))
}

/// Creates a competition: checks its spec, admits its mazes (a practice maze must be
/// public on this server, a ranking maze hidden; a layout stored already is reused if
/// so), draws its secret seeds.
///
/// # Errors
/// [`RegistryError::Invalid`] saying what is wrong (with the maze and its line for a bad
/// maze), [`RegistryError::Conflict`] for a name taken, the database.
pub async fn create(
    storage: &Storage,
    spec: Spec<MazeText>,
    organiser_id: Option<i64>,
) -> Result<CompetitionRow> {
    spec.check().map_err(|e| RegistryError::Invalid(e.0))?;
    let mut ids: MazeSets<i64> = MazeSets {
        practice: Vec::new(),
        public: Vec::new(),
        private: Vec::new(),
    };
    let sets = [
        ("practice", &spec.mazes.practice),
        ("public", &spec.mazes.public),
        ("private", &spec.mazes.private),
    ];
    for (set, mazes) in sets {
        let hidden = set != "practice";
        for m in mazes {
            let id = admit(storage, m, hidden).await.map_err(|e| match e {
                RegistryError::Invalid(why) => {
                    RegistryError::Invalid(format!("{set} maze {:?}: {why}", m.name))
                }
                other => other,
            })?;
            match set {
                "practice" => ids.practice.push(id),
                "public" => ids.public.push(id),
                _ => ids.private.push(id),
            }
        }
    }
    let mut seeds = Vec::with_capacity(SEEDS);
    let mut bytes = [0u8; 4 * SEEDS];
    getrandom::fill(&mut bytes)
        .map_err(|e| RegistryError::Internal(format!("no randomness: {e}")))?;
    for chunk in bytes.chunks(4) {
        seeds.push(i64::from(
            u32::from_le_bytes(chunk.try_into().unwrap_or_default()) >> 1,
        ));
    }
    Ok(storage
        .create_competition(&spec.with_mazes(ids), &seeds, organiser_id)
        .await?)
}

/// Adds maze `m` to competition `c`'s practice set while it takes part (before its
/// close): public on this server (admitted if new); answers its id.
///
/// # Errors
/// [`RegistryError::Conflict`] once closed or for a maze in it already, or a hidden
/// maze's layout; [`RegistryError::Invalid`] for a bad maze; the database.
pub async fn add_practice_maze(
    storage: &Storage,
    c: &CompetitionRow,
    m: &MazeText,
    now: i64,
) -> Result<i64> {
    practice_open(c, now)?;
    let id = admit(storage, m, false).await.map_err(|e| match e {
        RegistryError::Invalid(why) => {
            RegistryError::Invalid(format!("practice maze {:?}: {why}", m.name))
        }
        other => other,
    })?;
    storage.add_practice_maze(c.competition_id, id).await?;
    Ok(id)
}

/// Removes practice maze `maze_id` from competition `c` while it takes part (its
/// practice matches stay).
///
/// # Errors
/// [`RegistryError::Conflict`] once closed; [`RegistryError::NotFound`] for a maze that
/// is not one of its practice mazes; the database.
pub async fn remove_practice_maze(
    storage: &Storage,
    c: &CompetitionRow,
    maze_id: i64,
    now: i64,
) -> Result<()> {
    practice_open(c, now)?;
    if !storage
        .remove_practice_maze(c.competition_id, maze_id)
        .await?
    {
        return Err(RegistryError::NotFound(format!(
            "maze {maze_id} is not a practice maze of competition {}",
            c.name
        )));
    }
    Ok(())
}

/// Refuses a change of the practice mazes once `c` has closed.
fn practice_open(c: &CompetitionRow, now: i64) -> Result<()> {
    if c.kind == "default" || phase(c, now).is_closed() {
        return Err(RegistryError::Conflict(format!(
            "competition {} takes no practice mazes now: it has closed (or is the default one)",
            c.name
        )));
    }
    Ok(())
}

/// The stored maze of `m`'s layout, or `m` admitted; its visibility must be `hidden`.
async fn admit(storage: &Storage, m: &MazeText, hidden: bool) -> Result<i64> {
    let text = m.layout.clone().into_bytes();
    let maze = super::bundles::blocking(move || mazefile::parse(&text))
        .await?
        .map_err(|e| RegistryError::Invalid(format!("invalid maze: {e}")))?;
    if let Some(stored) = storage.get_maze_by_hash(&maze.hash()).await? {
        // A hidden maze that ranks in another competition stays that competition's:
        // played here, its results would show there (what a sealed set holds is the
        // other competition's secret, so the answer names neither).
        if stored.hidden && storage.maze_ranks_in_a_competition(stored.maze_id).await? {
            return Err(RegistryError::Conflict(
                "its layout is a hidden ranking maze of another competition on this server: choose another maze"
                    .into(),
            ));
        }
        return match (stored.hidden, hidden) {
            (true, true) | (false, false) => Ok(stored.maze_id),
            (false, true) => Err(RegistryError::Invalid(
                "its layout is public on this server already: a ranking maze must be hidden".into(),
            )),
            (true, false) => Err(RegistryError::Invalid(
                "its layout is a hidden maze on this server: a practice maze must be public".into(),
            )),
        };
    }
    Ok(
        super::mazes::admit(storage, &m.name, m.layout.as_bytes(), hidden)
            .await?
            .maze_id,
    )
}

/// What an organiser may change after creating a competition (fields left out stay).
#[derive(Debug, Clone, Default, serde::Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct Patch {
    /// Title.
    pub title: Option<String>,
    /// Description.
    pub description: Option<String>,
    /// Rules.
    pub rules: Option<String>,
    /// Opening (before it opens only).
    pub opens_at: Option<Timestamp>,
    /// Close (before it closes only; the close moved to now closes it now).
    pub closes_at: Option<Timestamp>,
    /// Freeze before the close, hours (a negative number: no freeze).
    pub freeze_hours: Option<f64>,
    /// Versions per entrant per 24 hours.
    pub versions_per_day: Option<u32>,
    /// Practice matches per entrant per 24 hours.
    pub practice_per_day: Option<u32>,
    /// The final selection rule.
    pub selection: Option<Rule>,
    /// With `choice`: how many versions an entrant may choose.
    pub max_selected: Option<u32>,
    /// The final run's repeats.
    pub final_repeats: Option<u32>,
    /// Whether the private mazes are shown with the results.
    pub reveal_private_mazes: Option<bool>,
    /// Whether the results wait for an organiser to publish them (until they are
    /// written: afterwards they are published, [`publish`]).
    pub hold_results: Option<bool>,
    /// The match limits (all three, replacing the old).
    pub limits: Option<Limits>,
    /// How new versions are checked: `start`, `match` or `off` (versions checked
    /// already keep their status).
    pub validation: Option<crate::competition::Validation>,
    /// Hands the competition to the organiser of this name (the admin only: the API
    /// checks it).
    pub organiser: Option<String>,
}

/// Applies `patch` to competition `c` at `now`. Once closed, nothing but the texts
/// changes; the opening cannot move once open.
///
/// # Errors
/// [`RegistryError::Conflict`] for a change too late, [`RegistryError::Invalid`] for a
/// value out of range, the database.
pub async fn edit(
    storage: &Storage,
    mut c: CompetitionRow,
    patch: Patch,
    now: i64,
) -> Result<CompetitionRow> {
    if c.kind == "default" {
        return Err(RegistryError::Conflict(
            "the default competition (the server's ranking) has no settings to edit".into(),
        ));
    }
    let phase = phase(&c, now);
    let rules_change = patch.opens_at.is_some()
        || patch.closes_at.is_some()
        || patch.freeze_hours.is_some()
        || patch.versions_per_day.is_some()
        || patch.practice_per_day.is_some()
        || patch.selection.is_some()
        || patch.max_selected.is_some()
        || patch.final_repeats.is_some()
        || patch.reveal_private_mazes.is_some()
        || patch.limits.is_some()
        || patch.validation.is_some();
    if phase.is_closed() && rules_change {
        return Err(RegistryError::Conflict(format!(
            "competition {} closed at {}: only its title, description and rules can change",
            c.name,
            Timestamp(c.closes_at.unwrap_or(0)).words()
        )));
    }
    if let Some(t) = patch.opens_at
        && phase != Phase::Upcoming
        && Some(t.0) != c.opens_at
    {
        return Err(RegistryError::Conflict(format!(
            "competition {} is open already: its opening cannot move",
            c.name
        )));
    }
    let invalid = |e: spec::SpecError| RegistryError::Invalid(e.0);
    if let Some(title) = patch.title {
        if title.trim().is_empty() || title.chars().count() > spec::MAX_TITLE_CHARS {
            return Err(RegistryError::Invalid(format!(
                "a title is 1 to {} characters",
                spec::MAX_TITLE_CHARS
            )));
        }
        c.title = title;
    }
    for (text, slot) in [
        (patch.description, &mut c.description),
        (patch.rules, &mut c.rules),
    ] {
        if let Some(text) = text {
            if text.chars().count() > spec::MAX_TEXT_CHARS {
                return Err(RegistryError::Invalid(format!(
                    "a text is at most {} characters",
                    spec::MAX_TEXT_CHARS
                )));
            }
            *slot = text;
        }
    }
    let opens = patch.opens_at.map_or(c.opens_at.unwrap_or(0), |t| t.0);
    // A close moved into the past closes the competition now.
    let closes = patch
        .closes_at
        .map_or(c.closes_at.unwrap_or(0), |t| t.0.max(now));
    let freeze_hours = match patch.freeze_hours {
        Some(h) if h < 0.0 => None,
        Some(h) => Some(h),
        None => c.freeze_ms.map(|ms| ms as f64 / 3_600_000.0),
    };
    check_schedule(Timestamp(opens), Timestamp(closes), freeze_hours).map_err(invalid)?;
    let old_freeze = timeline(&c).and_then(|t| t.frozen_from());
    let old_close = c.closes_at.unwrap_or(0);
    c.opens_at = Some(opens);
    c.closes_at = Some(closes);
    c.freeze_ms = freeze_hours.map(|h| (h * 3_600_000.0).round() as i64);
    // A close moved earlier never freezes the board in the past: a board frozen
    // already stays frozen from when it froze, and one not frozen yet freezes at the
    // earliest now (a close moved to now: not before the close).
    if closes < old_close
        && patch.freeze_hours.is_none()
        && let (Some(freeze), Some(new)) = (c.freeze_ms, timeline(&c).and_then(|t| t.frozen_from()))
    {
        let start = match old_freeze {
            Some(old) if old <= now => old,
            _ => new.max(now),
        };
        if start != new {
            c.freeze_ms = Some((closes - start).clamp(0, freeze));
        }
    }
    let counts = [
        (
            "versions_per_day",
            patch.versions_per_day,
            0,
            1000,
            &mut c.versions_per_day,
        ),
        (
            "practice_per_day",
            patch.practice_per_day,
            0,
            10_000,
            &mut c.practice_per_day,
        ),
        (
            "max_selected",
            patch.max_selected,
            1,
            10,
            &mut c.max_selected,
        ),
        (
            "final_repeats",
            patch.final_repeats,
            0,
            50,
            &mut c.final_repeats,
        ),
    ];
    for (field, value, low, high, slot) in counts {
        if let Some(v) = value {
            if !(low..=high).contains(&v) {
                return Err(RegistryError::Invalid(format!(
                    "{field} is {low} to {high}, not {v}"
                )));
            }
            *slot = i64::from(v);
        }
    }
    if let Some(rule) = patch.selection {
        c.selection = rule.as_str().to_string();
    }
    if let Some(reveal) = patch.reveal_private_mazes {
        c.reveal_private_mazes = reveal;
    }
    if let Some(hold) = patch.hold_results.filter(|&h| h != c.hold_results) {
        if matches!(c.state.as_deref(), Some("held" | "final")) {
            return Err(RegistryError::Conflict(format!(
                "the results of {} are written: they are published, not held, from now on{}",
                c.name,
                if c.state.as_deref() == Some("held") {
                    " (publish them when the class is ready)"
                } else {
                    ""
                }
            )));
        }
        c.hold_results = hold;
    }
    if let Some(v) = patch.validation {
        c.validation = v.as_str().to_string();
    }
    if let Some(limits) = patch.limits {
        limits.check().map_err(invalid)?;
        c.limits = serde_json::to_string(&limits).unwrap_or_else(|_| "{}".into());
    }
    let organiser = match &patch.organiser {
        Some(name) => Some(
            storage
                .organiser_by_name(name.trim())
                .await?
                .ok_or_else(|| RegistryError::Invalid(format!("no organiser {name:?}")))?,
        ),
        None => None,
    };
    storage.save_competition_settings(&c).await?;
    if let Some(id) = organiser {
        storage
            .set_competition_organiser(c.competition_id, Some(id))
            .await?;
        c.organiser_id = Some(id);
    }
    Ok(c)
}

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
/// They go to [`super::bots::add_version`], which counts them again in the transaction
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

/// Which board.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, Serialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum BoardKind {
    /// The public ranking set.
    Public,
    /// The private ranking set.
    Private,
}

/// One entrant's line on a board.
#[derive(Debug, Clone, PartialEq, Serialize, utoipa::ToSchema)]
pub struct BoardLine {
    /// 1 for the best mean score; equal numbers share a rank.
    pub rank: i64,
    /// The entrant's name.
    pub entrant: String,
    /// The bot.
    pub bot_id: i64,
    /// The bot's name.
    pub bot_name: String,
    /// The version counted: the entrant's latest that has played all its matches there
    /// (while frozen, the latest uploaded before the freeze).
    pub version: i64,
    /// Matches counted.
    pub played: i64,
    /// Of which finished.
    pub finished: i64,
    /// Mean score, a did-not-finish counting as 1000, rounded to 3 decimals (ranks and
    /// ties come from the exact sum, `score_sum30`).
    pub mean_score: f64,
    /// Sum of the scores in thirtieths of a step (a did-not-finish: 30,000): the exact
    /// mean is `score_sum30 / (30 x played)`.
    pub score_sum30: i64,
    /// finished / played, rounded to 3 decimals.
    pub finish_rate: f64,
    /// How sure the rank is ([`crate::ranking`]).
    pub uncertainty: crate::ranking::Uncertainty,
}

impl BoardLine {
    /// A version's line from its board row, not yet ranked (rank 0).
    pub fn from_row(r: &BoardRow) -> BoardLine {
        BoardLine {
            rank: 0,
            entrant: r.entrant_name.clone().unwrap_or_default(),
            bot_id: r.bot_id,
            bot_name: r.bot_name.clone(),
            version: r.version,
            played: r.played,
            finished: r.finished,
            mean_score: r.mean().rounded(),
            score_sum30: r.score_sum30,
            finish_rate: ratio_3dp(r.finished, r.played),
            uncertainty: Default::default(),
        }
    }

    /// An entrant's line of the final results.
    pub fn from_result(r: &ResultRow) -> BoardLine {
        BoardLine {
            rank: r.rank,
            entrant: r.entrant_name.clone(),
            bot_id: r.bot_id,
            bot_name: r.bot_name.clone(),
            version: r.version,
            played: r.played,
            finished: r.finished,
            mean_score: r.mean_score,
            score_sum30: r.score_sum30,
            finish_rate: r.finish_rate,
            uncertainty: r.uncertainty.clone(),
        }
    }

    /// The exact mean score.
    pub fn mean(&self) -> Mean {
        Mean::new(self.score_sum30, self.played)
    }
}

/// A board as some caller may see it.
#[derive(Debug, Clone, PartialEq, Serialize, utoipa::ToSchema)]
pub struct Board {
    /// Which board.
    pub board: BoardKind,
    /// True when the caller may not see it yet (the private board until the results;
    /// for the competition's organisers, until the final run has played): `standings`
    /// is then empty.
    pub sealed: bool,
    /// Since when the public board shows only versions uploaded before the freeze.
    pub frozen_at: Option<Timestamp>,
    /// On the private board: how far the final run has played, for the competition's
    /// organisers, and for everyone once the results are written (none before the
    /// close's selection has queued it; none for anyone else while it plays: its count
    /// would time each private match).
    pub final_run: Option<RunProgress>,
    /// On the private board: whether the final run is playing now (for everyone).
    pub final_run_playing: bool,
    /// Best first.
    pub standings: Vec<BoardLine>,
}

/// How far a competition's final run (the private set's only run) has played.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, utoipa::ToSchema)]
pub struct RunProgress {
    /// Matches played.
    pub played: i64,
    /// Matches in the final run.
    pub total: i64,
}

impl RunProgress {
    /// Whether every match has been played.
    pub fn done(&self) -> bool {
        self.played >= self.total
    }
}

/// The final run's progress, once the final selection has queued it.
///
/// # Errors
/// The database.
pub async fn final_progress(storage: &Storage, c: &CompetitionRow) -> Result<Option<RunProgress>> {
    let Some(t) = c.final_tournament_id else {
        return Ok(None);
    };
    let (played, total) = storage.tournament_progress(t).await?;
    Ok(Some(RunProgress { played, total }))
}

/// The final run's progress `progress` as a caller may see it: the competition's
/// organisers (`organiser`) while it plays, everyone once the results are written. For
/// anyone else a count that moves with each match would be a clock of the private
/// matches (their order is random, but their times are not).
pub fn progress_for(
    c: &CompetitionRow,
    progress: Option<RunProgress>,
    organiser: bool,
) -> Option<RunProgress> {
    progress.filter(|_| organiser || c.state.as_deref() == Some("final"))
}

/// Board `kind` of competition `c` at `now`, as an organiser of it (`organiser`:
/// everything, versions still playing included) or anyone else sees it. The private
/// board is the final run's: before the close no bot has played a private maze, so
/// there is nothing to show; organisers see it once the final run has played, everyone
/// with the results. On either board only versions whose matches there have all been
/// played (a mean that moves with each match would show each match's result); while the
/// public board is frozen, only versions uploaded before the freeze.
///
/// # Errors
/// The database.
pub async fn board(
    storage: &Storage,
    c: &CompetitionRow,
    kind: BoardKind,
    organiser: bool,
    now: i64,
) -> Result<Board> {
    let phase = phase(c, now);
    let progress = match kind {
        BoardKind::Public => None,
        BoardKind::Private => final_progress(storage, c).await?,
    };
    let tournament = match kind {
        BoardKind::Public => c.public_tournament_id,
        BoardKind::Private => deciding_tournament(c),
    };
    let frozen_at = timeline(c)
        .and_then(|t| t.frozen_from())
        .filter(|&f| kind == BoardKind::Public && now >= f);
    let sealed = kind == BoardKind::Private
        && c.state.as_deref() != Some("final")
        && !(organiser && progress.is_some_and(|p| p.done()));
    let rows = match tournament {
        Some(t) if !sealed => storage.competition_board(t, false).await?,
        _ => Vec::new(),
    };
    let kept = rows.into_iter().filter(|r| {
        organiser || (!r.pending && frozen_at.is_none_or(|f| r.created_at < f || phase.is_closed()))
    });
    let mut standings = latest_per_bot(kept);
    // Over hidden mazes, nothing but the means for anyone but the organisers: an
    // interval over few hidden matches would show single matches' scores.
    let revealed =
        kind == BoardKind::Private && c.reveal_private_mazes && c.state.as_deref() == Some("final");
    let set = |l: &mut BoardLine, rank, u| {
        l.rank = rank;
        l.uncertainty = u;
    };
    match (tournament, standings.is_empty()) {
        (Some(_), false) if !organiser && !revealed => rankings::rank_lines_withheld(
            &mut standings,
            BoardLine::mean,
            |l| l.bot_name.as_str(),
            set,
        ),
        (Some(t), false) => {
            let samples = storage.standing_samples(Scope::Tournament(t)).await?;
            rankings::rank_lines(
                &mut standings,
                &samples,
                BoardLine::mean,
                |l| l.bot_name.as_str(),
                |l| (l.bot_id, l.version),
                set,
            );
        }
        _ => {}
    }
    Ok(Board {
        board: kind,
        sealed,
        frozen_at: frozen_at.map(Timestamp),
        final_run: progress_for(c, progress, organiser),
        final_run_playing: progress.is_some() && c.state.as_deref() != Some("final"),
        standings,
    })
}

/// Each bot's latest version among `rows`, not yet ranked.
fn latest_per_bot(rows: impl Iterator<Item = BoardRow>) -> Vec<BoardLine> {
    let mut latest: Vec<BoardRow> = Vec::new();
    for r in rows {
        match latest.iter_mut().find(|l| l.bot_id == r.bot_id) {
            Some(l) if l.version < r.version => *l = r,
            Some(_) => {}
            None => latest.push(r),
        }
    }
    latest.iter().map(BoardLine::from_row).collect()
}

/// The stored results of `c`, best first, each with how sure its rank is (from the
/// deciding set's matches, which no longer change; the stored ranks are kept; withheld
/// while the private mazes stay hidden, [`crate::ranking::withheld`]).
///
/// # Errors
/// The database.
pub async fn results(storage: &Storage, c: &CompetitionRow) -> Result<Vec<ResultRow>> {
    let mut rows = storage.competition_results(c.competition_id).await?;
    if let (Some(t), false) = (deciding_tournament(c), rows.is_empty()) {
        // The private mazes stay hidden: their matches' scores are never shown, so
        // neither is anything that would tell them (the means and ranks only).
        if c.reveal_private_mazes {
            let samples = storage.standing_samples(Scope::Tournament(t)).await?;
            rankings::rank_lines(
                &mut rows,
                &samples,
                ResultRow::mean,
                |r| r.entrant_name.as_str(),
                |r| (r.bot_id, r.version),
                |r, _, u| r.uncertainty = u,
            );
        }
        rows.sort_by(|a, b| {
            a.rank
                .cmp(&b.rank)
                .then(a.entrant_name.cmp(&b.entrant_name))
        });
        if !c.reveal_private_mazes {
            rankings::withhold_lines(
                &mut rows,
                |r| r.rank,
                ResultRow::mean,
                |r, u| r.uncertainty = u,
            );
        }
    }
    Ok(rows)
}

/// What the server's clock did in one [`tick`].
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TickReport {
    /// Versions queued on ranking sets.
    pub ranked: usize,
    /// Competitions whose final selection was made.
    pub selected: usize,
    /// Competitions whose results were written.
    pub finalized: usize,
    /// Closed competitions still waiting for their last matches or their final run
    /// (the clock looks at them more often).
    pub closing: usize,
}

/// The clock's work at `now`: queues every new ready version of an entered bot on its
/// competitions' public ranking sets; for each closed competition, once its last public
/// matches and builds are done, makes the final selection and queues the final run (the
/// private set's only run), and once that is played writes the results. Safe to run on
/// several servers at once: each step is done once.
///
/// # Errors
/// The database.
pub async fn tick(storage: &Storage, now: i64) -> Result<TickReport> {
    let mut report = TickReport::default();
    let to_rank = storage.versions_to_rank(now).await?;
    let mut cache: Vec<(CompetitionRow, Vec<CompetitionMaze>)> = Vec::new();
    for (competition_id, version_id) in to_rank {
        if !cache
            .iter()
            .any(|(c, _)| c.competition_id == competition_id)
        {
            let Some(c) = storage.get_competition_by_id(competition_id).await? else {
                continue;
            };
            let mazes = storage.competition_mazes(competition_id).await?;
            cache.push((c, mazes));
        }
        let Some((c, mazes)) = cache
            .iter()
            .find(|(c, _)| c.competition_id == competition_id)
        else {
            continue;
        };
        if storage
            .rank_version(c, version_id, &in_set(mazes, "public"))
            .await?
        {
            report.ranked += 1;
        }
    }
    for c in storage.list_competitions().await? {
        if c.kind != "competition"
            || !phase(&c, now).is_closed()
            || matches!(c.state.as_deref(), Some("final" | "held"))
        {
            continue;
        }
        storage.unseal_private_set(&c).await?;
        if storage.competition_work_left(&c).await? > 0 {
            report.closing += 1;
            continue;
        }
        match c.state.as_deref() {
            None => {
                let selected = final_selection(storage, &c).await?;
                let mazes = storage.competition_mazes(c.competition_id).await?;
                let private = in_set(&mazes, "private");
                let mut order = [0u8; 8];
                getrandom::fill(&mut order)
                    .map_err(|e| RegistryError::Internal(format!("no randomness: {e}")))?;
                let order = u64::from_le_bytes(order);
                if storage.start_final(&c, &selected, &private, order).await? {
                    report.selected += 1;
                    report.closing += 1;
                }
            }
            Some("final_run") if finalize(storage, &c).await? => report.finalized += 1,
            _ => {}
        }
    }
    Ok(report)
}

/// The ids of `mazes` in set `set` (`practice`, `public`, `private`), in order.
fn in_set(mazes: &[CompetitionMaze], set: &str) -> Vec<i64> {
    mazes
        .iter()
        .filter(|m| m.maze_set == set)
        .map(|m| m.maze_id)
        .collect()
}

/// The versions each entrant has counting at the end, by the competition's rule.
async fn final_selection(storage: &Storage, c: &CompetitionRow) -> Result<Vec<i64>> {
    let rule = Rule::parse(&c.selection).unwrap_or_default();
    let public: Vec<BoardRow> = match c.public_tournament_id {
        Some(t) => storage.competition_board(t, false).await?,
        None => Vec::new(),
    };
    let mut selected = Vec::new();
    for e in storage.competition_entries(c.competition_id).await? {
        let candidates: Vec<Candidate> = storage
            .submissions(c, e.entrant_id)
            .await?
            .into_iter()
            .filter(|s| s.ranked && s.build_status == "ready")
            .map(|s| Candidate {
                bot_version_id: s.bot_version_id,
                version: s.version,
                public_mean: public
                    .iter()
                    .find(|r| r.bot_version_id == s.bot_version_id)
                    .map(BoardRow::mean),
                chosen: s.chosen,
            })
            .collect();
        selected.extend(selection::select(
            rule,
            c.max_selected as usize,
            &candidates,
        ));
    }
    Ok(selected)
}

/// The tournament whose matches decide the results: the final run's if there is one,
/// else the private set's.
pub fn deciding_tournament(c: &CompetitionRow) -> Option<i64> {
    c.final_tournament_id.or(c.private_tournament_id)
}

/// Writes the results of a competition whose final run is played: each entrant's best
/// selected version on the deciding set, with its manifest (what it is, what it played:
/// each match's maze hash, seed, status and score, so that anyone can count the mean
/// again or play a match again with `mazearena run`) and the recount check.
async fn finalize(storage: &Storage, c: &CompetitionRow) -> Result<bool> {
    let Some(t) = deciding_tournament(c) else {
        return Ok(false);
    };
    let kept = storage.competition_board(t, false).await?;
    let counted = storage.competition_board(t, true).await?;
    let chosen: std::collections::HashSet<i64> = storage
        .selected_versions(c.competition_id)
        .await?
        .into_iter()
        .collect();
    let scores: Vec<VersionScore> = kept
        .iter()
        .filter(|r| chosen.contains(&r.bot_version_id))
        .filter_map(|r| {
            Some(VersionScore {
                entrant_id: r.entrant_id?,
                bot_version_id: r.bot_version_id,
                played: r.played,
                finished: r.finished,
                mean: r.mean(),
            })
        })
        .collect();
    let private: Vec<CompetitionMaze> = storage
        .competition_mazes(c.competition_id)
        .await?
        .into_iter()
        .filter(|m| m.maze_set == "private")
        .collect();
    let mazes: Vec<serde_json::Value> = private
        .iter()
        .map(|m| serde_json::json!({"name": m.name, "hash": m.hash}))
        .collect();
    let seeds: Vec<serde_json::Value> = storage
        .tournament_seeds(t)
        .await?
        .into_iter()
        .map(|(repeat, seed)| serde_json::json!({"repeat": repeat, "seed": seed}))
        .collect();
    let matches = storage.tournament_matches(t).await?;
    let limits = c.limit_set();
    let mut limit_args = String::new();
    if let Some(ms) = limits.move_timeout_ms {
        limit_args.push_str(&format!(" --move-timeout-ms {ms}"));
    }
    if let Some(ms) = limits.startup_timeout_ms {
        limit_args.push_str(&format!(" --startup-timeout-ms {ms}"));
    }
    if let Some(ms) = limits.time_bank_ms {
        limit_args.push_str(&format!(" --time-bank-ms {ms}"));
    }
    if let Some(mb) = limits.memory_limit_mb {
        limit_args.push_str(&format!(" --memory-limit-mb {mb}"));
    }
    let mut rows = Vec::new();
    for (rank, s) in selection::rank_entrants(&scores) {
        let Some(row) = kept.iter().find(|r| r.bot_version_id == s.bot_version_id) else {
            continue;
        };
        let recount = counted
            .iter()
            .find(|r| r.bot_version_id == s.bot_version_id);
        let equal = recount.is_some_and(|r| {
            r.played == row.played && r.finished == row.finished && r.score_sum30 == row.score_sum30
        });
        if !equal {
            tracing::error!(competition = %c.name, version = s.bot_version_id,
                "the running sums differ from the recount of the match records");
        }
        let version = storage.get_bot_version(s.bot_version_id).await?;
        let played: Vec<serde_json::Value> = matches
            .iter()
            .filter(|m| m.bot_version_id == s.bot_version_id)
            .map(|m| {
                serde_json::json!({
                    "match_id": m.match_id, "maze": m.maze_name, "maze_hash": m.maze_hash,
                    "repeat": m.repeat, "seed": m.seed, "status": m.status.to_string(),
                    "score": m.score,
                })
            })
            .collect();
        let env = version.as_ref().map(|v| v.env_pairs()).unwrap_or_default();
        let runtime = version.as_ref().and_then(|v| v.runtime.clone());
        let build_command = version.as_ref().and_then(|v| v.build_command.clone());
        let replay = replay_command(
            &env,
            runtime.as_deref(),
            build_command.as_deref(),
            &limit_args,
        );
        let manifest = serde_json::json!({
            "competition": c.name,
            "bot_version_id": s.bot_version_id,
            "bundle_sha256": version.as_ref().map(|v| v.files_sha256.clone()),
            "built_sha256": version.as_ref().and_then(|v| v.built_sha256.clone()),
            "command": version.as_ref().map(|v| v.command.clone()),
            "runtime": runtime,
            "build_command": build_command,
            "env": declared_env(&env),
            "referee": crate::runner::ENGINE_VERSION,
            "tournament_id": t,
            "mazes": mazes,
            "seeds": seeds,
            "limits": c.limit_set(),
            "recount": {
                "equal": equal,
                "played": recount.map(|r| r.played),
                "finished": recount.map(|r| r.finished),
                "mean_score": recount.map(|r| r.mean().rounded()),
                "score_sum30": recount.map(|r| r.score_sum30),
            },
            "matches": played,
            "replay": replay,
        });
        rows.push(ResultRow {
            rank,
            entrant_id: s.entrant_id,
            entrant_name: row.entrant_name.clone().unwrap_or_default(),
            bot_id: row.bot_id,
            bot_name: row.bot_name.clone(),
            bot_version_id: s.bot_version_id,
            version: row.version,
            played: row.played,
            finished: row.finished,
            mean_score: row.mean().rounded(),
            score_sum30: row.score_sum30,
            finish_rate: ratio_3dp(row.finished, row.played),
            manifest: manifest.to_string(),
            uncertainty: Default::default(),
        });
    }
    let reveal = mazes_to_reveal(storage, c, &private).await?;
    Ok(storage.write_results(c, &rows, &reveal).await?)
}

/// The private mazes that publishing `c`'s results shows: all of them if it reveals
/// them, but none that another live competition still uses.
async fn mazes_to_reveal(
    storage: &Storage,
    c: &CompetitionRow,
    private: &[CompetitionMaze],
) -> Result<Vec<i64>> {
    let mut reveal = Vec::new();
    if c.reveal_private_mazes {
        for m in private {
            if !storage
                .maze_in_other_live_competition(m.maze_id, c.competition_id)
                .await?
            {
                reveal.push(m.maze_id);
            }
        }
    }
    Ok(reveal)
}

/// Publishes the held results of `c` (its organisers' decision, after the reveal's
/// rehearsal): from now on everyone sees them, the private board, the reveal and the
/// races, and the private mazes if the competition reveals them.
///
/// # Errors
/// [`RegistryError::Conflict`] when there are no held results (not written yet, or
/// published already); the database.
pub async fn publish(storage: &Storage, c: &CompetitionRow) -> Result<()> {
    match c.state.as_deref() {
        Some("held") => {}
        Some("final") => {
            return Err(RegistryError::Conflict(format!(
                "the results of {} are published already",
                c.name
            )));
        }
        _ => {
            return Err(RegistryError::Conflict(format!(
                "competition {} has no results to publish yet: they are written once its final run has played",
                c.name
            )));
        }
    }
    let private: Vec<CompetitionMaze> = storage
        .competition_mazes(c.competition_id)
        .await?
        .into_iter()
        .filter(|m| m.maze_set == "private")
        .collect();
    let reveal = mazes_to_reveal(storage, c, &private).await?;
    if !storage.publish_results(c, &reveal).await? {
        return Err(RegistryError::Conflict(format!(
            "the results of {} are published already",
            c.name
        )));
    }
    Ok(())
}

/// The declared environment of a version as a manifest holds it: each variable's name
/// and the SHA-256 (hex) of `NAME=VALUE`, so that the owner, who knows the values, can
/// check them, and nobody else learns them.
fn declared_env(env: &[(String, String)]) -> Vec<serde_json::Value> {
    env.iter()
        .map(|(k, v)| {
            serde_json::json!({
                "name": k,
                "sha256": super::tokens::hash_token(&format!("{k}={v}")),
            })
        })
        .collect()
}

/// The command line that plays one of a version's matches again with `mazearena run`:
/// its declared variables (values from the owner), its runtime, the build run first.
fn replay_command(
    env: &[(String, String)],
    runtime: Option<&str>,
    build: Option<&str>,
    limit_args: &str,
) -> String {
    let mut out = String::new();
    if let Some(b) = build {
        out.push_str(&format!("(cd FOLDER_OF_THE_BUNDLE && {b}) && "));
    }
    out.push_str(
        "mazearena run --maze MAZE_FILE --bot COMMAND --bot-dir FOLDER_OF_THE_BUNDLE --seed SEED",
    );
    out.push_str(limit_args);
    if runtime.is_some() {
        out.push_str(" --runtime DIR_OF_THE_RUNTIME");
    }
    for (k, _) in env {
        out.push_str(&format!(" --bot-env {k}=VALUE"));
    }
    out
}

/// Checks stored results against a recount from the match records now: the rows whose
/// numbers differ (empty: the snapshot holds).
///
/// # Errors
/// The database.
pub async fn recount_differences(storage: &Storage, c: &CompetitionRow) -> Result<Vec<String>> {
    let Some(t) = deciding_tournament(c) else {
        return Ok(Vec::new());
    };
    let counted = storage.competition_board(t, true).await?;
    let mut differ = Vec::new();
    for r in storage.competition_results(c.competition_id).await? {
        let same = counted
            .iter()
            .find(|x| x.bot_version_id == r.bot_version_id)
            .is_some_and(|x| {
                x.played == r.played && x.finished == r.finished && x.score_sum30 == r.score_sum30
            });
        if !same {
            differ.push(format!("{} (version {})", r.entrant_name, r.version));
        }
    }
    Ok(differ)
}

/// The results as CSV: a header, then one row per entrant. A name that a spreadsheet
/// would take for a formula (starting with `=`, `+`, `-`, `@`, a tab or a carriage
/// return) is written after a `'`.
pub fn results_csv(rows: &[ResultRow]) -> String {
    let field = |s: &str| {
        let s = if s.starts_with(['=', '+', '-', '@', '\t', '\r']) {
            format!("'{s}")
        } else {
            s.to_string()
        };
        if s.contains([',', '"', '\n', '\r']) {
            format!("\"{}\"", s.replace('"', "\"\""))
        } else {
            s
        }
    };
    let mut out = String::from(
        "rank,rank_range,tie_group,entrant,bot,version,played,finished,mean_score,score_low,score_high,finish_rate,score_sum30,bundle_sha256\n",
    );
    for r in rows {
        let bundle = serde_json::from_str::<serde_json::Value>(&r.manifest)
            .ok()
            .and_then(|m| m["bundle_sha256"].as_str().map(str::to_string))
            .unwrap_or_default();
        out.push_str(&format!(
            "{},{},{},{},{},{},{},{},{},{:.3},{:.3},{:.3},{},{}\n",
            r.rank,
            r.uncertainty.rank_range,
            r.uncertainty.tie_group,
            field(&r.entrant_name),
            field(&r.bot_name),
            r.version,
            r.played,
            r.finished,
            r.mean(),
            r.uncertainty.low,
            r.uncertainty.high,
            r.finish_rate,
            r.score_sum30,
            bundle
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::generator::generate;
    use crate::engine::mazefile::numeric;
    use crate::storage::now_ms;
    use crate::storage::test_support::{backends, plain_version};

    fn maze(seed: u64) -> MazeText {
        MazeText {
            name: format!("m{seed}"),
            layout: numeric::write(&generate(12, seed).unwrap()),
        }
    }

    fn spec(now: i64) -> Spec<MazeText> {
        Spec {
            name: "c".into(),
            title: "C".into(),
            description: String::new(),
            rules: String::new(),
            opens_at: Timestamp(now - 1000),
            closes_at: Timestamp(now + 3_600_000),
            freeze_hours: None,
            repeats: 2,
            final_repeats: 1,
            versions_per_day: 5,
            practice_per_day: 5,
            selection: Rule::Latest,
            max_selected: 1,
            reveal_private_mazes: true,
            hold_results: false,
            limits: Limits::default(),
            validation: Default::default(),
            mazes: MazeSets {
                practice: vec![maze(7001)],
                public: vec![maze(7002)],
                private: vec![maze(7003), maze(7004)],
            },
        }
    }

    /// A version that failed its validation match (`invalid`) gives its quota back, as
    /// one that failed to build does.
    #[tokio::test]
    async fn an_invalid_version_does_not_count_against_the_quota() {
        use crate::storage::bots::build_status;
        for (db, _guard) in backends().await {
            let now = now_ms();
            let c = create(&db, spec(now), None).await.unwrap();
            let (e, v) = entered_bot(&db, &c).await;
            let used = |q: Quota| q.used;
            let before = used(
                version_quota(&db, &c, e.entrant_id, now_ms())
                    .await
                    .unwrap(),
            );
            db.add_bot_version(v.bot_id, &crate::storage::test_support::with_build())
                .await
                .unwrap();
            let claimed = db.claim_build("w", 60_000).await.unwrap().unwrap();
            let counted = used(
                version_quota(&db, &c, e.entrant_id, now_ms())
                    .await
                    .unwrap(),
            );
            assert_eq!(counted, before + 1);
            assert!(
                db.finish_build(
                    claimed.bot_version_id,
                    "w",
                    build_status::INVALID,
                    None,
                    "crashed",
                    1_000
                )
                .await
                .unwrap()
            );
            let after = used(
                version_quota(&db, &c, e.entrant_id, now_ms())
                    .await
                    .unwrap(),
            );
            assert_eq!(after, before, "the invalid version still counts");
            let row = db
                .get_bot_version(claimed.bot_version_id)
                .await
                .unwrap()
                .unwrap();
            assert_eq!(row.build_status, build_status::INVALID);
        }
    }

    /// A close moved earlier never freezes the public board in the past: moved to now,
    /// the board shows what it showed (no freeze before the close); a board frozen
    /// already stays frozen from the same instant.
    #[tokio::test]
    async fn shortening_a_competition_never_freezes_its_board_retroactively() {
        for (db, _guard) in backends().await {
            let now = now_ms();
            let mut s = spec(now);
            s.closes_at = Timestamp(now + 48 * 3_600_000);
            s.freeze_hours = Some(24.0);
            let c = create(&db, s, None).await.unwrap();
            let frozen_from = |c: &CompetitionRow| timeline(c).and_then(|t| t.frozen_from());
            assert_eq!(frozen_from(&c), Some(now + 24 * 3_600_000));
            let patch = Patch {
                closes_at: Some(Timestamp(now)),
                ..Patch::default()
            };
            let closed = edit(&db, c.clone(), patch, now).await.unwrap();
            assert_eq!(closed.closes_at, Some(now));
            assert!(frozen_from(&closed).unwrap() >= now, "{closed:?}");
            // Frozen already (the close 12 hours away, frozen for 12): closing in an
            // hour keeps the freeze where it was.
            let later = now + 36 * 3_600_000;
            let patch = Patch {
                closes_at: Some(Timestamp(later + 3_600_000)),
                ..Patch::default()
            };
            let moved = edit(&db, c, patch, later).await.unwrap();
            assert_eq!(frozen_from(&moved), Some(now + 24 * 3_600_000));
        }
    }

    /// Plays every waiting match of the competition's tournaments by hand: finished,
    /// score `score`.
    async fn play_all(db: &Storage, score: f64) {
        db.run_sql_for_tests(&format!(
            "update match set status = 'finished', score = {score}, total_steps = 10
             where status = 'queued' and tournament_id is not null"
        ))
        .await;
    }

    /// An entrant ("e") with a bot ("b") entered in `c`.
    async fn entered_bot(
        db: &Storage,
        c: &CompetitionRow,
    ) -> (
        crate::storage::entrants::EntrantRow,
        crate::storage::bots::BotVersionRow,
    ) {
        let e = db.create_entrant("e", "[]", "k", None).await.unwrap();
        let v = db.create_bot("b", "h", &plain_version()).await.unwrap();
        db.set_bot_entrant(v.bot_id, e.entrant_id).await.unwrap();
        db.enter_competition(c.competition_id, v.bot_id, e.entrant_id)
            .await
            .unwrap();
        (e, v)
    }

    /// A close waits for each entered bot's newest version uploaded before it, built
    /// before anyone else's builds (a flood of uploads outside the competition waits),
    /// and not for the older versions it supersedes.
    #[tokio::test]
    async fn a_close_waits_for_one_build_per_entrant_built_first() {
        use crate::storage::bots::build_status;
        use crate::storage::test_support::with_build;
        for (db, _guard) in backends().await {
            let now = now_ms();
            let c = create(&db, spec(now), None).await.unwrap();
            let (_, v) = entered_bot(&db, &c).await;
            // Someone floods the builder with bots in no competition first.
            for i in 0..3 {
                db.create_bot(&format!("flood-{i}"), "flooder", &with_build())
                    .await
                    .unwrap();
            }
            // The entrant uploads three versions just before the close.
            let mut uploaded = Vec::new();
            for _ in 0..3 {
                uploaded.push(db.add_bot_version(v.bot_id, &with_build()).await.unwrap());
            }
            tokio::time::sleep(std::time::Duration::from_millis(5)).await;
            let closed = close_now(&db, c, now_ms()).await;
            // Only the newest holds the close.
            assert_eq!(db.competition_work_left(&closed).await.unwrap(), 1);
            // It is built first, ahead of the flood and of the entrant's older ones.
            let first = db.claim_build("w", 60_000).await.unwrap().unwrap();
            assert_eq!(first.bot_version_id, uploaded[2].bot_version_id);
            assert!(
                db.finish_build(first.bot_version_id, "w", build_status::READY, None, "", 5)
                    .await
                    .unwrap()
            );
            assert_eq!(db.competition_work_left(&closed).await.unwrap(), 0);
            // Then the others take turns as usual.
            let next = db.claim_build("w", 60_000).await.unwrap().unwrap();
            assert_ne!(
                next.bot_id, v.bot_id,
                "the flooder was served least recently"
            );
        }
    }

    /// `c` closed at `now`.
    async fn close_now(db: &Storage, c: CompetitionRow, now: i64) -> CompetitionRow {
        let patch = Patch {
            closes_at: Some(Timestamp(now)),
            ..Patch::default()
        };
        edit(db, c, patch, now).await.unwrap()
    }

    async fn sealed(db: &Storage, t: Option<i64>) -> bool {
        db.get_tournament(t.unwrap()).await.unwrap().unwrap().sealed
    }

    #[test]
    fn the_csv_quotes_what_it_must_and_no_name_is_a_formula() {
        let row = |entrant: &str, bot: &str| ResultRow {
            rank: 1,
            entrant_id: 1,
            entrant_name: entrant.into(),
            bot_id: 1,
            bot_name: bot.into(),
            bot_version_id: 1,
            version: 2,
            played: 4,
            finished: 3,
            mean_score: 260.5,
            score_sum30: 31260,
            finish_rate: 0.75,
            manifest: r#"{"bundle_sha256":"abc"}"#.into(),
            uncertainty: crate::ranking::Uncertainty {
                low: 250.0,
                high: 270.0,
                rank_range: "1-2".into(),
                tie_group: 1,
                ..Default::default()
            },
        };
        let csv = results_csv(&[row("team, \"a\"", "=cmd|' /c calc'!A1"), row("b", "@sum")]);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(
            lines[0],
            "rank,rank_range,tie_group,entrant,bot,version,played,finished,mean_score,score_low,score_high,finish_rate,score_sum30,bundle_sha256"
        );
        assert_eq!(
            lines[1],
            r#"1,1-2,1,"team, ""a""",'=cmd|' /c calc'!A1,2,4,3,260.500,250.000,270.000,0.750,31260,abc"#
        );
        assert_eq!(
            lines[2],
            "1,1-2,1,b,'@sum,2,4,3,260.500,250.000,270.000,0.750,31260,abc"
        );
    }

    /// The close is one instant: a version whose upload passed every check before the
    /// close but reaches the database after it is not stored (the clock would never
    /// rank it), and one stored before it is ranked.
    #[tokio::test]
    async fn a_version_that_loses_the_race_with_the_close_is_not_stored() {
        for (db, _guard) in backends().await {
            let now = now_ms();
            let c = create(&db, spec(now), None).await.unwrap();
            let (e, v) = entered_bot(&db, &c).await;
            // Checked while open (no refusal), then the close passes before it is stored.
            let checked = check_upload(&db, v.bot_id, now).await.unwrap().unwrap();
            let stored = db
                .add_bot_version_within(v.bot_id, &plain_version(), &checked, None)
                .await
                .unwrap();
            assert!(stored.is_ok(), "{stored:?}");
            close_now(&db, c, now).await;
            let late = db
                .add_bot_version_within(v.bot_id, &plain_version(), &checked, None)
                .await
                .unwrap();
            assert!(
                matches!(&late, Err(crate::storage::bots::VersionRefusal::Closed { name, .. }) if name == "c"),
                "{late:?}"
            );
            let versions = db
                .submissions(
                    &db.get_competition("c").await.unwrap().unwrap(),
                    e.entrant_id,
                )
                .await
                .unwrap();
            assert_eq!(
                versions.len(),
                2,
                "the late one was not stored: {versions:?}"
            );
        }
    }

    #[tokio::test]
    async fn each_step_of_the_clock_happens_once_and_the_results_equal_a_recount() {
        for (db, _guard) in backends().await {
            let now = now_ms();
            let c = create(&db, spec(now), None).await.unwrap();
            assert!(sealed(&db, c.private_tournament_id).await);
            assert!(!sealed(&db, c.public_tournament_id).await);
            // A ranking maze must not be public, a practice maze not hidden.
            let mut bad = spec(now);
            bad.name = "d".into();
            bad.mazes.public = vec![maze(7001)];
            let err = create(&db, bad, None).await.unwrap_err();
            assert!(err.to_string().contains("must be hidden"), "{err}");
            let (_, v) = entered_bot(&db, &c).await;
            // Ranked once: 1 public maze x 2 repeats, every seed secret; no private match
            // before the close.
            assert_eq!(tick(&db, now).await.unwrap().ranked, 1);
            assert_eq!(tick(&db, now).await.unwrap(), TickReport::default());
            let seeds = c.seed_list();
            let queued = db
                .tournament_matches(c.public_tournament_id.unwrap())
                .await
                .unwrap();
            assert_eq!(queued.len(), 2);
            assert_eq!(
                queued.iter().map(|m| m.seed).collect::<Vec<_>>(),
                seeds[..2].to_vec()
            );
            let private_matches = db
                .tournament_matches(c.private_tournament_id.unwrap())
                .await
                .unwrap();
            assert!(private_matches.is_empty(), "{private_matches:?}");
            play_all(&db, 20.0).await;
            let public = board(&db, &c, BoardKind::Public, false, now).await.unwrap();
            assert_eq!(public.standings.len(), 1);
            for organiser in [false, true] {
                let private = board(&db, &c, BoardKind::Private, organiser, now)
                    .await
                    .unwrap();
                assert!(private.sealed && private.standings.is_empty());
                assert_eq!(private.final_run, None);
            }
            // Closed: the private set unsealed, the selection and final run made once.
            let c = close_now(&db, c, now).await;
            let later = now + 1;
            assert_eq!(tick(&db, later).await.unwrap().selected, 1);
            assert!(!sealed(&db, c.private_tournament_id).await);
            let c = db.get_competition("c").await.unwrap().unwrap();
            assert!(
                !db.start_final(&c, &[v.bot_version_id], &[], 7)
                    .await
                    .unwrap()
            );
            assert!(sealed(&db, c.final_tournament_id).await);
            // The final run: 2 private mazes x 1 repeat, with seeds of its own.
            let final_matches = db
                .tournament_matches(c.final_tournament_id.unwrap())
                .await
                .unwrap();
            assert_eq!(final_matches.len(), 2);
            assert!(final_matches.iter().all(|m| m.seed == seeds[2]));
            assert!(!seeds[..2].contains(&seeds[2]));
            assert_eq!(
                tick(&db, later).await.unwrap(),
                TickReport {
                    closing: 1,
                    ..TickReport::default()
                },
                "the final run waits"
            );
            let private = board(&db, &c, BoardKind::Private, true, later)
                .await
                .unwrap();
            assert!(private.sealed);
            assert_eq!(
                private.final_run,
                Some(RunProgress {
                    played: 0,
                    total: 2
                })
            );
            play_all(&db, 30.0).await;
            // Played: its organisers see it, nobody else until the results.
            let private = board(&db, &c, BoardKind::Private, true, later)
                .await
                .unwrap();
            assert!(!private.sealed);
            assert_eq!(private.standings[0].played, 2);
            let private = board(&db, &c, BoardKind::Private, false, later)
                .await
                .unwrap();
            assert!(private.sealed && private.standings.is_empty());
            assert_eq!(
                (private.final_run, private.final_run_playing),
                (None, true),
                "only the organisers see how far the final run has played"
            );
            assert_eq!(tick(&db, later).await.unwrap().finalized, 1);
            assert_eq!(tick(&db, later).await.unwrap(), TickReport::default());
            let c = db.get_competition("c").await.unwrap().unwrap();
            assert!(
                !db.write_results(&c, &[], &[]).await.unwrap(),
                "written once"
            );
            let results = db.competition_results(c.competition_id).await.unwrap();
            assert_eq!(results.len(), 1);
            assert_eq!((results[0].played, results[0].mean_score), (2, 30.0));
            assert!(recount_differences(&db, &c).await.unwrap().is_empty());
            assert!(!sealed(&db, c.final_tournament_id).await);
            // Revealed: the private mazes are public now.
            for m in db.competition_mazes(c.competition_id).await.unwrap() {
                let row = db.get_maze(m.maze_id).await.unwrap().unwrap();
                assert_eq!(row.hidden, m.maze_set == "public", "{}", m.name);
            }
            // A changed match record shows as a difference from the snapshot.
            db.run_sql_for_tests("update match set score = 31.0 where tournament_id is not null")
                .await;
            assert_eq!(recount_differences(&db, &c).await.unwrap().len(), 1);
        }
    }
}

/// Competition `c` as the files of a folder that `competition create` (or the
/// organiser's page) takes back: `competition.toml` naming `mazes/SET/NAME.txt`, and
/// those mazes; each as (relative path, text), the competition file first. Private and
/// public mazes are in it: it is for the competition's organisers only.
///
/// # Errors
/// [`RegistryError::Conflict`] for the default competition (nothing to export); a maze
/// gone; the database.
pub async fn export_files(storage: &Storage, c: &CompetitionRow) -> Result<Vec<(String, String)>> {
    let (Some(opens), Some(closes)) = (c.opens_at, c.closes_at) else {
        return Err(RegistryError::Conflict(
            "the default competition is the server's ranking: there is nothing to export".into(),
        ));
    };
    let mut sets: crate::competition::MazeSets<String> = crate::competition::MazeSets {
        practice: Vec::new(),
        public: Vec::new(),
        private: Vec::new(),
    };
    let mut mazes: Vec<(String, String)> = Vec::new();
    for m in storage.competition_mazes(c.competition_id).await? {
        let layout = storage
            .get_maze(m.maze_id)
            .await?
            .ok_or_else(|| RegistryError::Internal(format!("maze {} is gone", m.maze_id)))?
            .layout;
        let stem: String = m
            .name
            .chars()
            .map(|ch| {
                if ch.is_ascii_alphanumeric() || "-_.".contains(ch) {
                    ch
                } else {
                    '_'
                }
            })
            .collect();
        let stem = stem.trim_start_matches('.').to_string();
        let folder = format!("mazes/{}", m.maze_set);
        let mut rel = format!("{folder}/{stem}.txt");
        let mut n = 2;
        while mazes.iter().any(|(p, _)| *p == rel) {
            rel = format!("{folder}/{stem}-{n}.txt");
            n += 1;
        }
        match m.maze_set.as_str() {
            "practice" => sets.practice.push(rel.clone()),
            "public" => sets.public.push(rel.clone()),
            _ => sets.private.push(rel.clone()),
        }
        mazes.push((rel, layout));
    }
    let spec = Spec {
        name: c.name.clone(),
        title: c.title.clone(),
        description: c.description.clone(),
        rules: c.rules.clone(),
        opens_at: Timestamp(opens),
        closes_at: Timestamp(closes),
        freeze_hours: c.freeze_ms.map(|ms| ms as f64 / 3_600_000.0),
        repeats: c.repeats as u32,
        final_repeats: c.final_repeats as u32,
        versions_per_day: c.versions_per_day as u32,
        practice_per_day: c.practice_per_day as u32,
        selection: Rule::parse(&c.selection).unwrap_or_default(),
        max_selected: c.max_selected as u32,
        reveal_private_mazes: c.reveal_private_mazes,
        hold_results: c.hold_results,
        limits: c.limit_set(),
        validation: crate::competition::Validation::parse(&c.validation),
        mazes: sets,
    };
    let text = toml::to_string(&spec).map_err(|e| {
        RegistryError::Internal(format!("cannot write the competition as TOML: {e}"))
    })?;
    let mut files = vec![(
        "competition.toml".to_string(),
        format!(
            "# Exported by mazearena {}\n{text}",
            crate::runner::ENGINE_VERSION
        ),
    )];
    files.extend(mazes);
    Ok(files)
}

/// `files` (relative path, text) as a `.tar.gz` archive under folder `top`.
///
/// # Errors
/// Writing the archive in memory.
pub fn tar_gz(top: &str, files: &[(String, String)]) -> std::io::Result<Vec<u8>> {
    let gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    let mut tar = tar::Builder::new(gz);
    for (rel, text) in files {
        let mut header = tar::Header::new_gnu();
        header.set_size(text.len() as u64);
        header.set_mode(0o644);
        header.set_mtime(0);
        header.set_cksum();
        tar.append_data(&mut header, format!("{top}/{rel}"), text.as_bytes())?;
    }
    tar.into_inner()?.finish()
}

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
