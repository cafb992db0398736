//! Databases made by earlier releases open in this one: their migrations run, and what
//! they hold reads back the same. `tests/fixtures/db/made-by-0.1.0.db` was made by
//! release 0.1.0 (a tournament of the shipped Python bots and a bot that quits, on two
//! shipped mazes); `replay-N.json` are its own exports of matches N.
//! `made-by-0.2.0.db` was made by release 0.2.0 before competitions (two bots in a
//! tournament on two hidden mazes and a public one, a third bot's single match);
//! `leaderboards-0.2.0.json` are its own leaderboards. An older data
//! folder (uploaded bots' files on disk) moves into the database; a bundle damaged in
//! the database is refused by the worker. `schema-N.*` are databases of three earlier
//! schemas filled by their own commits' servers (`make-old-schemas.sh` says how), on
//! SQLite and PostgreSQL: migrated by `mazearena migrate`, every board and result reads
//! the same.

use std::path::Path;

use serde_json::Value;

use crate::support::{assert_standings_equal_recount, mazearena, root};

/// A copy of the fixture database (opening it migrates it).
fn copy_of_old_database(dir: &Path) -> String {
    let to = dir.join("old.db");
    std::fs::copy(root().join("tests/fixtures/db/made-by-0.1.0.db"), &to).unwrap();
    format!("sqlite://{}", to.display())
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
        let mut out = Vec::new();
        differences(&new, &old, "replay", false, &mut out);
        assert!(out.is_empty(), "match {id}: {out:?}");
    }
}

/// A server started on the data folder of a release that kept uploaded bots' files
/// there (`DATA_DIR/bots/<random>/`, the version's `dir`) moves them into the database:
/// the version then plays from its stored bundle, with the old folder gone.
#[tokio::test]
async fn a_data_folder_of_an_earlier_release_moves_into_the_database() {
    use mazearena::botfiles::{BundleLimits, hash_dir, skip_nothing};
    use mazearena::registry::tokens::hash_token;
    use mazearena::storage::Storage;
    use mazearena::storage::bots::NewVersion;

    let dir = tempfile::tempdir().unwrap();
    let old = dir.path().join("data/bots/3f9c2a71d0be");
    std::fs::create_dir_all(&old).unwrap();
    for f in ["simple_bot.py", "mazebot.py"] {
        std::fs::copy(root().join("bots/python").join(f), old.join(f)).unwrap();
    }
    let files = hash_dir(&old, &BundleLimits::default(), &skip_nothing).unwrap();
    let database = format!("sqlite://{}", dir.path().join("mazearena.db").display());
    let storage = Storage::open(&database).await.unwrap();
    let version = storage
        .create_bot(
            "old-upload",
            &hash_token("old-owner-token"),
            &NewVersion {
                command: "python3 simple_bot.py",
                dir: &old.display().to_string(),
                files_sha256: &files.sha256,
                file_count: 2,
                build_command: None,
                env: &[],
                bundle_sha256: None,
                runtime: None,
                protocol: None,
            },
        )
        .await
        .unwrap();
    storage.close().await;

    let server = crate::support::TestServer::start(dir.path(), &[]);
    std::fs::remove_dir_all(dir.path().join("data/bots")).unwrap();
    let (s, queued) = server
        .post(
            "/api/matches",
            serde_json::json!({"bot_id": version.bot_id, "maze_id": 1, "seed": 3}),
            Some("old-owner-token"),
        )
        .await;
    assert_eq!(s, 202, "{queued}");
    let done = crate::support::wait_match(&server, queued["match_id"].as_i64().unwrap()).await;
    assert_eq!(done["status"], "finished", "{done}");

    let storage = Storage::open(&database).await.unwrap();
    let moved = storage
        .get_bot_version(version.bot_version_id)
        .await
        .unwrap()
        .unwrap();
    assert_eq!(moved.bundle_sha256.as_deref(), Some(files.sha256.as_str()));
    assert_eq!(moved.dir, "");
    assert!(storage.get_bundle(&files.sha256).await.unwrap().is_some());
}

/// A process the test started, killed and reaped when the test ends, also by a failed
/// assertion: nothing is left running.
struct KilledOnDrop(std::process::Child);

impl Drop for KilledOnDrop {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// A bundle damaged in the database (its files no longer give its hash) never plays:
/// the worker refuses it, and the match is recorded as crashed with the reason, once.
/// A version waiting for its build whose files are damaged fails its build, with the
/// reason in its build log (it is not claimed again at every lease's end).
#[tokio::test(flavor = "multi_thread")]
async fn a_damaged_bundle_is_refused_by_the_worker_and_its_match_says_why() {
    use mazearena::storage::Storage;
    use mazearena::storage::bundles::NewBundle;

    let dir = tempfile::tempdir().unwrap();
    let server = crate::support::TestServer::start(dir.path(), &["--jobs", "0"]);
    let (bot, token) = crate::support::register(
        &server,
        "tampered",
        "python3 simple_bot.py",
        crate::support::simple_bot_files(),
    )
    .await;
    // Someone with the database swaps the version's files for other files under a
    // made-up hash.
    let storage = Storage::open(&server.database).await.unwrap();
    let version = storage.bot_versions(bot).await.unwrap().remove(0);
    let real = version.bundle_sha256.clone().unwrap();
    let archive = storage.get_bundle(&real).await.unwrap().unwrap();
    let forged = "0123456789abcdef".repeat(4);
    storage
        .put_bundle(&NewBundle {
            sha256: &forged,
            archive: &archive,
            files: 2,
            bytes: 1,
        })
        .await
        .unwrap();
    storage
        .set_version_bundles(version.bot_version_id, Some(&forged), None)
        .await
        .unwrap();
    // The same for a version that waits for its build (this server builds nothing).
    let (s, built) = server
        .post(
            "/api/bots",
            serde_json::json!({"name": "tampered-build", "command": "python3 simple_bot.py",
                "build": "python3 -c pass", "files": crate::support::simple_bot_files()}),
            None,
        )
        .await;
    assert_eq!(s, 201, "{built}");
    let built_bot = built["bot_id"].as_i64().unwrap();
    let waiting = storage.bot_versions(built_bot).await.unwrap().remove(0);
    storage
        .set_version_bundles(waiting.bot_version_id, Some(&forged), None)
        .await
        .unwrap();

    let mut worker = KilledOnDrop(
        std::process::Command::new(env!("CARGO_BIN_EXE_mazearena"))
            .args([
                "worker",
                "--jobs",
                "1",
                // The match itself meets the damaged bundle (a validating builder
                // would fail the version before any match).
                "--no-validation",
                "--database",
                &server.database,
                "--data-dir",
            ])
            .arg(dir.path().join("worker"))
            .env("MAZEARENA_SANDBOX", crate::support::sandbox().level())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap(),
    );
    let (s, queued) = server
        .post(
            "/api/matches",
            serde_json::json!({"bot_id": bot, "maze_id": 1}),
            Some(&token),
        )
        .await;
    assert_eq!(s, 202, "{queued}");
    let id = queued["match_id"].as_i64().unwrap();
    let done = crate::support::wait_match(&server, id).await;
    let version = crate::support::wait_built(&server, built_bot).await;
    assert_eq!(version["build_status"], "build_failed", "{version}");
    let (_, mine) = server
        .get(
            &format!("/api/bots/{built_bot}"),
            built["owner_token"].as_str(),
        )
        .await;
    let log = mine["versions"][0]["build_log_tail"].as_str().unwrap();
    assert!(
        log.starts_with("the server could not use the version's stored files")
            && log.contains("refused"),
        "{log}"
    );
    let _ = nix::sys::signal::kill(
        nix::unistd::Pid::from_raw(worker.0.id() as i32),
        nix::sys::signal::Signal::SIGTERM,
    );
    assert!(worker.0.wait().unwrap().success());
    assert_eq!(
        (&done["status"], &done["attempts"]),
        (&serde_json::json!("crashed"), &serde_json::json!(1)),
        "{done}"
    );
    let (_, log) = server
        .get(&format!("/api/matches/{id}/log"), Some(&token))
        .await;
    let reason = log["error"]["reason"].as_str().unwrap();
    assert!(
        reason.starts_with("the server could not use the bot's stored files")
            && reason.contains("refused"),
        "{reason}"
    );
    // Nothing of it stayed in the worker's cache.
    assert!(!dir.path().join("worker/cache").join(&forged).exists());
}

/// The ranking of release 0.2.0 becomes the default competition: its leaderboards read
/// back the same, and the default competition's board is the ranking.
#[tokio::test]
async fn a_database_of_release_0_2_0_keeps_its_ranking_as_the_default_competition() {
    let dir = tempfile::tempdir().unwrap();
    let to = dir.path().join("old.db");
    std::fs::copy(root().join("tests/fixtures/db/made-by-0.2.0.db"), &to).unwrap();
    let database = format!("sqlite://{}", to.display());
    let old: Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("tests/fixtures/db/leaderboards-0.2.0.json")).unwrap(),
    )
    .unwrap();
    let server =
        crate::support::TestServer::start_on(dir.path(), Some(&database), &["--jobs", "0"], &[]);
    for (query, key) in [
        ("", "ranking"),
        ("?scope=all", "all"),
        ("?tournament=1", "tournament_1"),
    ] {
        let (s, now) = server.get(&format!("/api/leaderboard{query}"), None).await;
        assert_eq!(s, 200, "{now}");
        let (now, then) = (now.as_array().unwrap(), old[key].as_array().unwrap());
        assert_eq!(now.len(), then.len(), "{key}");
        for (n, t) in now.iter().zip(then) {
            // Every number of 0.2.0 reads back the same; the rank is shared now by equal
            // means (0.2.0 ranked two bots of equal scores 1 and 2), and the line says
            // how sure it is.
            // Means and rates are shown rounded to 3 decimals now (0.2.0 printed
            // every float's digits).
            for (field, value) in t.as_object().unwrap() {
                match (field.as_str(), value.as_f64()) {
                    ("rank", _) => {}
                    ("mean_score" | "finish_rate" | "mean_ratio", Some(v)) => assert_eq!(
                        n[field].as_f64(),
                        Some((v * 1000.0).round() / 1000.0),
                        "{key}: {field}"
                    ),
                    _ => assert_eq!(&n[field], value, "{key}: {field}"),
                }
            }
            let better = now
                .iter()
                .filter(|o| o["mean_score"].as_f64() < n["mean_score"].as_f64())
                .count() as i64;
            assert_eq!(n["rank"].as_i64(), Some(better + 1), "{key}: {n}");
            assert!(n["uncertainty"]["rank_range"].is_string(), "{key}: {n}");
        }
    }
    let (_, list) = server.get("/api/competitions", None).await;
    assert_eq!(list[0]["name"], "ranking", "{list}");
    assert_eq!(list[0]["kind"], "default", "{list}");
    let (_, board) = server
        .get("/api/competitions/ranking/leaderboard", None)
        .await;
    let lines = board["standings"].as_array().unwrap();
    let ranking = old["ranking"].as_array().unwrap();
    assert_eq!(lines.len(), ranking.len(), "{board}");
    for (line, old) in lines.iter().zip(ranking) {
        for field in ["bot_id", "version", "played", "finished"] {
            assert_eq!(line[field], old[field], "{field}: {board}");
        }
        let rounded = (old["mean_score"].as_f64().unwrap() * 1000.0).round() / 1000.0;
        assert_eq!(line["mean_score"].as_f64(), Some(rounded), "{board}");
    }
    // The ranking's ratio column is "-" over hidden mazes, and the page says why.
    let (_, home) = server.get_text("/").await;
    assert!(home.contains("where hidden mazes are counted"), "{home}");
    let (_, page) = server.get_text("/competitions/ranking").await;
    assert!(page.contains("alpha") && page.contains("beta"), "{page}");
    drop(server);
    assert_standings_equal_recount(&database, &[1]).await;
}

/// A committed migration is never edited again (a database migrated by it would refuse
/// to open: sqlx checks each applied migration's checksum): each file's SHA-256 is the
/// one `migrations/checksums.sha256` recorded when it was added, and every migration is
/// recorded there. A change of schema is a new file, and a new line.
#[test]
fn every_committed_migration_is_unchanged() {
    use sha2::{Digest, Sha256};
    let dir = root().join("migrations");
    let recorded = std::fs::read_to_string(dir.join("checksums.sha256")).unwrap();
    let mut seen = std::collections::BTreeMap::new();
    for line in recorded.lines().filter(|l| !l.trim().is_empty()) {
        let (hash, path) = line.split_once("  ").expect("`HASH  PATH` lines");
        seen.insert(path.to_string(), hash.to_string());
    }
    let mut files = Vec::new();
    for backend in ["sqlite", "postgres"] {
        for entry in std::fs::read_dir(dir.join(backend)).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "sql") {
                files.push(format!(
                    "{backend}/{}",
                    path.file_name().unwrap().to_string_lossy()
                ));
            }
        }
    }
    files.sort();
    let listed: Vec<String> = seen.keys().cloned().collect();
    assert_eq!(
        files, listed,
        "every migration, and only those, has its checksum recorded"
    );
    for file in files {
        let text = std::fs::read(dir.join(&file)).unwrap();
        let hash: String = Sha256::digest(&text)
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        assert_eq!(
            hash, seen[&file],
            "{file} was edited after it was committed: add a new migration instead"
        );
    }
}

/// The schemas of earlier commits with a database filled by that commit's own server
/// (`tests/fixtures/db/make-old-schemas.sh` made them): competitions added (0012), exact
/// sums (0016), the mms protocol and rejudges (0018). Each holds a competition open
/// (entrants, bots, versions, practice and ranking matches), one closed with its final
/// run and results (at 0018 rejudged twice), one still to come, and a tournament and
/// bots outside competitions; `schema-N.{sqlite,pg}.json` are what its API showed each
/// caller.
const EARLIER_SCHEMAS: [&str; 3] = ["0012", "0016", "0018"];

fn fixture(name: &str) -> std::path::PathBuf {
    root().join("tests/fixtures/db").join(name)
}

/// `mazearena migrate` brings `database` up to this release's schema.
fn migrate(database: &str) {
    let run = mazearena(&["migrate", "--database", database]);
    let out = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{run:?}");
    let newest = std::fs::read_dir(root().join("migrations/sqlite"))
        .unwrap()
        .count();
    assert!(
        out.contains(&format!("({newest} applied)")),
        "every migration applied: {out}"
    );
}

/// The differences between what a view shows now and what it showed (`old`), as paths;
/// `close` allows a float to differ by its rounding to 3 decimals.
fn differences(new: &Value, old: &Value, at: &str, close: bool, out: &mut Vec<String>) {
    match (new, old) {
        (Value::Object(n), Value::Object(o)) => {
            for (k, v) in o {
                differences(
                    n.get(k).unwrap_or(&Value::Null),
                    v,
                    &format!("{at}.{k}"),
                    close,
                    out,
                );
            }
        }
        (Value::Array(n), Value::Array(o)) if n.len() == o.len() => {
            for (i, (a, b)) in n.iter().zip(o).enumerate() {
                differences(a, b, &format!("{at}[{i}]"), close, out);
            }
        }
        (Value::Number(a), Value::Number(b))
            if close && (a.as_f64().unwrap() - b.as_f64().unwrap()).abs() <= 0.000_501 => {}
        _ if new == old => {}
        _ => out.push(format!("{at}: now {new}, was {old}")),
    }
}

/// Every view the old server showed, asked again of this release's server on the
/// migrated database: the same status, and every field of the old body with the same
/// value (new fields may be added). An error's code counts, not its wording.
/// `who` chooses the callers compared; `skip` the paths compared another way.
async fn views_read_the_same(
    server: &crate::support::TestServer,
    made: &Value,
    who: &dyn Fn(&str) -> bool,
    skip: &dyn Fn(&str) -> bool,
    close: bool,
) -> usize {
    let token = |caller: &str| match caller {
        "admin" => Some(crate::support::ADMIN.to_string()),
        "anonymous" => None,
        other => Some(made["tokens"][other].as_str().unwrap().to_string()),
    };
    let mut compared = 0;
    let mut wrong = Vec::new();
    for view in made["views"].as_array().unwrap() {
        let (caller, path) = (view["as"].as_str().unwrap(), view["path"].as_str().unwrap());
        // What this machine's runtimes are is not the database's.
        if path == "/api/runtimes" || !who(caller) || skip(path) {
            continue;
        }
        let (status, text, _) = server.get_raw(path, token(caller).as_deref()).await;
        let old_status = view["status"].as_i64().unwrap() as u16;
        if status != old_status {
            wrong.push(format!(
                "{caller} {path}: status {status}, was {old_status}: {text}"
            ));
            continue;
        }
        let now = serde_json::from_str(&text).unwrap_or(Value::String(text));
        let mut out = Vec::new();
        if old_status >= 400 {
            differences(
                &now["error"]["code"],
                &view["body"]["error"]["code"],
                "",
                close,
                &mut out,
            );
        } else {
            differences(&now, &view["body"], "", close, &mut out);
        }
        wrong.extend(out.into_iter().map(|d| format!("{caller} {path}{d}")));
        compared += 1;
    }
    assert!(
        wrong.is_empty(),
        "{} differences:\n{}",
        wrong.len(),
        wrong.join("\n")
    );
    compared
}

/// What an old server showed, from `schema-N.{backend}.json`.
fn made_by(schema: &str, backend: &str) -> Value {
    serde_json::from_str(
        &std::fs::read_to_string(fixture(&format!("schema-{schema}.{backend}.json"))).unwrap(),
    )
    .unwrap()
}

/// Today's server on the migrated `database` reads as the old one did.
async fn an_earlier_schema_reads_the_same(dir: &Path, database: &str, schema: &str, made: &Value) {
    migrate(database);
    let server = crate::support::TestServer::start_on(dir, Some(database), &["--jobs", "0"], &[]);
    let everyone = |_: &str| true;
    let nothing = |_: &str| false;
    if schema != "0012" {
        let compared = views_read_the_same(&server, made, &everyone, &nothing, false).await;
        assert!(compared > 100, "{schema}: {compared} views");
    } else {
        // Since 0012, on purpose: the last phase is named `final`; means are shown
        // rounded to 3 decimals (from exact sums); a competition belongs to the
        // organiser who made it (0012 recorded no maker: its competitions are the
        // admin's, who hands them on); the private set is played only by the final run,
        // and the rules of what other callers see are stricter. So the admin's views
        // are compared, and the private boards below.
        let admin = |who: &str| who == "admin";
        let private = |path: &str| path.contains("board=private");
        let renamed = rename_phase(made);
        let compared = views_read_the_same(&server, &renamed, &admin, &private, true).await;
        assert!(compared > 15, "{schema}: {compared} views");
        old_private_boards_read_from_their_tournaments(&server, made).await;
        // Handed to their organiser, the competitions read for it as for the admin.
        let teacher = made["tokens"]["organiser"].as_str().unwrap();
        for name in ["open-cup", "closed-cup", "future-cup"] {
            let (s, handed, _) = server
                .call(
                    reqwest::Method::PATCH,
                    &format!("/api/competitions/{name}"),
                    Some(serde_json::json!({"organiser": "teacher"})),
                    Some(crate::support::ADMIN),
                )
                .await;
            assert_eq!(s, 200, "{name}: {handed}");
            let path = format!("/api/competitions/{name}");
            let (_, as_admin) = server.get(&path, Some(crate::support::ADMIN)).await;
            let (_, as_teacher) = server.get(&path, Some(teacher)).await;
            assert_eq!(as_teacher, as_admin, "{name}");
        }
    }
    // The closed competition's private board is its final run, the run its results
    // were written from.
    let (_, board) = server
        .get(
            "/api/competitions/closed-cup/leaderboard?board=private",
            Some(crate::support::ADMIN),
        )
        .await;
    let (_, results) = server
        .get(
            "/api/competitions/closed-cup/results",
            Some(crate::support::ADMIN),
        )
        .await;
    let results = results["results"].as_array().unwrap();
    assert!(!results.is_empty(), "{schema}: results");
    for r in results {
        let line = board["standings"]
            .as_array()
            .unwrap()
            .iter()
            .find(|l| l["bot_id"] == r["bot_id"])
            .unwrap_or_else(|| panic!("{schema}: {r} on the private board {board}"));
        for field in ["version", "played", "finished", "score_sum30"] {
            assert_eq!(line[field], r[field], "{schema} {field}: {line} / {r}");
        }
    }
}

/// 0012's last phase, `closed`, is named `final` now.
fn rename_phase(made: &Value) -> Value {
    fn walk(v: &mut Value) {
        match v {
            Value::Object(o) => {
                for (k, v) in o.iter_mut() {
                    if k == "phase" && v == "closed" {
                        *v = Value::String("final".into());
                    } else {
                        walk(v);
                    }
                }
            }
            Value::Array(a) => a.iter_mut().for_each(walk),
            _ => {}
        }
    }
    let mut made = made.clone();
    walk(&mut made);
    made
}

/// 0012's private boards were tournaments of their own ("NAME: private ranking", played
/// while the competition was open); their matches and lines are all still there.
async fn old_private_boards_read_from_their_tournaments(
    server: &crate::support::TestServer,
    made: &Value,
) {
    let admin = Some(crate::support::ADMIN);
    let (_, list) = server.get("/api/tournaments?limit=100", admin).await;
    for view in made["views"].as_array().unwrap() {
        let path = view["path"].as_str().unwrap();
        if view["as"] != "admin" || !path.ends_with("/leaderboard?board=private") {
            continue;
        }
        let name = path.split('/').nth(3).unwrap();
        let tournament = list["items"]
            .as_array()
            .unwrap()
            .iter()
            .find(|t| t["name"] == format!("{name}: private ranking"))
            .unwrap_or_else(|| panic!("{name}'s private ranking in {list}"));
        let (_, lines) = server
            .get(
                &format!(
                    "/api/leaderboard?tournament={}",
                    tournament["tournament_id"]
                ),
                admin,
            )
            .await;
        for old in view["body"]["standings"].as_array().unwrap() {
            let now = lines
                .as_array()
                .unwrap()
                .iter()
                .find(|l| l["bot_id"] == old["bot_id"] && l["version"] == old["version"])
                .unwrap_or_else(|| panic!("{name}: {old} in {lines}"));
            let mut out = Vec::new();
            for field in ["played", "finished", "mean_score"] {
                differences(&now[field], &old[field], field, true, &mut out);
            }
            assert!(out.is_empty(), "{name}: {out:?}");
        }
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn databases_of_earlier_schemas_read_the_same_after_migrate_on_sqlite() {
    for schema in EARLIER_SCHEMAS {
        let dir = tempfile::tempdir().unwrap();
        let to = dir.path().join("old.db");
        std::fs::copy(fixture(&format!("schema-{schema}.db")), &to).unwrap();
        let database = format!("sqlite://{}", to.display());
        an_earlier_schema_reads_the_same(dir.path(), &database, schema, &made_by(schema, "sqlite"))
            .await;
    }
}

#[tokio::test(flavor = "multi_thread")]
async fn databases_of_earlier_schemas_read_the_same_after_migrate_on_postgresql() {
    let Some((cluster, _)) = crate::faults::postgres("the PostgreSQL upgrade test") else {
        return;
    };
    for schema in EARLIER_SCHEMAS {
        let dir = tempfile::tempdir().unwrap();
        let database = crate::faults::new_database(&cluster, &format!("upgrade_{schema}")).await;
        // The old server's database, as `pg_dump` wrote it.
        let load = std::process::Command::new("psql")
            .args(["-X", "-q", "-v", "ON_ERROR_STOP=1", "-d", &database, "-f"])
            .arg(fixture(&format!("schema-{schema}.pg.sql")))
            .output()
            .expect("psql runs");
        assert!(load.status.success(), "{schema}: {load:?}");
        an_earlier_schema_reads_the_same(dir.path(), &database, schema, &made_by(schema, "pg"))
            .await;
    }
}
