//! What a reveal or a race, once made, answers for a few seconds.

use std::sync::Arc;

use super::{Race, Result, Reveal, race, results_open, reveal};
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

/// What a kept show answers: a competition's results as one caller sees them.
#[derive(Debug, Clone, PartialEq, Eq)]
struct ShowKey {
    competition_id: i64,
    state: Option<String>,
    finalized_at: Option<i64>,
    organiser: bool,
    /// `None`: the reveal; else the race on this maze and seed.
    race: Option<(String, i64)>,
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

    fn key(c: &CompetitionRow, organiser: bool, race: Option<(String, i64)>) -> ShowKey {
        ShowKey {
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
        let key = Self::key(c, organiser, None);
        if let Some(Show::Reveal(r)) = self.find(&key) {
            return Ok(r);
        }
        let _one = self.making.lock().await;
        if let Some(Show::Reveal(r)) = self.find(&key) {
            return Ok(r);
        }
        let r = Arc::new(reveal(storage, c, organiser).await?);
        self.keep(key, Show::Reveal(r.clone()));
        Ok(r)
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
        if let Some(Show::Race(r)) = self.find(&key) {
            return Ok(r);
        }
        let _one = self.making.lock().await;
        if let Some(Show::Race(r)) = self.find(&key) {
            return Ok(r);
        }
        let r = Arc::new(race(storage, c, organiser, maze, repeat).await?);
        self.keep(key, Show::Race(r.clone()));
        Ok(r)
    }
}
