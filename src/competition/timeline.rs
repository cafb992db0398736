//! A competition's timeline (opens, freeze, closes) and its phases, and the rolling
//! 24-hour quotas of versions and practice matches.

use serde::Serialize;

/// A day in unix milliseconds: quotas count over the last 24 hours.
pub const DAY_MS: i64 = 86_400_000;

/// When a competition opens, freezes and closes (unix ms).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Timeline {
    /// Versions are ranked from then on.
    pub opens_at: i64,
    /// No new versions from then on; the final selection and run follow.
    pub closes_at: i64,
    /// The public leaderboard stops moving this long before the close (`None`: never).
    pub freeze_ms: Option<i64>,
}

/// Where a competition stands at some moment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum Phase {
    /// Before `opens_at`: entrants may enter and upload; nothing is ranked yet.
    Upcoming,
    /// Versions are ranked as they become ready.
    Open,
    /// Open, but the public leaderboard shows only versions uploaded before the freeze.
    Frozen,
    /// After `closes_at`: no new versions; the final selection and run.
    Closed,
    /// Closed, and its results are written.
    Final,
}

impl Phase {
    /// The word the API uses.
    pub fn as_str(self) -> &'static str {
        match self {
            Phase::Upcoming => "upcoming",
            Phase::Open => "open",
            Phase::Frozen => "frozen",
            Phase::Closed => "closed",
            Phase::Final => "final",
        }
    }

    /// Whether uploads have stopped: closed, with or without its results.
    pub fn is_closed(self) -> bool {
        matches!(self, Phase::Closed | Phase::Final)
    }
}

impl Timeline {
    /// When the public leaderboard freezes, if it does.
    pub fn frozen_from(&self) -> Option<i64> {
        self.freeze_ms
            .map(|f| (self.closes_at - f).max(self.opens_at))
    }

    /// The phase at `now`.
    pub fn phase(&self, now: i64) -> Phase {
        if now >= self.closes_at {
            Phase::Closed
        } else if now < self.opens_at {
            Phase::Upcoming
        } else if self.frozen_from().is_some_and(|f| now >= f) {
            Phase::Frozen
        } else {
            Phase::Open
        }
    }
}

/// A rolling 24-hour quota: how much of it is used at some moment, and when the next
/// one is allowed once it is all used.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, utoipa::ToSchema)]
pub struct Quota {
    /// Counted in the last 24 hours.
    pub used: u32,
    /// Allowed in any 24 hours.
    pub limit: u32,
    /// When one more is allowed, if none is allowed now.
    pub next_at: Option<super::Timestamp>,
    /// The same in words: "2 of 5 versions used in the last 24 hours".
    pub message: String,
}

impl Quota {
    /// The quota of `limit` per 24 hours at `now`, given the times (unix ms) of what
    /// counts against it (any order; those older than 24 hours are not counted).
    /// `what` names the thing counted, plural ("versions").
    pub fn at(times: &[i64], limit: u32, now: i64, what: &str) -> Quota {
        let mut recent: Vec<i64> = times
            .iter()
            .copied()
            .filter(|&t| t > now - DAY_MS && t <= now)
            .collect();
        recent.sort_unstable();
        let used = recent.len() as u32;
        // One more is allowed once the count in the window drops below the limit: when
        // the (used - limit + 1)-th oldest leaves it.
        let next_at = (used >= limit && limit > 0).then(|| {
            let index = (used - limit) as usize;
            super::Timestamp(recent.get(index).map_or(now, |t| t + DAY_MS))
        });
        let mut message = if limit == 0 {
            format!("no {what} allowed")
        } else {
            format!("{used} of {limit} {what} used in the last 24 hours")
        };
        if let Some(next) = next_at {
            message.push_str(&format!("; the next one at {}", next.words()));
        }
        Quota {
            used,
            limit,
            next_at,
            message,
        }
    }

    /// Seconds until one more is allowed, from `now` (a day when none ever is): the
    /// `Retry-After` of a refusal.
    pub fn retry_after_secs(&self, now: i64) -> u64 {
        let wait_ms = self.next_at.map_or(DAY_MS, |t| t.0 - now);
        (wait_ms.max(0) as u64).div_ceil(1000).max(1)
    }

    /// Whether one more is allowed now.
    pub fn allows_one_more(&self) -> bool {
        self.used < self.limit
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::competition::Timestamp;

    const H: i64 = 3_600_000;

    #[test]
    fn phases_follow_the_timeline() {
        let t = Timeline {
            opens_at: 10 * H,
            closes_at: 20 * H,
            freeze_ms: Some(2 * H),
        };
        assert_eq!(t.phase(0), Phase::Upcoming);
        assert_eq!(t.phase(10 * H), Phase::Open);
        assert_eq!(t.phase(18 * H - 1), Phase::Open);
        assert_eq!(t.phase(18 * H), Phase::Frozen);
        assert_eq!(t.phase(20 * H), Phase::Closed);
        // A freeze longer than the competition starts at the opening.
        let long = Timeline {
            freeze_ms: Some(100 * H),
            ..t
        };
        assert_eq!(long.frozen_from(), Some(10 * H));
        assert_eq!(
            Timeline {
                freeze_ms: None,
                ..t
            }
            .phase(19 * H),
            Phase::Open
        );
    }

    #[test]
    fn a_quota_counts_the_last_24_hours_and_says_when_the_next_one_comes() {
        let now = 100 * H;
        let q = Quota::at(&[now - 25 * H, now - 3 * H], 2, now, "versions");
        assert_eq!((q.used, q.next_at), (1, None));
        assert!(q.allows_one_more());
        assert_eq!(q.message, "1 of 2 versions used in the last 24 hours");
        // Full: the next one when the oldest of the window turns 24 hours old.
        let q = Quota::at(&[now - H, now - 10 * H], 2, now, "versions");
        assert_eq!(q.used, 2);
        assert_eq!(q.next_at, Some(Timestamp(now - 10 * H + DAY_MS)));
        assert!(!q.allows_one_more());
        assert!(
            q.message
                .starts_with("2 of 2 versions used in the last 24 hours; the next one at "),
            "{}",
            q.message
        );
        // Over the limit (the limit was lowered): the next one waits for all but 0 to leave.
        let q = Quota::at(&[now - H, now - 2 * H, now - 3 * H], 1, now, "versions");
        assert_eq!(q.next_at, Some(Timestamp(now - H + DAY_MS)));
        // A zero quota allows nothing, ever.
        let q = Quota::at(&[], 0, now, "practice matches");
        assert!(!q.allows_one_more());
        assert_eq!(
            (q.next_at, q.message.as_str()),
            (None, "no practice matches allowed")
        );
    }
}
