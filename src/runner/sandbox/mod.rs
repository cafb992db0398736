//! The isolated world a bot runs in, one per match.
//!
//! [`Sandbox::Full`] runs every bot through **bubblewrap** (the sandbox Flatpak uses):
//! fresh mount, PID, network (a down loopback only), IPC and UTS namespaces, plus a user
//! namespace when the server is not root; a filesystem view that holds only what a
//! language runtime needs, read-only, the bot's own files read-only, and a size-limited
//! tmpfs scratch area as its working directory and `/tmp`. Inside, `mazearena
//! sandbox-exec` ([`jail`]) switches to the match's own unprivileged uid when the server
//! is root, sets `no_new_privs`, Landlock and a seccomp filter, then `exec`s the bot.
//! Limits hold for the whole match, every process together: a cgroup ([`cgroup`], v1 or
//! v2) where one can be made, else a watchdog over the process tree ([`proctree`]).
//!
//! A runner of many matches (a server, a worker, a tournament) keeps **warm sandboxes**
//! ([`warm`]): bubblewrap and the view made once per worker slot, and for each match new
//! PID, mount and IPC namespaces, `/proc` and scratch area made inside by a supervisor
//! ([`supervisor`]), with the same jail step. `mazearena run` and builds use a one-shot
//! sandbox.
//!
//! [`Sandbox::None`] runs the bot directly as the server's user: only for bots you trust.

pub mod ahead;
pub mod cgroup;
pub mod enter;
pub mod fresh;
pub mod jail;
pub mod mounts;
pub mod proctree;
pub mod seccomp;
pub mod supervisor;
mod uid;
mod view;
pub mod warm;

use std::path::{Path, PathBuf};
use std::sync::Arc;

pub use uid::UidLease;

/// The fields of `/proc/self/status` as a process in the sandbox sees them.
type Status = std::collections::BTreeMap<String, String>;

/// Where the `mazearena` binary is mounted inside the sandbox.
pub const HELPER_IN_SANDBOX: &str = "/run/mazearena/mazearena";

/// The bot's working directory inside the sandbox, where its files are mounted.
pub const WORKDIR: &str = "/sandbox/work";

/// The subcommand of the helper that runs [`jail::exec`].
pub const JAIL_SUBCOMMAND: &str = "sandbox-exec";

/// The subcommand of the helper that runs [`enter::exec`].
pub const ENTER_SUBCOMMAND: &str = "sandbox-enter";

/// The subcommand of the helper that runs [`supervisor::serve`] in a warm sandbox.
pub const SERVE_SUBCOMMAND: &str = "sandbox-serve";

/// Reads a sandbox step's arguments, `--name value ... -- command...`: hands each
/// option to `each` in order (its value `None` when the arguments end after its name),
/// then returns the command.
///
/// # Errors
/// What `each` refuses, or no command after `--`.
fn parse_step_args(
    args: &[std::ffi::OsString],
    mut each: impl FnMut(&str, Option<&std::ffi::OsString>) -> Result<(), String>,
) -> Result<Vec<std::ffi::OsString>, String> {
    let mut i = 0;
    while i < args.len() {
        let name = args[i].to_string_lossy();
        if name == "--" {
            let command = args[i + 1..].to_vec();
            return if command.is_empty() {
                Err("no command after --".into())
            } else {
                Ok(command)
            };
        }
        each(&name, args.get(i + 1))?;
        i += 2;
    }
    Err("no command after --".into())
}

/// How bots are isolated.
#[derive(Debug, Clone, Default)]
pub enum Sandbox {
    /// No isolation: the bot runs as the server's own user, in its own process group,
    /// with per-process limits. Only for bots you trust.
    #[default]
    None,
    /// The full sandbox.
    Full(Arc<FullSandbox>),
}

/// What the full sandbox found on this machine.
#[derive(Debug)]
pub struct FullSandbox {
    /// The bubblewrap program.
    pub bwrap: PathBuf,
    /// The `mazearena` binary, mounted inside for `sandbox-exec`.
    pub helper: PathBuf,
    /// True when the server runs as root: each match gets its own unprivileged uid.
    pub as_root: bool,
    /// The cgroup hierarchy for whole-match limits, or why there is none (then the
    /// watchdog enforces them).
    pub cgroups: Result<cgroup::CgroupRoot, String>,
    /// The operator's runtimes (`--runtime`), mounted read-only in every bot's view.
    pub runtimes: Vec<Runtime>,
    /// Whether the runtime of each bot's own program is found and mounted too (local
    /// runs, where the owner is the operator; never on a server).
    pub detect: bool,
    /// Paths no runtime may hold (data folder, database).
    pub hide: Vec<PathBuf>,
    /// Whether matches may reuse warm sandboxes ([`warm`]): a runner of many matches.
    pub reuse: bool,
    /// Network namespaces each warm sandbox makes ahead of its matches
    /// ([`fresh::FreshPool`]).
    pub ahead: usize,
    /// The idle warm sandboxes.
    pub warm: warm::WarmPool,
    /// The runtimes found so far by program and bot folder (with `detect`).
    detected: DetectedRuntimes,
}

/// Runtimes found from bots' programs, by program and bot folder.
type DetectedRuntimes =
    std::sync::Mutex<std::collections::HashMap<(String, PathBuf), Vec<Runtime>>>;

/// What the full sandbox is set up with.
#[derive(Debug, Clone)]
pub struct Setup {
    /// Paths that must never be visible to a bot (data folder, database).
    pub hide: Vec<PathBuf>,
    /// The operator's runtime list: install prefixes mounted read-only for every bot.
    pub runtimes: Vec<PathBuf>,
    /// Find each bot's runtime from its program (`run`, `tournament`).
    pub detect: bool,
    /// Keep warm sandboxes for the next matches ([`warm`]): servers, workers and
    /// tournaments, which play many.
    pub reuse: bool,
    /// Network namespaces each warm sandbox makes ahead of its matches
    /// ([`fresh::FreshPool`]; 0: each match's is made as it starts).
    pub ahead: usize,
}

impl Default for Setup {
    /// Nothing hidden, no runtimes, no detection, no warm sandboxes, one network
    /// namespace made ahead.
    fn default() -> Setup {
        Setup {
            hide: Vec::new(),
            runtimes: Vec::new(),
            detect: false,
            reuse: false,
            ahead: 1,
        }
    }
}

impl FullSandbox {
    /// The command that runs `jail` inside a sandbox made with bubblewrap arguments
    /// `bwrap_args` (from `view::bwrap_args`), with an empty environment of its own.
    /// With a `cgroup`, it starts as `mazearena sandbox-enter` ([`enter`]), which joins
    /// the cgroup before it runs bubblewrap: nothing needs to run in the server between
    /// `fork` and `exec`, so the command can start with `posix_spawn`.
    pub fn command(
        &self,
        bwrap_args: Vec<std::ffi::OsString>,
        jail: &jail::JailArgs,
        cgroup: Option<&cgroup::MatchCgroup>,
    ) -> std::process::Command {
        let step = std::iter::once(JAIL_SUBCOMMAND.into())
            .chain(jail.to_args())
            .collect();
        self.command_step(bwrap_args, step, cgroup)
    }

    /// [`FullSandbox::command`] for any step of the helper: `step` is its subcommand
    /// and arguments.
    pub fn command_step(
        &self,
        bwrap_args: Vec<std::ffi::OsString>,
        step: Vec<std::ffi::OsString>,
        cgroup: Option<&cgroup::MatchCgroup>,
    ) -> std::process::Command {
        let tail = bwrap_args.into_iter().chain(step);
        let mut cmd = match cgroup {
            None => {
                let mut cmd = std::process::Command::new(&self.bwrap);
                cmd.args(tail);
                cmd
            }
            // A runner of one match (`mazearena run`) is a small process of few threads:
            // its child joins the cgroup itself between fork and bubblewrap's exec, which
            // saves the exec of this binary as `sandbox-enter` (BENCHMARKS.md, "The
            // sandbox's cost per match"). A server or a tournament keeps posix_spawn.
            Some(cgroup) if !self.reuse => {
                let join = enter::join_in_child(&cgroup.join_files());
                let mut cmd = std::process::Command::new(&self.bwrap);
                cmd.args(tail);
                use std::os::unix::process::CommandExt;
                // SAFETY: the closure only opens, writes and closes files by paths made
                // before the fork (async-signal-safe system calls, no allocation).
                unsafe { cmd.pre_exec(join) };
                cmd
            }
            Some(cgroup) => {
                let enter = enter::EnterArgs {
                    join: cgroup.join_files(),
                    command: std::iter::once(self.bwrap.clone().into_os_string())
                        .chain(tail)
                        .collect(),
                };
                let mut cmd = std::process::Command::new(&self.helper);
                cmd.arg(ENTER_SUBCOMMAND).args(enter.to_args());
                cmd
            }
        };
        cmd.env_clear();
        cmd
    }
}

/// Why the full sandbox cannot run here.
#[derive(Debug, Clone, thiserror::Error)]
#[error("the sandbox is not available: {0}")]
pub struct Unavailable(pub String);

/// One line of `mazearena doctor`.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct Check {
    /// The mechanism.
    pub name: String,
    /// Whether it works here.
    pub ok: bool,
    /// What was found.
    pub detail: String,
}

impl Sandbox {
    /// `full` or `none`, as recorded with every match and shown by `/healthz`.
    pub fn level(&self) -> &'static str {
        match self {
            Sandbox::None => "none",
            Sandbox::Full(_) => "full",
        }
    }

    /// What keeps a match's memory, process and CPU limits, shown by `/healthz` and the
    /// server's first line: `cgroup` (a cgroup per match: memory, processes, one core),
    /// `watchdog` (no cgroup could be made here, e.g. in a container: memory and
    /// processes watched over the bot's process tree, no CPU limit) or `rlimit` (no
    /// sandbox: the address space only).
    pub fn limits(&self) -> &'static str {
        match self {
            Sandbox::Full(f) if f.cgroups.is_ok() => "cgroup",
            Sandbox::Full(_) => "watchdog",
            Sandbox::None => "rlimit",
        }
    }

    /// Sets up the full sandbox with `helper` as the `mazearena` binary (usually
    /// `std::env::current_exe()`), and proves that it works by running a command in it.
    /// `setup` says which runtimes are mounted and what no runtime may hold.
    ///
    /// # Errors
    /// [`Unavailable`] with the reason when bubblewrap is missing or cannot make the
    /// namespaces, a listed runtime cannot be used, or the jail step fails.
    pub fn full(helper: &Path, setup: &Setup) -> Result<Sandbox, Unavailable> {
        Sandbox::full_tested(helper, setup).map(|(sandbox, _)| sandbox)
    }

    /// Runs the test command in the sandbox and checks what it saw (`NoNewPrivs`,
    /// `Seccomp`); `Ok` for no sandbox.
    ///
    /// # Errors
    /// [`Unavailable`] with the reason.
    pub fn verify(&self) -> Result<(), Unavailable> {
        match self {
            Sandbox::None => Ok(()),
            Sandbox::Full(_) => self.checked_status().map(drop),
        }
    }

    /// [`Sandbox::full`], with the fields of `/proc/self/status` its test command saw.
    fn full_tested(helper: &Path, setup: &Setup) -> Result<(Sandbox, Status), Unavailable> {
        let sandbox = Sandbox::full_unverified(helper, setup)?;
        let status = sandbox.checked_status()?;
        Ok((sandbox, status))
    }

    /// The test command's `/proc/self/status`, once its walls are checked.
    fn checked_status(&self) -> Result<Status, Unavailable> {
        let status = self.self_test()?;
        for (key, want) in [("NoNewPrivs", "1"), ("Seccomp", "2")] {
            if status.get(key).map(String::as_str) != Some(want) {
                return Err(Unavailable(format!(
                    "a test command in the sandbox has {key} = {:?}, not {want}",
                    status.get(key)
                )));
            }
        }
        Ok(status)
    }

    /// [`Sandbox::full`] without the test command: bubblewrap, the cgroups and the
    /// runtimes found, for one match that proves the sandbox itself (`mazearena run`).
    /// Every wall is still made, and the jail still refuses to run the bot when one
    /// cannot be; a match that fails is followed by [`Sandbox::verify`], so a sandbox
    /// that does not work is reported as such.
    ///
    /// # Errors
    /// As [`Sandbox::full`], except for the test command's.
    pub fn full_unverified(helper: &Path, setup: &Setup) -> Result<Sandbox, Unavailable> {
        let bwrap = find_program("bwrap").ok_or_else(|| {
            Unavailable(
                "bubblewrap (`bwrap`) is not installed (Debian: apt-get install bubblewrap)".into(),
            )
        })?;
        let helper = helper
            .canonicalize()
            .map_err(|e| Unavailable(format!("the mazearena binary {}: {e}", helper.display())))?;
        let full = FullSandbox {
            bwrap,
            helper,
            as_root: nix::unistd::geteuid().is_root(),
            cgroups: cgroup::CgroupRoot::detect(),
            runtimes: view::listed_runtimes(&setup.runtimes, &setup.hide).map_err(Unavailable)?,
            detect: setup.detect,
            hide: setup.hide.clone(),
            reuse: setup.reuse,
            ahead: setup.ahead,
            warm: warm::WarmPool::default(),
            detected: DetectedRuntimes::default(),
        };
        Ok(Sandbox::Full(Arc::new(full)))
    }

    /// Runs `cat /proc/self/status` in the sandbox and returns its fields.
    fn self_test(&self) -> Result<Status, Unavailable> {
        let Sandbox::Full(full) = self else {
            return Err(Unavailable("no sandbox".into()));
        };
        let lease = full
            .as_root
            .then(UidLease::take)
            .transpose()
            .map_err(Unavailable)?;
        let args = view::bwrap_args(full, None, 1 << 20, Work::Match, &full.runtimes)
            .map_err(|e| Unavailable(e.to_string()))?;
        let jail = jail::JailArgs {
            uid: lease.as_ref().map(UidLease::uid),
            nproc: Some(16),
            command: vec!["cat".into(), "/proc/self/status".into()],
            ..jail::JailArgs::default()
        };
        let out = full
            .command(args, &jail, None)
            .stdin(std::process::Stdio::null())
            .output()
            .map_err(|e| Unavailable(format!("cannot run {}: {e}", full.bwrap.display())))?;
        if !out.status.success() {
            return Err(Unavailable(format!(
                "a test command in the sandbox failed ({}): {}",
                out.status,
                String::from_utf8_lossy(&out.stderr).trim()
            )));
        }
        Ok(String::from_utf8_lossy(&out.stdout)
            .lines()
            .filter_map(|l| l.split_once(':'))
            .map(|(k, v)| (k.trim().to_string(), v.trim().to_string()))
            .collect())
    }

    /// Every mechanism and whether it works here, for `mazearena doctor`, and every
    /// mount of a bot's view with the reason it is there.
    pub fn doctor(helper: &Path, setup: &Setup) -> (Vec<Check>, Result<Sandbox, Unavailable>) {
        let check = |name: &str, ok: bool, detail: String| Check {
            name: name.into(),
            ok,
            detail,
        };
        let mut checks = Vec::new();
        let bwrap = find_program("bwrap");
        checks.push(check(
            "bubblewrap",
            bwrap.is_some(),
            bwrap.as_ref().map_or("not found on PATH".into(), |p| {
                let v = std::process::Command::new(p).arg("--version").output();
                format!(
                    "{} ({})",
                    p.display(),
                    v.map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
                        .unwrap_or_default()
                )
            }),
        ));
        let root = nix::unistd::geteuid().is_root();
        checks.push(check(
            "identity",
            true,
            if root {
                "running as root: each match runs as its own unprivileged uid".into()
            } else {
                "not root: each match gets a user namespace".into()
            },
        ));
        let (result, status) = match Sandbox::full_tested(helper, setup) {
            Ok((sandbox, status)) => (Ok(sandbox), status),
            Err(e) => (Err(e), Status::new()),
        };
        let field = |k: &str| status.get(k).cloned().unwrap_or_default();
        checks.push(check(
            "namespaces",
            result.is_ok(),
            match &result {
                Ok(_) => {
                    "mount, pid, net, ipc, uts (and user when not root): a test command ran".into()
                }
                Err(e) => e.0.clone(),
            },
        ));
        checks.push(check(
            "no_new_privs",
            field("NoNewPrivs") == "1",
            format!("NoNewPrivs = {:?} in the sandbox", field("NoNewPrivs")),
        ));
        checks.push(check(
            "seccomp",
            field("Seccomp") == "2",
            format!(
                "Seccomp = {:?} (2: filtering), {} filters",
                field("Seccomp"),
                field("Seccomp_filters")
            ),
        ));
        let abi = landlock_abi();
        checks.push(check(
            "landlock",
            abi > 0,
            if abi > 0 {
                format!("ABI {abi} (second wall: filesystem writes, TCP, signals)")
            } else {
                "not available in this kernel (optional: the namespaces still hold)".into()
            },
        ));
        let cg = match &result {
            Ok(Sandbox::Full(f)) => f.cgroups.clone(),
            _ => cgroup::CgroupRoot::detect(),
        };
        checks.push(check(
            "cgroups",
            cg.is_ok(),
            match &cg {
                Ok(r) => format!(
                    "{}: memory, processes and one core per match ({}), CPU time of every process",
                    r.version(),
                    r.cpu_limit()
                ),
                Err(e) => format!(
                    "{e} (limits fall back to a watchdog over the process tree; no CPU limit)"
                ),
            },
        ));
        let warm = match &result {
            Err(_) => Err("no sandbox"),
            Ok(_) => warm::unavailable(root, cg.is_ok()).map_or(Ok(()), Err),
        };
        checks.push(check(
            "warm",
            warm.is_ok(),
            match warm {
                Ok(()) => "servers, workers and tournaments keep a sandbox per worker slot and \
                    give each match new PID, mount and IPC namespaces in it"
                    .into(),
                Err(why) => format!("not used here: {why}; every match gets a sandbox of its own"),
            },
        ));
        let runtimes = match &result {
            Ok(Sandbox::Full(f)) => f.runtimes.clone(),
            _ => Vec::new(),
        };
        checks.push(check(
            "runtimes",
            true,
            if runtimes.is_empty() {
                "none listed: bots see the system's runtimes only (add one with --runtime DIR)"
                    .into()
            } else {
                runtimes
                    .iter()
                    .map(|r| r.prefix.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            },
        ));
        for (at, why) in view::describe(&runtimes) {
            checks.push(check("mount", true, format!("{at}: {why}")));
        }
        (checks, result)
    }
}

/// The highest Landlock ABI the kernel offers, 0 when none.
pub fn landlock_abi() -> i64 {
    // SAFETY: landlock_create_ruleset(NULL, 0, LANDLOCK_CREATE_RULESET_VERSION) only
    // returns a number.
    let v = unsafe {
        libc::syscall(
            libc::SYS_landlock_create_ruleset,
            std::ptr::null::<u8>(),
            0usize,
            1u32,
        )
    };
    v.max(0)
}

/// Finds `name` on PATH.
pub fn find_program(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join(name))
        .find(|p| p.is_file())
}

pub use crate::runner::runtimes::Runtime;
pub use crate::runner::runtimes::real_program;
pub(crate) use view::bwrap_args;
pub use view::{Work, listed_runtimes, runtime_of_program};

impl FullSandbox {
    /// The runtimes mounted for a bot or build whose program is `program`: the
    /// operator's, and on local runs the one the program comes from; the one named
    /// `preferred` first (its `bin` first on the `PATH`).
    ///
    /// # Errors
    /// The program's own runtime cannot be used, and why; no runtime is named
    /// `preferred`.
    pub fn runtimes_for(
        &self,
        program: &str,
        bot_dir: &Path,
        preferred: Option<&str>,
    ) -> Result<Vec<Runtime>, String> {
        let mut all = self.runtimes.clone();
        if let Some(name) = preferred {
            let at = all
                .iter()
                .position(|r| !r.base_of_venv && super::runtimes::name_of(r) == name)
                .ok_or_else(|| {
                    format!(
                        "the bot asks for runtime {name:?}, which this server does not offer ({})",
                        super::runtimes::offered(&self.runtimes)
                    )
                })?;
            let first = all.remove(at);
            all.insert(0, first);
        }
        if self.detect {
            // Found once per program and folder: a tournament plays one bot many times.
            let key = (program.to_string(), bot_dir.to_path_buf());
            let mut found = self.detected.lock().unwrap_or_else(|p| p.into_inner());
            let own = match found.get(&key) {
                Some(known) => known.clone(),
                None => {
                    let own = runtime_of_program(program, bot_dir, &self.hide)?;
                    found.insert(key, own.clone());
                    own
                }
            };
            for r in own {
                if !all.iter().any(|o| o.prefix == r.prefix) {
                    all.push(r);
                }
            }
        }
        Ok(all)
    }
}
