//! Bots: register (with files), upload new versions (which resumes a paused bot), list,
//! show, and resume a paused bot (admin).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use axum::extract::{DefaultBodyLimit, FromRequest, Multipart, Request, State};
use axum::http::{StatusCode, header};
use base64::Engine;
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

use super::auth::{Caller, hash_token, new_token};
use super::error::{ApiError, ApiResult, AppJson, AppPath, ErrorBody};
use super::{AppState, MAX_UPLOAD_BYTES};
use crate::botfiles::{self, BundleError, BundleLimits, BundleSummary};
use crate::storage::bots::{BotVersionRow, NewVersion};

/// Longest bot name.
pub const MAX_NAME_CHARS: usize = 64;
/// Longest bot command.
pub const MAX_COMMAND_CHARS: usize = 1000;

pub(super) fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(create_bot, list_bots))
        .routes(routes!(get_bot))
        .routes(routes!(create_bot_version))
        .routes(routes!(resume_bot))
        .layer(DefaultBodyLimit::max(MAX_UPLOAD_BYTES))
}

/// A bot upload as JSON: the files either as a map of name to text, or as a base64
/// `.tar.gz` / `.tar` / `.zip` archive. (The same fields can be sent as
/// `multipart/form-data`, the archive as a file field named `archive`.)
#[derive(Debug, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct BotUpload {
    /// The bot's unique name (registration only): letters, digits, `-`, `_`, `.`.
    #[serde(default)]
    pub name: Option<String>,
    /// The command that runs the bot in its directory, e.g. `python3 bot.py`.
    pub command: String,
    /// Small bots: file name -> content.
    #[serde(default)]
    pub files: Option<BTreeMap<String, String>>,
    /// An archive of the bot's directory, base64-encoded.
    #[serde(default)]
    pub archive_base64: Option<String>,
}

/// A stored version of a bot.
#[derive(Debug, Serialize, ToSchema)]
pub struct VersionView {
    /// Version number, 1 first.
    pub version: i64,
    /// Its id (matches record it).
    pub bot_version_id: i64,
    /// The command.
    pub command: String,
    /// Content hash of its files.
    pub files_sha256: String,
    /// Number of files.
    pub file_count: i64,
    /// When it was uploaded (unix ms).
    pub created_at: i64,
}

impl From<BotVersionRow> for VersionView {
    fn from(v: BotVersionRow) -> Self {
        VersionView {
            version: v.version,
            bot_version_id: v.bot_version_id,
            command: v.command,
            files_sha256: v.files_sha256,
            file_count: v.file_count,
            created_at: v.created_at,
        }
    }
}

/// The answer to a registration: the owner token is shown this once.
#[derive(Debug, Serialize, ToSchema)]
pub struct BotCreated {
    /// The bot's id.
    pub bot_id: i64,
    /// Its name.
    pub name: String,
    /// The token that owns the bot: keep it, it is not stored in clear and never shown again.
    pub owner_token: String,
    /// The first version.
    pub version: VersionView,
}

/// A bot in a list.
#[derive(Debug, Serialize, ToSchema)]
pub struct BotView {
    /// Id.
    pub bot_id: i64,
    /// Name.
    pub name: String,
    /// Latest version.
    pub version: i64,
    /// Latest version's command.
    pub command: String,
    /// Registered at (unix ms).
    pub created_at: i64,
    /// Paused: its matches keep aborting, so no new ones are accepted.
    pub paused: bool,
}

/// A bot with all its versions.
#[derive(Debug, Serialize, ToSchema)]
pub struct BotDetail {
    /// Id.
    pub bot_id: i64,
    /// Name.
    pub name: String,
    /// Registered at (unix ms).
    pub created_at: i64,
    /// Paused: its matches kept aborting (the server stopped each time they ran), so
    /// its queued matches were aborted and no new ones are accepted until the admin
    /// resumes it or a new version is uploaded.
    pub paused: bool,
    /// Why it is paused (null when it is not).
    pub paused_reason: Option<String>,
    /// When it was paused (unix ms; null when it is not).
    pub paused_at: Option<i64>,
    /// Every version, oldest first.
    pub versions: Vec<VersionView>,
}

/// Register a bot with its files; answers its id and owner token.
#[utoipa::path(post, path = "/api/bots", tag = "bots",
    request_body(content(
        (BotUpload = "application/json"),
        (BotUpload = "multipart/form-data"),
    )),
    responses(
        (status = 201, body = BotCreated),
        (status = 400, body = ErrorBody), (status = 409, body = ErrorBody),
        (status = 413, body = ErrorBody), (status = 422, body = ErrorBody),
    ))]
async fn create_bot(
    State(state): State<AppState>,
    request: Request,
) -> ApiResult<(StatusCode, axum::Json<BotCreated>)> {
    let upload = read_upload(&state, request).await?;
    let name = upload
        .name
        .clone()
        .ok_or_else(|| ApiError::Unprocessable("a bot needs a `name`".into()))?;
    check_name(&name)?;
    check_command(&upload.command)?;
    if state.storage.get_bot_by_name(&name).await?.is_some() {
        return Err(ApiError::Conflict(format!(
            "a bot named {name:?} exists already"
        )));
    }
    let (dir, summary) =
        store_files(&state.settings.data_dir, upload.files, upload.archive).await?;
    let token = new_token()?;
    let new = NewVersion {
        command: &upload.command,
        dir: &dir.display().to_string(),
        files_sha256: &summary.sha256,
        file_count: summary.files as i64,
    };
    let row = match state
        .storage
        .create_bot(&name, &hash_token(&token), &new)
        .await
    {
        Ok(row) => row,
        Err(e) => {
            remove_dir(&dir).await;
            return Err(e.into());
        }
    };
    Ok((
        StatusCode::CREATED,
        axum::Json(BotCreated {
            bot_id: row.bot_id,
            name,
            owner_token: token,
            version: row.into(),
        }),
    ))
}

/// Upload a new version of a bot (owner token or admin); a paused bot is resumed.
#[utoipa::path(post, path = "/api/bots/{id}/versions", tag = "bots",
    params(("id" = i64, Path, description = "bot id")),
    request_body(content(
        (BotUpload = "application/json"),
        (BotUpload = "multipart/form-data"),
    )),
    security(("bearer" = [])),
    responses(
        (status = 201, body = VersionView),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 404, body = ErrorBody), (status = 422, body = ErrorBody),
    ))]
async fn create_bot_version(
    State(state): State<AppState>,
    AppPath(id): AppPath<i64>,
    caller: Caller,
    request: Request,
) -> ApiResult<(StatusCode, axum::Json<VersionView>)> {
    if state.storage.get_bot(id).await?.is_none() {
        return Err(ApiError::NotFound(format!("no bot {id}")));
    }
    caller.require_owner(&state, id).await?;
    let upload = read_upload(&state, request).await?;
    check_command(&upload.command)?;
    let (dir, summary) =
        store_files(&state.settings.data_dir, upload.files, upload.archive).await?;
    let new = NewVersion {
        command: &upload.command,
        dir: &dir.display().to_string(),
        files_sha256: &summary.sha256,
        file_count: summary.files as i64,
    };
    match state.storage.add_bot_version(id, &new).await {
        Ok(row) => Ok((StatusCode::CREATED, axum::Json(row.into()))),
        Err(e) => {
            remove_dir(&dir).await;
            Err(e.into())
        }
    }
}

/// List the bots with their latest version.
#[utoipa::path(get, path = "/api/bots", tag = "bots",
    responses((status = 200, body = [BotView])))]
async fn list_bots(State(state): State<AppState>) -> ApiResult<axum::Json<Vec<BotView>>> {
    let bots = state.storage.list_bots().await?;
    Ok(axum::Json(
        bots.into_iter()
            .map(|b| BotView {
                paused: b.is_paused(),
                bot_id: b.bot_id,
                name: b.name,
                version: b.version,
                command: b.command,
                created_at: b.created_at,
            })
            .collect(),
    ))
}

/// A bot and all its versions, and whether it is paused (with the reason).
#[utoipa::path(get, path = "/api/bots/{id}", tag = "bots",
    params(("id" = i64, Path, description = "bot id")),
    responses((status = 200, body = BotDetail), (status = 404, body = ErrorBody)))]
async fn get_bot(
    State(state): State<AppState>,
    AppPath(id): AppPath<i64>,
) -> ApiResult<axum::Json<BotDetail>> {
    Ok(axum::Json(bot_detail(&state, id).await?))
}

/// Resume a paused bot (admin token): its matches are accepted and played again.
/// Resuming a bot that is not paused changes nothing.
#[utoipa::path(post, path = "/api/bots/{id}/resume", tag = "bots",
    params(("id" = i64, Path, description = "bot id")),
    security(("bearer" = [])),
    responses(
        (status = 200, body = BotDetail),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody),
        (status = 404, body = ErrorBody),
    ))]
async fn resume_bot(
    State(state): State<AppState>,
    caller: Caller,
    AppPath(id): AppPath<i64>,
) -> ApiResult<axum::Json<BotDetail>> {
    caller.require_admin()?;
    if state.storage.get_bot(id).await?.is_none() {
        return Err(ApiError::NotFound(format!("no bot {id}")));
    }
    if state.storage.resume_bot(id).await? {
        tracing::info!(bot_id = id, "bot resumed by the admin");
        state.wake.notify_waiters();
    }
    Ok(axum::Json(bot_detail(&state, id).await?))
}

async fn bot_detail(state: &AppState, id: i64) -> ApiResult<BotDetail> {
    let bot = state
        .storage
        .get_bot(id)
        .await?
        .ok_or_else(|| ApiError::NotFound(format!("no bot {id}")))?;
    let versions = state.storage.bot_versions(id).await?;
    Ok(BotDetail {
        bot_id: bot.bot_id,
        paused: bot.is_paused(),
        name: bot.name,
        created_at: bot.created_at,
        paused_reason: bot.paused_reason,
        paused_at: bot.paused_at,
        versions: versions.into_iter().map(Into::into).collect(),
    })
}

/// An upload, whichever way it came.
struct Upload {
    name: Option<String>,
    command: String,
    files: Option<BTreeMap<String, String>>,
    archive: Option<Vec<u8>>,
}

async fn read_upload(state: &AppState, request: Request) -> ApiResult<Upload> {
    // Refuse a declared oversized upload before reading any of it.
    let declared = request
        .headers()
        .get(header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.parse::<u64>().ok());
    if declared.is_some_and(|n| n > MAX_UPLOAD_BYTES as u64) {
        return Err(ApiError::PayloadTooLarge(format!(
            "the upload is larger than {MAX_UPLOAD_BYTES} bytes; bots are limited to 50 MiB unpacked \
             and uploads to {MAX_UPLOAD_BYTES} bytes"
        )));
    }
    let content_type = request
        .headers()
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .unwrap_or("")
        .to_ascii_lowercase();
    if content_type.starts_with("multipart/form-data") {
        let mut form = Multipart::from_request(request, state).await?;
        let (mut name, mut command, mut archive) = (None, None, None);
        while let Some(field) = form.next_field().await? {
            match field.name().unwrap_or("") {
                "name" => name = Some(field.text().await?),
                "command" => command = Some(field.text().await?),
                "archive" => archive = Some(field.bytes().await?.to_vec()),
                other => {
                    return Err(ApiError::BadRequest(format!(
                        "unknown form field {other:?}: expected name, command, archive"
                    )));
                }
            }
        }
        return Ok(Upload {
            name,
            command: command.ok_or_else(|| {
                ApiError::Unprocessable("the form needs a `command` field".into())
            })?,
            files: None,
            archive: Some(archive.ok_or_else(|| {
                ApiError::Unprocessable("the form needs an `archive` file field".into())
            })?),
        });
    }
    let AppJson(body) = AppJson::<BotUpload>::from_request(request, state).await?;
    let archive = match body.archive_base64 {
        Some(text) => Some(
            base64::engine::general_purpose::STANDARD
                .decode(text.trim())
                .map_err(|e| {
                    ApiError::Unprocessable(format!("`archive_base64` is not valid base64: {e}"))
                })?,
        ),
        None => None,
    };
    Ok(Upload {
        name: body.name,
        command: body.command,
        files: body.files,
        archive,
    })
}

fn check_name(name: &str) -> ApiResult<()> {
    let ok = !name.is_empty()
        && name.chars().count() <= MAX_NAME_CHARS
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c));
    if ok {
        Ok(())
    } else {
        Err(ApiError::Unprocessable(format!(
            "bot name {name:?} is not allowed: 1 to {MAX_NAME_CHARS} letters, digits, '-', '_' or '.'"
        )))
    }
}

fn check_command(command: &str) -> ApiResult<()> {
    if command.chars().count() > MAX_COMMAND_CHARS {
        return Err(ApiError::Unprocessable(format!(
            "the command is longer than {MAX_COMMAND_CHARS} characters"
        )));
    }
    match shlex::split(command) {
        Some(words) if !words.is_empty() => Ok(()),
        _ => Err(ApiError::Unprocessable(format!(
            "the command {command:?} is empty or has unbalanced quotes"
        ))),
    }
}

/// Unpacks the files into a new directory under `data_dir/bots`.
async fn store_files(
    data_dir: &Path,
    files: Option<BTreeMap<String, String>>,
    archive: Option<Vec<u8>>,
) -> ApiResult<(PathBuf, BundleSummary)> {
    let dir = data_dir
        .join("bots")
        .join(new_token()?.get(..24).unwrap_or("bot"));
    tokio::fs::create_dir_all(&dir)
        .await
        .map_err(|e| ApiError::Internal(format!("cannot create {}: {e}", dir.display())))?;
    let dest = dir.clone();
    let result = tokio::task::spawn_blocking(move || {
        let limits = BundleLimits::default();
        match (files, archive) {
            (Some(_), Some(_)) => Err(ApiError::Unprocessable(
                "send the files either as `files` or as `archive_base64`, not both".into(),
            )),
            (None, None) => Err(ApiError::Unprocessable(
                "the bot has no files: send `files` or `archive_base64`".into(),
            )),
            (Some(map), None) => botfiles::write_files(&map, &dest, &limits).map_err(bundle_error),
            (None, Some(bytes)) => {
                botfiles::unpack_archive(&bytes, &dest, &limits).map_err(bundle_error)
            }
        }
    })
    .await
    .map_err(|e| ApiError::Internal(format!("unpacking task failed: {e}")))?;
    match result {
        Ok(summary) => Ok((dir, summary)),
        Err(e) => {
            remove_dir(&dir).await;
            Err(e)
        }
    }
}

fn bundle_error(e: BundleError) -> ApiError {
    if matches!(
        e,
        BundleError::TooLarge { .. } | BundleError::TooManyFiles { .. }
    ) {
        ApiError::PayloadTooLarge(e.to_string())
    } else if e.is_client_error() {
        ApiError::Unprocessable(e.to_string())
    } else {
        ApiError::Internal(e.to_string())
    }
}

async fn remove_dir(dir: &Path) {
    if let Err(e) = tokio::fs::remove_dir_all(dir).await {
        tracing::warn!(cause = %e, dir = %dir.display(), "could not remove a bot directory");
    }
}
