//! Real maze files: the 521 micromouse contest mazes in the ASCII "mazefiles" format and
//! the three classic numeric test mazes of the task (RULES.md "Reference figures").

use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;

use mazearena::engine::mazefile::{self, ascii};
use mazearena::engine::{MazeError, solver};

const CONTEST_DIR: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../shared/mazes/micromouseonline/classic"
);
const CLASSIC_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/mazes/classic");

/// The number of contest maze files in the snapshot (shared/mazes/README.md).
const CONTEST_FILES: usize = 521;

fn contest_files() -> Vec<(String, Vec<u8>)> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(CONTEST_DIR)
        .unwrap_or_else(|e| panic!("cannot list {CONTEST_DIR}: {e}"))
        .map(|entry| entry.expect("directory entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "txt"))
        .collect();
    paths.sort();
    paths
        .into_iter()
        .map(|p| {
            let name = p
                .file_name()
                .expect("file name")
                .to_string_lossy()
                .into_owned();
            let bytes = std::fs::read(&p).unwrap_or_else(|e| panic!("cannot read {name}: {e}"));
            (name, bytes)
        })
        .collect()
}

/// The kind of a rejection, without the place and cells (for grouping).
fn reason_kind(e: &MazeError) -> String {
    let text = match e {
        MazeError::Syntax { reason, .. } => reason.clone(),
        MazeError::Structure { error, .. } => error.to_string(),
        MazeError::TooLarge { .. } => e.to_string(),
    };
    text.chars()
        .map(|c| if c.is_ascii_digit() { '#' } else { c })
        .collect()
}

#[test]
fn every_contest_maze_imports_or_is_rejected_with_a_reason() {
    let files = contest_files();
    assert_eq!(files.len(), CONTEST_FILES);
    let mut imported = 0usize;
    let mut rejected: BTreeMap<String, Vec<String>> = BTreeMap::new();
    let mut reachable = 0usize;
    let mut unreachable = BTreeSet::new();
    let mut strict = 0usize;
    let mut layouts = BTreeSet::new();
    for (name, bytes) in &files {
        assert_eq!(mazefile::detect(bytes), mazefile::Format::Ascii, "{name}");
        match mazefile::parse(bytes) {
            Ok(maze) => {
                imported += 1;
                assert_eq!(maze.dim(), 16, "{name}");
                if solver::solve(&maze).is_some() {
                    reachable += 1;
                } else {
                    unreachable.insert(name.as_str());
                }
                if maze.strict_problems().is_empty() {
                    strict += 1;
                }
                layouts.insert(maze.hash());
            }
            Err(e) => {
                let text = e.to_string();
                assert!(!text.is_empty() && e.line() >= 1, "{name}: {e:?}");
                rejected
                    .entry(reason_kind(&e))
                    .or_default()
                    .push(format!("{name}: {text}"));
            }
        }
    }
    let rejected_count: usize = rejected.values().map(Vec::len).sum();
    assert_eq!(imported + rejected_count, CONTEST_FILES);
    // Observed on the snapshot: every file imports (all draw S bottom-left opening up,
    // the four G in the centre, a closed perimeter).
    assert!(
        imported >= CONTEST_FILES,
        "only {imported} imported; rejected by reason: {rejected:#?}"
    );
    // Two files wall the goal room off on purpose (test patterns, not contest mazes).
    assert_eq!(
        unreachable,
        BTreeSet::from(["001-anomaly-test.txt", "001.txt"]),
        "mazes without a route to the goal"
    );
    assert_eq!(reachable, imported - 2);
    assert_eq!(
        strict, reachable,
        "reachable contest mazes are valid task mazes but for the side"
    );
    // The collection holds duplicates (README: "some files may contain ... duplicates").
    assert_eq!(layouts.len(), 508, "distinct layouts");
}

#[test]
fn contest_mazes_survive_crlf_mirroring_and_flipping() {
    for (name, bytes) in contest_files().iter().step_by(7) {
        let text = String::from_utf8(bytes.clone()).expect("ASCII text");
        let Ok(maze) = ascii::parse(bytes) else {
            continue;
        };
        let lines: Vec<&str> = text.lines().collect();
        let crlf = lines.join("\r\n");
        assert_eq!(
            ascii::parse(crlf.as_bytes()).as_ref(),
            Ok(&maze),
            "{name} CRLF"
        );
        // Left-right mirror: S ends at the bottom-right; a reflection brings it back.
        let mirrored: Vec<String> = lines.iter().map(|l| l.chars().rev().collect()).collect();
        assert_eq!(
            ascii::parse(mirrored.join("\n").as_bytes()).as_ref(),
            Ok(&maze),
            "{name} mirrored"
        );
        // Upside down: S at the top-left opening down.
        let flipped: Vec<&str> = lines.iter().rev().copied().collect();
        assert_eq!(
            ascii::parse(flipped.join("\n").as_bytes()).as_ref(),
            Ok(&maze),
            "{name} flipped"
        );
        assert_eq!(
            ascii::parse(ascii::write(&maze).as_bytes()).as_ref(),
            Ok(&maze),
            "{name}"
        );
    }
}

#[test]
fn broken_contest_mazes_are_rejected_with_the_line() {
    let files = contest_files();
    let (name, bytes) = files
        .iter()
        .find(|(n, _)| n == "japan2017eq.txt")
        .expect("japan2017eq.txt is in the snapshot");
    let text = String::from_utf8(bytes.clone()).expect("ASCII text");
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    assert!(ascii::parse(bytes).is_ok(), "{name}");

    // A gap in the east wall of the 5th row from the top (line 10).
    let mut open = lines.clone();
    open[9].replace_range(64..65, " ");
    let e = ascii::parse(open.join("\n").as_bytes()).unwrap_err();
    assert!(matches!(e, MazeError::Structure { line: 10, .. }), "{e}");
    assert!(e.to_string().contains("perimeter"), "{e}");

    // The start moved to the middle of the bottom row.
    let mut moved = lines.clone();
    moved[31] = moved[31].replacen('S', " ", 1);
    moved[31].replace_range(30..31, "S");
    let e = ascii::parse(moved.join("\n").as_bytes()).unwrap_err();
    assert!(
        matches!(
            e,
            MazeError::Syntax {
                line: 32,
                column: 31,
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("not in a corner"), "{e}");

    // A fifth goal mark.
    lines[1].replace_range(2..3, "G");
    let e = ascii::parse(lines.join("\n").as_bytes()).unwrap_err();
    assert!(
        matches!(
            e,
            MazeError::Syntax {
                line: 2,
                column: 3,
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("not the centre 2x2 room"), "{e}");
}

#[test]
fn classic_numeric_mazes_match_the_reference_figures() {
    for (file, steps) in [
        ("test_maze_01.txt", 17),
        ("test_maze_02.txt", 22),
        ("test_maze_03.txt", 25),
    ] {
        let path = format!("{CLASSIC_DIR}/{file}");
        let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("cannot read {path}: {e}"));
        let maze = mazefile::parse(&bytes).unwrap_or_else(|e| panic!("{file}: {e}"));
        let solution = solver::solve(&maze).unwrap_or_else(|| panic!("{file}: no route"));
        assert_eq!(solution.steps, steps, "{file}");
        // The ASCII drawing of a numeric maze reads back to the same maze.
        assert_eq!(
            ascii::parse(ascii::write(&maze).as_bytes()),
            Ok(maze.clone()),
            "{file}"
        );
        if file == "test_maze_01.txt" {
            assert!(
                maze.strict_problems().is_empty(),
                "{:?}",
                maze.strict_problems()
            );
        }
    }
}
