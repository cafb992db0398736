//! What a reveal or a race, once made, answers for a few seconds.

use std::sync::Arc;

use super::{Race, Result, Reveal, race, results_open, reveal, tournament_race};
use crate::storage::Storage;
use crate::storage::competitions::CompetitionRow;

/// How long a reveal or a race, once made, answers the same request again: making one
/// reads every shown match's record, so a crowd reloading the projector's page (or a
/// client asking in a loop) is answered from the copy, one making at a time. Results
/// change only with a rejudge or the publish, which the key holds; what the key does
/// not hold (another competition starting to use a maze) is seen within this time.
pub const KEPT_FOR: std::time::Duration = std::time::Duration::from_secs(5);

/// How many reveals and races are kept.
const KEPT: usize = 32;

/// What a kept show answers: a competition's results as one caller sees them, or a
/// tournament's race (whose access the caller checked).
#[derive(Debug, Clone, PartialEq, Eq)]
enum ShowKey {
    Competition {
        competition_id: i64,
        state: Option<String>,
        finalized_at: Option<i64>,
        organiser: bool,
        /// `None`: the reveal; else the race on this maze and seed.
        race: Option<(String, i64)>,
    },
    Tournament {
        tournament_id: i64,
        maze_id: i64,
        repeat: i64,
    },
}

#[derive(Debug, Clone)]
enum Show {
    Reveal(Arc<Reveal>),
    Race(Arc<Race>),
}

/// The reveals and races made in the last [`KEPT_FOR`], and the one making at a time.
#[derive(Debug, Default)]
pub struct Shows {
    kept: std::sync::Mutex<Vec<(ShowKey, std::time::Instant, Show)>>,
    making: tokio::sync::Mutex<()>,
}

impl Shows {
    fn find(&self, key: &ShowKey) -> Option<Show> {
        let mut kept = self.kept.lock().unwrap_or_else(|e| e.into_inner());
        kept.retain(|(_, at, _)| at.elapsed() < KEPT_FOR);
        kept.iter()
            .find(|(k, _, _)| k == key)
            .map(|(_, _, s)| s.clone())
    }

    fn keep(&self, key: ShowKey, show: Show) {
        let mut kept = self.kept.lock().unwrap_or_else(|e| e.into_inner());
        kept.retain(|(k, at, _)| at.elapsed() < KEPT_FOR && *k != key);
        if kept.len() >= KEPT {
            kept.remove(0);
        }
        kept.push((key, std::time::Instant::now(), show));
    }

    /// The show kept under `key`, else `make`'s (one making at a time), kept.
    async fn kept_or_made(
        &self,
        key: ShowKey,
        make: impl std::future::Future<Output = Result<Show>>,
    ) -> Result<Show> {
        if let Some(s) = self.find(&key) {
            return Ok(s);
        }
        let _one = self.making.lock().await;
        if let Some(s) = self.find(&key) {
            return Ok(s);
        }
        let s = make.await?;
        self.keep(key, s.clone());
        Ok(s)
    }

    fn key(c: &CompetitionRow, organiser: bool, race: Option<(String, i64)>) -> ShowKey {
        ShowKey::Competition {
            competition_id: c.competition_id,
            state: c.state.clone(),
            finalized_at: c.finalized_at,
            organiser,
            race,
        }
    }

    /// [`reveal`], kept.
    ///
    /// # Errors
    /// As [`reveal`].
    pub async fn reveal(
        &self,
        storage: &Storage,
        c: &CompetitionRow,
        organiser: bool,
    ) -> Result<Arc<Reveal>> {
        results_open(c, organiser)?;
        let make = async { Ok(Show::Reveal(Arc::new(reveal(storage, c, organiser).await?))) };
        match self
            .kept_or_made(Self::key(c, organiser, None), make)
            .await?
        {
            Show::Reveal(r) => Ok(r),
            Show::Race(_) => unreachable!("a reveal's key holds a reveal"),
        }
    }

    /// [`race`], kept.
    ///
    /// # Errors
    /// As [`race`].
    pub async fn race(
        &self,
        storage: &Storage,
        c: &CompetitionRow,
        organiser: bool,
        maze: &str,
        repeat: i64,
    ) -> Result<Arc<Race>> {
        results_open(c, organiser)?;
        let key = Self::key(c, organiser, Some((maze.to_string(), repeat)));
        let make = async {
            Ok(Show::Race(Arc::new(
                race(storage, c, organiser, maze, repeat).await?,
            )))
        };
        Self::as_race(self.kept_or_made(key, make).await?)
    }

    /// [`tournament_race`], kept: the caller has checked that it may see it.
    ///
    /// # Errors
    /// As [`tournament_race`].
    pub async fn tournament_race(
        &self,
        storage: &Storage,
        tournament_id: i64,
        maze_id: i64,
        repeat: i64,
    ) -> Result<Arc<Race>> {
        let key = ShowKey::Tournament {
            tournament_id,
            maze_id,
            repeat,
        };
        let make = async {
            Ok(Show::Race(Arc::new(
                tournament_race(storage, tournament_id, maze_id, repeat).await?,
            )))
        };
        Self::as_race(self.kept_or_made(key, make).await?)
    }

    fn as_race(show: Show) -> Result<Arc<Race>> {
        match show {
            Show::Race(r) => Ok(r),
            Show::Reveal(_) => unreachable!("a race's key holds a race"),
        }
    }
}
