//! What the client's commands share: the session from the saved login, the caller's
//! bots, the server's maze names, and how scores are printed.

use crate::client::config::{self, Config};
use crate::client::show::text;
use crate::client::{Api, ClientError};
use anyhow::{Context, bail};
use serde_json::Value;
use std::path::PathBuf;

pub(super) fn runtime() -> anyhow::Result<tokio::runtime::Runtime> {
    Ok(tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()?)
}

pub(super) fn config_path() -> anyhow::Result<PathBuf> {
    config::path().context("cannot tell where to keep the login: set HOME or MAZEARENA_CONFIG")
}

/// The configuration and the logged-in server's API.
pub(super) fn session() -> anyhow::Result<(Config, PathBuf, Api)> {
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
pub(super) struct Me {
    /// `admin`, `organiser`, `entrant`, `owner`, or `anonymous` without a key.
    pub(super) kind: String,
    /// The entrant's name, for an entrant's key.
    pub(super) entrant: Option<String>,
    /// The bots the key acts for, as (id, name).
    pub(super) bots: Vec<(i64, String)>,
}

/// Who the key is; without a key, anonymous (no request is made).
pub(super) async fn me(api: &Api) -> Result<Me, ClientError> {
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
pub(super) fn my_bots(me: &Me, cfg: &Config) -> Vec<(i64, String, Option<String>)> {
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
pub(super) fn pick<'a>(
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

/// The API as the owner of `bot_id`: with its stored owner token when it has one (a
/// bot registered without an entrant's key), else with the key.
pub(super) fn owner_api(api: &Api, cfg: &Config, bot_id: i64) -> Api {
    match cfg.bots.values().find(|b| b.bot_id == bot_id) {
        Some(b) => api.with_key(Some(b.token.clone())),
        None => api.clone(),
    }
}

/// The mazes' names by id.
pub(super) async fn maze_names(api: &Api) -> anyhow::Result<Vec<(i64, String, Option<i64>, bool)>> {
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

pub(super) fn score_text(v: &Value) -> String {
    v.as_f64().map_or("-".into(), |s| format!("{s:.3}"))
}

/// A match named on the command line: its id, or `last` for the newest match of your
/// bots on a public maze (a hidden maze's match has no replay and a shortened log).
pub(super) async fn match_id(api: &Api, cfg: &Config, spec: &str) -> anyhow::Result<i64> {
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
