//! Reading a bot upload (JSON or a multipart form), checking its fields, and unpacking
//! its files into a new folder under the data directory.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use axum::extract::{FromRequest, Multipart, Request};
use axum::http::header;
use base64::Engine;

use super::super::auth::new_token;
use super::super::error::{ApiError, ApiResult, AppJson};
use super::super::{AppState, MAX_UPLOAD_BYTES};
use super::{BotUpload, MAX_COMMAND_CHARS, MAX_NAME_CHARS};
use crate::botfiles::{self, BundleError, BundleLimits, BundleSummary};
use crate::runner::botenv;

/// An upload, whichever way it came.
pub(super) struct Upload {
    pub name: Option<String>,
    pub command: String,
    pub build: Option<String>,
    pub env: Vec<(String, String)>,
    pub files: Option<BTreeMap<String, String>>,
    pub archive: Option<Vec<u8>>,
}

pub(super) async fn read_upload(state: &AppState, request: Request) -> ApiResult<Upload> {
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
        let (mut name, mut command, mut archive, mut build) = (None, None, None, None);
        let mut env = Vec::new();
        while let Some(field) = form.next_field().await? {
            match field.name().unwrap_or("") {
                "name" => name = Some(field.text().await?),
                "command" => command = Some(field.text().await?),
                "build" => build = Some(field.text().await?),
                "env" => {
                    let text = field.text().await?;
                    env.push(botenv::parse_assignment(&text).map_err(env_error)?);
                }
                "archive" => archive = Some(field.bytes().await?.to_vec()),
                other => {
                    return Err(ApiError::BadRequest(format!(
                        "unknown form field {other:?}: expected name, command, build, env, archive"
                    )));
                }
            }
        }
        return checked(Upload {
            name,
            build,
            env,
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
    checked(Upload {
        name: body.name,
        command: body.command,
        build: body.build,
        env: body.env.unwrap_or_default().into_iter().collect(),
        files: body.files,
        archive,
    })
}

/// Checks the command, the build command and the environment of an upload.
fn checked(upload: Upload) -> ApiResult<Upload> {
    check_command(&upload.command)?;
    if let Some(build) = &upload.build {
        check_command(build).map_err(|_| {
            ApiError::Unprocessable(format!(
                "the build command {build:?} is empty, too long or has unbalanced quotes"
            ))
        })?;
    }
    botenv::check(&upload.env).map_err(env_error)?;
    Ok(upload)
}

fn env_error(e: botenv::BotEnvError) -> ApiError {
    ApiError::Unprocessable(format!("env: {e}"))
}

pub(super) fn check_name(name: &str) -> ApiResult<()> {
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

pub(super) fn check_command(command: &str) -> ApiResult<()> {
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
pub(super) async fn store_files(
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

pub(super) async fn remove_dir(dir: &Path) {
    if let Err(e) = tokio::fs::remove_dir_all(dir).await {
        tracing::warn!(cause = %e, dir = %dir.display(), "could not remove a bot directory");
    }
}
