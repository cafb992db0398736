//! The HTTP face (axum): thin handlers that extract, call the registry's operations or
//! storage, and answer JSON.
//!
//! Routes (see `GET /api/openapi.json`, generated from these handlers):
//! bots, entrants, competitions, mazes, matches, tournaments, leaderboard, plus
//! `/healthz` and `/metrics`; and the site ([`site`]: the handlers of the pages and
//! forms, `/`, `/competitions`, `/bots`, `/mazes`, `/matches`, `/tournaments`, whose
//! views are [`crate::web`]).
//! Every error has the shape `{"error":{"code":..,"message":..}}` ([`error`]).

pub mod auth;
pub mod bots;
pub mod client_address;
pub mod competitions;
pub mod connections;
pub mod entrants;
pub mod error;
pub mod finale;
pub mod invites;
pub mod leaderboard;
pub mod limits;
pub mod lists;
pub mod matches;
pub mod mazes;
pub mod practice;
pub mod session;
pub mod site;
pub mod system;
pub mod tournaments;

use std::future::Future;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use axum::Router;
use axum::extract::DefaultBodyLimit;
use axum::http::StatusCode;
use tokio::net::TcpListener;
use tokio::sync::Notify;
use tower_http::catch_panic::CatchPanicLayer;
use tower_http::compression::CompressionLayer;
use tower_http::timeout::TimeoutLayer;
use tower_http::trace::TraceLayer;
use utoipa::OpenApi;
use utoipa_axum::router::OpenApiRouter;

use crate::metrics::Metrics;
use crate::storage::Storage;

/// Largest request body outside bot uploads: a 1 MiB maze plus its JSON envelope.
pub const MAX_BODY_BYTES: usize = 2 * 1024 * 1024;

/// Largest bot upload body (an archive, base64 in JSON or raw in a form).
pub const MAX_UPLOAD_BYTES: usize = 32 * 1024 * 1024;

/// How long one request may take before it is answered 408.
pub const REQUEST_TIMEOUT: Duration = Duration::from_secs(30);

/// Server settings the handlers need.
#[derive(Debug, Clone)]
pub struct Settings {
    /// SHA-256 of the admin token.
    pub admin_token_hash: String,
    /// SHA-256 of the token that may read `/metrics` besides the admin's.
    pub metrics_token_hash: Option<String>,
    /// The local data folder (uploads are checked in its `tmp` folder).
    pub data_dir: PathBuf,
    /// The most matches that may wait in the queue; beyond it, 429.
    pub max_queue: i64,
    /// The isolation of bots (`full` or `none`), shown by `/healthz`.
    pub sandbox_level: &'static str,
    /// What keeps each match's limits ([`crate::runner::Sandbox::limits`]), shown by
    /// `/healthz`.
    pub limits: &'static str,
    /// The most matches one owner may have waiting in the queue (the admin: no limit).
    pub max_queued_per_owner: i64,
    /// The most bytes of stored match records one owner may have before its new matches
    /// are refused (`None`: no cap; the admin: no cap).
    pub max_stored_bytes_per_owner: Option<i64>,
    /// The budgets of what proves nothing (wrong keys and codes, anonymous
    /// registrations), per client address ([`limits`]).
    pub budgets: limits::Budgets,
    /// The owners' quotas on uploads ([`crate::registry::owners`]).
    pub owner_quotas: crate::registry::owners::OwnerQuotas,
    /// Whether the server is reached over HTTPS: session cookies are then `Secure`.
    pub secure_cookies: bool,
}

impl Settings {
    /// The local folder where uploads are unpacked and checked before they are stored.
    pub fn scratch(&self) -> PathBuf {
        self.data_dir.join("tmp")
    }
}

/// What every handler gets: cheap to clone.
#[derive(Debug, Clone)]
pub struct AppState {
    /// The database.
    pub storage: Storage,
    /// Settings.
    pub settings: Arc<Settings>,
    /// Metrics.
    pub metrics: Metrics,
    /// Wakes the workers when matches are queued.
    pub wake: Arc<Notify>,
    /// Ranks standings with their uncertainty, keeping the last tables.
    pub ranker: Arc<crate::registry::rankings::Ranker>,
    /// The final night's reveals and races made lately (a few seconds).
    pub shows: Arc<crate::registry::finale::Shows>,
    /// The runtimes bots may use here (found at start-up).
    pub runtimes: Arc<Vec<crate::runner::runtimes::RuntimeInfo>>,
}

/// The OpenAPI document's header; paths come from the handlers.
#[derive(OpenApi)]
#[openapi(
    info(
        title = "mazearena",
        description = "Match server for the micromouse maze task: bots, mazes, matches, tournaments, leaderboards."
    ),
    components(schemas(error::ErrorBody))
)]
pub struct ApiDoc;

/// The OpenAPI document of every route, built once.
pub fn openapi() -> &'static utoipa::openapi::OpenApi {
    static DOC: std::sync::OnceLock<utoipa::openapi::OpenApi> = std::sync::OnceLock::new();
    DOC.get_or_init(|| routes().1)
}

/// All routes with their OpenAPI description.
pub fn routes() -> (Router<AppState>, utoipa::openapi::OpenApi) {
    let (router, mut doc) = OpenApiRouter::with_openapi(ApiDoc::openapi())
        .merge(bots::router())
        .merge(entrants::router())
        .merge(competitions::router())
        .merge(finale::router())
        .merge(invites::router())
        .merge(practice::router())
        .merge(mazes::router())
        .merge(matches::router())
        .merge(tournaments::router())
        .merge(leaderboard::router())
        .merge(system::router())
        .split_for_parts();
    document_input_errors(&mut doc);
    (router, doc)
}

/// Adds to every operation the JSON errors that any route answers to bad input, so that
/// the document lists every status a client can get: 400 for a malformed id or query
/// parameter (or body), and for a request body also 413 (too large), 415 (not the
/// content type asked for) and 422 (well-formed but invalid values).
fn document_input_errors(doc: &mut utoipa::openapi::OpenApi) {
    use utoipa::openapi::{ContentBuilder, Ref, RefOr, ResponseBuilder};
    let error = |description: &str| {
        RefOr::T(
            ResponseBuilder::new()
                .description(description)
                .content(
                    "application/json",
                    ContentBuilder::new()
                        .schema(Some(Ref::from_schema_name("ErrorBody")))
                        .build(),
                )
                .build(),
        )
    };
    for item in doc.paths.paths.values_mut() {
        for op in [
            &mut item.get,
            &mut item.post,
            &mut item.put,
            &mut item.patch,
            &mut item.delete,
        ]
        .into_iter()
        .flatten()
        {
            let has_params = op.parameters.as_ref().is_some_and(|p| !p.is_empty());
            let has_body = op.request_body.is_some();
            let mut add = |code: &str, description: &str| {
                op.responses
                    .responses
                    .entry(code.to_string())
                    .or_insert_with(|| error(description));
            };
            if has_params || has_body {
                add(
                    "400",
                    "Bad request: a malformed id, query parameter or body",
                );
            }
            if has_body {
                add("413", "The request body is too large");
                add(
                    "415",
                    "The request body is not of a content type the route takes",
                );
                add(
                    "422",
                    "The request body is well-formed but its values are invalid",
                );
            }
        }
    }
}

/// The application: routes, JSON fallbacks and the middleware stack.
pub fn app(state: AppState) -> Router {
    let (router, _) = routes();
    router
        .merge(site::router())
        .fallback(error::not_found)
        .method_not_allowed_fallback(error::method_not_allowed)
        .layer(DefaultBodyLimit::max(MAX_BODY_BYTES))
        .layer(axum::middleware::from_fn_with_state(
            state.clone(),
            session::clear_tossed_cookies,
        ))
        .layer(CompressionLayer::new())
        .layer(TimeoutLayer::with_status_code(
            StatusCode::REQUEST_TIMEOUT,
            REQUEST_TIMEOUT,
        ))
        .layer(CatchPanicLayer::custom(system::panic_response))
        .layer(axum::middleware::map_response(security_headers))
        .layer(TraceLayer::new_for_http())
        .with_state(state)
}

/// Adds the security headers ([`crate::web::policy`]) to every answer.
async fn security_headers(mut response: axum::response::Response) -> axum::response::Response {
    use axum::http::{HeaderName, HeaderValue};
    static HEADERS: std::sync::OnceLock<Vec<(HeaderName, HeaderValue)>> =
        std::sync::OnceLock::new();
    let headers = HEADERS.get_or_init(|| {
        crate::web::policy::headers()
            .into_iter()
            .map(|(name, value)| {
                (
                    HeaderName::from_static(name),
                    HeaderValue::from_str(&value).expect("BUG: a security header is not ASCII"),
                )
            })
            .collect()
    });
    for (name, value) in headers {
        response
            .headers_mut()
            .entry(name.clone())
            .or_insert_with(|| value.clone());
    }
    response
}

/// Serves the API on `listener` within `limits` ([`connections`]), believing the
/// forwarding headers of the `trusted` proxies only ([`client_address`]), until
/// `shutdown` completes, then finishes the requests in flight.
///
/// # Errors
/// When the listener fails.
pub async fn serve(
    listener: TcpListener,
    state: AppState,
    limits: connections::ConnectionLimits,
    trusted: client_address::TrustedProxies,
    shutdown: impl Future<Output = ()> + Send + 'static,
) -> std::io::Result<()> {
    connections::serve(listener, app(state), limits, Arc::new(trusted), shutdown).await
}
