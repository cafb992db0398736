//! What the pages' forms share: errors answered as pages (never JSON), redirects, the
//! client's address, and reading a urlencoded form into a struct.

use axum::extract::{FromRequest, Multipart, Request};
use axum::http::{HeaderValue, StatusCode, header};
use axum::response::{Html, IntoResponse, Redirect, Response};
use serde::de::DeserializeOwned;

use super::super::AppState;
use super::super::error::ApiError;
use super::super::session::Visitor;
use crate::web::pages as web;

/// A form's failure, answered as a page with its status.
#[derive(Debug)]
pub(super) struct PageError {
    status: StatusCode,
    message: String,
    retry_after: Option<u64>,
    /// The whole page to answer instead of the short message page.
    page: Option<String>,
}

/// A page handler's result.
pub(super) type PageResult<T = Response> = Result<T, PageError>;

impl PageError {
    /// A failure with this status and message.
    pub(super) fn new(status: StatusCode, message: impl Into<String>) -> PageError {
        PageError {
            status,
            message: message.into(),
            retry_after: None,
            page: None,
        }
    }

    /// The same failure answered with `page` (a form shown again with the message).
    pub(super) fn with_page(mut self, page: impl FnOnce(&str) -> String) -> PageError {
        self.page = Some(page(&self.message));
        self
    }

    /// Its message.
    pub(super) fn message(&self) -> &str {
        &self.message
    }
}

impl From<ApiError> for PageError {
    fn from(e: ApiError) -> PageError {
        let status = e.status_code();
        let retry_after = match &e {
            ApiError::TooManyRequests {
                retry_after_secs, ..
            } => Some(*retry_after_secs),
            _ => None,
        };
        let message = if status.is_server_error() {
            tracing::error!(error = %e, "a page's request failed");
            "the server failed to do this; it has been logged. Try again in a moment.".to_string()
        } else {
            e.to_string()
        };
        PageError {
            status,
            message,
            retry_after,
            page: None,
        }
    }
}

impl From<crate::storage::StorageError> for PageError {
    fn from(e: crate::storage::StorageError) -> PageError {
        ApiError::from(e).into()
    }
}

impl From<crate::registry::RegistryError> for PageError {
    fn from(e: crate::registry::RegistryError) -> PageError {
        ApiError::from(e).into()
    }
}

impl IntoResponse for PageError {
    fn into_response(self) -> Response {
        let title = match self.status {
            StatusCode::UNAUTHORIZED => "Please log in",
            StatusCode::FORBIDDEN => "Not allowed",
            StatusCode::NOT_FOUND => "Not found",
            StatusCode::TOO_MANY_REQUESTS => "Too many tries",
            StatusCode::PAYLOAD_TOO_LARGE => "Too large",
            s if s.is_server_error() => "Server error",
            _ => "Not done",
        };
        let body = self
            .page
            .unwrap_or_else(|| web::message(title, &self.message));
        let mut response = (self.status, Html(body)).into_response();
        if let Some(secs) = self.retry_after {
            response
                .headers_mut()
                .insert(header::RETRY_AFTER, HeaderValue::from(secs));
        }
        response
    }
}

/// A 303 to `to` (after a form post), with `cookie` set if given.
pub(super) fn see_other(to: &str, cookie: Option<cookie::Cookie<'static>>) -> Response {
    let mut response = Redirect::to(to).into_response();
    if let Some(c) = cookie
        && let Ok(v) = HeaderValue::from_str(&c.to_string())
    {
        response.headers_mut().append(header::SET_COOKIE, v);
    }
    response
}

/// The address of the client that sent `request`, when the server knows it.
pub(super) fn client_of(request: &Request) -> Option<std::net::IpAddr> {
    super::super::client_address::of_request(request)
}

/// Reads a urlencoded form into `T`; a malformed one is a 400 page.
pub(super) async fn read_form<T: DeserializeOwned>(
    state: &AppState,
    request: Request,
) -> PageResult<T> {
    axum::Form::<T>::from_request(request, state)
        .await
        .map(|f| f.0)
        .map_err(|e| {
            PageError::new(
                StatusCode::BAD_REQUEST,
                format!("the form is malformed: {e}"),
            )
        })
}

/// A redirect to the login page that comes back to `here`, for a visitor without a
/// session (`None`: signed in).
pub(super) fn login_first(visitor: &Visitor, here: &str) -> Option<Response> {
    (!visitor.signed_in())
        .then(|| Redirect::to(&format!("/login?next={}", encode_path(here))).into_response())
}

/// `path` made safe as a query value (a local path: letters, digits and `/-_.`).
fn encode_path(path: &str) -> String {
    path.bytes()
        .map(|b| {
            if b.is_ascii_alphanumeric() || b"/-_.".contains(&b) {
                (b as char).to_string()
            } else {
                format!("%{b:02X}")
            }
        })
        .collect()
}

/// Where a login may send the browser next: a path of this site only (no scheme, no
/// `//host`, no backslash), else `/me`.
pub(super) fn local_next(next: Option<&str>) -> String {
    match next {
        Some(n)
            if n.starts_with('/')
                && !n.starts_with("//")
                && !n.contains('\\')
                && !n.chars().any(char::is_control)
                && n.len() <= 512 =>
        {
            n.to_string()
        }
        _ => "/me".to_string(),
    }
}

/// Opens a multipart form whose first field must be the session's anti-forgery token:
/// checked before any other field (a file above all) is read. Answers the form past it.
pub(super) async fn multipart_after_token(
    state: &AppState,
    visitor: &Visitor,
    request: Request,
) -> PageResult<Multipart> {
    let mut form = Multipart::from_request(request, state)
        .await
        .map_err(ApiError::from)?;
    let token = match form.next_field().await.map_err(ApiError::from)? {
        Some(field) if field.name() == Some(super::super::session::CSRF_FIELD) => {
            Some(field.text().await.map_err(ApiError::from)?)
        }
        _ => None,
    };
    visitor.check_csrf(token.as_deref())?;
    Ok(form)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_login_goes_back_only_to_this_site() {
        assert_eq!(
            local_next(Some("/competitions/x/submit")),
            "/competitions/x/submit"
        );
        for bad in [
            "//evil.test/x",
            "https://evil.test",
            "/\\evil.test",
            "me",
            "",
        ] {
            assert_eq!(local_next(Some(bad)), "/me", "{bad}");
        }
        assert_eq!(local_next(None), "/me");
        assert_eq!(encode_path("/a b?c"), "/a%20b%3Fc");
    }
}

/// A form with nothing but its anti-forgery token.
#[derive(Debug, serde::Deserialize)]
pub(super) struct TokenForm {
    pub(super) csrf: Option<String>,
}

/// Reads a form that holds nothing but its anti-forgery token, and checks the token.
///
/// # Errors
/// A malformed form; no session, or not its token.
pub(super) async fn read_token_form(
    state: &AppState,
    visitor: &Visitor,
    request: Request,
) -> PageResult<()> {
    let form: TokenForm = read_form(state, request).await?;
    visitor.check_csrf(form.csrf.as_deref())?;
    Ok(())
}

/// A page that shows a key, shown once: no cache keeps it.
pub(super) fn no_store(html: String) -> Response {
    let mut response = axum::response::Html(html).into_response();
    response.headers_mut().insert(
        header::CACHE_CONTROL,
        axum::http::HeaderValue::from_static("no-store"),
    );
    response
}

/// The session's anti-forgery token for a page's forms (empty without a session).
pub(super) fn csrf(visitor: &Visitor) -> String {
    visitor
        .session
        .as_ref()
        .map(|s| s.csrf.clone())
        .unwrap_or_default()
}
