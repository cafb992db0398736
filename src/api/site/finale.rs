//! The final night's pages: the reveal (`/competitions/{name}/reveal`), the races
//! (`/competitions/{name}/race`, `.../race/{maze}/{repeat}`, a tournament's
//! `/tournaments/{id}/race/{maze_id}/{repeat}`), each also as one offline file
//! (`?download=1`), and the organiser's publish form. Each calls the API's operation of
//! the same purpose.

use axum::Router;
use axum::extract::{Request, State};
use axum::http::{HeaderValue, header};
use axum::response::Response;
use axum::routing::{get, post};
use serde::Deserialize;

use super::super::AppState;
use super::super::error::{AppPath, AppQuery};
use super::super::finale as api;
use super::super::session::Visitor;
use super::forms::{PageResult, no_store, read_form};
use crate::web::finale::{self as web, Online};

/// Their routes.
pub(super) fn router() -> Router<AppState> {
    Router::new()
        .route("/competitions/{name}/reveal", get(reveal_page))
        .route("/competitions/{name}/race", get(races_page))
        .route("/competitions/{name}/race/{maze}/{repeat}", get(race_page))
        .route(
            "/tournaments/{id}/race/{maze_id}/{repeat}",
            get(tournament_race_page),
        )
        .route("/competitions/{name}/publish", post(publish))
        .route("/competitions/{name}/hold", post(hold))
}

/// `?download=1`: the page as one offline file.
#[derive(Debug, Deserialize)]
struct DownloadQuery {
    download: Option<u8>,
}

/// An offline file sent as a download, never kept by a cache.
fn attachment(html: String, file: &str) -> Response {
    let mut response = no_store(html);
    if let Ok(v) = HeaderValue::from_str(&format!("attachment; filename=\"{file}\"")) {
        response
            .headers_mut()
            .insert(header::CONTENT_DISPOSITION, v);
    }
    response
}

/// A file name made of a name's safe characters.
fn file_name(parts: &[&str]) -> String {
    parts
        .iter()
        .map(|p| {
            p.chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                        c
                    } else {
                        '_'
                    }
                })
                .collect::<String>()
        })
        .collect::<Vec<_>>()
        .join("-")
        + ".html"
}

async fn reveal_page(
    State(state): State<AppState>,
    visitor: Visitor,
    AppPath(name): AppPath<String>,
    AppQuery(q): AppQuery<DownloadQuery>,
) -> PageResult {
    let reveal = api::reveal(&state, &visitor.caller, &name).await?;
    if q.download.is_some() {
        return Ok(attachment(
            web::reveal_file(&reveal),
            &file_name(&[&name, "reveal"]),
        ));
    }
    let online = Online {
        back: (
            format!("/competitions/{name}"),
            format!("{} (the competition)", reveal.title),
        ),
        download: format!("/competitions/{name}/reveal?download=1"),
        races: (!reveal.races.is_empty()).then(|| format!("/competitions/{name}/race")),
    };
    Ok(no_store(web::reveal_page(&reveal, &online)))
}

async fn races_page(
    State(state): State<AppState>,
    visitor: Visitor,
    AppPath(name): AppPath<String>,
) -> PageResult {
    let (c, races) = api::races(&state, &visitor.caller, &name).await?;
    Ok(no_store(web::races_page(&c.name, &c.title, &races)))
}

async fn race_page(
    State(state): State<AppState>,
    visitor: Visitor,
    AppPath((name, maze, repeat)): AppPath<(String, String, i64)>,
    AppQuery(q): AppQuery<DownloadQuery>,
) -> PageResult {
    let race = api::race(&state, &visitor.caller, &name, &maze, repeat).await?;
    if q.download.is_some() {
        let seed = format!("seed{}", repeat + 1);
        return Ok(attachment(
            web::race_file(&race),
            &file_name(&[&name, "race", &maze, &seed]),
        ));
    }
    let online = Online {
        back: (format!("/competitions/{name}"), "the competition".into()),
        download: format!("{}?download=1", race_path(&name, &maze, repeat)),
        races: Some(format!("/competitions/{name}/race")),
    };
    Ok(no_store(web::race_page(&race, &online)))
}

/// The path of a competition's race page.
fn race_path(name: &str, maze: &str, repeat: i64) -> String {
    let maze = crate::registry::finale::path_segment(maze);
    format!("/competitions/{name}/race/{maze}/{repeat}")
}

async fn tournament_race_page(
    State(state): State<AppState>,
    visitor: Visitor,
    AppPath((id, maze_id, repeat)): AppPath<(i64, i64, i64)>,
    AppQuery(q): AppQuery<DownloadQuery>,
) -> PageResult {
    let race = api::tournament_race(&state, &visitor.caller, id, maze_id, repeat).await?;
    if q.download.is_some() {
        let file = file_name(&[
            &format!("tournament{id}"),
            "race",
            &race.maze,
            &format!("seed{}", repeat + 1),
        ]);
        return Ok(attachment(web::race_file(&race), &file));
    }
    let online = Online {
        back: (format!("/tournaments/{id}"), format!("tournament {id}")),
        download: format!("/tournaments/{id}/race/{maze_id}/{repeat}?download=1"),
        races: None,
    };
    Ok(no_store(web::race_page(&race, &online)))
}

/// The publish form: a confirmation box that must be ticked.
#[derive(Debug, Deserialize)]
struct PublishForm {
    csrf: Option<String>,
    confirm: Option<String>,
}

async fn publish(
    State(state): State<AppState>,
    visitor: Visitor,
    AppPath(name): AppPath<String>,
    request: Request,
) -> PageResult {
    let form: PublishForm = read_form(&state, request).await?;
    visitor.check_csrf(form.csrf.as_deref())?;
    let result = async {
        if form.confirm.as_deref() != Some("yes") {
            return Err(super::forms::PageError::new(
                axum::http::StatusCode::UNPROCESSABLE_ENTITY,
                "tick the box to confirm: once published, everyone sees the results",
            ));
        }
        api::publish(&state, &visitor.caller, &name).await?;
        Ok("published".to_string())
    }
    .await;
    super::organise::manage_after(&state, &visitor, &name, result).await
}

/// The hold form: whether the results, once written, wait for the organisers.
#[derive(Debug, Deserialize)]
struct HoldForm {
    csrf: Option<String>,
    hold_results: String,
}

async fn hold(
    State(state): State<AppState>,
    visitor: Visitor,
    AppPath(name): AppPath<String>,
    request: Request,
) -> PageResult {
    let form: HoldForm = read_form(&state, request).await?;
    visitor.check_csrf(form.csrf.as_deref())?;
    let result = async {
        let hold = match form.hold_results.as_str() {
            "yes" => true,
            "no" => false,
            other => {
                return Err(super::forms::PageError::new(
                    axum::http::StatusCode::UNPROCESSABLE_ENTITY,
                    format!("hold_results: {other:?} is not yes or no"),
                ));
            }
        };
        let patch = crate::registry::competitions::Patch {
            hold_results: Some(hold),
            ..Default::default()
        };
        super::super::competitions::edit(&state, &visitor.caller, &name, patch).await?;
        Ok(if hold { "held" } else { "saved" }.to_string())
    }
    .await;
    super::organise::manage_after(&state, &visitor, &name, result).await
}
