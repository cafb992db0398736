//! `mazearena` as a client of a server: `login`, `logout`, `submit`, `status`,
//! `matches`, `logs`, `practice`, and `replay ID` (in [`super::replay`]). Every HTTP
//! failure is reported with the server's own message ([`crate::client::ClientError`]).
//!
//! Every text that comes from the server (names, statuses, messages, logs) is printed
//! through [`show`], so none of its control characters reaches the terminal raw.

mod account;
mod common;
mod practice;
mod reading;
mod submit;

pub use account::{LoginArgs, login, logout};
pub use practice::{PracticeArgs, practice};
pub use reading::{LogsArgs, MatchesArgs, StatusArgs, logs, matches, replay, status};
pub use submit::{SubmitArgs, submit};

pub(in crate::cli) use reading::is_match_spec;
