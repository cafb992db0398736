//! The reveal: the final ranking from the last place to the first, each entrant with its
//! public rank, its move and its best and worst private match (each a race of one).

use std::collections::BTreeMap;

use super::race::{race_of, races, runner_of};
use super::{MatchLink, Result, Reveal, RevealLine, drawn, repeat_index, results_open, score30};
use crate::registry::competitions::{self as ops, BoardKind};
use crate::storage::Storage;
use crate::storage::competitions::{CompetitionRow, ResultRow};
use crate::storage::matches::MatchRow;

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
