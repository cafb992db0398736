//! mazearena: a match server for the micromouse task "Plot and Navigate a Virtual Maze".
//!
//! # A tour: one match, from upload to leaderboard
//! 1. **An upload arrives.** `POST /api/bots` ([`api::bots`]), the upload form
//!    (`api::site::submit`) and `mazearena submit` (through [`client`]) all call one
//!    operation, [`registry::bots::register`] or [`registry::bots::add_version`]: it checks
//!    the name and command, unpacks the archive safely ([`botfiles`]: nothing outside the
//!    bot's folder, sizes capped), stores the files once as a content-addressed bundle
//!    ([`storage::bundles`]) and, inside a competition, asks its quotas first
//!    ([`registry::competitions`], its quotas; rules in [`competition`]).
//! 2. **It is built and validated.** The build worker of a pool ([`work::builder`]) claims
//!    the version, runs its build in the sandbox ([`runner::build`]) and plays its
//!    validation match; the version becomes `ready`, `build_failed` or `invalid`
//!    ([`storage::build_status`]).
//! 3. **Matches are queued.** A practice request, a tournament ([`api::tournaments`]) or a
//!    competition's clock ([`registry::competitions::tick`]) puts matches in the queue
//!    ([`storage::matches::queue`]: lanes, one owner's after another's).
//! 4. **A worker plays one.** A match worker ([`work::worker`]), pinned to a core of its own,
//!    claims the next match with a lease, fetches the bot's bundle into its cache
//!    ([`registry::cache`]) and calls [`runner::run_match`]: the bot starts in the sandbox
//!    ([`runner::sandbox`]: bubblewrap, Landlock, seccomp, a cgroup), and the session
//!    ([`runner::session`]) trades sensor readings for moves in the bot's dialect
//!    ([`protocol`]: v1 JSON lines or mms) while the pure referee ([`engine`]) applies the
//!    rules: two runs, 1,000 steps, the score in whole thirtieths.
//! 5. **The record is written** in one transaction with the standing's exact sums
//!    ([`storage::matches::match_records`]); a worker that died gives its match back when
//!    its lease ends.
//! 6. **The boards read it.** [`storage::leaderboard`] keeps the sums;
//!    [`registry::competitions::board`] makes a competition's boards and results;
//!    [`ranking`] says how sure each rank is; [`api::leaderboard`] serves them as JSON and
//!    [`web`] renders the pages, the replay viewer and the final night's shows
//!    ([`registry::finale`]).
//!
//! # The rooms, each with one job, on floors (a room uses only rooms below it)
//! - [`engine`]: the pure referee (maze model and files, rules, score, solver, generator,
//!   SVG); [`botfiles`]: safe unpacking of uploads; [`client`]: a server's HTTP client.
//! - [`protocol`]: the bots' dialects (v1 JSON lines, mms); [`ranking`]: rankings that say
//!   how sure they are (bootstrap intervals, rank ranges, ties).
//! - [`runner`]: the only room that starts processes: one bot against one maze, in the
//!   sandbox, returning a [`runner::MatchRecord`].
//! - [`competition`]: a competition's pure rules (its file, timeline, selection);
//!   [`manifest`]: `bot.toml`.
//! - [`storage`]: the only SQL (SQLite and PostgreSQL, migrations in `migrations/`).
//! - [`registry`]: the operations several faces share (bots, mazes, tokens, entrants,
//!   competitions, the final night), with their own errors; [`metrics`]: Prometheus.
//! - [`work`]: the work that plays and builds (match workers, the builder), apart from
//!   the web face; [`web`]: pure rendering of HTML.
//! - [`api`]: the HTTP face (axum): the JSON API with its OpenAPI document and, in
//!   [`api::site`], the handlers of the pages and forms, which call the same operations.
//! - [`cli`]: the `mazearena` command.
//!
//! `tests/it/house.rs` measures the floors, the circles and the rooms' sizes.
//!
//! # Where a new feature goes
//! - A rule of the game: [`engine`], with its test against `RULES.md`. A new bot dialect:
//!   [`protocol`], then [`runner::session`].
//! - A rule of competitions (a quota, a phase, a selection): a pure function in
//!   [`competition`] or [`ranking`]; its use of the database in [`registry`].
//! - A new stored fact: a new migration in `migrations/sqlite` and `migrations/postgres`
//!   (never edit a committed one), its queries in [`storage`].
//! - A new route: a handler in [`api`] that calls a [`registry`] operation; its page: a
//!   handler in [`api::site`] calling the same operation and a view in [`web`].
//! - A new command: a file in [`cli`].

pub mod api;
pub mod botfiles;
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
pub mod work;
