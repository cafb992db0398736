//! Reports of a finished tournament: the standings table, every match's result, and the
//! Markdown tables of bots/README.md.

use crate::manifest::BotManifest;
use crate::storage::Storage;
use crate::storage::leaderboard::Standing;

/// Prints the standings as a table.
pub(super) fn print_table(rows: &[Standing]) {
    let width = rows.iter().map(|r| r.name.len()).max().unwrap_or(4).max(4);
    println!(
        "{:>4}  {:<width$}  {:>10}  {:>8}  {:>10}  {:>6}",
        "rank", "bot", "mean score", "finished", "vs optimum", "played"
    );
    for r in rows {
        println!(
            "{:>4}  {:<width$}  {:>10.3}  {:>7.0}%  {:>10}  {:>6}",
            r.rank,
            r.name,
            r.mean_score,
            r.finish_rate * 100.0,
            r.mean_ratio.map_or("-".to_string(), |x| format!("{x:.3}")),
            r.played
        );
    }
}

/// One played match, for reports.
#[derive(Debug, Clone, serde::Serialize)]
pub(super) struct MatchResult {
    bot: String,
    maze: String,
    repeat: i64,
    status: String,
    run0_steps: Option<i64>,
    run1_steps: Option<i64>,
    score: Option<f64>,
}

/// Every match of a tournament with its bot's and maze's names.
pub(super) async fn results(
    storage: &Storage,
    tournament_id: i64,
) -> anyhow::Result<Vec<MatchResult>> {
    let mut out = Vec::new();
    let mut bot_names = std::collections::BTreeMap::new();
    let mut maze_names = std::collections::BTreeMap::new();
    for row in storage.tournament_matches(tournament_id).await? {
        if let std::collections::btree_map::Entry::Vacant(e) = bot_names.entry(row.bot_id) {
            e.insert(
                storage
                    .get_bot(row.bot_id)
                    .await?
                    .map_or_else(String::new, |b| b.name),
            );
        }
        if let std::collections::btree_map::Entry::Vacant(e) = maze_names.entry(row.maze_id) {
            e.insert(
                storage
                    .get_maze(row.maze_id)
                    .await?
                    .map_or_else(String::new, |m| m.name),
            );
        }
        out.push(MatchResult {
            bot: bot_names[&row.bot_id].clone(),
            maze: maze_names[&row.maze_id].clone(),
            repeat: row.repeat.unwrap_or(0),
            status: row.status,
            run0_steps: row.run0_steps,
            run1_steps: row.run1_steps,
            score: row.score,
        });
    }
    Ok(out)
}

/// The Markdown report: bot x maze (means over repeats), then the standings.
pub(super) fn markdown(
    bots: &[BotManifest],
    results: &[MatchResult],
    standings: &[Standing],
) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "| bot | maze | run-0 steps | run-1 steps | score | claimed |"
    );
    let _ = writeln!(out, "|---|---|---:|---:|---:|---:|");
    let mut mazes: Vec<&str> = results.iter().map(|r| r.maze.as_str()).collect();
    mazes.sort();
    mazes.dedup();
    for bot in bots {
        for maze in &mazes {
            let runs: Vec<&MatchResult> = results
                .iter()
                .filter(|r| r.bot == bot.name && r.maze == *maze)
                .collect();
            if runs.is_empty() {
                continue;
            }
            let mean = |f: &dyn Fn(&MatchResult) -> Option<f64>| -> String {
                let vals: Vec<f64> = runs.iter().filter_map(|r| f(r)).collect();
                if vals.len() < runs.len() || vals.is_empty() {
                    let dnf = runs.len() - vals.len();
                    return format!("{dnf}/{} DNF", runs.len());
                }
                let m = vals.iter().sum::<f64>() / vals.len() as f64;
                if runs.len() == 1 {
                    format!("{m}")
                } else {
                    format!("{m:.1}")
                }
            };
            let run0 = mean(&|r| r.run0_steps.map(|v| v as f64));
            let run1 = mean(&|r| r.run1_steps.map(|v| v as f64));
            let score = {
                let vals: Vec<f64> = runs.iter().filter_map(|r| r.score).collect();
                if vals.len() == runs.len() {
                    format!("{:.3}", vals.iter().sum::<f64>() / vals.len() as f64)
                } else {
                    format!(
                        "{} ({}/{} DNF)",
                        runs[0].status,
                        runs.len() - vals.len(),
                        runs.len()
                    )
                }
            };
            let claimed = bot
                .claimed
                .get(*maze)
                .map_or_else(|| "-".to_string(), |c| format!("{c}"));
            let _ = writeln!(
                out,
                "| {} | {maze} | {run0} | {run1} | {score} | {claimed} |",
                bot.name
            );
        }
    }
    let _ = writeln!(out);
    let _ = writeln!(
        out,
        "| rank | bot | mean score | finish rate | mean score / optimum | played |"
    );
    let _ = writeln!(out, "|---:|---|---:|---:|---:|---:|");
    for s in standings {
        let _ = writeln!(
            out,
            "| {} | {} | {:.3} | {:.1}% | {} | {} |",
            s.rank,
            s.name,
            s.mean_score,
            s.finish_rate * 100.0,
            s.mean_ratio.map_or("-".to_string(), |x| format!("{x:.3}")),
            s.played
        );
    }
    out
}
