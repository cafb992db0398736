//! The bubblewrap command line: which namespaces, and the filesystem view of a bot.

use std::ffi::OsString;
use std::path::{Path, PathBuf};

use super::{FullSandbox, HELPER_IN_SANDBOX, jail::SCRATCH};

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

/// Environment variables passed on to bots (all others are cleared).
const PASSED_ENV: &[&str] = &[
    "PATH",
    "LANG",
    "LC_ALL",
    "TZ",
    "PYENV_ROOT",
    "PYENV_VERSION",
    "RUSTUP_HOME",
    "CARGO_HOME",
    "RUSTUP_TOOLCHAIN",
];

/// Files inside runtime roots that hold credentials: hidden behind an empty file.
const SECRET_FILES: &[&str] = &[
    "credentials",
    "credentials.toml",
    ".npmrc",
    ".pypirc",
    ".netrc",
];

/// The environment of a bot in the sandbox: the passed variables, and its scratch area as
/// home and temporary directory.
pub fn bot_env() -> Vec<(String, String)> {
    let mut env: Vec<(String, String)> = PASSED_ENV
        .iter()
        .filter_map(|k| std::env::var(k).ok().map(|v| (k.to_string(), v)))
        .collect();
    let tmp = format!("{SCRATCH}/tmp");
    env.push(("HOME".into(), tmp.clone()));
    env.push(("TMPDIR".into(), tmp));
    env.push(("PYTHONUNBUFFERED".into(), "1".into()));
    env.push(("PYTHONDONTWRITEBYTECODE".into(), "1".into()));
    // rustup's proxies look for their toolchains under $HOME, which is the scratch area
    // here: point them at the ones mounted from ours.
    if std::env::var_os("RUSTUP_HOME").is_none()
        && let Some(rustup) = default_rustup_home()
    {
        env.push(("RUSTUP_HOME".into(), rustup.to_string_lossy().into_owned()));
    }
    env
}

/// `~/.rustup` when rustup's proxies in `~/.cargo/bin` are on PATH (and it exists).
fn default_rustup_home() -> Option<PathBuf> {
    let home = PathBuf::from(std::env::var_os("HOME")?);
    let cargo_bin = home.join(".cargo").join("bin");
    let on_path = std::env::split_paths(&std::env::var_os("PATH")?).any(|d| d == cargo_bin);
    let rustup = home.join(".rustup");
    (on_path && rustup.is_dir()).then_some(rustup)
}

fn is_system(path: &Path) -> bool {
    path.starts_with("/usr") || SYSTEM_DIRS.iter().any(|d| path.starts_with(d))
}

/// Install roots of the language runtimes on PATH that live outside the system folders
/// (a pyenv root, a Node prefix, cargo and rustup homes), never one that contains or
/// lies inside a path of `hide`.
pub fn runtime_roots(hide: &[PathBuf]) -> Vec<PathBuf> {
    let mut roots: Vec<PathBuf> = Vec::new();
    let mut add = |p: PathBuf| {
        if p.is_dir() && !is_system(&p) && p != Path::new("/") && !roots.contains(&p) {
            roots.push(p);
        }
    };
    for key in ["PYENV_ROOT", "RUSTUP_HOME", "CARGO_HOME"] {
        if let Some(v) = std::env::var_os(key) {
            add(PathBuf::from(v));
        }
    }
    // rustup's proxies in ~/.cargo/bin need the toolchains in ~/.rustup.
    if let Some(rustup) = default_rustup_home() {
        add(rustup);
    }
    if let Some(path) = std::env::var_os("PATH") {
        for dir in std::env::split_paths(&path) {
            if !dir.is_absolute() || is_system(&dir) || !dir.is_dir() {
                continue;
            }
            let dir = dir.canonicalize().unwrap_or(dir);
            let name = dir.file_name().and_then(|n| n.to_str()).unwrap_or("");
            let root = if matches!(name, "bin" | "shims") {
                dir.parent().map_or(dir.clone(), Path::to_path_buf)
            } else {
                dir.clone()
            };
            add(root);
        }
    }
    let canon = |p: &PathBuf| p.canonicalize().unwrap_or_else(|_| p.clone());
    let hide: Vec<PathBuf> = hide.iter().map(canon).collect();
    roots.retain(|r| {
        let r = canon(r);
        !hide.iter().any(|h| h.starts_with(&r) || r.starts_with(h))
    });
    roots.sort();
    // A root inside another is mounted with it.
    let all = roots.clone();
    roots.retain(|r| !all.iter().any(|o| o != r && r.starts_with(o)));
    roots
}

/// The bubblewrap arguments for one bot, up to and including the helper's path: the
/// caller appends `sandbox-exec` and the jail's arguments. For a match, `bot_dir`'s
/// top-level entries are mounted read-only in the working directory (`/sandbox/work`),
/// which is otherwise writable scratch of `scratch_bytes` shared with `/tmp`. For a
/// build (`writable`), the folder itself is the working directory, writable, so that
/// what the build makes stays; as root, a build then runs as a root without any
/// capability in a user namespace of its own (it must write files the server owns).
///
/// # Errors
/// The bot folder cannot be listed.
pub fn bwrap_args(
    full: &FullSandbox,
    bot_dir: Option<&Path>,
    scratch_bytes: u64,
    writable: bool,
    extra_env: &[(String, String)],
) -> std::io::Result<Vec<OsString>> {
    let mut a: Vec<OsString> = Vec::new();
    let mut push = |items: &[&dyn AsRef<std::ffi::OsStr>]| {
        a.extend(items.iter().map(|i| i.as_ref().to_os_string()));
    };
    if full.as_root && !writable {
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
    push(&[
        &"--die-with-parent",
        &"--new-session",
        &"--hostname",
        &"mazearena",
    ]);
    push(&[&"--ro-bind", &"/usr", &"/usr"]);
    for dir in SYSTEM_DIRS {
        let p = Path::new(dir);
        match std::fs::read_link(p) {
            Ok(target) => push(&[&"--symlink", &target, dir]),
            Err(_) if p.is_dir() => push(&[&"--ro-bind", dir, dir]),
            Err(_) => {}
        }
    }
    for f in ETC_FILES {
        push(&[&"--ro-bind-try", f, f]);
    }
    for root in &full.runtime_roots {
        push(&[&"--ro-bind", root, root]);
        for secret in SECRET_FILES {
            let f = root.join(secret);
            if f.is_file() {
                push(&[&"--ro-bind", &"/dev/null", &f]);
            }
        }
    }
    push(&[&"--proc", &"/proc", &"--dev", &"/dev"]);
    let size = scratch_bytes.to_string();
    let work = format!("{SCRATCH}/work");
    let tmp = format!("{SCRATCH}/tmp");
    push(&[
        &"--size", &size, &"--tmpfs", &SCRATCH, &"--dir", &tmp, &"--dir", &work,
    ]);
    if let (Some(dir), true) = (bot_dir, writable) {
        push(&[&"--bind", &dir, &work]);
    } else if let Some(dir) = bot_dir {
        let mut entries: Vec<_> = std::fs::read_dir(dir)?
            .filter_map(Result::ok)
            .map(|e| e.file_name())
            .collect();
        entries.sort();
        for name in entries {
            let dest = Path::new(&work).join(&name);
            push(&[&"--ro-bind", &dir.join(&name), &dest]);
        }
    }
    if full.as_root && !writable {
        push(&[&"--chmod", &"1777", &tmp, &"--chmod", &"0777", &work]);
    }
    push(&[&"--symlink", &tmp, &"/tmp"]);
    push(&[&"--ro-bind", &full.helper, &HELPER_IN_SANDBOX]);
    // bubblewrap makes the folders above a mount point for root only (0700): open them
    // to the match's uid, which must reach the runtimes (e.g. /root/.pyenv) and /etc.
    let mut parents: Vec<PathBuf> = Vec::new();
    let dests = ETC_FILES
        .iter()
        .map(PathBuf::from)
        .chain(full.runtime_roots.iter().cloned())
        .chain([PathBuf::from(HELPER_IN_SANDBOX)]);
    for dest in dests {
        for a in dest.ancestors().skip(1) {
            if a != Path::new("/") && !parents.iter().any(|p| p == a) {
                parents.push(a.to_path_buf());
            }
        }
    }
    parents.retain(|p| !full.runtime_roots.iter().any(|r| p.starts_with(r)));
    for p in &parents {
        if p.exists() || p.starts_with("/run") {
            push(&[&"--chmod", &"0755", p]);
        }
    }
    push(&[&"--clearenv"]);
    for (k, v) in full.env.iter().chain(extra_env) {
        push(&[&"--setenv", k, v]);
    }
    push(&[&"--chdir", &work, &"--", &HELPER_IN_SANDBOX]);
    Ok(a)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hidden_paths_are_never_under_a_runtime_root() {
        let tmp = tempfile::tempdir().unwrap();
        let tools = tmp.path().join("tools/bin");
        std::fs::create_dir_all(&tools).unwrap();
        // SAFETY (test): single-threaded use of the environment in this test binary is
        // not guaranteed, so only read what was set; the function reads PATH itself.
        let roots = runtime_roots(&[tmp.path().join("tools/data.db")]);
        assert!(
            roots
                .iter()
                .all(|r| !tmp.path().join("tools/data.db").starts_with(r))
        );
        assert!(roots.iter().all(|r| !is_system(r)));
    }
}
