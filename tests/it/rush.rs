//! The deadline rush: a class of students through a real nginx, each as a browser does it
//! (register with the invite code, log in, upload an original-task robot.py through the
//! submission form, wait until it is ready, play two practice matches), all at once,
//! while a tournament keeps every worker busy. Behind one address (`--trusted-proxies`
//! off: everyone is nginx) and from two client addresses (`--trusted-proxies` naming
//! nginx). No right key or code is ever refused, and no upload is lost.
//! (`benches/rush.sh` does the same with 300 students and reports the times.)

use std::time::{Duration, Instant};

use serde_json::{Value, json};

use crate::support::{ADMIN, Nginx, TestServer, client_from, root, simple_bot_files};

/// How many students take part in each run.
const STUDENTS: usize = 30;

/// The invite code of the class.
const CODE: &str = "rush-hour-2026";

/// What happened to one student.
#[derive(Debug, Default)]
struct Report {
    /// Answers 429 to a request that proved who it was (a right code, key or session).
    refusals: Vec<String>,
    /// Anything else that went wrong (an upload that never became a ready version).
    failures: Vec<String>,
    /// From the upload's answer to the version's `ready`, in ms.
    upload_to_ready_ms: Option<u128>,
}

/// A student's browser: its client (from its address) and its session cookie.
struct Student {
    http: reqwest::Client,
    base: String,
    session: Option<String>,
    report: Report,
}

/// The value of `name="csrf"` in a page.
fn csrf(page: &str) -> Option<String> {
    let at = page.find("name=\"csrf\" value=\"")? + "name=\"csrf\" value=\"".len();
    Some(page[at..at + page[at..].find('"')?].to_string())
}

impl Student {
    fn cookie(&self) -> String {
        format!(
            "mazearena_session={}",
            self.session.clone().unwrap_or_default()
        )
    }

    /// Sends `r` (with the session), noting a 429 as a refusal of `what`; the status,
    /// the body, and a new session cookie if one was set.
    async fn send(&mut self, what: &str, r: reqwest::RequestBuilder) -> (u16, String) {
        let response = r
            .header("cookie", self.cookie())
            .send()
            .await
            .unwrap_or_else(|e| panic!("{what}: {e}"));
        let status = response.status().as_u16();
        for v in response.headers().get_all("set-cookie") {
            if let Some(s) = v
                .to_str()
                .ok()
                .and_then(|c| c.split(';').next())
                .and_then(|c| c.strip_prefix("mazearena_session="))
                .filter(|s| !s.is_empty())
            {
                self.session = Some(s.to_string());
            }
        }
        let body = response.text().await.unwrap_or_default();
        if status == 429 {
            self.report.refusals.push(format!("{what}: {body}"));
        }
        (status, body)
    }

    /// GET `path` of the API with `key`: its JSON.
    async fn api(&self, path: &str, key: &str) -> Value {
        let r = self.http.get(format!("{}{path}", self.base));
        r.bearer_auth(key)
            .send()
            .await
            .unwrap()
            .json()
            .await
            .unwrap()
    }

    async fn get(&mut self, what: &str, path: &str) -> (u16, String) {
        let r = self.http.get(format!("{}{path}", self.base));
        self.send(what, r).await
    }

    /// The whole journey of student `i`.
    async fn take_part(mut self, i: usize, robot: String) -> Report {
        let name = format!("student-{i}");
        self.get("the registration page", "/register").await;
        let r = self
            .http
            .post(format!("{}/register", self.base))
            .form(&[("name", name.as_str()), ("invite_code", CODE)]);
        let (status, page) = self.send("registering with the right code", r).await;
        let Some(key) = page
            .find("id=\"new-key\"")
            .and_then(|at| {
                let rest = &page[at..];
                let start = rest.find('>')? + 1;
                Some(
                    rest[start..start + rest[start..].find('<')?]
                        .trim()
                        .to_string(),
                )
            })
            .filter(|_| status == 200)
        else {
            self.report
                .failures
                .push(format!("registration answered {status}"));
            return self.report;
        };
        let r = self
            .http
            .post(format!("{}/login", self.base))
            .form(&[("key", key.as_str())]);
        let (status, _) = self.send("logging in with the right key", r).await;
        if status != 303 {
            self.report
                .failures
                .push(format!("login answered {status}"));
            return self.report;
        }
        let (_, page) = self
            .get("the submission page", "/competitions/rush/submit")
            .await;
        let Some(token) = csrf(&page) else {
            self.report.failures.push("no submission form".into());
            return self.report;
        };
        let form = reqwest::multipart::Form::new()
            .text("csrf", token)
            .text("name", format!("robot-{i}"))
            .text("original_task", "true")
            .part(
                "files",
                reqwest::multipart::Part::bytes(robot.into_bytes()).file_name("robot.py"),
            );
        let r = self
            .http
            .post(format!("{}/competitions/rush/submit", self.base))
            .multipart(form);
        let (status, body) = self.send("uploading", r).await;
        let uploaded = Instant::now();
        if status != 303 {
            self.report
                .failures
                .push(format!("upload answered {status}: {body}"));
            return self.report;
        }
        // Ready: the student's page says so (the API, with the key, for the test).
        let me = self.api("/api/me", &key).await;
        let Some(bot) = me["bots"][0]["bot_id"].as_i64() else {
            self.report
                .failures
                .push(format!("the upload was lost: {me}"));
            return self.report;
        };
        let deadline = Instant::now() + Duration::from_secs(600);
        loop {
            let v = self.api(&format!("/api/bots/{bot}"), &key).await;
            match v["versions"][0]["build_status"].as_str() {
                Some("ready") => break,
                Some("building") if Instant::now() < deadline => {}
                other => {
                    self.report
                        .failures
                        .push(format!("the version never became ready: {other:?} {v}"));
                    return self.report;
                }
            }
            tokio::time::sleep(Duration::from_millis(250)).await;
        }
        self.report.upload_to_ready_ms = Some(uploaded.elapsed().as_millis());
        // Two practice matches, each with the button on the student's page.
        let mut matches = Vec::new();
        for _ in 0..2 {
            let (_, page) = self.get("the student's page", "/me").await;
            let (Some(token), Some(maze)) = (
                csrf(&page),
                page.find("name=\"maze_id\"").and_then(|at| {
                    let rest = &page[at..];
                    let start = rest.find("option value=\"")? + "option value=\"".len();
                    Some(rest[start..start + rest[start..].find('"')?].to_string())
                }),
            ) else {
                self.report.failures.push("no practice form".into());
                return self.report;
            };
            let r = self.http.post(format!("{}/me/practice", self.base)).form(&[
                ("csrf", token.as_str()),
                ("bot_id", bot.to_string().as_str()),
                ("maze_id", maze.as_str()),
            ]);
            let response = r.header("cookie", self.cookie()).send().await.unwrap();
            let status = response.status().as_u16();
            let location = response
                .headers()
                .get("location")
                .and_then(|l| l.to_str().ok())
                .unwrap_or("")
                .to_string();
            if status == 429 {
                self.report.refusals.push("practice".into());
            }
            match location
                .strip_prefix("/matches/")
                .and_then(|m| m.parse::<i64>().ok())
            {
                Some(id) if status == 303 => matches.push(id),
                _ => {
                    self.report
                        .failures
                        .push(format!("practice answered {status}"));
                    return self.report;
                }
            }
        }
        for id in matches {
            let deadline = Instant::now() + Duration::from_secs(600);
            loop {
                let (_, body) = self
                    .get("a practice match", &format!("/api/matches/{id}"))
                    .await;
                let v: Value = serde_json::from_str(&body).unwrap_or(Value::Null);
                match v["status"].as_str() {
                    Some("finished" | "step_limit") => break,
                    Some("queued" | "running") if Instant::now() < deadline => {}
                    other => {
                        self.report
                            .failures
                            .push(format!("practice match {id}: {other:?}"));
                        break;
                    }
                }
                tokio::time::sleep(Duration::from_millis(500)).await;
            }
        }
        self.report
    }
}

/// One rush: a server (`trusted`: naming nginx as a trusted proxy) behind nginx, a
/// competition and a busy tournament, and `STUDENTS` students from `addresses` in turn.
async fn rush(trusted: bool, addresses: &[&str]) -> Option<Vec<Report>> {
    let dir = tempfile::tempdir().unwrap();
    let mut extra = vec![];
    if trusted {
        extra.extend(["--trusted-proxies", "127.0.0.1"]);
    }
    // The server's own limits, not the tests' relaxed ones.
    let server = TestServer::start_env(
        dir.path(),
        &extra,
        &[
            ("MAZEARENA_REGISTRATIONS_PER_HOUR", "20"),
            ("MAZEARENA_VERSIONS_PER_DAY", "20"),
            ("MAZEARENA_PENDING_BUILDS_PER_OWNER", "3"),
        ],
    );
    let nginx = Nginx::start(&server.base, "the deadline rush")?;
    let (s, v, _) = server
        .call(
            reqwest::Method::PUT,
            "/api/registration",
            Some(json!({"mode": "invite", "invite_code": CODE})),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 200, "{v}");
    let (s, o) = server
        .post("/api/organisers", json!({"name": "teacher"}), Some(ADMIN))
        .await;
    assert_eq!(s, 201, "{o}");
    let layout = |seed| {
        mazearena::engine::mazefile::numeric::write(
            &mazearena::engine::generator::generate(12, seed).unwrap(),
        )
    };
    let now = mazearena::storage::now_ms();
    let spec = json!({
        "name": "rush", "title": "Rush hour",
        "opens_at": mazearena::competition::Timestamp(now - 1_000).rfc3339(),
        "closes_at": mazearena::competition::Timestamp(now + 3_600_000).rfc3339(),
        "repeats": 1, "versions_per_day": 5, "practice_per_day": 5,
        "mazes": {"practice": [{"name": "rush-practice", "layout": layout(4801)}],
                  "public": [{"name": "rush-public", "layout": layout(4802)}],
                  "private": [{"name": "rush-private", "layout": layout(4803)}]},
    });
    let (s, c) = server
        .post("/api/competitions", spec, Some(o["key"].as_str().unwrap()))
        .await;
    assert_eq!(s, 201, "{c}");
    // Every worker busy: a tournament of two bots on every shipped maze, many times.
    let mut bots = Vec::new();
    for name in ["busy-a", "busy-b"] {
        let (s, b) = server
            .post(
                "/api/bots",
                json!({"name": name, "command": "python3 simple_bot.py", "files": simple_bot_files()}),
                Some(ADMIN),
            )
            .await;
        assert_eq!(s, 201, "{b}");
        bots.push(b["bot_id"].as_i64().unwrap());
    }
    let (s, t) = server
        .post(
            "/api/tournaments",
            json!({"name": "busy", "bot_ids": bots, "maze_ids": (1..=9).collect::<Vec<i64>>(), "repeats": 20}),
            Some(ADMIN),
        )
        .await;
    assert_eq!(s, 202, "{t}");
    let robot = std::fs::read_to_string(root().join("tests/fixtures/robot_py/robot.py")).unwrap();
    let students: Vec<_> = (0..STUDENTS)
        .map(|i| {
            let student = Student {
                http: client_from(addresses[i % addresses.len()]),
                base: nginx.base.clone(),
                session: None,
                report: Report::default(),
            };
            tokio::spawn(student.take_part(i, robot.clone()))
        })
        .collect();
    let mut reports = Vec::new();
    for s in students {
        reports.push(s.await.unwrap());
    }
    // The tournament was still playing: the workers were busy all along.
    let (_, t) = server
        .get(&format!("/api/tournaments/{}", t["tournament_id"]), None)
        .await;
    assert!(
        t["done"].as_i64() < t["total"].as_i64(),
        "the tournament ended before the rush did: the test proves nothing: {t}"
    );
    Some(reports)
}

/// The zeros the rush must show, and its times, printed.
fn check(what: &str, reports: &[Report]) {
    let refusals: Vec<&String> = reports.iter().flat_map(|r| &r.refusals).collect();
    let failures: Vec<&String> = reports.iter().flat_map(|r| &r.failures).collect();
    let mut ready: Vec<u128> = reports
        .iter()
        .filter_map(|r| r.upload_to_ready_ms)
        .collect();
    ready.sort_unstable();
    eprintln!(
        "{what}: {} students, upload to ready median {} ms, worst {} ms",
        reports.len(),
        ready.get(ready.len() / 2).copied().unwrap_or(0),
        ready.last().copied().unwrap_or(0)
    );
    assert!(
        refusals.is_empty(),
        "{what}: right keys or codes refused: {refusals:?}"
    );
    assert!(failures.is_empty(), "{what}: {failures:?}");
    assert_eq!(ready.len(), reports.len(), "{what}: uploads lost");
}

#[test]
fn a_deadline_rush_through_nginx_refuses_no_right_key_and_loses_no_upload() {
    let _heavy = crate::support::heavy();
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    runtime.block_on(async {
        let Some(one) = rush(false, &["127.0.0.1"]).await else {
            return;
        };
        check("behind one address (trusted proxies off)", &one);
        let Some(two) = rush(true, &["127.0.0.2", "127.0.0.3"]).await else {
            return;
        };
        check("from two addresses (trusted proxies on)", &two);
    });
}
