//! The final selection (which of an entrant's versions count at the end) and the final
//! ranking of entrants.

use serde::{Deserialize, Serialize};

use crate::ranking::Mean;

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
    pub public_mean: Option<Mean>,
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
                    .cmp(&b.public_mean)
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
    /// Mean score, exact, a did-not-finish counting as 1000.
    pub mean: Mean,
}

impl VersionScore {
    /// Lower mean first, exactly.
    fn rank_order(&self, other: &VersionScore) -> std::cmp::Ordering {
        self.mean.cmp(&other.mean)
    }
}

/// Each entrant's best version (lowest mean score, then highest finish rate, then the
/// lower version id), best entrant first, with its rank: entrants whose means are equal
/// (exactly: [`Mean`]) share a rank, as on the boards, and are listed by id.
pub fn rank_entrants(scores: &[VersionScore]) -> Vec<(i64, VersionScore)> {
    let better = |a: &VersionScore, b: &VersionScore| {
        // finished / played, higher first, compared as fractions.
        let rate = |v: &VersionScore| (i128::from(v.finished), i128::from(v.played.max(1)));
        let ((fa, pa), (fb, pb)) = (rate(a), rate(b));
        a.rank_order(b).then((fb * pa).cmp(&(fa * pb)))
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
    best.sort_by(|a, b| a.rank_order(b).then(a.entrant_id.cmp(&b.entrant_id)));
    let ranks = shared_ranks(&best, |a, b| a.rank_order(b).is_eq());
    ranks.into_iter().zip(best).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(id: i64, mean: Option<f64>, chosen: bool) -> Candidate {
        Candidate {
            bot_version_id: id * 10,
            version: id,
            public_mean: mean.map(|m| Mean::of_scores([m])),
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
        let s = |entrant_id, bot_version_id, scores: &[f64]| VersionScore {
            entrant_id,
            bot_version_id,
            played: scores.len() as i64,
            finished: scores.iter().filter(|&&x| x < 1000.0).count() as i64,
            mean: Mean::of_scores(scores.iter().copied()),
        };
        // Entrants 5 and 6: the same scores (whole thirtieths) in another order, whose
        // float means are 23.7 and 23.699999999999996. Entrant 1's better version counts.
        let twin = [19.0 + 17.0 / 30.0, 34.4, 17.0 + 4.0 / 30.0, 23.7];
        let ranked = rank_entrants(&[
            s(1, 11, &[40.0; 4]),
            s(1, 12, &[30.0; 4]),
            s(2, 21, &[30.0; 4]),
            s(4, 41, &[10.0; 4]),
            s(5, 51, &twin),
            s(6, 61, &[twin[3], twin[1], twin[2], twin[0]]),
        ]);
        let got: Vec<(i64, i64, i64)> = ranked
            .iter()
            .map(|(r, v)| (*r, v.entrant_id, v.bot_version_id))
            .collect();
        assert_eq!(
            got,
            vec![(1, 4, 41), (2, 5, 51), (2, 6, 61), (4, 1, 12), (4, 2, 21)]
        );
        // Equal means share a rank whatever the finish rates (1000 + 20 and 510 + 510).
        let ranked = rank_entrants(&[s(7, 71, &[1000.0, 20.0]), s(8, 81, &[510.0, 510.0])]);
        assert_eq!((ranked[0].0, ranked[1].0), (1, 1));
    }
}
