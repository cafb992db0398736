//! The bootstrap behind the intervals and the paired test: a bot's matches grouped by
//! maze, each maze's runs resampled with replacement, the maze set kept as it is.
//!
//! The mazes of a standing are its test set: every bot is ranked on those mazes, so they
//! are not resampled. What would change if the matches were played again is the seeds,
//! so each maze's runs (one per seed) are resampled within the maze. A deterministic bot
//! scores the same on a maze whatever the seed: its interval has zero width.

use std::collections::BTreeMap;

use super::Sample;

/// Bootstrap replicates drawn per interval or test.
pub const REPLICATES: usize = 2000;

/// The fixed seed of every bootstrap: the same records always give the same table, and
/// two bots with the same records get the same interval.
pub const SEED: u128 = 0x6d61_7a65_6172_656e_615f_626f_6f74;

/// A bot's runs per maze: `(maze, [(seed, score)])`, in a fixed order (mazes and seeds
/// ascending; several runs on one seed are averaged into one).
#[derive(Debug, Clone, PartialEq)]
pub struct Cells(Vec<(i64, Vec<(i64, f64)>)>);

impl Cells {
    /// Groups `samples` by maze and seed.
    pub fn new(samples: &[Sample]) -> Self {
        let mut by: BTreeMap<i64, BTreeMap<i64, (f64, u32)>> = BTreeMap::new();
        for s in samples {
            let cell = by.entry(s.maze).or_default().entry(s.seed).or_default();
            cell.0 += s.score;
            cell.1 += 1;
        }
        Cells(
            by.into_iter()
                .map(|(maze, seeds)| {
                    let runs = seeds
                        .into_iter()
                        .map(|(seed, (sum, n))| (seed, sum / f64::from(n)))
                        .collect();
                    (maze, runs)
                })
                .collect(),
        )
    }

    /// The fewest runs (seeds) on any one maze; 0 without matches.
    pub fn runs_per_maze(&self) -> usize {
        self.0.iter().map(|(_, r)| r.len()).min().unwrap_or(0)
    }

    /// The cells both bots played, as per-maze differences `self - other`.
    pub fn differences(&self, other: &Cells) -> Cells {
        let mut out = Vec::new();
        for (maze, runs) in &self.0 {
            let Some((_, theirs)) = other.0.iter().find(|(m, _)| m == maze) else {
                continue;
            };
            let diffs: Vec<(i64, f64)> = runs
                .iter()
                .filter_map(|(seed, a)| {
                    theirs
                        .iter()
                        .find(|(s, _)| s == seed)
                        .map(|(_, b)| (*seed, a - b))
                })
                .collect();
            if !diffs.is_empty() {
                out.push((*maze, diffs));
            }
        }
        Cells(out)
    }

    /// Whether no cell holds anything.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// Whether every value is exactly zero (for differences: identical records).
    pub fn all_zero(&self) -> bool {
        self.0.iter().all(|(_, r)| r.iter().all(|(_, v)| *v == 0.0))
    }

    /// The mean over every cell.
    pub fn mean(&self) -> f64 {
        let (sum, n) = self.0.iter().fold((0.0, 0usize), |(s, n), (_, r)| {
            (s + r.iter().map(|(_, v)| v).sum::<f64>(), n + r.len())
        });
        if n == 0 { 0.0 } else { sum / n as f64 }
    }

    /// The 95% percentile interval of the mean over [`REPLICATES`] resamplings of the
    /// runs within each maze, drawn from [`SEED`]. A maze with one run contributes its
    /// value to every replicate.
    pub fn interval(&self) -> (f64, f64) {
        let n: usize = self.0.iter().map(|(_, r)| r.len()).sum();
        if n == 0 {
            return (0.0, 0.0);
        }
        if self
            .0
            .iter()
            .all(|(_, r)| r.iter().all(|(_, v)| *v == r[0].1))
        {
            let m = self.mean();
            return (m, m);
        }
        let mut rng = oorandom::Rand64::new(SEED);
        let mut means = Vec::with_capacity(REPLICATES);
        for _ in 0..REPLICATES {
            let mut sum = 0.0;
            for (_, runs) in &self.0 {
                let k = runs.len() as u64;
                for _ in 0..k {
                    sum += runs[rng.rand_range(0..k) as usize].1;
                }
            }
            means.push(sum / n as f64);
        }
        means.sort_by(f64::total_cmp);
        let low = means[(REPLICATES as f64 * 0.025) as usize];
        let high = means[(REPLICATES as f64 * 0.975) as usize - 1];
        // The interval always holds the mean itself (a skewed sample can push both
        // percentiles to one side of it).
        let m = self.mean();
        (low.min(m), high.max(m))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(maze: i64, seed: i64, score: f64) -> Sample {
        Sample { maze, seed, score }
    }

    #[test]
    fn cells_average_repeated_seeds_and_keep_a_fixed_order() {
        let a = Cells::new(&[s(2, 1, 10.0), s(1, 5, 4.0), s(1, 5, 6.0), s(1, 3, 1.0)]);
        assert_eq!(
            a,
            Cells(vec![(1, vec![(3, 1.0), (5, 5.0)]), (2, vec![(1, 10.0)])])
        );
        assert_eq!(a.runs_per_maze(), 1);
        let b = Cells::new(&[s(1, 3, 1.0), s(1, 5, 4.0), s(3, 1, 9.0)]);
        assert_eq!(
            a.differences(&b),
            Cells(vec![(1, vec![(3, 0.0), (5, 1.0)])])
        );
    }

    #[test]
    fn a_bot_that_scores_the_same_on_every_seed_of_a_maze_has_a_zero_width_interval() {
        // Different mazes, different scores; the same score on every seed of a maze.
        let c = Cells::new(&[s(1, 1, 20.0), s(1, 2, 20.0), s(2, 1, 31.5), s(2, 2, 31.5)]);
        assert_eq!(c.interval(), (25.75, 25.75));
    }

    #[test]
    fn a_bot_whose_score_depends_on_the_seed_gets_an_interval_around_its_mean() {
        let samples: Vec<Sample> = (0..10)
            .map(|seed| s(1, seed, if seed % 2 == 0 { 20.0 } else { 30.0 }))
            .collect();
        let c = Cells::new(&samples);
        let (low, high) = c.interval();
        assert!(low < 25.0 && 25.0 < high, "{low} {high}");
        // Ten draws of 20 or 30: the mean's standard error is 5 / sqrt(10) = 1.58, so
        // the 95% interval is about 25 +- 3.1 (it can only be a multiple of 1).
        assert!(
            (21.0..=23.0).contains(&low) && (27.0..=29.0).contains(&high),
            "{low} {high}"
        );
        // Deterministic.
        assert_eq!(c.interval(), (low, high));
    }
}
