//! Rankings that state their uncertainty, on every surface: the `tournament` command
//! (JSON and table), the API's tournament and leaderboard, and the pages. Two bots with
//! the same program share a rank and a tie group, and a deterministic bot's interval has
//! zero width; a randomized bot's has not.

use serde_json::Value;

use crate::support::{TestServer, mazearena, mazearena_json, root, shared_maze};

/// A folder of three bots: two names for the simple bot, and the random explorer.
fn twins_and_a_random_bot(dir: &std::path::Path) -> std::path::PathBuf {
    let bots = dir.join("bots");
    std::fs::create_dir(&bots).unwrap();
    for f in [
        "simple_bot.py",
        "mazebot.py",
        "mazemap.py",
        "random_explorer.py",
    ] {
        std::fs::copy(root().join("bots/python").join(f), bots.join(f)).unwrap();
    }
    std::fs::write(
        bots.join("bot.toml"),
        "[[bot]]\nname = \"twin-a\"\ncommand = \"python3 simple_bot.py\"\n\n\
         [[bot]]\nname = \"twin-b\"\ncommand = \"python3 simple_bot.py\"\n\n\
         [[bot]]\nname = \"random\"\ncommand = \"python3 random_explorer.py\"\n",
    )
    .unwrap();
    bots
}

fn line<'a>(standings: &'a Value, name: &str) -> &'a Value {
    standings
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["name"] == name)
        .unwrap_or_else(|| panic!("no {name} in {standings}"))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn twins_share_a_rank_a_deterministic_bot_is_sure_and_a_random_one_is_not() {
    let dir = tempfile::tempdir().unwrap();
    let bots = twins_and_a_random_bot(dir.path());
    let db = format!("sqlite://{}", dir.path().join("t.db").display());
    let m1 = shared_maze("classic/test_maze_01.txt");
    let m2 = shared_maze("classic/test_maze_02.txt");
    let v = mazearena_json(&[
        "tournament",
        "--bots",
        bots.to_str().unwrap(),
        "--mazes",
        m1.to_str().unwrap(),
        m2.to_str().unwrap(),
        "--repeats",
        "3",
        "--database",
        &db,
        "--json",
    ]);
    let standings = &v["standings"];
    let (a, b, r) = (
        line(standings, "twin-a"),
        line(standings, "twin-b"),
        line(standings, "random"),
    );
    // The twins: one rank, one tie group, zero-width intervals at their mean.
    assert_eq!(a["rank"], b["rank"], "{standings}");
    assert_eq!(a["uncertainty"], b["uncertainty"], "{standings}");
    let u = &a["uncertainty"];
    assert_eq!(u["low"], a["mean_score"], "{standings}");
    assert_eq!(u["high"], a["mean_score"], "{standings}");
    assert_eq!(u["tied"], true, "{standings}");
    assert_eq!(u["runs_per_maze"], 3, "{standings}");
    // Listed by name within the tie.
    let names: Vec<&str> = standings
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    let (ia, ib) = (
        names.iter().position(|n| *n == "twin-a").unwrap(),
        names.iter().position(|n| *n == "twin-b").unwrap(),
    );
    assert_eq!(ib, ia + 1, "{names:?}");
    // The random explorer: its score depends on the seed, so its interval is wide and
    // holds its mean.
    let ru = &r["uncertainty"];
    let (low, high, mean) = (
        ru["low"].as_f64().unwrap(),
        ru["high"].as_f64().unwrap(),
        r["mean_score"].as_f64().unwrap(),
    );
    assert!(low < high && low <= mean && mean <= high, "{r}");
    assert_ne!(ru["tie_group"], u["tie_group"], "{standings}");

    // The same table from the server: the API's tournament and leaderboard, the pages.
    let server = TestServer::start_on(dir.path(), Some(&db), &["--jobs", "1"], &[]);
    let id = v["tournament_id"].as_i64().unwrap();
    let (s, t) = server.get(&format!("/api/tournaments/{id}"), None).await;
    assert_eq!(s, 200, "{t}");
    let (s, lb) = server
        .get(&format!("/api/leaderboard?tournament={id}"), None)
        .await;
    assert_eq!(s, 200, "{lb}");
    for served in [&t["standings"], &lb] {
        for name in ["twin-a", "twin-b", "random"] {
            assert_eq!(
                line(served, name)["uncertainty"],
                line(standings, name)["uncertainty"],
                "{served}"
            );
        }
    }
    let (_, all) = server.get("/api/leaderboard?scope=all", None).await;
    assert_eq!(line(&all, "twin-a")["uncertainty"]["tied"], true, "{all}");
    let (s, page) = server.get_text(&format!("/tournaments/{id}")).await;
    assert_eq!(s, 200);
    assert!(
        page.contains("95% interval")
            && page.contains("tied (group")
            && page.contains("equal means share a rank and are listed by name"),
        "{page}"
    );
    let (_, home) = server.get_text("/?scope=all").await;
    assert!(home.contains("95% interval"), "{home}");
}

#[test]
fn the_tournament_table_shows_intervals_tie_groups_and_its_rules() {
    let dir = tempfile::tempdir().unwrap();
    let bots = twins_and_a_random_bot(dir.path());
    std::fs::write(
        bots.join("bot.toml"),
        "[[bot]]\nname = \"twin-a\"\ncommand = \"python3 simple_bot.py\"\n\n\
         [[bot]]\nname = \"twin-b\"\ncommand = \"python3 simple_bot.py\"\n",
    )
    .unwrap();
    let out = mazearena(&[
        "tournament",
        "--bots",
        bots.to_str().unwrap(),
        "--mazes",
        shared_maze("classic/test_maze_01.txt").to_str().unwrap(),
        "--database",
        &format!("sqlite://{}", dir.path().join("t.db").display()),
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    let rows: Vec<&str> = text.lines().filter(|l| l.contains("twin-")).collect();
    assert_eq!(rows.len(), 2, "{text}");
    for row in rows {
        let cells: Vec<&str> = row.split_whitespace().collect();
        // rank, possible ranks, bot, mean, interval, tie group, ...
        assert_eq!((cells[0], cells[1]), ("1", "1"), "{text}");
        assert_eq!(cells[3], "22.133", "{text}");
        assert_eq!(cells[4], "22.133-22.133", "{text}");
        assert_eq!(cells[5], "=1", "{text}");
    }
    assert!(
        text.contains("95% interval") && text.contains("equal means share a rank (by name)"),
        "{text}"
    );
    assert!(text.contains("One run per maze"), "{text}");
}
