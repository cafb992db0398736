//! Reading matches: one, a tournament's, and the filtered, paged lists with their
//! counts.

use super::MatchRow;
use crate::runner::outcome::MatchState;
use crate::storage::{Result, Storage};

impl Storage {
    /// A match by id.
    ///
    /// # Errors
    /// Database failures.
    pub async fn get_match(&self, match_id: i64) -> Result<Option<MatchRow>> {
        Ok(
            sqlx::query_as(&format!("{} where m.match_id = $1", self.match_select()))
                .bind(match_id)
                .fetch_optional(self.pool())
                .await?,
        )
    }

    /// One page of the matches that pass `filter`, newest first, and how many pass it
    /// (without its `before`).
    ///
    /// # Errors
    /// Database failures.
    pub async fn list_matches(
        &self,
        filter: &MatchFilter,
        page: Page,
    ) -> Result<(Vec<MatchRow>, MatchCount)> {
        let (clause, values) = filter_clause(filter, true);
        let n = values.len();
        let sql = format!(
            "{}{clause} order by m.match_id desc limit ${} offset ${}",
            self.match_select(),
            n + 1,
            n + 2
        );
        let mut rows = sqlx::query_as(&sql);
        for value in &values {
            rows = match value {
                FilterValue::Id(id) => rows.bind(*id),
                FilterValue::Text(text) => rows.bind(*text),
            };
        }
        let rows = rows
            .bind(page.limit)
            .bind(page.offset)
            .fetch_all(self.pool())
            .await?;
        let (clause, values) = filter_clause(filter, false);
        let sql = format!(
            "select count(*) from (select 1 from match m{clause} limit ${}) as counted",
            values.len() + 1
        );
        let mut count = sqlx::query_scalar(&sql);
        for value in &values {
            count = match value {
                FilterValue::Id(id) => count.bind(*id),
                FilterValue::Text(text) => count.bind(*text),
            };
        }
        let counted: i64 = count.bind(COUNT_CAP + 1).fetch_one(self.pool()).await?;
        Ok((
            rows,
            MatchCount {
                total: counted.min(COUNT_CAP),
                exact: counted <= COUNT_CAP,
            },
        ))
    }

    /// Matches of a tournament, by id.
    ///
    /// # Errors
    /// Database failures.
    pub async fn tournament_matches(&self, tournament_id: i64) -> Result<Vec<MatchRow>> {
        Ok(sqlx::query_as(&format!(
            "{} where m.tournament_id = $1 order by m.match_id",
            self.match_select()
        ))
        .bind(tournament_id)
        .fetch_all(self.pool())
        .await?)
    }

    /// The number of matches in each status.
    ///
    /// # Errors
    /// Database failures.
    pub async fn count_by_status(&self) -> Result<Vec<(String, i64)>> {
        Ok(
            sqlx::query_as("select status, count(*) from match group by status order by status")
                .fetch_all(self.pool())
                .await?,
        )
    }
}

/// Which matches [`Storage::list_matches`] returns.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct MatchFilter {
    /// Only this bot's (any version).
    pub bot_id: Option<i64>,
    /// Only this tournament's.
    pub tournament_id: Option<i64>,
    /// Only this maze's.
    pub maze_id: Option<i64>,
    /// Only matches in this state.
    pub status: Option<MatchState>,
    /// Only matches older than this one (smaller ids): the page after a page that ends
    /// with it. Unlike an offset, it costs the same however deep the page.
    pub before: Option<i64>,
    /// Leave out the matches of sealed tournaments (for anyone but the admin and the
    /// organisers).
    pub hide_sealed: bool,
}

/// How many matches pass a filter, counted up to [`COUNT_CAP`] so that a count costs
/// the same at a million matches as at a thousand.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MatchCount {
    /// The number counted (at most [`COUNT_CAP`]).
    pub total: i64,
    /// False when more pass than were counted.
    pub exact: bool,
}

/// The most matches a list counts.
pub const COUNT_CAP: i64 = 10_000;

/// One page of a list: at most `limit` rows after skipping `offset`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Page {
    /// Rows to skip.
    pub offset: i64,
    /// Rows to return.
    pub limit: i64,
}

/// A value [`filter_clause`] binds.
enum FilterValue {
    Id(i64),
    Text(&'static str),
}

/// `filter` as the where clause of a query on `match m`, with its parameters numbered
/// from `$1`, and their values in order: only the conditions it sets, so that the
/// database can use the index each one has (`before` only if `keyset`).
fn filter_clause(filter: &MatchFilter, keyset: bool) -> (String, Vec<FilterValue>) {
    let mut clause = String::from(" where 1 = 1");
    let mut values = Vec::new();
    let mut add = |column: &str, op: &str, value: FilterValue| {
        values.push(value);
        clause.push_str(&format!(" and m.{column} {op} ${}", values.len()));
    };
    if let Some(bot_id) = filter.bot_id {
        add("bot_id", "=", FilterValue::Id(bot_id));
    }
    if let Some(tournament_id) = filter.tournament_id {
        add("tournament_id", "=", FilterValue::Id(tournament_id));
    }
    if let Some(maze_id) = filter.maze_id {
        add("maze_id", "=", FilterValue::Id(maze_id));
    }
    if let Some(status) = filter.status {
        add("status", "=", FilterValue::Text(status.as_str()));
    }
    if let Some(before) = filter.before.filter(|_| keyset) {
        add("match_id", "<", FilterValue::Id(before));
    }
    if filter.hide_sealed {
        clause.push_str(
            " and not exists (select 1 from tournament t where t.tournament_id = m.tournament_id and t.sealed = 1)",
        );
    }
    (clause, values)
}
