//! Bot runner.
