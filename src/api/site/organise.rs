//! The organiser's pages (`/organise`, `/competitions/{name}/manage` and its forms, the
//! export download; the admin's are in [`super::admin`]). Each form goes through the
//! operation the API's route of the same purpose calls.

use std::collections::BTreeMap;
use std::path::Path;

use axum::Router;
use axum::extract::{DefaultBodyLimit, Request, State};
use axum::http::StatusCode;
use axum::response::{Html, IntoResponse};
use axum::routing::{get, post};
use serde::Deserialize;

use super::super::AppState;
use super::super::auth::Caller;
use super::super::error::{ApiError, AppPath, AppQuery};
use super::super::session::Visitor;
use super::forms::{PageError, PageResult, csrf, login_first, read_form, see_other};
use crate::competition::{MazeText, Spec, Timestamp};
use crate::registry::competitions::{self as ops, Patch, RejudgeRequest};
use crate::web::pages::organise as web;

/// Their routes.
pub(super) fn router() -> Router<AppState> {
    Router::new()
        .route(
            "/organise",
            get(organise_page)
                .post(create)
                .layer(DefaultBodyLimit::max(super::super::MAX_UPLOAD_BYTES)),
        )
        .route("/competitions/{name}/manage", get(manage_page))
        .route("/competitions/{name}/edit", post(edit))
        .route("/competitions/{name}/close", post(close))
        .route("/competitions/{name}/rejudge", post(rejudge))
        .route("/competitions/{name}/export.tar.gz", get(export))
}

/// The competitions the caller organises (the admin: all), as lines.
async fn organised(state: &AppState, caller: &Caller) -> PageResult<Vec<web::OrganisedLine>> {
    let now = crate::storage::now_ms();
    Ok(state
        .storage
        .list_competitions()
        .await?
        .into_iter()
        .filter(|c| c.kind == "competition" && caller.organises(c))
        .map(|c| web::OrganisedLine {
            phase: ops::phase(&c, now).as_str().into(),
            name: c.name,
            title: c.title,
        })
        .collect())
}

async fn organise_page(State(state): State<AppState>, visitor: Visitor) -> PageResult {
    if let Some(r) = login_first(&visitor, "/organise") {
        return Ok(r);
    }
    visitor.caller.require_organiser()?;
    let mine = organised(&state, &visitor.caller).await?;
    Ok(Html(web::organise(&csrf(&visitor), &mine, None)).into_response())
}

/// Every regular text file under `dir`, by its path relative to `dir`.
fn text_files(dir: &Path) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let path = e.path();
            let Ok(meta) = std::fs::symlink_metadata(&path) else {
                continue;
            };
            if meta.is_dir() {
                stack.push(path);
            } else if meta.is_file()
                && meta.len() <= crate::engine::mazefile::MAX_FILE_BYTES as u64
                && let (Ok(rel), Ok(text)) =
                    (path.strip_prefix(dir), std::fs::read_to_string(&path))
            {
                out.insert(rel.to_string_lossy().replace('\\', "/"), text);
            }
        }
    }
    out
}

/// The competition file and mazes of the creation form: (competition file text, files
/// by path or name).
async fn read_creation(
    state: &AppState,
    visitor: &Visitor,
    request: Request,
) -> PageResult<Spec<MazeText>> {
    let mut form = super::forms::multipart_after_token(state, visitor, request).await?;
    let mut file: Option<String> = None;
    let mut files: BTreeMap<String, String> = BTreeMap::new();
    let mut archive: Option<Vec<u8>> = None;
    while let Some(field) = form.next_field().await.map_err(ApiError::from)? {
        let name = field.name().unwrap_or("").to_string();
        let file_name = field.file_name().unwrap_or("").to_string();
        let bytes = field.bytes().await.map_err(ApiError::from)?;
        if bytes.is_empty() {
            continue;
        }
        let text = || {
            String::from_utf8(bytes.to_vec()).map_err(|_| {
                PageError::new(
                    StatusCode::UNPROCESSABLE_ENTITY,
                    format!("{file_name} is not a text file"),
                )
            })
        };
        match name.as_str() {
            "competition" => file = Some(text()?),
            "mazes" => {
                files.insert(file_name.clone(), text()?);
            }
            "archive" => archive = Some(bytes.to_vec()),
            other => {
                return Err(PageError::new(
                    StatusCode::BAD_REQUEST,
                    format!("the form has an unknown field {other:?}"),
                ));
            }
        }
    }
    if let Some(bytes) = archive {
        if file.is_some() || !files.is_empty() {
            return Err(PageError::new(
                StatusCode::UNPROCESSABLE_ENTITY,
                "send either the competition file and its mazes, or an archive, not both",
            ));
        }
        // Unpacked with every rule and limit of a bot upload, in the server's scratch.
        let scratch = state.settings.scratch();
        let unpacked = tokio::task::spawn_blocking(move || {
            std::fs::create_dir_all(&scratch)?;
            let tmp = tempfile::tempdir_in(&scratch)?;
            let dest = tmp.path().join("folder");
            std::fs::create_dir(&dest)?;
            crate::botfiles::unpack_archive(
                &bytes,
                &dest,
                &crate::botfiles::BundleLimits::default(),
            )
            .map_err(|e| {
                // The archive's own faults are told; the server's (paths) are not.
                let message = if e.is_client_error() {
                    e.to_string()
                } else {
                    tracing::error!(error = %e, "unpacking a competition archive");
                    "the server could not unpack it".to_string()
                };
                std::io::Error::new(std::io::ErrorKind::InvalidData, message)
            })?;
            Ok::<_, std::io::Error>(text_files(&dest))
        })
        .await
        .map_err(|e| ApiError::Internal(format!("unpacking: {e}")))?
        .map_err(|e| {
            PageError::new(
                StatusCode::UNPROCESSABLE_ENTITY,
                format!("the archive cannot be read: {e}"),
            )
        })?;
        // The competition file at the top, or in the archive's one top folder.
        let top = unpacked
            .keys()
            .filter(|k| *k == "competition.toml" || k.ends_with("/competition.toml"))
            .min_by_key(|k| k.matches('/').count())
            .cloned()
            .ok_or_else(|| {
                PageError::new(
                    StatusCode::UNPROCESSABLE_ENTITY,
                    "the archive has no competition.toml",
                )
            })?;
        let base = top.trim_end_matches("competition.toml").to_string();
        file = unpacked.get(&top).cloned();
        files = unpacked
            .into_iter()
            .filter_map(|(k, v)| k.strip_prefix(&base).map(|rel| (rel.to_string(), v)))
            .collect();
    }
    let text = file.ok_or_else(|| {
        PageError::new(
            StatusCode::UNPROCESSABLE_ENTITY,
            "choose the competition file (competition.toml), or an archive of its folder",
        )
    })?;
    crate::competition::read_competition_file(&text, |p| {
        let name = p.rsplit('/').next().unwrap_or(p);
        files
            .get(p.trim_start_matches("./"))
            .or_else(|| files.get(name))
            .cloned()
            .ok_or_else(|| format!("the maze file {p} was not uploaded"))
    })
    .map_err(|e| PageError::new(StatusCode::UNPROCESSABLE_ENTITY, e.0))
}

async fn create(State(state): State<AppState>, visitor: Visitor, request: Request) -> PageResult {
    visitor.caller.require_organiser()?;
    let mine = organised(&state, &visitor.caller).await?;
    let token = csrf(&visitor);
    let again = |m: &str| web::organise(&token, &mine, Some(m));
    let spec = read_creation(&state, &visitor, request)
        .await
        .map_err(|e| e.with_page(again))?;
    let c = super::super::competitions::create(&state, &visitor.caller, spec)
        .await
        .map_err(|e| PageError::from(e).with_page(again))?;
    Ok(see_other(&format!("/competitions/{}/manage", c.name), None))
}

async fn manage_data(
    state: &AppState,
    visitor: &Visitor,
    name: &str,
    notice: Option<String>,
) -> PageResult<web::ManagePage> {
    let c = super::super::competitions::find(state, name).await?;
    visitor.caller.require_organiser_of(&c)?;
    let now = crate::storage::now_ms();
    let phase = ops::phase(&c, now);
    let mut entrants = Vec::new();
    for e in state.storage.competition_entries(c.competition_id).await? {
        let versions = state
            .storage
            .submissions(&c, e.entrant_id)
            .await?
            .into_iter()
            .map(|s| (s.bot_version_id, s.version, s.build_status))
            .collect();
        let vq = ops::version_quota(&state.storage, &c, e.entrant_id, now).await?;
        let pq = ops::practice_quota(&state.storage, &c, e.entrant_id, now).await?;
        entrants.push(web::EntrantLine {
            entrant_id: e.entrant_id,
            entrant: e.entrant_name,
            bot: (e.bot_id, e.bot_name),
            versions,
            quotas: format!("{}; {}", vq.message, pq.message),
        });
    }
    let rfc = |t: Option<i64>| t.map(|t| Timestamp(t).rfc3339()).unwrap_or_default();
    Ok(web::ManagePage {
        name: c.name.clone(),
        title: c.title.clone(),
        phase: match c.state.as_deref() {
            Some(s) => format!("{} ({s})", phase.as_str()),
            None => phase.as_str().into(),
        },
        closed: phase.is_closed(),
        final_results: c.state.as_deref() == Some("final"),
        results_state: match c.state.as_deref() {
            Some(s @ ("held" | "final")) => s.to_string(),
            _ => String::new(),
        },
        hold_results: c.hold_results,
        opens_at: rfc(c.opens_at),
        closes_at: rfc(c.closes_at),
        freeze_hours: c
            .freeze_ms
            .map(|ms| format!("{}", ms as f64 / 3_600_000.0))
            .unwrap_or_default(),
        versions_per_day: c.versions_per_day,
        practice_per_day: c.practice_per_day,
        entrants,
        registered: state
            .storage
            .registered_without_entry(c.competition_id)
            .await?,
        invite: c
            .invite_code
            .as_deref()
            .map(|code| (code.to_string(), crate::registry::invites::link(&c, code))),
        validation: c.validation.clone(),
        work_left: state.storage.competition_work_left(&c).await?,
        final_run: ops::final_progress(&state.storage, &c)
            .await?
            .map(|r| (r.played, r.total)),
        mazes: state
            .storage
            .competition_mazes(c.competition_id)
            .await?
            .into_iter()
            .map(|m| (m.maze_id, m.maze_set, m.name))
            .collect(),
        rejudges: state.storage.rejudges(c.competition_id).await?,
        csrf: csrf(visitor),
        notice,
    })
}

/// What a form of the manage page did: after it, the browser is sent back to the page
/// (post/redirect/get: a reload does not post again), which says so.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
enum Done {
    /// The times and quotas were saved.
    Saved,
    /// The competition was closed.
    Closed,
    /// A rejudge was queued (its id in `rejudge`).
    Rejudged,
    /// The invite code was set or replaced.
    Invite,
    /// The invite code was removed.
    InviteRemoved,
    /// A practice maze was added.
    PracticeAdded,
    /// A practice maze was removed.
    PracticeRemoved,
    /// The results will be held for the reveal.
    Held,
    /// The held results were published.
    Published,
}

/// The manage page's query: what the last form did (a fixed word, never text to show).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct DoneQuery {
    done: Option<Done>,
    rejudge: Option<i64>,
}

async fn manage_page(
    State(state): State<AppState>,
    visitor: Visitor,
    AppPath(name): AppPath<String>,
    AppQuery(q): AppQuery<DoneQuery>,
) -> PageResult {
    if let Some(r) = login_first(&visitor, &format!("/competitions/{name}/manage")) {
        return Ok(r);
    }
    let mut p = manage_data(&state, &visitor, &name, None).await?;
    p.notice = match q.done {
        Some(Done::Saved) => Some("Saved.".to_string()),
        Some(Done::Closed) => {
            Some("Closed: the final selection and the final run follow.".to_string())
        }
        Some(Done::Rejudged) => p
            .rejudges
            .iter()
            .find(|r| Some(r.rejudge_id) == q.rejudge)
            .map(|r| {
                format!(
                    "Rejudge {}: {} matches queued again; their earlier records are kept.",
                    r.rejudge_id, r.matches
                )
            }),
        Some(Done::Invite) => Some(
            "The invite code is set: the old one no longer registers anyone. Give the class the new link."
                .to_string(),
        ),
        Some(Done::InviteRemoved) => Some("The invite code is removed.".to_string()),
        Some(Done::Held) => Some(
            "Saved: the results will be held for the reveal until you publish them.".to_string(),
        ),
        Some(Done::Published) => Some(
            "Published: everyone sees the results, the reveal and the races.".to_string(),
        ),
        Some(Done::PracticeAdded) => Some(
            "The practice maze is added: entrants practise on it, and new versions are validated on the practice mazes in order."
                .to_string(),
        ),
        Some(Done::PracticeRemoved) => Some("The practice maze is removed.".to_string()),
        None => None,
    };
    Ok(Html(web::manage(&p)).into_response())
}

/// Sends the browser back to the manage page saying what was done (`done`, a query
/// of [`DoneQuery`]), or answers the page again with `result`'s error.
pub(super) async fn manage_after(
    state: &AppState,
    visitor: &Visitor,
    name: &str,
    result: Result<String, PageError>,
) -> PageResult {
    match result {
        Ok(done) => Ok(see_other(
            &format!("/competitions/{name}/manage?done={done}"),
            None,
        )),
        Err(e) => {
            let p = manage_data(state, visitor, name, Some(e.message().to_string())).await?;
            Err(e.with_page(|_| web::manage(&p)))
        }
    }
}

/// The times-and-quotas form: fields of `PATCH /api/competitions/{name}` (empty: not
/// changed).
#[derive(Debug, Deserialize)]
struct EditForm {
    csrf: Option<String>,
    #[serde(default)]
    opens_at: String,
    #[serde(default)]
    closes_at: String,
    #[serde(default)]
    freeze_hours: String,
    #[serde(default)]
    versions_per_day: String,
    #[serde(default)]
    practice_per_day: String,
    #[serde(default)]
    validation: String,
}

fn parse_field<T: std::str::FromStr>(name: &str, value: &str) -> Result<Option<T>, PageError> {
    let v = value.trim();
    if v.is_empty() {
        return Ok(None);
    }
    v.parse().map(Some).map_err(|_| {
        PageError::new(
            StatusCode::UNPROCESSABLE_ENTITY,
            format!("{name}: {v:?} is not a valid value"),
        )
    })
}

fn parse_time(name: &str, value: &str) -> Result<Option<Timestamp>, PageError> {
    let v = value.trim();
    if v.is_empty() {
        return Ok(None);
    }
    Timestamp::parse(v)
        .map(Some)
        .map_err(|e| PageError::new(StatusCode::UNPROCESSABLE_ENTITY, format!("{name}: {e}")))
}

async fn edit(
    State(state): State<AppState>,
    visitor: Visitor,
    AppPath(name): AppPath<String>,
    request: Request,
) -> PageResult {
    let form: EditForm = read_form(&state, request).await?;
    visitor.check_csrf(form.csrf.as_deref())?;
    let result = async {
        let c = super::super::competitions::find(&state, &name).await?;
        let unchanged = |new: Option<Timestamp>, old: Option<i64>| new.filter(|t| Some(t.0) != old);
        let patch = Patch {
            opens_at: unchanged(parse_time("opens_at", &form.opens_at)?, c.opens_at),
            closes_at: unchanged(parse_time("closes_at", &form.closes_at)?, c.closes_at),
            freeze_hours: match parse_field::<f64>("freeze_hours", &form.freeze_hours)? {
                Some(h) => Some(h),
                None if c.freeze_ms.is_some() => Some(-1.0),
                None => None,
            },
            versions_per_day: parse_field("versions_per_day", &form.versions_per_day)?,
            practice_per_day: parse_field("practice_per_day", &form.practice_per_day)?,
            validation: match form.validation.trim() {
                "" => None,
                v if v == c.validation => None,
                v @ ("start" | "match" | "off") => Some(crate::competition::Validation::parse(v)),
                other => {
                    return Err(PageError::new(
                        StatusCode::UNPROCESSABLE_ENTITY,
                        format!("validation: {other:?} is not start, match or off"),
                    ));
                }
            },
            ..Patch::default()
        };
        super::super::competitions::edit(&state, &visitor.caller, &name, patch).await?;
        Ok::<_, PageError>("saved".to_string())
    }
    .await;
    manage_after(&state, &visitor, &name, result).await
}

/// The close form: a confirmation box that must be ticked.
#[derive(Debug, Deserialize)]
struct CloseForm {
    csrf: Option<String>,
    confirm: Option<String>,
}

async fn close(
    State(state): State<AppState>,
    visitor: Visitor,
    AppPath(name): AppPath<String>,
    request: Request,
) -> PageResult {
    let form: CloseForm = read_form(&state, request).await?;
    visitor.check_csrf(form.csrf.as_deref())?;
    let result = async {
        if form.confirm.as_deref() != Some("yes") {
            return Err(PageError::new(
                StatusCode::UNPROCESSABLE_ENTITY,
                "tick the box to confirm the close: it cannot be undone",
            ));
        }
        let patch = Patch {
            closes_at: Some(Timestamp(crate::storage::now_ms())),
            ..Patch::default()
        };
        super::super::competitions::edit(&state, &visitor.caller, &name, patch).await?;
        Ok("closed".to_string())
    }
    .await;
    manage_after(&state, &visitor, &name, result).await
}

/// The rejudge forms: the fields of `POST /api/competitions/{name}/rejudges`.
#[derive(Debug, Deserialize)]
struct RejudgeForm {
    csrf: Option<String>,
    bot_version_id: Option<i64>,
    maze_id: Option<i64>,
    reason: String,
}

async fn rejudge(
    State(state): State<AppState>,
    visitor: Visitor,
    AppPath(name): AppPath<String>,
    request: Request,
) -> PageResult {
    let form: RejudgeForm = read_form(&state, request).await?;
    visitor.check_csrf(form.csrf.as_deref())?;
    let request = RejudgeRequest {
        bot_version_id: form.bot_version_id,
        maze_id: form.maze_id,
        reason: form.reason,
    };
    let result = super::super::competitions::rejudge(&state, &visitor.caller, &name, &request)
        .await
        .map(|r| format!("rejudged&rejudge={}", r.rejudge_id))
        .map_err(PageError::from);
    manage_after(&state, &visitor, &name, result).await
}

async fn export(
    State(state): State<AppState>,
    visitor: Visitor,
    AppPath(name): AppPath<String>,
) -> PageResult {
    if let Some(r) = login_first(&visitor, &format!("/competitions/{name}/manage")) {
        return Ok(r);
    }
    Ok(super::super::competitions::export_archive(&state, &visitor.caller, &name).await?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_unpacked_folder_is_read_without_following_links() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(dir.path().join("mazes/public")).unwrap();
        std::fs::write(dir.path().join("competition.toml"), "x").unwrap();
        std::fs::write(dir.path().join("mazes/public/a.txt"), "12").unwrap();
        std::os::unix::fs::symlink("/etc/passwd", dir.path().join("mazes/leak.txt")).unwrap();
        let files = text_files(dir.path());
        assert_eq!(
            files.keys().cloned().collect::<Vec<_>>(),
            ["competition.toml", "mazes/public/a.txt"]
        );
    }
}
