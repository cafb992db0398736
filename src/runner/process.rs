//! Starting a bot process and ending it: its own process group, piped stdio, a small
//! environment, resource limits, and a kill of the whole group when the match is over.

use std::path::Path;
use std::process::Stdio;

use nix::sys::resource::{Resource, setrlimit};
use nix::sys::signal::{Signal, killpg};
use nix::unistd::Pid;
use tokio::process::{Child, Command};

/// Environment variables passed through to bots; everything else is cleared so a bot
/// sees the same environment under the CLI and the server.
const PASSED_ENV: &[&str] = &[
    "PATH",
    "HOME",
    "LANG",
    "LC_ALL",
    "TZ",
    "TMPDIR",
    "PYENV_ROOT",
    "PYENV_VERSION",
];

/// The largest file a bot may write (RLIMIT_FSIZE), so a bot cannot fill the disk.
pub const MAX_BOT_FILE_BYTES: u64 = 64 * 1024 * 1024;

/// How the bot process is started.
#[derive(Debug, Clone)]
pub struct Launch<'a> {
    /// The command line, split like a shell would (no shell is run).
    pub command: &'a str,
    /// The bot's working directory.
    pub dir: &'a Path,
    /// Address-space limit in bytes (RLIMIT_AS); `None`: no limit.
    pub memory_limit_bytes: Option<u64>,
}

/// Why a bot could not be started.
#[derive(Debug, thiserror::Error)]
pub enum LaunchError {
    /// The command is empty or has unbalanced quotes.
    #[error("the bot command {0:?} cannot be split into words (empty, or unbalanced quotes)")]
    BadCommand(String),
    /// The operating system refused to start it.
    #[error("could not start {program:?} in {dir}: {source}")]
    Spawn {
        /// The program.
        program: String,
        /// The working directory.
        dir: String,
        /// The OS error.
        source: std::io::Error,
    },
}

/// Starts the bot in its own process group with piped stdin, stdout and stderr.
///
/// # Errors
/// [`LaunchError`] when the command is malformed or cannot be started.
pub fn spawn(launch: &Launch<'_>) -> Result<Child, LaunchError> {
    let words = shlex::split(launch.command)
        .filter(|w| !w.is_empty())
        .ok_or_else(|| LaunchError::BadCommand(launch.command.to_string()))?;
    let mut cmd = Command::new(&words[0]);
    cmd.args(&words[1..])
        .current_dir(launch.dir)
        .env_clear()
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .process_group(0)
        .kill_on_drop(true);
    for key in PASSED_ENV {
        if let Some(value) = std::env::var_os(key) {
            cmd.env(key, value);
        }
    }
    cmd.env("PYTHONUNBUFFERED", "1");
    cmd.env("PYTHONDONTWRITEBYTECODE", "1");
    let memory = launch.memory_limit_bytes;
    // SAFETY: the closure runs in the child between fork and exec; it only calls
    // setrlimit, which is async-signal-safe, and allocates nothing.
    unsafe {
        cmd.pre_exec(move || {
            let _ = setrlimit(Resource::RLIMIT_CORE, 0, 0);
            let _ = setrlimit(
                Resource::RLIMIT_FSIZE,
                MAX_BOT_FILE_BYTES,
                MAX_BOT_FILE_BYTES,
            );
            if let Some(bytes) = memory {
                setrlimit(Resource::RLIMIT_AS, bytes, bytes).map_err(std::io::Error::from)?;
            }
            Ok(())
        });
    }
    cmd.spawn().map_err(|source| LaunchError::Spawn {
        program: words[0].clone(),
        dir: launch.dir.display().to_string(),
        source,
    })
}

/// Kills every process of the bot's process group (the group id is the bot's pid).
/// A group that is already gone is not an error.
pub fn kill_group(pgid: u32) {
    let _ = killpg(Pid::from_raw(pgid as i32), Signal::SIGKILL);
}

/// Kills the bot's process group when dropped, so a cancelled match leaves nothing behind.
#[derive(Debug)]
pub struct GroupGuard {
    /// The process group id (the bot's pid).
    pub pgid: Option<u32>,
}

impl Drop for GroupGuard {
    fn drop(&mut self) {
        if let Some(pgid) = self.pgid {
            kill_group(pgid);
        }
    }
}

/// CPU time (user + system, including waited-for children) of a live or not yet reaped
/// process, in milliseconds, read from `/proc/<pid>/stat` (Linux); `None` elsewhere.
pub fn cpu_time_ms(pid: u32) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // Fields after the command name, which is in parentheses and may hold spaces.
    let rest = &stat[stat.rfind(')')? + 2..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    // utime, stime, cutime, cstime are fields 14..=17 of stat(5); `rest` starts at 3.
    let ticks: u64 = fields
        .get(11..15)?
        .iter()
        .map(|f| f.parse::<u64>().unwrap_or(0))
        .sum();
    let hz = nix::unistd::sysconf(nix::unistd::SysconfVar::CLK_TCK)
        .ok()
        .flatten()
        .filter(|&h| h > 0)? as u64;
    Some(ticks * 1000 / hz)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cpu_time_of_this_process_is_readable() {
        assert!(cpu_time_ms(std::process::id()).is_some());
    }

    #[tokio::test]
    async fn a_malformed_command_is_refused() {
        let dir = std::env::temp_dir();
        for bad in ["", "   ", "python3 'unterminated"] {
            let launch = Launch {
                command: bad,
                dir: &dir,
                memory_limit_bytes: None,
            };
            assert!(
                matches!(spawn(&launch), Err(LaunchError::BadCommand(_))),
                "{bad:?}"
            );
        }
        let launch = Launch {
            command: "/nonexistent/bot",
            dir: &dir,
            memory_limit_bytes: None,
        };
        assert!(matches!(spawn(&launch), Err(LaunchError::Spawn { .. })));
    }
}
