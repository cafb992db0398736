//! The final night of a competition: the reveal of its results from the last place to
//! the first ([`reveal`]), and the races, every entrant's match on one maze and seed
//! played together ([`race`]). The pages, the API and the command line show what these
//! return; who may see what is decided here, once:
//!
//! - results held for the reveal (`hold_results`, state `held`) are the organisers'
//!   alone; published (`final`), they are everyone's;
//! - a private maze the competition keeps hidden is drawn for its organisers only: for
//!   everyone else the reveal has no match on it (not even a score: one match's score
//!   on a hidden maze is withheld like the rest, [`crate::ranking::withheld`]) and there
//!   is no race on it.
//!
//! [`reveal`] makes the reveal, [`race`] the races, [`shows`] keeps what was made a
//! few seconds.

mod race;
mod reveal;
pub mod shows;

use std::collections::BTreeMap;

use serde::Serialize;

use super::{RegistryError, Result};
use crate::runner::outcome::{MatchState, MatchStatus};
use crate::storage::Storage;
use crate::storage::competitions::{CompetitionMaze, CompetitionRow};
use crate::storage::matches::MatchRow;

pub use race::{path_segment, race, races, tournament_race};
pub use reveal::reveal;
pub use shows::Shows;

/// A score no finished match reaches, in thirtieths: a match that did not finish.
pub(super) const UNFINISHED30: i64 = 30_000;

/// What a competition's final night shows one caller.
#[derive(Debug, Clone, Serialize, utoipa::ToSchema)]
pub struct Reveal {
    /// The competition's name.
    pub competition: String,
    /// Its title.
    pub title: String,
    /// False while the results are held for the reveal (the organisers' rehearsal).
    pub published: bool,
    /// True when it draws private mazes the competition keeps hidden: its organisers'
    /// copy, not to be shared (the page and the export say so on their first screen).
    pub organiser_copy: bool,
    /// True when the private mazes stay hidden from this caller: no match on them is
    /// shown.
    pub private_hidden: bool,
    /// The entrants, best first (the reveal plays them from the end); ties share a rank.
    pub lines: Vec<RevealLine>,
    /// The races this caller may watch.
    pub races: Vec<RaceLink>,
    /// Each shown match (best and worst) as a race of one, by match id, so that the
    /// reveal plays it without the server.
    pub plays: BTreeMap<i64, Race>,
}

/// One entrant in the reveal.
#[derive(Debug, Clone, Serialize, utoipa::ToSchema)]
pub struct RevealLine {
    /// Its final rank (equal ranks: a tie, revealed together).
    pub rank: i64,
    /// The entrant.
    pub entrant: String,
    /// Its bot.
    pub bot_name: String,
    /// The version that counted.
    pub version: i64,
    /// The mean score over the private matches (3 decimals).
    pub mean_score: f64,
    /// The exact sum of its scores in thirtieths (a match that did not finish: 30,000).
    pub score_sum30: i64,
    /// Private matches played.
    pub played: i64,
    /// Of them, finished.
    pub finished: i64,
    /// Its rank on the public board as everyone saw it at the end (none: it was not on
    /// it).
    pub public_rank: Option<i64>,
    /// Places moved from the public rank to the final one: up is positive.
    pub moved: Option<i64>,
    /// Its best private match (none when the private mazes are hidden from the caller).
    pub best: Option<MatchLink>,
    /// Its worst private match.
    pub worst: Option<MatchLink>,
}

/// A match the reveal names.
#[derive(Debug, Clone, Serialize, utoipa::ToSchema)]
pub struct MatchLink {
    /// The match.
    pub match_id: i64,
    /// Its maze's name in the competition.
    pub maze: String,
    /// Which of its set's seeds it played (0: the first).
    pub repeat: i64,
    /// How it ended.
    pub status: String,
    /// Its score, when finished (3 decimals).
    pub score: Option<f64>,
}

/// A race a caller may watch: one maze and one repeat (one seed).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, utoipa::ToSchema)]
pub struct RaceLink {
    /// The set: `private` (the final run) or `public`.
    pub set: String,
    /// The maze's name in the competition.
    pub maze: String,
    /// Which of the set's seeds (0: the first).
    pub repeat: i64,
    /// The page's path.
    pub path: String,
}

/// Every entrant's match on one maze and seed, to be played together.
#[derive(Debug, Clone, Serialize, utoipa::ToSchema)]
pub struct Race {
    /// A heading.
    pub title: String,
    /// The competition (none: a tournament's race).
    pub competition: Option<String>,
    /// The maze's name.
    pub maze: String,
    /// The set it belongs to (`private`, `public`; `tournament` for a tournament's).
    pub set: String,
    /// Which of the set's seeds (0: the first).
    pub repeat: i64,
    /// The seed every runner was given.
    pub seed: i64,
    /// The maze's side.
    pub dim: u32,
    /// The canonical numeric text of the maze.
    pub layout: String,
    /// The fewest steps of a run 1 and the cells of one such route, the start first
    /// (none: the goal room cannot be reached).
    pub optimal: Option<Optimal>,
    /// True when the maze is one the competition keeps hidden (an organiser's copy).
    pub organiser_copy: bool,
    /// The runners, by final rank where there is one, then by name.
    pub runners: Vec<Runner>,
}

/// The solver's best run 1.
#[derive(Debug, Clone, Serialize, utoipa::ToSchema)]
pub struct Optimal {
    /// Its steps.
    pub steps: u32,
    /// Its cells, the start first.
    pub path: Vec<[u32; 2]>,
}

/// One robot in a race.
#[derive(Debug, Clone, Serialize, utoipa::ToSchema)]
pub struct Runner {
    /// The entrant (a tournament's race: the bot).
    pub name: String,
    /// The bot and its version, e.g. `wallfollower v3`.
    pub bot: String,
    /// Its final rank, in a competition's race.
    pub rank: Option<i64>,
    /// The match.
    pub match_id: i64,
    /// How it ended.
    pub status: String,
    /// Its score when finished (3 decimals).
    pub score: Option<f64>,
    /// Its score in thirtieths when finished (run 1 x 30 + run 0): exact, for ordering.
    pub score30: Option<i64>,
    /// Run 0's steps, once its reset was accepted.
    pub run0_steps: Option<i64>,
    /// Run 1's steps, when finished.
    pub run1_steps: Option<i64>,
    /// The step of run 0 at which it first stood in the goal room.
    pub goal0: Option<u32>,
    /// Its cell after each step of run 0 (the start first; a reset keeps it where it
    /// was).
    pub run0: Vec<[u32; 2]>,
    /// Its cell after each step of run 1 (the start first; only the start when run 1
    /// never began).
    pub run1: Vec<[u32; 2]>,
}

/// Whether `organiser` may see `c`'s results now: published ones anyone, held ones its
/// organisers.
///
/// # Errors
/// [`RegistryError::Forbidden`] for held results and someone else,
/// [`RegistryError::Conflict`] before the results.
pub fn results_open(c: &CompetitionRow, organiser: bool) -> Result<()> {
    match c.state.as_deref() {
        Some("final") => Ok(()),
        Some("held") if organiser => Ok(()),
        Some("held") => Err(RegistryError::Forbidden(format!(
            "the results of {} are held by its organisers until the reveal",
            c.name
        ))),
        _ => Err(RegistryError::Conflict(format!(
            "competition {} has no results yet: they come after its close and its final run",
            c.name
        ))),
    }
}

/// Each maze of set `set` with whether this caller sees it drawn and whether it is
/// drawn for the organisers only. Once the results are published, the public mazes are
/// drawn for everyone, and the private ones if the competition reveals them, but never
/// a maze another live competition still uses.
pub(super) async fn drawn(
    storage: &Storage,
    c: &CompetitionRow,
    mazes: &[CompetitionMaze],
    set: &str,
    organiser: bool,
) -> Result<Vec<(CompetitionMaze, bool, bool)>> {
    let published = c.state.as_deref() == Some("final");
    let mut out = Vec::new();
    for m in mazes.iter().filter(|m| m.maze_set == set) {
        let open = published
            && (set == "public" || c.reveal_private_mazes)
            && !storage
                .maze_in_other_live_competition(m.maze_id, c.competition_id)
                .await?;
        out.push((m.clone(), organiser || open, !open));
    }
    Ok(out)
}

/// A match's score in thirtieths, a match that did not finish last.
pub(super) fn score30(m: &MatchRow) -> i64 {
    match (m.status, m.run0_steps, m.run1_steps) {
        (MatchState::Ended(MatchStatus::Finished), Some(r0), Some(r1)) => r1 * 30 + r0,
        _ => UNFINISHED30,
    }
}

/// The repeat indexes a tournament's matches played, in order: a set's seeds (a final
/// run's follow the public set's indexes; a race names them from 0 in its set).
pub(super) async fn repeat_index(storage: &Storage, tournament: i64) -> Result<Vec<i64>> {
    Ok(storage
        .tournament_seeds(tournament)
        .await?
        .into_iter()
        .map(|(r, _)| r)
        .collect())
}
