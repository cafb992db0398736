//! What defines a competition: the same fields in a competition file (TOML, maze sets
//! naming maze files) and in the API (JSON, maze sets holding the mazes' text), checked
//! here once for both.

use serde::{Deserialize, Serialize};

use super::Rule;

/// Longest competition name (an address part: `a-z`, `0-9`, `-`).
pub const MAX_NAME_CHARS: usize = 64;
/// Longest title.
pub const MAX_TITLE_CHARS: usize = 200;
/// Longest description or rules text.
pub const MAX_TEXT_CHARS: usize = 20_000;
/// Most mazes in one competition (all sets).
pub const MAX_MAZES: usize = 500;

/// A moment, unix milliseconds; written as RFC 3339 in UTC (`2027-03-01T00:00:00Z`),
/// read from RFC 3339 with any offset (a string, or a TOML date-time).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct Timestamp(pub i64);

impl Timestamp {
    /// RFC 3339 in UTC, with milliseconds only when there are some.
    pub fn rfc3339(self) -> String {
        let (date, secs_of_day) = civil(self.0);
        let ms = self.0.rem_euclid(1000);
        let time = format!(
            "{:02}:{:02}:{:02}",
            secs_of_day / 3600,
            (secs_of_day % 3600) / 60,
            secs_of_day % 60
        );
        if ms == 0 {
            format!("{date}T{time}Z")
        } else {
            format!("{date}T{time}.{ms:03}Z")
        }
    }

    /// For people, the one way times are written on pages and in messages:
    /// `2027-03-01 14:00 UTC`.
    pub fn words(self) -> String {
        let (date, secs_of_day) = civil(self.0);
        format!(
            "{date} {:02}:{:02} UTC",
            secs_of_day / 3600,
            (secs_of_day % 3600) / 60
        )
    }

    /// Parses RFC 3339 with a date, a time and an offset.
    ///
    /// # Errors
    /// A text that is not such a date-time, said in words.
    pub fn parse(text: &str) -> Result<Timestamp, String> {
        let dt: toml::value::Datetime = text
            .trim()
            .parse()
            .map_err(|_| format!("{text:?} is not a date-time like 2027-03-01T00:00:00Z"))?;
        Timestamp::from_toml(&dt)
    }

    fn from_toml(dt: &toml::value::Datetime) -> Result<Timestamp, String> {
        let (Some(date), Some(time), Some(offset)) = (dt.date, dt.time, dt.offset) else {
            return Err(format!(
                "{dt} needs a date, a time and an offset (Z for UTC), like 2027-03-01T00:00:00Z"
            ));
        };
        let offset_minutes = match offset {
            toml::value::Offset::Z => 0,
            toml::value::Offset::Custom { minutes } => i64::from(minutes),
        };
        let days = days_from_civil(
            i64::from(date.year),
            i64::from(date.month),
            i64::from(date.day),
        );
        let secs = days * 86_400
            + i64::from(time.hour) * 3600
            + i64::from(time.minute) * 60
            + i64::from(time.second)
            - offset_minutes * 60;
        Ok(Timestamp(
            secs * 1000 + i64::from(time.nanosecond / 1_000_000),
        ))
    }
}

/// Days since 1970-01-01 of a civil date (Howard Hinnant's algorithm).
fn days_from_civil(y: i64, m: i64, d: i64) -> i64 {
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let mp = (m + 9) % 12;
    let doy = (153 * mp + 2) / 5 + d - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// The civil date (`YYYY-MM-DD`) and second of the day of unix ms `ms`.
fn civil(ms: i64) -> (String, i64) {
    let secs = ms.div_euclid(1000);
    let days = secs.div_euclid(86_400);
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    (format!("{y:04}-{m:02}-{d:02}"), secs.rem_euclid(86_400))
}

impl Serialize for Timestamp {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.rfc3339())
    }
}

impl<'de> Deserialize<'de> for Timestamp {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Text(String),
            Toml(toml::value::Datetime),
        }
        match Raw::deserialize(d).map_err(|_| {
            serde::de::Error::custom("expected a date-time like 2027-03-01T00:00:00Z")
        })? {
            Raw::Text(t) => Timestamp::parse(&t),
            Raw::Toml(dt) => Timestamp::from_toml(&dt),
        }
        .map_err(serde::de::Error::custom)
    }
}

impl utoipa::PartialSchema for Timestamp {
    fn schema() -> utoipa::openapi::RefOr<utoipa::openapi::schema::Schema> {
        utoipa::openapi::schema::ObjectBuilder::new()
            .schema_type(utoipa::openapi::schema::Type::String)
            .format(Some(utoipa::openapi::schema::SchemaFormat::KnownFormat(
                utoipa::openapi::schema::KnownFormat::DateTime,
            )))
            .into()
    }
}

impl utoipa::ToSchema for Timestamp {}

/// A maze given by its text (numeric or ASCII format) and a name.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct MazeText {
    /// The maze's name.
    pub name: String,
    /// The maze file's text.
    pub layout: String,
}

/// The three maze sets; `M` is a file path (competition file) or a [`MazeText`] (API).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct MazeSets<M> {
    /// Public layouts, full replays, matches on request.
    #[serde(default = "Vec::new")]
    pub practice: Vec<M>,
    /// Hidden layouts; their scores make the public leaderboard.
    pub public: Vec<M>,
    /// Hidden layouts; their scores stay sealed until the close.
    pub private: Vec<M>,
}

/// A competition's match limits; a limit left out is the server's.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct Limits {
    /// CPU time for every answer after the first (ms).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub move_timeout_ms: Option<u64>,
    /// CPU time for the first answer, from the process start (ms).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub startup_timeout_ms: Option<u64>,
    /// CPU time the moves of a match may use beyond `move_timeout_ms`, all together (ms).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_bank_ms: Option<u64>,
    /// The bot's memory (MiB).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub memory_limit_mb: Option<u64>,
}

/// A competition as written in its file or sent to the API.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct Spec<M> {
    /// Short unique name, used in addresses: `a-z`, `0-9` and `-`.
    pub name: String,
    /// Title shown on its pages.
    pub title: String,
    /// What the competition is about (shown as text).
    #[serde(default)]
    pub description: String,
    /// Its rules (shown as text).
    #[serde(default)]
    pub rules: String,
    /// Versions are ranked from then on.
    pub opens_at: Timestamp,
    /// No new versions from then on.
    pub closes_at: Timestamp,
    /// The public leaderboard freezes this many hours before the close.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub freeze_hours: Option<f64>,
    /// Matches of each version on each ranking maze (1 to 20; default 1).
    #[serde(default = "one")]
    pub repeats: u32,
    /// The final run's matches of each selected version on each private maze (up to
    /// 50; 0: as many as `repeats`). The final run, after the close, is the private
    /// set's only run.
    #[serde(default)]
    pub final_repeats: u32,
    /// Versions per entrant per 24 hours (default 5); a version that fails to build or
    /// whose matches the server could not play does not count.
    #[serde(default = "five")]
    pub versions_per_day: u32,
    /// Practice matches per entrant per 24 hours (default 50).
    #[serde(default = "fifty")]
    pub practice_per_day: u32,
    /// Which versions count at the end: `latest`, `best_public`, or `choice`.
    #[serde(default)]
    pub selection: Rule,
    /// With `choice`: how many versions an entrant may choose (1 to 10; default 1).
    #[serde(default = "one")]
    pub max_selected: u32,
    /// Whether the private mazes' layouts and replays are shown once the results are
    /// final.
    #[serde(default)]
    pub reveal_private_mazes: bool,
    /// Whether the results, once written, wait for an organiser to publish them (for a
    /// reveal: the class learns them from `/competitions/NAME/reveal`); by default they
    /// are published at once.
    #[serde(default)]
    pub hold_results: bool,
    /// The match limits.
    #[serde(default)]
    pub limits: Limits,
    /// How each new version is checked before it plays: `start` (the default), `match`
    /// or `off` ([`Validation`]).
    #[serde(default)]
    pub validation: Validation,
    /// The maze sets.
    pub mazes: MazeSets<M>,
}

/// How a competition checks each new version before it plays: its validation match, on
/// the competition's practice mazes, under its limits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "snake_case")]
pub enum Validation {
    /// Invalid only for a failure that no maze causes: the version fails before its
    /// first move on every maze it is tried on (its practice mazes, then a generated
    /// maze of another size): it does not start, has a syntax error, needs another
    /// runtime or speaks another protocol. A failure on a maze after the first move, or
    /// on some mazes only, is a warning to its owner: the version plays.
    #[default]
    Start,
    /// Invalid for any failure in the validation match on the first practice maze.
    Match,
    /// No validation match: every version that builds plays.
    Off,
}

impl Validation {
    /// Its name: `start`, `match` or `off`.
    pub fn as_str(self) -> &'static str {
        match self {
            Validation::Start => "start",
            Validation::Match => "match",
            Validation::Off => "off",
        }
    }

    /// The validation named `name` (a stored one that is not known: `start`).
    pub fn parse(name: &str) -> Validation {
        match name {
            "match" => Validation::Match,
            "off" => Validation::Off,
            _ => Validation::Start,
        }
    }
}

fn one() -> u32 {
    1
}
fn five() -> u32 {
    5
}
fn fifty() -> u32 {
    50
}

/// A competition that cannot be.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct SpecError(pub String);

/// Whether `name` may name a competition.
pub fn check_name(name: &str) -> Result<(), SpecError> {
    let ok = !name.is_empty()
        && name.len() <= MAX_NAME_CHARS
        && name
            .bytes()
            .all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'-')
        && !name.starts_with('-');
    if ok {
        Ok(())
    } else {
        Err(SpecError(format!(
            "a competition name is 1 to {MAX_NAME_CHARS} of a-z, 0-9 and -, not starting with -: {name:?}"
        )))
    }
}

impl<M> Spec<M> {
    /// Checks every field but the mazes' contents: names, texts, times, counts, limits.
    ///
    /// # Errors
    /// The first thing wrong, in words.
    pub fn check(&self) -> Result<(), SpecError> {
        let fail = |m: String| Err(SpecError(m));
        check_name(&self.name)?;
        if self.title.trim().is_empty() || self.title.chars().count() > MAX_TITLE_CHARS {
            return fail(format!("a title is 1 to {MAX_TITLE_CHARS} characters"));
        }
        for (field, text) in [("description", &self.description), ("rules", &self.rules)] {
            if text.chars().count() > MAX_TEXT_CHARS {
                return fail(format!(
                    "the {field} is longer than {MAX_TEXT_CHARS} characters"
                ));
            }
        }
        self.check_schedule()?;
        let counts = [
            ("repeats", self.repeats, 1, 20),
            ("final_repeats", self.final_repeats, 0, 50),
            ("versions_per_day", self.versions_per_day, 0, 1000),
            ("practice_per_day", self.practice_per_day, 0, 10_000),
            ("max_selected", self.max_selected, 1, 10),
        ];
        for (field, value, low, high) in counts {
            if !(low..=high).contains(&value) {
                return fail(format!("{field} is {low} to {high}, not {value}"));
            }
        }
        self.limits.check()?;
        let m = &self.mazes;
        if m.public.is_empty() || m.private.is_empty() {
            return fail("the public and private ranking sets need a maze each at least".into());
        }
        let total = m.practice.len() + m.public.len() + m.private.len();
        if total > MAX_MAZES {
            return fail(format!("{total} mazes: at most {MAX_MAZES}"));
        }
        Ok(())
    }

    /// Checks the times: opening before closing, a freeze of 0 or more hours.
    ///
    /// # Errors
    /// As said.
    pub fn check_schedule(&self) -> Result<(), SpecError> {
        check_schedule(self.opens_at, self.closes_at, self.freeze_hours)
    }

    /// The freeze in milliseconds.
    pub fn freeze_ms(&self) -> Option<i64> {
        self.freeze_hours.map(|h| (h * 3_600_000.0).round() as i64)
    }

    /// The same competition with its mazes given otherwise.
    pub fn with_mazes<N>(self, mazes: MazeSets<N>) -> Spec<N> {
        Spec {
            name: self.name,
            title: self.title,
            description: self.description,
            rules: self.rules,
            opens_at: self.opens_at,
            closes_at: self.closes_at,
            freeze_hours: self.freeze_hours,
            repeats: self.repeats,
            final_repeats: self.final_repeats,
            versions_per_day: self.versions_per_day,
            practice_per_day: self.practice_per_day,
            selection: self.selection,
            max_selected: self.max_selected,
            reveal_private_mazes: self.reveal_private_mazes,
            hold_results: self.hold_results,
            limits: self.limits,
            validation: self.validation,
            mazes,
        }
    }
}

/// Checks a timeline: opening before closing, a freeze of 0 to 10,000 hours.
///
/// # Errors
/// As said.
pub fn check_schedule(
    opens_at: Timestamp,
    closes_at: Timestamp,
    freeze_hours: Option<f64>,
) -> Result<(), SpecError> {
    if opens_at >= closes_at {
        return Err(SpecError(format!(
            "opens_at ({}) must come before closes_at ({})",
            opens_at.rfc3339(),
            closes_at.rfc3339()
        )));
    }
    if let Some(h) = freeze_hours
        && !(h.is_finite() && (0.0..=10_000.0).contains(&h))
    {
        return Err(SpecError(format!("freeze_hours is 0 to 10000, not {h}")));
    }
    Ok(())
}

impl Limits {
    /// Checks each limit given against its range.
    ///
    /// # Errors
    /// The first out of range.
    pub fn check(&self) -> Result<(), SpecError> {
        let ranges = [
            ("move_timeout_ms", self.move_timeout_ms, 1, 60_000),
            ("startup_timeout_ms", self.startup_timeout_ms, 1, 600_000),
            ("time_bank_ms", self.time_bank_ms, 0, 600_000),
            ("memory_limit_mb", self.memory_limit_mb, 16, 16_384),
        ];
        for (field, value, low, high) in ranges {
            if let Some(v) = value
                && !(low..=high).contains(&v)
            {
                return Err(SpecError(format!(
                    "limits.{field} is {low} to {high}, not {v}"
                )));
            }
        }
        Ok(())
    }

    /// `base` with these limits in place of its own where given.
    pub fn apply(&self, mut base: crate::runner::Limits) -> crate::runner::Limits {
        use std::time::Duration;
        if let Some(ms) = self.move_timeout_ms {
            base.move_timeout = Some(Duration::from_millis(ms));
        }
        if let Some(ms) = self.startup_timeout_ms {
            base.startup_timeout = Some(Duration::from_millis(ms));
        }
        if let Some(ms) = self.time_bank_ms {
            base.time_bank = Duration::from_millis(ms);
        }
        if let Some(mb) = self.memory_limit_mb {
            base.memory_limit_mb = Some(mb);
        }
        base
    }
}

/// Reads a competition file's text (TOML naming maze files) and gives each maze its
/// text from `lookup` (a path as the file names it -> the maze file's text, or why
/// not). A maze is named by its file's stem.
///
/// # Errors
/// The text is not a competition file; a maze cannot be found or read.
pub fn read_competition_file(
    text: &str,
    mut lookup: impl FnMut(&str) -> Result<String, String>,
) -> Result<Spec<MazeText>, SpecError> {
    let spec: Spec<String> =
        toml::from_str(text).map_err(|e| SpecError(format!("not a competition file: {e}")))?;
    let mut load = |paths: &Vec<String>| -> Result<Vec<MazeText>, SpecError> {
        paths
            .iter()
            .map(|p| {
                let layout = lookup(p).map_err(SpecError)?;
                let file = p.rsplit('/').next().unwrap_or(p);
                let name = file
                    .rsplit_once('.')
                    .map_or(file, |(stem, _)| stem)
                    .to_string();
                let name = if name.is_empty() { p.clone() } else { name };
                Ok(MazeText { name, layout })
            })
            .collect()
    };
    let mazes = MazeSets {
        practice: load(&spec.mazes.practice)?,
        public: load(&spec.mazes.public)?,
        private: load(&spec.mazes.private)?,
    };
    Ok(spec.with_mazes(mazes))
}

#[cfg(test)]
mod tests {
    use super::*;

    const FILE: &str = r#"
name = "spring-2027"
title = "Spring 2027"
opens_at = 2027-03-01T00:00:00Z
closes_at = "2027-04-01T12:30:00+02:00"
freeze_hours = 24
selection = "choice"
max_selected = 2
[limits]
move_timeout_ms = 500
[mazes]
practice = ["a.txt"]
public = ["b.txt"]
private = ["c.txt", "d.txt"]
"#;

    #[test]
    fn a_competition_file_reads_with_its_defaults_and_times_in_utc() {
        let spec: Spec<String> = toml::from_str(FILE).unwrap();
        spec.check().unwrap();
        assert_eq!(spec.opens_at.rfc3339(), "2027-03-01T00:00:00Z");
        assert_eq!(spec.closes_at.rfc3339(), "2027-04-01T10:30:00Z");
        assert_eq!(
            spec.opens_at,
            Timestamp::parse("2027-03-01T00:00:00Z").unwrap()
        );
        assert_eq!(
            (spec.repeats, spec.versions_per_day, spec.practice_per_day),
            (1, 5, 50)
        );
        assert_eq!((spec.selection, spec.max_selected), (Rule::Choice, 2));
        assert_eq!(spec.freeze_ms(), Some(24 * 3_600_000));
        assert_eq!(spec.limits.move_timeout_ms, Some(500));
        assert_eq!(spec.mazes.private.len(), 2);
        // Written back (as JSON here, as TOML by `competition export`), read the same.
        let json = serde_json::to_string(&spec).unwrap();
        assert_eq!(serde_json::from_str::<Spec<String>>(&json).unwrap(), spec);
        assert_eq!(
            Timestamp(1_795_437_296_123).rfc3339(),
            "2026-11-23T12:34:56.123Z"
        );
        assert_eq!(
            Timestamp::parse("2026-11-23T12:34:56.123Z").unwrap().0,
            1_795_437_296_123
        );
    }

    #[test]
    fn a_competition_that_cannot_be_says_why() {
        let base: Spec<String> = toml::from_str(FILE).unwrap();
        let bad = |edit: &dyn Fn(&mut Spec<String>)| {
            let mut s = base.clone();
            edit(&mut s);
            s.check().unwrap_err().0
        };
        assert!(bad(&|s| s.name = "Spring 2027".into()).contains("a-z, 0-9"));
        assert!(bad(&|s| s.closes_at = s.opens_at).contains("must come before"));
        assert!(bad(&|s| s.repeats = 0).contains("repeats is 1 to 20"));
        assert!(bad(&|s| s.freeze_hours = Some(f64::NAN)).contains("freeze_hours"));
        assert!(bad(&|s| s.limits.memory_limit_mb = Some(1)).contains("memory_limit_mb"));
        assert!(bad(&|s| s.mazes.private.clear()).contains("private"));
        assert!(toml::from_str::<Spec<String>>("name = 1").is_err());
        let unknown = FILE.replace("freeze_hours", "freeze_hour");
        assert!(toml::from_str::<Spec<String>>(&unknown).is_err());
        assert!(Timestamp::parse("2027-03-01").unwrap_err().contains("time"));
        assert!(
            Timestamp::parse("2027-03-01T00:00:00")
                .unwrap_err()
                .contains("offset")
        );
    }
}
