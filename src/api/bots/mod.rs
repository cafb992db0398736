//! Bots: register (with files), upload new versions (which resumes a paused bot), list,
//! show, and resume a paused bot (admin).

pub(crate) mod upload;

use std::collections::BTreeMap;

use axum::extract::{DefaultBodyLimit, Request, State};
use axum::http::StatusCode;
use serde::{Deserialize, Serialize};
use utoipa::ToSchema;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

use super::auth::Caller;
use super::error::{ApiError, ApiResult, AppPath, ErrorBody};
use super::{AppState, MAX_UPLOAD_BYTES};
use crate::registry;
use crate::storage::bots::BotVersionRow;
use crate::storage::owners::Owner;
use upload::{Upload, read_upload};

pub use crate::registry::bots::{MAX_COMMAND_CHARS, MAX_NAME_CHARS};

pub(super) fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(create_bot, list_bots))
        .routes(routes!(get_bot))
        .routes(routes!(create_bot_version))
        .routes(routes!(resume_bot))
        .routes(routes!(get_build_log))
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
    /// The command that runs the bot in its directory, e.g. `python3 bot.py` (may be
    /// left out with `original_task`).
    #[serde(default)]
    pub command: String,
    /// The files are a robot of the original task (and its own modules): the server
    /// adds its adapter, `udacity_adapter.py`, and the command defaults to `python3
    /// udacity_adapter.py ROBOT_FILE` (`python ...` with a `runtime`). (Form: `original_task`
    /// set to `true` or `on`.)
    #[serde(default)]
    pub original_task: bool,
    /// Registration only, with an entrant's key: enter the new bot in this competition
    /// (its short name) in the same step, so that its first version is validated by
    /// the competition's rule on its practice mazes. (Form: `competition`.)
    #[serde(default)]
    pub competition: Option<String>,
    /// With `original_task`: the file that holds `class Robot`, at the top of the files
    /// (e.g. `robot_final.py`); left out: `robot.py`, or else the only top-level `.py`
    /// file that defines `class Robot`. The command then names it. (Form: `robot_file`.)
    #[serde(default)]
    pub robot_file: Option<String>,
    /// The protocol the bot speaks: `v1` (the default: JSON lines, docs/PROTOCOL.md) or
    /// `mms` (a mouse written for the mms simulator, played unchanged through the
    /// referee's translation: docs/PROTOCOL-mms.md). (Form: `protocol`.)
    #[serde(default)]
    pub protocol: Option<String>,
    /// Small bots: file name -> content.
    #[serde(default)]
    pub files: Option<BTreeMap<String, String>>,
    /// An archive of the bot's directory, base64-encoded.
    #[serde(default)]
    pub archive_base64: Option<String>,
    /// A build command (e.g. `make`, `cargo build --release --offline`) that the server
    /// runs once in the sandbox (no network) before the version plays. (Form: `build`.)
    #[serde(default)]
    pub build: Option<String>,
    /// Environment variables for the bot: names `[A-Za-z_][A-Za-z0-9_]*`, not PATH, HOME,
    /// TMPDIR or `MAZEARENA_*`. (Form: repeated `env` fields `KEY=VALUE`.)
    #[serde(default)]
    pub env: Option<BTreeMap<String, String>>,
    /// The server's runtime to put first on the bot's `PATH` (a name from
    /// `GET /api/runtimes`, e.g. a venv with numpy). (Form: `runtime`.)
    #[serde(default)]
    pub runtime: Option<String>,
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
    /// The build command run once before it plays, if any.
    pub build_command: Option<String>,
    /// `ready` (plays), `building` (waiting for or in its build) or `build_failed`
    /// (never plays; its matches are recorded as crashed).
    pub build_status: String,
    /// When the build ended (unix ms).
    pub built_at: Option<i64>,
    /// How long its build and validation match took on the builder (ms): spent from its
    /// owner's daily build minutes, whatever the outcome.
    pub build_ms: Option<i64>,
    /// The end of the build's output (owner and admin only; the whole log is at
    /// `GET /api/bots/{id}/versions/{version}/build-log`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub build_log_tail: Option<String>,
    /// The names of the environment variables declared for the bot (values are shown
    /// to nobody).
    pub env_names: Vec<String>,
    /// The runtime it asked to have first on its `PATH` (`GET /api/runtimes`).
    pub runtime: Option<String>,
    /// The protocol it speaks: `v1` or `mms`.
    pub protocol: String,
}

/// Lines of a build log shown in a version's view.
const BUILD_LOG_TAIL_LINES: usize = 20;

impl From<BotVersionRow> for VersionView {
    fn from(v: BotVersionRow) -> Self {
        VersionView {
            version: v.version,
            bot_version_id: v.bot_version_id,
            env_names: v.env_pairs().into_iter().map(|(k, _)| k).collect(),
            command: v.command,
            files_sha256: v.files_sha256,
            file_count: v.file_count,
            created_at: v.created_at,
            build_command: v.build_command,
            build_status: v.build_status,
            built_at: v.built_at,
            build_ms: v.build_ms,
            build_log_tail: None,
            protocol: crate::runner::BotProtocol::of_stored(v.protocol.as_deref())
                .as_str()
                .to_string(),
            runtime: v.runtime,
        }
    }
}

/// A version's build log (owner and admin).
#[derive(Debug, Serialize, ToSchema)]
pub struct BuildLogView {
    /// The version number.
    pub version: i64,
    /// The build command.
    pub build_command: Option<String>,
    /// `ready`, `building` or `build_failed`.
    pub build_status: String,
    /// When the build ended (unix ms).
    pub built_at: Option<i64>,
    /// The build's output (stdout and stderr, its last 64 KiB); null before it ran.
    pub build_log: Option<String>,
}

fn log_tail(log: &str) -> String {
    let lines: Vec<&str> = log.lines().collect();
    lines[lines.len().saturating_sub(BUILD_LOG_TAIL_LINES)..].join("\n")
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
    /// The latest version's build status: `ready`, `building` or `build_failed`.
    pub build_status: String,
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

/// Register a bot with its files; answers its id and owner token. Registrations
/// without a key are limited per client address, an entrant's by its own quotas (429
/// with Retry-After saying whose).
#[utoipa::path(post, path = "/api/bots", tag = "bots",
    request_body(content(
        (BotUpload = "application/json"),
        (BotUpload = "multipart/form-data"),
    )),
    responses(
        (status = 201, body = BotCreated),
        (status = 400, body = ErrorBody), (status = 409, body = ErrorBody),
        (status = 413, body = ErrorBody), (status = 422, body = ErrorBody),
        (status = 404, body = ErrorBody, description = "no competition of the name given in `competition`"),
        (status = 403, body = ErrorBody, description = "registration is not open and no entrant's key was given, or `competition` without an entrant's key"),
        (status = 429, body = ErrorBody, description = "a budget is used up: registrations without a key from this address, or the entrant's quotas (the message says whose); see Retry-After"),
    ))]
async fn create_bot(
    State(state): State<AppState>,
    caller: Caller,
    request: Request,
) -> ApiResult<(StatusCode, axum::Json<BotCreated>)> {
    let client = super::client_address::of_request(&request);
    let upload = read_upload(&state, request).await?;
    let enter = upload.competition.clone();
    let created = register_bot(&state, &caller, client, upload, enter.as_deref()).await?;
    Ok((StatusCode::CREATED, axum::Json(created)))
}

/// Registers a bot from `upload` for `caller` (from address `client`): the API's and
/// the submission page's one way.
///
/// # Errors
/// The registration limit or mode; a bad upload; a taken name.
pub(crate) async fn register_bot(
    state: &AppState,
    caller: &Caller,
    client: Option<std::net::IpAddr>,
    upload: Upload,
    enter: Option<&str>,
) -> ApiResult<BotCreated> {
    // With an entrant's key the bot is the entrant's, held by the entrant's quotas;
    // without one, only an open server takes it, on its address's budget
    // (`api::limits`). The admin and the organisers have neither.
    let entrant = match caller {
        Caller::Token(hash) => state.storage.entrant_by_key(hash).await?,
        _ => None,
    };
    // Entered in a competition in the same step: the entrant's, while it takes part.
    let enter = match enter.map(str::trim).filter(|n| !n.is_empty()) {
        Some(name) => {
            let c = super::competitions::find(state, name).await?;
            if entrant.is_none() {
                return Err(ApiError::Forbidden(format!(
                    "entering competition {} needs an entrant's key (Authorization: Bearer KEY)",
                    c.name
                )));
            }
            if c.kind != "competition" {
                return Err(ApiError::Conflict(
                    "the default competition needs no entry: every bot's latest version counts"
                        .into(),
                ));
            }
            if registry::competitions::phase(&c, crate::storage::now_ms()).is_closed() {
                return Err(ApiError::Conflict(format!(
                    "competition {} closed at {}",
                    c.name,
                    crate::competition::Timestamp(c.closes_at.unwrap_or(0)).words()
                )));
            }
            Some(c.competition_id)
        }
        None => None,
    };
    if entrant.is_none() && !caller.is_admin() {
        let registration = state.storage.registration().await?;
        if registration != crate::storage::entrants::Registration::Open {
            return Err(ApiError::Forbidden(
                "registration is not open: register bots with an entrant's key \
                 (POST /api/entrants, then Authorization: Bearer KEY)"
                    .into(),
            ));
        }
        if !caller.can_organise() {
            super::limits::spend(state, super::limits::Spend::AnonymousRegistration, client)
                .await?;
        }
    }
    // An entrant's new bot is held by the entrant's quotas (its first version is one of
    // a bot outside competitions); checked before the files are unpacked, and again where
    // the bot is stored.
    let now = crate::storage::now_ms();
    let owner = match (&entrant, caller.is_admin()) {
        (Some(e), false) => Some(state.settings.owner_quotas.limits(
            Owner::Entrant(e.entrant_id),
            enter.is_none(),
            now,
        )),
        _ => None,
    };
    if let Some(limits) = &owner {
        registry::owners::check(&state.storage, limits, now).await?;
    }
    let (name, submission) = upload.submission()?;
    check_runtime(state, submission.runtime.as_deref())?;
    let name = name.ok_or_else(|| ApiError::Unprocessable("a bot needs a `name`".into()))?;
    let registered = registry::bots::register(
        &state.storage,
        &name,
        submission,
        &state.settings.scratch(),
        entrant.as_ref().map(|e| e.entrant_id),
        owner.as_ref(),
        enter,
    )
    .await?;
    state.wake.notify_waiters();
    let row = registered.version;
    let token = registered.owner_token;
    Ok(BotCreated {
        bot_id: row.bot_id,
        name,
        owner_token: token,
        version: row.into(),
    })
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
        (status = 404, body = ErrorBody), (status = 409, body = ErrorBody),
        (status = 422, body = ErrorBody), (status = 429, body = ErrorBody),
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
    let row = add_bot_version(&state, &caller, id, upload).await?;
    Ok((StatusCode::CREATED, axum::Json(row.into())))
}

/// Adds a version from `upload` to bot `id` for `caller` (its owner or the admin): the
/// API's and the submission page's one way.
///
/// # Errors
/// No such bot; not its owner; the competition's close or quota; a bad upload.
pub(crate) async fn add_bot_version(
    state: &AppState,
    caller: &Caller,
    id: i64,
    upload: Upload,
) -> ApiResult<BotVersionRow> {
    if state.storage.get_bot(id).await?.is_none() {
        return Err(ApiError::NotFound(format!("no bot {id}")));
    }
    caller.require_owner(state, id).await?;
    let now = crate::storage::now_ms();
    let quotas = match registry::competitions::check_upload(&state.storage, id, now).await? {
        Ok(quotas) => quotas,
        Err(registry::competitions::UploadRefusal::Closed(message)) => {
            return Err(ApiError::Conflict(message));
        }
        Err(registry::competitions::UploadRefusal::Quota(message, quota)) => {
            return Err(ApiError::TooManyRequests {
                message,
                retry_after_secs: quota.retry_after_secs(now),
            });
        }
    };
    // The owner's own quotas (builds waiting, build time, and for a bot in no
    // competition its daily versions); the admin has none.
    let owner = if caller.is_admin() {
        None
    } else {
        let outside = state
            .storage
            .competitions_of_bot(id)
            .await?
            .iter()
            .all(|c| c.kind != "competition");
        state
            .storage
            .owner_of_bot(id)
            .await?
            .map(|o| state.settings.owner_quotas.limits(o, outside, now))
    };
    if let Some(limits) = &owner {
        registry::owners::check(&state.storage, limits, now).await?;
    }
    let (_, submission) = upload.submission()?;
    check_runtime(state, submission.runtime.as_deref())?;
    // The quotas are counted again where the version is added: uploads sent at once
    // all pass the check above before any is added.
    let row = registry::bots::add_version(
        &state.storage,
        id,
        submission,
        &state.settings.scratch(),
        &quotas,
        owner.as_ref(),
    )
    .await?;
    state.wake.notify_waiters();
    Ok(row)
}

/// Refuses a runtime this server does not offer (422, with those it offers).
fn check_runtime(state: &AppState, runtime: Option<&str>) -> ApiResult<()> {
    let Some(name) = runtime else {
        return Ok(());
    };
    let offered: Vec<&str> = state
        .runtimes
        .iter()
        .filter(|r| r.kind == "operator")
        .map(|r| r.name.as_str())
        .collect();
    if offered.contains(&name) {
        return Ok(());
    }
    Err(ApiError::Unprocessable(format!(
        "this server has no runtime named {name:?}: {} (GET /api/runtimes lists them; \
         leave `runtime` out for the system's)",
        if offered.is_empty() {
            "it offers none besides the system's".to_string()
        } else {
            format!("it offers {}", offered.join(", "))
        }
    )))
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
                build_status: b.build_status,
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
    caller: Caller,
    AppPath(id): AppPath<i64>,
) -> ApiResult<axum::Json<BotDetail>> {
    let mut detail = bot_detail(&state, id).await?;
    if caller.owns(&state, id).await? {
        let versions = state.storage.bot_versions(id).await?;
        for (view, row) in detail.versions.iter_mut().zip(versions) {
            view.build_log_tail = row.build_log.as_deref().map(log_tail);
        }
    }
    Ok(axum::Json(detail))
}

/// A version's whole build log (owner token or admin).
#[utoipa::path(get, path = "/api/bots/{id}/versions/{version}/build-log", tag = "bots",
    params(("id" = i64, Path, description = "bot id"), ("version" = i64, Path, description = "version number")),
    security(("bearer" = [])),
    responses(
        (status = 200, body = BuildLogView),
        (status = 401, body = ErrorBody), (status = 403, body = ErrorBody), (status = 404, body = ErrorBody),
    ))]
async fn get_build_log(
    State(state): State<AppState>,
    caller: Caller,
    AppPath((id, version)): AppPath<(i64, i64)>,
) -> ApiResult<axum::Json<BuildLogView>> {
    if state.storage.get_bot(id).await?.is_none() {
        return Err(ApiError::NotFound(format!("no bot {id}")));
    }
    caller.require_owner(&state, id).await?;
    let v = state
        .storage
        .bot_versions(id)
        .await?
        .into_iter()
        .find(|v| v.version == version)
        .ok_or_else(|| ApiError::NotFound(format!("bot {id} has no version {version}")))?;
    Ok(axum::Json(BuildLogView {
        version: v.version,
        build_command: v.build_command,
        build_status: v.build_status,
        built_at: v.built_at,
        build_log: v.build_log,
    }))
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
