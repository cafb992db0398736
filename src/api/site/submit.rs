//! The upload page of a competition (`/competitions/{name}/submit`): an entrant's new
//! version from a form, through the API's upload, with the same checks and limits.

use std::collections::BTreeMap;

use axum::extract::{Request, State};
use axum::http::StatusCode;
use axum::response::{Html, IntoResponse};

use super::super::AppState;
use super::super::bots::upload::{Upload, checked};
use super::super::error::{ApiError, AppPath};
use super::super::session::Visitor;
use super::forms::{PageError, PageResult, client_of, login_first, see_other};
use crate::web::pages::account;

/// The submission page's data for an entrant in competition `name`.
async fn submit_data(
    state: &AppState,
    visitor: &Visitor,
    name: &str,
) -> PageResult<account::SubmitPage> {
    let c = super::super::competitions::find(state, name).await?;
    if c.kind != "competition" {
        return Err(PageError::new(
            StatusCode::CONFLICT,
            "the server's default ranking takes no submissions: choose a competition",
        ));
    }
    let e = super::super::competitions::entrant(state, &visitor.caller).await?;
    let now = crate::storage::now_ms();
    if crate::registry::competitions::phase(&c, now).is_closed() {
        return Err(PageError::new(
            StatusCode::CONFLICT,
            format!("competition {} is closed: it takes no new versions", c.name),
        ));
    }
    let bot = state
        .storage
        .competition_entries(c.competition_id)
        .await?
        .into_iter()
        .find(|x| x.entrant_id == e.entrant_id)
        .map(|x| (x.bot_id, x.bot_name));
    let quota = crate::registry::competitions::version_quota(&state.storage, &c, e.entrant_id, now)
        .await?
        .message;
    let runtimes = state
        .runtimes
        .iter()
        .filter(|r| r.kind == "operator")
        .map(|r| (r.name.clone(), account::runtime_words(r)))
        .collect();
    Ok(account::SubmitPage {
        competition: c.name,
        title: c.title,
        csrf: visitor
            .session
            .as_ref()
            .map(|s| s.csrf.clone())
            .unwrap_or_default(),
        bot,
        runtimes,
        quota,
        error: None,
    })
}

pub(super) async fn submit_page(
    State(state): State<AppState>,
    visitor: Visitor,
    AppPath(name): AppPath<String>,
) -> PageResult {
    if let Some(r) = login_first(&visitor, &format!("/competitions/{name}/submit")) {
        return Ok(r);
    }
    let p = submit_data(&state, &visitor, &name).await?;
    Ok(Html(account::submit(&p)).into_response())
}

/// Reads the submission form: its first field must be the anti-forgery token, checked
/// before any file is read.
async fn read_submission(
    state: &AppState,
    visitor: &Visitor,
    request: Request,
) -> PageResult<Upload> {
    let mut form = super::forms::multipart_after_token(state, visitor, request).await?;
    let mut upload = Upload::default();
    let mut files: BTreeMap<String, String> = BTreeMap::new();
    while let Some(field) = form.next_field().await.map_err(ApiError::from)? {
        let name = field.name().unwrap_or("").to_string();
        match name.as_str() {
            "name" => upload.name = Some(field.text().await.map_err(ApiError::from)?.trim().into()),
            "command" => upload.command = field.text().await.map_err(ApiError::from)?,
            "build" => upload.build = Some(field.text().await.map_err(ApiError::from)?),
            "runtime" => upload.runtime = Some(field.text().await.map_err(ApiError::from)?),
            "protocol" => upload.protocol = Some(field.text().await.map_err(ApiError::from)?),
            "original_task" => {
                upload.original_task = checked(&field.text().await.map_err(ApiError::from)?)
            }
            "robot_file" => upload.robot_file = Some(field.text().await.map_err(ApiError::from)?),
            "files" => {
                let file_name = field.file_name().unwrap_or("").to_string();
                let bytes = field.bytes().await.map_err(ApiError::from)?;
                if file_name.is_empty() && bytes.is_empty() {
                    continue; // no file chosen
                }
                let text = String::from_utf8(bytes.to_vec()).map_err(|_| {
                    PageError::new(
                        StatusCode::UNPROCESSABLE_ENTITY,
                        format!(
                            "{file_name} is not a text file: send files that are not text in an \
                             archive (.zip or .tar.gz)"
                        ),
                    )
                })?;
                if files.insert(file_name.clone(), text).is_some() {
                    return Err(PageError::new(
                        StatusCode::UNPROCESSABLE_ENTITY,
                        format!("two files are named {file_name}"),
                    ));
                }
            }
            "archive" => {
                let bytes = field.bytes().await.map_err(ApiError::from)?;
                if !bytes.is_empty() {
                    upload.archive = Some(bytes.to_vec());
                }
            }
            other => {
                return Err(PageError::new(
                    StatusCode::BAD_REQUEST,
                    format!("the form has an unknown field {other:?}"),
                ));
            }
        }
    }
    if !files.is_empty() {
        upload.files = Some(files);
    }
    // The form's list of the robot's file counts only for an original-task robot.
    if !upload.original_task {
        upload.robot_file = None;
    }
    if upload.files.is_some() && upload.archive.is_some() {
        return Err(PageError::new(
            StatusCode::UNPROCESSABLE_ENTITY,
            "send either files or an archive, not both",
        ));
    }
    Ok(upload)
}

pub(super) async fn submit(
    State(state): State<AppState>,
    visitor: Visitor,
    AppPath(name): AppPath<String>,
    request: Request,
) -> PageResult {
    let client = client_of(&request);
    let p = submit_data(&state, &visitor, &name).await?;
    let again = |m: &str| {
        account::submit(&account::SubmitPage {
            error: Some(m.to_string()),
            ..p.clone()
        })
    };
    let upload = read_submission(&state, &visitor, request)
        .await
        .map_err(|e| e.with_page(again))?;
    let caller = &visitor.caller;
    match &p.bot {
        Some((bot_id, _)) => {
            super::super::bots::add_bot_version(&state, caller, *bot_id, upload)
                .await
                .map_err(|e| PageError::from(e).with_page(again))?;
        }
        None => {
            // Registered and entered in one step: its first version is validated by the
            // competition's rule.
            super::super::bots::register_bot(&state, caller, client, upload, Some(&name))
                .await
                .map_err(|e| PageError::from(e).with_page(again))?;
        }
    }
    Ok(see_other(&format!("/me#competition-{name}"), None))
}
