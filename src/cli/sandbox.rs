//! The `--sandbox` flag shared by `run`, `tournament` and `serve`, and `mazearena doctor`.

use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, ValueEnum};

use crate::runner::Sandbox;
use crate::runner::sandbox::{Check, Setup, enter, jail};

/// How bots are isolated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SandboxChoice {
    /// The full sandbox (namespaces, read-only view, seccomp, Landlock, whole-match
    /// limits). Refuses to start when it cannot be had.
    Full,
    /// No isolation: bots run as your own user. Only for bots you trust.
    None,
}

/// The `--sandbox` flag.
#[derive(Debug, Clone, Args)]
pub struct SandboxArgs {
    /// Isolation of every bot: `full` (default) or `none` (only for bots you trust: a
    /// bot then runs as your user and can read, write and signal what you can).
    #[arg(long, env = "MAZEARENA_SANDBOX", value_enum, default_value = "full")]
    pub sandbox: SandboxChoice,
    /// A language runtime's install folder that bots may use, mounted read-only in
    /// every bot's view, its `bin` first on their PATH (repeatable; a venv brings its
    /// base interpreter): a pyenv version, a venv, a Node prefix, a rustup toolchain, a
    /// JDK, a Go root. Never a home folder or a folder holding dotfiles. Without it:
    /// `MAZEARENA_RUNTIMES`, folders separated by `:` (empty parts, or an empty
    /// variable, name none).
    #[arg(long = "runtime", value_name = "DIR")]
    runtime: Vec<PathBuf>,
    /// Network namespaces each warm sandbox (servers, workers, tournaments) makes
    /// before the matches that take them, so that a match's start does not wait for
    /// one; 0 makes each match's as it starts (to measure what making them ahead saves).
    #[arg(long, env = "MAZEARENA_SANDBOX_AHEAD", default_value_t = 1,
          value_parser = clap::value_parser!(u8).range(0..=8))]
    sandbox_ahead: u8,
}

/// The variable that lists runtimes when `--runtime` is not given.
const RUNTIMES_VAR: &str = "MAZEARENA_RUNTIMES";

/// The folders `list` names (a `:`-separated list; empty parts name none).
fn split_runtimes(list: &std::ffi::OsStr) -> Vec<PathBuf> {
    std::env::split_paths(list)
        .filter(|p| !p.as_os_str().is_empty())
        .collect()
}

impl SandboxArgs {
    /// The runtimes listed for bots: `--runtime`, else `MAZEARENA_RUNTIMES`.
    pub fn runtimes(&self) -> Vec<PathBuf> {
        if !self.runtime.is_empty() {
            return self.runtime.clone();
        }
        std::env::var_os(RUNTIMES_VAR).map_or_else(Vec::new, |v| split_runtimes(&v))
    }

    /// What the full sandbox is set up with: `hide` lists paths that must never be
    /// visible to a bot (data dir, database); `local` finds each bot's runtime from its
    /// program too (`run`, `tournament`: the owner is the operator).
    pub fn setup(&self, hide: &[PathBuf], local: bool) -> Setup {
        Setup {
            hide: hide.to_vec(),
            runtimes: self.runtimes(),
            detect: local,
            reuse: false,
            ahead: usize::from(self.sandbox_ahead),
        }
    }

    /// Sets up the chosen isolation (see [`SandboxArgs::setup`]).
    ///
    /// # Errors
    /// `full` was asked and cannot be had here: the reason, and how to see more.
    pub fn open(&self, hide: &[PathBuf], local: bool) -> anyhow::Result<Sandbox> {
        self.open_checked(hide, local, true)
    }

    /// [`SandboxArgs::open`] without the test command (see
    /// [`Sandbox::full_unverified`]): for one match, which is followed by
    /// [`verify`] when it fails.
    ///
    /// # Errors
    /// As [`SandboxArgs::open`], except for the test command's.
    pub fn open_unverified(&self, hide: &[PathBuf], local: bool) -> anyhow::Result<Sandbox> {
        self.open_checked(hide, local, false)
    }

    fn open_checked(&self, hide: &[PathBuf], local: bool, test: bool) -> anyhow::Result<Sandbox> {
        match self.sandbox {
            SandboxChoice::None => {
                eprintln!(
                    "warning: --sandbox none: bots run as your own user, unisolated (only for bots you trust)"
                );
                Ok(Sandbox::None)
            }
            SandboxChoice::Full => {
                let exe = std::env::current_exe().context("cannot find the mazearena binary")?;
                let mut setup = self.setup(hide, local);
                // A runner that tests the sandbox first plays many matches (a server, a
                // worker, a tournament): it keeps warm sandboxes for them.
                setup.reuse = test;
                if test {
                    Sandbox::full(&exe, &setup)
                } else {
                    Sandbox::full_unverified(&exe, &setup)
                }
                .map_err(unavailable)
            }
        }
    }
}

/// Runs the sandbox's test command: `Err` with the reason when the sandbox does not
/// work here, worded as [`SandboxArgs::open`]'s.
///
/// # Errors
/// The sandbox does not work here.
pub fn verify(sandbox: &Sandbox) -> anyhow::Result<()> {
    sandbox.verify().map_err(unavailable)
}

/// The sandbox's reason, with what to do about it.
fn unavailable(e: crate::runner::sandbox::Unavailable) -> anyhow::Error {
    anyhow::anyhow!(
        "{e}\n`mazearena doctor` shows what works here; `--sandbox none` runs bots unisolated (only for bots you trust)"
    )
}

/// Arguments of `mazearena doctor`.
#[derive(Debug, Args)]
pub struct DoctorArgs {
    /// Print the checks as JSON.
    #[arg(long)]
    json: bool,
    /// The runtimes to check, as `serve --runtime` takes them.
    #[command(flatten)]
    sandbox: SandboxArgs,
}

/// Prints every isolation mechanism and whether it works here. Fails (exit status 1)
/// when the full sandbox cannot run.
///
/// # Errors
/// The full sandbox is not available.
pub fn doctor(args: DoctorArgs) -> anyhow::Result<()> {
    let exe = std::env::current_exe().context("cannot find the mazearena binary")?;
    let (checks, result) = Sandbox::doctor(&exe, &args.sandbox.setup(&[], false));
    if args.json {
        let v = serde_json::json!({
            "sandbox": result.as_ref().map_or("none", Sandbox::level),
            "checks": checks,
        });
        println!("{v}");
    } else {
        for Check { name, ok, detail } in &checks {
            println!("{:<13} {:<4} {detail}", name, if *ok { "ok" } else { "no" });
        }
        println!(
            "sandbox level: {}",
            result.as_ref().map_or("none", Sandbox::level)
        );
    }
    result.map(|_| ()).map_err(|e| {
        super::ExitWith {
            code: 1,
            message: e.to_string(),
        }
        .into()
    })
}

/// `mazearena sandbox-exec ARGS`: the jail step inside the sandbox (not for people).
/// Returns only on failure, with exit status [`jail::SETUP_FAILED`].
pub fn sandbox_exec(args: &[std::ffi::OsString]) -> std::process::ExitCode {
    setup_failed(match jail::JailArgs::parse(args) {
        Ok(a) => jail::exec(&a),
        Err(e) => e,
    })
}

/// `mazearena sandbox-enter ARGS`: joins the match's cgroup, then runs bubblewrap (not
/// for people). Returns only on failure, with exit status [`jail::SETUP_FAILED`].
pub fn sandbox_enter(args: &[std::ffi::OsString]) -> std::process::ExitCode {
    setup_failed(match enter::EnterArgs::parse(args) {
        Ok(a) => enter::exec(&a),
        Err(e) => e,
    })
}

/// `mazearena sandbox-serve [--ahead N]`: a warm sandbox's supervisor (not for
/// people). Ends when the runner closes its socket; on failure with
/// [`jail::SETUP_FAILED`].
pub fn sandbox_serve(args: &[std::ffi::OsString]) -> std::process::ExitCode {
    let ahead = match args {
        [] => 0,
        [flag, n] if flag == "--ahead" => match n.to_str().and_then(|n| n.parse().ok()) {
            Some(n) => n,
            None => return setup_failed(format!("a bad --ahead: {n:?}")),
        },
        _ => return setup_failed(format!("unexpected arguments: {args:?}")),
    };
    match crate::runner::sandbox::supervisor::serve(ahead) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => setup_failed(e),
    }
}

/// A sandbox step's end when it could not run the bot: the line the runner reads the
/// reason from, and [`jail::SETUP_FAILED`].
fn setup_failed(reason: String) -> std::process::ExitCode {
    eprintln!("mazearena sandbox: {reason}");
    std::process::ExitCode::from(jail::SETUP_FAILED as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_runtime_list_skips_empty_parts_and_an_empty_list_names_none() {
        let list = |s: &str| split_runtimes(std::ffi::OsStr::new(s));
        assert!(list("").is_empty());
        assert!(list(":").is_empty());
        assert_eq!(
            list("/opt/a::/opt/b:"),
            [PathBuf::from("/opt/a"), PathBuf::from("/opt/b")]
        );
    }
}
