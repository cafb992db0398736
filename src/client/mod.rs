//! The client side of a server: what `mazearena login`, `submit`, `status`, `matches`,
//! `logs`, `replay ID` and `practice` use to speak to a mazearena server's API.
//!
//! - [`config`]: the server and key a participant logged in with, kept in a file only
//!   they can read (or given by `MAZEARENA_SERVER` and `MAZEARENA_KEY`).
//! - [`pack`]: a bot's folder packed as the server stores it (`.gitignore` honoured,
//!   dot-files left out unless `bot.toml` names them in `include`).
//! - [`show`]: server text made safe to print (no control character of the server's
//!   reaches the terminal).
//! - [`Api`]: the HTTP calls, each failure turned into a [`ClientError`] that says what
//!   the server said, not how HTTP failed.

pub mod config;
pub mod pack;
pub mod show;

use std::time::Duration;

use reqwest::{Method, StatusCode};
use serde::Serialize;
use serde::de::DeserializeOwned;
use serde_json::Value;

/// Why a call to the server did not work. Its text ([`std::fmt::Display`]) shows what
/// came from the server escaped ([`show::text`]), so it can be printed as it is.
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    /// The server answered with an error: its own message.
    #[error("{} (HTTP {status} from {})", show::text(.message), show::text(.what))]
    Refused {
        /// The HTTP status.
        status: u16,
        /// The server's message (its JSON error's `message`, or the start of its
        /// answer).
        message: String,
        /// The request, e.g. `POST /api/bots`.
        what: String,
        /// Seconds to wait, when the server said (`Retry-After`).
        retry_after: Option<u64>,
    },
    /// The server could not be reached or its answer not read.
    #[error(
        "cannot reach the server at {}: {}",
        show::text(.server),
        show::text(.reason)
    )]
    Unreachable {
        /// The server's address.
        server: String,
        /// Why, in a few words.
        reason: String,
    },
    /// The server answered something that is not what mazearena answers.
    #[error(
        "the server's answer to {} is not what a mazearena server sends: {}",
        show::text(.what),
        show::text(.reason)
    )]
    Unexpected {
        /// The request.
        what: String,
        /// Why.
        reason: String,
    },
}

impl ClientError {
    /// The HTTP status of a refusal.
    pub fn status(&self) -> Option<u16> {
        match self {
            ClientError::Refused { status, .. } => Some(*status),
            _ => None,
        }
    }
}

/// A server's API, called with a key (or none).
#[derive(Debug, Clone)]
pub struct Api {
    server: String,
    key: Option<String>,
    http: reqwest::Client,
}

/// What an answer is read as.
enum Body {
    Json(Value),
    Form(reqwest::multipart::Form),
    None,
}

impl Api {
    /// The API of the server at `server` (e.g. `http://localhost:8080`), called with
    /// `key` when given.
    ///
    /// # Errors
    /// An address that is not `http://` or `https://`.
    pub fn new(server: &str, key: Option<String>) -> Result<Api, ClientError> {
        let server = server.trim().trim_end_matches('/').to_string();
        if !(server.starts_with("http://") || server.starts_with("https://")) {
            return Err(ClientError::Unreachable {
                server,
                reason: "the address must start with http:// or https://".into(),
            });
        }
        let http = reqwest::Client::builder()
            .connect_timeout(Duration::from_secs(10))
            .timeout(Duration::from_secs(120))
            .user_agent(concat!("mazearena/", env!("CARGO_PKG_VERSION")))
            .build()
            .map_err(|e| ClientError::Unreachable {
                server: server.clone(),
                reason: e.to_string(),
            })?;
        Ok(Api { server, key, http })
    }

    /// The server's address, without a trailing `/`.
    pub fn server(&self) -> &str {
        &self.server
    }

    /// The key the calls are made with.
    pub fn key(&self) -> Option<&str> {
        self.key.as_deref()
    }

    /// The same server with another key.
    pub fn with_key(&self, key: Option<String>) -> Api {
        Api {
            key,
            ..self.clone()
        }
    }

    async fn call(
        &self,
        method: Method,
        path: &str,
        body: Body,
    ) -> Result<reqwest::Response, ClientError> {
        let what = format!("{method} {path}");
        let mut request = self.http.request(method, format!("{}{path}", self.server));
        if let Some(key) = &self.key {
            request = request.bearer_auth(key);
        }
        request = match body {
            Body::Json(v) => request.json(&v),
            Body::Form(f) => request.multipart(f),
            Body::None => request,
        };
        let response = request.send().await.map_err(|e| ClientError::Unreachable {
            server: self.server.clone(),
            reason: short_reason(&e),
        })?;
        let status = response.status();
        if status.is_success() {
            return Ok(response);
        }
        let retry_after = response
            .headers()
            .get(reqwest::header::RETRY_AFTER)
            .and_then(|v| v.to_str().ok())
            .and_then(|v| v.trim().parse().ok());
        let text = response.text().await.unwrap_or_default();
        let message = serde_json::from_str::<Value>(&text)
            .ok()
            .and_then(|v| {
                v["error"]["message"]
                    .as_str()
                    .or_else(|| v["error"].as_str())
                    .map(str::to_string)
            })
            .unwrap_or_else(|| {
                let t = text.trim();
                if t.is_empty() {
                    status
                        .canonical_reason()
                        .unwrap_or("no message")
                        .to_string()
                } else {
                    t.chars().take(300).collect()
                }
            });
        Err(ClientError::Refused {
            status: status.as_u16(),
            message,
            what,
            retry_after,
        })
    }

    async fn json<T: DeserializeOwned>(
        &self,
        method: Method,
        path: &str,
        body: Body,
    ) -> Result<T, ClientError> {
        let what = format!("{method} {path}");
        let response = self.call(method, path, body).await?;
        let bytes = response
            .bytes()
            .await
            .map_err(|e| ClientError::Unreachable {
                server: self.server.clone(),
                reason: short_reason(&e),
            })?;
        serde_json::from_slice(&bytes).map_err(|e| ClientError::Unexpected {
            what,
            reason: e.to_string(),
        })
    }

    /// `GET path`, read as JSON.
    ///
    /// # Errors
    /// See [`ClientError`].
    pub async fn get<T: DeserializeOwned>(&self, path: &str) -> Result<T, ClientError> {
        self.json(Method::GET, path, Body::None).await
    }

    /// `GET path`, as text.
    ///
    /// # Errors
    /// See [`ClientError`].
    pub async fn get_text(&self, path: &str) -> Result<String, ClientError> {
        let response = self.call(Method::GET, path, Body::None).await?;
        response.text().await.map_err(|e| ClientError::Unreachable {
            server: self.server.clone(),
            reason: short_reason(&e),
        })
    }

    /// `POST path` with a JSON body, read as JSON.
    ///
    /// # Errors
    /// See [`ClientError`].
    pub async fn post<T: DeserializeOwned>(
        &self,
        path: &str,
        body: &impl Serialize,
    ) -> Result<T, ClientError> {
        let body = serde_json::to_value(body).map_err(|e| ClientError::Unexpected {
            what: format!("POST {path}"),
            reason: e.to_string(),
        })?;
        self.json(Method::POST, path, Body::Json(body)).await
    }

    /// `POST path` with a form, read as JSON.
    ///
    /// # Errors
    /// See [`ClientError`].
    pub async fn post_form<T: DeserializeOwned>(
        &self,
        path: &str,
        form: reqwest::multipart::Form,
    ) -> Result<T, ClientError> {
        self.json(Method::POST, path, Body::Form(form)).await
    }
}

/// Why a request failed, in a few words (not the chain of HTTP library details).
fn short_reason(e: &reqwest::Error) -> String {
    if e.is_timeout() {
        "no answer in time".into()
    } else if e.is_connect() {
        let mut source: Option<&dyn std::error::Error> = std::error::Error::source(e);
        let mut last = None;
        while let Some(s) = source {
            last = Some(s.to_string());
            source = s.source();
        }
        format!(
            "cannot connect ({})",
            last.unwrap_or_else(|| "refused".into())
        )
    } else if e.is_decode() || e.is_body() {
        "the answer was cut off".into()
    } else {
        e.to_string()
    }
}

/// Whether a refusal has `status`.
pub fn is_status(e: &ClientError, status: StatusCode) -> bool {
    e.status() == Some(status.as_u16())
}
