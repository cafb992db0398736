//! What the runtimes a server offers bots are: for each of the operator's runtime
//! folders (`--runtime DIR`) and the system's own interpreters and compilers, its
//! programs, their version and its installed packages, for `GET /api/runtimes`, the
//! home page and `mazearena doctor`.
//!
//! The versions come from running each program with `--version` (or `-version`,
//! `version`) once, at start-up, outside any sandbox: these are the operator's own
//! programs. The packages are read from the install folders (Python's `*.dist-info`
//! and `*.egg-info`, Node's `node_modules/*/package.json`), never by running anything
//! a bot could have written.

use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::Duration;

use serde::Serialize;

/// How long a program may take to say its version.
const VERSION_TIMEOUT: Duration = Duration::from_secs(10);

/// The programs looked for, by language: (language, programs, how to ask the version).
const PROGRAMS: &[(&str, &[&str], &str)] = &[
    ("python", &["python3", "python", "pip3"], "--version"),
    ("javascript", &["node", "npm"], "--version"),
    ("c", &["gcc", "cc", "make"], "--version"),
    ("c++", &["g++", "c++"], "--version"),
    ("java", &["java", "javac"], "-version"),
    ("go", &["go"], "version"),
    ("rust", &["rustc", "cargo"], "--version"),
];

/// One installed package.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Serialize, utoipa::ToSchema)]
pub struct Package {
    /// Its name.
    pub name: String,
    /// Its version.
    pub version: String,
}

/// One runtime a bot may use.
#[derive(Debug, Clone, PartialEq, Serialize, utoipa::ToSchema)]
pub struct RuntimeInfo {
    /// The name a bot gives as `runtime` to have this one first on its `PATH`: the
    /// install folder's name for the operator's runtimes, `system` for the system's.
    pub name: String,
    /// `operator` (listed with `--runtime`) or `system`.
    pub kind: String,
    /// The languages found in it.
    pub languages: Vec<String>,
    /// Each program found and the first line it gives as its version.
    pub programs: Vec<ProgramInfo>,
    /// The packages installed in it (Python and Node), by name.
    pub packages: Vec<Package>,
}

/// A program of a runtime and its version.
#[derive(Debug, Clone, PartialEq, Serialize, utoipa::ToSchema)]
pub struct ProgramInfo {
    /// Its name, as a bot calls it.
    pub program: String,
    /// The first line of its version text (empty if it gave none).
    pub version: String,
}

/// The name a bot uses for runtime `r`: its install folder's name.
pub fn name_of(r: &Runtime) -> String {
    r.prefix.file_name().map_or_else(
        || r.prefix.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// The names of `runtimes`, for a message: "a, b", or "none listed".
pub fn offered(runtimes: &[Runtime]) -> String {
    if runtimes.is_empty() {
        "it lists none".into()
    } else {
        let names: Vec<String> = runtimes
            .iter()
            .filter(|r| !r.base_of_venv)
            .map(name_of)
            .collect();
        format!("it offers {}", names.join(", "))
    }
}

/// Describes the operator's `runtimes` and the system's programs.
pub async fn probe(runtimes: &[Runtime]) -> Vec<RuntimeInfo> {
    let mut out = Vec::new();
    for r in runtimes.iter().filter(|r| !r.base_of_venv) {
        let bin = r.prefix.join("bin");
        let (languages, programs) = programs_in(&[bin]).await;
        out.push(RuntimeInfo {
            name: name_of(r),
            kind: "operator".into(),
            languages,
            programs,
            packages: packages_in(&r.prefix),
        });
    }
    let system: Vec<PathBuf> = ["/usr/local/bin", "/usr/bin", "/bin"]
        .iter()
        .map(PathBuf::from)
        .collect();
    let (languages, programs) = programs_in(&system).await;
    let mut packages = Vec::new();
    for root in [
        "/usr/lib/python3/dist-packages",
        "/usr/local/lib/node_modules",
        "/usr/lib/node_modules",
    ] {
        packages.extend(packages_of_folder(Path::new(root)));
    }
    if let Ok(entries) = std::fs::read_dir("/usr/local/lib") {
        for e in entries.flatten() {
            if e.file_name().to_string_lossy().starts_with("python3") {
                packages.extend(packages_of_folder(&e.path().join("dist-packages")));
                packages.extend(packages_of_folder(&e.path().join("site-packages")));
            }
        }
    }
    packages.sort();
    packages.dedup();
    out.push(RuntimeInfo {
        name: "system".into(),
        kind: "system".into(),
        languages,
        programs,
        packages,
    });
    out
}

/// The known programs in `dirs` (the first of each name), their languages and versions.
async fn programs_in(dirs: &[PathBuf]) -> (Vec<String>, Vec<ProgramInfo>) {
    let mut languages = Vec::new();
    let mut programs = Vec::new();
    for (language, names, flag) in PROGRAMS {
        for name in *names {
            let Some(path) = dirs.iter().map(|d| d.join(name)).find(|p| is_program(p)) else {
                continue;
            };
            programs.push(ProgramInfo {
                program: name.to_string(),
                version: version_of(&path, flag).await,
            });
            if !languages.iter().any(|l| l == language) {
                languages.push(language.to_string());
            }
        }
    }
    (languages, programs)
}

fn is_program(p: &Path) -> bool {
    use std::os::unix::fs::PermissionsExt;
    std::fs::metadata(p).is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
}

/// The first non-empty line `program flag` prints (Java prints it on stderr).
async fn version_of(program: &Path, flag: &str) -> String {
    let run = tokio::process::Command::new(program)
        .arg(flag)
        .stdin(Stdio::null())
        .kill_on_drop(true)
        .output();
    match tokio::time::timeout(VERSION_TIMEOUT, run).await {
        Ok(Ok(out)) => {
            let text = format!(
                "{}\n{}",
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr)
            );
            let line = text
                .lines()
                .map(str::trim)
                .find(|l| !l.is_empty())
                .unwrap_or("");
            without_paths(line).chars().take(200).collect()
        }
        _ => String::new(),
    }
}

/// `line` without the server's paths: cut before " from /" (pip says where it lives),
/// any other word that starts with `/` written as `...`.
fn without_paths(line: &str) -> String {
    let line = line.split(" from /").next().unwrap_or(line);
    line.split(' ')
        .map(|w| if w.starts_with('/') { "..." } else { w })
        .collect::<Vec<_>>()
        .join(" ")
}

/// The packages under a runtime's install folder: Python's site-packages of each
/// `lib/python*`, and Node's global `lib/node_modules`.
fn packages_in(prefix: &Path) -> Vec<Package> {
    let mut out = Vec::new();
    if let Ok(entries) = std::fs::read_dir(prefix.join("lib")) {
        for e in entries.flatten() {
            let name = e.file_name();
            let name = name.to_string_lossy();
            if name.starts_with("python") {
                out.extend(packages_of_folder(&e.path().join("site-packages")));
            } else if name == "node_modules" {
                out.extend(packages_of_folder(&e.path()));
            }
        }
    }
    out.sort();
    out.dedup();
    out
}

/// The packages of one folder: `NAME-VERSION.dist-info` / `.egg-info` folders, and
/// `NAME/package.json` (with `@scope/NAME`) for Node.
fn packages_of_folder(dir: &Path) -> Vec<Package> {
    let mut out = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return out;
    };
    for e in entries.flatten() {
        let file = e.file_name();
        let file = file.to_string_lossy();
        if let Some(stem) = file
            .strip_suffix(".dist-info")
            .or_else(|| file.strip_suffix(".egg-info"))
        {
            if let Some((name, version)) = stem.split_once('-') {
                let version = version.split('-').next().unwrap_or(version);
                out.push(Package {
                    name: name.replace('_', "-").to_lowercase(),
                    version: version.to_string(),
                });
            }
        } else if file.starts_with('@') {
            for inner in std::fs::read_dir(e.path()).into_iter().flatten().flatten() {
                if let Some(p) = node_package(&inner.path(), Some(&file)) {
                    out.push(p);
                }
            }
        } else if let Some(p) = node_package(&e.path(), None) {
            out.push(p);
        }
    }
    out
}

/// A Node package folder's name and version, from its `package.json` (at most 1 MiB).
fn node_package(dir: &Path, scope: Option<&str>) -> Option<Package> {
    let file = dir.join("package.json");
    let meta = std::fs::metadata(&file).ok()?;
    if !meta.is_file() || meta.len() > 1 << 20 {
        return None;
    }
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&file).ok()?).ok()?;
    let folder = dir.file_name()?.to_string_lossy().into_owned();
    let name = v["name"].as_str().map_or_else(
        || match scope {
            Some(s) => format!("{s}/{folder}"),
            None => folder,
        },
        str::to_string,
    );
    Some(Package {
        name,
        version: v["version"].as_str().unwrap_or("").to_string(),
    })
}

/// One language runtime's installation, mounted read-only in every bot's view at its
/// own path: an install prefix (a pyenv version, a venv, a Node prefix, a rustup
/// toolchain, a JDK, a Go root), never a home folder or a folder holding dotfiles.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Runtime {
    /// The install prefix (canonical).
    pub prefix: PathBuf,
    /// Why it is in the view, for `mazearena doctor`.
    pub why: String,
    /// The base interpreter of a listed venv: mounted, because the venv's programs run
    /// it, but not a runtime of its own: not offered by name, not listed, not on the
    /// bot's `PATH` (its site-packages are the operator's, not the venv's).
    pub base_of_venv: bool,
}

impl Runtime {
    /// An install folder mounted for bots and offered to them.
    pub fn offered(prefix: PathBuf, why: impl Into<String>) -> Runtime {
        Runtime {
            prefix,
            why: why.into(),
            base_of_venv: false,
        }
    }
}

/// Past a pyenv shim or a rustup proxy, the program that it runs: `pyenv which` and
/// `rustup which` (the runner's own tools, asked about a file that is on its `PATH`),
/// asked once a process for each program. A bot is started with the program itself
/// with or without the sandbox: a shim's own start (a shell script and `pyenv exec`,
/// some 50 ms) is not in a match's time either way.
pub fn real_program(found: &Path, name: &str) -> PathBuf {
    type Known = std::sync::Mutex<std::collections::HashMap<(PathBuf, String), PathBuf>>;
    static KNOWN: std::sync::OnceLock<Known> = std::sync::OnceLock::new();
    let known = KNOWN.get_or_init(Default::default);
    let key = (found.to_path_buf(), name.to_string());
    if let Some(real) = known.lock().ok().and_then(|k| k.get(&key).cloned()) {
        return real;
    }
    let real = ask_manager(found, name);
    if let Ok(mut k) = known.lock() {
        k.insert(key, real.clone());
    }
    real
}

/// [`real_program`], asked of the version manager.
fn ask_manager(found: &Path, name: &str) -> PathBuf {
    let dir = found.parent().unwrap_or(Path::new("/"));
    let manager = if dir.ends_with("shims") {
        dir.parent().map(|root| root.join("bin/pyenv"))
    } else {
        Some(dir.join("rustup")).filter(|r| r.is_file())
    };
    let Some(manager) = manager.filter(|m| m.is_file()) else {
        return found.to_path_buf();
    };
    std::process::Command::new(&manager)
        .args(["which", name])
        .stdin(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| PathBuf::from(String::from_utf8_lossy(&o.stdout).trim()))
        .filter(|p| p.is_file())
        .unwrap_or_else(|| found.to_path_buf())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packages_are_read_from_python_and_node_install_folders() {
        let dir = tempfile::tempdir().unwrap();
        let site = dir.path().join("lib/python3.11/site-packages");
        std::fs::create_dir_all(site.join("numpy-2.1.3.dist-info")).unwrap();
        std::fs::create_dir_all(site.join("Scikit_Learn-1.5.0.dist-info")).unwrap();
        std::fs::create_dir_all(site.join("numpy")).unwrap();
        let nm = dir.path().join("lib/node_modules");
        std::fs::create_dir_all(nm.join("lodash")).unwrap();
        std::fs::write(
            nm.join("lodash/package.json"),
            r#"{"name":"lodash","version":"4.17.21"}"#,
        )
        .unwrap();
        std::fs::create_dir_all(nm.join("@types/node")).unwrap();
        std::fs::write(
            nm.join("@types/node/package.json"),
            r#"{"version":"20.1.0"}"#,
        )
        .unwrap();
        let p = packages_in(dir.path());
        let names: Vec<(&str, &str)> = p
            .iter()
            .map(|p| (p.name.as_str(), p.version.as_str()))
            .collect();
        assert_eq!(
            names,
            vec![
                ("@types/node", "20.1.0"),
                ("lodash", "4.17.21"),
                ("numpy", "2.1.3"),
                ("scikit-learn", "1.5.0"),
            ]
        );
    }

    #[test]
    fn version_lines_name_no_path_of_the_server() {
        assert_eq!(
            without_paths("pip 23.2.1 from /tmp/x/lib/python3.11/site-packages/pip (python 3.11)"),
            "pip 23.2.1"
        );
        assert_eq!(
            without_paths("tool 1.0 (/opt/tool)"),
            "tool 1.0 (/opt/tool)"
        );
        assert_eq!(without_paths("tool 1.0 at /opt/tool"), "tool 1.0 at ...");
    }

    #[tokio::test]
    async fn the_system_runtime_lists_the_programs_found_with_their_versions() {
        let all = probe(&[]).await;
        let system = all.iter().find(|r| r.name == "system").unwrap();
        // The tests run python3 bots: it is here, and says its version.
        let py = system
            .programs
            .iter()
            .find(|p| p.program == "python3")
            .expect("python3 is found");
        assert!(py.version.starts_with("Python 3"), "{py:?}");
        assert!(system.languages.contains(&"python".to_string()));
    }
}
