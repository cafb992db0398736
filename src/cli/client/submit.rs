//! `submit`: a bot's folder packed and uploaded as a new version, its build followed.

use super::common::{me, my_bots, owner_api, runtime, session};
use crate::client::config::{Config, OwnedBot};
use crate::client::show::{self, text};
use crate::client::{Api, ClientError, pack};
use crate::manifest::BotManifest;
use anyhow::{Context, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::{Value, json};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// How long `submit` follows a build before it stops waiting (the server's own limit
/// on a build is 10 minutes).
const BUILD_WAIT: Duration = Duration::from_secs(15 * 60);

/// Arguments of `mazearena submit`.
#[derive(Debug, Args)]
pub struct SubmitArgs {
    /// The bot's folder, with its `bot.toml`.
    #[arg(default_value = ".")]
    dir: PathBuf,
    /// Which bot of a `bot.toml` that lists several (its `name`).
    #[arg(long)]
    bot: Option<String>,
    /// Enter the bot in this competition (if it is not entered yet).
    #[arg(long)]
    competition: Option<String>,
    /// Upload only: do not follow the build.
    #[arg(long)]
    no_wait: bool,
}

/// The manifest's bot to submit.
fn manifest_bot(dir: &Path, name: Option<&str>) -> anyhow::Result<BotManifest> {
    let file = dir.join("bot.toml");
    anyhow::ensure!(
        file.is_file(),
        "{} has no bot.toml (name, command, and build if it needs one)",
        dir.display()
    );
    let bots = crate::manifest::load(&file)?;
    match name {
        Some(n) => bots
            .into_iter()
            .find(|b| b.name == n)
            .with_context(|| format!("{} has no bot named {n:?}", file.display())),
        None if bots.len() == 1 => Ok(bots.into_iter().next().expect("one bot")),
        None => bail!(
            "{} lists several bots ({}): say which with --bot NAME",
            file.display(),
            bots.iter()
                .map(|b| b.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// Runs `mazearena submit`.
///
/// # Errors
/// No login, a bad folder or manifest, a refusal by the server, or a failed build.
pub fn submit(args: SubmitArgs) -> anyhow::Result<()> {
    let (mut cfg, path, api) = session()?;
    let bot = manifest_bot(&args.dir, args.bot.as_deref())?;
    let packed = pack::pack(&args.dir, &bot.include)?;
    anyhow::ensure!(
        !packed.files.is_empty(),
        "{} has no file to upload",
        args.dir.display()
    );
    eprintln!(
        "packed {} from {} ({} KiB){}",
        crate::cli::count(packed.files.len() as i64, "file", "files"),
        args.dir.display(),
        packed.archive.len().div_ceil(1024),
        if packed.skipped.is_empty() {
            String::new()
        } else {
            format!(
                "; left out {} that {} not a regular file",
                packed
                    .skipped
                    .iter()
                    .map(|p| text(&p.display().to_string()).into_owned())
                    .collect::<Vec<_>>()
                    .join(", "),
                if packed.skipped.len() == 1 {
                    "is"
                } else {
                    "are"
                }
            )
        }
    );
    let rt = runtime()?;
    rt.block_on(async {
        let form = || {
            let mut f = reqwest::multipart::Form::new()
                .text("command", bot.command.clone())
                .part(
                    "archive",
                    reqwest::multipart::Part::bytes(packed.archive.clone())
                        .file_name("bot.tar.gz")
                        .mime_str("application/gzip")
                        .expect("a valid type"),
                );
            if let Some(b) = &bot.build {
                f = f.text("build", b.clone());
            }
            if bot.protocol != crate::runner::BotProtocol::V1 {
                f = f.text("protocol", bot.protocol.as_str());
            }
            if let Some(r) = &bot.runtime {
                f = f.text("runtime", r.clone());
            }
            for (k, v) in &bot.env {
                f = f.text("env", format!("{k}={v}"));
            }
            f
        };
        let who = me(&api).await?;
        let entrant = who.kind == "entrant";
        let mine = my_bots(&who, &cfg);
        let existing = mine.iter().find(|b| b.1 == bot.name);
        let entered_now = existing.is_none() && entrant && args.competition.is_some();
        let (bot_id, version) = match existing {
            Some((id, _, token)) => {
                // The key acts for its own bots; a bot registered without one uploads
                // with its owner token.
                let as_owner = match token {
                    Some(t) => api.with_key(Some(t.clone())),
                    None => api.clone(),
                };
                let v: Value = as_owner
                    .post_form(&format!("/api/bots/{id}/versions"), form())
                    .await?;
                (*id, v["version"].as_i64().unwrap_or(0))
            }
            None => {
                // A new bot of an entrant is entered in the competition in the same step
                // (validated by its rule); the entry below then finds it there.
                let mut f = form().text("name", bot.name.clone());
                if let (true, Some(c)) = (entrant, &args.competition) {
                    f = f.text("competition", c.clone());
                }
                let v: Value = api.post_form("/api/bots", f).await?;
                let id = v["bot_id"].as_i64().context("the server sent no bot id")?;
                if !entrant {
                    // Not an entrant's bot: keep its owner token to upload versions later.
                    if let Some(token) = v["owner_token"].as_str() {
                        cfg.bots.insert(
                            bot.name.clone(),
                            OwnedBot {
                                bot_id: id,
                                token: token.to_string(),
                            },
                        );
                        cfg.save(&path)?;
                    }
                }
                (id, v["version"]["version"].as_i64().unwrap_or(1))
            }
        };
        println!("uploaded {} version {version} (bot {bot_id})", bot.name);
        if let (true, Some(c)) = (entered_now, &args.competition) {
            println!("entered {} in competition {c}", bot.name);
        } else if let Some(c) = &args.competition {
            match api
                .post::<Value>(
                    &format!("/api/competitions/{c}/entries"),
                    &json!({"bot_id": bot_id}),
                )
                .await
            {
                Ok(_) => println!("entered {} in competition {c}", bot.name),
                Err(ClientError::Refused {
                    status: 409,
                    message,
                    ..
                }) => {
                    eprintln!("competition {c}: {}", text(&message))
                }
                Err(e) => return Err(e.into()),
            }
        }
        let page = format!("{}/bots/{bot_id}", api.server());
        if args.no_wait {
            println!("{page}");
            return Ok(());
        }
        let status = follow_build(&api, &cfg, bot_id, version).await?;
        match status.as_str() {
            "ready" => {
                // A failure on a maze that does not make the version invalid: its owner
                // reads it (with the traceback) before the ranking shows it.
                let owner = owner_api(&api, &cfg, bot_id);
                let log: Value = owner
                    .get(&format!("/api/bots/{bot_id}/versions/{version}/build-log"))
                    .await
                    .unwrap_or(Value::Null);
                if let Some(log) = log["build_log"].as_str().filter(|l| l.contains("warning: ")) {
                    eprintln!("--- validation (with a warning) ---\n{}", show::log(log.trim_end()));
                }
                println!("version {version} is ready: {page}");
                Ok(())
            }
            "build_failed" | "invalid" => {
                let owner = owner_api(&api, &cfg, bot_id);
                let log: Value = owner
                    .get(&format!("/api/bots/{bot_id}/versions/{version}/build-log"))
                    .await
                    .unwrap_or(Value::Null);
                if let Some(log) = log["build_log"].as_str() {
                    eprintln!("--- build log ---\n{}", show::log(log.trim_end()));
                }
                let message = if status == "invalid" {
                    format!(
                        "version {version} is invalid: it failed its validation match (see the log above); \
                         it will not play and does not count against your quota ({page})"
                    )
                } else {
                    format!("version {version} failed to build: it will not play ({page})")
                };
                // Exit status 1: the upload worked, the version does not (2 is for a
                // command that could not do its work).
                Err(crate::cli::ExitWith { code: 1, message }.into())
            }
            other => bail!("version {version}: {}", text(other)),
        }
    })
}

/// Follows the build of `bot_id`'s `version` until it is ready or failed, with a
/// spinner on a terminal.
async fn follow_build(
    api: &Api,
    cfg: &Config,
    bot_id: i64,
    version: i64,
) -> anyhow::Result<String> {
    let owner = owner_api(api, cfg, bot_id);
    let spinner = if std::io::stderr().is_terminal() {
        let s = ProgressBar::new_spinner();
        s.set_style(
            ProgressStyle::with_template("{spinner} {msg} {elapsed}")
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        );
        s.enable_steady_tick(Duration::from_millis(120));
        s
    } else {
        ProgressBar::hidden()
    };
    let started = Instant::now();
    let mut said = String::new();
    loop {
        let v: Value = owner.get(&format!("/api/bots/{bot_id}")).await?;
        let status = v["versions"]
            .as_array()
            .and_then(|vs| vs.iter().find(|x| x["version"].as_i64() == Some(version)))
            .and_then(|x| x["build_status"].as_str())
            .unwrap_or("building")
            .to_string();
        let shown = text(&status);
        if status != said {
            spinner.set_message(format!("version {version}: {shown}"));
            if spinner.is_hidden() {
                eprintln!("version {version}: {shown}");
            }
            said.clone_from(&status);
        }
        if status != "building" {
            spinner.finish_and_clear();
            return Ok(status);
        }
        if started.elapsed() > BUILD_WAIT {
            spinner.finish_and_clear();
            bail!(
                "version {version} is still building after {} minutes: see {}/bots/{bot_id}",
                BUILD_WAIT.as_secs() / 60,
                api.server()
            );
        }
        tokio::time::sleep(Duration::from_millis(500)).await;
    }
}
