//! A store's coarser datasets as the volume's pyramid levels, used as the file gives them where
//! they lie on the pyramid's grid (docs/design.md §5): a dataset whose spatial dimensions are
//! those of pyramid level k and whose scale and translation are level 0's composed with that
//! level's (scale 2^k, a shift of (2^k − 1)/2 voxels) is read as level k, in place of computing
//! it. Others (another grid, another downsampling factor) are listed by `info` and not used.

use std::path::{Path, PathBuf};

use super::Layout;
use super::meta::{ArrayMeta, Image};
use super::read::Dataset;
use super::root::Root;
use crate::progress::Cancel;
use crate::volume::Voxels;
use crate::volume::pyramid::{LevelSource, coarser_dims, step};

/// The datasets of a store that are pyramid levels, by level.
#[derive(Debug)]
pub struct StoreLevels {
    root: Root,
    node: String,
    image: PathBuf,
    layout: Layout,
    at: [u64; 2],
    max_memory: u64,
    scratch: Option<PathBuf>,
    /// The load's cancellation, looked at as a level is read.
    cancel: Cancel,
    /// Pyramid level, dataset path and array metadata, of each dataset on the grid.
    levels: Vec<(usize, String, ArrayMeta)>,
}

impl StoreLevels {
    /// The levels of `image` (whose datasets' arrays are `arrays`) beyond `first`, the dataset
    /// read as level 0; `None` when none lies on the pyramid's grid.
    pub fn new(image: &Image, arrays: &[ArrayMeta], first: &Dataset<'_>) -> Option<Self> {
        let levels: Vec<(usize, String, ArrayMeta)> = (1..image.datasets.len())
            .filter_map(|i| {
                let k = pyramid_level(image, arrays, first.layout, i)?;
                Some((k, image.datasets[i].path.clone(), arrays[i].clone()))
            })
            .collect();
        (!levels.is_empty()).then(|| Self {
            root: first.root.clone(),
            node: first.node.to_string(),
            image: first.image.to_path_buf(),
            layout: first.layout.clone(),
            at: first.at,
            max_memory: first.max_memory,
            scratch: first.scratch.map(Path::to_path_buf),
            cancel: first.cancel.clone(),
            levels,
        })
    }
}

/// The pyramid level dataset `i` of `image` is, when it lies on the pyramid's grid.
pub fn pyramid_level(
    image: &Image,
    arrays: &[ArrayMeta],
    layout: &Layout,
    i: usize,
) -> Option<usize> {
    let (base, this) = (&arrays[0], &arrays[i]);
    let spatial: Vec<usize> = layout.spatial.iter().flatten().copied().collect();
    // Time and channel as level 0 has them.
    let same_rest = (0..base.shape.len())
        .filter(|a| !spatial.contains(a))
        .all(|a| base.shape[a] == this.shape[a]);
    if !same_rest {
        return None;
    }
    let dims0 = layout.dims(&base.shape);
    let target = layout.dims(&this.shape);
    let (mut d, mut factor, mut k) = (dims0, [1usize; 3], 0);
    while d != target {
        // Every axis as coarse as it gets (a zero, from a broken store, stays zero).
        if d.iter().all(|&n| n <= 1) {
            return None;
        }
        let s = step(d);
        factor = std::array::from_fn(|m| factor[m] * s[m]);
        d = coarser_dims(d);
        k += 1;
    }
    let (d0, di) = (&image.datasets[0], &image.datasets[i]);
    // Volume axis m (x first) is array axis spatial[2 - m].
    let on_grid = layout.spatial.iter().rev().enumerate().all(|(m, axis)| {
        let Some(a) = *axis else { return true };
        let f = factor[m] as f64;
        let (s0, t0) = (d0.scale[a], d0.translation[a]);
        let tolerance = 1e-6 * s0 * f;
        (di.scale[a] - s0 * f).abs() <= tolerance
            && (di.translation[a] - (t0 + s0 * (f - 1.0) / 2.0)).abs() <= tolerance
    });
    (k > 0 && on_grid).then_some(k)
}

impl LevelSource for StoreLevels {
    fn level(&self, k: usize, dims: [usize; 3]) -> Option<crate::error::Result<Voxels>> {
        let (_, path, meta) = self.levels.iter().find(|(level, _, _)| *level == k)?;
        let dataset = Dataset {
            root: &self.root,
            node: &self.node,
            image: &self.image,
            path,
            meta,
            layout: &self.layout,
            at: self.at,
            max_memory: self.max_memory,
            scratch: self.scratch.as_deref(),
            cancel: &self.cancel,
        };
        // A level that cannot be read is computed instead unless asked for (`asked_level`).
        Some(dataset.voxels(dims))
    }
}
