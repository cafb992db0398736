//! Environment variables declared for a bot (`--bot-env KEY=VALUE`, a manifest's `env`
//! table, a bot version's `env`): the only variables of ours a bot gets, checked so that
//! they cannot change the sandbox's own settings.

/// The most variables a bot may declare.
pub const MAX_VARS: usize = 64;

/// The longest value, in bytes.
pub const MAX_VALUE_BYTES: usize = 4096;

/// Variables the runner sets itself, which a bot may not replace.
pub const RESERVED: [&str; 3] = ["PATH", "HOME", "TMPDIR"];

/// Why a declared variable is refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum BotEnvError {
    /// Not `KEY=VALUE`.
    #[error("{0:?} is not KEY=VALUE")]
    NotAnAssignment(String),
    /// A name outside `[A-Za-z_][A-Za-z0-9_]*`.
    #[error("{0:?} is not a variable name: use letters, digits and _, not starting with a digit")]
    BadName(String),
    /// PATH, HOME, TMPDIR or a `MAZEARENA_` name.
    #[error("{0} is set by mazearena itself and cannot be declared for a bot")]
    Reserved(String),
    /// A value too long or holding a NUL byte.
    #[error("the value of {0} is longer than {MAX_VALUE_BYTES} bytes or holds a NUL byte")]
    BadValue(String),
    /// More than [`MAX_VARS`].
    #[error("at most {MAX_VARS} variables may be declared for a bot")]
    TooMany,
    /// The same name twice.
    #[error("{0} is declared twice")]
    Duplicate(String),
}

/// Splits `KEY=VALUE` (as given to `--bot-env`) and checks it.
///
/// # Errors
/// A [`BotEnvError`] saying what is wrong.
pub fn parse_assignment(text: &str) -> Result<(String, String), BotEnvError> {
    let (k, v) = text
        .split_once('=')
        .ok_or_else(|| BotEnvError::NotAnAssignment(text.to_string()))?;
    let pair = (k.to_string(), v.to_string());
    check(std::slice::from_ref(&pair))?;
    Ok(pair)
}

/// Checks a whole set of declared variables.
///
/// # Errors
/// The first [`BotEnvError`] found.
pub fn check(vars: &[(String, String)]) -> Result<(), BotEnvError> {
    if vars.len() > MAX_VARS {
        return Err(BotEnvError::TooMany);
    }
    for (i, (k, v)) in vars.iter().enumerate() {
        let mut chars = k.chars();
        let first_ok = chars
            .next()
            .is_some_and(|c| c.is_ascii_alphabetic() || c == '_');
        if !first_ok || !chars.all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return Err(BotEnvError::BadName(k.clone()));
        }
        if RESERVED.contains(&k.as_str()) || k.to_ascii_uppercase().starts_with("MAZEARENA_") {
            return Err(BotEnvError::Reserved(k.clone()));
        }
        if v.len() > MAX_VALUE_BYTES || v.contains('\0') {
            return Err(BotEnvError::BadValue(k.clone()));
        }
        if vars[..i].iter().any(|(other, _)| other == k) {
            return Err(BotEnvError::Duplicate(k.clone()));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn assignments_are_split_at_the_first_equals_sign() {
        assert_eq!(
            parse_assignment("ALPHA=0.5=x").unwrap(),
            ("ALPHA".into(), "0.5=x".into())
        );
        assert_eq!(
            parse_assignment("_X=").unwrap(),
            ("_X".into(), String::new())
        );
    }

    #[test]
    fn bad_and_reserved_names_are_refused() {
        assert!(matches!(
            parse_assignment("NOEQUALS"),
            Err(BotEnvError::NotAnAssignment(_))
        ));
        for bad in ["1X=a", "A-B=c", "=v", "A B=c"] {
            assert!(
                matches!(parse_assignment(bad), Err(BotEnvError::BadName(_))),
                "{bad}"
            );
        }
        for reserved in [
            "PATH=/x",
            "HOME=/",
            "TMPDIR=/",
            "MAZEARENA_ADMIN_TOKEN=x",
            "mazearena_db=x",
        ] {
            assert!(
                matches!(parse_assignment(reserved), Err(BotEnvError::Reserved(_))),
                "{reserved}"
            );
        }
        assert!(matches!(
            parse_assignment(&format!("A={}", "x".repeat(MAX_VALUE_BYTES + 1))),
            Err(BotEnvError::BadValue(_))
        ));
    }

    #[test]
    fn sets_are_checked_for_duplicates_and_size() {
        let v = |k: &str| (k.to_string(), "1".to_string());
        assert_eq!(
            check(&[v("A"), v("B"), v("A")]),
            Err(BotEnvError::Duplicate("A".into()))
        );
        let many: Vec<_> = (0..=MAX_VARS).map(|i| v(&format!("V{i}"))).collect();
        assert_eq!(check(&many), Err(BotEnvError::TooMany));
    }
}
