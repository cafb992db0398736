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

use std::collections::BTreeMap;

use serde::Serialize;

use super::competitions::{self as ops, BoardKind};
use super::{RegistryError, Result};
use crate::engine::game::StepEvent;
use crate::engine::{Maze, Position, mazefile, solver};
use crate::runner::outcome::{MatchState, MatchStatus};
use crate::storage::Storage;
use crate::storage::competitions::{CompetitionMaze, CompetitionRow, ResultRow};
use crate::storage::matches::MatchRow;

/// A score no finished match reaches, in thirtieths: a match that did not finish.
const UNFINISHED30: i64 = 30_000;

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

/// How long a reveal or a race, once made, answers the same request again: making one
/// reads every shown match's record, so a crowd reloading the projector's page (or a
/// client asking in a loop) is answered from the copy, one making at a time. Results
/// change only with a rejudge or the publish, which the key holds; what the key does
/// not hold (another competition starting to use a maze) is seen within this time.
pub const KEPT_FOR: std::time::Duration = std::time::Duration::from_secs(5);

/// How many reveals and races are kept.
const KEPT: usize = 32;

/// What a kept show answers: a competition's results as one caller sees them.
#[derive(Debug, Clone, PartialEq, Eq)]
struct ShowKey {
    competition_id: i64,
    state: Option<String>,
    finalized_at: Option<i64>,
    organiser: bool,
    /// `None`: the reveal; else the race on this maze and seed.
    race: Option<(String, i64)>,
}

#[derive(Debug, Clone)]
enum Show {
    Reveal(std::sync::Arc<Reveal>),
    Race(std::sync::Arc<Race>),
}

/// The reveals and races made in the last [`KEPT_FOR`], and the one making at a time.
#[derive(Debug, Default)]
pub struct Shows {
    kept: std::sync::Mutex<Vec<(ShowKey, std::time::Instant, Show)>>,
    making: tokio::sync::Mutex<()>,
}

impl Shows {
    fn find(&self, key: &ShowKey) -> Option<Show> {
        let mut kept = self.kept.lock().unwrap_or_else(|e| e.into_inner());
        kept.retain(|(_, at, _)| at.elapsed() < KEPT_FOR);
        kept.iter()
            .find(|(k, _, _)| k == key)
            .map(|(_, _, s)| s.clone())
    }

    fn keep(&self, key: ShowKey, show: Show) {
        let mut kept = self.kept.lock().unwrap_or_else(|e| e.into_inner());
        kept.retain(|(k, at, _)| at.elapsed() < KEPT_FOR && *k != key);
        if kept.len() >= KEPT {
            kept.remove(0);
        }
        kept.push((key, std::time::Instant::now(), show));
    }

    fn key(c: &CompetitionRow, organiser: bool, race: Option<(String, i64)>) -> ShowKey {
        ShowKey {
            competition_id: c.competition_id,
            state: c.state.clone(),
            finalized_at: c.finalized_at,
            organiser,
            race,
        }
    }

    /// [`reveal`], kept.
    ///
    /// # Errors
    /// As [`reveal`].
    pub async fn reveal(
        &self,
        storage: &Storage,
        c: &CompetitionRow,
        organiser: bool,
    ) -> Result<std::sync::Arc<Reveal>> {
        results_open(c, organiser)?;
        let key = Self::key(c, organiser, None);
        if let Some(Show::Reveal(r)) = self.find(&key) {
            return Ok(r);
        }
        let _one = self.making.lock().await;
        if let Some(Show::Reveal(r)) = self.find(&key) {
            return Ok(r);
        }
        let r = std::sync::Arc::new(reveal(storage, c, organiser).await?);
        self.keep(key, Show::Reveal(r.clone()));
        Ok(r)
    }

    /// [`race`], kept.
    ///
    /// # Errors
    /// As [`race`].
    pub async fn race(
        &self,
        storage: &Storage,
        c: &CompetitionRow,
        organiser: bool,
        maze: &str,
        repeat: i64,
    ) -> Result<std::sync::Arc<Race>> {
        results_open(c, organiser)?;
        let key = Self::key(c, organiser, Some((maze.to_string(), repeat)));
        if let Some(Show::Race(r)) = self.find(&key) {
            return Ok(r);
        }
        let _one = self.making.lock().await;
        if let Some(Show::Race(r)) = self.find(&key) {
            return Ok(r);
        }
        let r = std::sync::Arc::new(race(storage, c, organiser, maze, repeat).await?);
        self.keep(key, Show::Race(r.clone()));
        Ok(r)
    }
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

/// The reveal of `c`'s results for a caller (`organiser`: one of its organisers or the
/// admin).
///
/// # Errors
/// As [`results_open`]; the database.
pub async fn reveal(storage: &Storage, c: &CompetitionRow, organiser: bool) -> Result<Reveal> {
    results_open(c, organiser)?;
    let results = ops::results(storage, c).await?;
    let mazes = storage.competition_mazes(c.competition_id).await?;
    let private_drawn = drawn(storage, c, &mazes, "private", organiser).await?;
    let private_hidden = !private_drawn.iter().all(|(_, shown, _)| *shown);
    let organiser_copy = private_drawn
        .iter()
        .any(|(_, shown, hidden)| *shown && *hidden);
    // The public board as everyone saw it at the end.
    let public = ops::board(
        storage,
        c,
        BoardKind::Public,
        false,
        crate::storage::now_ms(),
    )
    .await?;
    let public_rank = |r: &ResultRow| {
        public
            .standings
            .iter()
            .filter(|l| l.entrant == r.entrant_name)
            .map(|l| l.rank)
            .min()
    };
    let (finals, repeats) = match ops::deciding_tournament(c) {
        Some(t) => (
            storage.tournament_matches(t).await?,
            repeat_index(storage, t).await?,
        ),
        None => (Vec::new(), Vec::new()),
    };
    let index = |m: &MatchRow| {
        repeats
            .iter()
            .position(|&r| Some(r) == m.repeat)
            .unwrap_or(0) as i64
    };
    let mut plays = BTreeMap::new();
    let mut lines = Vec::new();
    for r in &results {
        let mine: Vec<&MatchRow> = finals
            .iter()
            .filter(|m| m.bot_version_id == r.bot_version_id && m.status.ended().is_some())
            .filter(|m| {
                private_drawn
                    .iter()
                    .any(|(cm, shown, _)| cm.maze_id == m.maze_id && *shown)
            })
            .collect();
        let best = mine
            .iter()
            .min_by_key(|m| (score30(m), m.match_id))
            .copied();
        let worst = mine
            .iter()
            .max_by_key(|m| (score30(m), -m.match_id))
            .copied();
        for m in [best, worst].into_iter().flatten() {
            if let std::collections::btree_map::Entry::Vacant(slot) = plays.entry(m.match_id) {
                let cm = mazes.iter().find(|cm| cm.maze_id == m.maze_id);
                let name = cm.map_or(m.maze_name.clone(), |cm| cm.name.clone());
                let set = cm.map_or("private".to_string(), |cm| cm.maze_set.clone());
                let runner = runner_of(storage, m, &r.entrant_name, Some(r.rank)).await?;
                if let Some(race) = race_of(
                    storage,
                    Some(c),
                    &name,
                    &set,
                    m.maze_id,
                    index(m),
                    m.seed,
                    runner.into_iter().collect(),
                    private_drawn
                        .iter()
                        .any(|(cm, _, only)| cm.maze_id == m.maze_id && *only),
                )
                .await?
                {
                    slot.insert(race);
                }
            }
        }
        let link = |m: &MatchRow| MatchLink {
            match_id: m.match_id,
            maze: mazes
                .iter()
                .find(|cm| cm.maze_id == m.maze_id)
                .map_or(m.maze_name.clone(), |cm| cm.name.clone()),
            repeat: index(m),
            status: m.status.to_string(),
            score: m.score,
        };
        let public_rank = public_rank(r);
        lines.push(RevealLine {
            rank: r.rank,
            entrant: r.entrant_name.clone(),
            bot_name: r.bot_name.clone(),
            version: r.version,
            mean_score: r.mean_score,
            score_sum30: r.score_sum30,
            played: r.played,
            finished: r.finished,
            public_rank,
            moved: public_rank.map(|p| p - r.rank),
            best: best.map(link),
            worst: worst.map(link),
        });
    }
    Ok(Reveal {
        competition: c.name.clone(),
        title: c.title.clone(),
        published: c.state.as_deref() == Some("final"),
        organiser_copy,
        private_hidden,
        lines,
        races: races(storage, c, organiser).await?,
        plays,
    })
}

/// Each maze of set `set` with whether this caller sees it drawn and whether it is
/// drawn for the organisers only. Once the results are published, the public mazes are
/// drawn for everyone, and the private ones if the competition reveals them, but never
/// a maze another live competition still uses.
async fn drawn(
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
fn score30(m: &MatchRow) -> i64 {
    match (m.status, m.run0_steps, m.run1_steps) {
        (MatchState::Ended(MatchStatus::Finished), Some(r0), Some(r1)) => r1 * 30 + r0,
        _ => UNFINISHED30,
    }
}

/// The races of `c` a caller may watch once its results are open to them: each private
/// maze (drawn for them) and each public maze, each repeat.
///
/// # Errors
/// As [`results_open`]; the database.
pub async fn races(
    storage: &Storage,
    c: &CompetitionRow,
    organiser: bool,
) -> Result<Vec<RaceLink>> {
    results_open(c, organiser)?;
    let mazes = storage.competition_mazes(c.competition_id).await?;
    let mut out = Vec::new();
    for (set, tournament) in [
        ("private", ops::deciding_tournament(c)),
        ("public", c.public_tournament_id),
    ] {
        let Some(t) = tournament else { continue };
        let repeats = repeat_index(storage, t).await?;
        for (m, shown, _) in drawn(storage, c, &mazes, set, organiser).await? {
            if !shown {
                continue;
            }
            for repeat in 0..repeats.len() as i64 {
                out.push(RaceLink {
                    set: set.to_string(),
                    maze: m.name.clone(),
                    repeat,
                    path: format!(
                        "/competitions/{}/race/{}/{repeat}",
                        c.name,
                        urlencoding_path(&m.name)
                    ),
                });
            }
        }
    }
    Ok(out)
}

/// The repeat indexes a tournament's matches played, in order: a set's seeds (a final
/// run's follow the public set's indexes; a race names them from 0 in its set).
async fn repeat_index(storage: &Storage, tournament: i64) -> Result<Vec<i64>> {
    Ok(storage
        .tournament_seeds(tournament)
        .await?
        .into_iter()
        .map(|(r, _)| r)
        .collect())
}

/// A maze name as one segment of a path (names are letters, digits, `-`, `_`, `.`;
/// anything else is escaped).
fn urlencoding_path(name: &str) -> String {
    let mut out = String::new();
    for b in name.bytes() {
        if b.is_ascii_alphanumeric() || b"-_.".contains(&b) {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

/// The race of `c`'s entrants on its maze named `maze` (or of that id), repeat `repeat`: the final run's
/// matches on a private maze, the public set's on a public one, of the version that
/// counted for each entrant.
///
/// # Errors
/// As [`results_open`]; [`RegistryError::Forbidden`] for a hidden private maze and
/// anyone but the organisers; [`RegistryError::NotFound`] for no such maze or repeat;
/// the database.
pub async fn race(
    storage: &Storage,
    c: &CompetitionRow,
    organiser: bool,
    maze: &str,
    repeat: i64,
) -> Result<Race> {
    results_open(c, organiser)?;
    let mazes = storage.competition_mazes(c.competition_id).await?;
    // By its name in the competition, else by its id.
    let Some(cm) = mazes
        .iter()
        .filter(|m| m.maze_set != "practice")
        .find(|m| m.name == maze)
        .or_else(|| {
            let id = maze.parse::<i64>().ok()?;
            mazes
                .iter()
                .find(|m| m.maze_id == id && m.maze_set != "practice")
        })
    else {
        return Err(RegistryError::NotFound(format!(
            "competition {} has no ranking maze {maze:?}",
            c.name
        )));
    };
    let (shown, organiser_only) = drawn(
        storage,
        c,
        std::slice::from_ref(cm),
        &cm.maze_set,
        organiser,
    )
    .await?
    .first()
    .map_or((false, true), |(_, s, h)| (*s, *h));
    if !shown {
        return Err(RegistryError::Forbidden(format!(
            "the maze {maze:?} of {} stays hidden: its races are its organisers' only",
            c.name
        )));
    }
    let tournament = if cm.maze_set == "private" {
        ops::deciding_tournament(c)
    } else {
        c.public_tournament_id
    };
    let (matches, actual) = match tournament {
        Some(t) => (
            storage.tournament_matches(t).await?,
            repeat_index(storage, t)
                .await?
                .get(repeat as usize)
                .copied(),
        ),
        None => (Vec::new(), None),
    };
    let Some(actual) = actual.filter(|_| repeat >= 0) else {
        return Err(RegistryError::NotFound(format!(
            "the {} set of {} has no seed {}",
            cm.maze_set,
            c.name,
            repeat + 1
        )));
    };
    let results = ops::results(storage, c).await?;
    let mut runners = Vec::new();
    let mut seed = None;
    for r in &results {
        let Some(m) = matches.iter().find(|m| {
            m.bot_version_id == r.bot_version_id
                && m.maze_id == cm.maze_id
                && m.repeat == Some(actual)
                && m.status.ended().is_some()
        }) else {
            continue;
        };
        seed = Some(m.seed);
        runners.extend(runner_of(storage, m, &r.entrant_name, Some(r.rank)).await?);
    }
    let Some(seed) = seed else {
        return Err(RegistryError::NotFound(format!(
            "no match of {} on {maze:?} has repeat {repeat}",
            c.name
        )));
    };
    race_of(
        storage,
        Some(c),
        &cm.name,
        &cm.maze_set,
        cm.maze_id,
        repeat,
        seed,
        runners,
        organiser_only,
    )
    .await?
    .ok_or_else(|| RegistryError::NotFound(format!("the maze {maze:?} is not stored")))
}

/// The race of every bot of tournament `tournament_id` on maze `maze_id`, repeat
/// `repeat` (a sealed tournament's: its competition's organisers only, which the caller
/// checks).
///
/// # Errors
/// [`RegistryError::NotFound`] for no such match; the database.
pub async fn tournament_race(
    storage: &Storage,
    tournament_id: i64,
    maze_id: i64,
    repeat: i64,
) -> Result<Race> {
    let matches = storage.tournament_matches(tournament_id).await?;
    let actual = repeat_index(storage, tournament_id)
        .await?
        .get(repeat.max(0) as usize)
        .copied()
        .filter(|_| repeat >= 0);
    let mut runners = Vec::new();
    let mut seed = None;
    let mut name = None;
    for m in matches.iter().filter(|m| {
        m.maze_id == maze_id
            && m.repeat.is_some()
            && m.repeat == actual
            && m.status.ended().is_some()
    }) {
        seed = Some(m.seed);
        name = Some(m.maze_name.clone());
        runners.extend(runner_of(storage, m, &m.bot_name, None).await?);
    }
    let (Some(seed), Some(name)) = (seed, name) else {
        return Err(RegistryError::NotFound(format!(
            "tournament {tournament_id} has no played match on maze {maze_id}, repeat {repeat}"
        )));
    };
    runners.sort_by(|a, b| {
        (a.score30.unwrap_or(UNFINISHED30), &a.name)
            .cmp(&(b.score30.unwrap_or(UNFINISHED30), &b.name))
    });
    race_of(
        storage,
        None,
        &name,
        "tournament",
        maze_id,
        repeat,
        seed,
        runners,
        false,
    )
    .await?
    .ok_or_else(|| RegistryError::NotFound(format!("maze {maze_id} is not stored")))
}

/// The race on maze `maze_id` from its runners.
#[allow(clippy::too_many_arguments)]
async fn race_of(
    storage: &Storage,
    c: Option<&CompetitionRow>,
    name: &str,
    set: &str,
    maze_id: i64,
    repeat: i64,
    seed: i64,
    runners: Vec<Runner>,
    organiser_copy: bool,
) -> Result<Option<Race>> {
    let Some(row) = storage.get_maze(maze_id).await? else {
        return Ok(None);
    };
    let Ok(maze) = mazefile::parse(row.layout.as_bytes()) else {
        return Ok(None);
    };
    let optimal = solver::solve(&maze).map(|s| Optimal {
        steps: s.steps,
        path: s.path.iter().map(|p| [p.x, p.y]).collect(),
    });
    let title = match c {
        Some(c) => format!("{}: {name}, seed {} ({set})", c.title, repeat + 1),
        None => format!("{name}, seed {}", repeat + 1),
    };
    Ok(Some(Race {
        title,
        competition: c.map(|c| c.name.clone()),
        maze: name.to_string(),
        set: set.to_string(),
        repeat,
        seed,
        dim: maze.dim(),
        layout: mazefile::numeric::write(&maze),
        optimal,
        organiser_copy,
        runners,
    }))
}

/// Match `m` as a runner named `name`: its cells run by run from its replay record
/// (none when the record cannot be read or its trace was removed).
async fn runner_of(
    storage: &Storage,
    m: &MatchRow,
    name: &str,
    rank: Option<i64>,
) -> Result<Option<Runner>> {
    let Some(record) = storage.get_record(m.match_id).await? else {
        return Ok(None);
    };
    let maze = storage
        .get_maze(m.maze_id)
        .await?
        .and_then(|z| mazefile::parse(z.layout.as_bytes()).ok());
    let (run0, run1, goal0) = paths(&record.trace, maze.as_ref());
    let finished = m.status == MatchState::Ended(MatchStatus::Finished);
    Ok(Some(Runner {
        name: name.to_string(),
        bot: format!("{} v{}", m.bot_name, m.version),
        rank,
        match_id: m.match_id,
        status: m.status.to_string(),
        score: m.score,
        score30: finished.then(|| score30(m)),
        run0_steps: m.run0_steps,
        run1_steps: m.run1_steps,
        goal0,
        run0,
        run1,
    }))
}

/// The cells after each step of run 0 and of run 1 (each from the start), and the step
/// of run 0 at which the robot first stood in the goal room.
fn paths(
    trace: &[crate::runner::outcome::TraceStep],
    maze: Option<&Maze>,
) -> (Vec<[u32; 2]>, Vec<[u32; 2]>, Option<u32>) {
    let start = [0, 0];
    let (mut run0, mut run1) = (vec![start], vec![start]);
    let mut goal0 = None;
    for s in trace {
        let r = &s.report;
        let cell = |p: Position| [p.x, p.y];
        if r.run == 0 {
            let here = if r.event == StepEvent::ResetAccepted {
                *run0.last().unwrap_or(&start)
            } else {
                cell(r.position)
            };
            run0.push(here);
            if goal0.is_none() && maze.is_some_and(|m| m.is_goal(r.position)) {
                goal0 = Some((run0.len() - 1) as u32);
            }
        } else {
            run1.push(cell(r.position));
        }
    }
    (run0, run1, goal0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_path_name_is_one_segment() {
        assert_eq!(urlencoding_path("test_maze-01.txt"), "test_maze-01.txt");
        assert_eq!(urlencoding_path("a/b c"), "a%2Fb%20c");
    }
}
