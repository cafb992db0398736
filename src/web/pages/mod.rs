//! The server's pages: leaderboard, bots, mazes, matches, tournaments. Each function
//! takes what the page shows (already filtered for what an anonymous visitor may see:
//! `api::site` applies the hidden-maze rules) and returns the whole page.
//!
//! Lists are plain HTML tables with links (sorting and paging are links too), so they
//! work without JavaScript; scripts only add live progress and the owner's logs.

pub mod account;
mod board;
mod competitions;
mod detail;
mod lists;
pub mod organise;
mod ranks;

pub use account::message;
pub use board::{CompetitionBoard, LeaderboardPage, SortKey, StandingsSection, leaderboard};
pub use competitions::{
    CompetitionPage, CompetitionSummary, MY_SUBMISSIONS_JS, competition, competitions,
};
pub use detail::{
    BotPage, Cell, MATCH_STDERR_JS, MatchPage, OWNER_LOGS_JS, PROGRESS_JS, TournamentPage, bot,
    match_page, maze, tournament,
};
pub use lists::{
    ApiRoute, MatchLine, MatchPager, Pager, api_routes, bots, match_table, matches, mazes,
    tournaments, workers,
};
