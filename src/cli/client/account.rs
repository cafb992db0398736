//! `login` and `logout`.

use super::common::{Me, config_path, me, runtime};
use crate::client::Api;
use crate::client::config::Config;
use crate::client::show::text;
use anyhow::bail;
use clap::Args;
use std::io::{BufRead, IsTerminal};

/// Arguments of `mazearena login`.
#[derive(Debug, Args)]
pub struct LoginArgs {
    /// The server's address, e.g. `http://localhost:8080`.
    server: String,
    /// Your entrant's key (or a bot's owner token). Without it, the key is read from
    /// the first line of standard input.
    #[arg(long)]
    key: Option<String>,
}

/// Runs `mazearena login`: checks the key with the server, then keeps both.
///
/// # Errors
/// A server that cannot be reached or does not know the key; a file that cannot be
/// written.
pub fn login(args: LoginArgs) -> anyhow::Result<()> {
    let key = match args.key {
        Some(k) => k,
        None => {
            if std::io::stdin().is_terminal() {
                eprint!("key: ");
            }
            let mut line = String::new();
            std::io::stdin().lock().read_line(&mut line)?;
            line.trim().to_string()
        }
    };
    anyhow::ensure!(
        !key.trim().is_empty(),
        "no key given (--key KEY, or on standard input)"
    );
    let api = Api::new(&args.server, Some(key.trim().to_string()))?;
    let Me {
        kind,
        entrant,
        bots,
    } = runtime()?.block_on(me(&api))?;
    let path = config_path()?;
    let mut cfg = Config::load(&path)?;
    if cfg.server.as_deref() != Some(api.server()) {
        cfg.bots.clear();
    }
    cfg.server = Some(api.server().to_string());
    cfg.key = api.key().map(str::to_string);
    cfg.save(&path)?;
    let who = match (kind.as_str(), entrant) {
        ("entrant", Some(name)) => format!("entrant {}", text(&name)),
        ("owner", _) => "the owner of a bot".to_string(),
        (k, _) => text(k).into_owned(),
    };
    println!(
        "logged in to {} as {who} ({}); kept in {}",
        api.server(),
        crate::cli::count(bots.len() as i64, "bot", "bots"),
        path.display()
    );
    Ok(())
}

/// Runs `mazearena logout`: forgets the server, the key and the bots' tokens.
///
/// # Errors
/// A file that cannot be removed.
pub fn logout() -> anyhow::Result<()> {
    let path = config_path()?;
    match std::fs::remove_file(&path) {
        Ok(()) => println!("logged out (removed {})", path.display()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => println!("not logged in"),
        Err(e) => bail!("cannot remove {}: {e}", path.display()),
    }
    Ok(())
}
