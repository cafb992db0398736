//! A competition's settings: made from its file, edited, its practice mazes, its
//! timeline and phase, and the tournament whose matches decide its results.

use crate::competition::selection::Rule;
use crate::competition::spec::{self, check_schedule};
use crate::competition::{Limits, MazeSets, MazeText, Phase, Spec, Timeline, Timestamp};
use crate::engine::mazefile;
use crate::registry::{RegistryError, Result};
use crate::storage::Storage;
use crate::storage::competitions::{CompetitionMaze, CompetitionRow};

/// Seeds drawn for every competition: enough for the most ranking and final repeats.
pub const SEEDS: usize = 70;

/// The competition's timeline (`None` for the default competition).
pub fn timeline(c: &CompetitionRow) -> Option<Timeline> {
    Some(Timeline {
        opens_at: c.opens_at?,
        closes_at: c.closes_at?,
        freeze_ms: c.freeze_ms,
    })
}

/// Its phase at `now` (the default competition is always open).
pub fn phase(c: &CompetitionRow, now: i64) -> Phase {
    if c.state.as_deref() == Some("final") {
        return Phase::Final;
    }
    timeline(c).map_or(Phase::Open, |t| t.phase(now))
}

/// Creates a competition: checks its spec, admits its mazes (a practice maze must be
/// public on this server, a ranking maze hidden; a layout stored already is reused if
/// so), draws its secret seeds.
///
/// # Errors
/// [`RegistryError::Invalid`] saying what is wrong (with the maze and its line for a bad
/// maze), [`RegistryError::Conflict`] for a name taken, the database.
pub async fn create(
    storage: &Storage,
    spec: Spec<MazeText>,
    organiser_id: Option<i64>,
) -> Result<CompetitionRow> {
    spec.check().map_err(|e| RegistryError::Invalid(e.0))?;
    let mut ids: MazeSets<i64> = MazeSets {
        practice: Vec::new(),
        public: Vec::new(),
        private: Vec::new(),
    };
    let sets = [
        ("practice", &spec.mazes.practice),
        ("public", &spec.mazes.public),
        ("private", &spec.mazes.private),
    ];
    for (set, mazes) in sets {
        let hidden = set != "practice";
        for m in mazes {
            let id = admit(storage, m, hidden).await.map_err(|e| match e {
                RegistryError::Invalid(why) => {
                    RegistryError::Invalid(format!("{set} maze {:?}: {why}", m.name))
                }
                other => other,
            })?;
            match set {
                "practice" => ids.practice.push(id),
                "public" => ids.public.push(id),
                _ => ids.private.push(id),
            }
        }
    }
    let mut seeds = Vec::with_capacity(SEEDS);
    let mut bytes = [0u8; 4 * SEEDS];
    getrandom::fill(&mut bytes)
        .map_err(|e| RegistryError::Internal(format!("no randomness: {e}")))?;
    for chunk in bytes.chunks(4) {
        seeds.push(i64::from(
            u32::from_le_bytes(chunk.try_into().unwrap_or_default()) >> 1,
        ));
    }
    Ok(storage
        .create_competition(&spec.with_mazes(ids), &seeds, organiser_id)
        .await?)
}

/// Adds maze `m` to competition `c`'s practice set while it takes part (before its
/// close): public on this server (admitted if new); answers its id.
///
/// # Errors
/// [`RegistryError::Conflict`] once closed or for a maze in it already, or a hidden
/// maze's layout; [`RegistryError::Invalid`] for a bad maze; the database.
pub async fn add_practice_maze(
    storage: &Storage,
    c: &CompetitionRow,
    m: &MazeText,
    now: i64,
) -> Result<i64> {
    practice_open(c, now)?;
    let id = admit(storage, m, false).await.map_err(|e| match e {
        RegistryError::Invalid(why) => {
            RegistryError::Invalid(format!("practice maze {:?}: {why}", m.name))
        }
        other => other,
    })?;
    storage.add_practice_maze(c.competition_id, id).await?;
    Ok(id)
}

/// Removes practice maze `maze_id` from competition `c` while it takes part (its
/// practice matches stay).
///
/// # Errors
/// [`RegistryError::Conflict`] once closed; [`RegistryError::NotFound`] for a maze that
/// is not one of its practice mazes; the database.
pub async fn remove_practice_maze(
    storage: &Storage,
    c: &CompetitionRow,
    maze_id: i64,
    now: i64,
) -> Result<()> {
    practice_open(c, now)?;
    if !storage
        .remove_practice_maze(c.competition_id, maze_id)
        .await?
    {
        return Err(RegistryError::NotFound(format!(
            "maze {maze_id} is not a practice maze of competition {}",
            c.name
        )));
    }
    Ok(())
}

/// Refuses a change of the practice mazes once `c` has closed.
fn practice_open(c: &CompetitionRow, now: i64) -> Result<()> {
    if c.kind == "default" || phase(c, now).is_closed() {
        return Err(RegistryError::Conflict(format!(
            "competition {} takes no practice mazes now: it has closed (or is the default one)",
            c.name
        )));
    }
    Ok(())
}

/// The stored maze of `m`'s layout, or `m` admitted; its visibility must be `hidden`.
async fn admit(storage: &Storage, m: &MazeText, hidden: bool) -> Result<i64> {
    let text = m.layout.clone().into_bytes();
    let maze = crate::registry::bundles::blocking(move || mazefile::parse(&text))
        .await?
        .map_err(|e| RegistryError::Invalid(format!("invalid maze: {e}")))?;
    if let Some(stored) = storage.get_maze_by_hash(&maze.hash()).await? {
        // A hidden maze that ranks in another competition stays that competition's:
        // played here, its results would show there (what a sealed set holds is the
        // other competition's secret, so the answer names neither).
        if stored.hidden && storage.maze_ranks_in_a_competition(stored.maze_id).await? {
            return Err(RegistryError::Conflict(
                "its layout is a hidden ranking maze of another competition on this server: choose another maze"
                    .into(),
            ));
        }
        return match (stored.hidden, hidden) {
            (true, true) | (false, false) => Ok(stored.maze_id),
            (false, true) => Err(RegistryError::Invalid(
                "its layout is public on this server already: a ranking maze must be hidden".into(),
            )),
            (true, false) => Err(RegistryError::Invalid(
                "its layout is a hidden maze on this server: a practice maze must be public".into(),
            )),
        };
    }
    Ok(
        crate::registry::mazes::admit(storage, &m.name, m.layout.as_bytes(), hidden)
            .await?
            .maze_id,
    )
}

/// What an organiser may change after creating a competition (fields left out stay).
#[derive(Debug, Clone, Default, serde::Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct Patch {
    /// Title.
    pub title: Option<String>,
    /// Description.
    pub description: Option<String>,
    /// Rules.
    pub rules: Option<String>,
    /// Opening (before it opens only).
    pub opens_at: Option<Timestamp>,
    /// Close (before it closes only; the close moved to now closes it now).
    pub closes_at: Option<Timestamp>,
    /// Freeze before the close, hours (a negative number: no freeze).
    pub freeze_hours: Option<f64>,
    /// Versions per entrant per 24 hours.
    pub versions_per_day: Option<u32>,
    /// Practice matches per entrant per 24 hours.
    pub practice_per_day: Option<u32>,
    /// The final selection rule.
    pub selection: Option<Rule>,
    /// With `choice`: how many versions an entrant may choose.
    pub max_selected: Option<u32>,
    /// The final run's repeats.
    pub final_repeats: Option<u32>,
    /// Whether the private mazes are shown with the results.
    pub reveal_private_mazes: Option<bool>,
    /// Whether the results wait for an organiser to publish them (until they are
    /// written: afterwards they are published, [`super::publish`]).
    pub hold_results: Option<bool>,
    /// The match limits (all three, replacing the old).
    pub limits: Option<Limits>,
    /// How new versions are checked: `start`, `match` or `off` (versions checked
    /// already keep their status).
    pub validation: Option<crate::competition::Validation>,
    /// Hands the competition to the organiser of this name (the admin only: the API
    /// checks it).
    pub organiser: Option<String>,
}

/// Applies `patch` to competition `c` at `now`. Once closed, nothing but the texts
/// changes; the opening cannot move once open.
///
/// # Errors
/// [`RegistryError::Conflict`] for a change too late, [`RegistryError::Invalid`] for a
/// value out of range, the database.
pub async fn edit(
    storage: &Storage,
    mut c: CompetitionRow,
    patch: Patch,
    now: i64,
) -> Result<CompetitionRow> {
    if c.kind == "default" {
        return Err(RegistryError::Conflict(
            "the default competition (the server's ranking) has no settings to edit".into(),
        ));
    }
    let phase = phase(&c, now);
    let rules_change = patch.opens_at.is_some()
        || patch.closes_at.is_some()
        || patch.freeze_hours.is_some()
        || patch.versions_per_day.is_some()
        || patch.practice_per_day.is_some()
        || patch.selection.is_some()
        || patch.max_selected.is_some()
        || patch.final_repeats.is_some()
        || patch.reveal_private_mazes.is_some()
        || patch.limits.is_some()
        || patch.validation.is_some();
    if phase.is_closed() && rules_change {
        return Err(RegistryError::Conflict(format!(
            "competition {} closed at {}: only its title, description and rules can change",
            c.name,
            Timestamp(c.closes_at.unwrap_or(0)).words()
        )));
    }
    if let Some(t) = patch.opens_at
        && phase != Phase::Upcoming
        && Some(t.0) != c.opens_at
    {
        return Err(RegistryError::Conflict(format!(
            "competition {} is open already: its opening cannot move",
            c.name
        )));
    }
    let invalid = |e: spec::SpecError| RegistryError::Invalid(e.0);
    if let Some(title) = patch.title {
        if title.trim().is_empty() || title.chars().count() > spec::MAX_TITLE_CHARS {
            return Err(RegistryError::Invalid(format!(
                "a title is 1 to {} characters",
                spec::MAX_TITLE_CHARS
            )));
        }
        c.title = title;
    }
    for (text, slot) in [
        (patch.description, &mut c.description),
        (patch.rules, &mut c.rules),
    ] {
        if let Some(text) = text {
            if text.chars().count() > spec::MAX_TEXT_CHARS {
                return Err(RegistryError::Invalid(format!(
                    "a text is at most {} characters",
                    spec::MAX_TEXT_CHARS
                )));
            }
            *slot = text;
        }
    }
    let opens = patch.opens_at.map_or(c.opens_at.unwrap_or(0), |t| t.0);
    // A close moved into the past closes the competition now.
    let closes = patch
        .closes_at
        .map_or(c.closes_at.unwrap_or(0), |t| t.0.max(now));
    let freeze_hours = match patch.freeze_hours {
        Some(h) if h < 0.0 => None,
        Some(h) => Some(h),
        None => c.freeze_ms.map(|ms| ms as f64 / 3_600_000.0),
    };
    check_schedule(Timestamp(opens), Timestamp(closes), freeze_hours).map_err(invalid)?;
    let old_freeze = timeline(&c).and_then(|t| t.frozen_from());
    let old_close = c.closes_at.unwrap_or(0);
    c.opens_at = Some(opens);
    c.closes_at = Some(closes);
    c.freeze_ms = freeze_hours.map(|h| (h * 3_600_000.0).round() as i64);
    // A close moved earlier never freezes the board in the past: a board frozen
    // already stays frozen from when it froze, and one not frozen yet freezes at the
    // earliest now (a close moved to now: not before the close).
    if closes < old_close
        && patch.freeze_hours.is_none()
        && let (Some(freeze), Some(new)) = (c.freeze_ms, timeline(&c).and_then(|t| t.frozen_from()))
    {
        let start = match old_freeze {
            Some(old) if old <= now => old,
            _ => new.max(now),
        };
        if start != new {
            c.freeze_ms = Some((closes - start).clamp(0, freeze));
        }
    }
    let counts = [
        (
            "versions_per_day",
            patch.versions_per_day,
            0,
            1000,
            &mut c.versions_per_day,
        ),
        (
            "practice_per_day",
            patch.practice_per_day,
            0,
            10_000,
            &mut c.practice_per_day,
        ),
        (
            "max_selected",
            patch.max_selected,
            1,
            10,
            &mut c.max_selected,
        ),
        (
            "final_repeats",
            patch.final_repeats,
            0,
            50,
            &mut c.final_repeats,
        ),
    ];
    for (field, value, low, high, slot) in counts {
        if let Some(v) = value {
            if !(low..=high).contains(&v) {
                return Err(RegistryError::Invalid(format!(
                    "{field} is {low} to {high}, not {v}"
                )));
            }
            *slot = i64::from(v);
        }
    }
    if let Some(rule) = patch.selection {
        c.selection = rule.as_str().to_string();
    }
    if let Some(reveal) = patch.reveal_private_mazes {
        c.reveal_private_mazes = reveal;
    }
    if let Some(hold) = patch.hold_results.filter(|&h| h != c.hold_results) {
        if matches!(c.state.as_deref(), Some("held" | "final")) {
            return Err(RegistryError::Conflict(format!(
                "the results of {} are written: they are published, not held, from now on{}",
                c.name,
                if c.state.as_deref() == Some("held") {
                    " (publish them when the class is ready)"
                } else {
                    ""
                }
            )));
        }
        c.hold_results = hold;
    }
    if let Some(v) = patch.validation {
        c.validation = v.as_str().to_string();
    }
    if let Some(limits) = patch.limits {
        limits.check().map_err(invalid)?;
        c.limits = serde_json::to_string(&limits).unwrap_or_else(|_| "{}".into());
    }
    let organiser = match &patch.organiser {
        Some(name) => Some(
            storage
                .organiser_by_name(name.trim())
                .await?
                .ok_or_else(|| RegistryError::Invalid(format!("no organiser {name:?}")))?,
        ),
        None => None,
    };
    storage.save_competition_settings(&c).await?;
    if let Some(id) = organiser {
        storage
            .set_competition_organiser(c.competition_id, Some(id))
            .await?;
        c.organiser_id = Some(id);
    }
    Ok(c)
}

/// The ids of `mazes` in set `set` (`practice`, `public`, `private`), in order.
pub(super) fn in_set(mazes: &[CompetitionMaze], set: &str) -> Vec<i64> {
    mazes
        .iter()
        .filter(|m| m.maze_set == set)
        .map(|m| m.maze_id)
        .collect()
}

/// The tournament whose matches decide the results: the final run's if there is one,
/// else the private set's.
pub fn deciding_tournament(c: &CompetitionRow) -> Option<i64> {
    c.final_tournament_id.or(c.private_tournament_id)
}
