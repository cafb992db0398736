//! Health, metrics, the OpenAPI document, and the JSON answer to a handler panic.

use std::any::Any;

use axum::extract::State;
use axum::http::{StatusCode, header};
use axum::response::{IntoResponse, Response};
use serde::Serialize;
use utoipa::ToSchema;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

use super::AppState;
use super::auth::Caller;
use super::error::{ApiError, ApiResult};
use crate::storage::workers::WorkerRow;

pub(super) fn router() -> OpenApiRouter<AppState> {
    OpenApiRouter::new()
        .routes(routes!(healthz))
        .routes(routes!(metrics))
        .routes(routes!(openapi_json))
        .routes(routes!(runtimes))
}

/// The runtimes bots may use on this server: the operator's (`--runtime DIR`, each by
/// the name a bot gives as `runtime` to have it first on its `PATH`) and the system's,
/// with their programs' versions and installed packages.
#[utoipa::path(get, path = "/api/runtimes", tag = "system",
    responses((status = 200, body = [crate::runner::runtimes::RuntimeInfo])))]
async fn runtimes(
    State(state): State<AppState>,
) -> axum::Json<Vec<crate::runner::runtimes::RuntimeInfo>> {
    axum::Json(state.runtimes.as_ref().clone())
}

/// Health of the server. The counts (`queued`, `workers`) are the admin's: they move
/// with matches on hidden mazes, so anyone else gets the status and the server's kind
/// of isolation only.
#[derive(Debug, Serialize, ToSchema)]
pub struct Health {
    /// `ok` when the database answers.
    pub status: &'static str,
    /// Matches waiting to be played (the admin only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub queued: Option<i64>,
    /// How bots are isolated: `full` (the sandbox), `none` (started with
    /// `--sandbox none`: only for bots the operator trusts) or `unused` (an API server,
    /// `serve --jobs 0`, runs no bot; each of `workers` reports its own).
    pub sandbox: &'static str,
    /// What keeps each match's limits on this server: `cgroup` (memory, processes, one
    /// core per match), `watchdog` (no cgroup could be made here, e.g. in a container:
    /// memory and processes watched over the bot's process tree, no CPU limit) or
    /// `rlimit` (no sandbox: the address space only); `unused` on an API server.
    pub limits: &'static str,
    /// The processes playing matches (this server's pool and `mazearena worker`s, on any
    /// machine) that reported within the last 30 seconds, with their counts (the admin
    /// only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub workers: Option<Vec<WorkerRow>>,
}

/// Liveness and database check: `ok`, or a 500 when the database does not answer. The
/// admin also gets the queue's length and the workers.
#[utoipa::path(get, path = "/healthz", tag = "system",
    responses((status = 200, body = Health), (status = 500, body = super::error::ErrorBody)))]
async fn healthz(State(state): State<AppState>, caller: Caller) -> ApiResult<axum::Json<Health>> {
    state.storage.ping().await?;
    let (queued, workers) = if caller.is_admin() {
        let queued = state.storage.queued_count().await?;
        let workers = state
            .storage
            .live_workers(crate::metrics::LIVE_WINDOW.as_millis() as i64)
            .await?;
        (Some(queued), Some(workers))
    } else {
        (None, None)
    };
    Ok(axum::Json(Health {
        status: "ok",
        queued,
        sandbox: state.settings.sandbox_level,
        limits: state.settings.limits,
        workers,
    }))
}

/// Prometheus metrics: matches by status, queue depth, match duration histogram. They
/// count and time matches on hidden mazes, so they answer only the metrics token
/// (`serve --metrics-token`, Prometheus' `bearer_token`) or the admin token.
#[utoipa::path(get, path = "/metrics", tag = "system", security(("bearer" = [])),
    responses((status = 200, description = "Prometheus metrics in the OpenMetrics text format",
        content_type = "application/openmetrics-text; version=1.0.0; charset=utf-8"),
        (status = 401, body = super::error::ErrorBody), (status = 403, body = super::error::ErrorBody)))]
async fn metrics(
    State(state): State<AppState>,
    headers: axum::http::HeaderMap,
    caller: Caller,
) -> ApiResult<Response> {
    let metrics_token = headers
        .get(header::AUTHORIZATION)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.strip_prefix("Bearer "))
        .map(|t| super::auth::hash_token(t.trim()));
    let allowed = caller.is_admin()
        || (metrics_token.is_some() && metrics_token == state.settings.metrics_token_hash);
    if !allowed {
        return Err(match caller {
            Caller::Anonymous => ApiError::Unauthorized(
                "/metrics needs the metrics token or the admin token (Authorization: Bearer TOKEN)"
                    .into(),
            ),
            _ => ApiError::Forbidden("/metrics needs the metrics token or the admin token".into()),
        });
    }
    let text = state.metrics.render(&state.storage).await?;
    Ok((
        [(
            header::CONTENT_TYPE,
            "application/openmetrics-text; version=1.0.0; charset=utf-8",
        )],
        text,
    )
        .into_response())
}

/// This API's OpenAPI 3 document.
#[utoipa::path(get, path = "/api/openapi.json", tag = "system",
    responses((status = 200, description = "OpenAPI document", content_type = "application/json")))]
async fn openapi_json() -> Response {
    axum::Json(super::openapi()).into_response()
}

/// Turns a handler panic into a JSON 500 (the details go to the log).
pub(super) fn panic_response(err: Box<dyn Any + Send + 'static>) -> Response {
    let detail = err
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| err.downcast_ref::<&str>().map(|s| s.to_string()))
        .unwrap_or_else(|| "unknown panic".to_string());
    let mut response = ApiError::Internal(format!("handler panicked: {detail}")).into_response();
    *response.status_mut() = StatusCode::INTERNAL_SERVER_ERROR;
    response
}
