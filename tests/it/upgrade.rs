//! Databases made by earlier releases open in this one: their migrations run, and what
//! they hold reads back the same. `tests/fixtures/db/made-by-0.1.0.db` was made by
//! release 0.1.0 (a tournament of the shipped Python bots and a bot that quits, on two
//! shipped mazes); `replay-N.json` are its own exports of matches N.

use std::path::Path;

use serde_json::Value;

use crate::support::{assert_standings_equal_recount, mazearena, root};

/// A copy of the fixture database (opening it migrates it).
fn copy_of_old_database(dir: &Path) -> String {
    let to = dir.join("old.db");
    std::fs::copy(root().join("tests/fixtures/db/made-by-0.1.0.db"), &to).unwrap();
    format!("sqlite://{}", to.display())
}

/// Whether every field of `old` is in `new` with the same value (`new` may have more).
fn holds(new: &Value, old: &Value, at: &str) -> Result<(), String> {
    match (new, old) {
        (Value::Object(n), Value::Object(o)) => o.iter().try_for_each(|(k, v)| {
            holds(n.get(k).unwrap_or(&Value::Null), v, &format!("{at}.{k}"))
        }),
        (Value::Array(n), Value::Array(o)) if n.len() == o.len() => n
            .iter()
            .zip(o)
            .enumerate()
            .try_for_each(|(i, (a, b))| holds(a, b, &format!("{at}[{i}]"))),
        _ if new == old => Ok(()),
        _ => Err(format!("{at}: now {new}, was {old}")),
    }
}

#[tokio::test]
async fn a_database_of_release_0_1_0_keeps_its_standings_and_replays() {
    let dir = tempfile::tempdir().unwrap();
    let db = copy_of_old_database(dir.path());
    assert_standings_equal_recount(&db, &[1]).await;
    for id in [2, 5, 8] {
        let out = dir.path().join(format!("replay-{id}.json"));
        let run = mazearena(&[
            "match",
            "show",
            &id.to_string(),
            "--database",
            &db,
            "--replay",
            out.to_str().unwrap(),
        ]);
        assert!(run.status.success(), "{run:?}");
        let read = |p: &Path| -> Value {
            serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
        };
        let old = read(&root().join(format!("tests/fixtures/db/replay-{id}.json")));
        let new = read(&out);
        let steps = old["trace"].as_array().map_or(0, Vec::len);
        assert_eq!(
            steps > 0,
            id != 5,
            "match 5 crashed at once, the others played"
        );
        if let Err(e) = holds(&new, &old, "replay") {
            panic!("match {id}: {e}");
        }
    }
}
