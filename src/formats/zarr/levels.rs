//! A store's coarser datasets as the volume's pyramid levels, used as the file gives them where
//! they lie on a pyramid's grid (docs/design.md §5). From each dataset to the next (those off the
//! grid passed over), every spatial axis is halved one or more times (rounding up) or kept: the
//! pyramid's steps between them halve each axis as many times as the store does, so a store
//! that halves y and x only (ome-zarr-py's `write_image`) gives a level a dataset, and one that
//! halves every axis gives the pyramid that halves every axis. A dataset is on the grid when,
//! besides, its scale and translation are level 0's composed with its level's (a factor f per
//! axis, a shift of (f − 1)/2 voxels); it is then read as that level, in place of computing it.
//! Others are listed by `info` and not used. Past the store's last level, every axis is halved.

use std::path::{Path, PathBuf};

use super::Layout;
use super::meta::{ArrayMeta, Image};
use super::read::Dataset;
use super::root::Root;
use crate::progress::Cancel;
use crate::volume::Voxels;
use crate::volume::pyramid::{LevelSource, coarser_dims_by};

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
    /// read as level 0, and the steps of the pyramid's levels down to the last of them; `None`
    /// when none lies on the pyramid's grid.
    pub fn new(
        image: &Image,
        arrays: &[ArrayMeta],
        first: &Dataset<'_>,
    ) -> Option<(Self, Vec<[usize; 3]>)> {
        let pyramid = StorePyramid::of(image, arrays, first.layout);
        let levels: Vec<(usize, String, ArrayMeta)> = (pyramid.levels.iter())
            .map(|&(k, i)| (k, image.datasets[i].path.clone(), arrays[i].clone()))
            .collect();
        let source = (!levels.is_empty()).then(|| Self {
            root: first.root.clone(),
            node: first.node.to_string(),
            image: first.image.to_path_buf(),
            layout: first.layout.clone(),
            at: first.at,
            max_memory: first.max_memory,
            scratch: first.scratch.map(Path::to_path_buf),
            cancel: first.cancel.clone(),
            levels,
        })?;
        Some((source, pyramid.steps))
    }
}

/// The pyramid a store's datasets make.
#[derive(Debug, Default)]
pub struct StorePyramid {
    /// The steps (per axis, x first, 1 or 2) of its levels down to the last dataset on the grid.
    pub steps: Vec<[usize; 3]>,
    /// The pyramid level and the index of each dataset on the grid beyond the first.
    pub levels: Vec<(usize, usize)>,
}

impl StorePyramid {
    /// The pyramid of `image`'s datasets (whose arrays are `arrays`).
    pub fn of(image: &Image, arrays: &[ArrayMeta], layout: &Layout) -> Self {
        let mut pyramid = Self::default();
        let Some(base) = arrays.first() else {
            return pyramid;
        };
        let spatial: Vec<usize> = layout.spatial.iter().flatten().copied().collect();
        let (mut dims, mut factor) = (layout.dims(&base.shape), [1usize; 3]);
        for (i, this) in arrays.iter().enumerate().skip(1) {
            // Time and channel as level 0 has them.
            let same_rest = (0..base.shape.len())
                .filter(|a| !spatial.contains(a))
                .all(|a| base.shape.get(a) == this.shape.get(a));
            let Some(steps) = same_rest
                .then(|| steps_between(dims, layout.dims(&this.shape)))
                .flatten()
            else {
                continue;
            };
            let f = steps
                .iter()
                .fold(factor, |f, s| std::array::from_fn(|m| f[m] * s[m]));
            if on_grid(image, layout, i, f) {
                dims = layout.dims(&this.shape);
                factor = f;
                pyramid.steps.extend(steps);
                pyramid.levels.push((pyramid.steps.len(), i));
            }
        }
        pyramid
    }

    /// The pyramid level dataset `i` is, when it lies on the pyramid's grid.
    pub fn level_of(&self, i: usize) -> Option<usize> {
        (self.levels.iter()).find_map(|&(k, j)| (j == i).then_some(k))
    }
}

/// The steps from a level of `from` to one of `to`: along each axis, `to` is `from` halved
/// (rounding up) h times, 0 when kept; as many steps as the most halvings, each halving an axis
/// until its own count is done. `None` when `to` is not such a level, or is `from` itself.
fn steps_between(from: [usize; 3], to: [usize; 3]) -> Option<Vec<[usize; 3]>> {
    let mut halvings = [0usize; 3];
    for m in 0..3 {
        let mut d = from[m];
        while d != to[m] {
            // As coarse as it gets (a zero, from a broken store, stays zero).
            if d <= 1 {
                return None;
            }
            d = d.div_ceil(2);
            halvings[m] += 1;
        }
    }
    let levels = *halvings.iter().max()?;
    let steps: Vec<[usize; 3]> = (0..levels)
        .map(|j| halvings.map(|h| if j < h { 2 } else { 1 }))
        .collect();
    debug_assert_eq!(steps.iter().fold(from, |d, &s| coarser_dims_by(d, s)), to);
    (levels > 0).then_some(steps)
}

/// Whether dataset `i` of `image` has the scale and translation of a level whose voxels span
/// `factor` (x first) of level 0's: level 0's scale times the factor, its translation shifted by
/// (factor − 1)/2 of level 0's voxels.
fn on_grid(image: &Image, layout: &Layout, i: usize, factor: [usize; 3]) -> bool {
    let (d0, di) = (&image.datasets[0], &image.datasets[i]);
    // Volume axis m (x first) is array axis spatial[2 - m].
    layout.spatial.iter().rev().enumerate().all(|(m, axis)| {
        let Some(a) = *axis else { return true };
        let f = factor[m] as f64;
        let (s0, t0) = (d0.scale[a], d0.translation[a]);
        let tolerance = 1e-6 * s0 * f;
        (di.scale[a] - s0 * f).abs() <= tolerance
            && (di.translation[a] - (t0 + s0 * (f - 1.0) / 2.0)).abs() <= tolerance
    })
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
