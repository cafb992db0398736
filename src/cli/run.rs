//! `mazearena run`: referee one match locally and print the result.

use std::io::Write;
use std::path::PathBuf;
use std::time::Duration;

use anyhow::Context;
use clap::Args;

use crate::engine::game::StepEvent;
use crate::runner::{self, BotSpec, Limits, MatchRecord, MatchStatus, TraceStep};

/// Arguments of `mazearena run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// The maze file (numeric or ASCII format).
    #[arg(long)]
    maze: PathBuf,
    /// The bot's command line, split like a shell (no shell is run), e.g. 'python3 bot.py'.
    #[arg(long)]
    bot: String,
    /// The bot's working directory (default: the current directory).
    #[arg(long)]
    bot_dir: Option<PathBuf>,
    /// The seed sent to the bot in the start message.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Print one JSON object with the result instead of the progress text.
    #[arg(long)]
    json: bool,
    /// CPU time limit for every answer after the first, in milliseconds (CPU time of all
    /// the bot's processes: the same on an idle or a busy machine).
    #[arg(long, default_value_t = runner::DEFAULT_MOVE_TIMEOUT.as_millis() as u64)]
    move_timeout_ms: u64,
    /// CPU time limit for the first answer (includes the interpreter's start), in
    /// milliseconds.
    #[arg(long, default_value_t = runner::DEFAULT_STARTUP_TIMEOUT.as_millis() as u64)]
    startup_timeout_ms: u64,
    /// CPU time the moves may use beyond their limit, all together over the match, in
    /// milliseconds (a few slow moves do not end a match).
    #[arg(long, default_value_t = runner::DEFAULT_TIME_BANK.as_millis() as u64)]
    time_bank_ms: u64,
    /// No time limits at all (to debug a bot step by step).
    #[arg(long)]
    no_timeout: bool,
    /// The bot's memory limit in MiB (0: no limit): resident memory of all its processes
    /// together in the sandbox; without it, twice this as each process's address space.
    #[arg(long, default_value_t = runner::DEFAULT_MEMORY_LIMIT_MB)]
    memory_limit_mb: u64,
    /// The most processes and threads the bot may have at once (sandbox only).
    #[arg(long, default_value_t = runner::DEFAULT_PROCESS_LIMIT)]
    process_limit: u32,
    /// The size of the bot's writable scratch area (working directory and /tmp), in MiB.
    #[arg(long, default_value_t = runner::DEFAULT_SCRATCH_MB)]
    scratch_mb: u64,
    #[command(flatten)]
    sandbox: super::sandbox::SandboxArgs,
    /// Write the full match record with its per-step trace and the maze (JSON) to this
    /// file; `mazearena replay FILE -o match.html` shows it.
    #[arg(long)]
    replay: Option<PathBuf>,
    /// Write the match as a self-contained HTML replay viewer to this file.
    #[arg(long)]
    html: Option<PathBuf>,
    /// Print every exchange (sensors in, answer out) and the bot's stderr as it comes.
    #[arg(long, short = 'v', conflicts_with = "json")]
    verbose: bool,
    /// The protocol the bot speaks: `v1` (JSON lines) or `mms` (a mouse written for the
    /// mms simulator, translated by the referee: docs/PROTOCOL-mms.md).
    #[arg(long, default_value = "v1", value_parser = crate::runner::BotProtocol::parse)]
    protocol: crate::runner::BotProtocol,
    /// An environment variable for the bot, KEY=VALUE (repeatable); the bot gets no
    /// other variable of yours.
    #[arg(long = "bot-env", value_name = "KEY=VALUE", value_parser = parse_bot_env)]
    bot_env: Vec<(String, String)>,
}

pub(super) fn parse_bot_env(text: &str) -> Result<(String, String), String> {
    runner::botenv::parse_assignment(text).map_err(|e| e.to_string())
}

/// Runs `mazearena run`.
///
/// # Errors
/// A bad maze, a missing bot directory, or a replay file that cannot be written. What
/// the bot does is never an error: it is the match's status.
pub fn run(args: RunArgs) -> anyhow::Result<()> {
    let maze = super::load_maze(&args.maze)?;
    let dir = match &args.bot_dir {
        Some(d) => d.clone(),
        None => std::env::current_dir().context("cannot read the current directory")?,
    };
    anyhow::ensure!(
        dir.is_dir(),
        "the bot directory {} does not exist",
        dir.display()
    );
    let limits = Limits {
        startup_timeout: (!args.no_timeout).then(|| Duration::from_millis(args.startup_timeout_ms)),
        move_timeout: (!args.no_timeout).then(|| Duration::from_millis(args.move_timeout_ms)),
        time_bank: Duration::from_millis(args.time_bank_ms),
        memory_limit_mb: (args.memory_limit_mb > 0).then_some(args.memory_limit_mb),
        process_limit: Some(args.process_limit.max(1)),
        scratch_mb: args.scratch_mb.max(1),
        ..Limits::default()
    };
    // The match itself proves the sandbox: the test command runs only if it fails.
    let sandbox = args.sandbox.open_unverified(&[], true)?;
    // Said before the match (the match still runs: the bot may mean to fail to open it).
    if let Some(outside) = file_outside_the_folder(&args.bot, &dir) {
        let message = outside_message(&args.bot, &dir, &outside);
        if sandbox.level() == "full" {
            eprintln!("warning: {message}");
        } else {
            eprintln!(
                "warning: {message} (it opens here only because the sandbox is off; a server's sandbox is on)"
            );
        }
    }
    runner::botenv::check(&args.bot_env)?;
    let bot = BotSpec {
        command: args.bot.clone(),
        dir,
        env: args.bot_env.clone(),
        echo_stderr: args.verbose,
        runtime: None,
        protocol: args.protocol,
    };
    // One core for the referee and the bot (runner::affinity): the one we are on.
    crate::runner::affinity::pin_to_this_core();
    // The sandbox's orphans are ours to reap (see below), not the host's init's.
    let reaps = runner::sandbox::proctree::adopt_orphans().is_ok();
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("cannot start the async runtime")?;
    let (json, verbose) = (args.json, args.verbose);
    if !json {
        println!(
            "Maze {} ({}x{}), bot `{}`, seed {}",
            args.maze.display(),
            maze.dim(),
            maze.dim(),
            args.bot,
            args.seed
        );
        println!("Starting run 0.");
    }
    let record = runtime.block_on(runner::run_match(
        &bot,
        &maze,
        args.seed,
        limits,
        &sandbox,
        |step| {
            if verbose {
                print_exchange(step);
            }
            if !json {
                print_step(step);
            }
        },
    ));
    // A bot that failed in a sandbox that does not work here is not the bot's fault.
    let verified = if matches!(
        record.status,
        MatchStatus::Finished | MatchStatus::StepLimit
    ) {
        Ok(())
    } else {
        super::sandbox::verify(&sandbox)
    };
    if reaps {
        // Every process of the match (and of the test) was killed and its outer process
        // waited for; what is left are ended orphans (bubblewrap's init), which would
        // hold the match's kept cgroup for the next run until the host's init reaped
        // them.
        runner::sandbox::proctree::reap_orphans();
    }
    verified?;
    let mut record = record;
    record.maze_layout = Some(crate::engine::mazefile::numeric::write(&maze));
    let title = format!(
        "{} on {} (seed {})",
        args.bot,
        args.maze
            .file_stem()
            .map_or_else(String::new, |s| s.to_string_lossy().into_owned()),
        args.seed
    );
    record.title = Some(title.clone());
    if let Some(path) = &args.replay {
        let text = serde_json::to_string(&record).context("cannot encode the match record")?;
        std::fs::write(path, text)
            .with_context(|| format!("cannot write the replay to {}", path.display()))?;
    }
    if let Some(path) = &args.html {
        super::replay::write_html(&record, Some(&maze), title, path)?;
    }
    if json {
        let summary =
            serde_json::to_string(&record.summary()).context("cannot encode the result")?;
        println!("{summary}");
    } else {
        print_result(&record);
    }
    Ok(())
}

/// An argument of the bot's command (not its program) that names an existing file
/// outside the bot's folder `dir` (and outside the system's folders): in the sandbox
/// the bot sees only its folder, so it could not open it.
fn file_outside_the_folder(command: &str, dir: &std::path::Path) -> Option<PathBuf> {
    let words = shlex::split(command)?;
    let dir = dir.canonicalize().ok()?;
    words.iter().skip(1).find_map(|word| {
        let path = dir.join(word);
        let real = path.canonicalize().ok().filter(|p| p.is_file())?;
        let system = ["/usr", "/lib", "/lib64", "/bin", "/sbin", "/etc"]
            .iter()
            .any(|s| real.starts_with(s));
        (!real.starts_with(&dir) && !system).then_some(real)
    })
}

/// What to say of a command naming `file` outside the bot's folder `dir`, with the flags
/// that would work.
fn outside_message(command: &str, dir: &std::path::Path, file: &std::path::Path) -> String {
    let words = shlex::split(command).unwrap_or_default();
    let name = file
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let folder = file.parent().unwrap_or(std::path::Path::new("/"));
    let fix = if words.len() == 2 {
        format!(
            "give its folder: --bot-dir {} --bot '{} {name}'",
            folder.display(),
            words[0]
        )
    } else {
        format!(
            "copy it into the bot's folder, or run from a folder that holds it (--bot-dir {})",
            folder.display()
        )
    };
    format!(
        "the bot's command names {}, which is outside the bot's folder {} (--bot-dir, by \
         default the current folder): a bot sees only its own folder besides the system and \
         its runtimes, so it cannot open that file; {fix}",
        file.display(),
        dir.display(),
    )
}

/// `--verbose`: one line per exchange, as the bot saw it and answered.
fn print_exchange(step: &TraceStep) {
    let r = &step.report;
    let answer = match r.action {
        crate::engine::Action::Move { rotation, movement } => {
            format!("{{\"rotation\":{rotation},\"movement\":{movement}}}")
        }
        crate::engine::Action::Reset { .. } => "{\"reset\":true}".to_string(),
    };
    println!(
        "step {:>4} run {}: sensors {:?} -> {answer}  => ({},{}) {:?}{}  [{:.1} ms]",
        r.step,
        r.run,
        r.sensors,
        r.position.x,
        r.position.y,
        r.heading,
        if r.blocked { " blocked" } else { "" },
        step.answer_us as f64 / 1000.0
    );
    if let Some(text) = step
        .debug
        .as_ref()
        .and_then(|d| d.get("text"))
        .and_then(|t| t.as_str())
    {
        println!("           debug: {text}");
    }
}

fn print_step(step: &TraceStep) {
    let r = &step.report;
    for w in &r.warnings {
        println!("step {}: warning: {}", w.step, w.message);
    }
    match r.event {
        StepEvent::ResetAccepted => {
            println!("Ending first run at step {}. Starting next run.", r.step);
            println!("Starting run 1.");
        }
        StepEvent::GoalReached => println!("Goal found at step {}; run 1 completed!", r.step),
        StepEvent::Move | StepEvent::ResetRejected => {}
    }
    let _ = std::io::stdout().flush();
}

fn print_result(record: &MatchRecord) {
    let steps = |s: Option<u32>| s.map_or("-".to_string(), |n| n.to_string());
    match record.status {
        MatchStatus::Finished => {
            println!(
                "Run 0: {} steps, run 1: {} steps, {} warning(s).",
                steps(record.run0_steps),
                steps(record.run1_steps),
                record.warnings.len()
            );
            if let Some(score) = record.score {
                println!("Task complete! Score: {score:.3}");
            }
        }
        MatchStatus::StepLimit => {
            println!("Allotted time exceeded: the 1000-step budget ran out.");
            println!(
                "Match did not finish (step_limit). Run 0: {} steps.",
                steps(record.run0_steps)
            );
        }
        status => {
            println!(
                "Match did not finish ({status}) at step {}.",
                record.total_steps
            );
        }
    }
    for n in &record.notices {
        println!("Note: {}", n.message);
    }
    if let Some(error) = &record.error {
        println!("Reason: {}", error.reason);
        if let Some(line) = &error.line {
            println!("Offending line: {line}");
        }
        if let Some(code) = error.exit_code {
            println!("Exit code: {code}");
        }
        if let Some(signal) = error.signal {
            println!("Killed by signal {signal}");
        }
        let tail: Vec<&str> = record.stderr_tail.lines().rev().take(20).collect();
        if !tail.is_empty() {
            println!("Last lines of the bot's stderr:");
            for line in tail.into_iter().rev() {
                println!("  | {line}");
            }
        }
    }
}
