//! slabscope: similarity-based exploded views of 3D volumes (Ruiz, Viola, Boada, Bruckner,
//! Feixas and Sbert, 2008), as a library.
//!
//! Three steps, each a call: find the most structured view (the axis of lowest entropy rate over
//! an icosphere of viewpoints), cut the volume into slabs across it (top-down by information
//! gain, bottom-up by NMI merges, or the optimum), and render the slabs pulled apart.
//!
//! ```
//! use slabscope::render::{DEFAULT_SPREAD, Gap};
//! use slabscope::{AnalysisParams, Layout, LoadOptions, Monitor, RenderParams, Renderer};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! // A small CT-like phantom, written to a file so that it is loaded as any volume would be.
//! let dir = tempfile::tempdir()?;
//! let path = dir.path().join("body.nrrd");
//! let phantom = slabscope::volume::phantom::body([32, 32, 48], 1)?;
//! slabscope::formats::write_volume(&path, &phantom, false)?;
//!
//! let volume = slabscope::load(&path, &LoadOptions::default())?.volume;
//! let analysis = slabscope::analyze(&volume, &AnalysisParams::default(), &Monitor::none())?;
//! assert_eq!(analysis.partition.slabs.len(), 4);
//!
//! let layout = Layout::exploded(&analysis.partition, Gap::Similarity, DEFAULT_SPREAD);
//! let params = RenderParams { width: 160, height: 120, ..RenderParams::default() };
//! let image = Renderer::new(&volume)?.render(&layout, &params, &Monitor::none())?;
//! std::fs::write(dir.path().join("exploded.png"), image.png()?)?;
//! # Ok(())
//! # }
//! ```
//!
//! The library knows nothing of terminals; the `slabscope` binary puts a TUI and a CLI over it
//! (the repository's `README.md` and `docs/` describe them). Its modules, from the bottom up
//! (each depends only on those above it; `docs/design.md` gives the layer order):
//!
//! - [`measure`]: entropy, block entropies, Jensen-Shannon divergence, MI and NMI: pure maths.
//! - [`geometry`]: vectors, the [`Axis`] type (parsed, printed, canonical), an axis's frame, the
//!   ray lattice and its sampling parameters, world transforms.
//! - [`error`]: the [`Error`] enum, grouped by concern, with the parameter's name and value as data.
//! - [`progress`]: the [`Monitor`] every long computation takes: phase, progress and cancellation.
//! - [`volume`]: the [`Volume`] (voxels in their own type, owned or mapped), its statistics and
//!   quantization (docs/design.md §2), trilinear interpolation, the cell map, the pyramid and
//!   synthetic phantoms.
//! - [`formats`]: reading volumes from files, one reader per format, and writing them.
//! - [`view`]: the most structured view (paper §3.1, §4): the icosphere, the entropy rate of an
//!   axis and the search over the sphere.
//! - [`partition`](mod@partition): slabs along an axis (paper §5): slice stacks, top-down (§5.1), bottom-up
//!   (§5.2), the optimum, and [`Histories`], all three step histories read at any position.
//! - [`analysis`]: the view search and the partition together, as one call.
//! - [`explain`]: the numbers behind the chosen axis and each step, for teaching.
//! - [`render`]: the exploded view (paper §3, step 3): camera, transfer functions, layout, the ray
//!   caster and overlays.
//! - [`report`]: the JSON contract (docs/design.md §3, field by field in docs/json.md) and the
//!   other exports, built from the results.
//! - [`budget`]: the one planner of the pyramid level each piece of work runs on.
//! - [`triage`]: many volumes at once: what a set of paths holds, shards of it, one row each.
//! - [`params`]: every parameter a user sets, defined once, and the values given, parsed.
//! - [`request`]: analyse, render and slice as request values the front ends build and run.

pub mod analysis;
pub mod budget;
pub mod error;
pub mod explain;
pub mod formats;
pub mod geometry;
pub mod measure;
pub mod params;
pub mod partition;
pub mod progress;
pub mod render;
pub mod report;
pub mod request;
#[cfg(test)]
mod testing;
pub mod triage;
pub mod view;
pub mod volume;

pub use analysis::{Analysis, AnalysisParams, Plan, analyze, analyze_planned};
pub use error::{Error, Result};
pub use formats::{Format, LoadOptions, Loaded, load};
pub use geometry::Axis;
pub use geometry::lattice::SamplingParams;
pub use partition::{
    Histories, Method, Partition, PartitionParams, Scope, Stop, label_volume, partition,
};
pub use progress::{Cancel, Monitor, Progress};
pub use render::{Layout, RenderParams, Renderer};
pub use report::{AnalysisReport, SCHEMA_VERSION, SlabsReport};
pub use view::{ViewParams, ViewSearch, search};
pub use volume::{Quantizer, Stats, Volume, VoxelType};

/// The name shown for the built-in dataset.
pub const BUILTIN_NAME: &str = "built-in body phantom (128x128x208)";

/// The built-in dataset: a `body` phantom of 128x128x208 voxels, made in memory in well under a second.
pub fn builtin_dataset() -> Result<Volume> {
    volume::phantom::body([128, 128, 208], 1)
}
