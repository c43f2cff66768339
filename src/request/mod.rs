//! Requests: analyse, render and slice as values, each run with a progress [`Monitor`]. A front
//! end (the CLI's commands, the TUI's jobs, Python's calls) builds a request from its flags or
//! keywords and prints, draws or returns its outcome; the steps between (the level asked for,
//! the budget's plan, the analysis on it, the report of where it ran, the tile of the strip of
//! faces) are written here once.
//!
//! - [`AnalysisRequest`]: the view search and the partition at the level asked for within the
//!   memory budget ([`Planned`] between planning and running, [`Analysed`] when done, with its
//!   report).
//! - [`RenderRequest`]: the exploded view of an analysis's slabs, or the strip of their faces.
//! - [`SliceRequest`]: one slice across the slab axis.
//!
//! [`Monitor`]: crate::progress::Monitor

mod analysis;
mod render;
mod slice;

pub use analysis::{Analysed, AnalysisRequest, Level, Planned};
pub use render::{RenderRequest, Shown, faces_tile};
pub use slice::SliceRequest;

#[cfg(test)]
mod tests;
