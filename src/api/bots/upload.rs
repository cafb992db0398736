//! Reading a bot upload (JSON or a multipart form) into a registry submission.

use std::collections::BTreeMap;

use axum::extract::{FromRequest, Multipart, Request};
use axum::http::header;
use base64::Engine;

use super::super::error::{ApiError, ApiResult, AppJson};
use super::super::{AppState, MAX_UPLOAD_BYTES};
use super::BotUpload;
use crate::registry::bots::Submission;
use crate::registry::bundles::BotFiles;
use crate::runner::botenv;

/// An upload, whichever way it came (JSON, the API's multipart form, or the
/// submission page's form): the fields of [`BotUpload`].
#[derive(Debug, Default)]
pub(crate) struct Upload {
    pub name: Option<String>,
    pub command: String,
    pub build: Option<String>,
    pub env: Vec<(String, String)>,
    pub files: Option<BTreeMap<String, String>>,
    pub archive: Option<Vec<u8>>,
    pub runtime: Option<String>,
    pub original_task: bool,
    pub robot_file: Option<String>,
    pub protocol: Option<String>,
    pub competition: Option<String>,
}

/// Whether a form's checkbox value is set.
pub(crate) fn checked(value: &str) -> bool {
    matches!(value.trim(), "true" | "on" | "1" | "yes")
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
        let mut runtime = None;
        let mut original_task = false;
        let mut robot_file = None;
        let mut competition = None;
        let mut protocol = None;
        let mut env = Vec::new();
        while let Some(field) = form.next_field().await? {
            match field.name().unwrap_or("") {
                "name" => name = Some(field.text().await?),
                "command" => command = Some(field.text().await?),
                "build" => build = Some(field.text().await?),
                "runtime" => runtime = Some(field.text().await?),
                "original_task" => original_task = checked(&field.text().await?),
                "robot_file" => robot_file = Some(field.text().await?),
                "competition" => competition = Some(field.text().await?),
                "protocol" => protocol = Some(field.text().await?),
                "env" => {
                    let text = field.text().await?;
                    env.push(botenv::parse_assignment(&text).map_err(env_error)?);
                }
                "archive" => archive = Some(field.bytes().await?.to_vec()),
                other => {
                    return Err(ApiError::BadRequest(format!(
                        "unknown form field {other:?}: expected name, command, build, env, runtime, original_task, robot_file, competition, protocol, archive"
                    )));
                }
            }
        }
        return Ok(Upload {
            name,
            build,
            env,
            command: command.unwrap_or_default(),
            files: None,
            runtime,
            original_task,
            robot_file,
            competition,
            protocol,
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
        build: body.build,
        env: body.env.unwrap_or_default().into_iter().collect(),
        files: body.files,
        archive,
        runtime: body.runtime,
        original_task: body.original_task,
        robot_file: body.robot_file,
        competition: body.competition,
        protocol: body.protocol,
    })
}

fn env_error(e: botenv::BotEnvError) -> ApiError {
    ApiError::Unprocessable(format!("env: {e}"))
}

impl Upload {
    /// The upload as a registry submission (its files sent one way or the other).
    pub(crate) fn submission(self) -> ApiResult<(Option<String>, Submission)> {
        let files = match (self.files, self.archive) {
            (Some(_), Some(_)) => {
                return Err(ApiError::Unprocessable(
                    "send the files either as `files` or as `archive_base64`, not both".into(),
                ));
            }
            (None, None) => {
                return Err(ApiError::Unprocessable(
                    "the bot has no files: send `files` or `archive_base64`".into(),
                ));
            }
            (Some(map), None) => BotFiles::Map(map),
            (None, Some(bytes)) => BotFiles::Archive(bytes),
        };
        let runtime = self.runtime.filter(|r| !r.trim().is_empty());
        let protocol = match self.protocol.as_deref().map(str::trim) {
            None | Some("") => crate::runner::BotProtocol::V1,
            Some(name) => {
                crate::runner::BotProtocol::parse(name).map_err(ApiError::Unprocessable)?
            }
        };
        if self.original_task && protocol != crate::runner::BotProtocol::V1 {
            return Err(ApiError::Unprocessable(
                "an original-task robot.py speaks through its adapter (protocol v1), not `mms`"
                    .into(),
            ));
        }
        // An original-task robot without a command gets the adapter's, naming its
        // robot's file, once the files are stored (the registry finds the file).
        let command = self.command.trim().to_string();
        let robot = self.robot_file.filter(|r| !r.trim().is_empty());
        if robot.is_some() && !self.original_task {
            return Err(ApiError::Unprocessable(
                "`robot_file` names the file of an original-task robot: set `original_task` too"
                    .into(),
            ));
        }
        let files = if self.original_task {
            BotFiles::OriginalTask {
                files: Box::new(files),
                robot,
            }
        } else {
            files
        };
        if command.is_empty() && !self.original_task {
            return Err(ApiError::Unprocessable(
                "the bot needs a `command` (e.g. `python3 bot.py`), or `original_task` for a \
                 robot.py of the original task"
                    .into(),
            ));
        }
        Ok((
            self.name,
            Submission {
                command,
                build: self.build.filter(|b| !b.trim().is_empty()),
                env: self.env,
                files,
                runtime,
                protocol,
            },
        ))
    }
}
