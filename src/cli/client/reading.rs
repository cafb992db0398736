//! `status`, `matches`, `logs` and `replay`: what the server says of the caller's bots.

use super::common::{
    Me, match_id, maze_names, me, my_bots, owner_api, pick, runtime, score_text, session,
};
use crate::client::show::{self, text};
use anyhow::Context;
use clap::Args;
use serde_json::{Value, json};
use std::path::PathBuf;

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

/// Whether `spec` names a match for [`replay`]: a number or `last`.
pub(in crate::cli) fn is_match_spec(spec: &str) -> bool {
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
