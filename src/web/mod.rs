//! The web face: HTML for the replay viewer and the server's pages.
//!
//! Pure rendering: every function here takes data and returns markup (maud escapes
//! every value, so names, stderr lines and debug text from bots stay text). Nothing in
//! here reads the database, the clock or files; `api::site` fetches and calls in, and
//! the CLI writes the standalone viewer to a file. The viewer's script and styles are
//! embedded in the binary: no page loads anything from the network.

pub mod finale;
pub mod layout;
pub mod pages;
pub mod policy;
pub mod viewer;

/// The site's icon.
pub const FAVICON_SVG: &str = include_str!("assets/favicon.svg");
