//! Competitions: their rows and maze sets, organisers, entries, the versions queued on
//! the ranking sets, the boards, the quotas' counts and the final results.
//!
//! A competition's ranking matches live in tournaments of its own: one for the public
//! set, one for the final run (the private set's only matches, all played after the
//! close and sealed until the results), so that the running sums of `standing` give its
//! boards. The private set's own tournament is kept for competitions of earlier
//! versions, which played it before the close; none gets matches now.

use sqlx::FromRow;

use super::matches::PRIORITY_TOURNAMENT;
use super::{Result, Storage, StorageError, is_unique_violation, now_ms};
use crate::competition::Spec;

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

const COMPETITION_COLUMNS: &str = "competition_id, name, title, description, rules, kind, repeats,
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
const COUNTED_VERSIONS: &str = "from bot_version v
     join competition_entry e on e.bot_id = v.bot_id and v.bot_version_id >= e.first_version_id
     where e.competition_id = $1 and e.entrant_id = $2 and v.created_at > $3
         and v.build_status not in ('build_failed', 'invalid')
         and not exists (select 1 from match m join tournament t on t.tournament_id = m.tournament_id
             where t.competition_id = $1 and m.bot_version_id = v.bot_version_id and m.status = 'aborted')";

impl Storage {
    /// Creates a competition whose mazes are given by id, with its secret `seeds` (one
    /// per repeat index, the final run's after the ranking's), and its tournaments.
    ///
    /// # Errors
    /// [`StorageError::Conflict`] when the name is taken; database failures.
    pub async fn create_competition(
        &self,
        spec: &Spec<i64>,
        seeds: &[i64],
        organiser_id: Option<i64>,
    ) -> Result<CompetitionRow> {
        let _turn = self.write_turn().await;
        let now = now_ms();
        let limits = serde_json::to_string(&spec.limits).unwrap_or_else(|_| "{}".into());
        let seeds = serde_json::to_string(seeds).unwrap_or_else(|_| "[]".into());
        let mut tx = self.begin_write().await?;
        let mut tournaments = Vec::new();
        for (set, sealed) in [("public ranking", 0), ("private ranking", 1)] {
            let id: i64 = sqlx::query_scalar(
                "insert into tournament (name, repeats, created_at, sealed, limits)
                 values ($1, $2, $3, $4, $5) returning tournament_id",
            )
            .bind(format!("{}: {set}", spec.name))
            .bind(i64::from(spec.repeats))
            .bind(now)
            .bind(sealed)
            .bind(&limits)
            .fetch_one(&mut *tx)
            .await?;
            tournaments.push(id);
        }
        let id: i64 = sqlx::query_scalar(
            "insert into competition (name, title, description, rules, kind, repeats, final_repeats,
                 limits, opens_at, closes_at, freeze_ms, versions_per_day, practice_per_day,
                 selection, max_selected, reveal_private_mazes, seeds, public_tournament_id,
                 private_tournament_id, created_at, organiser_id, validation, hold_results)
             values ($1, $2, $3, $4, 'competition', $5, $6, $7, $8, $9, $10, $11, $12, $13, $14,
                 $15, $16, $17, $18, $19, $20, $21, $22)
             returning competition_id",
        )
        .bind(&spec.name)
        .bind(&spec.title)
        .bind(&spec.description)
        .bind(&spec.rules)
        .bind(i64::from(spec.repeats))
        .bind(i64::from(spec.final_repeats))
        .bind(&limits)
        .bind(spec.opens_at.0)
        .bind(spec.closes_at.0)
        .bind(spec.freeze_ms())
        .bind(i64::from(spec.versions_per_day))
        .bind(i64::from(spec.practice_per_day))
        .bind(spec.selection.as_str())
        .bind(i64::from(spec.max_selected))
        .bind(i64::from(spec.reveal_private_mazes))
        .bind(&seeds)
        .bind(tournaments[0])
        .bind(tournaments[1])
        .bind(now)
        .bind(organiser_id)
        .bind(spec.validation.as_str())
        .bind(i64::from(spec.hold_results))
        .fetch_one(&mut *tx)
        .await
        .map_err(|e| {
            if is_unique_violation(&e) {
                StorageError::Conflict(format!("a competition named {:?} exists already (names that differ only in case are one name)", spec.name))
            } else {
                e.into()
            }
        })?;
        sqlx::query("update tournament set competition_id = $1 where tournament_id in ($2, $3)")
            .bind(id)
            .bind(tournaments[0])
            .bind(tournaments[1])
            .execute(&mut *tx)
            .await?;
        let sets = [
            ("practice", &spec.mazes.practice),
            ("public", &spec.mazes.public),
            ("private", &spec.mazes.private),
        ];
        for (set, ids) in sets {
            for (position, maze_id) in ids.iter().enumerate() {
                sqlx::query(
                    "insert into competition_maze (competition_id, maze_id, maze_set, position)
                     values ($1, $2, $3, $4)",
                )
                .bind(id)
                .bind(maze_id)
                .bind(set)
                .bind(position as i64)
                .execute(&mut *tx)
                .await
                .map_err(|e| {
                    if is_unique_violation(&e) {
                        StorageError::Conflict(format!(
                            "maze {maze_id} is given twice: a maze belongs to one set"
                        ))
                    } else {
                        e.into()
                    }
                })?;
            }
        }
        tx.commit().await?;
        Ok(self
            .get_competition(&spec.name)
            .await?
            .expect("the competition was just created"))
    }

    /// The competition named `name`.
    ///
    /// # Errors
    /// Database failures.
    pub async fn get_competition(&self, name: &str) -> Result<Option<CompetitionRow>> {
        Ok(sqlx::query_as(&format!(
            "select {COMPETITION_COLUMNS} from competition where name = $1"
        ))
        .bind(name)
        .fetch_optional(self.pool())
        .await?)
    }

    /// The competition `competition_id`.
    ///
    /// # Errors
    /// Database failures.
    pub async fn get_competition_by_id(
        &self,
        competition_id: i64,
    ) -> Result<Option<CompetitionRow>> {
        Ok(sqlx::query_as(&format!(
            "select {COMPETITION_COLUMNS} from competition where competition_id = $1"
        ))
        .bind(competition_id)
        .fetch_optional(self.pool())
        .await?)
    }

    /// Every competition, the default one first, then newest first.
    ///
    /// # Errors
    /// Database failures.
    pub async fn list_competitions(&self) -> Result<Vec<CompetitionRow>> {
        Ok(sqlx::query_as(&format!(
            "select {COMPETITION_COLUMNS} from competition
             order by case when kind = 'default' then 0 else 1 end, competition_id desc"
        ))
        .fetch_all(self.pool())
        .await?)
    }

    /// Writes a competition's editable settings (title, texts, times, quotas, selection,
    /// final run, reveal, limits) as `row` holds them, its tournaments' limits with them.
    ///
    /// # Errors
    /// Database failures.
    pub async fn save_competition_settings(&self, row: &CompetitionRow) -> Result<()> {
        let _turn = self.write_turn().await;
        let mut tx = self.begin_write().await?;
        sqlx::query(
            "update competition set title = $2, description = $3, rules = $4, opens_at = $5,
                 closes_at = $6, freeze_ms = $7, versions_per_day = $8, practice_per_day = $9,
                 selection = $10, max_selected = $11, final_repeats = $12,
                 reveal_private_mazes = $13, limits = $14, validation = $15, hold_results = $16
             where competition_id = $1",
        )
        .bind(row.competition_id)
        .bind(&row.title)
        .bind(&row.description)
        .bind(&row.rules)
        .bind(row.opens_at)
        .bind(row.closes_at)
        .bind(row.freeze_ms)
        .bind(row.versions_per_day)
        .bind(row.practice_per_day)
        .bind(&row.selection)
        .bind(row.max_selected)
        .bind(row.final_repeats)
        .bind(i64::from(row.reveal_private_mazes))
        .bind(&row.limits)
        .bind(&row.validation)
        .bind(i64::from(row.hold_results))
        .execute(&mut *tx)
        .await?;
        sqlx::query("update tournament set limits = $2 where competition_id = $1")
            .bind(row.competition_id)
            .bind(&row.limits)
            .execute(&mut *tx)
            .await?;
        tx.commit().await?;
        Ok(())
    }

    /// A competition's mazes, set by set (practice, public, private), in order.
    ///
    /// # Errors
    /// Database failures.
    pub async fn competition_mazes(&self, competition_id: i64) -> Result<Vec<CompetitionMaze>> {
        Ok(sqlx::query_as(
            "select z.maze_id, z.name, z.hash, z.dim, c.maze_set, c.position
             from competition_maze c join maze z on z.maze_id = c.maze_id
             where c.competition_id = $1
             order by case c.maze_set when 'practice' then 0 when 'public' then 1 else 2 end, c.position",
        )
        .bind(competition_id)
        .fetch_all(self.pool())
        .await?)
    }

    /// Whether a competition other than `competition_id` whose results are not final
    /// uses maze `maze_id` (its layout must then stay hidden).
    ///
    /// # Errors
    /// Database failures.
    pub async fn maze_in_other_live_competition(
        &self,
        maze_id: i64,
        competition_id: i64,
    ) -> Result<bool> {
        let n: i64 = sqlx::query_scalar(
            "select count(*) from competition_maze m join competition c on c.competition_id = m.competition_id
             where m.maze_id = $1 and m.competition_id <> $2 and coalesce(c.state, '') <> 'final'",
        )
        .bind(maze_id)
        .bind(competition_id)
        .fetch_one(self.pool())
        .await?;
        Ok(n > 0)
    }

    /// Whether maze `maze_id` is in the public or private set of a competition.
    ///
    /// # Errors
    /// Database failures.
    pub async fn maze_ranks_in_a_competition(&self, maze_id: i64) -> Result<bool> {
        let n: i64 = sqlx::query_scalar(
            "select count(*) from competition_maze where maze_id = $1 and maze_set <> 'practice'",
        )
        .bind(maze_id)
        .fetch_one(self.pool())
        .await?;
        Ok(n > 0)
    }

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

    /// Sets competition `competition_id`'s own invite code to `code` (with its SHA-256
    /// `hash`), or removes it (`None`): the old code stops working at once.
    ///
    /// # Errors
    /// [`StorageError::Conflict`] when another competition has that code; database
    /// failures.
    pub async fn set_competition_invite(
        &self,
        competition_id: i64,
        code: Option<(&str, &str)>,
    ) -> Result<()> {
        let _turn = self.write_turn().await;
        sqlx::query(
            "update competition set invite_code = $1, invite_hash = $2 where competition_id = $3",
        )
        .bind(code.map(|c| c.0))
        .bind(code.map(|c| c.1))
        .bind(competition_id)
        .execute(self.pool())
        .await
        .map_err(|e| {
            if is_unique_violation(&e) {
                StorageError::Conflict(
                    "another competition has this invite code: choose another".into(),
                )
            } else {
                e.into()
            }
        })?;
        Ok(())
    }

    /// The competition whose own invite code has SHA-256 `hash`.
    ///
    /// # Errors
    /// Database failures.
    pub async fn competition_by_invite(&self, hash: &str) -> Result<Option<CompetitionRow>> {
        Ok(sqlx::query_as(&format!(
            "select {COMPETITION_COLUMNS} from competition where invite_hash = $1"
        ))
        .bind(hash)
        .fetch_optional(self.pool())
        .await?)
    }

    /// Adds maze `maze_id` to competition `competition_id`'s practice set, last.
    ///
    /// # Errors
    /// [`StorageError::Conflict`] when the maze is in the competition already; database
    /// failures.
    pub async fn add_practice_maze(&self, competition_id: i64, maze_id: i64) -> Result<()> {
        let _turn = self.write_turn().await;
        sqlx::query(
            "insert into competition_maze (competition_id, maze_id, maze_set, position)
             values ($1, $2, 'practice',
                 (select coalesce(max(position), -1) + 1 from competition_maze
                  where competition_id = $1 and maze_set = 'practice'))",
        )
        .bind(competition_id)
        .bind(maze_id)
        .execute(self.pool())
        .await
        .map_err(|e| {
            if is_unique_violation(&e) {
                StorageError::Conflict("this maze is in the competition already".into())
            } else {
                e.into()
            }
        })?;
        Ok(())
    }

    /// Removes maze `maze_id` from competition `competition_id`'s practice set (its
    /// matches stay). Returns false if it is not one of its practice mazes.
    ///
    /// # Errors
    /// Database failures.
    pub async fn remove_practice_maze(&self, competition_id: i64, maze_id: i64) -> Result<bool> {
        let _turn = self.write_turn().await;
        Ok(sqlx::query(
            "delete from competition_maze
             where competition_id = $1 and maze_id = $2 and maze_set = 'practice'",
        )
        .bind(competition_id)
        .bind(maze_id)
        .execute(self.pool())
        .await?
        .rows_affected()
            > 0)
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

    /// The competitions entrant `entrant_id` has a bot entered in.
    ///
    /// # Errors
    /// Database failures.
    pub async fn competitions_of_entrant(&self, entrant_id: i64) -> Result<Vec<CompetitionRow>> {
        Ok(sqlx::query_as(&format!(
            "select {COMPETITION_COLUMNS} from competition where competition_id in
                 (select competition_id from competition_entry where entrant_id = $1)"
        ))
        .bind(entrant_id)
        .fetch_all(self.pool())
        .await?)
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

    /// Enters `bot_id` of `entrant_id` into a competition: its versions from its latest
    /// on (or its first, if it has none yet) are ranked.
    ///
    /// # Errors
    /// [`StorageError::Conflict`] when the entrant has a bot entered already; database
    /// failures.
    pub async fn enter_competition(
        &self,
        competition_id: i64,
        bot_id: i64,
        entrant_id: i64,
    ) -> Result<()> {
        let _turn = self.write_turn().await;
        sqlx::query(
            "insert into competition_entry (competition_id, bot_id, entrant_id, first_version_id, entered_at)
             values ($1, $2, $3,
                 coalesce((select max(bot_version_id) from bot_version where bot_id = $2), 0), $4)",
        )
        .bind(competition_id)
        .bind(bot_id)
        .bind(entrant_id)
        .bind(now_ms())
        .execute(self.pool())
        .await
        .map_err(|e| {
            if is_unique_violation(&e) {
                StorageError::Conflict(
                    "this entrant has a bot in this competition already (one bot per entrant)".into(),
                )
            } else {
                e.into()
            }
        })?;
        Ok(())
    }

    /// The entrant bot `bot_id` belongs to, if any.
    ///
    /// # Errors
    /// Database failures.
    pub async fn entrant_of_bot(&self, bot_id: i64) -> Result<Option<i64>> {
        Ok(
            sqlx::query_scalar::<_, Option<i64>>("select entrant_id from bot where bot_id = $1")
                .bind(bot_id)
                .fetch_optional(self.pool())
                .await?
                .flatten(),
        )
    }

    /// The entrant that entered bot `bot_id` in competition `competition_id`, if it is.
    ///
    /// # Errors
    /// Database failures.
    pub async fn entrant_of_entry(&self, competition_id: i64, bot_id: i64) -> Result<Option<i64>> {
        Ok(sqlx::query_scalar(
            "select entrant_id from competition_entry where competition_id = $1 and bot_id = $2",
        )
        .bind(competition_id)
        .bind(bot_id)
        .fetch_optional(self.pool())
        .await?)
    }

    /// The versions the final selection of a competition took.
    ///
    /// # Errors
    /// Database failures.
    pub async fn selected_versions(&self, competition_id: i64) -> Result<Vec<i64>> {
        Ok(sqlx::query_scalar(
            "select bot_version_id from competition_version where competition_id = $1 and selected = 1",
        )
        .bind(competition_id)
        .fetch_all(self.pool())
        .await?)
    }

    /// The bots entered in a competition, by entrant name.
    ///
    /// # Errors
    /// Database failures.
    pub async fn competition_entries(&self, competition_id: i64) -> Result<Vec<EntryRow>> {
        Ok(sqlx::query_as(
            "select e.bot_id, b.name as bot_name, e.entrant_id, n.name as entrant_name,
                 e.first_version_id, e.entered_at
             from competition_entry e join bot b on b.bot_id = e.bot_id
             join entrant n on n.entrant_id = e.entrant_id
             where e.competition_id = $1 order by n.name",
        )
        .bind(competition_id)
        .fetch_all(self.pool())
        .await?)
    }

    /// The competitions (not the default one) bot `bot_id` is entered in.
    ///
    /// # Errors
    /// Database failures.
    pub async fn competitions_of_bot(&self, bot_id: i64) -> Result<Vec<CompetitionRow>> {
        Ok(sqlx::query_as(&format!(
            "select {COMPETITION_COLUMNS} from competition where competition_id in
                 (select competition_id from competition_entry where bot_id = $1)"
        ))
        .bind(bot_id)
        .fetch_all(self.pool())
        .await?)
    }

    /// The ready versions of entered bots that open competitions (opened by `now`, not
    /// yet selected) have still to queue on their ranking sets: (competition, version).
    /// A version uploaded after the close never is.
    ///
    /// # Errors
    /// Database failures.
    pub async fn versions_to_rank(&self, now: i64) -> Result<Vec<(i64, i64)>> {
        Ok(sqlx::query_as(
            "select c.competition_id, v.bot_version_id from competition c
             join competition_entry e on e.competition_id = c.competition_id
             join bot_version v on v.bot_id = e.bot_id and v.bot_version_id >= e.first_version_id
             where c.kind = 'competition' and c.state is null and c.opens_at <= $1
                 and v.created_at < c.closes_at and v.build_status = 'ready'
                 and not exists (select 1 from competition_version x
                     where x.competition_id = c.competition_id and x.bot_version_id = v.bot_version_id)
             order by v.bot_version_id",
        )
        .bind(now)
        .fetch_all(self.pool())
        .await?)
    }

    /// Queues version `bot_version_id` on a competition's public ranking set (`public`
    /// maze ids), every repeat with its secret seed. The private set is never played
    /// before the close: its only matches are the final run's ([`Storage::start_final`]).
    /// Returns false if it was queued already.
    ///
    /// # Errors
    /// Database failures.
    pub async fn rank_version(
        &self,
        c: &CompetitionRow,
        bot_version_id: i64,
        public: &[i64],
    ) -> Result<bool> {
        let _turn = self.write_turn().await;
        let now = now_ms();
        let mut tx = self.begin_write().await?;
        let added = sqlx::query(
            "insert into competition_version (competition_id, bot_version_id, ranked_at)
             values ($1, $2, $3) on conflict do nothing",
        )
        .bind(c.competition_id)
        .bind(bot_version_id)
        .bind(now)
        .execute(&mut *tx)
        .await?
        .rows_affected();
        if added == 0 {
            return Ok(false);
        }
        if let Some(tournament) = c.public_tournament_id {
            queue_matches(
                &mut tx,
                tournament,
                bot_version_id,
                public,
                0..c.repeats,
                &c.seed_list(),
                now,
            )
            .await?;
        }
        tx.commit().await?;
        Ok(true)
    }

    /// How many of an entrant's versions in a competition since `since` count against
    /// its quota (as [`Storage::counted_version_times`]), read in transaction `tx`.
    pub(crate) async fn count_counted_versions_in(
        tx: &mut sqlx::AnyConnection,
        competition_id: i64,
        entrant_id: i64,
        since: i64,
    ) -> Result<i64> {
        Ok(sqlx::query_scalar(&format!(
            "select cast(count(*) as bigint) {COUNTED_VERSIONS}"
        ))
        .bind(competition_id)
        .bind(entrant_id)
        .bind(since)
        .fetch_one(&mut *tx)
        .await?)
    }

    /// The upload times of an entrant's versions in a competition since `since` that
    /// count against its quota: not failed to build, none of their ranking matches
    /// aborted.
    ///
    /// # Errors
    /// Database failures.
    pub async fn counted_version_times(
        &self,
        c: &CompetitionRow,
        entrant_id: i64,
        since: i64,
    ) -> Result<Vec<i64>> {
        Ok(
            sqlx::query_scalar(&format!("select v.created_at {COUNTED_VERSIONS}"))
                .bind(c.competition_id)
                .bind(entrant_id)
                .bind(since)
                .fetch_all(self.pool())
                .await?,
        )
    }

    /// When an entrant's practice matches on a competition's practice mazes since
    /// `since` were queued.
    ///
    /// # Errors
    /// Database failures.
    pub async fn practice_times(
        &self,
        competition_id: i64,
        entrant_id: i64,
        since: i64,
    ) -> Result<Vec<i64>> {
        Ok(
            sqlx::query_scalar(&format!("select m.created_at {PRACTICE_MATCHES}"))
                .bind(competition_id)
                .bind(entrant_id)
                .bind(since)
                .fetch_all(self.pool())
                .await?,
        )
    }

    /// Every version's line in tournament `tournament_id`, from the running sums; with
    /// `recount`, counted from the match table itself instead (to check the sums).
    ///
    /// # Errors
    /// Database failures.
    pub async fn competition_board(
        &self,
        tournament_id: i64,
        recount: bool,
    ) -> Result<Vec<BoardRow>> {
        let sums = if recount {
            format!(
                "select m.bot_version_id, count(*) as played,
                     sum(case when m.status = 'finished' then 1 else 0 end) as finished,
                     sum(case when m.status = 'finished' then cast(round(m.score * 30) as bigint)
                         else {dnf} end) as score_sum30
                 from match m where m.tournament_id = $1 and m.status not in ('queued', 'running')
                 group by m.bot_version_id",
                dnf = crate::ranking::mean::DNF_THIRTIETHS
            )
        } else {
            "select bot_version_id, sum(played) as played, sum(finished) as finished,
                 sum(score_sum30) as score_sum30
             from standing where tournament_id = $1 group by bot_version_id"
                .to_string()
        };
        Ok(sqlx::query_as(&format!(
            "select v.bot_version_id, v.bot_id, b.name as bot_name, b.entrant_id, n.name as entrant_name,
                 v.version, v.created_at, cast(s.played as bigint) as played,
                 cast(s.finished as bigint) as finished,
                 cast(s.score_sum30 as bigint) as score_sum30,
                 case when exists (select 1 from match p where p.tournament_id = $1
                     and p.bot_version_id = v.bot_version_id and p.status in ('queued', 'running'))
                     then 1 else 0 end as pending
             from ({sums}) s
             join bot_version v on v.bot_version_id = s.bot_version_id
             join bot b on b.bot_id = v.bot_id
             left join entrant n on n.entrant_id = b.entrant_id
             where s.played > 0
             order by 1.0 * s.score_sum30 / s.played asc, 1.0 * s.finished / s.played desc,
                 b.name asc, v.version desc"
        ))
        .bind(tournament_id)
        .fetch_all(self.pool())
        .await?)
    }

    /// An entrant's versions in a competition, newest first, with where each stands.
    ///
    /// # Errors
    /// Database failures.
    pub async fn submissions(
        &self,
        c: &CompetitionRow,
        entrant_id: i64,
    ) -> Result<Vec<SubmissionRow>> {
        Ok(sqlx::query_as(
            "select v.bot_version_id, v.bot_id, v.version, v.created_at, v.build_status,
                 case when x.bot_version_id is null then 0 else 1 end as ranked,
                 coalesce(x.chosen, 0) as chosen, coalesce(x.selected, 0) as selected,
                 case when exists (select 1 from match m join tournament t on t.tournament_id = m.tournament_id
                     where t.competition_id = $1 and m.bot_version_id = v.bot_version_id
                         and m.status = 'aborted') then 1 else 0 end as aborted
             from bot_version v
             join competition_entry e on e.bot_id = v.bot_id and v.bot_version_id >= e.first_version_id
             left join competition_version x on x.competition_id = e.competition_id
                 and x.bot_version_id = v.bot_version_id
             where e.competition_id = $1 and e.entrant_id = $2
             order by v.bot_version_id desc",
        )
        .bind(c.competition_id)
        .bind(entrant_id)
        .fetch_all(self.pool())
        .await?)
    }

    /// Marks an entrant's chosen versions for the final (the others unchosen).
    ///
    /// # Errors
    /// Database failures.
    pub async fn choose_versions(
        &self,
        c: &CompetitionRow,
        entrant_id: i64,
        version_ids: &[i64],
    ) -> Result<()> {
        let _turn = self.write_turn().await;
        let mut tx = self.begin_write().await?;
        sqlx::query(
            "update competition_version set chosen = 0 where competition_id = $1 and bot_version_id in
                 (select v.bot_version_id from bot_version v join competition_entry e on e.bot_id = v.bot_id
                  where e.competition_id = $1 and e.entrant_id = $2)",
        )
        .bind(c.competition_id)
        .bind(entrant_id)
        .execute(&mut *tx)
        .await?;
        for id in version_ids {
            sqlx::query(
                "update competition_version set chosen = 1 where competition_id = $1 and bot_version_id = $2",
            )
            .bind(c.competition_id)
            .bind(id)
            .execute(&mut *tx)
            .await?;
        }
        tx.commit().await?;
        Ok(())
    }

    /// How much of a closed competition is still to happen before its selection: matches
    /// of its tournaments queued or running, and for each entered bot, its newest version
    /// uploaded before the close if that is still waiting for its build (the builders
    /// take those first: [`super::builds::FAIR_BUILD_ORDER`]). An older version still
    /// building is superseded and does not hold the close: an entrant who uploads several
    /// versions at the deadline holds it for one build at most.
    ///
    /// # Errors
    /// Database failures.
    pub async fn competition_work_left(&self, c: &CompetitionRow) -> Result<i64> {
        Ok(sqlx::query_scalar(
            "select (select count(*) from match m join tournament t on t.tournament_id = m.tournament_id
                     where t.competition_id = $1 and m.status in ('queued', 'running'))
                  + (select count(*) from bot_version v
                     join competition_entry e on e.bot_id = v.bot_id and v.bot_version_id >= e.first_version_id
                     where e.competition_id = $1 and v.build_status = 'building' and v.created_at < $2
                         and v.bot_version_id = (select max(w.bot_version_id) from bot_version w
                                                 where w.bot_id = v.bot_id and w.created_at < $2))",
        )
        .bind(c.competition_id)
        .bind(c.closes_at.unwrap_or(0))
        .fetch_one(self.pool())
        .await?)
    }

    /// Unseals a competition's private set (its close has passed). Reads first, so that
    /// the clock's every tick after the close writes nothing once it is done.
    ///
    /// # Errors
    /// Database failures.
    pub async fn unseal_private_set(&self, c: &CompetitionRow) -> Result<()> {
        let Some(t) = c.private_tournament_id else {
            return Ok(());
        };
        if !self.get_tournament(t).await?.is_some_and(|t| t.sealed) {
            return Ok(());
        }
        let _turn = self.write_turn().await;
        sqlx::query("update tournament set sealed = 0 where tournament_id = $1 and sealed = 1")
            .bind(c.private_tournament_id)
            .execute(self.pool())
            .await?;
        Ok(())
    }

    /// Records the final selection and queues the final run of the `selected` versions
    /// on the private mazes ([`CompetitionRow::final_run_repeats`] each, with seeds of
    /// their own: the repeat indexes after the public set's), in a sealed tournament:
    /// the private set's only matches, queued in an order shuffled by `order` (a random
    /// number: matches are played in the order they were queued, so that no one can
    /// tell which entrant's match is playing from how far the run is). Returns false if
    /// another server did it first.
    ///
    /// # Errors
    /// Database failures.
    pub async fn start_final(
        &self,
        c: &CompetitionRow,
        selected: &[i64],
        private: &[i64],
        order: u64,
    ) -> Result<bool> {
        let _turn = self.write_turn().await;
        let now = now_ms();
        let mut tx = self.begin_write().await?;
        let moved = sqlx::query(
            "update competition set state = 'final_run' where competition_id = $1 and state is null",
        )
        .bind(c.competition_id)
        .execute(&mut *tx)
        .await?
        .rows_affected();
        if moved == 0 {
            return Ok(false);
        }
        for id in selected {
            sqlx::query(
                "update competition_version set selected = 1 where competition_id = $1 and bot_version_id = $2",
            )
            .bind(c.competition_id)
            .bind(id)
            .execute(&mut *tx)
            .await?;
        }
        let repeats = c.final_run_repeats();
        if !selected.is_empty() && !private.is_empty() {
            let t: i64 = sqlx::query_scalar(
                "insert into tournament (name, repeats, created_at, sealed, limits, competition_id)
                 values ($1, $2, $3, 1, $4, $5) returning tournament_id",
            )
            .bind(format!("{}: final run", c.name))
            .bind(repeats)
            .bind(now)
            .bind(&c.limits)
            .bind(c.competition_id)
            .fetch_one(&mut *tx)
            .await?;
            let seeds = c.seed_list();
            let mut rows: Vec<MatchToQueue> = selected
                .iter()
                .flat_map(|&id| match_rows(id, private, c.repeats..c.repeats + repeats, &seeds))
                .collect();
            shuffle(&mut rows, order);
            insert_matches(&mut tx, t, &rows, now).await?;
            sqlx::query(
                "update competition set final_tournament_id = $2 where competition_id = $1",
            )
            .bind(c.competition_id)
            .bind(t)
            .execute(&mut *tx)
            .await?;
        }
        tx.commit().await?;
        Ok(true)
    }

    /// Writes the results of competition `c` (in its final run) in one transaction:
    /// `held` for its organisers alone when it holds them (`hold_results`), else published
    /// at once ([`Storage::publish_results`]'s work: `final`, its tournaments unsealed,
    /// `reveal`'s mazes shown). False when another server wrote them first.
    ///
    /// # Errors
    /// Database failures.
    pub async fn write_results(
        &self,
        c: &CompetitionRow,
        rows: &[ResultRow],
        reveal: &[i64],
    ) -> Result<bool> {
        let _turn = self.write_turn().await;
        let mut tx = self.begin_write().await?;
        let state = if c.hold_results { "held" } else { "final" };
        let moved = sqlx::query(
            "update competition set state = $3, finalized_at = $2
             where competition_id = $1 and state = 'final_run'",
        )
        .bind(c.competition_id)
        .bind(now_ms())
        .bind(state)
        .execute(&mut *tx)
        .await?
        .rows_affected();
        if moved == 0 {
            return Ok(false);
        }
        for r in rows {
            sqlx::query(
                "insert into competition_result (competition_id, rank, entrant_id, entrant_name, bot_id,
                     bot_name, bot_version_id, version, played, finished, mean_score, finish_rate, manifest,
                     score_sum30)
                 values ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12, $13, $14)",
            )
            .bind(c.competition_id)
            .bind(r.rank)
            .bind(r.entrant_id)
            .bind(&r.entrant_name)
            .bind(r.bot_id)
            .bind(&r.bot_name)
            .bind(r.bot_version_id)
            .bind(r.version)
            .bind(r.played)
            .bind(r.finished)
            .bind(r.mean_score)
            .bind(r.finish_rate)
            .bind(&r.manifest)
            .bind(r.score_sum30)
            .execute(&mut *tx)
            .await?;
        }
        if !c.hold_results {
            open_results(&mut tx, c.competition_id, reveal).await?;
        }
        tx.commit().await?;
        Ok(true)
    }

    /// Publishes the held results of competition `c`: `final`, its tournaments unsealed,
    /// `reveal`'s mazes shown. False when they were not held (published already, or not
    /// written).
    ///
    /// # Errors
    /// Database failures.
    pub async fn publish_results(&self, c: &CompetitionRow, reveal: &[i64]) -> Result<bool> {
        let _turn = self.write_turn().await;
        let mut tx = self.begin_write().await?;
        let moved = sqlx::query(
            "update competition set state = 'final' where competition_id = $1 and state = 'held'",
        )
        .bind(c.competition_id)
        .execute(&mut *tx)
        .await?
        .rows_affected();
        if moved == 0 {
            return Ok(false);
        }
        open_results(&mut tx, c.competition_id, reveal).await?;
        tx.commit().await?;
        Ok(true)
    }

    /// A competition's final results, best first.
    ///
    /// # Errors
    /// Database failures.
    pub async fn competition_results(&self, competition_id: i64) -> Result<Vec<ResultRow>> {
        let mut rows: Vec<ResultRow> = sqlx::query_as(
            "select rank, entrant_id, entrant_name, bot_id, bot_name, bot_version_id, version, played,
                 finished, score_sum30, manifest
             from competition_result where competition_id = $1 order by rank, entrant_name",
        )
        .bind(competition_id)
        .fetch_all(self.pool())
        .await?;
        for r in &mut rows {
            r.fill_shown();
        }
        Ok(rows)
    }

    /// How far tournament `tournament_id` has played: (matches played, matches in it).
    ///
    /// # Errors
    /// Database failures.
    pub async fn tournament_progress(&self, tournament_id: i64) -> Result<(i64, i64)> {
        Ok(sqlx::query_as(
            "select cast(coalesce(sum(case when status in ('queued', 'running') then 0 else 1 end), 0) as bigint),
                 cast(count(*) as bigint)
             from match where tournament_id = $1",
        )
        .bind(tournament_id)
        .fetch_one(self.pool())
        .await?)
    }

    /// The seeds of a tournament's matches, by repeat index.
    ///
    /// # Errors
    /// Database failures.
    pub async fn tournament_seeds(&self, tournament_id: i64) -> Result<Vec<(i64, i64)>> {
        Ok(sqlx::query_as(
            "select distinct repeat, seed from match where tournament_id = $1 order by repeat",
        )
        .bind(tournament_id)
        .fetch_all(self.pool())
        .await?)
    }
}

/// Queues `bot_version_id` on `mazes` in tournament `tournament`, repeat indexes
/// `repeats` with `seeds[r]` (the repeat index itself past the list's end).
async fn queue_matches(
    tx: &mut sqlx::Transaction<'_, sqlx::Any>,
    tournament: i64,
    bot_version_id: i64,
    mazes: &[i64],
    repeats: std::ops::Range<i64>,
    seeds: &[i64],
    now: i64,
) -> Result<()> {
    let rows = match_rows(bot_version_id, mazes, repeats, seeds);
    insert_matches(tx, tournament, &rows, now).await
}

/// A match to queue: version, maze, repeat, seed.
type MatchToQueue = (i64, i64, i64, i64);

/// The matches of version `bot_version_id` on `mazes`, each repeat in `repeats` with
/// its seed (the repeat's index in `seeds`).
fn match_rows(
    bot_version_id: i64,
    mazes: &[i64],
    repeats: std::ops::Range<i64>,
    seeds: &[i64],
) -> Vec<MatchToQueue> {
    repeats
        .flat_map(|r| {
            let seed = seeds.get(r as usize).copied().unwrap_or(r);
            mazes.iter().map(move |&z| (bot_version_id, z, r, seed))
        })
        .collect()
}

/// Shuffles `rows` (Fisher-Yates) with a generator seeded by `order`.
fn shuffle<T>(rows: &mut [T], order: u64) {
    let mut rng = oorandom::Rand64::new(u128::from(order));
    for i in (1..rows.len()).rev() {
        let j = rng.rand_range(0..(i as u64 + 1)) as usize;
        rows.swap(i, j);
    }
}

/// Queues `rows` in tournament `tournament`, in their order (matches are played in the
/// order they were queued).
async fn insert_matches(
    tx: &mut sqlx::Transaction<'_, sqlx::Any>,
    tournament: i64,
    rows: &[MatchToQueue],
    now: i64,
) -> Result<()> {
    for chunk in rows.chunks(super::ROWS_PER_INSERT) {
        let sql = format!(
            "insert into match (bot_version_id, maze_id, seed, tournament_id, repeat, priority, created_at)
             values {} on conflict do nothing",
            super::placeholders(chunk.len(), 7)
        );
        let mut query = sqlx::query(&sql);
        for &(bot_version_id, maze_id, repeat, seed) in chunk {
            query = query
                .bind(bot_version_id)
                .bind(maze_id)
                .bind(seed)
                .bind(tournament)
                .bind(repeat)
                .bind(PRIORITY_TOURNAMENT)
                .bind(now);
        }
        query.execute(&mut **tx).await?;
    }
    Ok(())
}

/// What publishing results opens: the competition's tournaments unsealed, `reveal`'s
/// mazes shown.
async fn open_results(
    tx: &mut sqlx::Transaction<'_, sqlx::Any>,
    competition_id: i64,
    reveal: &[i64],
) -> Result<()> {
    sqlx::query("update tournament set sealed = 0 where competition_id = $1")
        .bind(competition_id)
        .execute(&mut **tx)
        .await?;
    for maze_id in reveal {
        sqlx::query("update maze set hidden = 0 where maze_id = $1")
            .bind(maze_id)
            .execute(&mut **tx)
            .await?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{match_rows, shuffle};

    #[test]
    fn the_final_runs_order_is_a_permutation_that_its_random_number_decides() {
        let rows: Vec<_> = [11, 12, 13]
            .iter()
            .flat_map(|&v| match_rows(v, &[1, 2], 4..6, &[0, 0, 0, 0, 40, 50]))
            .collect();
        assert_eq!(rows.len(), 12);
        assert_eq!(rows[0], (11, 1, 4, 40));
        assert_eq!(rows[3], (11, 2, 5, 50));
        let mut a = rows.clone();
        shuffle(&mut a, 7);
        let mut b = rows.clone();
        shuffle(&mut b, 8);
        assert_ne!(a, rows, "the order moved");
        assert_ne!(a, b, "another number, another order");
        let mut again = rows.clone();
        shuffle(&mut again, 7);
        assert_eq!(a, again, "the same number, the same order");
        // Not one version's matches after another's: the run's progress would say
        // whose match is playing.
        let grouped = a.chunks(4).all(|c| c.iter().all(|r| r.0 == c[0].0));
        assert!(!grouped, "{a:?}");
        let mut sorted = rows.clone();
        sorted.sort_unstable();
        a.sort_unstable();
        assert_eq!(a, sorted, "every match once");
    }
}
