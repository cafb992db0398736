//! Competitions, the operations the API, the command line and the server's clock share:
//! creating one from its spec (admitting its mazes), editing it, entering a bot, the
//! quotas, the boards as each caller may see them, and the clock's work ([`tick`]):
//! ranking every new ready version automatically, and after the close the final
//! selection, the final run and the results (an immutable snapshot checked against a
//! recount of the match records).

mod boards;
mod closing;
mod export;
mod quotas;
mod rejudge;
mod settings;
#[cfg(test)]
mod tests;

pub use boards::{
    Board, BoardKind, BoardLine, RunProgress, board, final_progress, progress_for, results,
};
pub use closing::{TickReport, publish, recount_differences, results_csv, tick};
pub use export::{export_files, tar_gz};
pub use quotas::{
    UploadRefusal, check_practice, check_upload, practice_limits, practice_quota, practice_refusal,
    quota_refusal, version_quota,
};
pub use rejudge::{RejudgeRequest, rejudge};
pub use settings::{
    Patch, SEEDS, add_practice_maze, create, deciding_tournament, edit, phase,
    remove_practice_maze, timeline,
};
