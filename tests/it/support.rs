//! Helpers shared by the integration tests: paths, fixture bots, process checks.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use mazearena::engine::{Maze, mazefile};
use mazearena::runner::BotSpec;

/// The crate root.
pub fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// A file under ../shared/mazes (beside the checkout).
pub fn shared_maze(rel: &str) -> PathBuf {
    root().join("../shared/mazes").join(rel)
}

/// Parses a maze from ../shared/mazes.
pub fn load_shared(rel: &str) -> Maze {
    let path = shared_maze(rel);
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    mazefile::parse(&bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The classic test maze `n` (1, 2 or 3).
pub fn classic(n: u32) -> Maze {
    load_shared(&format!("classic/test_maze_0{n}.txt"))
}

/// A fixture bot from tests/fixtures/bots, run with python3 from the crate root.
pub fn fixture_bot(name: &str, args: &[&str]) -> BotSpec {
    let mut command = format!("python3 tests/fixtures/bots/{name}.py");
    for a in args {
        command.push(' ');
        command.push_str(&shlex::try_quote(a).unwrap());
    }
    BotSpec {
        command,
        dir: root().to_path_buf(),
    }
}

/// Runs the real `mazearena` binary with `args` from the crate root.
pub fn mazearena(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mazearena"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("the mazearena binary runs")
}

/// Processes (not zombies) that are still members of process group `pgid`.
pub fn live_group_members(pgid: u32) -> Vec<u32> {
    let mut found = Vec::new();
    let Ok(entries) = std::fs::read_dir("/proc") else {
        return found;
    };
    for entry in entries.flatten() {
        let Ok(pid) = entry.file_name().to_string_lossy().parse::<u32>() else {
            continue;
        };
        let Ok(stat) = std::fs::read_to_string(format!("/proc/{pid}/stat")) else {
            continue;
        };
        let Some(close) = stat.rfind(')') else {
            continue;
        };
        let fields: Vec<&str> = stat[close + 2..].split_whitespace().collect();
        // fields[0] = state, fields[2] = pgrp (stat(5) fields 3 and 5).
        if fields.len() > 2 && fields[0] != "Z" && fields[2] == pgid.to_string() {
            found.push(pid);
        }
    }
    found
}
