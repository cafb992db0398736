//! Standings ranked with their uncertainty: the rules of [`crate::ranking`] applied to
//! the lines a caller is shown (after any line is left out, so the ranks are among the
//! lines shown), with the matches of the standing's scope.

use std::collections::HashMap;

use crate::ranking::{self, Entry, Sample, Uncertainty};
use crate::storage::leaderboard::{Scope, Standing};
use crate::storage::{Result, Storage};

/// Ranks `lines` (any order) by mean score with [`ranking::assess`]: puts them best
/// first (equal means by name), and hands each its rank and [`Uncertainty`]. `key` is a
/// line's (bot id, version) in `samples`.
pub fn rank_lines<T>(
    lines: &mut [T],
    samples: &[(i64, i64, Sample)],
    mean: impl Fn(&T) -> f64,
    name: impl Fn(&T) -> &str,
    key: impl Fn(&T) -> (i64, i64),
    mut set: impl FnMut(&mut T, i64, Uncertainty),
) {
    lines.sort_by(|a, b| {
        if ranking::same_score(mean(a), mean(b)) {
            name(a).cmp(name(b))
        } else {
            mean(a).total_cmp(&mean(b))
        }
    });
    let mut by_version: HashMap<(i64, i64), Vec<Sample>> = HashMap::new();
    for (bot, version, s) in samples {
        by_version.entry((*bot, *version)).or_default().push(*s);
    }
    let entries: Vec<Entry> = lines
        .iter()
        .map(|l| Entry {
            mean: mean(l),
            samples: by_version.get(&key(l)).map_or(&[], Vec::as_slice),
        })
        .collect();
    let assessed = ranking::assess(&entries);
    for (line, (rank, u)) in lines.iter_mut().zip(assessed) {
        set(line, rank, u);
    }
}

/// Ranks the standings `rows` of `scope` (see [`rank_lines`]).
///
/// # Errors
/// Database failures.
pub async fn rank(
    storage: &Storage,
    scope: Scope,
    mut rows: Vec<Standing>,
) -> Result<Vec<Standing>> {
    if rows.is_empty() {
        return Ok(rows);
    }
    let samples = storage.standing_samples(scope).await?;
    rank_lines(
        &mut rows,
        &samples,
        |r| r.mean_score,
        |r| r.name.as_str(),
        |r| (r.bot_id, r.version),
        |r, rank, u| {
            r.rank = rank;
            r.uncertainty = u;
        },
    );
    Ok(rows)
}

/// The standings of `scope`, ranked.
///
/// # Errors
/// Database failures.
pub async fn leaderboard(storage: &Storage, scope: Scope) -> Result<Vec<Standing>> {
    let rows = storage.leaderboard(scope).await?;
    rank(storage, scope, rows).await
}
