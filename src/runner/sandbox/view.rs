//! The bubblewrap command line: which namespaces, and the filesystem view of a bot.

use std::ffi::OsString;
use std::path::{Path, PathBuf};

use super::{FullSandbox, HELPER_IN_SANDBOX, jail::SCRATCH};
use crate::runner::runtimes::{Runtime, real_program};

/// Where a match's bot folder is mounted, read-only; its working directory links to
/// each entry.
pub const BOT_FILES: &str = "/run/mazearena/bot";

/// Top-level system folders: mounted read-only, or re-created as the same symlinks
/// (merged-/usr systems).
const SYSTEM_DIRS: &[&str] = &["/bin", "/sbin", "/lib", "/lib32", "/lib64", "/libx32"];

/// What of `/etc` a language runtime needs: the dynamic linker's cache, Debian's
/// alternatives links, time zone and name-service switch. No passwd, no hosts, no keys.
const ETC_FILES: &[&str] = &[
    "/etc/ld.so.cache",
    "/etc/ld.so.conf",
    "/etc/ld.so.conf.d",
    "/etc/alternatives",
    "/etc/localtime",
    "/etc/nsswitch.conf",
    "/etc/ssl/openssl.cnf",
];

/// The folders of /etc whose name starts with one of these are mounted too: Debian's
/// JDKs keep their configuration there (`/etc/java-17-openjdk`: without its
/// `security/java.security`, `javac` and `SecureRandom` fail).
const ETC_PREFIXES: &[&str] = &["java-"];

/// [`ETC_FILES`] and the folders of [`ETC_PREFIXES`] that exist, in a fixed order.
fn etc_entries() -> Vec<String> {
    let mut out: Vec<String> = ETC_FILES.iter().map(|f| f.to_string()).collect();
    let mut extra: Vec<String> = std::fs::read_dir("/etc")
        .into_iter()
        .flatten()
        .filter_map(Result::ok)
        .filter(|e| {
            let name = e.file_name();
            let name = name.to_string_lossy();
            ETC_PREFIXES.iter().any(|p| name.starts_with(p))
                && e.file_type().is_ok_and(|t| t.is_dir())
        })
        .map(|e| e.path().display().to_string())
        .collect();
    extra.sort();
    out.extend(extra);
    out
}

/// Environment variables of the runner's passed on to bots (all others are cleared).
const PASSED_ENV: &[&str] = &["LANG", "LC_ALL", "TZ"];

/// The system part of a bot's `PATH`, after its runtimes' `bin` folders.
const SYSTEM_PATH: &str = "/usr/local/bin:/usr/bin:/bin";

/// Files inside runtime roots that hold credentials: hidden behind an empty file.
const SECRET_FILES: &[&str] = &[
    "credentials",
    "credentials.toml",
    ".npmrc",
    ".pypirc",
    ".netrc",
];

/// The environment of a bot in the sandbox, all of the runner's making: a `PATH` of its
/// runtimes' `bin` folders and the system's, its scratch area as home and temporary
/// directory, and the passed variables. The owner's declared variables are not here:
/// the jail step adds them at the bot's own `exec`.
pub fn bot_env(runtimes: &[Runtime]) -> Vec<(String, String)> {
    let mut path: Vec<String> = runtimes
        .iter()
        .filter(|r| !r.base_of_venv)
        .map(|r| r.prefix.join("bin"))
        .filter(|b| b.is_dir())
        .map(|b| b.to_string_lossy().into_owned())
        .collect();
    path.dedup();
    path.push(SYSTEM_PATH.into());
    let mut env: Vec<(String, String)> = vec![("PATH".into(), path.join(":"))];
    env.extend(
        PASSED_ENV
            .iter()
            .filter_map(|k| std::env::var(k).ok().map(|v| (k.to_string(), v))),
    );
    let tmp = format!("{SCRATCH}/tmp");
    env.push(("HOME".into(), tmp.clone()));
    env.push(("TMPDIR".into(), tmp));
    env.push(("PYTHONUNBUFFERED".into(), "1".into()));
    env.push(("PYTHONDONTWRITEBYTECODE".into(), "1".into()));
    env
}

fn is_system(path: &Path) -> bool {
    path.starts_with("/usr") || SYSTEM_DIRS.iter().any(|d| path.starts_with(d))
}

/// Why `prefix` cannot be a runtime: `/`, a system or special folder, a home folder,
/// a folder holding dotfiles, or a folder that holds or lies inside a path of `hide`.
fn unfit(prefix: &Path, hide: &[PathBuf]) -> Option<String> {
    let shown = prefix.display();
    if prefix == Path::new("/") || !prefix.is_absolute() {
        return Some(format!("{shown} is not an install folder"));
    }
    if is_system(prefix) {
        return Some(format!("{shown} is a system folder (already in the view)"));
    }
    for special in [
        "/proc", "/sys", "/dev", "/etc", "/run", "/boot", "/var", "/home",
    ] {
        if prefix == Path::new(special) {
            return Some(format!("{shown} is a system folder"));
        }
    }
    let homes = [
        std::env::var_os("HOME").map(PathBuf::from),
        Some("/root".into()),
    ];
    let is_home =
        homes.iter().flatten().any(|h| h == prefix) || prefix.parent() == Some(Path::new("/home"));
    if is_home {
        return Some(format!("{shown} is a home folder"));
    }
    match std::fs::read_dir(prefix) {
        Err(e) => return Some(format!("{shown}: {e}")),
        Ok(entries) => {
            if let Some(dot) = entries
                .flatten()
                .map(|e| e.file_name())
                .filter(|n| n != ".gitignore")
                .find(|n| n.as_encoded_bytes().starts_with(b"."))
            {
                return Some(format!(
                    "{shown} holds a dotfile ({}): a runtime is an install folder, not a \
                     folder of a user's files",
                    dot.to_string_lossy()
                ));
            }
        }
    }
    if let Some(h) = hide
        .iter()
        .find(|h| h.starts_with(prefix) || prefix.starts_with(h))
    {
        return Some(format!(
            "{shown} holds or lies in {}, which bots must never see",
            h.display()
        ));
    }
    None
}

/// The runtime of install prefix `dir` (with a venv's base interpreter), checked.
///
/// # Errors
/// Why `dir` cannot be a runtime.
pub fn runtime(dir: &Path, why: &str, hide: &[PathBuf]) -> Result<Vec<Runtime>, String> {
    let prefix = dir
        .canonicalize()
        .map_err(|e| format!("the runtime {}: {e}", dir.display()))?;
    if !prefix.is_dir() {
        return Err(format!("the runtime {} is not a folder", dir.display()));
    }
    let hide: Vec<PathBuf> = hide
        .iter()
        .map(|h| h.canonicalize().unwrap_or_else(|_| h.clone()))
        .collect();
    if let Some(reason) = unfit(&prefix, &hide) {
        return Err(format!(
            "cannot use {} as a runtime: {reason}",
            dir.display()
        ));
    }
    let mut out = vec![Runtime::offered(prefix.clone(), why)];
    // A venv runs its base interpreter: `home = /x/bin` in its pyvenv.cfg.
    if let Ok(cfg) = std::fs::read_to_string(prefix.join("pyvenv.cfg")) {
        let home = cfg.lines().find_map(|l| {
            let (k, v) = l.split_once('=')?;
            (k.trim() == "home").then(|| PathBuf::from(v.trim()))
        });
        if let Some(bin) = home.and_then(|h| h.canonicalize().ok()) {
            let base = if bin.ends_with("bin") {
                bin.parent().map_or(bin.clone(), Path::to_path_buf)
            } else {
                bin
            };
            if !is_system(&base) {
                if let Some(reason) = unfit(&base, &hide) {
                    return Err(format!(
                        "cannot use the base interpreter of the venv {}: {reason}",
                        dir.display()
                    ));
                }
                out.push(Runtime {
                    prefix: base,
                    why: format!("base interpreter of the venv {}", prefix.display()),
                    base_of_venv: true,
                });
            }
        }
    }
    Ok(out)
}

/// The operator's runtime list, checked (`--runtime DIR`, `MAZEARENA_RUNTIMES`).
///
/// # Errors
/// The first listed folder that cannot be a runtime, and why.
pub fn listed_runtimes(listed: &[PathBuf], hide: &[PathBuf]) -> Result<Vec<Runtime>, String> {
    let mut out: Vec<Runtime> = Vec::new();
    for dir in listed.iter().filter(|d| !d.as_os_str().is_empty()) {
        for r in runtime(dir, "listed by the operator (--runtime)", hide)? {
            if !out.iter().any(|o| o.prefix == r.prefix) {
                out.push(r);
            }
        }
    }
    Ok(out)
}

/// The runtime a bot's (or build's) `program` comes from, for local runs (`run`,
/// `tournament`): an absolute path to an interpreter outside the bot's folder and the
/// system (`/srv/venvs/sci/bin/python`), or a bare name found on the runner's `PATH`
/// outside the system (through a pyenv shim or a rustup proxy to the real program). The
/// runtime is the folder holding the program's `bin` folder; nothing when the program is
/// in the system, in the bot's folder, or not found. Never used by a server: there only
/// the operator's list counts.
///
/// # Errors
/// The program's folder cannot be a runtime, and why.
pub fn runtime_of_program(
    program: &str,
    bot_dir: &Path,
    hide: &[PathBuf],
) -> Result<Vec<Runtime>, String> {
    let path = Path::new(program);
    let found: Option<PathBuf> = if path.is_absolute() {
        let bot_dir = bot_dir.canonicalize().unwrap_or_else(|_| bot_dir.into());
        path.is_file()
            .then(|| path.to_path_buf())
            .filter(|p| !p.starts_with(&bot_dir))
    } else if program.contains('/') {
        None
    } else {
        std::env::var_os("PATH").and_then(|p| {
            std::env::split_paths(&p)
                .filter(|d| d.is_absolute())
                .map(|d| d.join(program))
                .find(|c| c.is_file())
        })
    };
    let Some(found) = found else {
        return Ok(Vec::new());
    };
    let found = real_program(&found, program);
    let Some(bin) = found.parent() else {
        return Ok(Vec::new());
    };
    if is_system(bin) {
        return Ok(Vec::new());
    }
    let prefix = if bin.ends_with("bin") {
        bin.parent().unwrap_or(bin)
    } else {
        bin
    };
    runtime(
        prefix,
        &format!("the install folder of the bot's program {program}"),
        hide,
    )
}

/// Where runtime `prefix` appears inside the view: at its own path, except under `/tmp`,
/// which is a link to the scratch area's `tmp` (the runtime is mounted there, so its own
/// path still leads to it).
fn mount_point(prefix: &Path) -> PathBuf {
    match prefix.strip_prefix("/tmp") {
        Ok(rel) => Path::new(SCRATCH).join("tmp").join(rel),
        Err(_) => prefix.to_path_buf(),
    }
}

/// Every mount of a bot's view and why it is there, for `mazearena doctor`.
pub fn describe(runtimes: &[Runtime]) -> Vec<(String, String)> {
    let mut out = vec![(
        "/usr".to_string(),
        "system programs and libraries, read-only".to_string(),
    )];
    for dir in SYSTEM_DIRS {
        let p = Path::new(dir);
        match std::fs::read_link(p) {
            Ok(target) => out.push((dir.to_string(), format!("link to {}", target.display()))),
            Err(_) if p.is_dir() => out.push((dir.to_string(), "system folder, read-only".into())),
            Err(_) => {}
        }
    }
    for f in etc_entries() {
        if Path::new(&f).exists() {
            out.push((
                f.to_string(),
                "what a runtime needs of /etc, read-only".into(),
            ));
        }
    }
    for r in runtimes {
        let at = mount_point(&r.prefix);
        let place = if at == r.prefix {
            String::new()
        } else {
            format!(" (mounted at {})", at.display())
        };
        out.push((
            r.prefix.display().to_string(),
            format!("runtime, read-only: {}{place}", r.why),
        ));
    }
    out.push((
        "/proc".into(),
        "the sandbox's own processes only (/proc/sys read-only)".into(),
    ));
    out.push((
        "/dev".into(),
        "null, zero, random, urandom, tty: a minimal /dev".into(),
    ));
    out.push((
        SCRATCH.into(),
        "scratch tmpfs of the match's size: tmp/ and work/".into(),
    ));
    out.push((BOT_FILES.into(), "the bot's own files, read-only".into()));
    out.push((
        format!("{SCRATCH}/work"),
        format!("the working directory: a link to each of the bot's files in {BOT_FILES}"),
    ));
    out.push(("/tmp".into(), format!("link to {SCRATCH}/tmp")));
    out.push((
        HELPER_IN_SANDBOX.into(),
        "the jail step (mazearena sandbox-exec), read-only".into(),
    ));
    out
}

/// Whether a match's view can show folder `dir` as one mount with a link per entry (see
/// [`bwrap_args`]): the match's uid (`own_uid`) may pass through it, and no entry is
/// itself a link.
///
/// # Errors
/// The folder cannot be read.
pub fn linkable(dir: &Path, own_uid: bool) -> std::io::Result<bool> {
    use std::os::unix::fs::PermissionsExt;
    if own_uid && std::fs::metadata(dir)?.permissions().mode() & 0o001 == 0 {
        return Ok(false);
    }
    for entry in std::fs::read_dir(dir)? {
        if entry?.file_type()?.is_symlink() {
            return Ok(false);
        }
    }
    Ok(true)
}

/// Whether a runtime's mount point lies in the scratch area (a runtime under `/tmp`),
/// which a warm sandbox makes anew for every match.
pub fn in_scratch(runtime: &Runtime) -> bool {
    mount_point(&runtime.prefix).starts_with(SCRATCH)
}

/// What a sandbox is for, which decides its working directory and its identity.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Work {
    /// A match: the bot's files read-only in a writable scratch working directory; as
    /// root, the jail drops to the match's own uid.
    Match,
    /// A build: its folder is the working directory, writable. With `own_uid` (as root,
    /// in an area of its own) the jail drops to the build's own uid; otherwise it runs as
    /// the runner's user in a user namespace (as root: a root without capabilities).
    Build {
        /// The build runs as a uid of its own.
        own_uid: bool,
    },
    /// A warm sandbox ([`super::warm`], root only): a match's view without a bot
    /// folder or scratch area of its own, kept for many matches; each match gets its
    /// own from the supervisor ([`super::supervisor`]). It does not die with the thread
    /// that started it: it ends when the runner closes its socket.
    Warm,
}

/// The bubblewrap arguments for one bot, up to and including the helper's path: the
/// caller appends `sandbox-exec` and the jail's arguments. For a match, `bot_dir`'s
/// top-level entries are mounted read-only in the working directory (`/sandbox/work`),
/// which is otherwise writable scratch of `scratch_bytes` shared with `/tmp`. For a
/// build ([`Work::Build`]), the folder itself is the working directory, writable, so
/// that what the build makes stays, and `/tmp` apart holds `scratch_bytes`.
/// `runtimes` are mounted read-only and their `bin` folders lead the bot's `PATH`. The
/// environment is the runner's alone ([`bot_env`]): nothing of the owner's acts on
/// bubblewrap or the jail step.
///
/// # Errors
/// The bot folder cannot be listed.
pub fn bwrap_args(
    full: &FullSandbox,
    bot_dir: Option<&Path>,
    scratch_bytes: u64,
    work_kind: Work,
    runtimes: &[Runtime],
) -> std::io::Result<Vec<OsString>> {
    let writable = matches!(work_kind, Work::Build { .. });
    let own_uid = full.as_root
        && matches!(
            work_kind,
            Work::Match | Work::Warm | Work::Build { own_uid: true }
        );
    let mut a: Vec<OsString> = Vec::new();
    let mut push = |items: &[&dyn AsRef<std::ffi::OsStr>]| {
        a.extend(items.iter().map(|i| i.as_ref().to_os_string()));
    };
    if own_uid {
        // Root makes the namespaces itself; the jail then drops to the match's uid.
        push(&[
            &"--unshare-ipc",
            &"--unshare-pid",
            &"--unshare-net",
            &"--unshare-uts",
            &"--unshare-cgroup-try",
        ]);
    } else {
        push(&[
            &"--unshare-user",
            &"--unshare-ipc",
            &"--unshare-pid",
            &"--unshare-net",
            &"--unshare-uts",
            &"--unshare-cgroup-try",
            &"--disable-userns",
        ]);
        if full.as_root {
            push(&[&"--cap-drop", &"ALL"]);
        }
    }
    if work_kind != Work::Warm {
        push(&[&"--die-with-parent"]);
    }
    push(&[&"--new-session", &"--hostname", &"mazearena"]);
    push(&[&"--ro-bind", &"/usr", &"/usr"]);
    for dir in SYSTEM_DIRS {
        let p = Path::new(dir);
        match std::fs::read_link(p) {
            Ok(target) => push(&[&"--symlink", &target, dir]),
            Err(_) if p.is_dir() => push(&[&"--ro-bind", dir, dir]),
            Err(_) => {}
        }
    }
    let etc = etc_entries();
    for f in &etc {
        push(&[&"--ro-bind-try", f, f]);
    }
    // /proc/sys read-only, whoever the bot runs as: a second wall beside the uid drop
    // (a root without capabilities in a user namespace could otherwise write some of it).
    push(&[
        &"--proc",
        &"/proc",
        &"--ro-bind",
        &"/proc/sys",
        &"/proc/sys",
    ]);
    push(&[
        &"--ro-bind-try",
        &"/proc/sysrq-trigger",
        &"/proc/sysrq-trigger",
    ]);
    push(&[&"--dev", &"/dev"]);
    let size = scratch_bytes.to_string();
    let work = format!("{SCRATCH}/work");
    let tmp = format!("{SCRATCH}/tmp");
    push(&[
        &"--size", &size, &"--tmpfs", &SCRATCH, &"--dir", &tmp, &"--dir", &work,
    ]);
    // After the scratch area: a runtime under /tmp is mounted in its tmp folder.
    for r in runtimes {
        let at = mount_point(&r.prefix);
        push(&[&"--ro-bind", &r.prefix, &at]);
        for secret in SECRET_FILES {
            let f = r.prefix.join(secret);
            if f.is_file() {
                push(&[&"--ro-bind", &"/dev/null", &at.join(secret)]);
            }
        }
    }
    if work_kind == Work::Warm {
        push(&[&"--dir", &BOT_FILES]);
    }
    if let (Some(dir), true) = (bot_dir, writable) {
        push(&[&"--bind", &dir, &work]);
    } else if let Some(dir) = bot_dir {
        // The folder is mounted once, read-only, and each of its entries is a link to it
        // in the (writable) working directory: one mount a match rather than one an
        // entry, each of which bubblewrap pays for by reading the whole mount table
        // (docs/PERFORMANCE.md). An entry that is itself a
        // link (a local run's) is mounted as before, so that it reaches what it names;
        // so is every entry of a folder the match's own uid may not pass through (a
        // local run's private folder).
        use std::os::unix::fs::PermissionsExt;
        let passable = !own_uid || std::fs::metadata(dir)?.permissions().mode() & 0o001 != 0;
        if passable {
            push(&[&"--ro-bind", &dir, &BOT_FILES]);
        }
        let mut entries: Vec<_> = std::fs::read_dir(dir)?
            .filter_map(Result::ok)
            .map(|e| (e.file_name(), e.file_type().is_ok_and(|t| t.is_symlink())))
            .collect();
        entries.sort();
        for (name, link) in entries {
            let dest = Path::new(&work).join(&name);
            if link || !passable {
                push(&[&"--ro-bind", &dir.join(&name), &dest]);
            } else {
                push(&[&"--symlink", &Path::new(BOT_FILES).join(&name), &dest]);
            }
        }
    }
    if own_uid {
        push(&[&"--chmod", &"1777", &tmp]);
        if !writable {
            push(&[&"--chmod", &"0777", &work]);
        }
    }
    push(&[&"--symlink", &tmp, &"/tmp"]);
    push(&[&"--ro-bind", &full.helper, &HELPER_IN_SANDBOX]);
    // bubblewrap makes the folders above a mount point for root only (0700): open them
    // to the match's uid, which must reach the runtimes (e.g. /root/.pyenv) and /etc.
    let mut parents: Vec<PathBuf> = Vec::new();
    let dests = etc
        .iter()
        .map(PathBuf::from)
        .chain(runtimes.iter().map(|r| mount_point(&r.prefix)))
        .chain([PathBuf::from(HELPER_IN_SANDBOX), PathBuf::from(BOT_FILES)]);
    for dest in dests {
        for a in dest.ancestors().skip(1) {
            if a != Path::new("/") && !parents.iter().any(|p| p == a) {
                parents.push(a.to_path_buf());
            }
        }
    }
    // The scratch area's folders have their own modes; a runtime's own are kept.
    // The scratch area's own folders have their modes already (tmp is 1777).
    let scratch_dirs = [SCRATCH.to_string(), tmp.clone(), work.clone()];
    parents.retain(|p| {
        !scratch_dirs.iter().any(|d| p == Path::new(d))
            && !runtimes.iter().any(|r| p.starts_with(&r.prefix))
    });
    for p in &parents {
        if p.exists() || p.starts_with("/run") || p.starts_with(SCRATCH) {
            push(&[&"--chmod", &"0755", p]);
        }
    }
    push(&[&"--clearenv"]);
    for (k, v) in bot_env(runtimes) {
        push(&[&"--setenv", &k, &v]);
    }
    push(&[&"--chdir", &work, &"--", &HELPER_IN_SANDBOX]);
    Ok(a)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pyenv_shim_is_passed_to_the_program_it_runs_and_asked_once() {
        use std::os::unix::fs::PermissionsExt;
        let tmp = tempfile::tempdir().unwrap();
        let root = tmp.path();
        let real = root.join("versions/3.11/bin/python3");
        let asked = root.join("asked");
        for dir in ["shims", "bin", "versions/3.11/bin"] {
            std::fs::create_dir_all(root.join(dir)).unwrap();
        }
        let script = |path: &Path, text: String| {
            std::fs::write(path, text).unwrap();
            std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755)).unwrap();
        };
        script(&root.join("shims/python3"), "#!/bin/sh\nexit 1\n".into());
        script(&real, "#!/bin/sh\n".into());
        // `pyenv which python3`, counting its calls.
        script(
            &root.join("bin/pyenv"),
            format!(
                "#!/bin/sh\necho x >> {}\necho {}\n",
                asked.display(),
                real.display()
            ),
        );
        let shim = root.join("shims/python3");
        assert_eq!(real_program(&shim, "python3"), real);
        assert_eq!(real_program(&shim, "python3"), real);
        assert_eq!(std::fs::read_to_string(&asked).unwrap().lines().count(), 1);
        // A program that is no shim is itself.
        assert_eq!(real_program(&real, "python3"), real);
    }

    #[test]
    fn home_folders_dotfile_folders_and_hidden_paths_are_never_runtimes() {
        let tmp = tempfile::tempdir().unwrap();
        let home_like = tmp.path().join("me");
        std::fs::create_dir_all(home_like.join(".ssh")).unwrap();
        let err = runtime(&home_like, "t", &[]).unwrap_err();
        assert!(err.contains("dotfile (.ssh)"), "{err}");
        let prefix = tmp.path().join("venv");
        std::fs::create_dir_all(prefix.join("bin")).unwrap();
        let db = prefix.join("data.db");
        let err = runtime(&prefix, "t", &[db]).unwrap_err();
        assert!(err.contains("bots must never see"), "{err}");
        assert!(runtime(Path::new("/root"), "t", &[]).is_err());
        assert!(runtime(Path::new("/usr"), "t", &[]).is_err());
        assert!(runtime(Path::new("/"), "t", &[]).is_err());
        let ok = runtime(&prefix, "t", &[]).unwrap();
        assert_eq!(ok[0].prefix, prefix.canonicalize().unwrap());
    }

    #[test]
    fn a_venv_brings_its_base_interpreter_and_leads_the_path() {
        let tmp = tempfile::tempdir().unwrap();
        let base = tmp.path().join("py/3.12");
        std::fs::create_dir_all(base.join("bin")).unwrap();
        let venv = tmp.path().join("venv");
        std::fs::create_dir_all(venv.join("bin")).unwrap();
        std::fs::write(
            venv.join("pyvenv.cfg"),
            format!(
                "home = {}\ninclude-system-site-packages = false\n",
                base.join("bin").display()
            ),
        )
        .unwrap();
        let rts = runtime(&venv, "t", &[]).unwrap();
        assert_eq!(rts.len(), 2);
        assert_eq!(rts[1].prefix, base.canonicalize().unwrap());
        let env = bot_env(&rts);
        let path = &env.iter().find(|(k, _)| k == "PATH").unwrap().1;
        let venv_bin = venv.canonicalize().unwrap().join("bin");
        assert!(path.starts_with(&*venv_bin.to_string_lossy()), "{path}");
        assert!(path.ends_with(SYSTEM_PATH), "{path}");
    }

    #[test]
    fn a_program_in_the_system_or_the_bot_folder_brings_no_runtime() {
        let tmp = tempfile::tempdir().unwrap();
        assert!(
            runtime_of_program("/usr/bin/python3", tmp.path(), &[])
                .unwrap()
                .is_empty()
        );
        std::fs::write(tmp.path().join("bot"), "").unwrap();
        let inside = tmp.path().join("bot").display().to_string();
        assert!(
            runtime_of_program(&inside, tmp.path(), &[])
                .unwrap()
                .is_empty()
        );
        assert!(
            runtime_of_program("./bot", tmp.path(), &[])
                .unwrap()
                .is_empty()
        );
    }

    /// The bubblewrap words of a match's view of `dir`, as root or not.
    fn match_words(dir: &Path, as_root: bool) -> Vec<String> {
        let full = FullSandbox {
            bwrap: "/usr/bin/bwrap".into(),
            helper: "/usr/bin/true".into(),
            as_root,
            cgroups: Err("none in this test".into()),
            runtimes: Vec::new(),
            detect: false,
            hide: Vec::new(),
            reuse: false,
            ahead: 1,
            warm: Default::default(),
            detected: Default::default(),
        };
        bwrap_args(&full, Some(dir), 1 << 20, Work::Match, &[])
            .unwrap()
            .into_iter()
            .map(|w| w.to_string_lossy().into_owned())
            .collect()
    }

    /// `words` holds `triple` in a row.
    fn has(words: &[String], triple: [&str; 3]) -> bool {
        words.windows(3).any(|w| w == triple)
    }

    #[test]
    fn a_bots_folder_is_one_mount_and_links_unless_its_uid_cannot_pass_through_it() {
        use std::os::unix::fs::PermissionsExt;
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("bot");
        std::fs::create_dir(&dir).unwrap();
        std::fs::write(dir.join("bot.py"), "").unwrap();
        std::fs::write(tmp.path().join("shared.py"), "").unwrap();
        std::os::unix::fs::symlink(tmp.path().join("shared.py"), dir.join("shared.py")).unwrap();
        let d = dir.display().to_string();
        let (bot, shared) = (format!("{d}/bot.py"), format!("{d}/shared.py"));
        std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o755)).unwrap();
        for as_root in [true, false] {
            let words = match_words(&dir, as_root);
            assert!(has(&words, ["--ro-bind", &d, BOT_FILES]), "{words:?}");
            let link = format!("{BOT_FILES}/bot.py");
            assert!(
                has(&words, ["--symlink", &link, "/sandbox/work/bot.py"]),
                "{words:?}"
            );
            // A link of the folder's is mounted: it reaches what it names.
            assert!(
                has(&words, ["--ro-bind", &shared, "/sandbox/work/shared.py"]),
                "{words:?}"
            );
            assert!(!words.contains(&bot), "{words:?}");
        }
        // A private folder: the match's own uid could not pass through it.
        std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o700)).unwrap();
        let words = match_words(&dir, true);
        assert!(!words.iter().any(|w| w == BOT_FILES), "{words:?}");
        assert!(
            has(&words, ["--ro-bind", &bot, "/sandbox/work/bot.py"]),
            "{words:?}"
        );
        // Without root the bot runs as the folder's owner, who may.
        let words = match_words(&dir, false);
        assert!(has(&words, ["--ro-bind", &d, BOT_FILES]), "{words:?}");
    }

    #[test]
    fn runtimes_under_tmp_are_mounted_in_the_scratch_tmp() {
        assert_eq!(
            mount_point(Path::new("/tmp/v/env")),
            Path::new("/sandbox/tmp/v/env")
        );
        assert_eq!(mount_point(Path::new("/opt/node")), Path::new("/opt/node"));
    }
}
