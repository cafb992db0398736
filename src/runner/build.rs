//! Running a bot's build command (`bot.toml`'s `build`), which is as untrusted as the bot:
//! in the sandbox, with the bot's folder writable so that what it builds stays, no
//! network, and the match limits; without the sandbox, directly in the folder.

use std::path::Path;
use std::time::Duration;

use super::sandbox::{Sandbox, jail};

/// The longest a build may take.
pub const BUILD_TIMEOUT: Duration = Duration::from_secs(600);

/// The scratch (`/tmp`) size of a build, in bytes.
const BUILD_SCRATCH_BYTES: u64 = 1 << 30;

/// Processes and threads a build may have at once.
const BUILD_PROCESS_LIMIT: u64 = 256;

/// Why a build failed.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// The command is empty or has unbalanced quotes.
    #[error("the build command {0:?} cannot be split into words")]
    BadCommand(String),
    /// It could not be started.
    #[error("cannot run the build command {command:?}: {source}")]
    Spawn {
        /// The command.
        command: String,
        /// The OS error.
        source: std::io::Error,
    },
    /// It ran and failed.
    #[error("the build command {command:?} failed ({status}){stderr}")]
    Failed {
        /// The command.
        command: String,
        /// How it ended.
        status: String,
        /// The end of its stderr, prefixed with a newline when not empty.
        stderr: String,
    },
}

/// The most memory a build's processes may hold together (in the sandbox, with a
/// cgroup): compilers need more than bots.
pub const BUILD_MEMORY_BYTES: u64 = 2 << 30;

/// How much of a build's output (stdout and stderr, interleaved) is kept.
pub const BUILD_LOG_BYTES: usize = 64 * 1024;

/// How a build ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BuildOutcome {
    /// Whether it exited with status 0 in time.
    pub ok: bool,
    /// How it ended, for people ("exit status: 2", "took more than 600 s").
    pub status: String,
    /// The end of its output ([`BUILD_LOG_BYTES`]).
    pub log: String,
}

/// Runs `command` in `dir` under `sandbox`, waiting at most [`BUILD_TIMEOUT`].
///
/// # Errors
/// [`BuildError`] when it cannot run, fails or takes too long.
pub async fn build(command: &str, dir: &Path, sandbox: &Sandbox) -> Result<(), BuildError> {
    let outcome = build_logged(command, dir, sandbox).await?;
    if outcome.ok {
        return Ok(());
    }
    let tail: String = outcome
        .log
        .chars()
        .rev()
        .take(2000)
        .collect::<Vec<_>>()
        .into_iter()
        .rev()
        .collect();
    Err(BuildError::Failed {
        command: command.to_string(),
        status: outcome.status,
        stderr: if tail.trim().is_empty() {
            String::new()
        } else {
            format!("\n{}", tail.trim_end())
        },
    })
}

/// Runs `command` in `dir` under `sandbox` with the build limits (time
/// [`BUILD_TIMEOUT`], memory [`BUILD_MEMORY_BYTES`] where a cgroup can be made, output
/// kept to its last [`BUILD_LOG_BYTES`]), and returns how it ended with its output.
///
/// # Errors
/// [`BuildError`] only when it cannot be started at all.
pub async fn build_logged(
    command: &str,
    dir: &Path,
    sandbox: &Sandbox,
) -> Result<BuildOutcome, BuildError> {
    let words = shlex::split(command)
        .filter(|w| !w.is_empty())
        .ok_or_else(|| BuildError::BadCommand(command.to_string()))?;
    let spawn_err = |source| BuildError::Spawn {
        command: command.to_string(),
        source,
    };
    let mut cgroup = None;
    let mut cmd = match sandbox {
        Sandbox::None => {
            let mut cmd = tokio::process::Command::new(&words[0]);
            cmd.args(&words[1..]).current_dir(dir);
            cmd
        }
        Sandbox::Full(full) => {
            let args = super::sandbox::bwrap_args(full, Some(dir), BUILD_SCRATCH_BYTES, true, &[])
                .map_err(spawn_err)?;
            if let Ok(root) = &full.cgroups {
                cgroup = Some(
                    root.create(super::sandbox::cgroup::CgroupLimits {
                        memory_bytes: Some(BUILD_MEMORY_BYTES),
                        pids: Some(BUILD_PROCESS_LIMIT),
                        core: None,
                    })
                    .map_err(spawn_err)?,
                );
            }
            let jail = jail::JailArgs {
                nproc: (!full.as_root).then_some(BUILD_PROCESS_LIMIT),
                command: words.iter().map(Into::into).collect(),
                ..jail::JailArgs::default()
            };
            tokio::process::Command::from(full.command(args, &jail, cgroup.as_ref()))
        }
    };
    // One pipe for stdout and stderr, so the log keeps their order.
    let (reader, writer) = std::io::pipe().map_err(spawn_err)?;
    let writer2 = writer.try_clone().map_err(spawn_err)?;
    cmd.stdin(std::process::Stdio::null())
        .stdout(writer)
        .stderr(writer2)
        .process_group(0)
        .kill_on_drop(true);
    let mut child = cmd.spawn().map_err(spawn_err)?;
    // Our copies of the pipe's write end went with `cmd`: drop it so the read ends.
    drop(cmd);
    let log = tokio::task::spawn_blocking(move || read_tail_blocking(reader, BUILD_LOG_BYTES));
    let pid = child.id();
    let waited = tokio::time::timeout(BUILD_TIMEOUT, child.wait()).await;
    if let Some(pid) = pid {
        super::sandbox::proctree::kill_tree(pid);
        super::process::kill_group(pid);
    }
    let status = match &waited {
        Ok(Ok(s)) => s.to_string(),
        Ok(Err(e)) => format!("could not be waited for: {e}"),
        Err(_) => {
            let _ = child.kill().await;
            format!("took more than {} s", BUILD_TIMEOUT.as_secs())
        }
    };
    let ok = matches!(&waited, Ok(Ok(s)) if s.success());
    let oom = cgroup
        .as_ref()
        .and_then(|c| c.limit_hit())
        .is_some_and(|k| k == super::sandbox::cgroup::CgroupHit::Memory);
    let mut log = tokio::time::timeout(std::time::Duration::from_secs(5), log)
        .await
        .ok()
        .and_then(Result::ok)
        .unwrap_or_else(|| "[the build's output could not be read to its end]".into());
    if oom {
        log.push_str(&format!(
            "\n[the build went over its memory limit of {} MiB]",
            BUILD_MEMORY_BYTES >> 20
        ));
    }
    Ok(BuildOutcome {
        ok: ok && !oom,
        status,
        log,
    })
}

/// Reads `reader` to its end, keeping its last `cap` bytes as text.
fn read_tail_blocking(mut reader: impl std::io::Read, cap: usize) -> String {
    let mut tail: std::collections::VecDeque<u8> = std::collections::VecDeque::new();
    let mut total = 0u64;
    let mut buf = [0u8; 8192];
    loop {
        match reader.read(&mut buf) {
            Ok(0) | Err(_) => break,
            Ok(n) => {
                total += n as u64;
                tail.extend(&buf[..n]);
                if tail.len() > cap {
                    let extra = tail.len() - cap;
                    tail.drain(..extra);
                }
            }
        }
    }
    let text = String::from_utf8_lossy(tail.make_contiguous()).into_owned();
    if total > tail.len() as u64 {
        format!(
            "[... {} earlier bytes not kept]\n{text}",
            total - tail.len() as u64
        )
    } else {
        text
    }
}
