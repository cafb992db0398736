//! The budgets of requests that prove nothing, counted per client address in the
//! database ([`crate::storage::budgets`]), so that every API server of one database
//! spends the same ones.
//!
//! A request that proves who it is (a right key at `/login`, a session, a bearer key or
//! owner token, the admin token, the right invite code) never spends, and is never
//! refused by, an address's budget: it is held by its own account's quotas instead
//! ([`crate::registry::owners`], the competitions' quotas). What proves nothing is
//! counted by the address it came from ([`super::client_address`]: behind a trusted
//! proxy, the address it forwards):
//! - **guesses**: a key at `/login` that is not known, an invite code that is wrong;
//! - **anonymous registrations**: a bot or an entrant registered without any key on a
//!   server whose registration is open.
//!
//! The right invite code has a budget of its own, shared by everyone who has it (a
//! leaked code cannot fill the database). An IPv6 client is counted by its /64
//! network, the block one home or school is given. The admin has no limit.

use std::net::IpAddr;

use super::AppState;
use super::error::{ApiError, ApiResult};
use crate::storage::budgets::Rate;

/// The budgets' sizes, per hour (0: no limit).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Budgets {
    /// Wrong keys at `/login` and wrong invite codes, per client address.
    pub guesses_per_hour: u32,
    /// Bots and entrants registered without a key, per client address.
    pub anonymous_registrations_per_hour: u32,
    /// Entrants registered with the right invite code, all together.
    pub invite_registrations_per_hour: u32,
}

impl Default for Budgets {
    /// 60 guesses and 20 anonymous registrations an hour per address, 600 registrations
    /// an hour with the invite code.
    fn default() -> Self {
        Budgets {
            guesses_per_hour: 60,
            anonymous_registrations_per_hour: 20,
            invite_registrations_per_hour: 600,
        }
    }
}

/// What a request spends.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Spend<'a> {
    /// A key at `/login` that no one holds.
    WrongKey,
    /// An invite code that is not the server's.
    WrongInviteCode,
    /// A bot or entrant registered without a key.
    AnonymousRegistration,
    /// An entrant registered with the right invite code (by the code's hash).
    InviteRegistration(&'a str),
}

/// The budget key of a client address: an IPv4 address, or an IPv6 address's /64.
fn address_key(addr: IpAddr) -> String {
    match addr.to_canonical() {
        IpAddr::V4(v4) => v4.to_string(),
        IpAddr::V6(v6) => {
            let s = v6.segments();
            format!("{:x}:{:x}:{:x}:{:x}::/64", s[0], s[1], s[2], s[3])
        }
    }
}

/// "3 minutes", "45 seconds": a wait in words.
pub fn wait_words(secs: u64) -> String {
    match secs {
        0..=1 => "a second".into(),
        2..=89 => format!("{secs} seconds"),
        _ => format!("{} minutes", secs.div_ceil(60)),
    }
}

/// Spends `what` from the budget it belongs to, for a request from `client` (`None`:
/// not known, nothing is counted): `Ok`, or a 429 that says whose budget is used up,
/// in words for the person who sent it, and when to try again.
///
/// # Errors
/// The budget is used up (429 with Retry-After); the database.
pub async fn spend(state: &AppState, what: Spend<'_>, client: Option<IpAddr>) -> ApiResult<()> {
    let budgets = state.settings.budgets;
    let (name, per_hour) = match what {
        Spend::WrongKey | Spend::WrongInviteCode => {
            let Some(addr) = client else { return Ok(()) };
            (
                format!("guesses:{}", address_key(addr)),
                budgets.guesses_per_hour,
            )
        }
        Spend::AnonymousRegistration => {
            let Some(addr) = client else { return Ok(()) };
            (
                format!("anonymous:{}", address_key(addr)),
                budgets.anonymous_registrations_per_hour,
            )
        }
        Spend::InviteRegistration(code_hash) => (
            format!("invite:{code_hash}"),
            budgets.invite_registrations_per_hour,
        ),
    };
    if per_hour == 0 {
        return Ok(());
    }
    let now = crate::storage::now_ms();
    let Err(wait_ms) = state
        .storage
        .spend_budget(&name, Rate::per_hour(per_hour), now)
        .await?
    else {
        return Ok(());
    };
    let secs = (wait_ms as u64).div_ceil(1000).max(1);
    let wait = wait_words(secs);
    if let Some(addr) = client {
        tracing::info!(budget = %name, client = %addr, wait_secs = secs, "a budget is used up");
    }
    let message = match what {
        Spend::WrongKey => format!(
            "Too many keys that are not known here were tried from your network's address \
             in the last hour (everyone on your network, a school or a home, shares this \
             count). A right key always logs in; other tries wait {wait}."
        ),
        Spend::WrongInviteCode => format!(
            "Too many wrong invite codes were tried from your network's address in the last \
             hour (everyone on your network, a school or a home, shares this count). The \
             right code always works; other tries wait {wait}."
        ),
        Spend::AnonymousRegistration => format!(
            "Too many registrations without a key came from your network's address in the \
             last hour (everyone on your network, a school or a home, shares this count). \
             Register with your entrant's key, which has its own quota, or try again in {wait}."
        ),
        Spend::InviteRegistration(_) => format!(
            "So many people registered with this invite code in the last hour that the \
             server is taking a breath ({per_hour} an hour): try again in {wait}."
        ),
    };
    Err(ApiError::TooManyRequests {
        message,
        retry_after_secs: secs,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ipv6_clients_are_counted_by_their_64() {
        let a: IpAddr = "2001:db8:1:2:aaaa::1".parse().unwrap();
        let b: IpAddr = "2001:db8:1:2:bbbb::9".parse().unwrap();
        let c: IpAddr = "2001:db8:1:3::1".parse().unwrap();
        assert_eq!(address_key(a), address_key(b));
        assert_ne!(address_key(a), address_key(c));
        let mapped: IpAddr = "::ffff:192.0.2.4".parse().unwrap();
        assert_eq!(address_key(mapped), "192.0.2.4");
    }

    #[test]
    fn waits_read_as_words() {
        assert_eq!(wait_words(1), "a second");
        assert_eq!(wait_words(45), "45 seconds");
        assert_eq!(wait_words(121), "3 minutes");
    }
}
