//! The pyramid of a [`Volume`]: its coarser levels, each built the first time it is asked for,
//! from the file where the file holds it (an OME-Zarr store's coarser datasets, used as the file
//! gives them) or else computed from the finest level already built above it.

use std::sync::{Arc, OnceLock};

use super::{chain_dims, downsample_times, level_transform, steps_after};
use crate::volume::{Level, Volume, Voxels, compute_stats};

/// Pyramid levels a file holds itself, on the pyramid's grid (docs/design.md §5).
pub trait LevelSource: Send + Sync + std::fmt::Debug {
    /// The voxels (x fastest) of pyramid level `k`, whose dimensions are `dims`; `None` when the
    /// file holds no such level (it is then computed); an error when it holds the level and it
    /// cannot be read (computed instead, unless asked for: [`Volume::asked_level`]).
    fn level(&self, k: usize, dims: [usize; 3]) -> Option<crate::error::Result<Voxels>>;
}

/// The coarser levels of a volume's pyramid, shared by all its levels: slot `i` holds pyramid
/// level `i + 1`, which step `i` makes of level `i`.
#[derive(Debug)]
pub struct Pyramid {
    slots: Box<[OnceLock<Arc<Volume>>]>,
    /// Per level, the step (per axis 1 or 2) from the level above it: every axis longer than
    /// one voxel halved, but for a store's own levels the axes they halve.
    steps: Box<[[usize; 3]]>,
    /// The levels the file holds, read in place of computing them.
    source: Option<Arc<dyn LevelSource>>,
    /// Level 0's grid, when a coarser level was read without it.
    finest: Option<Finest>,
}

/// The grid of a pyramid's level 0, known from the file's metadata when a coarser level was read
/// without reading level 0 ([`Volume::unread_finest`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Finest {
    /// Level 0's dimensions, x first.
    pub dims: [usize; 3],
    /// Level 0's spacing, mm.
    pub spacing: [f64; 3],
    /// Level 0's voxel-to-world transform.
    pub transform: crate::geometry::WorldTransform,
}

impl std::ops::Deref for Pyramid {
    type Target = [OnceLock<Arc<Volume>>];

    fn deref(&self) -> &Self::Target {
        &self.slots
    }
}

/// No coarser level built yet, for a level 0 of `dims`: a slot for each level until every axis
/// is one voxel.
pub fn empty(dims: [usize; 3]) -> Arc<Pyramid> {
    Arc::new(Pyramid::new(steps_after(dims, &[]), None))
}

impl Pyramid {
    fn new(steps: Vec<[usize; 3]>, source: Option<Arc<dyn LevelSource>>) -> Self {
        Self {
            slots: steps.iter().map(|_| OnceLock::new()).collect(),
            steps: steps.into(),
            source,
            finest: None,
        }
    }
}

impl Volume {
    /// Where this volume sits in its pyramid.
    #[must_use]
    pub fn level(&self) -> Level {
        self.level
    }

    /// This volume (level 0, just read) with the coarser levels its file holds, read in place of
    /// computing them when first asked for; `steps` are the file's own first levels' steps (per
    /// axis 1 or 2), after which every axis is halved.
    #[must_use]
    pub(crate) fn with_level_source(
        mut self,
        source: Arc<dyn LevelSource>,
        steps: &[[usize; 3]],
    ) -> Self {
        self.pyramid = Arc::new(Pyramid::new(steps_after(self.dims, steps), Some(source)));
        self
    }

    /// The dimensions and spacing of this level and of each coarser level, finest first
    /// (nothing is built).
    #[must_use]
    pub fn level_grids(&self) -> Vec<([usize; 3], [f64; 3])> {
        (0..=self.coarser_levels())
            .map(|k| {
                let (scale, dims) = self.scale_to(k);
                (
                    dims,
                    std::array::from_fn(|m| self.spacing[m] * scale[m] as f64),
                )
            })
            .collect()
    }

    /// Level 0's grid when this level was read from a file without reading level 0 (an
    /// OME-Zarr store's coarser dataset: a preview, or `info`'s statistics of a remote store);
    /// `None` for every level of a volume whose level 0 was read.
    #[must_use]
    pub fn unread_finest(&self) -> Option<&Finest> {
        self.pyramid.finest.as_ref()
    }

    /// The dimensions of every level of this volume's pyramid from level 0, finest first: those
    /// of level 0's grid on for a level read without level 0 ([`unread_finest`](Self::unread_finest)),
    /// else [`level_dims`](Self::level_dims).
    #[must_use]
    pub fn pyramid_dims(&self) -> Vec<[usize; 3]> {
        match &self.pyramid.finest {
            Some(finest) => chain_dims(finest.dims, &self.pyramid.steps),
            None => self.level_dims(),
        }
    }

    /// The dimensions of this level and of each coarser level, finest first.
    #[must_use]
    pub fn level_dims(&self) -> Vec<[usize; 3]> {
        chain_dims(self.dims, &self.pyramid.steps[self.level.index..])
    }

    /// This volume, read from a file that holds it as pyramid level `k` of a level 0 of grid
    /// `finest` not read (an OME-Zarr store's coarser dataset, on the pyramid's grid, whose own
    /// first levels' steps are `steps`): it takes that place in the pyramid, and is quantized
    /// with its own range, level 0's being unknown. Its coarser levels are computed from it.
    #[must_use]
    pub(crate) fn into_pyramid_level(
        mut self,
        k: usize,
        finest: Finest,
        steps: &[[usize; 3]],
    ) -> Self {
        let dims0 = finest.dims;
        let mut pyramid = Pyramid::new(steps_after(dims0, steps), None);
        pyramid.finest = Some(finest);
        let (factor, _) = scale_of(dims0, &pyramid.steps[..k]);
        let labels = self.labels().is_some();
        self.level = Level {
            index: k,
            factor,
            range: [self.stats.min, self.stats.max],
            labels,
        };
        self.pyramid = Arc::new(pyramid);
        self
    }

    /// Pyramid level `k` of this volume, `k` levels coarser (docs/design.md §5; the top level
    /// past the last): each level halves every axis longer than one voxel, a voxel the mean of
    /// the finite voxels under it (for a label volume their most frequent value), quantized with
    /// level 0's range. A level is made the first time it is asked for and kept: read from the
    /// file where it holds the level, else in one streaming pass from the finest level already
    /// built above it.
    #[must_use]
    pub fn coarser(&self, k: usize) -> Arc<Volume> {
        let here = self.level.index;
        let target = (here + k).min(self.pyramid.len());
        if target == here {
            return Arc::new(self.clone());
        }
        Arc::clone(self.pyramid[target - 1].get_or_init(|| {
            let (_, dims) = self.scale_to(target - here);
            let read = self
                .pyramid
                .source
                .as_ref()
                .and_then(|s| s.level(target, dims))
                .and_then(Result::ok);
            if let Some(data) = read {
                return Arc::new(self.level_of(target - here, data));
            }
            // The finest level built between this one and the target, or this one.
            match (here + 1..target)
                .rev()
                .find_map(|l| self.pyramid[l - 1].get())
            {
                Some(finer) => Arc::new(finer.halved(target - finer.level.index)),
                None => Arc::new(self.halved(target - here)),
            }
        }))
    }

    /// Pyramid level `k` of this volume as [`Volume::coarser`] gives it, asked for by the user
    /// (`--resolution K`): a level the file holds that cannot be read is an error, not computed
    /// in its place.
    pub fn asked_level(&self, k: usize) -> crate::error::Result<Arc<Volume>> {
        let here = self.level.index;
        let target = (here + k).min(self.pyramid.len());
        if target == here || self.pyramid[target - 1].get().is_some() {
            return Ok(self.coarser(k));
        }
        let (_, dims) = self.scale_to(target - here);
        let read = self
            .pyramid
            .source
            .as_ref()
            .and_then(|s| s.level(target, dims));
        match read {
            Some(Err(e)) => Err(e),
            Some(Ok(data)) => {
                Ok(Arc::clone(self.pyramid[target - 1].get_or_init(|| {
                    Arc::new(self.level_of(target - here, data))
                })))
            }
            None => Ok(self.coarser(k)),
        }
    }

    /// The number of pyramid levels below level 0: halving stops when every axis is one voxel.
    #[must_use]
    pub fn coarser_levels(&self) -> usize {
        self.pyramid.len() - self.level.index
    }

    /// Per axis, how many voxels of this level one voxel `times` levels coarser spans, and that
    /// level's dimensions.
    fn scale_to(&self, times: usize) -> ([usize; 3], [usize; 3]) {
        let here = self.level.index;
        scale_of(self.dims, &self.pyramid.steps[here..here + times])
    }

    /// Whether this level's coarser levels take the most frequent label.
    fn labelled(&self) -> bool {
        self.level.index == 0 && self.labels().is_some() || self.level.labels
    }

    /// The level `times` levels coarser than this one, computed.
    fn halved(&self, times: usize) -> Volume {
        let labels = self.labelled();
        let here = self.level.index;
        let steps = &self.pyramid.steps[here..here + times];
        let (values, _) = crate::volume::with_voxels!(&self.data, |v| {
            downsample_times(v, self.dims, labels, steps)
        });
        self.level_of(times, Voxels::owned(values))
    }

    /// The level `times` levels coarser than this one, of voxels `data`.
    fn level_of(&self, times: usize, data: Voxels) -> Volume {
        let labels = self.labelled();
        let (scale, dims) = self.scale_to(times);
        // Each halving doubles the span along the axes it halves.
        let factor: [usize; 3] = std::array::from_fn(|m| self.level.factor[m] * scale[m]);
        let scale = scale.map(|s| s as f64);
        let spacing: [f64; 3] = std::array::from_fn(|m| self.spacing[m] * scale[m]);
        let stats = crate::volume::with_voxels!(&data, |v| compute_stats(v));
        let labels_of_level0 = if labels {
            self.labels().map(<[_]>::to_vec)
        } else {
            None
        };
        Volume {
            data,
            dims,
            spacing,
            voxel_type: self.voxel_type,
            stats,
            transform: level_transform(&self.transform, scale),
            level: Level {
                index: self.level.index + times,
                factor,
                labels,
                range: self.level.range,
            },
            labels: Arc::new(OnceLock::from(labels_of_level0)),
            pyramid: Arc::clone(&self.pyramid),
            remote: self.remote,
        }
    }
}

/// Per axis, how many voxels of a level of `dims` one voxel of the level the steps `steps` make
/// of it spans, and that level's dimensions.
fn scale_of(dims: [usize; 3], steps: &[[usize; 3]]) -> ([usize; 3], [usize; 3]) {
    let scale = steps
        .iter()
        .fold([1usize; 3], |f, s| std::array::from_fn(|m| f[m] * s[m]));
    (scale, chain_dims(dims, steps)[steps.len()])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::VoxelType;

    /// A file that holds pyramid level 2 only, every voxel 7.
    #[derive(Debug)]
    struct Sevens;

    impl LevelSource for Sevens {
        fn level(&self, k: usize, dims: [usize; 3]) -> Option<crate::error::Result<Voxels>> {
            match k {
                2 => Some(Ok(Voxels::owned(vec![7u8; dims.iter().product()]))),
                3 => Some(Err(crate::error::Error::format(
                    std::path::Path::new("f"),
                    "level 3 unreadable",
                ))),
                _ => None,
            }
        }
    }

    #[test]
    fn levels_the_file_holds_are_read_the_others_computed() {
        let data: Vec<f32> = (0..8 * 6 * 4).map(|i| (i % 5) as f32).collect();
        let plain = Volume::new([8, 6, 4], [1.0, 2.0, 3.0], VoxelType::U8, data).unwrap();
        let v = plain.clone().with_level_source(Arc::new(Sevens), &[]);
        let (read, computed) = (v.coarser(2), plain.coarser(2));
        assert_eq!(read.dims(), computed.dims());
        assert_eq!(read.transform(), computed.transform(), "the pyramid's grid");
        assert_eq!(read.level(), computed.level());
        assert!((0..read.len()).all(|i| read.data().get(i) == 7.0));
        assert_eq!(read.stats().max, 7.0);
        // Level 1 the file lacks: computed, the same as without a source.
        let (a, b) = (v.coarser(1), plain.coarser(1));
        assert_eq!(a.data().to_f32_vec(), b.data().to_f32_vec());
        // Level 3 from level 2, which the file gave.
        assert!((0..v.coarser(3).len()).all(|i| v.coarser(3).data().get(i) == 7.0));
        // Level 3 the file holds but cannot give: computed when the budget picks it (above,
        // from level 2), an error when asked for.
        let fresh = plain.clone().with_level_source(Arc::new(Sevens), &[]);
        let asked = fresh.asked_level(3).err().map(|e| e.to_string());
        assert!(asked.is_some_and(|e| e.contains("unreadable")));
        let two = fresh.asked_level(2).ok().map(|l| l.data().get(0));
        assert_eq!(two, Some(7.0));
        assert_eq!(fresh.coarser(3).dims(), plain.coarser(3).dims());
    }
}
