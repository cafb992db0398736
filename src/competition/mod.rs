//! Competitions, the pure part (no I/O): the competition file ([`spec`]), the timeline
//! with its phases and the quotas ([`timeline`]), and the final selection and ranking
//! ([`selection`]). Storage keeps the rows, the registry applies these rules, the API,
//! the pages and the command line show them.

pub mod selection;
pub mod spec;
pub mod timeline;

pub use selection::{Candidate, Rule, VersionScore};
pub use spec::{
    Limits, MazeSets, MazeText, Spec, SpecError, Timestamp, Validation, read_competition_file,
};
pub use timeline::{DAY_MS, Phase, Quota, Timeline};
