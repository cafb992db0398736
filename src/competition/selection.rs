//! The final selection (which of an entrant's versions count at the end) and the final
//! ranking of entrants.

use serde::{Deserialize, Serialize};

/// Which versions of an entrant count at the end.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum Rule {
    /// The latest version that played.
    #[default]
    Latest,
    /// The version with the best public-ranking mean score (ties: the later one).
    BestPublic,
    /// The versions the entrant chose (up to the competition's `max_selected`); the
    /// latest when none is chosen.
    Choice,
}

impl Rule {
    /// The stored word.
    pub fn as_str(self) -> &'static str {
        match self {
            Rule::Latest => "latest",
            Rule::BestPublic => "best_public",
            Rule::Choice => "choice",
        }
    }

    /// From the stored word.
    pub fn parse(word: &str) -> Option<Rule> {
        Some(match word {
            "latest" => Rule::Latest,
            "best_public" => Rule::BestPublic,
            "choice" => Rule::Choice,
            _ => return None,
        })
    }
}

/// One ranked version of an entrant, as the selection sees it.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    /// Its id.
    pub bot_version_id: i64,
    /// Its number.
    pub version: i64,
    /// Its public-ranking mean score, once played.
    pub public_mean: Option<f64>,
    /// Whether the entrant chose it.
    pub chosen: bool,
}

/// The versions (ids) that count at the end by `rule`, from an entrant's ranked
/// versions (those that played).
pub fn select(rule: Rule, max_selected: usize, candidates: &[Candidate]) -> Vec<i64> {
    let latest = candidates.iter().max_by_key(|c| c.version);
    let picked: Vec<&Candidate> = match rule {
        Rule::Latest => latest.into_iter().collect(),
        Rule::BestPublic => candidates
            .iter()
            .filter(|c| c.public_mean.is_some())
            .min_by(|a, b| {
                a.public_mean
                    .partial_cmp(&b.public_mean)
                    .unwrap_or(std::cmp::Ordering::Equal)
                    .then(b.version.cmp(&a.version))
            })
            .or(latest)
            .into_iter()
            .collect(),
        Rule::Choice => {
            let mut chosen: Vec<&Candidate> = candidates.iter().filter(|c| c.chosen).collect();
            chosen.sort_by_key(|c| std::cmp::Reverse(c.version));
            chosen.truncate(max_selected);
            if chosen.is_empty() {
                latest.into_iter().collect()
            } else {
                chosen
            }
        }
    };
    picked.iter().map(|c| c.bot_version_id).collect()
}

/// The ranks of `items`, best first: 1, 2, ..., except that an item `tied` to the one
/// before it shares its rank ("1, 2, 2, 4").
pub fn shared_ranks<T>(items: &[T], tied: impl Fn(&T, &T) -> bool) -> Vec<i64> {
    let mut ranks: Vec<i64> = Vec::with_capacity(items.len());
    for i in 0..items.len() {
        let rank = if i > 0 && tied(&items[i - 1], &items[i]) {
            ranks[i - 1]
        } else {
            i as i64 + 1
        };
        ranks.push(rank);
    }
    ranks
}

/// A selected version's numbers on the set that decides.
#[derive(Debug, Clone, PartialEq)]
pub struct VersionScore {
    /// The entrant.
    pub entrant_id: i64,
    /// The version.
    pub bot_version_id: i64,
    /// Matches counted and finished.
    pub played: i64,
    /// Of which finished.
    pub finished: i64,
    /// Mean score, a did-not-finish counting as 1000.
    pub mean_score: f64,
    /// finished / played.
    pub finish_rate: f64,
}

/// Each entrant's best version (lowest mean score, then highest finish rate, then the
/// lower version id), best entrant first, with its rank (equal numbers share a rank).
pub fn rank_entrants(scores: &[VersionScore]) -> Vec<(i64, VersionScore)> {
    let better = |a: &VersionScore, b: &VersionScore| {
        a.mean_score
            .total_cmp(&b.mean_score)
            .then(b.finish_rate.total_cmp(&a.finish_rate))
    };
    let mut best: Vec<VersionScore> = Vec::new();
    for s in scores {
        match best.iter_mut().find(|b| b.entrant_id == s.entrant_id) {
            Some(b) => {
                if better(s, b)
                    .then(s.bot_version_id.cmp(&b.bot_version_id))
                    .is_lt()
                {
                    *b = s.clone();
                }
            }
            None => best.push(s.clone()),
        }
    }
    best.sort_by(|a, b| better(a, b).then(a.entrant_id.cmp(&b.entrant_id)));
    let ranks = shared_ranks(&best, |a, b| better(a, b).is_eq());
    ranks.into_iter().zip(best).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(id: i64, mean: Option<f64>, chosen: bool) -> Candidate {
        Candidate {
            bot_version_id: id * 10,
            version: id,
            public_mean: mean,
            chosen,
        }
    }

    #[test]
    fn each_rule_picks_what_it_says() {
        let all = [
            c(1, Some(30.0), true),
            c(2, Some(20.0), false),
            c(3, None, true),
        ];
        assert_eq!(select(Rule::Latest, 1, &all), vec![30]);
        assert_eq!(select(Rule::BestPublic, 1, &all), vec![20]);
        assert_eq!(select(Rule::Choice, 1, &all), vec![30]);
        assert_eq!(select(Rule::Choice, 2, &all), vec![30, 10]);
        // Nothing chosen: the latest. No public score yet: the latest. Nothing: nothing.
        let unchosen = [c(1, None, false), c(2, None, false)];
        assert_eq!(select(Rule::Choice, 2, &unchosen), vec![20]);
        assert_eq!(select(Rule::BestPublic, 1, &unchosen), vec![20]);
        assert!(select(Rule::Latest, 1, &[]).is_empty());
        // Equal public means: the later version.
        let tie = [c(1, Some(5.0), false), c(2, Some(5.0), false)];
        assert_eq!(select(Rule::BestPublic, 1, &tie), vec![20]);
        for rule in [Rule::Latest, Rule::BestPublic, Rule::Choice] {
            assert_eq!(Rule::parse(rule.as_str()), Some(rule));
        }
    }

    #[test]
    fn entrants_rank_by_their_best_version_and_ties_share_a_rank() {
        let s = |entrant_id, bot_version_id, mean_score, finish_rate| VersionScore {
            entrant_id,
            bot_version_id,
            played: 4,
            finished: 4,
            mean_score,
            finish_rate,
        };
        let ranked = rank_entrants(&[
            s(1, 11, 40.0, 1.0),
            s(1, 12, 30.0, 1.0),
            s(2, 21, 30.0, 1.0),
            s(3, 31, 30.0, 0.5),
            s(4, 41, 10.0, 1.0),
        ]);
        let got: Vec<(i64, i64, i64)> = ranked
            .iter()
            .map(|(r, v)| (*r, v.entrant_id, v.bot_version_id))
            .collect();
        assert_eq!(got, vec![(1, 4, 41), (2, 1, 12), (2, 2, 21), (4, 3, 31)]);
    }
}
