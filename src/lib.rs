//! mazearena: a match server for the micromouse task "Plot and Navigate a Virtual Maze".
//!
//! # Layout
//! - [`engine`]: the pure referee (maze model and files, rules, score, solver,
//!   generator, SVG). No I/O.
//! - [`protocol`]: the bot protocol v1 messages and the strict decoding of bot replies.
//! - [`competition`]: the pure rules of competitions (their file, timeline, quotas,
//!   final selection and ranking). No I/O.
//! - [`ranking`]: rankings that state their uncertainty (bootstrap intervals, rank
//!   ranges, tie groups). No I/O.
//! - [`runner`]: runs one bot process against one maze and returns a [`runner::MatchRecord`].
//! - [`storage`]: the only SQL: bots, mazes, the match queue, tournaments, leaderboards.
//! - [`registry`]: registering bots and versions (their files stored as bundles in
//!   the database), admitting mazes, tokens, the workers' cache of bots' files.
//! - [`worker`]: match workers that claim queued matches with a lease and record them;
//!   [`builder`]: builds uploaded bot versions that have a build command.
//! - [`api`]: the HTTP/JSON API (axum), with its OpenAPI document, and the pages'
//!   handlers: reading pages, and the forms of browser sessions (taking part,
//!   organising, administration), each calling the same operation as its API route.
//! - [`botfiles`]: safe unpacking of uploaded bots; [`manifest`]: `bot.toml` files.
//! - [`metrics`]: Prometheus metrics.
//! - [`web`]: HTML: the replay viewer and the server's pages (pure rendering).
//! - [`cli`]: the `mazearena` command line (run, replay, match, maze, serve, tournament,
//!   and the client commands: login, submit, status, matches, logs, practice).
//! - [`client`]: the HTTP client of a server that those client commands use.
//!
//! Dependencies point inwards: `engine` <- `protocol` <- `runner` <- `storage` <-
//! `registry` <- `worker` <- `api`, `cli`.

pub mod api;
pub mod botfiles;
pub mod builder;
pub mod cli;
pub mod client;
pub mod competition;
pub mod engine;
pub mod manifest;
pub mod metrics;
pub mod protocol;
pub mod ranking;
pub mod registry;
pub mod runner;
pub mod storage;
pub mod web;
pub mod worker;
