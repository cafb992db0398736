//! The quotas an owner's uploads are held by, whatever address they come from: an
//! owner (an entrant, all its bots together; or the owner token of a bot of no
//! entrant) has at most a few versions waiting for their build at once, a daily number
//! of versions of bots outside competitions (a competition's bots have the
//! competition's quota instead), and a daily budget of build time that failed and
//! invalid builds spend too. The admin has none. They are counted once when an upload
//! arrives, for a clear refusal before its files are read, and again in the transaction
//! that stores the version ([`crate::storage::owners`]).

use super::{RegistryError, Result};
use crate::competition::{DAY_MS, Timestamp};
use crate::storage::Storage;
use crate::storage::owners::{Owner, OwnerLimits, OwnerQuotaKind, OwnerUsage};

/// The sizes of the owners' quotas (0: no limit).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OwnerQuotas {
    /// Versions of bots outside competitions per owner in any 24 hours (a new bot's
    /// first version included; failed builds and invalid versions do not count).
    pub versions_per_day: u32,
    /// Versions per owner waiting for or in their build at once.
    pub pending_builds: u32,
    /// Minutes of build and validation per owner in any 24 hours.
    pub build_minutes_per_day: u32,
}

impl Default for OwnerQuotas {
    /// 20 versions a day outside competitions, 3 waiting builds, 60 build minutes a day.
    fn default() -> Self {
        OwnerQuotas {
            versions_per_day: 20,
            pending_builds: 3,
            build_minutes_per_day: 60,
        }
    }
}

/// Seconds to wait before one of a few waiting builds is likely done.
const PENDING_RETRY_SECS: u64 = 30;

impl OwnerQuotas {
    /// The limits on one more version of `owner` at `now`; `outside_competitions`: the
    /// bot is entered in none (a new bot always), so its daily version quota applies.
    pub fn limits(&self, owner: Owner, outside_competitions: bool, now: i64) -> OwnerLimits {
        let some = |n: u32| (n > 0).then_some(i64::from(n));
        OwnerLimits {
            owner,
            since: now - DAY_MS,
            most_pending: some(self.pending_builds),
            most_versions_outside: some(self.versions_per_day).filter(|_| outside_competitions),
            most_build_ms: some(self.build_minutes_per_day).map(|m| m * 60_000),
        }
    }
}

/// The refusal of an upload by quota `kind`, whose owner had used `usage`, at `now`:
/// whose quota it is and when the next upload is allowed, in words for its owner.
pub fn refusal(
    kind: OwnerQuotaKind,
    usage: &OwnerUsage,
    limits: &OwnerLimits,
    now: i64,
) -> RegistryError {
    let until = |oldest: Option<i64>| {
        let at = oldest.map_or(now + DAY_MS, |t| t + DAY_MS).max(now + 1000);
        (at, ((at - now) as u64).div_ceil(1000))
    };
    let (message, retry_after_secs) = match kind {
        OwnerQuotaKind::Pending => {
            let names: Vec<String> = usage
                .pending
                .iter()
                .map(|(bot, v)| format!("{bot} v{v}"))
                .collect();
            (
                format!(
                    "You have {} versions waiting for their build ({}), as many as may wait at \
                     once: upload again when one of them is ready (your page and \
                     GET /api/bots/ID show their build).",
                    usage.pending.len(),
                    names.join(", ")
                ),
                PENDING_RETRY_SECS,
            )
        }
        OwnerQuotaKind::VersionsOutside => {
            let (at, secs) = until(usage.oldest_outside_at);
            (
                format!(
                    "You have uploaded {} versions of bots that are in no competition in the \
                     last 24 hours, as many as this server allows ({}; failed builds do not \
                     count): the next one at {}. A bot entered in a competition has that \
                     competition's quota instead.",
                    usage.versions_outside,
                    limits.most_versions_outside.unwrap_or(0),
                    Timestamp(at).words()
                ),
                secs,
            )
        }
        OwnerQuotaKind::BuildTime => {
            let (at, secs) = until(usage.oldest_build_at);
            let minutes = |ms: i64| (ms as f64 / 60_000.0 * 10.0).round() / 10.0;
            (
                format!(
                    "Your builds and validation matches took {} of your {} minutes for any 24 \
                     hours (failed and invalid ones count too): the next upload at {}.",
                    minutes(usage.build_ms),
                    minutes(limits.most_build_ms.unwrap_or(0)),
                    Timestamp(at).words()
                ),
                secs,
            )
        }
    };
    RegistryError::Quota {
        message,
        retry_after_secs,
    }
}

/// What an owner has used of `quotas` (its `usage` over the last 24 hours), in words for
/// its page; `None` when the server sets none.
pub fn summary(quotas: &OwnerQuotas, usage: &OwnerUsage) -> Option<String> {
    let mut parts = Vec::new();
    if quotas.pending_builds > 0 {
        parts.push(format!(
            "{} of {} versions waiting for their build",
            usage.pending.len(),
            quotas.pending_builds
        ));
    }
    if quotas.build_minutes_per_day > 0 {
        parts.push(format!(
            "{:.1} of {} build minutes used in the last 24 hours",
            usage.build_ms as f64 / 60_000.0,
            quotas.build_minutes_per_day
        ));
    }
    if quotas.versions_per_day > 0 {
        parts.push(format!(
            "{} of {} versions of bots in no competition in the last 24 hours",
            usage.versions_outside, quotas.versions_per_day
        ));
    }
    (!parts.is_empty()).then(|| format!("Your uploads: {}.", parts.join("; ")))
}

/// Refuses one more version under `limits` at `now` when a quota is used up (the
/// early check, before the upload's files are read; the transaction that stores the
/// version counts again).
///
/// # Errors
/// [`RegistryError::Quota`] saying which; the database.
pub async fn check(storage: &Storage, limits: &OwnerLimits, now: i64) -> Result<()> {
    let usage = storage.owner_usage(&limits.owner, limits.since).await?;
    match limits.refusal(&usage) {
        Some(kind) => Err(refusal(kind, &usage, limits, now)),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_refusal_names_its_quota_and_the_next_time() {
        let now = 1_800_000_000_000;
        let q = OwnerQuotas::default();
        let limits = q.limits(Owner::Entrant(4), true, now);
        let usage = OwnerUsage {
            pending: vec![("ada".into(), 4), ("ada".into(), 5), ("ada".into(), 6)],
            versions_outside: 20,
            oldest_outside_at: Some(now - DAY_MS + 3_600_000),
            build_ms: 61 * 60_000,
            oldest_build_at: Some(now - 60_000),
        };
        assert_eq!(limits.refusal(&usage), Some(OwnerQuotaKind::Pending));
        let RegistryError::Quota {
            message,
            retry_after_secs,
        } = refusal(OwnerQuotaKind::Pending, &usage, &limits, now)
        else {
            panic!()
        };
        assert!(message.contains("ada v4, ada v5, ada v6"), "{message}");
        assert!(retry_after_secs > 0);
        let RegistryError::Quota {
            message,
            retry_after_secs,
        } = refusal(OwnerQuotaKind::VersionsOutside, &usage, &limits, now)
        else {
            panic!()
        };
        assert!(message.contains("20 versions"), "{message}");
        assert_eq!(retry_after_secs, 3600);
        let RegistryError::Quota { message, .. } =
            refusal(OwnerQuotaKind::BuildTime, &usage, &limits, now)
        else {
            panic!()
        };
        assert!(message.contains("61 of your 60 minutes"), "{message}");
        // A competition's bot is not held by the versions quota; 0 means no limit.
        let inside = q.limits(Owner::Entrant(4), false, now);
        assert_eq!(inside.most_versions_outside, None);
        let none = OwnerQuotas {
            versions_per_day: 0,
            pending_builds: 0,
            build_minutes_per_day: 0,
        }
        .limits(Owner::Entrant(4), true, now);
        assert_eq!(none.refusal(&usage), None);
        assert_eq!(
            summary(&q, &usage).as_deref(),
            Some(
                "Your uploads: 3 of 3 versions waiting for their build; 61.0 of 60 build \
                 minutes used in the last 24 hours; 20 of 20 versions of bots in no \
                 competition in the last 24 hours."
            )
        );
    }
}
