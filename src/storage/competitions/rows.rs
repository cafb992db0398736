//! A competition's own rows: made, read, listed, edited; its mazes, practice mazes and
//! invite code.

use super::{COMPETITION_COLUMNS, CompetitionMaze, CompetitionRow};
use crate::competition::Spec;
use crate::storage::{Result, Storage, StorageError, is_unique_violation, now_ms};

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
}
