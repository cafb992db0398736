//! `bot.toml`: how a bot folder says what its bots are and how to run them.
//!
//! ```toml
//! name = "simple-python"          # unique name
//! language = "python"             # for people
//! command = "python3 simple_bot.py"
//! build = "cargo build --release" # optional, run once in the folder before playing
//! report = "seed 004, section 4.1"  # optional: where the strategy comes from
//! claimed = { test_maze_01 = 18.133 } # optional: scores its author reported, by maze name
//! env = { ALPHA = "0.5" }         # optional: environment variables for the bot
//! include = [".env"]              # optional: dot-files `mazearena submit` sends too
//! ```
//! A folder with several bots lists them as `[[bot]]` tables with the same keys.

use std::path::{Path, PathBuf};

use serde::Deserialize;

/// The manifest's file name.
pub const MANIFEST_FILE: &str = "bot.toml";

/// One bot of a manifest.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BotManifest {
    /// Unique name.
    pub name: String,
    /// Language, for people.
    #[serde(default)]
    pub language: Option<String>,
    /// Command line run in the bot's folder.
    pub command: String,
    /// Build command run in the folder before playing.
    #[serde(default)]
    pub build: Option<String>,
    /// Free text.
    #[serde(default)]
    pub description: Option<String>,
    /// Where the strategy comes from (e.g. a report and its section).
    #[serde(default)]
    pub report: Option<String>,
    /// Scores the strategy's author reported, by maze file name without extension.
    #[serde(default)]
    pub claimed: std::collections::BTreeMap<String, f64>,
    /// Environment variables for the bot (the only ones of ours it gets).
    #[serde(default)]
    pub env: std::collections::BTreeMap<String, String>,
    /// The server's runtime to put first on the bot's `PATH`, by name (one that
    /// `GET /api/runtimes` lists, e.g. a venv with numpy); `mazearena submit` sends it.
    #[serde(default)]
    pub runtime: Option<String>,
    /// The protocol the bot speaks: `v1` (the default, JSON lines) or `mms` (a mouse
    /// written for the mms simulator, played unchanged: docs/PROTOCOL-mms.md).
    #[serde(default)]
    pub protocol: crate::runner::BotProtocol,
    /// Files `mazearena submit` uploads although it leaves them out otherwise (a name
    /// starting with `.`, or one a `.gitignore` names): relative paths of regular files
    /// inside the folder, checked when packing ([`crate::client::pack::pack`]).
    #[serde(default)]
    pub include: Vec<String>,
    /// The folder (where the manifest is); filled in when loading.
    #[serde(skip)]
    pub dir: PathBuf,
}

#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum ManifestFile {
    Many { bot: Vec<BotManifest> },
    One(Box<BotManifest>),
}

/// Why a manifest could not be used.
#[derive(Debug, thiserror::Error)]
pub enum ManifestError {
    /// The file cannot be read.
    #[error("cannot read {path}: {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The file is not a valid manifest.
    #[error("{path}: {message}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// Nothing found.
    #[error("no {MANIFEST_FILE} found in {0}")]
    NotFound(PathBuf),
}

/// Parses manifest text; `dir` is the folder the bots run in.
///
/// # Errors
/// A message naming what is wrong.
pub fn parse(text: &str, dir: &Path, path: &Path) -> Result<Vec<BotManifest>, ManifestError> {
    let invalid = |message: String| ManifestError::Invalid {
        path: path.to_path_buf(),
        message,
    };
    let file: ManifestFile = toml::from_str(text).map_err(|e| {
        invalid(format!(
            "not a valid manifest (want `name` and `command`, or [[bot]] tables): {e}"
        ))
    })?;
    let mut bots = match file {
        ManifestFile::Many { bot } => bot,
        ManifestFile::One(b) => vec![*b],
    };
    if bots.is_empty() {
        return Err(invalid("the manifest lists no bot".into()));
    }
    for b in &mut bots {
        if b.name.trim().is_empty() || b.command.trim().is_empty() {
            return Err(invalid(
                "every bot needs a non-empty `name` and `command`".into(),
            ));
        }
        let env: Vec<(String, String)> =
            b.env.iter().map(|(k, v)| (k.clone(), v.clone())).collect();
        crate::runner::botenv::check(&env)
            .map_err(|e| invalid(format!("bot {:?}: env: {e}", b.name)))?;
        b.dir = dir.to_path_buf();
    }
    Ok(bots)
}

/// Loads the bots of a manifest file, of a folder holding `bot.toml`, or of every
/// `bot.toml` found below a folder (three levels deep at most).
///
/// # Errors
/// An unreadable or invalid manifest, or none found.
pub fn load(path: &Path) -> Result<Vec<BotManifest>, ManifestError> {
    let read = |file: &Path| -> Result<Vec<BotManifest>, ManifestError> {
        let text = std::fs::read_to_string(file).map_err(|source| ManifestError::Read {
            path: file.to_path_buf(),
            source,
        })?;
        let dir = file.parent().unwrap_or(Path::new("."));
        let dir = dir.canonicalize().unwrap_or_else(|_| dir.to_path_buf());
        parse(&text, &dir, file)
    };
    if path.is_file() {
        return read(path);
    }
    let mut found = Vec::new();
    collect(path, 0, &mut found);
    found.sort();
    if found.is_empty() {
        return Err(ManifestError::NotFound(path.to_path_buf()));
    }
    let mut bots = Vec::new();
    for file in found {
        bots.extend(read(&file)?);
    }
    Ok(bots)
}

fn collect(dir: &Path, depth: usize, out: &mut Vec<PathBuf>) {
    let manifest = dir.join(MANIFEST_FILE);
    if manifest.is_file() {
        out.push(manifest);
        return;
    }
    if depth >= 3 {
        return;
    }
    if let Ok(entries) = std::fs::read_dir(dir) {
        for e in entries.flatten() {
            let p = e.path();
            let hidden = e.file_name().to_string_lossy().starts_with('.');
            let skip = ["target", "node_modules", "__pycache__"]
                .iter()
                .any(|s| e.file_name() == *s);
            if p.is_dir() && !hidden && !skip {
                collect(&p, depth + 1, out);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_bot_or_many() {
        let one = parse(
            "name = \"a\"\ncommand = \"python3 a.py\"\n",
            Path::new("/b"),
            Path::new("x"),
        )
        .unwrap();
        assert_eq!(one.len(), 1);
        assert_eq!(one[0].dir, Path::new("/b"));
        let many = parse(
            "[[bot]]\nname = \"a\"\ncommand = \"x\"\n[[bot]]\nname = \"b\"\ncommand = \"y\"\nbuild = \"make\"\n",
            Path::new("/b"),
            Path::new("x"),
        )
        .unwrap();
        assert_eq!(many.len(), 2);
        assert_eq!(many[1].build.as_deref(), Some("make"));
        let env = parse(
            "name = \"a\"\ncommand = \"x\"\nenv = { ALPHA = \"0.5\" }\n",
            Path::new("/b"),
            Path::new("x"),
        )
        .unwrap();
        assert_eq!(env[0].env["ALPHA"], "0.5");
    }

    #[test]
    fn bad_manifests_say_why() {
        for bad in [
            "name = \"a\"\n",
            "command = 1\n",
            "name = \"\"\ncommand = \"x\"\n",
            "[[bot]]\n",
            "name = \"a\"\ncommand = \"x\"\nenv = { PATH = \"/evil\" }\n",
        ] {
            let e = parse(bad, Path::new("/b"), Path::new("bot.toml")).unwrap_err();
            assert!(e.to_string().starts_with("bot.toml: "), "{e}");
        }
    }
}
