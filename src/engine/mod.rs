//! The pure game engine: maze model, file formats, the referee, scoring and the solver.
//!
//! Nothing in here performs I/O, reads a clock or draws unseeded randomness: the same
//! inputs always give the same outputs, which is what makes a match replayable to the
//! exact step. The bot runner, storage and CLI are layers around it.

pub mod game;
pub mod generator;
pub mod geometry;
pub mod maze;
pub mod mazefile;
pub mod render;
pub mod score;
pub mod solver;

pub use game::{Action, Game, GameConfig, GameEnd, Sense, Sensors, StepReport, Warning};
pub use geometry::{Heading, Position};
pub use maze::Maze;
pub use mazefile::MazeError;
pub use score::Score;
