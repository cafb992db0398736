//! The races: every entrant's (or every bot's) match on one maze and seed, each robot's
//! cells run by run from its replay record.

use super::{
    Optimal, Race, RaceLink, RegistryError, Result, Runner, UNFINISHED30, drawn, repeat_index,
    results_open, score30,
};
use crate::engine::game::StepEvent;
use crate::engine::maze::in_goal_room;
use crate::engine::{Position, mazefile, solver};
use crate::registry::competitions as ops;
use crate::runner::outcome::{MatchState, MatchStatus};
use crate::storage::Storage;
use crate::storage::competitions::CompetitionRow;
use crate::storage::matches::MatchRow;

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
                        path_segment(&m.name)
                    ),
                });
            }
        }
    }
    Ok(out)
}

/// A maze name as one segment of a path (names are letters, digits, `-`, `_`, `.`;
/// anything else is escaped).
pub fn path_segment(name: &str) -> String {
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
pub(super) async fn race_of(
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
pub(super) async fn runner_of(
    storage: &Storage,
    m: &MatchRow,
    name: &str,
    rank: Option<i64>,
) -> Result<Option<Runner>> {
    let Some(record) = storage.get_record(m.match_id).await? else {
        return Ok(None);
    };
    let (run0, run1, goal0) = paths(&record.trace, m.maze_dim as u32);
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
    dim: u32,
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
            if goal0.is_none() && in_goal_room(dim, r.position) {
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
        assert_eq!(path_segment("test_maze-01.txt"), "test_maze-01.txt");
        assert_eq!(path_segment("a/b c"), "a%2Fb%20c");
    }
}
