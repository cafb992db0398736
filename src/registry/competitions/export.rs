//! A competition written back as its folder (its file and every maze).

use crate::competition::selection::Rule;
use crate::competition::{Spec, Timestamp};
use crate::registry::{RegistryError, Result};
use crate::storage::Storage;
use crate::storage::competitions::CompetitionRow;

/// Competition `c` as the files of a folder that `competition create` (or the
/// organiser's page) takes back: `competition.toml` naming `mazes/SET/NAME.txt`, and
/// those mazes; each as (relative path, text), the competition file first. Private and
/// public mazes are in it: it is for the competition's organisers only.
///
/// # Errors
/// [`RegistryError::Conflict`] for the default competition (nothing to export); a maze
/// gone; the database.
pub async fn export_files(storage: &Storage, c: &CompetitionRow) -> Result<Vec<(String, String)>> {
    let (Some(opens), Some(closes)) = (c.opens_at, c.closes_at) else {
        return Err(RegistryError::Conflict(
            "the default competition is the server's ranking: there is nothing to export".into(),
        ));
    };
    let mut sets: crate::competition::MazeSets<String> = crate::competition::MazeSets {
        practice: Vec::new(),
        public: Vec::new(),
        private: Vec::new(),
    };
    let mut mazes: Vec<(String, String)> = Vec::new();
    for m in storage.competition_mazes(c.competition_id).await? {
        let layout = storage
            .get_maze(m.maze_id)
            .await?
            .ok_or_else(|| RegistryError::Internal(format!("maze {} is gone", m.maze_id)))?
            .layout;
        let stem: String = m
            .name
            .chars()
            .map(|ch| {
                if ch.is_ascii_alphanumeric() || "-_.".contains(ch) {
                    ch
                } else {
                    '_'
                }
            })
            .collect();
        let stem = stem.trim_start_matches('.').to_string();
        let folder = format!("mazes/{}", m.maze_set);
        let mut rel = format!("{folder}/{stem}.txt");
        let mut n = 2;
        while mazes.iter().any(|(p, _)| *p == rel) {
            rel = format!("{folder}/{stem}-{n}.txt");
            n += 1;
        }
        match m.maze_set.as_str() {
            "practice" => sets.practice.push(rel.clone()),
            "public" => sets.public.push(rel.clone()),
            _ => sets.private.push(rel.clone()),
        }
        mazes.push((rel, layout));
    }
    let spec = Spec {
        name: c.name.clone(),
        title: c.title.clone(),
        description: c.description.clone(),
        rules: c.rules.clone(),
        opens_at: Timestamp(opens),
        closes_at: Timestamp(closes),
        freeze_hours: c.freeze_ms.map(|ms| ms as f64 / 3_600_000.0),
        repeats: c.repeats as u32,
        final_repeats: c.final_repeats as u32,
        versions_per_day: c.versions_per_day as u32,
        practice_per_day: c.practice_per_day as u32,
        selection: Rule::parse(&c.selection).unwrap_or_default(),
        max_selected: c.max_selected as u32,
        reveal_private_mazes: c.reveal_private_mazes,
        hold_results: c.hold_results,
        limits: c.limit_set(),
        validation: crate::competition::Validation::parse(&c.validation),
        mazes: sets,
    };
    let text = toml::to_string(&spec).map_err(|e| {
        RegistryError::Internal(format!("cannot write the competition as TOML: {e}"))
    })?;
    let mut files = vec![(
        "competition.toml".to_string(),
        format!(
            "# Exported by mazearena {}\n{text}",
            crate::runner::ENGINE_VERSION
        ),
    )];
    files.extend(mazes);
    Ok(files)
}

/// `files` (relative path, text) as a `.tar.gz` archive under folder `top`.
///
/// # Errors
/// Writing the archive in memory.
pub fn tar_gz(top: &str, files: &[(String, String)]) -> std::io::Result<Vec<u8>> {
    let gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    let mut tar = tar::Builder::new(gz);
    for (rel, text) in files {
        let mut header = tar::Header::new_gnu();
        header.set_size(text.len() as u64);
        header.set_mode(0o644);
        header.set_mtime(0);
        header.set_cksum();
        tar.append_data(&mut header, format!("{top}/{rel}"), text.as_bytes())?;
    }
    tar.into_inner()?.finish()
}
