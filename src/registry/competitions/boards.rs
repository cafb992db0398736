//! The boards (public and private) as a caller may see them, and the stored results
//! with how sure each rank is.

use super::settings::{deciding_tournament, phase, timeline};
use crate::competition::Timestamp;
use crate::ranking::Mean;
use crate::ranking::mean::ratio_3dp;
use crate::registry::Result;
use crate::registry::rankings;
use crate::storage::Storage;
use crate::storage::competitions::{BoardRow, CompetitionRow, ResultRow};
use crate::storage::leaderboard::Scope;
use serde::Serialize;

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

    /// A bot's line of the server's ranking (the default competition's board: no
    /// entrants).
    pub fn from_standing(r: crate::storage::leaderboard::Standing) -> BoardLine {
        BoardLine {
            rank: r.rank,
            entrant: String::new(),
            bot_id: r.bot_id,
            bot_name: r.name,
            version: r.version,
            played: r.played,
            finished: r.finished,
            mean_score: r.mean_score,
            score_sum30: r.score_sum30,
            finish_rate: r.finish_rate,
            uncertainty: r.uncertainty,
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
