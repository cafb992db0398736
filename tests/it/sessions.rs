//! The browser's way in, attacked over real HTTP: sessions (stored hashed, ended by
//! logout and by key rotation, a stolen or ended cookie, fixation), cross-site form
//! posts, login guessing, markup in every field a user sets, framing, an upload bomb
//! through the form, and form errors answered as pages.

use std::io::Write;

use reqwest::header::HeaderMap;
use serde_json::json;

use super::support::{ADMIN, TestServer, simple_bot_files};

/// A client of the pages that follows no redirect and keeps no cookie of its own.
pub(crate) struct Web {
    pub(crate) base: String,
    pub(crate) http: reqwest::Client,
    /// The session cookie's name: `__Host-mazearena_session` for a server reached over
    /// HTTPS (`--secure-cookies`).
    pub(crate) cookie: &'static str,
}

/// An answer: status, headers, body.
pub(crate) struct Answer {
    pub(crate) status: u16,
    pub(crate) headers: HeaderMap,
    pub(crate) body: String,
}

impl Answer {
    /// The session cookie's value this answer sets, if any.
    pub(crate) fn session(&self) -> Option<String> {
        self.set_cookie().and_then(|c| {
            let pair = c.split(';').next()?;
            pair.strip_prefix("mazearena_session=")
                .or_else(|| pair.strip_prefix("__Host-mazearena_session="))
                .map(str::to_string)
        })
    }

    fn set_cookie(&self) -> Option<String> {
        self.headers
            .get_all("set-cookie")
            .iter()
            .filter_map(|v| v.to_str().ok())
            .find(|v| {
                v.starts_with("mazearena_session=") || v.starts_with("__Host-mazearena_session=")
            })
            .map(str::to_string)
    }

    fn location(&self) -> String {
        self.headers
            .get("location")
            .and_then(|v| v.to_str().ok())
            .unwrap_or("")
            .to_string()
    }

    /// The first form's anti-forgery token in the page.
    pub(crate) fn csrf(&self) -> String {
        let at = self
            .body
            .find("name=\"csrf\" value=\"")
            .unwrap_or_else(|| panic!("no form token in {}", self.body));
        let rest = &self.body[at + "name=\"csrf\" value=\"".len()..];
        rest[..rest.find('"').unwrap()].to_string()
    }
}

impl Web {
    pub(crate) fn new(server: &TestServer) -> Web {
        Web {
            base: server.base.clone(),
            http: reqwest::Client::builder()
                .redirect(reqwest::redirect::Policy::none())
                .build()
                .unwrap(),
            cookie: "mazearena_session",
        }
    }

    /// A client of a server started with `--secure-cookies` (its session cookie is
    /// `__Host-mazearena_session`).
    pub(crate) fn secure(server: &TestServer) -> Web {
        Web {
            cookie: "__Host-mazearena_session",
            ..Web::new(server)
        }
    }

    async fn answer(r: reqwest::RequestBuilder) -> Answer {
        let response = r.send().await.unwrap();
        Answer {
            status: response.status().as_u16(),
            headers: response.headers().clone(),
            body: response.text().await.unwrap(),
        }
    }

    pub(crate) async fn get(&self, path: &str, session: Option<&str>) -> Answer {
        let mut r = self.http.get(format!("{}{path}", self.base));
        if let Some(s) = session {
            r = r.header("cookie", format!("{}={s}", self.cookie));
        }
        Web::answer(r).await
    }

    /// Posts a urlencoded form as a browser on this site would (same-origin headers).
    pub(crate) async fn post(
        &self,
        path: &str,
        session: Option<&str>,
        fields: &[(&str, &str)],
    ) -> Answer {
        self.post_from(path, session, fields, Some(&self.base))
            .await
    }

    /// Posts a form with `Origin: origin` (None: no Origin, like curl).
    async fn post_from(
        &self,
        path: &str,
        session: Option<&str>,
        fields: &[(&str, &str)],
        origin: Option<&str>,
    ) -> Answer {
        let mut r = self.http.post(format!("{}{path}", self.base)).form(fields);
        if let Some(s) = session {
            r = r.header("cookie", format!("{}={s}", self.cookie));
        }
        if let Some(o) = origin {
            r = r.header("origin", o);
        }
        Web::answer(r).await
    }

    /// Logs in with `key`; answers the new session's cookie value.
    pub(crate) async fn login(&self, key: &str) -> String {
        let a = self.post("/login", None, &[("key", key)]).await;
        assert_eq!(a.status, 303, "{}", a.body);
        a.session().expect("a session cookie")
    }
}

/// Registers an entrant through the API; answers its id and key.
async fn entrant(server: &TestServer, name: &str) -> (i64, String) {
    let (s, v) = server
        .post("/api/entrants", json!({"name": name}), None)
        .await;
    assert_eq!(s, 201, "{v}");
    (
        v["entrant_id"].as_i64().unwrap(),
        v["key"].as_str().unwrap().to_string(),
    )
}

fn sha256_hex(text: &str) -> String {
    mazearena::registry::tokens::hash_token(text)
}

#[tokio::test]
async fn sessions_are_hashed_ended_by_logout_and_rotation_and_never_taken_from_the_visitor() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--no-validation"]);
    let web = Web::new(&server);
    let (id, key) = entrant(&server, "ada").await;

    // A wrong key opens nothing, and says so in the page.
    let wrong = web.post("/login", None, &[("key", "not-a-key")]).await;
    assert_eq!(wrong.status, 401);
    assert!(wrong.session().is_none());
    assert!(
        wrong.headers["content-type"]
            .to_str()
            .unwrap()
            .starts_with("text/html")
    );
    assert!(
        wrong.body.contains("not known on this server"),
        "{}",
        wrong.body
    );

    // Login: a cookie that is HttpOnly, SameSite=Strict, for the whole site, expiring.
    let login = web
        .post("/login", None, &[("key", &key), ("next", "/competitions")])
        .await;
    assert_eq!(login.status, 303);
    assert_eq!(login.location(), "/competitions");
    let cookie = login.set_cookie().unwrap();
    for part in ["HttpOnly", "SameSite=Strict", "Path=/", "Max-Age="] {
        assert!(cookie.contains(part), "{cookie} lacks {part}");
    }
    assert!(!cookie.contains("Secure"), "plain HTTP here: {cookie}");
    let session = login.session().unwrap();
    let me = web.get("/me", Some(&session)).await;
    assert_eq!(me.status, 200);
    assert!(me.body.contains("entrant ada"), "{}", me.body);
    // A login may only send the browser on within this site.
    let away = web
        .post("/login", None, &[("key", &key), ("next", "//evil.test/x")])
        .await;
    assert_eq!(away.location(), "/me");

    // Stored hashed: the database knows the cookie's SHA-256, not the cookie.
    let storage = mazearena::storage::Storage::open(&server.database)
        .await
        .unwrap();
    assert_eq!(
        storage.session_key(&sha256_hex(&session)).await.unwrap(),
        Some(sha256_hex(&key))
    );
    assert_eq!(storage.session_key(&session).await.unwrap(), None);

    // A stolen copy of the cookie works only as long as the session: logout ends it on
    // the server, so the copy opens nothing either.
    let thief = session.clone();
    let me = web.get("/me", Some(&thief)).await;
    assert_eq!(me.status, 200);
    let logout = web
        .post("/logout", Some(&session), &[("csrf", &me.csrf())])
        .await;
    assert_eq!(logout.status, 303);
    assert!(logout.set_cookie().unwrap().contains("Max-Age=0"));
    let after = web.get("/me", Some(&thief)).await;
    assert_eq!(after.status, 303);
    assert!(
        after.location().starts_with("/login"),
        "{}",
        after.location()
    );

    // An ended session (its time is up) opens nothing.
    storage
        .create_session(&sha256_hex("expired-secret"), &sha256_hex(&key), 1)
        .await
        .unwrap();
    assert_eq!(web.get("/me", Some("expired-secret")).await.status, 303);

    // Fixation: a cookie planted before the login is never the session; the login makes
    // a new one, and a session the browser had before ends.
    let planted = web.post_from("/login", None, &[("key", &key)], None).await;
    let planted = planted.session().unwrap();
    let r = web
        .http
        .post(format!("{}/login", server.base))
        .header("cookie", format!("mazearena_session={planted}"))
        .header("origin", &server.base)
        .form(&[("key", key.as_str())]);
    let relogin = Web::answer(r).await;
    let fresh = relogin.session().unwrap();
    assert_ne!(fresh, planted);
    assert_eq!(
        web.get("/me", Some(&planted)).await.status,
        303,
        "the old session ended"
    );
    let chosen = Web::answer(
        web.http
            .post(format!("{}/login", server.base))
            .header("cookie", "mazearena_session=attacker-chosen-value")
            .form(&[("key", key.as_str())]),
    )
    .await;
    assert_ne!(chosen.session().as_deref(), Some("attacker-chosen-value"));
    assert_eq!(
        web.get("/me", Some("attacker-chosen-value")).await.status,
        303
    );

    // Rotating the entrant's key ends its sessions, and those of its bots' owner tokens.
    let (s, bot) = server
        .post(
            "/api/bots",
            json!({"name": "ada-bot", "command": "python3 simple_bot.py", "files": simple_bot_files()}),
            Some(&key),
        )
        .await;
    assert_eq!(s, 201, "{bot}");
    let owner = web.login(bot["owner_token"].as_str().unwrap()).await;
    assert_eq!(web.get("/me", Some(&owner)).await.status, 200);
    assert_eq!(web.get("/me", Some(&fresh)).await.status, 200);
    let (s, rotated) = server
        .post(&format!("/api/entrants/{id}/key"), json!({}), Some(&key))
        .await;
    assert_eq!(s, 200, "{rotated}");
    assert_eq!(storage.sessions_of_key(&sha256_hex(&key)).await.unwrap(), 0);
    assert_eq!(web.get("/me", Some(&fresh)).await.status, 303);
    assert_eq!(web.get("/me", Some(&owner)).await.status, 303);
    // The new key logs in.
    let new_key = rotated["key"].as_str().unwrap();
    let mine = web.login(new_key).await;
    assert_eq!(web.get("/me", Some(&mine)).await.status, 200);
    // From the browser: "replace my key" shows the new key once, keeps the visitor in
    // with a new session, and ends the old key's.
    let other = web.login(new_key).await;
    let token = web.get("/me", Some(&mine)).await.csrf();
    // A copied session alone does not replace the key: the form asks for the key.
    for wrong in ["", "not-the-key", key.as_str()] {
        let page = web
            .post(
                "/me/key",
                Some(&mine),
                &[("csrf", &token), ("current_key", wrong)],
            )
            .await;
        assert_eq!(page.status, 403, "{wrong:?}: {}", page.body);
        assert!(
            page.body.contains("that is not your current key")
                && page.body.contains("role=\"alert\""),
            "{}",
            page.body
        );
        assert_eq!(web.get("/me", Some(&mine)).await.status, 200, "still in");
        assert_eq!(web.get("/me", Some(&other)).await.status, 200);
    }
    let (s, _) = server.get("/api/me", Some(new_key)).await;
    assert_eq!(s, 200, "the key stays");
    let page = web
        .post(
            "/me/key",
            Some(&mine),
            &[("csrf", &token), ("current_key", new_key)],
        )
        .await;
    assert_eq!(page.status, 200, "{}", page.body);
    assert_eq!(page.headers["cache-control"], "no-store");
    let newest = {
        let at = page.body.find("id=\"new-key\">").unwrap() + "id=\"new-key\">".len();
        page.body[at..at + 64].to_string()
    };
    assert_ne!(newest, new_key);
    let kept = page.session().expect("a new session");
    assert_eq!(web.get("/me", Some(&kept)).await.status, 200);
    assert_eq!(web.get("/me", Some(&mine)).await.status, 303);
    assert_eq!(web.get("/me", Some(&other)).await.status, 303);
    let (s, _) = server.get("/api/me", Some(new_key)).await;
    assert_eq!(s, 401, "the replaced key is dead");
    let (s, _) = server.get("/api/me", Some(&newest)).await;
    assert_eq!(s, 200);
}

#[tokio::test]
async fn cross_site_form_posts_are_refused_and_the_api_ignores_the_cookie() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--no-validation"]);
    let web = Web::new(&server);
    let (_, key) = entrant(&server, "bo").await;
    let (s, bot) = server
        .post(
            "/api/bots",
            json!({"name": "bo-bot", "command": "python3 simple_bot.py", "files": simple_bot_files()}),
            Some(&key),
        )
        .await;
    assert_eq!(s, 201, "{bot}");
    let bot_id = bot["bot_id"].as_i64().unwrap().to_string();
    let session = web.login(&key).await;
    let token = web.get("/me", Some(&session)).await.csrf();
    let fields = [
        ("csrf", token.as_str()),
        ("bot_id", bot_id.as_str()),
        ("maze_id", "1"),
    ];
    let queued = || async {
        let (_, v) = server
            .get(&format!("/api/matches?bot_id={bot_id}"), None)
            .await;
        v["items"].as_array().unwrap().len()
    };

    // Another site's page posting the form with the visitor's cookie: refused before
    // anything is read, by its Origin or by Sec-Fetch-Site.
    let evil = web
        .post_from(
            "/me/practice",
            Some(&session),
            &fields,
            Some("http://evil.test"),
        )
        .await;
    assert_eq!(evil.status, 403, "{}", evil.body);
    assert!(evil.body.contains("another site"), "{}", evil.body);
    let r = web
        .http
        .post(format!("{}/me/practice", server.base))
        .header("cookie", format!("mazearena_session={session}"))
        .header("sec-fetch-site", "cross-site")
        .form(&fields);
    assert_eq!(Web::answer(r).await.status, 403);
    // Logging in from another site is refused too (login CSRF).
    let login = web
        .post_from("/login", None, &[("key", &key)], Some("http://evil.test"))
        .await;
    assert_eq!(login.status, 403);
    assert!(login.session().is_none());
    // Without the form's token (or with another session's), nothing is done.
    let other = web.login(&key).await;
    let other_token = web.get("/me", Some(&other)).await.csrf();
    for bad in ["", "0000", other_token.as_str()] {
        let a = web
            .post(
                "/me/practice",
                Some(&session),
                &[("csrf", bad), ("bot_id", &bot_id), ("maze_id", "1")],
            )
            .await;
        assert_eq!(a.status, 403, "token {bad:?}: {}", a.body);
        assert!(
            a.headers["content-type"]
                .to_str()
                .unwrap()
                .starts_with("text/html")
        );
    }
    assert_eq!(queued().await, 0, "no refused form queued a match");
    // The same form from this site, with its token: done.
    let ok = web.post("/me/practice", Some(&session), &fields).await;
    assert_eq!(ok.status, 303, "{}", ok.body);
    assert!(ok.location().starts_with("/matches/"));
    assert_eq!(queued().await, 1);

    // The JSON API never reads the cookie: a cross-site request to it has no authority.
    let r = web
        .http
        .post(format!("{}/api/matches", server.base))
        .header("cookie", format!("mazearena_session={session}"))
        .json(&json!({"bot_id": bot_id.parse::<i64>().unwrap(), "maze_id": 1}));
    assert_eq!(Web::answer(r).await.status, 401);
}

#[tokio::test]
async fn login_guessing_is_limited_per_address_and_a_right_key_always_logs_in() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start_env(
        dir.path(),
        &["--no-validation"],
        &[("MAZEARENA_LOGINS_PER_HOUR", "5")],
    );
    let web = Web::new(&server);
    let (_, key) = entrant(&server, "cy").await;
    // Right keys spend nothing: more logins than the budget of guesses.
    for _ in 0..8 {
        web.login(&key).await;
    }
    for i in 0..5 {
        let a = web
            .post("/login", None, &[("key", &format!("guess-{i}"))])
            .await;
        assert_eq!(a.status, 401, "try {i}");
    }
    let limited = web.post("/login", None, &[("key", "guess-5")]).await;
    assert_eq!(limited.status, 429);
    assert!(limited.headers.contains_key("retry-after"));
    assert!(limited.body.contains("your network"), "{}", limited.body);
    assert!(!limited.body.contains("127.0.0.1"), "{}", limited.body);
    assert!(
        limited.headers["content-type"]
            .to_str()
            .unwrap()
            .starts_with("text/html")
    );
    // Past the limit the right key still logs in, and so does the admin's: guessing
    // from the same address locks nobody out.
    web.login(&key).await;
    web.login(ADMIN).await;
    // Wrong keys stay refused.
    let again = web.post("/login", None, &[("key", "guess-6")]).await;
    assert_eq!(again.status, 429);
}

/// A payload that runs if a page puts it into its markup unescaped.
const XSS: &str = "<script>alert('xss')</script><img src=x onerror=alert(1)>";

#[tokio::test]
async fn markup_in_every_field_a_user_sets_stays_text_and_pages_cannot_be_framed() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &[]);
    let web = Web::new(&server);
    // An organiser's competition whose texts are markup.
    let (s, o) = server
        .post("/api/organisers", json!({"name": XSS}), Some(ADMIN))
        .await;
    assert_eq!(s, 201, "{o}");
    let organiser = o["key"].as_str().unwrap().to_string();
    let now = mazearena::storage::now_ms();
    let maze = |n: u64| {
        json!({"name": format!("m{n}"), "layout": mazearena::engine::mazefile::numeric::write(
            &mazearena::engine::generator::generate(12, n).unwrap())})
    };
    let spec = json!({
        "name": "xss-cup", "title": XSS, "description": XSS, "rules": XSS,
        "opens_at": mazearena::competition::Timestamp(now - 1000).rfc3339(),
        "closes_at": mazearena::competition::Timestamp(now + 3_600_000).rfc3339(),
        "repeats": 1,
        "mazes": {"practice": [maze(9101)], "public": [maze(9102)], "private": [maze(9103)]},
    });
    let (s, c) = server
        .post("/api/competitions", spec, Some(&organiser))
        .await;
    assert_eq!(s, 201, "{c}");
    // An entrant whose members are markup, through the registration form.
    let reg = web
        .post("/register", None, &[("name", "dee"), ("members", XSS)])
        .await;
    assert_eq!(reg.status, 200, "{}", reg.body);
    let session = reg.session().unwrap();
    let key = {
        let at = reg.body.find("id=\"new-key\">").unwrap() + "id=\"new-key\">".len();
        reg.body[at..at + 64].to_string()
    };
    // A bot whose build log and stderr are markup, and one file whose name is.
    let mut files = simple_bot_files();
    files["main.py"] = json!(format!(
        "import sys, runpy\nsys.stderr.write({XSS:?} + '\\n')\nsys.stderr.flush()\n\
         sys.argv = ['simple_bot.py']\nrunpy.run_path('simple_bot.py', run_name='__main__')\n"
    ));
    let (s, bot) = server
        .post(
            "/api/bots",
            json!({"name": "dee-bot", "command": "python3 main.py", "files": files,
                   "build": format!("echo {XSS:?}")}),
            Some(&key),
        )
        .await;
    assert_eq!(s, 201, "{bot}");
    let bot_id = bot["bot_id"].as_i64().unwrap();
    let built = super::support::wait_built(&server, bot_id).await;
    assert_eq!(built["build_status"], "ready", "{built}");
    let (s, e) = server
        .post(
            "/api/competitions/xss-cup/entries",
            json!({"bot_id": bot_id}),
            Some(&key),
        )
        .await;
    assert_eq!(s, 201, "{e}");
    let practice = c["mazes"][0]["maze_id"].as_i64().unwrap();
    let m = super::support::queue(&server, bot_id, practice, 7, &key).await;
    super::support::wait_match(&server, m).await;
    // A file name that is markup, through the submission form: refused or stored, its
    // name never becomes markup.
    let form = reqwest::multipart::Form::new()
        .text("csrf", web.get("/me", Some(&session)).await.csrf())
        .part(
            "files",
            reqwest::multipart::Part::text("print(1)").file_name(format!("{XSS}.py")),
        )
        .text("command", "python3 x.py");
    let r = web
        .http
        .post(format!("{}/competitions/xss-cup/submit", server.base))
        .header("cookie", format!("mazearena_session={session}"))
        .multipart(form);
    let upload = Web::answer(r).await;
    assert!(!upload.body.contains(XSS), "the upload's answer");

    let owner = web.login(&key).await;
    let admin = web.login(ADMIN).await;
    let pages = [
        ("/competitions/xss-cup", None),
        ("/competitions", None),
        ("/", None),
        ("/me", Some(owner.as_str())),
        (&format!("/matches/{m}") as &str, Some(owner.as_str())),
        ("/competitions/xss-cup/submit", Some(owner.as_str())),
        ("/admin", Some(admin.as_str())),
        ("/competitions/xss-cup/manage", Some(admin.as_str())),
        ("/organise", Some(admin.as_str())),
        (&format!("/bots/{bot_id}") as &str, None),
    ];
    for (path, session) in pages {
        let a = web.get(path, session).await;
        assert_eq!(a.status, 200, "{path}: {}", a.body);
        assert!(
            !a.body.contains(XSS),
            "{path} puts the payload into its markup"
        );
        assert!(
            !a.body.contains("<img src=x"),
            "{path} puts an element of the payload into its markup"
        );
        // Framing is refused by both headers, and the policy has no unsafe-inline.
        assert_eq!(a.headers["x-frame-options"], "DENY", "{path}");
        let csp = a.headers["content-security-policy"].to_str().unwrap();
        assert!(csp.contains("frame-ancestors 'none'"), "{path}: {csp}");
        assert!(!csp.contains("unsafe-inline"), "{path}: {csp}");
    }
    // The payload is there, as text: the owner sees the build log and the stderr.
    let me = web.get("/me", Some(&owner)).await;
    assert!(
        me.body.contains("&lt;script&gt;alert("),
        "the build log as text"
    );
    let replay = web.get(&format!("/matches/{m}"), Some(&owner)).await;
    assert!(
        replay.body.contains("\\u003cscript\\u003ealert("),
        "the stderr, escaped in the viewer's data"
    );
    assert!(replay.body.contains("\"stderr_hidden\":false"));
    // The bot's page shows its owner the build log, and nobody else.
    let mine = web.get(&format!("/bots/{bot_id}"), Some(&owner)).await;
    assert!(mine.body.contains("owner-build-log"), "{}", mine.body);
    let theirs = web.get(&format!("/bots/{bot_id}"), None).await;
    assert!(!theirs.body.contains("owner-build-log"));
    // Anyone else sees the replay without the owner's stderr.
    let public = web.get(&format!("/matches/{m}"), None).await;
    assert!(public.body.contains("\"stderr_hidden\":true"));
    assert!(!public.body.contains("\\u003cscript\\u003ealert("));
}

/// A `.zip` holding `size` zero bytes (a few KiB compressed).
fn zip_bomb(size: usize) -> Vec<u8> {
    let mut out = std::io::Cursor::new(Vec::new());
    let mut zip = zip::ZipWriter::new(&mut out);
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .large_file(true);
    zip.start_file("robot.py", options).unwrap();
    let chunk = vec![0u8; 1 << 20];
    for _ in 0..size / chunk.len() {
        zip.write_all(&chunk).unwrap();
    }
    zip.finish().unwrap();
    out.into_inner()
}

#[tokio::test]
async fn an_upload_bomb_through_the_form_is_refused_in_the_page_and_stores_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--no-validation"]);
    let web = Web::new(&server);
    let (s, o) = server
        .post("/api/organisers", json!({"name": "t"}), Some(ADMIN))
        .await;
    assert_eq!(s, 201);
    let now = mazearena::storage::now_ms();
    let layout = |seed| {
        mazearena::engine::mazefile::numeric::write(
            &mazearena::engine::generator::generate(12, seed).unwrap(),
        )
    };
    let spec = json!({
        "name": "bomb-cup", "title": "Bombs",
        "opens_at": mazearena::competition::Timestamp(now - 1000).rfc3339(),
        "closes_at": mazearena::competition::Timestamp(now + 3_600_000).rfc3339(),
        "mazes": {"public": [{"name": "p", "layout": layout(4)}],
                  "private": [{"name": "q", "layout": layout(5)}]},
    });
    let (s, c) = server
        .post("/api/competitions", spec, Some(o["key"].as_str().unwrap()))
        .await;
    assert_eq!(s, 201, "{c}");
    let (_, key) = entrant(&server, "eve").await;
    let session = web.login(&key).await;
    let token = web
        .get("/competitions/bomb-cup/submit", Some(&session))
        .await
        .csrf();
    let bomb = zip_bomb(200 << 20);
    assert!(
        bomb.len() < 2 << 20,
        "a small archive: {} bytes",
        bomb.len()
    );
    let form = reqwest::multipart::Form::new()
        .text("csrf", token)
        .text("name", "eve-bot")
        .part(
            "archive",
            reqwest::multipart::Part::bytes(bomb).file_name("bot.zip"),
        )
        .text("original_task", "true");
    let r = web
        .http
        .post(format!("{}/competitions/bomb-cup/submit", server.base))
        .header("cookie", format!("mazearena_session={session}"))
        .header("origin", &server.base)
        .multipart(form);
    let a = Web::answer(r).await;
    assert!(
        (400..500).contains(&a.status),
        "a 4xx, not {}: {}",
        a.status,
        a.body
    );
    assert!(
        a.headers["content-type"]
            .to_str()
            .unwrap()
            .starts_with("text/html")
    );
    assert!(
        a.body.contains("role=\"alert\""),
        "the error in the form: {}",
        a.body
    );
    // Nothing was stored, and the server keeps serving.
    let (_, bots) = server.get("/api/bots", None).await;
    assert!(
        !bots
            .as_array()
            .unwrap()
            .iter()
            .any(|b| b["name"] == "eve-bot"),
        "{bots}"
    );
    let (s, _) = server.get("/healthz", None).await;
    assert_eq!(s, 200);
    // A too-large body is refused by its size, in a page too.
    // (The server answers before the body has all been sent, and closes: the client may
    // see its write fail before it reads the answer, so it tries again a few times.)
    let big = vec![b'x'; 33 << 20];
    let mut answered = None;
    for _ in 0..5 {
        let form = reqwest::multipart::Form::new().text("csrf", "x").part(
            "archive",
            reqwest::multipart::Part::bytes(big.clone()).file_name("big.zip"),
        );
        let sent = web
            .http
            .post(format!("{}/competitions/bomb-cup/submit", server.base))
            .header("cookie", format!("mazearena_session={session}"))
            .multipart(form)
            .send()
            .await;
        if let Ok(r) = sent {
            answered = Some((r.status().as_u16(), r.text().await.unwrap_or_default()));
            break;
        }
    }
    let (status, body) = answered.expect("an answer to one of five tries");
    assert!(matches!(status, 403 | 413), "{status}: {body}");
}

#[tokio::test]
async fn form_errors_are_pages_with_the_apis_messages() {
    let dir = tempfile::tempdir().unwrap();
    let server = TestServer::start(dir.path(), &["--no-validation"]);
    let web = Web::new(&server);
    // The same message as the API for the same mistake.
    let (s, api) = server
        .post("/api/entrants", json!({"name": "bad name!"}), None)
        .await;
    assert_eq!(s, 422);
    let message: &str = api["error"]["message"].as_str().unwrap();
    let page = web.post("/register", None, &[("name", "bad name!")]).await;
    assert_eq!(page.status, 422);
    assert!(
        page.headers["content-type"]
            .to_str()
            .unwrap()
            .starts_with("text/html")
    );
    let escaped = message.replace('"', "&quot;");
    assert!(page.body.contains(&escaped), "{message} in {}", page.body);
    // The form is shown again with what was typed.
    assert!(page.body.contains("value=\"bad name!\""), "{}", page.body);
    // A malformed form and a missing field: 400 pages, never a 500.
    let r = web
        .http
        .post(format!("{}/register", server.base))
        .header("content-type", "application/x-www-form-urlencoded")
        .body("%%%");
    let a = Web::answer(r).await;
    assert_eq!(a.status, 400, "{}", a.body);
    assert!(
        a.headers["content-type"]
            .to_str()
            .unwrap()
            .starts_with("text/html")
    );
    // Pages that need a session send the visitor to log in, and back.
    let me = web.get("/competitions/x/submit", None).await;
    assert_eq!(me.status, 303);
    assert_eq!(me.location(), "/login?next=/competitions/x/submit");
    // A signed-in entrant on a competition that does not exist: a 404 page.
    let (_, key) = entrant(&server, "fay").await;
    let session = web.login(&key).await;
    let missing = web.get("/competitions/nope/submit", Some(&session)).await;
    assert_eq!(missing.status, 404);
    assert!(missing.body.contains("<h1>"));
    // The API's page lists its routes, as a page.
    let api = web.get("/api", None).await;
    assert_eq!(api.status, 200);
    assert!(
        api.body.contains("/api/competitions/{name}/rejudges"),
        "{}",
        api.body
    );
    assert!(api.body.contains("href=\"/api/openapi.json\""));
    // An entrant on the organiser's and the admin's pages: refused, as pages.
    assert_eq!(web.get("/organise", Some(&session)).await.status, 403);
    assert_eq!(web.get("/admin", Some(&session)).await.status, 403);
}

#[tokio::test]
async fn an_exported_competition_is_created_again_from_its_archive_through_the_organisers_form() {
    let dir = tempfile::tempdir().unwrap();
    let first = TestServer::start(dir.path(), &["--no-validation"]);
    let (_, o) = first
        .post("/api/organisers", json!({"name": "t"}), Some(ADMIN))
        .await;
    let organiser = o["key"].as_str().unwrap().to_string();
    let (_, other) = first
        .post("/api/organisers", json!({"name": "u"}), Some(ADMIN))
        .await;
    let now = mazearena::storage::now_ms();
    let maze = |n: u64| {
        json!({"name": format!("m{n}"), "layout": mazearena::engine::mazefile::numeric::write(
            &mazearena::engine::generator::generate(12, n).unwrap())})
    };
    let spec = json!({
        "name": "moving-cup", "title": "Moving", "rules": "be kind",
        "opens_at": mazearena::competition::Timestamp(now + 3_600_000).rfc3339(),
        "closes_at": mazearena::competition::Timestamp(now + 7_200_000).rfc3339(),
        "mazes": {"practice": [maze(9201)], "public": [maze(9202), maze(9203)], "private": [maze(9204)]},
    });
    let (s, c) = first
        .post("/api/competitions", spec, Some(&organiser))
        .await;
    assert_eq!(s, 201, "{c}");
    // The export holds private mazes: its organiser's (and the admin's) only.
    let url = format!("{}/api/competitions/moving-cup/export", first.base);
    let http = reqwest::Client::new();
    let get = |token: Option<String>| {
        let mut r = http.get(&url);
        if let Some(t) = token {
            r = r.bearer_auth(t);
        }
        r.send()
    };
    assert_eq!(get(None).await.unwrap().status(), 401);
    assert_eq!(
        get(Some(other["key"].as_str().unwrap().to_string()))
            .await
            .unwrap()
            .status(),
        403
    );
    let archive = get(Some(organiser.clone())).await.unwrap();
    assert_eq!(archive.status(), 200);
    assert_eq!(archive.headers()["content-type"], "application/gzip");
    let archive = archive.bytes().await.unwrap().to_vec();

    // Another server takes it back through the form, as an archive.
    let dir2 = tempfile::tempdir().unwrap();
    let second = TestServer::start(dir2.path(), &["--no-validation", "--secure-cookies"]);
    let web = Web::secure(&second);
    let login = web.post("/login", None, &[("key", ADMIN)]).await;
    assert!(
        login.set_cookie().unwrap().contains("Secure"),
        "--secure-cookies marks the cookie Secure"
    );
    let session = login.session().unwrap();
    let token = web.get("/organise", Some(&session)).await.csrf();
    let form = reqwest::multipart::Form::new().text("csrf", token).part(
        "archive",
        reqwest::multipart::Part::bytes(archive).file_name("moving-cup.tar.gz"),
    );
    let r = web
        .http
        .post(format!("{}/organise", second.base))
        .header("cookie", format!("__Host-mazearena_session={session}"))
        .multipart(form);
    let created = Web::answer(r).await;
    assert_eq!(created.status, 303, "{}", created.body);
    assert_eq!(created.location(), "/competitions/moving-cup/manage");
    let (_, a) = first
        .get("/api/competitions/moving-cup", Some(&organiser))
        .await;
    let (_, b) = second
        .get("/api/competitions/moving-cup", Some(ADMIN))
        .await;
    for field in [
        "title",
        "rules",
        "opens_at",
        "closes_at",
        "repeats",
        "limits",
    ] {
        assert_eq!(a[field], b[field], "{field}");
    }
    let hashes = |v: &serde_json::Value| {
        let mut h: Vec<String> = v["mazes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|m| format!("{}:{}", m["set"], m["hash"]))
            .collect();
        h.sort();
        h
    };
    assert_eq!(hashes(&a), hashes(&b), "the same mazes in the same sets");
    // A competition file whose maze is missing: the page says which.
    let token = web.get("/organise", Some(&session)).await.csrf();
    let form = reqwest::multipart::Form::new()
        .text("csrf", token)
        .part(
            "competition",
            reqwest::multipart::Part::text(
                "name = \"x-cup\"\ntitle = \"X\"\nopens_at = 2099-01-01T00:00:00Z\n\
                 closes_at = 2099-02-01T00:00:00Z\n[mazes]\npublic = [\"mazes/a.txt\"]\nprivate = [\"mazes/b.txt\"]\n",
            )
            .file_name("competition.toml"),
        );
    let r = web
        .http
        .post(format!("{}/organise", second.base))
        .header("cookie", format!("__Host-mazearena_session={session}"))
        .multipart(form);
    let missing = Web::answer(r).await;
    assert_eq!(missing.status, 422, "{}", missing.body);
    assert!(
        missing
            .body
            .contains("the maze file mazes/a.txt was not uploaded"),
        "{}",
        missing.body
    );
}
