//! mazearena starter kit for Rust.
//!
//! - [`protocol`]: speaks protocol v1 on stdin/stdout; your bot implements [`protocol::Bot`].
//! - [`map`]: a wall map built from the sensor rays, and a planner that counts steps the
//!   way the referee does (one rotation, then up to 3 cells in a straight line).
//!
//! - [`champion`]: the strongest bot here, as a library so studies can drive it in-process.
//!
//! No dependencies: the kit builds in seconds and runs anywhere.

pub mod champion;
pub mod map;
pub mod protocol;
