//! mazearena: a match server for the micromouse task "Plot and Navigate a Virtual Maze".
//!
//! # Layout
//! - [`engine`]: the pure referee (maze model and files, rules, score, solver,
//!   generator). No I/O.
//! - [`protocol`]: the bot protocol v1 messages and the strict decoding of bot replies.
//! - [`runner`]: runs one bot process against one maze and returns a [`runner::MatchRecord`].
//! - [`cli`]: the `mazearena` command line.

pub mod api;
pub mod botfiles;
pub mod cli;
pub mod engine;
pub mod manifest;
pub mod metrics;
pub mod protocol;
pub mod runner;
pub mod storage;
pub mod worker;
