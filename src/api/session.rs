//! Browser sessions and the defences of the pages' forms.
//!
//! `/login` takes a key (the admin token, an organiser's, an entrant's or a bot owner's)
//! and sets a cookie holding a fresh random secret; the server keeps only the secret's
//! SHA-256 with the key's hash and an end time ([`SESSION_LIFETIME`]). The cookie is
//! `HttpOnly`, `SameSite=Strict`, `Path=/`, and `Secure` when the server is told it is
//! behind HTTPS, where its name carries the `__Host-` prefix. A request with two session
//! cookies (one set by a page of another port or a sibling host for a path of this site:
//! cookie tossing) is served as signed out, and its answer clears them. A session is
//! never taken from the visitor: each login makes a new one, so a secret planted before the login opens nothing. `/logout` deletes it on the
//! server; rotating an entrant's key deletes every session of that key and of its bots'
//! owner tokens.
//!
//! The JSON API never reads the cookie (it takes `Authorization: Bearer` only), so a
//! cross-site request to it carries no authority. The pages' forms are guarded twice:
//! every state-changing form of a session carries a token derived from the session's
//! secret ([`Session::csrf`]), and every form post whose `Origin` or `Sec-Fetch-Site`
//! says it came from another site is refused ([`refuse_cross_site`]).

use std::time::Duration;

use axum::extract::{FromRequestParts, Request};
use axum::http::request::Parts;
use axum::http::{HeaderMap, Method, StatusCode, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use cookie::{Cookie, SameSite};
use sha2::{Digest, Sha256};

use super::AppState;
use super::auth::{Caller, hash_token, new_token};
use super::error::ApiError;

/// The session cookie's name over plain HTTP.
pub const COOKIE: &str = "mazearena_session";

/// The session cookie's name over HTTPS: a browser keeps a `__Host-` cookie only when
/// it is `Secure`, for the path `/` and without a `Domain`, so a page of another port or
/// a sibling host cannot set one for a path of this site (cookie tossing).
pub const SECURE_COOKIE: &str = "__Host-mazearena_session";

/// The session cookie's name for a request served over HTTPS (`secure`) or not.
pub fn cookie_name(secure: bool) -> &'static str {
    if secure { SECURE_COOKIE } else { COOKIE }
}

/// How long a session lasts from its login.
pub const SESSION_LIFETIME: Duration = Duration::from_secs(7 * 24 * 3600);

/// The name of the forms' anti-forgery field.
pub const CSRF_FIELD: &str = "csrf";

/// A live session.
#[derive(Debug, Clone)]
pub struct Session {
    /// SHA-256 of the cookie's secret (its id on the server).
    pub hash: String,
    /// The anti-forgery token of its forms.
    pub csrf: String,
}

/// Who is looking at a page: the caller its session makes (anonymous without one).
#[derive(Debug, Clone)]
pub struct Visitor {
    /// The caller.
    pub caller: Caller,
    /// The session, if the cookie names a live one.
    pub session: Option<Session>,
}

impl Visitor {
    /// Whether the visitor is signed in.
    pub fn signed_in(&self) -> bool {
        self.session.is_some()
    }

    /// Refuses a form whose anti-forgery token is not this session's (403), or a
    /// visitor without a session (401).
    ///
    /// # Errors
    /// As said.
    pub fn check_csrf(&self, token: Option<&str>) -> Result<(), ApiError> {
        let Some(session) = &self.session else {
            return Err(ApiError::Unauthorized(
                "your session has ended: log in again (/login)".into(),
            ));
        };
        let given = token.unwrap_or("").as_bytes();
        if bool::from(subtle::ConstantTimeEq::ct_eq(
            given,
            session.csrf.as_bytes(),
        )) {
            Ok(())
        } else {
            Err(ApiError::Forbidden(
                "this form is not from this session (its anti-forgery token does not match): \
                 reload the page and send it again"
                    .into(),
            ))
        }
    }
}

/// The anti-forgery token of the session whose cookie holds `secret`: derived from the
/// secret, which only the visitor's browser has.
pub fn csrf_token(secret: &str) -> String {
    let digest = Sha256::digest(format!("mazearena form token\0{secret}").as_bytes());
    digest.iter().map(|b| format!("{b:02x}")).collect()
}

/// Every value of the cookie `name` in `headers`. A browser sends two cookies of one
/// name when a page of another port (cookies do not tell ports apart) or a sibling host
/// set one for a path of this site: which is the visitor's cannot be known.
fn cookie_values(headers: &HeaderMap, name: &str) -> Vec<String> {
    headers
        .get_all(header::COOKIE)
        .iter()
        .filter_map(|v| v.to_str().ok())
        .flat_map(|v| v.split(';'))
        .filter_map(|pair| Cookie::parse(pair.trim().to_string()).ok())
        .filter(|c| c.name() == name)
        .map(|c| c.value().to_string())
        .collect()
}

/// The session cookie's secret in `headers` (of a request served over HTTPS:
/// `secure`), if there is exactly one: with two or more (one of them tossed by another
/// site), none.
fn cookie_secret(headers: &HeaderMap, secure: bool) -> Option<String> {
    match cookie_values(headers, cookie_name(secure)).as_slice() {
        [one] if !one.is_empty() && one.len() <= 128 => Some(one.clone()),
        _ => None,
    }
}

/// Whether `headers` carry more than one session cookie: the request is served as
/// signed out, and [`clear_tossed_cookies`] clears them.
pub fn tossed(headers: &HeaderMap, secure: bool) -> bool {
    cookie_values(headers, cookie_name(secure)).len() > 1
}

/// Middleware: an answer to a request that carried two or more session cookies (one
/// tossed by another site: [`tossed`]) removes them: the cookie of this host at `/` and
/// at each folder of this request's path (where a tossed cookie that was sent with it
/// lives, unless another host set it for the whole domain; it is refused all the same).
/// The visitor logs in again. (`Clear-Site-Data` would also clear every other site's
/// cookies of the registrable domain: a school's other sites.)
pub async fn clear_tossed_cookies(
    axum::extract::State(state): axum::extract::State<AppState>,
    request: axum::extract::Request,
    next: axum::middleware::Next,
) -> axum::response::Response {
    let secure = secure(&state, request.headers());
    let path = request.uri().path().to_string();
    let clear = tossed(request.headers(), secure);
    let mut response = next.run(request).await;
    if clear {
        let headers = response.headers_mut();
        let mut paths = vec!["/".to_string()];
        // A path of the site's own pages (letters, digits and `/-_.`): each of its
        // folders, at most a few.
        if path
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b"/-_.".contains(&b))
        {
            let mut at = String::new();
            for part in path.split('/').filter(|p| !p.is_empty()).take(6) {
                at.push('/');
                at.push_str(part);
                paths.push(at.clone());
            }
        }
        for p in paths {
            let gone = Cookie::build((cookie_name(secure), ""))
                .path(p)
                .http_only(true)
                .secure(secure)
                .max_age(cookie::time::Duration::ZERO)
                .build();
            if let Ok(v) = axum::http::HeaderValue::from_str(&gone.to_string()) {
                headers.append(header::SET_COOKIE, v);
            }
        }
    }
    response
}

impl FromRequestParts<AppState> for Visitor {
    type Rejection = ApiError;

    async fn from_request_parts(
        parts: &mut Parts,
        state: &AppState,
    ) -> Result<Self, Self::Rejection> {
        let anonymous = Visitor {
            caller: Caller::Anonymous,
            session: None,
        };
        let Some(secret) = cookie_secret(&parts.headers, secure(state, &parts.headers)) else {
            return Ok(anonymous);
        };
        let hash = hash_token(&secret);
        let Some(key_hash) = state.storage.session_key(&hash).await? else {
            return Ok(anonymous);
        };
        Ok(Visitor {
            caller: Caller::from_key_hash(state, key_hash).await?,
            session: Some(Session {
                hash,
                csrf: csrf_token(&secret),
            }),
        })
    }
}

/// Whether a key is one this server knows (the admin token, an organiser's, an
/// entrant's, or the owner token of some bot): only those open a session.
///
/// # Errors
/// Database failures.
pub async fn known_key(state: &AppState, key_hash: &str) -> Result<bool, ApiError> {
    Ok(
        match Caller::from_key_hash(state, key_hash.to_string()).await? {
            Caller::Admin | Caller::Organiser(_) => true,
            Caller::Anonymous => false,
            Caller::Token(hash) => {
                state.storage.entrant_by_key(&hash).await?.is_some()
                    || !state.storage.bots_owned_by(&hash).await?.is_empty()
            }
        },
    )
}

/// Opens a session for the key with SHA-256 `key_hash`; answers the cookie to set.
///
/// # Errors
/// Randomness or the database.
pub async fn open(
    state: &AppState,
    key_hash: &str,
    secure: bool,
) -> Result<Cookie<'static>, ApiError> {
    let secret = new_token()?;
    let ends = crate::storage::now_ms() + SESSION_LIFETIME.as_millis() as i64;
    state
        .storage
        .create_session(&hash_token(&secret), key_hash, ends)
        .await?;
    Ok(cookie(secret, secure, SESSION_LIFETIME))
}

/// The session cookie holding `secret` for `max_age` (zero: the cookie that removes it).
pub fn cookie(secret: String, secure: bool, max_age: Duration) -> Cookie<'static> {
    Cookie::build((cookie_name(secure), secret))
        .path("/")
        .http_only(true)
        .same_site(SameSite::Strict)
        .secure(secure)
        .max_age(cookie::time::Duration::seconds(max_age.as_secs() as i64))
        .build()
}

/// Whether cookies must be `Secure`: the server says it is served over HTTPS, or the
/// proxy in front says this request came that way.
pub fn secure(state: &AppState, headers: &HeaderMap) -> bool {
    state.settings.secure_cookies
        || headers
            .get("x-forwarded-proto")
            .and_then(|v| v.to_str().ok())
            .is_some_and(|v| v.eq_ignore_ascii_case("https"))
}

/// Whether `headers` show a request sent by a page of another site. A browser's
/// `Sec-Fetch-Site` (which no page can set) decides when it is there: anything but
/// `same-origin` or `none` (typed or bookmarked) is another site. Without it, an
/// `Origin` whose host is not this request's `Host` is (and `null`, which the pages'
/// `Referrer-Policy: no-referrer` makes older browsers send even from this site, is
/// refused too: the form token still guards the signed-in forms). Clients that send
/// neither header, like curl, are not browsers acting for someone.
pub fn cross_site(headers: &HeaderMap) -> bool {
    if let Some(site) = headers.get("sec-fetch-site").and_then(|v| v.to_str().ok()) {
        return !matches!(site, "same-origin" | "none");
    }
    let Some(origin) = headers.get(header::ORIGIN) else {
        return false;
    };
    let origin = origin.to_str().unwrap_or("");
    let host = headers
        .get(header::HOST)
        .and_then(|v| v.to_str().ok())
        .unwrap_or("");
    let origin_host = origin
        .strip_prefix("http://")
        .or_else(|| origin.strip_prefix("https://"))
        .unwrap_or("");
    origin == "null" || origin_host.is_empty() || !origin_host.eq_ignore_ascii_case(host)
}

/// Middleware of the pages' routes: refuses (403, as a page) a form post sent from
/// another site's page, before anything reads it.
pub async fn refuse_cross_site(request: Request, next: Next) -> Response {
    if request.method() != Method::GET
        && request.method() != Method::HEAD
        && cross_site(request.headers())
    {
        let body = crate::web::pages::message(
            "Refused",
            "This form was sent from another site's page, so it was not acted on. \
             Use the form on this site.",
        );
        return (StatusCode::FORBIDDEN, axum::response::Html(body)).into_response();
    }
    next.run(request).await
}

#[cfg(test)]
mod tests {
    use super::*;
    use axum::http::HeaderValue;

    fn headers(pairs: &[(&'static str, &'static str)]) -> HeaderMap {
        let mut h = HeaderMap::new();
        for (k, v) in pairs {
            h.insert(*k, HeaderValue::from_static(v));
        }
        h
    }

    #[test]
    fn requests_from_other_sites_are_told_apart() {
        assert!(!cross_site(&headers(&[])), "curl sends neither");
        assert!(!cross_site(&headers(&[
            ("host", "example.org:8080"),
            ("origin", "http://example.org:8080"),
            ("sec-fetch-site", "same-origin"),
        ])));
        assert!(cross_site(&headers(&[
            ("host", "example.org:8080"),
            ("origin", "http://evil.test"),
        ])));
        assert!(cross_site(&headers(&[("sec-fetch-site", "cross-site")])));
        assert!(cross_site(&headers(&[("sec-fetch-site", "same-site")])));
        assert!(cross_site(&headers(&[
            ("host", "example.org"),
            ("origin", "null"),
        ])));
        // The pages' no-referrer policy makes Chromium send `Origin: null` from this
        // very site; its Sec-Fetch-Site says where the form came from.
        assert!(!cross_site(&headers(&[
            ("host", "example.org"),
            ("origin", "null"),
            ("sec-fetch-site", "same-origin"),
        ])));
        assert!(cross_site(&headers(&[
            ("host", "example.org"),
            ("origin", "http://example.org"),
            ("sec-fetch-site", "cross-site"),
        ])));
    }

    #[test]
    fn the_form_token_depends_on_the_secret_only() {
        assert_eq!(csrf_token("a"), csrf_token("a"));
        assert_ne!(csrf_token("a"), csrf_token("b"));
        assert_eq!(csrf_token("a").len(), 64);
    }

    #[test]
    fn the_cookie_is_http_only_strict_and_scoped_to_the_site() {
        let c = cookie("s3cret".into(), true, SESSION_LIFETIME).to_string();
        for part in [
            "mazearena_session=s3cret",
            "HttpOnly",
            "SameSite=Strict",
            "Secure",
            "Path=/",
            "Max-Age=604800",
        ] {
            assert!(c.contains(part), "{c} lacks {part}");
        }
        assert!(
            !cookie("x".into(), false, SESSION_LIFETIME)
                .to_string()
                .contains("Secure")
        );
    }
}
