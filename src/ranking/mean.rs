//! Exact means of scores. A score is a whole number of thirtieths of a step (run-1
//! steps + run-0 steps / 30), and a did-not-finish counts as 1000 = 30,000 thirtieths,
//! so a sum of scores is kept as an integer count of thirtieths: equal sums over equal
//! counts are equal however the scores were added up, and two means compare exactly
//! (by cross-multiplying). Floating point only appears where a mean is shown, rounded
//! to 3 decimals by [`Mean::millis`] the same way on every surface.

use std::cmp::Ordering;

use crate::engine::score::{DNF_SCORE, RUN0_DIVISOR};

/// A score's value in thirtieths of a step (a score read back from the database is a
/// float close to a whole number of thirtieths).
pub fn thirtieths(score: f64) -> i64 {
    (score * f64::from(RUN0_DIVISOR)).round() as i64
}

/// What a match that did not finish counts as, in thirtieths.
pub const DNF_THIRTIETHS: i64 = DNF_SCORE as i64 * RUN0_DIVISOR as i64;

/// `n / d` rounded half up to thousandths and shown as a number, e.g. a finish rate
/// 2/3 as 0.667 (0 when `d` is 0).
pub fn ratio_3dp(n: i64, d: i64) -> f64 {
    if d <= 0 {
        return 0.0;
    }
    div_round(i128::from(n) * 1000, i128::from(d)) as f64 / 1000.0
}

/// A float rounded half away from zero to 3 decimals (interval ends, ratios that are
/// not exact fractions), so that what is shown has 3 decimals at most.
pub fn round_3dp(x: f64) -> f64 {
    (x * 1000.0).round() / 1000.0
}

/// `n / d` rounded half up (towards +infinity at exactly one half), for `d > 0`.
fn div_round(n: i128, d: i128) -> i128 {
    (2 * n + d).div_euclid(2 * d)
}

/// A mean score kept exact: the sum of the scores in thirtieths, and how many there are.
#[derive(Debug, Clone, Copy, Default)]
pub struct Mean {
    /// Sum of the scores, in thirtieths of a step.
    pub sum30: i64,
    /// How many scores.
    pub count: i64,
}

impl Mean {
    /// The mean of `count` scores that add up to `sum30` thirtieths.
    pub fn new(sum30: i64, count: i64) -> Mean {
        Mean { sum30, count }
    }

    /// The mean of `scores` (each a float score, 1000 for a did-not-finish).
    pub fn of_scores(scores: impl IntoIterator<Item = f64>) -> Mean {
        scores.into_iter().fold(Mean::default(), |m, s| Mean {
            sum30: m.sum30 + thirtieths(s),
            count: m.count + 1,
        })
    }

    /// The mean in thousandths of a step, rounded half up (0 for no scores).
    pub fn millis(&self) -> i64 {
        if self.count <= 0 {
            return 0;
        }
        div_round(
            i128::from(self.sum30) * 1000,
            i128::from(self.count) * i128::from(RUN0_DIVISOR),
        ) as i64
    }

    /// The mean as shown and exported: rounded to 3 decimals ([`Mean::millis`]).
    pub fn rounded(&self) -> f64 {
        self.millis() as f64 / 1000.0
    }

    /// The mean as a float, unrounded (for the bootstrap's arithmetic only).
    pub fn value(&self) -> f64 {
        if self.count <= 0 {
            return 0.0;
        }
        self.sum30 as f64 / (self.count as f64 * f64::from(RUN0_DIVISOR))
    }

    /// The mean as an exact fraction of steps, e.g. "783/60" (its sum over 30 x count).
    pub fn fraction(&self) -> String {
        format!("{}/{}", self.sum30, self.count * i64::from(RUN0_DIVISOR))
    }
}

impl std::fmt::Display for Mean {
    /// The mean with 3 decimals, e.g. `13.050`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let m = self.millis();
        let sign = if m < 0 { "-" } else { "" };
        write!(f, "{sign}{}.{:03}", m.abs() / 1000, m.abs() % 1000)
    }
}

impl Ord for Mean {
    /// Lower mean first, exactly (no scores count as a mean of 0).
    fn cmp(&self, other: &Mean) -> Ordering {
        let a = i128::from(self.sum30) * i128::from(other.count.max(1));
        let b = i128::from(other.sum30) * i128::from(self.count.max(1));
        a.cmp(&b)
    }
}

impl PartialEq for Mean {
    /// Equal as fractions: 2 matches of 20 and 1 match of 20 are the same mean.
    fn eq(&self, other: &Mean) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Mean {}

impl PartialOrd for Mean {
    fn partial_cmp(&self, other: &Mean) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// Two means are the same mean when they are equal as fractions ([`Ord`]), even over
/// different counts (2 matches of 20 and 1 match of 20).
pub fn same_mean(a: Mean, b: Mean) -> bool {
    a.cmp(&b) == Ordering::Equal
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn the_float_sums_that_split_a_tie_are_equal_here() {
        // The same four scores (whole thirtieths) in two orders: as floats their means
        // are 23.699999999999996 and 23.700000000000003.
        let a = [19.0 + 17.0 / 30.0, 34.4, 17.0 + 4.0 / 30.0, 23.7];
        let b = [a[3], a[1], a[2], a[0]];
        let fa: f64 = a.iter().sum::<f64>() / 4.0;
        let fb: f64 = b.iter().sum::<f64>() / 4.0;
        assert_ne!(fa, fb, "the float sums no longer differ: pick other scores");
        let (ma, mb) = (Mean::of_scores(a), Mean::of_scores(b));
        assert_eq!(ma, mb);
        assert!(same_mean(ma, mb));
        assert_eq!(ma.to_string(), "23.700");
        assert_eq!(ma.rounded(), 23.7);
        assert_eq!(ma.fraction(), "2844/120");
    }

    #[test]
    fn means_round_half_up_to_thousandths_and_compare_as_fractions() {
        // 18 + 4/30 = 18.1333..., 23 + 14/30 = 23.4666...
        assert_eq!(Mean::new(18 * 30 + 4, 1).to_string(), "18.133");
        assert_eq!(Mean::new(23 * 30 + 14, 1).to_string(), "23.467");
        // (1/30 + 0) / 2 = 1/60 = 0.01666... -> 0.017
        assert_eq!(Mean::new(1, 2).millis(), 17);
        // 2 x 20 over 2 is the same mean as 20 over 1.
        assert!(same_mean(Mean::new(1200, 2), Mean::new(600, 1)));
        assert!(Mean::new(600, 1) < Mean::new(601, 1));
        assert_eq!(Mean::new(600 + DNF_THIRTIETHS, 2).to_string(), "510.000");
        assert_eq!(Mean::new(1567, 2).fraction(), "1567/60");
        assert_eq!(ratio_3dp(2, 3), 0.667);
        assert_eq!(ratio_3dp(1, 3), 0.333);
        assert_eq!(ratio_3dp(0, 0), 0.0);
        assert_eq!(thirtieths(21.133333333333333), 634);
    }

    fn score() -> impl Strategy<Value = f64> {
        prop_oneof![
            Just(DNF_SCORE),
            (1u32..200, 0u32..1000)
                .prop_map(|(run1, run0)| f64::from(run1) + f64::from(run0) / 30.0),
        ]
    }

    proptest! {
        /// The same multiset of scores, summed in any order, gives means that are
        /// equal, rank equal and print the same.
        #[test]
        fn the_same_scores_in_any_order_give_the_same_mean(
            scores in prop::collection::vec(score(), 1..40),
            seed in any::<u64>(),
        ) {
            let mut shuffled = scores.clone();
            // A permutation from the seed (Fisher-Yates with a small LCG).
            let mut x = seed | 1;
            for i in (1..shuffled.len()).rev() {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                shuffled.swap(i, (x >> 33) as usize % (i + 1));
            }
            let (a, b) = (Mean::of_scores(scores.iter().copied()), Mean::of_scores(shuffled));
            prop_assert_eq!(a, b);
            prop_assert_eq!(a.cmp(&b), Ordering::Equal);
            prop_assert_eq!(a.to_string(), b.to_string());
            prop_assert_eq!(a.rounded().to_bits(), b.rounded().to_bits());
            // A sum written as a running total, added and taken away again, lands on
            // the same integer.
            let running = scores.iter().fold(0i64, |s, &x| s + thirtieths(x));
            prop_assert_eq!(running, a.sum30);
        }
    }
}
