//! The demo (`serve --demo`): on a fresh database, the starter kits' bots (Python, and
//! JavaScript where `node` is installed) registered, each by an entrant of its own,
//! playing a tournament on the shipped mazes and entered in a demo competition that is
//! open, so that a newcomer's first page shows a live site. Everything goes through the
//! same registry operations as the API's; the bots build and play in the sandbox as any
//! upload does.

use std::collections::BTreeMap;
use std::path::Path;

use super::bots::{Submission, register};
use super::bundles::BotFiles;
use super::{RegistryError, Result};
use crate::competition::{Limits, MazeSets, MazeText, Rule, Spec, Timestamp, Validation};
use crate::storage::Storage;

/// The demo competition's short name.
pub const COMPETITION: &str = "demo-cup";

/// How long the demo competition stays open.
const OPEN_DAYS: i64 = 30;

/// A kit's file: its name and text.
type KitFile = (&'static str, &'static str);

/// The Python kit: the helper, its map, and four bots.
const PYTHON: &[KitFile] = &[
    ("mazebot.py", include_str!("../../bots/python/mazebot.py")),
    ("mazemap.py", include_str!("../../bots/python/mazemap.py")),
    (
        "simple_bot.py",
        include_str!("../../bots/python/simple_bot.py"),
    ),
    (
        "seed000_smart_map.py",
        include_str!("../../bots/python/seed000_smart_map.py"),
    ),
    (
        "seed002_random_dfs.py",
        include_str!("../../bots/python/seed002_random_dfs.py"),
    ),
    (
        "random_explorer.py",
        include_str!("../../bots/python/random_explorer.py"),
    ),
];

/// The JavaScript kit: the helper and three bots.
const JAVASCRIPT: &[KitFile] = &[
    (
        "mazebot.js",
        include_str!("../../bots/javascript/mazebot.js"),
    ),
    (
        "minimal_bot.js",
        include_str!("../../bots/javascript/minimal_bot.js"),
    ),
    (
        "seed001_value_table.js",
        include_str!("../../bots/javascript/seed001_value_table.js"),
    ),
    (
        "seed003_visit_count.js",
        include_str!("../../bots/javascript/seed003_visit_count.js"),
    ),
];

/// The demo's bots: name, kit, command.
const BOTS: &[(&str, &str, &str)] = &[
    ("simple-python", "python", "python3 simple_bot.py"),
    (
        "seed000-smart-map",
        "python",
        "python3 seed000_smart_map.py",
    ),
    (
        "seed002-random-dfs",
        "python",
        "python3 seed002_random_dfs.py",
    ),
    ("random-explorer", "python", "python3 random_explorer.py"),
    ("minimal-js", "javascript", "node minimal_bot.js"),
    (
        "seed001-value-table",
        "javascript",
        "node seed001_value_table.js",
    ),
    (
        "seed003-visit-count",
        "javascript",
        "node seed003_visit_count.js",
    ),
];

/// What the demo made.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Demo {
    /// The bots registered, by name.
    pub bots: Vec<String>,
    /// The tournament of every bot on the shipped mazes.
    pub tournament_id: i64,
    /// The open competition's short name.
    pub competition: String,
}

/// Seeds a fresh demo database (none if it has bots already: a demo started before):
/// the kits' bots (the JavaScript ones only `with_node`), an entrant each, entered in
/// [`COMPETITION`] (open now for `OPEN_DAYS` (30) days: the first shipped maze to
/// practise on, generated hidden mazes to rank on), and a tournament of them all on the
/// shipped (public) mazes `shipped`. `scratch` is a local folder for the uploads.
///
/// # Errors
/// The database; a kit that cannot be stored.
pub async fn seed(
    storage: &Storage,
    scratch: &Path,
    shipped: &[i64],
    with_node: bool,
    now: i64,
) -> Result<Option<Demo>> {
    if !storage.list_bots().await?.is_empty() {
        return Ok(None);
    }
    let generated = |seed: u64| -> Result<MazeText> {
        let maze = crate::engine::generator::generate(12, seed)
            .map_err(|e| RegistryError::Internal(format!("cannot make a demo maze: {e}")))?;
        Ok(MazeText {
            name: format!("demo-{seed}"),
            layout: crate::engine::mazefile::numeric::write(&maze),
        })
    };
    let practice =
        storage
            .get_maze(*shipped.first().ok_or_else(|| {
                RegistryError::Internal("the shipped mazes are not loaded".into())
            })?)
            .await?
            .ok_or_else(|| RegistryError::Internal("the first shipped maze is gone".into()))?;
    let spec = Spec {
        name: COMPETITION.into(),
        title: "The Demo Cup".into(),
        description: "A competition open on this demo server: register, upload a bot and see it ranked among the starter kits' bots.".into(),
        rules: "One bot per entrant. The public board ranks each entrant's latest version on the hidden public mazes.".into(),
        opens_at: Timestamp(now - 1000),
        closes_at: Timestamp(now + OPEN_DAYS * crate::competition::DAY_MS),
        freeze_hours: None,
        repeats: 1,
        final_repeats: 1,
        versions_per_day: 20,
        practice_per_day: 100,
        selection: Rule::Latest,
        max_selected: 1,
        reveal_private_mazes: true,
        hold_results: false,
        limits: Limits::default(),
        validation: Validation::Start,
        mazes: MazeSets {
            practice: vec![MazeText {
                name: practice.name.clone(),
                layout: practice.layout.clone(),
            }],
            public: vec![generated(9_001)?, generated(9_002)?, generated(9_003)?],
            private: vec![generated(9_004)?, generated(9_005)?],
        },
    };
    let c = super::competitions::create(storage, spec, None).await?;
    let mut names = Vec::new();
    let mut versions = Vec::new();
    for &(name, kit, command) in BOTS {
        let files = match kit {
            "python" => PYTHON,
            _ if with_node => JAVASCRIPT,
            _ => continue,
        };
        let map: BTreeMap<String, String> = files
            .iter()
            .map(|(f, text)| (f.to_string(), text.to_string()))
            .collect();
        let entrant = storage
            .create_entrant(
                &format!("{name}-team"),
                "[]",
                &super::tokens::hash_token(&super::tokens::new_token()?),
                None,
            )
            .await?;
        let submission = Submission {
            command: command.into(),
            build: None,
            env: Vec::new(),
            files: BotFiles::Map(map),
            runtime: None,
            protocol: crate::runner::BotProtocol::V1,
        };
        let registered = register(
            storage,
            name,
            submission,
            scratch,
            Some(entrant.entrant_id),
            None,
            Some(c.competition_id),
        )
        .await?;
        names.push(name.to_string());
        versions.push(registered.version.bot_version_id);
    }
    let t = storage
        .create_tournament("the shipped mazes", &versions, shipped, 1)
        .await?;
    Ok(Some(Demo {
        bots: names,
        tournament_id: t.tournament_id,
        competition: c.name,
    }))
}
