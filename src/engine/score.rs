//! The score of a finished match (RULES.md "Runs, time, score").
//!
//! Score = run-1 steps + run-0 steps / 30, lower is better, shown with 3 decimals.
//! A match that does not finish has no score; leaderboards count it as [`DNF_SCORE`].

use serde::{Deserialize, Serialize};

/// What a leaderboard counts for a match that did not finish.
pub const DNF_SCORE: f64 = 1000.0;

/// The weight of one run-0 step: each 30 exploration steps cost one point.
pub const RUN0_DIVISOR: u32 = 30;

/// The step counts of a finished match, from which the score follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Score {
    /// Steps of run 0, including the accepted reset step.
    pub run0_steps: u32,
    /// Steps of run 1.
    pub run1_steps: u32,
}

impl Score {
    /// The score in thousandths, exact: `(30 * run1 + run0) * 1000 / 30`, rounded half up.
    /// (A multiple of 1/30 never falls halfway between two thousandths.)
    pub fn millis(&self) -> u64 {
        let num = (RUN0_DIVISOR as u64 * self.run1_steps as u64 + self.run0_steps as u64) * 1000;
        let d = RUN0_DIVISOR as u64;
        (num + d / 2) / d
    }

    /// The score as a number rounded to 3 decimals, e.g. `18.133`.
    pub fn value(&self) -> f64 {
        self.millis() as f64 / 1000.0
    }
}

impl std::fmt::Display for Score {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let m = self.millis();
        write!(f, "{}.{:03}", m / 1000, m % 1000)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_example_is_60() {
        // RULES.md: run0 = 900 steps, run1 = 30 steps -> 30 + 900/30 = 60.000.
        let s = Score {
            run0_steps: 900,
            run1_steps: 30,
        };
        assert_eq!(s.to_string(), "60.000");
        assert_eq!(s.value(), 60.0);
    }

    #[test]
    fn thirds_round_to_three_decimals() {
        // 17 + 34/30 = 18.1333...; 20 + 104/30 = 23.4666... -> 23.467
        assert_eq!(
            Score {
                run0_steps: 34,
                run1_steps: 17
            }
            .to_string(),
            "18.133"
        );
        assert_eq!(
            Score {
                run0_steps: 104,
                run1_steps: 20
            }
            .to_string(),
            "23.467"
        );
        assert_eq!(
            Score {
                run0_steps: 104,
                run1_steps: 20
            }
            .value(),
            23.467
        );
        assert_eq!(
            Score {
                run0_steps: 1,
                run1_steps: 0
            }
            .to_string(),
            "0.033"
        );
    }
}
