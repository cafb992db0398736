//! The `mazearena` binary: a thin wrapper over [`mazearena::cli`].

use std::process::ExitCode;

fn main() -> ExitCode {
    // Inside the sandbox, before anything else: set up the jail and exec the bot.
    if let Some(code) = mazearena::cli::sandbox_exec_if_asked() {
        return code;
    }
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| "mazearena=warn".into()),
        )
        .with_writer(std::io::stderr)
        // Colours only on a terminal: a log written to a file or a pipe stays plain text.
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .init();
    match mazearena::cli::run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(
                e.downcast_ref::<mazearena::cli::ExitWith>()
                    .map_or(2, |x| x.code),
            )
        }
    }
}
