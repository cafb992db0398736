//! Starting a bot process and ending it. With [`Sandbox::Full`] the process is
//! bubblewrap (after `mazearena sandbox-enter` has put it in the match's cgroup), which
//! builds the bot's world and runs it through the jail step; with
//! [`Sandbox::None`] it is the bot itself. Either way it gets piped stdio, its own
//! process group and a small environment, and every process it makes is killed when the
//! match is over (by its cgroup, its PID namespace, and a kill of its tree and group).

use std::path::{Path, PathBuf};
use std::process::Stdio;

use nix::sys::signal::{Signal, killpg};
use nix::unistd::Pid;
use tokio::process::{Child, Command};

use super::sandbox::cgroup::{CgroupHit, CgroupLimits, MatchCgroup};
use super::sandbox::warm::{self, WarmMatch};
use super::sandbox::{Sandbox, UidLease, jail, proctree, supervisor};

/// Environment variables passed through to bots run without the sandbox; everything
/// else is cleared so a bot sees the same environment under the CLI and the server.
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

/// The largest file a bot may write without the sandbox (RLIMIT_FSIZE), so a bot cannot
/// fill the disk. In the sandbox its scratch size bounds it.
pub const MAX_BOT_FILE_BYTES: u64 = 64 * 1024 * 1024;

/// bubblewrap's own processes in the match (its monitor and the namespace's init),
/// counted by the cgroup's process limit on top of the bot's.
const BWRAP_PROCESSES: u64 = 2;

/// How the bot process is started.
#[derive(Debug, Clone)]
pub struct Launch<'a> {
    /// The command line, split like a shell would (no shell is run).
    pub command: &'a str,
    /// The bot's folder: its working directory (in the sandbox: mounted read-only in a
    /// writable scratch working directory).
    pub dir: &'a Path,
    /// The memory limit in bytes: all processes' resident memory in the sandbox, each
    /// process's address space (twice the value) without it.
    pub memory_limit_bytes: Option<u64>,
    /// The most processes and threads at once (sandbox only).
    pub process_limit: Option<u64>,
    /// The size of the scratch area in bytes (sandbox only).
    pub scratch_bytes: u64,
    /// The isolation.
    pub sandbox: &'a Sandbox,
    /// Variables declared for the bot (checked by [`super::botenv::check`]).
    pub env: &'a [(String, String)],
    /// The runtime to put first on its `PATH`, by name ([`super::runtimes::name_of`]).
    pub runtime: Option<&'a str>,
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
    /// The match's cgroup or sandbox could not be prepared (an operator problem).
    #[error("could not prepare the sandbox: {0}")]
    Sandbox(String),
}

/// Which whole-match limit a bot went over.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LimitKind {
    /// Resident memory of all its processes.
    Memory,
    /// Processes and threads at once.
    Processes,
    /// Its scratch area is full.
    Scratch,
}

/// What the runner writes the bot's stdin through: a pipe, which the match may also
/// write at once, past the runtime.
pub type BotStdin = tokio::net::unix::pipe::Sender;

/// What the runner reads the bot's stdout or stderr through: a pipe, which the match
/// may also wait on and read at once, past the runtime.
pub type BotOutput = tokio::net::unix::pipe::Receiver;

/// How the bot's processes were started.
#[derive(Debug)]
enum Started {
    /// A child of the runner: the bot itself, or a one-shot sandbox (bubblewrap).
    Child(Child),
    /// A match in a warm sandbox.
    Warm(Box<WarmMatch>),
}

/// The three pipes of a bot: its ends (for the process to start) and ours.
struct Pipes {
    stdin_bot: std::os::fd::OwnedFd,
    stdout_bot: std::os::fd::OwnedFd,
    stderr_bot: std::os::fd::OwnedFd,
    stdin_ours: std::os::fd::OwnedFd,
    stdout_ours: std::os::fd::OwnedFd,
    stderr_ours: std::os::fd::OwnedFd,
}

impl Pipes {
    fn new() -> nix::Result<Pipes> {
        let pipe = || nix::unistd::pipe2(nix::fcntl::OFlag::O_CLOEXEC);
        let (stdin_bot, stdin_ours) = pipe()?;
        let (stdout_ours, stdout_bot) = pipe()?;
        let (stderr_ours, stderr_bot) = pipe()?;
        Ok(Pipes {
            stdin_bot,
            stdout_bot,
            stderr_bot,
            stdin_ours,
            stdout_ours,
            stderr_ours,
        })
    }
}

/// Our ends of a bot's pipes, registered with the runtime.
fn our_ends(
    stdin: std::os::fd::OwnedFd,
    stdout: std::os::fd::OwnedFd,
    stderr: std::os::fd::OwnedFd,
) -> std::io::Result<(BotStdin, BotOutput, BotOutput)> {
    use tokio::net::unix::pipe::{Receiver, Sender};
    Ok((
        Sender::from_owned_fd(stdin)?,
        Receiver::from_owned_fd(stdout)?,
        Receiver::from_owned_fd(stderr)?,
    ))
}

/// A running bot: its processes and everything that bounds and measures them.
/// Dropping it kills every process of the bot.
#[derive(Debug)]
pub struct BotProcess {
    started: Started,
    /// The runner's ends of the bot's stdin, stdout and stderr, until taken.
    stdio: Option<(BotStdin, BotOutput, BotOutput)>,
    /// The outer process's pid, also its process group id (in a warm sandbox: the
    /// match's init).
    pub pid: Option<u32>,
    cgroup: Option<MatchCgroup>,
    _uid: Option<UidLease>,
    sandboxed: bool,
    memory_limit: Option<u64>,
    process_limit: Option<u64>,
    /// The scratch area as seen from here, through bubblewrap's init inside the
    /// sandbox (which lives as long as the match); found once.
    scratch: std::sync::OnceLock<PathBuf>,
    /// The CPU clock of the bot's process without the sandbox (all its threads, to the
    /// nanosecond), found once: read every step, it costs one system call, with no text
    /// to format or parse.
    cpu_clock: std::sync::OnceLock<Option<nix::time::ClockId>>,
}

/// Starts the bot with piped stdin, stdout and stderr.
///
/// # Errors
/// [`LaunchError`] when the command is malformed or cannot be started.
pub fn spawn(launch: &Launch<'_>) -> Result<BotProcess, LaunchError> {
    let words = shlex::split(launch.command)
        .filter(|w| !w.is_empty())
        .ok_or_else(|| LaunchError::BadCommand(launch.command.to_string()))?;
    let (mut cmd, cgroup, uid) = match launch.sandbox {
        Sandbox::None => (direct(launch, &words), None, None),
        Sandbox::Full(full) => {
            let uid = full
                .as_root
                .then(UidLease::take)
                .transpose()
                .map_err(LaunchError::Sandbox)?;
            let runtimes = full
                .runtimes_for(&words[0], launch.dir, launch.runtime)
                .map_err(LaunchError::Sandbox)?;
            let spawn_error = |source| LaunchError::Spawn {
                program: words[0].clone(),
                dir: launch.dir.display().to_string(),
                source,
            };
            if warm::plan(full, launch.dir, &runtimes).map_err(spawn_error)? {
                return spawn_warm(launch, &words, full, runtimes, uid);
            }
            let cgroup = match &full.cgroups {
                Ok(root) => Some(
                    root.kept(CgroupLimits {
                        memory_bytes: launch.memory_limit_bytes,
                        pids: launch.process_limit.map(|n| n + BWRAP_PROCESSES),
                        // Started from the match's thread: its core is the match's.
                        core: super::affinity::pinned_core(),
                    })
                    .map_err(|e| LaunchError::Sandbox(e.to_string()))?,
                ),
                Err(_) => None,
            };
            let args = super::sandbox::bwrap_args(
                full,
                Some(launch.dir),
                launch.scratch_bytes,
                super::sandbox::Work::Match,
                &runtimes,
            )
            .map_err(|e| LaunchError::Spawn {
                program: words[0].clone(),
                dir: launch.dir.display().to_string(),
                source: e,
            })?;
            let jail = jail_args(launch, &words, uid.as_ref(), cgroup.is_some());
            let cmd = full.command(args, &jail, cgroup.as_ref());
            (Command::from(cmd), cgroup, uid)
        }
    };
    let pipes = Pipes::new().map_err(|e| LaunchError::Sandbox(format!("pipe: {e}")))?;
    cmd.stdin(Stdio::from(pipes.stdin_bot))
        .stdout(Stdio::from(pipes.stdout_bot))
        .stderr(Stdio::from(pipes.stderr_bot))
        .process_group(0)
        .kill_on_drop(true);
    let per_process = match launch.sandbox {
        Sandbox::None => Some((MAX_BOT_FILE_BYTES, launch.memory_limit_bytes.map(|b| b * 2))),
        Sandbox::Full(_) => None,
    };
    // Nothing runs between fork and exec, so the bot (or `sandbox-enter`, which joins
    // its cgroup) starts with posix_spawn (vfork), which does not copy the server's
    // page tables: a fork would make every other match thread of the server take
    // copy-on-write faults. Its limits are set right after.
    let child = cmd.spawn().map_err(|source| LaunchError::Spawn {
        program: words[0].clone(),
        dir: launch.dir.display().to_string(),
        source,
    })?;
    // The command holds the bot's ends of its pipes: closed here, so that the bot's
    // exit ends its stdout.
    drop(cmd);
    if let Some(pid) = child.id() {
        set_limits(pid, per_process);
    }
    let stdio = our_ends(pipes.stdin_ours, pipes.stdout_ours, pipes.stderr_ours)
        .map_err(|e| LaunchError::Sandbox(format!("the bot's pipes: {e}")))?;
    Ok(BotProcess {
        pid: child.id(),
        started: Started::Child(child),
        stdio: Some(stdio),
        cgroup,
        _uid: uid,
        sandboxed: matches!(launch.sandbox, Sandbox::Full(_)),
        memory_limit: launch.memory_limit_bytes,
        process_limit: launch.process_limit,
        scratch: std::sync::OnceLock::new(),
        cpu_clock: std::sync::OnceLock::new(),
    })
}

/// The jail step's arguments for the bot's command `words`: its uid (as root), its
/// limits and its owner's variables. With a cgroup, the cgroup's process count is the
/// limit that is seen being hit; the uid's own count stays a little above it as a
/// second wall.
fn jail_args(
    launch: &Launch<'_>,
    words: &[String],
    uid: Option<&UidLease>,
    cgroup: bool,
) -> jail::JailArgs {
    jail::JailArgs {
        uid: uid.map(UidLease::uid),
        nproc: launch
            .process_limit
            .map(|n| if cgroup { n + 2 * BWRAP_PROCESSES } else { n }),
        fsize: Some(launch.scratch_bytes),
        address_space: None,
        env: launch
            .env
            .iter()
            .map(|(k, v)| (k.into(), v.into()))
            .collect(),
        command: std::iter::once(in_sandbox(&words[0], launch.dir))
            .chain(words[1..].iter().map(Into::into))
            .collect(),
    }
}

/// Starts the bot in a warm sandbox ([`warm`]) of `full`.
fn spawn_warm(
    launch: &Launch<'_>,
    words: &[String],
    full: &std::sync::Arc<super::sandbox::FullSandbox>,
    runtimes: Vec<super::sandbox::Runtime>,
    uid: Option<UidLease>,
) -> Result<BotProcess, LaunchError> {
    let sandbox_error = LaunchError::Sandbox;
    let pipes = Pipes::new().map_err(|e| sandbox_error(format!("pipe: {e}")))?;
    let request = supervisor::Request {
        cgroup_files: 0,
        scratch_bytes: launch.scratch_bytes,
        jail: jail_args(launch, words, uid.as_ref(), true)
            .to_args()
            .into_iter()
            .map(|a| a.to_string_lossy().into_owned())
            .collect(),
    };
    let key = warm::WarmKey {
        // Started from the match's thread: its core is the match's.
        core: super::affinity::pinned_core(),
        runtimes,
    };
    let warm = warm::start_match(
        full,
        key,
        launch.memory_limit_bytes,
        launch.process_limit.map(|n| n + warm::MATCH_PROCESSES),
        &request,
        launch.dir,
        warm::MatchStdio {
            stdin: pipes.stdin_bot,
            stdout: pipes.stdout_bot,
            stderr: pipes.stderr_bot,
        },
    )
    .map_err(sandbox_error)?;
    let stdio = our_ends(pipes.stdin_ours, pipes.stdout_ours, pipes.stderr_ours)
        .map_err(|e| sandbox_error(format!("the bot's pipes: {e}")))?;
    Ok(BotProcess {
        pid: Some(warm.init_pid),
        started: Started::Warm(Box::new(warm)),
        stdio: Some(stdio),
        cgroup: None,
        _uid: uid,
        sandboxed: true,
        memory_limit: launch.memory_limit_bytes,
        process_limit: launch.process_limit,
        scratch: std::sync::OnceLock::new(),
        cpu_clock: std::sync::OnceLock::new(),
    })
}

/// The bot's program, when given as an absolute path into its folder, as it is seen in
/// the sandbox (the folder is the working directory there); any other program unchanged.
/// Arguments are never rewritten.
fn in_sandbox(word: &str, dir: &Path) -> std::ffi::OsString {
    let dir = dir.canonicalize().unwrap_or_else(|_| dir.to_path_buf());
    let path = Path::new(word);
    match path
        .is_absolute()
        .then(|| path.strip_prefix(&dir).ok())
        .flatten()
    {
        Some(rel) => Path::new(super::sandbox::WORKDIR)
            .join(rel)
            .into_os_string(),
        None => word.into(),
    }
}

/// Sets the limits of the bot's process `pid` just after its start: no core dumps, and
/// without the sandbox a largest file and address space (`per_process`).
fn set_limits(pid: u32, per_process: Option<(u64, Option<u64>)>) {
    let set = |resource, value: u64| {
        let limit = libc::rlimit {
            rlim_cur: value,
            rlim_max: value,
        };
        // SAFETY: prlimit(2) reads `limit` and writes nothing (no old limit asked for);
        // a bot that is gone already is an error that is ignored.
        unsafe { libc::prlimit(pid as libc::pid_t, resource, &limit, std::ptr::null_mut()) };
    };
    set(libc::RLIMIT_CORE, 0);
    if let Some((fsize, address_space)) = per_process {
        set(libc::RLIMIT_FSIZE, fsize);
        if let Some(bytes) = address_space {
            set(libc::RLIMIT_AS, bytes);
        }
    }
}

/// `program` found on the `PATH` the bot gets, when it is a bare name: the process can
/// then start with posix_spawn (which the standard library uses only for a path when
/// the child's `PATH` differs from ours). Past a version manager's shim (pyenv's, or a
/// rustup proxy), the program the shim would run, as the sandbox runs it
/// ([`super::sandbox::real_program`]), and `true`. Unchanged when it is not found.
fn on_path(program: &str) -> (std::ffi::OsString, bool) {
    if program.contains('/') {
        return (program.into(), false);
    }
    let found = std::env::var_os("PATH").and_then(|path| {
        std::env::split_paths(&path)
            .filter(|dir| dir.is_absolute())
            .map(|dir| dir.join(program))
            .find(|candidate| {
                use std::os::unix::fs::PermissionsExt;
                std::fs::metadata(candidate)
                    .is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
            })
    });
    match found {
        None => (program.into(), false),
        Some(found) => {
            let real = super::sandbox::real_program(&found, program);
            let past_shim = real != found;
            (real.into_os_string(), past_shim)
        }
    }
}

fn direct(launch: &Launch<'_>, words: &[String]) -> Command {
    let (program, past_shim) = on_path(&words[0]);
    let mut cmd = Command::new(&program);
    // A shim's program is started by its own path, as the shim starts it (an
    // interpreter finds its installation from it).
    if past_shim {
        cmd.arg0(&program);
    } else {
        cmd.arg0(&words[0]);
    }
    cmd.args(&words[1..]).current_dir(launch.dir).env_clear();
    for key in PASSED_ENV {
        if let Some(value) = std::env::var_os(key) {
            cmd.env(key, value);
        }
    }
    cmd.env("PYTHONUNBUFFERED", "1");
    cmd.env("PYTHONDONTWRITEBYTECODE", "1");
    cmd.envs(launch.env.iter().map(|(k, v)| (k, v)));
    cmd
}

impl BotProcess {
    /// The runner's ends of the bot's stdin, stdout and stderr (once).
    pub fn take_stdio(&mut self) -> Option<(BotStdin, BotOutput, BotOutput)> {
        self.stdio.take()
    }

    /// Waits for the outer process to end: its exit status.
    ///
    /// # Errors
    /// Waiting failed.
    pub async fn wait(&mut self) -> std::io::Result<std::process::ExitStatus> {
        match &mut self.started {
            Started::Child(child) => child.wait().await,
            Started::Warm(warm) => warm.wait().await,
        }
    }

    /// The match's cgroup, if it has one.
    fn cgroup(&self) -> Option<&MatchCgroup> {
        match &self.started {
            Started::Warm(warm) => warm.cgroup(),
            Started::Child(_) => self.cgroup.as_ref(),
        }
    }

    /// CPU time of all the bot's processes so far, in microseconds: the cgroup's
    /// counter, else the sum over its live process tree (with waited-for children).
    pub fn cpu_us(&self) -> Option<u64> {
        match (self.cgroup(), self.pid) {
            (Some(cg), _) => cg.cpu_us(),
            // The sandbox without a cgroup: the whole tree (PID namespace: nothing escapes).
            (None, Some(pid)) if self.sandboxed => Some(proctree::usage(pid).cpu_us),
            // No sandbox: the bot's own process (its helpers count in the match's total).
            (None, Some(pid)) => {
                let clock = self.cpu_clock.get_or_init(|| {
                    let pid = nix::unistd::Pid::from_raw(i32::try_from(pid).ok()?);
                    nix::time::clock_getcpuclockid(pid).ok()
                });
                let now = clock.and_then(|c| c.now().ok())?;
                Some(now.tv_sec() as u64 * 1_000_000 + now.tv_nsec() as u64 / 1_000)
            }
            (None, None) => None,
        }
    }

    /// The whole-match limit the bot has gone over, if any. Without a cgroup, the
    /// watchdog reads the process tree and kills it when it holds too much memory.
    pub fn limit_hit(&self) -> Option<LimitKind> {
        if !self.sandboxed {
            return None;
        }
        if let Some(cg) = self.cgroup() {
            return match cg.limit_hit() {
                Some(CgroupHit::Memory) => Some(LimitKind::Memory),
                Some(CgroupHit::Pids) => Some(LimitKind::Processes),
                None => self.scratch_full().then_some(LimitKind::Scratch),
            };
        }
        let pid = self.pid?;
        let usage = proctree::usage(pid);
        if self.memory_limit.is_some_and(|m| usage.rss_bytes > m) {
            self.kill_all();
            return Some(LimitKind::Memory);
        }
        // The tree holds bubblewrap's two processes and the bot's.
        if self
            .process_limit
            .is_some_and(|n| usage.threads >= n + BWRAP_PROCESSES)
        {
            return Some(LimitKind::Processes);
        }
        self.scratch_full().then_some(LimitKind::Scratch)
    }

    /// Whether the bot's scratch tmpfs has no free block left, seen through the root of
    /// a process inside the sandbox.
    fn scratch_full(&self) -> bool {
        if self.scratch.get().is_none() {
            // In a warm sandbox the match's init holds the scratch area; in a one-shot
            // one, bubblewrap's process inside.
            let inner = match &self.started {
                Started::Warm(warm) => Some(warm.init_pid),
                Started::Child(_) => self
                    .pid
                    .map(proctree::members)
                    .unwrap_or_default()
                    .get(1)
                    .copied(),
            };
            let Some(inner) = inner else {
                return false;
            };
            let _ = self.scratch.set(PathBuf::from(format!(
                "/proc/{inner}/root{}",
                super::sandbox::jail::SCRATCH
            )));
        }
        self.scratch
            .get()
            .is_some_and(|p| nix::sys::statvfs::statvfs(p).is_ok_and(|s| s.blocks_available() == 0))
    }

    /// Kills every process of the bot: its cgroup, its process tree and its group.
    pub fn kill_all(&self) {
        // A warm match's init is not the runner's child: the match goes with its init,
        // killed through its pidfd (never by a pid that may have been reused), and takes
        // its PID namespace with it; its cgroup is emptied when it is removed.
        if let Started::Warm(warm) = &self.started {
            warm.kill();
            return;
        }
        if let Some(cg) = &self.cgroup {
            cg.kill_all();
        }
        if let Some(pid) = self.pid {
            proctree::kill_tree(pid);
            kill_group(pid);
        }
    }
}

impl Drop for BotProcess {
    fn drop(&mut self) {
        self.kill_all();
    }
}

/// Kills every process of the bot's process group (the group id is the bot's pid).
/// A group that is already gone is not an error.
pub fn kill_group(pgid: u32) {
    let _ = killpg(Pid::from_raw(pgid as i32), Signal::SIGKILL);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn a_malformed_command_is_refused() {
        let dir = std::env::temp_dir();
        let none = Sandbox::None;
        let launch = |command| Launch {
            command,
            dir: &dir,
            memory_limit_bytes: None,
            process_limit: None,
            scratch_bytes: 1 << 20,
            sandbox: &none,
            env: &[],
            runtime: None,
        };
        for bad in ["", "   ", "python3 'unterminated"] {
            assert!(
                matches!(spawn(&launch(bad)), Err(LaunchError::BadCommand(_))),
                "{bad:?}"
            );
        }
        assert!(matches!(
            spawn(&launch("/nonexistent/bot")),
            Err(LaunchError::Spawn { .. })
        ));
    }

    #[tokio::test]
    async fn a_bare_program_is_found_on_the_path_and_its_limits_are_set() {
        let (sh, past_shim) = on_path("sh");
        assert!(Path::new(&sh).is_absolute() && !past_shim, "{sh:?}");
        assert_eq!(on_path("./bot"), ("./bot".into(), false));
        assert_eq!(
            on_path("no-such-program-here"),
            ("no-such-program-here".into(), false)
        );

        // The limits reach the started process (read back from /proc).
        let dir = std::env::temp_dir();
        let none = Sandbox::None;
        let mut bot = spawn(&Launch {
            command: "sleep 5",
            dir: &dir,
            memory_limit_bytes: Some(64 << 20),
            process_limit: None,
            scratch_bytes: 1 << 20,
            sandbox: &none,
            env: &[],
            runtime: None,
        })
        .unwrap();
        let pid = bot.pid.unwrap();
        let limits = std::fs::read_to_string(format!("/proc/{pid}/limits")).unwrap();
        bot.kill_all();
        let _ = bot.wait().await;
        let line = |name: &str| {
            limits
                .lines()
                .find(|l| l.starts_with(name))
                .unwrap_or_default()
                .split_whitespace()
                .map(str::to_owned)
                .collect::<Vec<_>>()
        };
        assert!(
            line("Max core file size").contains(&"0".to_owned()),
            "{limits}"
        );
        let address = (128u64 << 20).to_string();
        assert!(line("Max address space").contains(&address), "{limits}");
    }
}
