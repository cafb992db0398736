//! Reports of a finished tournament: the standings table, every match's result, and the
//! Markdown tables of bots/README.md.

use crate::manifest::BotManifest;
use crate::storage::Storage;
use crate::storage::leaderboard::Standing;

/// Prints the standings as a table, with each mean's 95% interval, the ranks the
/// intervals allow and the tie groups, then the rules in two lines.
pub(super) fn print_table(rows: &[Standing]) {
    let width = rows.iter().map(|r| r.name.len()).max().unwrap_or(4).max(4);
    println!(
        "{:>4}  {:>8}  {:<width$}  {:>10}  {:>17}  {:>4}  {:>8}  {:>10}  {:>6}",
        "rank",
        "possible",
        "bot",
        "mean score",
        "95% interval",
        "tie",
        "finished",
        "vs optimum",
        "played"
    );
    for r in rows {
        let u = &r.uncertainty;
        println!(
            "{:>4}  {:>8}  {:<width$}  {:>10.3}  {:>17}  {:>4}  {:>7.0}%  {:>10}  {:>6}",
            r.rank,
            u.rank_range,
            r.name,
            r.mean_score,
            format!("{:.3}-{:.3}", u.low, u.high),
            if u.tied {
                format!("={}", u.tie_group)
            } else {
                String::new()
            },
            r.finish_rate * 100.0,
            r.mean_ratio.map_or("-".to_string(), |x| format!("{x:.3}")),
            r.played
        );
    }
    println!(
        "Lower mean first; equal means share a rank (by name). 95% interval: bootstrap over each maze's seeds;"
    );
    println!(
        "possible: the ranks those intervals allow; tie =N: not significantly different from group N's first bot."
    );
    if rows.iter().any(|r| r.uncertainty.runs_per_maze == 1) {
        println!(
            "One run per maze: a randomized bot's luck is not measured (use --repeats 2 or more)."
        );
    }
}

/// For each bot with matches that did not finish: how many, by status, and the first
/// one's id and reason, so its author knows where to look.
pub(super) fn print_failures(results: &[MatchResult], database: &str) {
    let db = if database == "sqlite://mazearena.db" {
        String::new()
    } else {
        format!(" --database {}", crate::storage::redacted_url(database))
    };
    let mut bots: Vec<&str> = results.iter().map(|r| r.bot.as_str()).collect();
    bots.dedup();
    let mut seen = std::collections::BTreeSet::new();
    let mut header = false;
    for bot in bots {
        if !seen.insert(bot) {
            continue;
        }
        let failed: Vec<&MatchResult> = results
            .iter()
            .filter(|r| r.bot == bot && r.status != "finished")
            .collect();
        let Some(first) = failed.first() else {
            continue;
        };
        if !header {
            println!();
            println!("Matches that did not finish:");
            header = true;
        }
        let mut by_status: std::collections::BTreeMap<&str, usize> = Default::default();
        for f in &failed {
            *by_status.entry(f.status.as_str()).or_default() += 1;
        }
        let counts: Vec<String> = by_status.iter().map(|(s, n)| format!("{n} {s}")).collect();
        let total = results.iter().filter(|r| r.bot == bot).count();
        println!(
            "  {bot}: {} of {total} ({})",
            failed.len(),
            counts.join(", ")
        );
        let why = match (&first.reason, first.step) {
            (Some(reason), _) => reason.clone(),
            (None, _) if first.status == "step_limit" => {
                "the 1000-step budget ran out before run 1 reached the goal room".into()
            }
            (None, _) => first.status.clone(),
        };
        println!(
            "    first: match {} on {} (seed {}): {} — {why}",
            first.match_id, first.maze, first.repeat, first.status
        );
        println!(
            "    see it: mazearena match show {}{db} --html match-{}.html",
            first.match_id, first.match_id
        );
    }
}

/// One played match, for reports.
#[derive(Debug, Clone, serde::Serialize)]
pub(super) struct MatchResult {
    match_id: i64,
    bot: String,
    maze: String,
    repeat: i64,
    status: String,
    run0_steps: Option<i64>,
    run1_steps: Option<i64>,
    score: Option<f64>,
    /// Why it did not finish (null when it finished or ran out of steps).
    reason: Option<String>,
    /// The step the failure happened at.
    step: Option<u64>,
}

/// Every match of a tournament with its bot's and maze's names (one query).
pub(super) async fn results(
    storage: &Storage,
    tournament_id: i64,
) -> anyhow::Result<Vec<MatchResult>> {
    let mut out = Vec::new();
    for row in storage.tournament_matches(tournament_id).await? {
        let error = row.summary().error;
        out.push(MatchResult {
            match_id: row.match_id,
            reason: error.as_ref().map(|e| e.reason.clone()),
            step: error.as_ref().and_then(|e| e.step).map(u64::from),
            bot: row.bot_name,
            maze: row.maze_name,
            repeat: row.repeat.unwrap_or(0),
            status: row.status.to_string(),
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
                    crate::ranking::Mean::of_scores(vals.iter().copied()).to_string()
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
