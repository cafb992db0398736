//! Competitions: their rows and maze sets, organisers, entries, the versions queued on
//! the ranking sets, the boards, the quotas' counts and the final results.
//!
//! A competition's ranking matches live in tournaments of its own: one for the public
//! set, one for the final run (the private set's only matches, all played after the
//! close and sealed until the results), so that the running sums of `standing` give its
//! boards. The private set's own tournament is kept for competitions of earlier
//! versions, which played it before the close; none gets matches now.

mod boards;
mod entries;
mod final_run;
mod organisers;
mod rows;

use sqlx::FromRow;

/// A stored competition.
#[derive(Debug, Clone, PartialEq, FromRow)]
pub struct CompetitionRow {
    /// Id.
    pub competition_id: i64,
    /// Short unique name.
    pub name: String,
    /// Title.
    pub title: String,
    /// Description (text).
    pub description: String,
    /// Rules (text).
    pub rules: String,
    /// `default` (the server's general ranking) or `competition`.
    pub kind: String,
    /// Matches per version per ranking maze.
    pub repeats: i64,
    /// The final run's matches per selected version per private maze (0: `repeats`).
    pub final_repeats: i64,
    /// Match limits (JSON, [`crate::competition::Limits`]).
    pub limits: String,
    /// Opening (unix ms); `None` for the default competition.
    pub opens_at: Option<i64>,
    /// Close (unix ms); `None` for the default competition.
    pub closes_at: Option<i64>,
    /// Freeze before the close (ms).
    pub freeze_ms: Option<i64>,
    /// Versions per entrant per 24 hours.
    pub versions_per_day: i64,
    /// Practice matches per entrant per 24 hours.
    pub practice_per_day: i64,
    /// The final selection rule (`latest`, `best_public`, `choice`).
    pub selection: String,
    /// With `choice`: the most versions an entrant may choose.
    pub max_selected: i64,
    /// Whether the private mazes are shown once the results are final.
    #[sqlx(try_from = "super::Flag")]
    pub reveal_private_mazes: bool,
    /// Whether the results wait, once written, for an organiser to publish them
    /// (state `held` until then).
    #[sqlx(try_from = "super::Flag")]
    pub hold_results: bool,
    /// The secret seeds (JSON array), one per repeat index.
    pub seeds: String,
    /// `None` while open; `final_run` once the selection is made; `held` with results
    /// its organisers alone see (`hold_results`); `final` with published results.
    pub state: Option<String>,
    /// The public set's tournament.
    pub public_tournament_id: Option<i64>,
    /// The private set's tournament.
    pub private_tournament_id: Option<i64>,
    /// The final run's tournament.
    pub final_tournament_id: Option<i64>,
    /// When the results were written (unix ms).
    pub finalized_at: Option<i64>,
    /// Created at (unix ms).
    pub created_at: i64,
    /// The organiser it belongs to (`None`: the admin's).
    pub organiser_id: Option<i64>,
    /// Its own invite code (its organiser's to see), if it has one.
    pub invite_code: Option<String>,
    /// How each new version is checked: `start`, `match` or `off`
    /// ([`crate::competition::Validation`]).
    pub validation: String,
}

impl CompetitionRow {
    /// The seeds, one per repeat index.
    pub fn seed_list(&self) -> Vec<i64> {
        serde_json::from_str(&self.seeds).unwrap_or_default()
    }

    /// The match limits.
    pub fn limit_set(&self) -> crate::competition::Limits {
        serde_json::from_str(&self.limits).unwrap_or_default()
    }

    /// The final run's matches per selected version per private maze: `final_repeats`,
    /// or `repeats` where that is 0.
    pub fn final_run_repeats(&self) -> i64 {
        if self.final_repeats > 0 {
            self.final_repeats
        } else {
            self.repeats
        }
    }

    /// Its tournaments (public, private, final) that exist.
    pub fn tournaments(&self) -> Vec<i64> {
        [
            self.public_tournament_id,
            self.private_tournament_id,
            self.final_tournament_id,
        ]
        .into_iter()
        .flatten()
        .collect()
    }
}

pub(super) const COMPETITION_COLUMNS: &str =
    "competition_id, name, title, description, rules, kind, repeats,
    final_repeats, limits, opens_at, closes_at, freeze_ms, versions_per_day, practice_per_day,
    selection, max_selected, reveal_private_mazes, seeds, state, public_tournament_id,
    private_tournament_id, final_tournament_id, finalized_at, created_at, organiser_id,
    invite_code, validation, hold_results";

/// A maze of a competition.
#[derive(Debug, Clone, PartialEq, FromRow)]
pub struct CompetitionMaze {
    /// The maze.
    pub maze_id: i64,
    /// Its name.
    pub name: String,
    /// SHA-256 of its canonical text.
    pub hash: String,
    /// Its side.
    pub dim: i64,
    /// `practice`, `public` or `private`.
    pub maze_set: String,
    /// Its place in the set.
    pub position: i64,
}

/// An entered bot.
#[derive(Debug, Clone, PartialEq, FromRow)]
pub struct EntryRow {
    /// The bot.
    pub bot_id: i64,
    /// Its name.
    pub bot_name: String,
    /// Its entrant.
    pub entrant_id: i64,
    /// The entrant's name.
    pub entrant_name: String,
    /// Versions from this id on are ranked.
    pub first_version_id: i64,
    /// When it entered (unix ms).
    pub entered_at: i64,
}

/// One version's line on a board (a tournament of the competition).
#[derive(Debug, Clone, PartialEq, FromRow)]
pub struct BoardRow {
    /// The version.
    pub bot_version_id: i64,
    /// Its bot.
    pub bot_id: i64,
    /// The bot's name.
    pub bot_name: String,
    /// Its entrant (entered bots always have one).
    pub entrant_id: Option<i64>,
    /// The entrant's name.
    pub entrant_name: Option<String>,
    /// The version's number.
    pub version: i64,
    /// When the version was uploaded (unix ms).
    pub created_at: i64,
    /// Matches counted.
    pub played: i64,
    /// Of which finished.
    pub finished: i64,
    /// Sum of the scores in thirtieths of a step (a did-not-finish: 30,000).
    pub score_sum30: i64,
    /// Whether some of its matches there are still queued or running.
    #[sqlx(try_from = "super::Flag")]
    pub pending: bool,
}

/// One of an entrant's versions, for "my submissions" and the final selection.
#[derive(Debug, Clone, PartialEq, FromRow)]
pub struct SubmissionRow {
    /// The version.
    pub bot_version_id: i64,
    /// The bot.
    pub bot_id: i64,
    /// Its number.
    pub version: i64,
    /// Uploaded at (unix ms).
    pub created_at: i64,
    /// `ready`, `building` or `build_failed`.
    pub build_status: String,
    /// Whether it was queued on the ranking sets.
    #[sqlx(try_from = "super::Flag")]
    pub ranked: bool,
    /// Whether the entrant chose it for the final.
    #[sqlx(try_from = "super::Flag")]
    pub chosen: bool,
    /// Whether the final selection took it.
    #[sqlx(try_from = "super::Flag")]
    pub selected: bool,
    /// Whether any of its ranking matches was aborted (the server could not play it).
    #[sqlx(try_from = "super::Flag")]
    pub aborted: bool,
}

/// A row of the final results.
#[derive(Debug, Clone, PartialEq, FromRow, serde::Serialize, utoipa::ToSchema)]
pub struct ResultRow {
    /// 1 for the best; equal numbers share a rank.
    pub rank: i64,
    /// The entrant.
    pub entrant_id: i64,
    /// Its name.
    pub entrant_name: String,
    /// The bot.
    pub bot_id: i64,
    /// Its name.
    pub bot_name: String,
    /// The version that counted.
    pub bot_version_id: i64,
    /// Its number.
    pub version: i64,
    /// Matches counted.
    pub played: i64,
    /// Of which finished.
    pub finished: i64,
    /// Mean score, a did-not-finish counting as 1000, rounded to 3 decimals (the rank
    /// comes from the exact sum, `score_sum30`).
    #[sqlx(skip)]
    pub mean_score: f64,
    /// Sum of the scores in thirtieths of a step (a did-not-finish: 30,000): the exact
    /// mean is `score_sum30 / (30 x played)`.
    pub score_sum30: i64,
    /// finished / played, rounded to 3 decimals.
    #[sqlx(skip)]
    pub finish_rate: f64,
    /// What makes the row checkable and replayable (JSON): the version's bundle hash, the
    /// referee version, the mazes' hashes, the seeds, the limits, the recount.
    pub manifest: String,
    /// How sure the rank is (not stored: counted from the matches when read, by
    /// [`crate::registry::competitions::results`]).
    #[sqlx(skip)]
    pub uncertainty: crate::ranking::Uncertainty,
}

impl BoardRow {
    /// The exact mean score.
    pub fn mean(&self) -> crate::ranking::Mean {
        crate::ranking::Mean::new(self.score_sum30, self.played)
    }
}

impl ResultRow {
    /// The exact mean score.
    pub fn mean(&self) -> crate::ranking::Mean {
        crate::ranking::Mean::new(self.score_sum30, self.played)
    }

    /// Sets the shown numbers from the exact ones: the mean and the finish rate,
    /// rounded to 3 decimals.
    pub fn fill_shown(&mut self) {
        self.mean_score = self.mean().rounded();
        self.finish_rate = crate::ranking::mean::ratio_3dp(self.finished, self.played);
    }
}

/// The practice matches of entrant `$2` on competition `$1`'s practice mazes queued
/// after `$3` (the `from` and `where` of a query).
pub(crate) const PRACTICE_MATCHES: &str = "from match m join bot b on b.bot_id = m.bot_id
     where b.entrant_id = $2 and m.tournament_id is null and m.created_at > $3
         and m.maze_id in (select maze_id from competition_maze
                           where competition_id = $1 and maze_set = 'practice')";

/// The versions of entrant `$2` in competition `$1` uploaded after `$3` that count
/// against its version quota: not failed to build, none of their ranking matches
/// aborted (the `from` and `where` of a query).
pub(super) const COUNTED_VERSIONS: &str = "from bot_version v
     join competition_entry e on e.bot_id = v.bot_id and v.bot_version_id >= e.first_version_id
     where e.competition_id = $1 and e.entrant_id = $2 and v.created_at > $3
         and v.build_status not in ('build_failed', 'invalid')
         and not exists (select 1 from match m join tournament t on t.tournament_id = m.tournament_id
             where t.competition_id = $1 and m.bot_version_id = v.bot_version_id and m.status = 'aborted')";

/// A match to queue: version, maze, repeat, seed.
pub(super) type MatchToQueue = (i64, i64, i64, i64);
