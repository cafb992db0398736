//! `mazearena` as a client of a server: `login`, `logout`, `submit`, `status`,
//! `matches`, `logs`, `practice`, and `replay ID` (in [`super::replay`]). Every HTTP
//! failure is reported with the server's own message ([`crate::client::ClientError`]).
//!
//! Every text that comes from the server (names, statuses, messages, logs) is printed
//! through [`show`], so none of its control characters reaches the terminal raw.

use std::io::{BufRead, IsTerminal};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::{Value, json};

use crate::client::config::{self, Config, OwnedBot};
use crate::client::show::{self, text};
use crate::client::{Api, ClientError, pack};
use crate::manifest::BotManifest;

/// How long `submit` follows a build before it stops waiting (the server's own limit
/// on a build is 10 minutes).
const BUILD_WAIT: Duration = Duration::from_secs(15 * 60);

/// How long `practice` waits for its matches.
const PRACTICE_WAIT: Duration = Duration::from_secs(30 * 60);

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

/// Arguments of `mazearena status`.
#[derive(Debug, Args)]
pub struct StatusArgs {
    /// Print the answer as JSON.
    #[arg(long)]
    json: bool,
}

/// Arguments of `mazearena matches`.
#[derive(Debug, Args)]
pub struct MatchesArgs {
    /// Only this bot's matches (its name).
    #[arg(long)]
    bot: Option<String>,
    /// How many, newest first.
    #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(1..=200))]
    limit: u32,
}

/// Arguments of `mazearena logs`.
#[derive(Debug, Args)]
pub struct LogsArgs {
    /// The match's id, or `last` for your newest match on a public maze.
    id: String,
}

/// Arguments of `mazearena practice`.
#[derive(Debug, Args)]
pub struct PracticeArgs {
    /// Which of your bots (its name; needed when you have several).
    #[arg(long)]
    bot: Option<String>,
    /// The practice mazes of this competition (default: every public maze on the
    /// server).
    #[arg(long)]
    competition: Option<String>,
    /// Queue the matches and return without waiting for them.
    #[arg(long)]
    no_wait: bool,
}

fn runtime() -> anyhow::Result<tokio::runtime::Runtime> {
    Ok(tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()?)
}

fn config_path() -> anyhow::Result<PathBuf> {
    config::path().context("cannot tell where to keep the login: set HOME or MAZEARENA_CONFIG")
}

/// The configuration and the logged-in server's API.
fn session() -> anyhow::Result<(Config, PathBuf, Api)> {
    let path = config_path()?;
    let cfg = Config::load(&path)?;
    let (server, key) = cfg.effective();
    let server = server.context(
        "not logged in: run `mazearena login URL --key KEY` (or set MAZEARENA_SERVER and MAZEARENA_KEY)",
    )?;
    let api = Api::new(&server, key)?;
    Ok((cfg, path, api))
}

/// Who the key is (`GET /api/me`), asked once per command.
struct Me {
    /// `admin`, `organiser`, `entrant`, `owner`, or `anonymous` without a key.
    kind: String,
    /// The entrant's name, for an entrant's key.
    entrant: Option<String>,
    /// The bots the key acts for, as (id, name).
    bots: Vec<(i64, String)>,
}

/// Who the key is; without a key, anonymous (no request is made).
async fn me(api: &Api) -> Result<Me, ClientError> {
    if api.key().is_none() {
        return Ok(Me {
            kind: "anonymous".into(),
            entrant: None,
            bots: Vec::new(),
        });
    }
    let v: Value = api.get("/api/me").await?;
    let bots = v["bots"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|b| Some((b["bot_id"].as_i64()?, b["name"].as_str()?.to_string())))
                .collect()
        })
        .unwrap_or_default();
    Ok(Me {
        kind: v["kind"].as_str().unwrap_or("").to_string(),
        entrant: v["entrant"].as_str().map(str::to_string),
        bots,
    })
}

/// Your bots: those the key acts for, and those registered from here without one
/// (with their owner token).
fn my_bots(me: &Me, cfg: &Config) -> Vec<(i64, String, Option<String>)> {
    let mut out: Vec<(i64, String, Option<String>)> = me
        .bots
        .iter()
        .map(|(id, name)| (*id, name.clone(), None))
        .collect();
    for (name, b) in &cfg.bots {
        if !out.iter().any(|(id, _, _)| *id == b.bot_id) {
            out.push((b.bot_id, name.clone(), Some(b.token.clone())));
        }
    }
    out
}

/// Picks one of `bots` by `name`, or the only one.
fn pick<'a>(
    bots: &'a [(i64, String, Option<String>)],
    name: Option<&str>,
) -> anyhow::Result<&'a (i64, String, Option<String>)> {
    match name {
        Some(n) => bots
            .iter()
            .find(|b| b.1 == n)
            .with_context(|| format!("you have no bot named {n:?} on this server")),
        None => match bots {
            [] => bail!("you have no bot on this server yet: `mazearena submit DIR` uploads one"),
            [one] => Ok(one),
            _ => bail!(
                "you have several bots ({}): say which with --bot NAME",
                bots.iter()
                    .map(|b| text(&b.1))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        },
    }
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
        super::count(bots.len() as i64, "bot", "bots"),
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
        super::count(packed.files.len() as i64, "file", "files"),
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
                Err(super::ExitWith { code: 1, message }.into())
            }
            other => bail!("version {version}: {}", text(other)),
        }
    })
}

/// The API as the owner of `bot_id`: with its stored owner token when it has one (a
/// bot registered without an entrant's key), else with the key.
fn owner_api(api: &Api, cfg: &Config, bot_id: i64) -> Api {
    match cfg.bots.values().find(|b| b.bot_id == bot_id) {
        Some(b) => api.with_key(Some(b.token.clone())),
        None => api.clone(),
    }
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

/// Runs `mazearena status`: your bots, their versions and builds, their ranks, and your
/// quotas in the competitions you entered.
///
/// # Errors
/// No login, or a refusal by the server.
pub fn status(args: StatusArgs) -> anyhow::Result<()> {
    let (cfg, _, api) = session()?;
    runtime()?.block_on(async {
        let who = me(&api).await?;
        let bots = my_bots(&who, &cfg);
        let Me { kind, entrant, .. } = who;
        let board: Value = api.get("/api/leaderboard?scope=all").await?;
        let ranking: Value = api.get("/api/leaderboard").await?;
        let mut out_bots = Vec::new();
        for (id, name, _) in &bots {
            let detail: Value = owner_api(&api, &cfg, *id).get(&format!("/api/bots/{id}")).await?;
            let line = |b: &Value| {
                b.as_array()
                    .and_then(|a| a.iter().find(|s| s["bot_id"].as_i64() == Some(*id)))
                    .cloned()
            };
            out_bots.push(json!({
                "bot_id": id, "name": name,
                "versions": detail["versions"],
                "paused": detail["paused"],
                "ranking": line(&ranking), "all_mazes": line(&board),
            }));
        }
        let mut competitions = Vec::new();
        if kind == "entrant" {
            let list: Value = api.get("/api/competitions").await?;
            for c in list.as_array().into_iter().flatten() {
                let Some(name) = c["name"].as_str() else { continue };
                if c["kind"] != "competition" {
                    continue;
                }
                match api.get::<Value>(&format!("/api/competitions/{name}/submissions")).await {
                    Ok(s) if !s["bot_id"].is_null() => {
                        let board: Value = api
                            .get(&format!("/api/competitions/{name}/leaderboard"))
                            .await
                            .unwrap_or(Value::Null);
                        let line = board["standings"].as_array().and_then(|a| {
                            a.iter().find(|l| l["bot_id"] == s["bot_id"]).cloned()
                        });
                        competitions.push(json!({
                            "competition": name, "phase": c["phase"], "closes_at": c["closes_at"],
                            "final_result": s["final_result"],
                            "submissions": s, "public_board": line,
                        }));
                    }
                    Ok(_) => {}
                    Err(e) if e.status().is_some_and(|s| (400..500).contains(&s)) => {}
                    Err(e) => return Err(e.into()),
                }
            }
        }
        if args.json {
            println!(
                "{}",
                show::json(&json!({
                    "server": api.server(), "kind": kind, "entrant": entrant,
                    "bots": out_bots, "competitions": competitions,
                }))?
            );
            return Ok(());
        }
        println!(
            "{}{}",
            text(api.server()),
            entrant.map_or_else(String::new, |e| format!(", entrant {}", text(&e)))
        );
        if out_bots.is_empty() {
            println!("no bot yet: `mazearena submit DIR` uploads one");
        }
        for b in &out_bots {
            println!();
            println!("{} (bot {}){}", text(b["name"].as_str().unwrap_or("")), b["bot_id"],
                if b["paused"] == true { " - paused" } else { "" });
            let versions = b["versions"].as_array().cloned().unwrap_or_default();
            for v in versions.iter().rev().take(3) {
                println!(
                    "  version {:<3} {:<13} {}",
                    show::value(&v["version"]),
                    text(v["build_status"].as_str().unwrap_or("")),
                    crate::web::layout::time(v["created_at"].as_i64().unwrap_or(0))
                );
            }
            for (label, key) in [("ranking", "ranking"), ("all mazes", "all_mazes")] {
                if let Some(s) = b[key].as_object() {
                    println!(
                        "  {label}: rank {} (possible {}), mean score {:.3} (95% interval {:.3}-{:.3}), {} played",
                        show::value(&s["rank"]), text(s["uncertainty"]["rank_range"].as_str().unwrap_or("?")),
                        s["mean_score"].as_f64().unwrap_or(0.0),
                        s["uncertainty"]["low"].as_f64().unwrap_or(0.0),
                        s["uncertainty"]["high"].as_f64().unwrap_or(0.0),
                        show::value(&s["played"])
                    );
                }
            }
        }
        for c in &competitions {
            println!();
            let s = &c["submissions"];
            println!("competition {} ({})", text(c["competition"].as_str().unwrap_or("")), text(c["phase"].as_str().unwrap_or("")));
            println!("  {}", text(s["versions_quota"]["message"].as_str().unwrap_or("")));
            println!("  {}", text(s["practice_quota"]["message"].as_str().unwrap_or("")));
            if let Some(v) = s["versions"].as_array().and_then(|a| a.last()) {
                println!("  latest version {}: {}", show::value(&v["version"]), text(v["status"].as_str().unwrap_or("")));
            }
            if let Some(l) = c["public_board"].as_object() {
                println!(
                    "  public board: rank {} (possible {}), mean score {:.3}",
                    show::value(&l["rank"]), text(l["uncertainty"]["rank_range"].as_str().unwrap_or("?")),
                    l["mean_score"].as_f64().unwrap_or(0.0)
                );
            }
            if let Some(f) = s["final_result"].as_object() {
                println!(
                    "  final result: rank {} with version {}, mean score {:.3} over {} private matches ({} finished)",
                    show::value(&f["rank"]), show::value(&f["version"]),
                    f["mean_score"].as_f64().unwrap_or(0.0),
                    show::value(&f["played"]), show::value(&f["finished"])
                );
            }
        }
        Ok(())
    })
}

/// The mazes' names by id.
async fn maze_names(api: &Api) -> anyhow::Result<Vec<(i64, String, Option<i64>, bool)>> {
    let list: Value = api.get("/api/mazes").await?;
    Ok(list
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|m| {
            Some((
                m["maze_id"].as_i64()?,
                m["name"].as_str()?.to_string(),
                m["optimum"].as_i64(),
                m["hidden"].as_bool().unwrap_or(false),
            ))
        })
        .collect())
}

fn score_text(v: &Value) -> String {
    v.as_f64().map_or("-".into(), |s| format!("{s:.3}"))
}

/// Runs `mazearena matches`: your bots' latest matches.
///
/// # Errors
/// No login, or a refusal by the server.
pub fn matches(args: MatchesArgs) -> anyhow::Result<()> {
    let (cfg, _, api) = session()?;
    runtime()?.block_on(async {
        let bots = my_bots(&me(&api).await?, &cfg);
        let chosen: Vec<&(i64, String, Option<String>)> = match &args.bot {
            Some(_) => vec![pick(&bots, args.bot.as_deref())?],
            None => bots.iter().collect(),
        };
        let mazes = maze_names(&api).await?;
        let mut rows: Vec<Value> = Vec::new();
        for (id, name, _) in chosen {
            let page: Value = api
                .get(&format!("/api/matches?bot_id={id}&limit={}", args.limit))
                .await?;
            for m in page["items"].as_array().into_iter().flatten() {
                let mut m = m.clone();
                m["bot"] = json!(name);
                rows.push(m);
            }
        }
        rows.sort_by_key(|m| std::cmp::Reverse(m["match_id"].as_i64().unwrap_or(0)));
        rows.truncate(args.limit as usize);
        if rows.is_empty() {
            println!("no match yet");
            return Ok(());
        }
        println!(
            "{:>6}  {:<20} {:<16} {:<14} {:>9} {:>5} {:>5}  queued",
            "match", "bot", "maze", "status", "score", "run0", "run1"
        );
        for m in rows {
            let maze = mazes
                .iter()
                .find(|z| Some(z.0) == m["maze_id"].as_i64())
                .map_or_else(|| show::value(&m["maze_id"]), |z| text(&z.1).into_owned());
            let steps = |k: &str| m[k].as_i64().map_or("-".into(), |s| s.to_string());
            println!(
                "{:>6}  {:<20} {:<16} {:<14} {:>9} {:>5} {:>5}  {}",
                show::value(&m["match_id"]),
                format!(
                    "{} v{}",
                    text(m["bot"].as_str().unwrap_or("")),
                    show::value(&m["bot_version"])
                ),
                maze,
                text(m["status"].as_str().unwrap_or("")),
                score_text(&m["score"]),
                steps("run0_steps"),
                steps("run1_steps"),
                crate::web::layout::time(m["created_at"].as_i64().unwrap_or(0))
            );
        }
        println!("`mazearena logs ID` shows a match's log; `mazearena replay ID` its replay");
        Ok(())
    })
}

/// Runs `mazearena logs`: a match's stderr tail and failure details.
///
/// # Errors
/// No login, or a refusal by the server (not your bot's match: 403).
pub fn logs(args: LogsArgs) -> anyhow::Result<()> {
    let (cfg, _, api) = session()?;
    runtime()?.block_on(async {
        let id = match_id(&api, &cfg, &args.id).await?;
        let m: Value = api.get(&format!("/api/matches/{id}")).await?;
        let owner = m["bot_id"]
            .as_i64()
            .map_or_else(|| api.clone(), |b| owner_api(&api, &cfg, b));
        let log: Value = owner.get(&format!("/api/matches/{id}/log")).await?;
        println!(
            "match {id}: {}{}",
            text(log["status"].as_str().unwrap_or("")),
            log["step"]
                .as_u64()
                .map_or_else(String::new, |s| format!(" at step {s}"))
        );
        if let Some(e) = log.get("error").filter(|e| !e.is_null()) {
            if let Some(reason) = e["reason"].as_str() {
                println!("reason: {}", text(reason));
                // A crash's own words (a Python exception's line) are its stderr's last.
                if log["status"] == "crashed"
                    && let Some(last) = log["stderr_tail"]
                        .as_str()
                        .and_then(|t| t.lines().rev().map(str::trim).find(|l| !l.is_empty()))
                {
                    println!("its last stderr line: {}", text(last));
                }
            } else {
                println!("error: {}", show::value(e));
            }
        }
        if log["redacted"] == true {
            println!("(a hidden maze's match: only its status and the failure's step are shown)");
        }
        match log["stderr_tail"].as_str() {
            Some(t) if !t.is_empty() => {
                println!("--- stderr (last 64 KiB) ---\n{}", show::log(t.trim_end()))
            }
            Some(_) => println!("(the bot wrote nothing to stderr)"),
            None => {}
        }
        Ok(())
    })
}

/// A match named on the command line: its id, or `last` for the newest match of your
/// bots on a public maze (a hidden maze's match has no replay and a shortened log).
async fn match_id(api: &Api, cfg: &Config, spec: &str) -> anyhow::Result<i64> {
    if let Ok(id) = spec.parse::<i64>() {
        return Ok(id);
    }
    anyhow::ensure!(
        spec == "last",
        "{spec:?} is not a match id (a number, or `last`)"
    );
    let mut newest: Option<i64> = None;
    for (bot, _, _) in my_bots(&me(api).await?, cfg) {
        let page: Value = api
            .get(&format!("/api/matches?bot_id={bot}&limit=200"))
            .await?;
        let id = page["items"]
            .as_array()
            .into_iter()
            .flatten()
            .filter(|m| m["maze_hidden"] == false)
            .filter_map(|m| m["match_id"].as_i64())
            .max();
        newest = newest.max(id);
    }
    newest.context("your bots have no match on a public maze yet (`mazearena practice` plays some)")
}

/// Whether `spec` names a match for [`replay`]: a number or `last`.
pub(super) fn is_match_spec(spec: &str) -> bool {
    spec == "last" || spec.parse::<i64>().is_ok()
}

/// Writes the replay of match `spec` (an id, or `last`) from the server as one HTML
/// file (`mazearena replay ID`).
///
/// # Errors
/// No login, a refusal by the server, or a file that cannot be written.
pub fn replay(spec: &str, output: Option<PathBuf>) -> anyhow::Result<()> {
    let (cfg, _, api) = session()?;
    runtime()?.block_on(async {
        let id = match_id(&api, &cfg, spec).await?;
        let m: Value = api.get(&format!("/api/matches/{id}")).await?;
        let owner = m["bot_id"]
            .as_i64()
            .map_or_else(|| api.clone(), |b| owner_api(&api, &cfg, b));
        let html = owner
            .get_text(&format!("/api/matches/{id}/replay.html"))
            .await?;
        let output = output.unwrap_or_else(|| PathBuf::from(format!("match-{id}.html")));
        std::fs::write(&output, html)
            .with_context(|| format!("cannot write {}", output.display()))?;
        eprintln!("wrote {}", output.display());
        Ok(())
    })
}

/// Runs `mazearena practice`: your bot's latest version on every practice maze, then
/// the table of results.
///
/// # Errors
/// No login, a refusal by the server (a used-up practice quota: 429, with when the next
/// match is allowed), or matches that did not end in time.
pub fn practice(args: PracticeArgs) -> anyhow::Result<()> {
    let (cfg, _, api) = session()?;
    runtime()?.block_on(async {
        let bots = my_bots(&me(&api).await?, &cfg);
        let (bot_id, bot_name, _) = pick(&bots, args.bot.as_deref())?.clone();
        let owner = owner_api(&api, &cfg, bot_id);
        let all = maze_names(&api).await?;
        let mazes: Vec<(i64, String, Option<i64>)> = match &args.competition {
            Some(c) => {
                let v: Value = api.get(&format!("/api/competitions/{c}")).await?;
                v["mazes"]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .filter(|m| m["set"] == "practice")
                    .filter_map(|m| {
                        let id = m["maze_id"].as_i64()?;
                        let opt = all.iter().find(|z| z.0 == id).and_then(|z| z.2);
                        Some((id, m["name"].as_str()?.to_string(), opt))
                    })
                    .collect()
            }
            None => all
                .iter()
                .filter(|z| !z.3)
                .map(|z| (z.0, z.1.clone(), z.2))
                .collect(),
        };
        anyhow::ensure!(!mazes.is_empty(), "there is no practice maze to play");
        let mut queued = Vec::new();
        for (maze_id, name, optimum) in &mazes {
            let q: Result<Value, ClientError> = owner
                .post(
                    "/api/matches",
                    &json!({"bot_id": bot_id, "maze_id": maze_id}),
                )
                .await;
            match q {
                Ok(v) => queued.push((v["match_id"].as_i64().unwrap_or(0), name.clone(), *optimum)),
                Err(e) if e.status() == Some(429) && !queued.is_empty() => {
                    eprintln!("stopped queueing: {e}");
                    break;
                }
                Err(e) => return Err(e.into()),
            }
        }
        println!(
            "queued {} of {} ({})",
            super::count(queued.len() as i64, "match", "matches"),
            text(&bot_name),
            queued
                .iter()
                .map(|q| q.0.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
        if args.no_wait {
            return Ok(());
        }
        let started = Instant::now();
        let mut results: Vec<Value> = Vec::new();
        for (id, _, _) in &queued {
            loop {
                let m: Value = api.get(&format!("/api/matches/{id}")).await?;
                let s = m["status"].as_str().unwrap_or("");
                if s != "queued" && s != "running" {
                    results.push(m);
                    break;
                }
                anyhow::ensure!(
                    started.elapsed() < PRACTICE_WAIT,
                    "the matches did not end within {} minutes (`mazearena matches` shows them)",
                    PRACTICE_WAIT.as_secs() / 60
                );
                tokio::time::sleep(Duration::from_millis(300)).await;
            }
        }
        println!(
            "{:>6}  {:<16} {:<14} {:>5} {:>5} {:>9} {:>8}",
            "match", "maze", "status", "run0", "run1", "score", "optimum"
        );
        for (m, (_, name, optimum)) in results.iter().zip(&queued) {
            let steps = |k: &str| m[k].as_i64().map_or("-".into(), |s| s.to_string());
            println!(
                "{:>6}  {:<16} {:<14} {:>5} {:>5} {:>9} {:>8}",
                show::value(&m["match_id"]),
                text(name),
                text(m["status"].as_str().unwrap_or("")),
                steps("run0_steps"),
                steps("run1_steps"),
                score_text(&m["score"]),
                optimum.map_or("-".into(), |o| o.to_string())
            );
        }
        let scores: Vec<f64> = results
            .iter()
            .map(|m| {
                m["score"]
                    .as_f64()
                    .unwrap_or(crate::engine::score::DNF_SCORE)
            })
            .collect();
        if !scores.is_empty() {
            println!(
                "mean score {} over {} ({} finished)",
                crate::ranking::Mean::of_scores(scores.iter().copied()),
                super::count(scores.len() as i64, "maze", "mazes"),
                results.iter().filter(|m| m["status"] == "finished").count()
            );
        }
        Ok(())
    })
}
