//! The clock's work: ranking new versions, the final selection and run at the close,
//! the results with their manifests, and their publishing.

use super::settings::{deciding_tournament, in_set, phase};
use crate::competition::selection::{self, Candidate, Rule, VersionScore};
use crate::ranking::mean::ratio_3dp;
use crate::registry::{RegistryError, Result};
use crate::storage::Storage;
use crate::storage::competitions::{BoardRow, CompetitionMaze, CompetitionRow, ResultRow};

/// What the server's clock did in one [`tick`].
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TickReport {
    /// Versions queued on ranking sets.
    pub ranked: usize,
    /// Competitions whose final selection was made.
    pub selected: usize,
    /// Competitions whose results were written.
    pub finalized: usize,
    /// Closed competitions still waiting for their last matches or their final run
    /// (the clock looks at them more often).
    pub closing: usize,
}

/// The clock's work at `now`: queues every new ready version of an entered bot on its
/// competitions' public ranking sets; for each closed competition, once its last public
/// matches and builds are done, makes the final selection and queues the final run (the
/// private set's only run), and once that is played writes the results. Safe to run on
/// several servers at once: each step is done once.
///
/// # Errors
/// The database.
pub async fn tick(storage: &Storage, now: i64) -> Result<TickReport> {
    let mut report = TickReport::default();
    let to_rank = storage.versions_to_rank(now).await?;
    let mut cache: Vec<(CompetitionRow, Vec<CompetitionMaze>)> = Vec::new();
    for (competition_id, version_id) in to_rank {
        if !cache
            .iter()
            .any(|(c, _)| c.competition_id == competition_id)
        {
            let Some(c) = storage.get_competition_by_id(competition_id).await? else {
                continue;
            };
            let mazes = storage.competition_mazes(competition_id).await?;
            cache.push((c, mazes));
        }
        let Some((c, mazes)) = cache
            .iter()
            .find(|(c, _)| c.competition_id == competition_id)
        else {
            continue;
        };
        if storage
            .rank_version(c, version_id, &in_set(mazes, "public"))
            .await?
        {
            report.ranked += 1;
        }
    }
    for c in storage.list_competitions().await? {
        if c.kind != "competition"
            || !phase(&c, now).is_closed()
            || matches!(c.state.as_deref(), Some("final" | "held"))
        {
            continue;
        }
        storage.unseal_private_set(&c).await?;
        if storage.competition_work_left(&c).await? > 0 {
            report.closing += 1;
            continue;
        }
        match c.state.as_deref() {
            None => {
                let selected = final_selection(storage, &c).await?;
                let mazes = storage.competition_mazes(c.competition_id).await?;
                let private = in_set(&mazes, "private");
                let mut order = [0u8; 8];
                getrandom::fill(&mut order)
                    .map_err(|e| RegistryError::Internal(format!("no randomness: {e}")))?;
                let order = u64::from_le_bytes(order);
                if storage.start_final(&c, &selected, &private, order).await? {
                    report.selected += 1;
                    report.closing += 1;
                }
            }
            Some("final_run") if finalize(storage, &c).await? => report.finalized += 1,
            _ => {}
        }
    }
    Ok(report)
}

/// The versions each entrant has counting at the end, by the competition's rule.
async fn final_selection(storage: &Storage, c: &CompetitionRow) -> Result<Vec<i64>> {
    let rule = Rule::parse(&c.selection).unwrap_or_default();
    let public: Vec<BoardRow> = match c.public_tournament_id {
        Some(t) => storage.competition_board(t, false).await?,
        None => Vec::new(),
    };
    let mut selected = Vec::new();
    for e in storage.competition_entries(c.competition_id).await? {
        let candidates: Vec<Candidate> = storage
            .submissions(c, e.entrant_id)
            .await?
            .into_iter()
            .filter(|s| s.ranked && s.build_status == "ready")
            .map(|s| Candidate {
                bot_version_id: s.bot_version_id,
                version: s.version,
                public_mean: public
                    .iter()
                    .find(|r| r.bot_version_id == s.bot_version_id)
                    .map(BoardRow::mean),
                chosen: s.chosen,
            })
            .collect();
        selected.extend(selection::select(
            rule,
            c.max_selected as usize,
            &candidates,
        ));
    }
    Ok(selected)
}

/// Writes the results of a competition whose final run is played: each entrant's best
/// selected version on the deciding set, with its manifest (what it is, what it played:
/// each match's maze hash, seed, status and score, so that anyone can count the mean
/// again or play a match again with `mazearena run`) and the recount check.
async fn finalize(storage: &Storage, c: &CompetitionRow) -> Result<bool> {
    let Some(t) = deciding_tournament(c) else {
        return Ok(false);
    };
    let kept = storage.competition_board(t, false).await?;
    let counted = storage.competition_board(t, true).await?;
    let chosen: std::collections::HashSet<i64> = storage
        .selected_versions(c.competition_id)
        .await?
        .into_iter()
        .collect();
    let scores: Vec<VersionScore> = kept
        .iter()
        .filter(|r| chosen.contains(&r.bot_version_id))
        .filter_map(|r| {
            Some(VersionScore {
                entrant_id: r.entrant_id?,
                bot_version_id: r.bot_version_id,
                played: r.played,
                finished: r.finished,
                mean: r.mean(),
            })
        })
        .collect();
    let private = private_mazes(storage, c).await?;
    let mazes: Vec<serde_json::Value> = private
        .iter()
        .map(|m| serde_json::json!({"name": m.name, "hash": m.hash}))
        .collect();
    let seeds: Vec<serde_json::Value> = storage
        .tournament_seeds(t)
        .await?
        .into_iter()
        .map(|(repeat, seed)| serde_json::json!({"repeat": repeat, "seed": seed}))
        .collect();
    let matches = storage.tournament_matches(t).await?;
    let limits = c.limit_set();
    let mut limit_args = String::new();
    if let Some(ms) = limits.move_timeout_ms {
        limit_args.push_str(&format!(" --move-timeout-ms {ms}"));
    }
    if let Some(ms) = limits.startup_timeout_ms {
        limit_args.push_str(&format!(" --startup-timeout-ms {ms}"));
    }
    if let Some(ms) = limits.time_bank_ms {
        limit_args.push_str(&format!(" --time-bank-ms {ms}"));
    }
    if let Some(mb) = limits.memory_limit_mb {
        limit_args.push_str(&format!(" --memory-limit-mb {mb}"));
    }
    let mut rows = Vec::new();
    for (rank, s) in selection::rank_entrants(&scores) {
        let Some(row) = kept.iter().find(|r| r.bot_version_id == s.bot_version_id) else {
            continue;
        };
        let recount = counted
            .iter()
            .find(|r| r.bot_version_id == s.bot_version_id);
        let equal = recount.is_some_and(|r| {
            r.played == row.played && r.finished == row.finished && r.score_sum30 == row.score_sum30
        });
        if !equal {
            tracing::error!(competition = %c.name, version = s.bot_version_id,
                "the running sums differ from the recount of the match records");
        }
        let version = storage.get_bot_version(s.bot_version_id).await?;
        let played: Vec<serde_json::Value> = matches
            .iter()
            .filter(|m| m.bot_version_id == s.bot_version_id)
            .map(|m| {
                serde_json::json!({
                    "match_id": m.match_id, "maze": m.maze_name, "maze_hash": m.maze_hash,
                    "repeat": m.repeat, "seed": m.seed, "status": m.status.to_string(),
                    "score": m.score,
                })
            })
            .collect();
        let env = version.as_ref().map(|v| v.env_pairs()).unwrap_or_default();
        let runtime = version.as_ref().and_then(|v| v.runtime.clone());
        let build_command = version.as_ref().and_then(|v| v.build_command.clone());
        let replay = replay_command(
            &env,
            runtime.as_deref(),
            build_command.as_deref(),
            &limit_args,
        );
        let manifest = serde_json::json!({
            "competition": c.name,
            "bot_version_id": s.bot_version_id,
            "bundle_sha256": version.as_ref().map(|v| v.files_sha256.clone()),
            "built_sha256": version.as_ref().and_then(|v| v.built_sha256.clone()),
            "command": version.as_ref().map(|v| v.command.clone()),
            "runtime": runtime,
            "build_command": build_command,
            "env": declared_env(&env),
            "referee": crate::runner::ENGINE_VERSION,
            "tournament_id": t,
            "mazes": mazes,
            "seeds": seeds,
            "limits": c.limit_set(),
            "recount": {
                "equal": equal,
                "played": recount.map(|r| r.played),
                "finished": recount.map(|r| r.finished),
                "mean_score": recount.map(|r| r.mean().rounded()),
                "score_sum30": recount.map(|r| r.score_sum30),
            },
            "matches": played,
            "replay": replay,
        });
        rows.push(ResultRow {
            rank,
            entrant_id: s.entrant_id,
            entrant_name: row.entrant_name.clone().unwrap_or_default(),
            bot_id: row.bot_id,
            bot_name: row.bot_name.clone(),
            bot_version_id: s.bot_version_id,
            version: row.version,
            played: row.played,
            finished: row.finished,
            mean_score: row.mean().rounded(),
            score_sum30: row.score_sum30,
            finish_rate: ratio_3dp(row.finished, row.played),
            manifest: manifest.to_string(),
            uncertainty: Default::default(),
        });
    }
    let reveal = mazes_to_reveal(storage, c, &private).await?;
    Ok(storage.write_results(c, &rows, &reveal).await?)
}

/// The private mazes that publishing `c`'s results shows: all of them if it reveals
/// them, but none that another live competition still uses.
async fn mazes_to_reveal(
    storage: &Storage,
    c: &CompetitionRow,
    private: &[CompetitionMaze],
) -> Result<Vec<i64>> {
    let mut reveal = Vec::new();
    if c.reveal_private_mazes {
        for m in private {
            if !storage
                .maze_in_other_live_competition(m.maze_id, c.competition_id)
                .await?
            {
                reveal.push(m.maze_id);
            }
        }
    }
    Ok(reveal)
}

/// Publishes the held results of `c` (its organisers' decision, after the reveal's
/// rehearsal): from now on everyone sees them, the private board, the reveal and the
/// races, and the private mazes if the competition reveals them.
///
/// # Errors
/// [`RegistryError::Conflict`] when there are no held results (not written yet, or
/// published already); the database.
pub async fn publish(storage: &Storage, c: &CompetitionRow) -> Result<()> {
    match c.state.as_deref() {
        Some("held") => {}
        Some("final") => {
            return Err(RegistryError::Conflict(format!(
                "the results of {} are published already",
                c.name
            )));
        }
        _ => {
            return Err(RegistryError::Conflict(format!(
                "competition {} has no results to publish yet: they are written once its final run has played",
                c.name
            )));
        }
    }
    let private = private_mazes(storage, c).await?;
    let reveal = mazes_to_reveal(storage, c, &private).await?;
    if !storage.publish_results(c, &reveal).await? {
        return Err(RegistryError::Conflict(format!(
            "the results of {} are published already",
            c.name
        )));
    }
    Ok(())
}

/// The declared environment of a version as a manifest holds it: each variable's name
/// and the SHA-256 (hex) of `NAME=VALUE`, so that the owner, who knows the values, can
/// check them, and nobody else learns them.
fn declared_env(env: &[(String, String)]) -> Vec<serde_json::Value> {
    env.iter()
        .map(|(k, v)| {
            serde_json::json!({
                "name": k,
                "sha256": crate::registry::tokens::hash_token(&format!("{k}={v}")),
            })
        })
        .collect()
}

/// The command line that plays one of a version's matches again with `mazearena run`:
/// its declared variables (values from the owner), its runtime, the build run first.
fn replay_command(
    env: &[(String, String)],
    runtime: Option<&str>,
    build: Option<&str>,
    limit_args: &str,
) -> String {
    let mut out = String::new();
    if let Some(b) = build {
        out.push_str(&format!("(cd FOLDER_OF_THE_BUNDLE && {b}) && "));
    }
    out.push_str(
        "mazearena run --maze MAZE_FILE --bot COMMAND --bot-dir FOLDER_OF_THE_BUNDLE --seed SEED",
    );
    out.push_str(limit_args);
    if runtime.is_some() {
        out.push_str(" --runtime DIR_OF_THE_RUNTIME");
    }
    for (k, _) in env {
        out.push_str(&format!(" --bot-env {k}=VALUE"));
    }
    out
}

/// Checks stored results against a recount from the match records now: the rows whose
/// numbers differ (empty: the snapshot holds).
///
/// # Errors
/// The database.
pub async fn recount_differences(storage: &Storage, c: &CompetitionRow) -> Result<Vec<String>> {
    let Some(t) = deciding_tournament(c) else {
        return Ok(Vec::new());
    };
    let counted = storage.competition_board(t, true).await?;
    let mut differ = Vec::new();
    for r in storage.competition_results(c.competition_id).await? {
        let same = counted
            .iter()
            .find(|x| x.bot_version_id == r.bot_version_id)
            .is_some_and(|x| {
                x.played == r.played && x.finished == r.finished && x.score_sum30 == r.score_sum30
            });
        if !same {
            differ.push(format!("{} (version {})", r.entrant_name, r.version));
        }
    }
    Ok(differ)
}

/// The results as CSV: a header, then one row per entrant. A name that a spreadsheet
/// would take for a formula (starting with `=`, `+`, `-`, `@`, a tab or a carriage
/// return) is written after a `'`.
pub fn results_csv(rows: &[ResultRow]) -> String {
    let field = |s: &str| {
        let s = if s.starts_with(['=', '+', '-', '@', '\t', '\r']) {
            format!("'{s}")
        } else {
            s.to_string()
        };
        if s.contains([',', '"', '\n', '\r']) {
            format!("\"{}\"", s.replace('"', "\"\""))
        } else {
            s
        }
    };
    let mut out = String::from(
        "rank,rank_range,tie_group,entrant,bot,version,played,finished,mean_score,score_low,score_high,finish_rate,score_sum30,bundle_sha256\n",
    );
    for r in rows {
        let bundle = serde_json::from_str::<serde_json::Value>(&r.manifest)
            .ok()
            .and_then(|m| m["bundle_sha256"].as_str().map(str::to_string))
            .unwrap_or_default();
        out.push_str(&format!(
            "{},{},{},{},{},{},{},{},{},{:.3},{:.3},{:.3},{},{}\n",
            r.rank,
            r.uncertainty.rank_range,
            r.uncertainty.tie_group,
            field(&r.entrant_name),
            field(&r.bot_name),
            r.version,
            r.played,
            r.finished,
            r.mean(),
            r.uncertainty.low,
            r.uncertainty.high,
            r.finish_rate,
            r.score_sum30,
            bundle
        ));
    }
    out
}

/// The mazes of `c`'s private set.
async fn private_mazes(storage: &Storage, c: &CompetitionRow) -> Result<Vec<CompetitionMaze>> {
    let mut mazes = storage.competition_mazes(c.competition_id).await?;
    mazes.retain(|m| m.maze_set == "private");
    Ok(mazes)
}
