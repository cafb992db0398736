//! Bots and their versions: registering a bot, adding a version (which resumes a paused
//! bot), from an upload or from a local folder.

use std::path::Path;

use super::bundles::{BotFiles, Stored, store_upload};
use super::tokens::{hash_token, new_token};
use super::{RegistryError, Result};
use crate::botfiles::{BundleLimits, BundleSummary, hash_dir, skip_build_outputs};
use crate::manifest::BotManifest;
use crate::runner::botenv;
use crate::storage::Storage;
use crate::storage::bots::{BotVersionRow, NewVersion, VersionQuota, VersionRefusal};
use crate::storage::owners::OwnerLimits;

/// Longest bot name.
pub const MAX_NAME_CHARS: usize = 64;
/// Longest bot command (and build command).
pub const MAX_COMMAND_CHARS: usize = 1000;

/// Limits on hashing a local bot folder (its sources: build outputs are skipped).
const LOCAL_LIMITS: BundleLimits = BundleLimits {
    max_total_bytes: 1 << 30,
    max_files: 50_000,
};

/// A version as submitted: its command, files, build command and environment.
#[derive(Debug, Clone)]
pub struct Submission {
    /// The command that runs the bot in its folder.
    pub command: String,
    /// An optional build command, run once in the sandbox before the version plays.
    pub build: Option<String>,
    /// Environment variables for the bot.
    pub env: Vec<(String, String)>,
    /// The files.
    pub files: BotFiles,
    /// The server's runtime to put first on the bot's `PATH`, by name.
    pub runtime: Option<String>,
    /// The protocol it speaks.
    pub protocol: crate::runner::BotProtocol,
}

/// A registered bot: its first version and its owner token (shown this once).
#[derive(Debug, Clone)]
pub struct Registered {
    /// The first version.
    pub version: BotVersionRow,
    /// The owner token in clear.
    pub owner_token: String,
}

/// Checks a bot name: 1 to [`MAX_NAME_CHARS`] letters, digits, `-`, `_` or `.`.
///
/// # Errors
/// [`RegistryError::Invalid`] with what is allowed.
pub fn check_name(name: &str) -> Result<()> {
    let ok = !name.is_empty()
        && name.chars().count() <= MAX_NAME_CHARS
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c));
    if ok {
        Ok(())
    } else {
        Err(RegistryError::Invalid(format!(
            "bot name {name:?} is not allowed: 1 to {MAX_NAME_CHARS} letters, digits, '-', '_' or '.'"
        )))
    }
}

/// Checks a command line: at most [`MAX_COMMAND_CHARS`], split like a shell into at
/// least one word.
///
/// # Errors
/// [`RegistryError::Invalid`] saying why (`what` names it: "the command").
pub fn check_command(what: &str, command: &str) -> Result<()> {
    if command.chars().count() > MAX_COMMAND_CHARS {
        return Err(RegistryError::Invalid(format!(
            "{what} is longer than {MAX_COMMAND_CHARS} characters"
        )));
    }
    match shlex::split(command) {
        Some(words) if !words.is_empty() => Ok(()),
        _ => Err(RegistryError::Invalid(format!(
            "{what} {command:?} is empty or has unbalanced quotes"
        ))),
    }
}

/// Checks a submission's command, build command and environment.
///
/// # Errors
/// [`RegistryError::Invalid`].
pub fn check_submission(s: &Submission) -> Result<()> {
    // An original-task robot's command may be left out: it is made once its robot's
    // file is known ([`with_robot_command`]).
    if !(s.command.is_empty() && matches!(s.files, BotFiles::OriginalTask { .. })) {
        check_command("the command", &s.command)?;
    }
    if let Some(build) = &s.build {
        check_command("the build command", build)?;
    }
    botenv::check(&s.env).map_err(|e| RegistryError::Invalid(format!("env: {e}")))
}

/// The submission's command once its files are stored as `stored`: an original-task
/// robot without a command of its own runs its robot's file through the adapter.
fn with_robot_command(submission: &mut Submission, stored: &Stored) -> Result<()> {
    if submission.command.is_empty() {
        let robot = stored.robot.as_deref().ok_or_else(|| {
            RegistryError::Invalid(
                "the bot needs a `command` (e.g. `python3 bot.py`), or `original_task` for a \
                 robot.py of the original task"
                    .into(),
            )
        })?;
        submission.command =
            super::bundles::original_task_command(submission.runtime.is_some(), robot);
    }
    check_command("the command", &submission.command)
}

/// Registers a bot named `name` with its first version, the bot of `entrant` if given
/// (entered in competition `enter` in the same step, if given) and held by `owner`'s
/// quotas if given ([`super::owners`]); its files are stored as a bundle (`scratch`: a
/// local folder to unpack in).
///
/// # Errors
/// [`RegistryError::Invalid`] (name, command, environment), [`RegistryError::Conflict`]
/// (the name is taken), [`RegistryError::Bundle`] (the files), [`RegistryError::Quota`]
/// (the owner's), the database.
pub async fn register(
    storage: &Storage,
    name: &str,
    mut submission: Submission,
    scratch: &Path,
    entrant: Option<i64>,
    owner: Option<&OwnerLimits>,
    enter: Option<i64>,
) -> Result<Registered> {
    check_name(name)?;
    check_submission(&submission)?;
    if storage.get_bot_by_name(name).await?.is_some() {
        return Err(taken(name));
    }
    let files = std::mem::replace(&mut submission.files, BotFiles::Map(Default::default()));
    let stored = store_upload(storage, files, scratch).await?;
    with_robot_command(&mut submission, &stored)?;
    let summary = stored.summary;
    let owner_token = new_token()?;
    let version = match storage
        .create_bot_within(
            name,
            &hash_token(&owner_token),
            entrant,
            &stored_version(&submission, &summary),
            owner,
            enter,
        )
        .await?
    {
        Ok(row) => row,
        Err(refused) => return Err(version_refusal(storage, refused, owner).await?),
    };
    Ok(Registered {
        version,
        owner_token,
    })
}

/// Adds a version to bot `bot_id` (which resumes it if it was paused).
///
/// # Errors
/// [`RegistryError::NotFound`] (no such bot), as [`register`] otherwise.
pub async fn add_version(
    storage: &Storage,
    bot_id: i64,
    mut submission: Submission,
    scratch: &Path,
    quotas: &[VersionQuota],
    owner: Option<&OwnerLimits>,
) -> Result<BotVersionRow> {
    check_submission(&submission)?;
    if storage.get_bot(bot_id).await?.is_none() {
        return Err(RegistryError::NotFound(format!("no bot {bot_id}")));
    }
    let files = std::mem::replace(&mut submission.files, BotFiles::Map(Default::default()));
    let stored = store_upload(storage, files, scratch).await?;
    with_robot_command(&mut submission, &stored)?;
    let summary = stored.summary;
    match storage
        .add_bot_version_within(
            bot_id,
            &stored_version(&submission, &summary),
            quotas,
            owner,
        )
        .await?
    {
        Ok(row) => Ok(row),
        Err(refused) => Err(version_refusal(storage, refused, owner).await?),
    }
}

/// What a version that `refused` stored nothing says.
async fn version_refusal(
    storage: &Storage,
    refused: VersionRefusal,
    owner: Option<&OwnerLimits>,
) -> Result<RegistryError> {
    let now = crate::storage::now_ms();
    Ok(match refused {
        VersionRefusal::Quota(full) => {
            super::competitions::quota_refusal(storage, full, now).await?
        }
        VersionRefusal::Owner(kind, usage) => match owner {
            Some(limits) => super::owners::refusal(kind, &usage, limits, now),
            None => RegistryError::Internal("an owner's quota without its limits".into()),
        },
        VersionRefusal::Closed { name, closes_at } => RegistryError::Conflict(format!(
            "competition {name} closed at {}: no new versions",
            crate::competition::Timestamp(closes_at).words()
        )),
    })
}

/// Finds or registers a bot from a local folder (a `bot.toml`), which plays from that
/// folder on this machine (already built by the caller): a new version when its
/// command, environment, folder or files (their bundle hash, build outputs left out)
/// changed. Bots registered this way are owned by the admin (their token is never
/// shown). Answers the version's id.
///
/// # Errors
/// [`RegistryError::Invalid`] (name, command, environment, a folder that cannot be
/// hashed), the database.
pub async fn register_local(storage: &Storage, bot: &BotManifest) -> Result<i64> {
    check_name(&bot.name)?;
    let env: Vec<(String, String)> = bot.env.clone().into_iter().collect();
    check_command("the command", &bot.command)?;
    botenv::check(&env).map_err(|e| RegistryError::Invalid(format!("env: {e}")))?;
    let folder = bot.dir.clone();
    let summary =
        super::bundles::blocking(move || hash_dir(&folder, &LOCAL_LIMITS, &skip_build_outputs))
            .await?
            .map_err(|e| {
                RegistryError::Invalid(format!("bot {}: cannot read its folder: {e}", bot.name))
            })?;
    let dir = bot.dir.display().to_string();
    let new = NewVersion {
        command: &bot.command,
        dir: &dir,
        files_sha256: &summary.sha256,
        file_count: summary.files as i64,
        build_command: None,
        env: &env,
        bundle_sha256: None,
        runtime: bot.runtime.as_deref(),
        protocol: bot.protocol.stored(),
    };
    if let Some(existing) = storage.get_bot_by_name(&bot.name).await? {
        let latest = storage
            .get_bot_version(existing.bot_version_id)
            .await?
            .ok_or_else(|| RegistryError::Internal("a bot's latest version vanished".into()))?;
        // A bot registered through the API belongs to its owner: only the owner's token
        // adds a version to it, never a local tournament run on the server's database.
        if latest.bundle_sha256.is_some() {
            return Err(RegistryError::Conflict(format!(
                "the bot name {:?} is taken by bot {} of this database, registered through \
                 the API: a local tournament never changes it; give the local bot another \
                 name (its manifest's `name`) or use another --database",
                bot.name, existing.bot_id
            )));
        }
        let same = latest.files_sha256 == summary.sha256
            && latest.dir == dir
            && latest.command == bot.command
            && latest.env_pairs() == env
            && latest.runtime == bot.runtime
            && latest.protocol.as_deref() == bot.protocol.stored()
            && latest.bundle_sha256.is_none();
        if same {
            return Ok(latest.bot_version_id);
        }
        return Ok(storage
            .add_bot_version(existing.bot_id, &new)
            .await?
            .bot_version_id);
    }
    let token = new_token()?;
    Ok(storage
        .create_bot(&bot.name, &hash_token(&token), &new)
        .await
        .map_err(|e| match RegistryError::from(e) {
            RegistryError::Conflict(_) => taken(&bot.name),
            other => other,
        })?
        .bot_version_id)
}

/// The version of a submission whose files were stored as the bundle `summary`.
fn stored_version<'a>(submission: &'a Submission, summary: &'a BundleSummary) -> NewVersion<'a> {
    NewVersion {
        command: &submission.command,
        dir: "",
        files_sha256: &summary.sha256,
        file_count: summary.files as i64,
        build_command: submission.build.as_deref(),
        env: &submission.env,
        bundle_sha256: Some(&summary.sha256),
        runtime: submission.runtime.as_deref(),
        protocol: submission.protocol.stored(),
    }
}

fn taken(name: &str) -> RegistryError {
    RegistryError::Conflict(format!(
        "a bot named {name:?} exists already (names that differ only in case are one name)"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::storage::test_support;
    use std::collections::BTreeMap;

    fn submission(files: &[(&str, &str)]) -> Submission {
        Submission {
            command: "python3 bot.py".into(),
            build: None,
            env: vec![],
            runtime: None,
            protocol: Default::default(),
            files: BotFiles::Map(
                files
                    .iter()
                    .map(|(k, v)| (k.to_string(), v.to_string()))
                    .collect::<BTreeMap<_, _>>(),
            ),
        }
    }

    #[tokio::test]
    async fn an_upload_and_the_same_local_folder_have_one_bundle_hash() {
        let (db, _d) = test_support::fresh().await;
        let scratch = tempfile::tempdir().unwrap();
        let up = register(
            &db,
            "up",
            submission(&[("bot.py", "print(1)\n")]),
            scratch.path(),
            None,
            None,
            None,
        )
        .await
        .unwrap();
        assert_eq!(
            up.version.bundle_sha256.as_deref(),
            Some(up.version.files_sha256.as_str())
        );
        assert_eq!(up.version.dir, "");
        assert!(
            db.get_bundle(&up.version.files_sha256)
                .await
                .unwrap()
                .is_some()
        );

        let folder = tempfile::tempdir().unwrap();
        std::fs::write(folder.path().join("bot.py"), "print(1)\n").unwrap();
        std::fs::create_dir(folder.path().join("__pycache__")).unwrap();
        std::fs::write(folder.path().join("__pycache__/bot.pyc"), "junk").unwrap();
        let manifest = BotManifest {
            name: "local".into(),
            command: "python3 bot.py".into(),
            language: None,
            build: None,
            description: None,
            report: None,
            claimed: BTreeMap::new(),
            env: BTreeMap::new(),
            runtime: None,
            protocol: Default::default(),
            include: Vec::new(),
            dir: folder.path().to_path_buf(),
        };
        let id = register_local(&db, &manifest).await.unwrap();
        let local = db.get_bot_version(id).await.unwrap().unwrap();
        assert_eq!(local.files_sha256, up.version.files_sha256);
        assert_eq!(local.bundle_sha256, None);
        // Unchanged: the same version; a changed file or command: a new one.
        assert_eq!(register_local(&db, &manifest).await.unwrap(), id);
        std::fs::write(folder.path().join("bot.py"), "print(2)\n").unwrap();
        let id2 = register_local(&db, &manifest).await.unwrap();
        assert_ne!(id2, id);
        let other = BotManifest {
            command: "python3 -u bot.py".into(),
            ..manifest.clone()
        };
        assert_ne!(register_local(&db, &other).await.unwrap(), id2);
    }

    #[tokio::test]
    async fn bad_submissions_are_refused_before_anything_is_stored() {
        let (db, _d) = test_support::fresh().await;
        let scratch = tempfile::tempdir().unwrap();
        let ok = submission(&[("bot.py", "x")]);
        for (name, s) in [
            ("bad name!", ok.clone()),
            (
                "b",
                Submission {
                    command: "'unbalanced".into(),
                    ..ok.clone()
                },
            ),
            (
                "c",
                Submission {
                    build: Some(String::new()),
                    ..ok.clone()
                },
            ),
            (
                "d",
                Submission {
                    env: vec![("PATH".into(), "/x".into())],
                    ..ok.clone()
                },
            ),
        ] {
            let err = register(&db, name, s, scratch.path(), None, None, None)
                .await
                .unwrap_err();
            assert!(matches!(err, RegistryError::Invalid(_)), "{name}: {err}");
        }
        let err = register(
            &db,
            "e",
            submission(&[("../x", "1")]),
            scratch.path(),
            None,
            None,
            None,
        )
        .await
        .unwrap_err();
        assert!(matches!(err, RegistryError::Bundle(_)), "{err}");
        assert_eq!(db.bundle_totals().await.unwrap().0, 0);
        assert!(db.list_bots().await.unwrap().is_empty());

        register(&db, "f", ok.clone(), scratch.path(), None, None, None)
            .await
            .unwrap();
        let err = register(&db, "f", ok.clone(), scratch.path(), None, None, None)
            .await
            .unwrap_err();
        assert!(matches!(err, RegistryError::Conflict(_)), "{err}");
        let err = add_version(&db, 999, ok, scratch.path(), &[], None)
            .await
            .unwrap_err();
        assert!(matches!(err, RegistryError::NotFound(_)), "{err}");
    }
}
