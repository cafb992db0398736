//! The `mazearena` command line.

/// Runs the command line.
///
/// # Errors
/// Any failure, as a message for the user.
pub fn run() -> anyhow::Result<()> {
    Ok(())
}
