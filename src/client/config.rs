//! The participant's login: the server's address and their key, kept in a TOML file that
//! only they can read (`$XDG_CONFIG_HOME/mazearena/client.toml`, else
//! `~/.config/mazearena/client.toml`; `MAZEARENA_CONFIG` names another file), and the
//! owner tokens of bots registered without an entrant's key. `MAZEARENA_SERVER` and
//! `MAZEARENA_KEY` override the file.

use std::collections::BTreeMap;
use std::io::Write;
use std::os::unix::fs::{DirBuilderExt, OpenOptionsExt, PermissionsExt};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

/// A bot registered without an entrant's key: its id and owner token.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct OwnedBot {
    /// The bot's id on the server.
    pub bot_id: i64,
    /// Its owner token.
    pub token: String,
}

/// What `mazearena login` keeps.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Config {
    /// The server's address, e.g. `https://maze.example.org`.
    #[serde(default)]
    pub server: Option<String>,
    /// The entrant's key (or a bot's owner token).
    #[serde(default)]
    pub key: Option<String>,
    /// Bots registered without an entrant's key, by name, on `server`.
    #[serde(default)]
    pub bots: BTreeMap<String, OwnedBot>,
}

/// The configuration file's path.
pub fn path() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("MAZEARENA_CONFIG").filter(|p| !p.is_empty()) {
        return Some(PathBuf::from(p));
    }
    let base = std::env::var_os("XDG_CONFIG_HOME")
        .filter(|p| !p.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".config")))?;
    Some(base.join("mazearena").join("client.toml"))
}

impl Config {
    /// The file at `path`, or an empty configuration when there is none.
    ///
    /// # Errors
    /// A file that cannot be read or is not a configuration; one that others can read
    /// (a key must stay its owner's).
    pub fn load(path: &Path) -> anyhow::Result<Config> {
        let text = match std::fs::read_to_string(path) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Config::default()),
            Err(e) => anyhow::bail!("cannot read {}: {e}", path.display()),
        };
        let mode = std::fs::metadata(path)?.permissions().mode();
        anyhow::ensure!(
            mode & 0o077 == 0,
            "{} can be read by others (mode {:o}): it holds your key; run `chmod 600 {}`",
            path.display(),
            mode & 0o777,
            path.display()
        );
        toml::from_str(&text)
            .map_err(|e| anyhow::anyhow!("{} is not a mazearena client file: {e}", path.display()))
    }

    /// Writes the configuration to `path`, readable and writable by its owner only (its
    /// folder made as 0700 if missing), replacing the file in one step.
    ///
    /// # Errors
    /// The file or its folder cannot be written.
    pub fn save(&self, path: &Path) -> anyhow::Result<()> {
        let dir = path.parent().unwrap_or(Path::new("."));
        std::fs::DirBuilder::new()
            .recursive(true)
            .mode(0o700)
            .create(dir)
            .map_err(|e| anyhow::anyhow!("cannot make {}: {e}", dir.display()))?;
        let text = toml::to_string(self)?;
        let tmp = path.with_extension("toml.new");
        let _ = std::fs::remove_file(&tmp);
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .mode(0o600)
            .open(&tmp)
            .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", tmp.display()))?;
        f.write_all(b"# mazearena client: the server and your key (keep this file to yourself)\n")?;
        f.write_all(text.as_bytes())?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
            .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))?;
        Ok(())
    }

    /// The server and key to use: `MAZEARENA_SERVER` and `MAZEARENA_KEY` when set, else
    /// the file's.
    pub fn effective(&self) -> (Option<String>, Option<String>) {
        let var = |name: &str| std::env::var(name).ok().filter(|v| !v.trim().is_empty());
        (
            var("MAZEARENA_SERVER").or_else(|| self.server.clone()),
            var("MAZEARENA_KEY").or_else(|| self.key.clone()),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_saved_login_is_read_back_and_only_its_owner_may_read_it() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sub/client.toml");
        assert_eq!(Config::load(&path).unwrap(), Config::default());
        let mut c = Config {
            server: Some("http://localhost:8080".into()),
            key: Some("k".repeat(40)),
            ..Config::default()
        };
        c.bots.insert(
            "mine".into(),
            OwnedBot {
                bot_id: 3,
                token: "t".into(),
            },
        );
        c.save(&path).unwrap();
        let mode = std::fs::metadata(&path).unwrap().permissions().mode();
        assert_eq!(mode & 0o777, 0o600);
        let dmode = std::fs::metadata(path.parent().unwrap())
            .unwrap()
            .permissions()
            .mode();
        assert_eq!(dmode & 0o777, 0o700);
        assert_eq!(Config::load(&path).unwrap(), c);
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o644)).unwrap();
        let err = Config::load(&path).unwrap_err().to_string();
        assert!(err.contains("can be read by others"), "{err}");
    }
}
