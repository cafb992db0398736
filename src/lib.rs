//! mazearena: a match server for the micromouse task "Plot and Navigate a Virtual Maze".
//!
//! # Layout
//! - [`engine`]: the pure referee (maze model and files, rules, score, solver,
//!   generator, SVG). No I/O.
//! - [`protocol`]: the bot protocol v1 messages and the strict decoding of bot replies.
//! - [`runner`]: runs one bot process against one maze and returns a [`runner::MatchRecord`].
//! - [`storage`]: the only SQL: bots, mazes, the match queue, tournaments, leaderboards.
//! - [`worker`]: match workers that claim queued matches with a lease and record them.
//! - [`api`]: the HTTP/JSON API (axum), with its OpenAPI document.
//! - [`botfiles`]: safe unpacking of uploaded bots; [`manifest`]: `bot.toml` files.
//! - [`metrics`]: Prometheus metrics.
//! - [`cli`]: the `mazearena` command line (run, maze, serve, tournament).
//!
//! Dependencies point inwards: `engine` <- `protocol` <- `runner` <- `worker`/`storage`
//! <- `api`, `cli`.

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
