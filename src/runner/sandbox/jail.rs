//! The last step inside the sandbox, run as `mazearena sandbox-exec` by bubblewrap once
//! the namespaces and the filesystem view are in place: resource limits, the drop to the
//! match's own unprivileged uid (when the server runs as root), `no_new_privs`, Landlock,
//! the seccomp filter, then `exec` of the bot's own program. Nothing of the bot runs
//! before all of these hold.

use std::ffi::OsString;
use std::os::unix::process::CommandExt;

use landlock::{
    ABI, Access, AccessFs, AccessNet, BitFlags, CompatLevel, Compatible, Ruleset, RulesetAttr,
    RulesetCreatedAttr, RulesetStatus, Scope, path_beneath_rules,
};
use nix::sys::resource::{Resource, setrlimit};

/// Where the bot's writable scratch area is mounted inside the sandbox.
pub const SCRATCH: &str = "/sandbox";

/// The exit code of `sandbox-exec` when it cannot set the sandbox up (the bot never ran).
pub const SETUP_FAILED: i32 = 125;

/// What `sandbox-exec` is asked to do (its command line).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct JailArgs {
    /// Switch to this uid and gid (only when started as root).
    pub uid: Option<u32>,
    /// The most processes and threads of this uid (RLIMIT_NPROC).
    pub nproc: Option<u64>,
    /// The largest file the bot may write (RLIMIT_FSIZE), in bytes.
    pub fsize: Option<u64>,
    /// Per-process address-space limit (RLIMIT_AS), in bytes.
    pub address_space: Option<u64>,
    /// Variables declared by the bot's owner: applied only to the bot's own program, at
    /// its `exec`, after every wall is up (never to bubblewrap or to this step).
    pub env: Vec<(OsString, OsString)>,
    /// The bot's program and arguments.
    pub command: Vec<OsString>,
}

impl JailArgs {
    /// The arguments after `sandbox-exec`.
    pub fn to_args(&self) -> Vec<OsString> {
        let mut out: Vec<OsString> = Vec::new();
        let mut opt = |name: &str, v: Option<u64>| {
            if let Some(v) = v {
                out.push(name.into());
                out.push(v.to_string().into());
            }
        };
        opt("--uid", self.uid.map(u64::from));
        opt("--nproc", self.nproc);
        opt("--fsize", self.fsize);
        opt("--as", self.address_space);
        for (k, v) in &self.env {
            let mut kv = k.clone();
            kv.push("=");
            kv.push(v);
            out.push("--env".into());
            out.push(kv);
        }
        out.push("--".into());
        out.extend(self.command.iter().cloned());
        out
    }

    /// Parses the arguments after `sandbox-exec`.
    ///
    /// # Errors
    /// A message naming the bad argument.
    pub fn parse(args: &[OsString]) -> Result<JailArgs, String> {
        let mut out = JailArgs::default();
        out.command = super::parse_step_args(args, |name, value| {
            if name == "--env" {
                // Kept as bytes, unread: it means something only to the bot's program.
                use std::os::unix::ffi::OsStrExt;
                let kv = value.ok_or("--env needs KEY=VALUE")?.as_bytes();
                let eq = kv
                    .iter()
                    .position(|&b| b == b'=')
                    .filter(|&i| i > 0)
                    .ok_or("--env needs KEY=VALUE")?;
                out.env.push((
                    std::ffi::OsStr::from_bytes(&kv[..eq]).to_os_string(),
                    std::ffi::OsStr::from_bytes(&kv[eq + 1..]).to_os_string(),
                ));
                return Ok(());
            }
            let value = value
                .and_then(|v| v.to_str())
                .and_then(|v| v.parse::<u64>().ok())
                .ok_or_else(|| format!("{name} needs a number"))?;
            match name {
                "--uid" => out.uid = Some(u32::try_from(value).map_err(|e| e.to_string())?),
                "--nproc" => out.nproc = Some(value),
                "--fsize" => out.fsize = Some(value),
                "--as" => out.address_space = Some(value),
                _ => return Err(format!("unknown argument {name}")),
            }
            Ok(())
        })?;
        Ok(out)
    }
}

/// Sets everything up and runs the bot's program in place of this process. Returns only
/// when that failed, with the reason.
pub fn exec(args: &JailArgs) -> String {
    match setup(args) {
        Ok(()) => {
            // The owner's variables join the runner's here, at the bot's own exec: a
            // loader variable (LD_PRELOAD, ...) acts on the bot alone, inside its walls.
            let err = std::process::Command::new(&args.command[0])
                .args(&args.command[1..])
                .envs(args.env.iter().map(|(k, v)| (k, v)))
                .exec();
            format!("could not start {:?}: {err}", args.command[0])
        }
        Err(e) => e,
    }
}

fn setup(args: &JailArgs) -> Result<(), String> {
    walls(args, &super::seccomp::filters().map_err(|e| e.to_string())?)
}

/// Puts up every wall of the jail on this process, in order: resource limits, the uid
/// (as root), `no_new_privs`, Landlock, then the seccomp `filters` (compiled by
/// [`super::seccomp::filters`]). Everything it starts from then on inherits them.
///
/// # Errors
/// The wall that could not be put up, and why.
pub fn walls(args: &JailArgs, filters: &[seccompiler::BpfProgram]) -> Result<(), String> {
    let limit = |r: Resource, v: u64| setrlimit(r, v, v).map_err(|e| format!("{r:?}: {e}"));
    limit(Resource::RLIMIT_CORE, 0)?;
    if let Some(v) = args.fsize {
        limit(Resource::RLIMIT_FSIZE, v)?;
    }
    if let Some(v) = args.address_space {
        limit(Resource::RLIMIT_AS, v)?;
    }
    if let Some(uid) = args.uid {
        drop_to(uid)?;
    }
    // After the uid change: RLIMIT_NPROC counts the processes of the real uid.
    if let Some(v) = args.nproc {
        limit(Resource::RLIMIT_NPROC, v)?;
    }
    nix::sys::prctl::set_no_new_privs().map_err(|e| format!("no_new_privs: {e}"))?;
    landlock().map_err(|e| format!("landlock: {e}"))?;
    for filter in filters {
        seccompiler::apply_filter(filter).map_err(|e| format!("seccomp: {e}"))?;
    }
    Ok(())
}

/// Switches to `uid` (and the group of the same number) with no supplementary groups:
/// as root, this also drops every capability.
fn drop_to(uid: u32) -> Result<(), String> {
    use nix::unistd::{Gid, Uid, setgroups, setresgid, setresuid};
    let (u, g) = (Uid::from_raw(uid), Gid::from_raw(uid));
    setgroups(&[]).map_err(|e| format!("setgroups: {e}"))?;
    setresgid(g, g, g).map_err(|e| format!("setresgid: {e}"))?;
    setresuid(u, u, u).map_err(|e| format!("setresuid: {e}"))?;
    Ok(())
}

/// The Landlock ruleset: read and execute anywhere in the (already reduced) filesystem
/// view, write only in the scratch area and to devices, no TCP bind or connect, no
/// signals to or abstract sockets of processes outside the sandbox. Best effort: a
/// kernel without Landlock (or an older ABI) enforces what it has.
///
/// # Errors
/// A ruleset the kernel refuses for another reason than missing support.
pub fn landlock() -> Result<RulesetStatus, landlock::RulesetError> {
    let abi = ABI::V6;
    let device: BitFlags<AccessFs> =
        AccessFs::from_read(abi) | AccessFs::WriteFile | AccessFs::IoctlDev;
    let status = Ruleset::default()
        .set_compatibility(CompatLevel::BestEffort)
        .handle_access(AccessFs::from_all(abi))?
        .handle_access(AccessNet::from_all(abi))?
        .scope(Scope::from_all(abi))?
        .create()?
        .add_rules(path_beneath_rules(["/"], AccessFs::from_read(abi)))?
        .add_rules(path_beneath_rules(["/dev"], device))?
        .add_rules(path_beneath_rules([SCRATCH], AccessFs::from_all(abi)))?
        .restrict_self()?;
    Ok(status.ruleset)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jail_arguments_round_trip() {
        let args = JailArgs {
            uid: Some(2_100_000_001),
            nproc: Some(64),
            fsize: Some(1 << 26),
            address_space: None,
            env: vec![
                ("LD_PRELOAD".into(), "/sandbox/work/x.so".into()),
                ("A".into(), "b=c d".into()),
                ("E".into(), "".into()),
            ],
            command: vec!["python3".into(), "bot.py".into(), "--x".into()],
        };
        assert_eq!(JailArgs::parse(&args.to_args()).unwrap(), args);
    }

    #[test]
    fn bad_jail_arguments_are_refused() {
        let parse = |a: &[&str]| JailArgs::parse(&a.iter().map(OsString::from).collect::<Vec<_>>());
        assert!(parse(&["--uid", "x", "--", "a"]).is_err());
        assert!(parse(&["--bogus", "1", "--", "a"]).is_err());
        assert!(parse(&["--nproc", "3"]).is_err());
        assert!(parse(&["--env", "NOEQUALS", "--", "a"]).is_err());
        assert!(parse(&["--env", "=x", "--", "a"]).is_err());
    }
}
