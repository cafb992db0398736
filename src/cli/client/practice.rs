//! `practice`: practice matches queued and followed to their results.

use super::common::{maze_names, me, my_bots, owner_api, pick, runtime, score_text, session};
use crate::client::ClientError;
use crate::client::show::{self, text};
use clap::Args;
use serde_json::{Value, json};
use std::time::{Duration, Instant};

/// How long `practice` waits for its matches.
const PRACTICE_WAIT: Duration = Duration::from_secs(30 * 60);

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
            crate::cli::count(queued.len() as i64, "match", "matches"),
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
                crate::cli::count(scores.len() as i64, "maze", "mazes"),
                results.iter().filter(|m| m["status"] == "finished").count()
            );
        }
        Ok(())
    })
}
