//! Competitions: created and edited by organisers (and the admin), entered by entrants
//! (their key), ranked by the server's clock, with a public and a private leaderboard,
//! "my submissions" for an entrant, and the final results (JSON and CSV).
//!
//! What is sealed stays sealed for anyone but the admin and the organisers: the private
//! board before the close; the private set's and final run's tournaments and matches
//! (not found) until the close and the results; the seeds until the results.

mod boards;
mod competition;
mod entries;
mod organisers;
mod organising;

use utoipa_axum::router::OpenApiRouter;

use super::AppState;

pub(crate) use boards::default_board;
pub use boards::{BoardQuery, ResultsView};
pub use competition::{CompetitionView, MazeLine};
pub(crate) use competition::{create, edit, find, view};
pub use entries::{ChoiceRequest, EntryRequest, EntryView, SubmissionView, SubmissionsView};
pub(crate) use entries::{entrant, my_submissions};
pub(crate) use organisers::register_organiser;
pub use organisers::{OrganiserCreated, OrganiserRequest};
pub(crate) use organising::{export_archive, rejudge};

/// Their routes.
pub(super) fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .merge(organisers::router())
        .merge(competition::router())
        .merge(entries::router())
        .merge(boards::router())
        .merge(organising::router())
}
