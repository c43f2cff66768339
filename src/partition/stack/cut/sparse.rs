//! The information a top-down partition along an axis keeps, estimated fast enough to rank
//! every axis of the viewpoint sphere: each voxel of a subset (every `e`-th along the two grid
//! axes most across the axis, every one along the third) is counted, by its own bin, in the
//! slice its centre lies in, of the slices [`SliceStack::new`](super::SliceStack) cuts (the same
//! positions along the axis, slice `k` holding the centres within half a slice of its own). One
//! linear pass over the voxels, without interpolation: along a coordinate axis, with every
//! voxel, these are the stack's histograms exactly; along an oblique one they are the voxels'
//! rather than the resampled lattice's (which mixes neighbouring values at the edges between
//! materials), which ranks axes as well at a fraction of the cost.

use std::borrow::Cow;

use rayon::prelude::*;

use super::{Cutter, StackParams, oblique_lattice};
use crate::error::Result;
use crate::geometry::{coordinate_axis, dot};
use crate::partition::SplitHistory;
use crate::progress::Monitor;
use crate::volume::background::Background;
use crate::volume::{Volume, Voxel, VoxelQuantizer};

/// Which voxels count and where the slice edges lie: every `every`-th voxel along the two grid
/// axes most across the axis, from an offset that phase `phase` (0 to 3) picks (none, half the
/// subset's spacing along both, along the first, along the second), and on an oblique axis the
/// slice edges moved by a quarter slice a phase.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InPlane {
    /// One voxel in this many along each of the two grid axes most across the axis (1: every
    /// voxel).
    pub every: usize,
    /// The phase, 0 to 3.
    pub phase: usize,
}

impl InPlane {
    /// Every voxel, the slices unshifted.
    pub const ALL: Self = Self { every: 1, phase: 0 };

    /// The phases that differ along `axis`: four, except one for every voxel along a
    /// coordinate axis (whose slices are the voxel planes).
    pub fn phases(every: usize, axis: [f64; 3]) -> usize {
        if every == 1 && coordinate_axis(axis).is_some() {
            1
        } else {
            4
        }
    }

    /// The offset of the subset along the two grid axes, in voxels.
    fn offset(self) -> [usize; 2] {
        let half = self.every / 2;
        match self.phase % 4 {
            0 => [0, 0],
            1 => [half, half],
            2 => [half, 0],
            _ => [0, half],
        }
    }
}

/// `I(slab; value)`, bits, of the top-down partition into `slabs` slabs (fewer when the stack has
/// fewer slices) of the voxels `in_plane` picks, each counted in the slice of `volume`'s stack
/// along `axis` its centre lies in, with `background` left out: the quantity top-down maximises
/// greedily, on a subset of its samples.
pub fn sampled_gain(
    volume: &Volume,
    axis: [f64; 3],
    params: &StackParams,
    background: &Background,
    in_plane: InPlane,
    slabs: usize,
    monitor: &Monitor,
) -> Result<f64> {
    let cutter = Cutter::with(volume, axis, params, Cow::Borrowed(background), |d| {
        oblique_lattice(volume, d, params)
    })?;
    let histograms = cutter.voxel_histograms(in_plane, monitor)?;
    let splits = slabs.saturating_sub(1);
    Ok(SplitHistory::with_limit(&histograms, cutter.bins(), splits).information(slabs))
}

/// Where a voxel's centre falls among the slices: slice `floor(t + 1 + ...) - 1` of the
/// position `t = p·d / y - k_first + ½ + shift` grows by `step[m]` a voxel along grid axis `m`.
struct Slicing {
    step: [f64; 3],
    /// `t + 1` at voxel (0, 0, 0): kept above 0 so that truncation is floor.
    origin: f64,
    slices: usize,
}

impl Slicing {
    #[inline]
    fn slice(&self, u: f64) -> usize {
        (u as usize).saturating_sub(1).min(self.slices - 1)
    }
}

impl Cutter<'_> {
    /// The slicing of the cutter's axis, slice edges shifted by `shift` of a slice.
    fn slicing(&self, shift: f64) -> Slicing {
        let spacing = self.volume.spacing();
        let slices = self.slices();
        match &self.lattice {
            Some(l) => {
                let y = l.sample_spacing;
                let (k_first, _) = l.sample_range();
                Slicing {
                    step: std::array::from_fn(|m| spacing[m] * l.d[m] / y),
                    origin: 1.5 + shift - k_first as f64,
                    slices,
                }
            }
            None => Slicing {
                step: self.axis,
                origin: 1.5,
                slices,
            },
        }
    }

    /// Per slice, the histogram of the symbols of the voxels `in_plane` picks, each in the slice
    /// its centre lies in: `slices × bins` counts.
    fn voxel_histograms(&self, in_plane: InPlane, monitor: &Monitor) -> Result<Vec<u64>> {
        crate::volume::with_voxels!(self.volume.data(), |voxels| {
            self.histograms_of(voxels, in_plane, monitor)
        })
    }

    /// [`voxel_histograms`](Self::voxel_histograms) of the voxels, in their own type.
    fn histograms_of<T: Voxel>(
        &self,
        voxels: &[T],
        in_plane: InPlane,
        monitor: &Monitor,
    ) -> Result<Vec<u64>> {
        let shift = if self.lattice.is_some() {
            in_plane.phase as f64 / 4.0
        } else {
            0.0
        };
        let slicing = self.slicing(shift);
        // The grid axis most along the axis is walked whole, the other two one voxel in `every`.
        let along = (0..3)
            .max_by(|&a, &b| slicing.step[a].abs().total_cmp(&slicing.step[b].abs()))
            .unwrap_or(2);
        let every = in_plane.every.max(1);
        let dims = self.volume.dims();
        let mut stride = [every; 3];
        stride[along] = 1;
        let mut first = [0; 3];
        for (m, o) in (0..3).filter(|&m| m != along).zip(in_plane.offset()) {
            first[m] = o.min(dims[m] - 1);
        }
        let (bins, q) = (self.bins, VoxelQuantizer::new::<T>(self.quantizer));
        let du = slicing.step[0] * stride[0] as f64;
        let zero = || vec![0u64; slicing.slices * bins];
        let background = self.background.test();
        (first[2]..dims[2])
            .into_par_iter()
            .step_by(stride[2])
            .try_fold(zero, |mut h, z| {
                for y in (first[1]..dims[1]).step_by(stride[1]) {
                    let row = (z * dims[1] + y) * dims[0];
                    let start = [first[0] as f64, y as f64, z as f64];
                    let mut u = slicing.origin + dot(slicing.step, start);
                    for x in (first[0]..dims[0]).step_by(stride[0]) {
                        let index = row + x;
                        let v = voxels[index];
                        if !background.contains(index, v.to_f32())
                            && let Some(b) = q.bin(v)
                        {
                            h[slicing.slice(u) * bins + usize::from(b)] += 1;
                        }
                        u += du;
                    }
                }
                monitor.check()?;
                Ok(h)
            })
            .try_reduce_with(|mut a, b| {
                a.iter_mut().zip(&b).for_each(|(x, y)| *x += y);
                Ok(a)
            })
            .unwrap_or_else(|| Ok(zero()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::partition::{PartitionParams, partition};
    use crate::volume::background::BackgroundRule;
    use crate::volume::phantom;

    fn gain(v: &Volume, axis: [f64; 3], p: &PartitionParams, b: &Background, at: InPlane) -> f64 {
        sampled_gain(v, axis, &p.stack, b, at, 4, &Monitor::none()).unwrap()
    }

    /// With every voxel, the estimate along a coordinate axis is the partition's information,
    /// with and without a background; along an oblique axis it is close to it, lower by the
    /// values the lattice's interpolation mixes at the edges between layers (a fifth of the
    /// samples of this small volume), which the slabs holding those edges gain.
    #[test]
    fn every_voxel_gives_the_partitions_information() {
        let v = phantom::layers([20, 18, 24], [0.2, 0.3, 1.0], 3).unwrap();
        for rule in [BackgroundRule::None, BackgroundRule::Below(80.0)] {
            let mut p = PartitionParams::default();
            p.stack.background = rule;
            let background = Background::find(&v, rule, &Monitor::none()).unwrap();
            for axis in [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.2, 0.3, 1.0]] {
                let full = partition(&v, axis, &p, &Monitor::none())
                    .unwrap()
                    .information;
                let g = gain(&v, axis, &p, &background, InPlane::ALL);
                let tolerance =
                    if coordinate_axis(crate::geometry::normalize(axis).unwrap()).is_some() {
                        1e-12
                    } else {
                        0.2 * full
                    };
                assert!(
                    (g - full).abs() < tolerance,
                    "{axis:?} {rule:?}: {g} vs {full}"
                );
            }
        }
    }

    /// A subset of voxels, and every phase of it, estimates the information closely; phases
    /// differ except for every voxel along a coordinate axis.
    #[test]
    fn a_subset_estimates_it() {
        let v = phantom::layers([32, 32, 32], [0.0, 0.0, 1.0], 3).unwrap();
        let p = PartitionParams::default();
        let none = Background::none();
        for axis in [[0.0, 0.0, 1.0], [0.1, 0.2, 1.0]] {
            let full = gain(&v, axis, &p, &none, InPlane::ALL);
            for phase in 0..4 {
                let g = gain(&v, axis, &p, &none, InPlane { every: 3, phase });
                assert!(
                    (g - full).abs() < 0.05 * full,
                    "phase {phase}: {g} vs {full}"
                );
            }
        }
        let z = [0.0, 0.0, 1.0];
        assert_eq!(InPlane::phases(1, z), 1);
        assert_eq!(InPlane::phases(2, z), 4);
        assert_eq!(InPlane::phases(1, [0.6, 0.8, 0.0]), 4);
        let oblique = [0.3, 0.2, 1.0];
        let a = gain(&v, oblique, &p, &none, InPlane { every: 1, phase: 0 });
        let b = gain(&v, oblique, &p, &none, InPlane { every: 1, phase: 2 });
        assert_ne!(a, b, "a shifted slicing counts other voxels in each slice");
    }
}
