//! The first step of a sandboxed bot, run as `mazearena sandbox-enter` outside the
//! sandbox: it moves itself into the match's cgroups, then `exec`s bubblewrap, so every
//! process of the sandbox, bubblewrap's own included, starts inside them.
//!
//! Joining from a process of its own, rather than in the server between `fork` and
//! `exec`, lets the server start it with `posix_spawn` (vfork): a fork of the server
//! would copy its page tables and make its other match threads take copy-on-write
//! faults. (cgroup v1 has no `CLONE_INTO_CGROUP`.)

use std::ffi::OsString;
use std::io::Write;
use std::os::unix::process::CommandExt;
use std::path::PathBuf;

/// What `sandbox-enter` is asked to do (its command line).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct EnterArgs {
    /// The files to join by, in order (see [`super::cgroup::MatchCgroup::join_files`]).
    pub join: Vec<PathBuf>,
    /// The program to run then (bubblewrap) and its arguments.
    pub command: Vec<OsString>,
}

impl EnterArgs {
    /// The arguments after `sandbox-enter`.
    pub fn to_args(&self) -> Vec<OsString> {
        let mut out = Vec::with_capacity(2 * self.join.len() + 1 + self.command.len());
        for path in &self.join {
            out.push("--join".into());
            out.push(path.clone().into_os_string());
        }
        out.push("--".into());
        out.extend(self.command.iter().cloned());
        out
    }

    /// Parses the arguments after `sandbox-enter`.
    ///
    /// # Errors
    /// A message naming the bad argument.
    pub fn parse(args: &[OsString]) -> Result<EnterArgs, String> {
        let mut join = Vec::new();
        let command = super::parse_step_args(args, |name, value| {
            if name != "--join" {
                return Err(format!("unknown argument {name}"));
            }
            join.push(PathBuf::from(value.ok_or("--join needs a path")?));
            Ok(())
        })?;
        Ok(EnterArgs { join, command })
    }
}

/// Joins the cgroups and runs the command in place of this process. Returns only when
/// that failed, with the reason.
///
/// A v1 `tasks` file moves only the writing thread: this step refuses one unless the
/// process has that one thread (as `sandbox-enter` has, being run before anything of the
/// binary starts a thread), so nothing of it stays outside.
pub fn exec(args: &EnterArgs) -> String {
    if args.join.iter().any(|p| p.ends_with("tasks")) {
        match std::fs::read_dir("/proc/self/task").map(Iterator::count) {
            Ok(1) => {}
            Ok(n) => return format!("cannot join the match's cgroup by thread: {n} threads"),
            Err(e) => return format!("cannot count this process's threads: {e}"),
        }
    }
    for path in &args.join {
        let joined = std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .and_then(|mut f| f.write_all(b"0"));
        if let Err(e) = joined {
            return format!("cannot join the match's cgroup {}: {e}", path.display());
        }
    }
    let err = std::process::Command::new(&args.command[0])
        .args(&args.command[1..])
        .exec();
    format!("could not start {:?}: {err}", args.command[0])
}

/// The cgroup join of [`exec`] for a forked child, run between `fork` and `exec` (a
/// `pre_exec` hook): writes `0` to each file of `join`. The paths are made into C
/// strings here, before the fork; the hook itself only opens, writes and closes. The
/// forked child has one thread, so joining by `tasks` moves all of it.
pub fn join_in_child(
    join: &[PathBuf],
) -> impl FnMut() -> std::io::Result<()> + Send + Sync + 'static {
    use std::os::unix::ffi::OsStrExt;
    let paths: Vec<std::ffi::CString> = join
        .iter()
        .filter_map(|p| std::ffi::CString::new(p.as_os_str().as_bytes()).ok())
        .collect();
    let complete = paths.len() == join.len();
    move || {
        if !complete {
            return Err(std::io::Error::other("a cgroup path holds a NUL byte"));
        }
        for path in &paths {
            // SAFETY: open(2), write(2) and close(2) with a live NUL-terminated path and
            // buffer; nothing else runs in the forked child.
            let fd = unsafe { libc::open(path.as_ptr(), libc::O_WRONLY | libc::O_CLOEXEC) };
            if fd < 0 {
                return Err(std::io::Error::last_os_error());
            }
            let written = unsafe { libc::write(fd, b"0".as_ptr().cast(), 1) };
            let err = std::io::Error::last_os_error();
            unsafe { libc::close(fd) };
            if written != 1 {
                return Err(err);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arguments_round_trip() {
        let args = EnterArgs {
            join: vec!["/sys/fs/cgroup/memory/m/tasks".into(), "/x y".into()],
            command: vec!["/usr/bin/bwrap".into(), "--".into(), "--join".into()],
        };
        assert_eq!(EnterArgs::parse(&args.to_args()), Ok(args));
    }

    #[test]
    fn bad_arguments_are_named() {
        let parse = |words: &[&str]| {
            EnterArgs::parse(&words.iter().map(OsString::from).collect::<Vec<_>>())
        };
        assert_eq!(parse(&["--join"]), Err("--join needs a path".into()));
        assert_eq!(
            parse(&["--cgroup", "x"]),
            Err("unknown argument --cgroup".into())
        );
        assert_eq!(parse(&["--join", "p"]), Err("no command after --".into()));
        assert_eq!(parse(&["--"]), Err("no command after --".into()));
    }

    #[test]
    fn joining_by_thread_is_refused_to_a_process_of_several_threads() {
        // The test harness runs this on a thread of its own: more than one.
        let dir = tempfile::tempdir().unwrap();
        let marker = dir.path().join("ran");
        let tasks = dir.path().join("tasks");
        std::fs::write(&tasks, "").unwrap();
        let args = EnterArgs {
            join: vec![tasks.clone()],
            command: vec![
                "sh".into(),
                "-c".into(),
                format!("touch {}", marker.display()).into(),
            ],
        };
        let reason = exec(&args);
        assert!(reason.contains("threads"), "{reason}");
        assert_eq!(
            std::fs::read_to_string(&tasks).unwrap(),
            "",
            "nothing joined"
        );
        assert!(!marker.exists());
    }

    #[test]
    fn a_forked_child_joins_by_writing_0_and_a_missing_cgroup_stops_it() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a/tasks"), dir.path().join("b/tasks"));
        for f in [&a, &b] {
            std::fs::create_dir_all(f.parent().unwrap()).unwrap();
            std::fs::write(f, "").unwrap();
        }
        join_in_child(&[a.clone(), b.clone()])().unwrap();
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "0");
        assert_eq!(std::fs::read_to_string(&b).unwrap(), "0");
        let missing = dir.path().join("gone/tasks");
        let err = join_in_child(&[missing])().unwrap_err();
        assert_eq!(err.kind(), std::io::ErrorKind::NotFound);
    }

    #[test]
    fn a_cgroup_that_cannot_be_joined_stops_it_before_the_command() {
        let dir = tempfile::tempdir().unwrap();
        let marker = dir.path().join("ran");
        let args = EnterArgs {
            join: vec![dir.path().join("missing/cgroup.procs")],
            command: vec![
                "sh".into(),
                "-c".into(),
                format!("touch {}", marker.display()).into(),
            ],
        };
        let reason = exec(&args);
        assert!(
            reason.starts_with("cannot join the match's cgroup"),
            "{reason}"
        );
        assert!(!marker.exists());
    }
}
