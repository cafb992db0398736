//! The registry: the one home of what the API, the command line and the workers do to
//! the set of bots and mazes.
//!
//! - [`bots`]: registering a bot and adding a version, from an upload (stored as a
//!   bundle in the database) or from a local folder (`mazearena tournament`); the
//!   checks on names, commands and environments.
//! - [`bundles`]: storing a folder as a content-addressed bundle, and the meaning of a
//!   version's `files_sha256`: always the bundle hash of `botfiles` (the files and
//!   links with their modes; no timestamps, order or archive format).
//! - [`cache`]: a worker's local cache of unpacked bundles, keyed and verified by hash,
//!   evicted by size.
//! - [`competitions`]: creating and editing competitions, entering bots, quotas, the
//!   boards as each caller may see them, and the clock that ranks new versions and
//!   writes the results.
//! - [`mazes`]: admitting a maze (parsed, made canonical, solved, stored once by layout).
//! - [`migrate`]: moving versions stored in an older data folder into the database.
//! - [`rankings`]: standings ranked with their uncertainty (intervals, rank ranges,
//!   tie groups).
//! - [`tokens`]: owner and admin tokens.
//!
//! Every failure is a [`RegistryError`], which says whose fault it was.

pub mod bots;
pub mod bundles;
pub mod cache;
pub mod competitions;
pub mod demo;
pub mod entrants;
pub mod finale;
pub mod invites;
pub mod mazes;
pub mod migrate;
pub mod owners;
pub mod rankings;
pub mod tokens;

use crate::botfiles::BundleError;
use crate::storage::StorageError;

/// Why a registry operation did not happen.
#[derive(Debug, thiserror::Error)]
pub enum RegistryError {
    /// Something the caller sent is not acceptable (a name, a command, a maze...).
    #[error("{0}")]
    Invalid(String),
    /// The thing exists already (a bot name, a maze layout).
    #[error("{0}")]
    Conflict(String),
    /// The thing asked for does not exist.
    #[error("{0}")]
    NotFound(String),
    /// The thing exists, but not for this caller (sealed until the results, or its
    /// organisers' only).
    #[error("{0}")]
    Forbidden(String),
    /// The bot's files were refused, or could not be stored.
    #[error(transparent)]
    Bundle(#[from] BundleError),
    /// A stored bundle does not hold what its hash says (or cannot be unpacked): a
    /// damaged database, never the bot's doing.
    #[error("{0}")]
    Corrupt(String),
    /// A quota is used up: what it says, and in how many seconds one more is allowed.
    #[error("{message}")]
    Quota {
        /// The quota in words.
        message: String,
        /// When to try again.
        retry_after_secs: u64,
    },
    /// The database failed.
    #[error(transparent)]
    Storage(StorageError),
    /// A failure on our side (no randomness, a task that died, a local disk).
    #[error("{0}")]
    Internal(String),
}

impl From<StorageError> for RegistryError {
    fn from(e: StorageError) -> Self {
        match e {
            StorageError::Conflict(msg) => RegistryError::Conflict(msg),
            other => RegistryError::Storage(other),
        }
    }
}

impl RegistryError {
    /// `true` when the caller sent something unacceptable (not a failure on our side).
    pub fn is_client_error(&self) -> bool {
        match self {
            RegistryError::Invalid(_)
            | RegistryError::Conflict(_)
            | RegistryError::NotFound(_)
            | RegistryError::Forbidden(_)
            | RegistryError::Quota { .. } => true,
            RegistryError::Bundle(e) => e.is_client_error(),
            RegistryError::Corrupt(_) | RegistryError::Storage(_) | RegistryError::Internal(_) => {
                false
            }
        }
    }

    /// `true` when trying again cannot help: a bundle missing from the database or
    /// damaged, a malformed hash (as opposed to a database or local disk failure).
    pub fn is_permanent(&self) -> bool {
        match self {
            RegistryError::Invalid(_)
            | RegistryError::Conflict(_)
            | RegistryError::NotFound(_)
            | RegistryError::Forbidden(_)
            | RegistryError::Corrupt(_) => true,
            RegistryError::Bundle(e) => e.is_client_error(),
            // The quota frees up with time.
            RegistryError::Quota { .. }
            | RegistryError::Storage(_)
            | RegistryError::Internal(_) => false,
        }
    }
}

/// Results of the registry.
pub type Result<T, E = RegistryError> = std::result::Result<T, E>;
