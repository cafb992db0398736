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

/// Runs `command` in `dir` under `sandbox`, waiting at most [`BUILD_TIMEOUT`].
///
/// # Errors
/// [`BuildError`] when it cannot run, fails or takes too long.
pub async fn build(command: &str, dir: &Path, sandbox: &Sandbox) -> Result<(), BuildError> {
    let words = shlex::split(command)
        .filter(|w| !w.is_empty())
        .ok_or_else(|| BuildError::BadCommand(command.to_string()))?;
    let spawn_err = |source| BuildError::Spawn {
        command: command.to_string(),
        source,
    };
    let mut cmd = match sandbox {
        Sandbox::None => {
            let mut cmd = tokio::process::Command::new(&words[0]);
            cmd.args(&words[1..]).current_dir(dir);
            cmd
        }
        Sandbox::Full(full) => {
            let args = super::sandbox::bwrap_args(full, Some(dir), BUILD_SCRATCH_BYTES, true)
                .map_err(spawn_err)?;
            let jail = jail::JailArgs {
                nproc: (!full.as_root).then_some(BUILD_PROCESS_LIMIT),
                command: words.iter().map(Into::into).collect(),
                ..jail::JailArgs::default()
            };
            tokio::process::Command::from(full.command(args, &jail))
        }
    };
    cmd.stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .process_group(0)
        .kill_on_drop(true);
    let child = cmd.spawn().map_err(spawn_err)?;
    let pid = child.id();
    let out = tokio::time::timeout(BUILD_TIMEOUT, child.wait_with_output()).await;
    if let Some(pid) = pid {
        super::sandbox::proctree::kill_tree(pid);
        super::process::kill_group(pid);
    }
    let (status, stderr) = match out {
        Ok(Ok(o)) if o.status.success() => return Ok(()),
        Ok(Ok(o)) => (o.status.to_string(), o.stderr),
        Ok(Err(e)) => return Err(spawn_err(e)),
        Err(_) => (
            format!("took more than {} s", BUILD_TIMEOUT.as_secs()),
            Vec::new(),
        ),
    };
    let text = String::from_utf8_lossy(&stderr);
    let tail: String = text
        .chars()
        .rev()
        .take(2000)
        .collect::<Vec<_>>()
        .into_iter()
        .rev()
        .collect();
    Err(BuildError::Failed {
        command: command.to_string(),
        status,
        stderr: if tail.trim().is_empty() {
            String::new()
        } else {
            format!("\n{}", tail.trim_end())
        },
    })
}
