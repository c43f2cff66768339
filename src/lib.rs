//! slabscope: similarity-based exploded views of 3D volumes (Ruiz, Viola, Boada, Bruckner,
//! Feixas and Sbert, 2008), as a library.
//!
//! The library knows nothing of terminals; the `slabscope` binary puts a TUI and a CLI over it.
//! [`volume`] loads and holds volumes; [`measure`] holds the information measures; [`view`] finds
//! the most structured view (paper §3.1 and §4).

pub mod error;
pub mod measure;
pub mod partition;
pub mod progress;
pub mod render;
#[cfg(test)]
mod testing;
pub mod view;
pub mod volume;

pub use error::{Error, Result};
pub use volume::io::{Format, LoadOptions, Loaded, load};
pub use volume::{Quantizer, Stats, Volume, VoxelType};

/// The name shown for the built-in dataset.
pub const BUILTIN_NAME: &str = "built-in body phantom (128x128x208)";

/// The built-in dataset: a `body` phantom of 128x128x208 voxels, made in memory in well under a second.
pub fn builtin_dataset() -> Result<Volume> {
    volume::phantom::body([128, 128, 208], 1)
}
