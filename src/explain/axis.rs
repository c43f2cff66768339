//! The numbers behind one axis's entropy rate (paper eq. 2 to 4): the block counts on the paper's
//! single lattice, the block entropies taken over them, and one ray's run of samples.

use serde::Serialize;

use crate::error::{Error, Result};
use crate::geometry::lattice::Lattice;
use crate::geometry::{WorldAxis, canonical, normalize};
use crate::measure::{BlockCounts, entropy};
use crate::progress::Monitor;
use crate::view::{
    BinSampler, ViewParams, block_counts, block_counts_streamed, ray_bins, streamed_slabs,
    work_units,
};
use crate::volume::Volume;

/// One block of symbols (quantized samples in sequence order) and how often it occurs.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct BlockCount {
    /// The bins of the block's samples, first sample first.
    pub symbols: Vec<u8>,
    /// How many times it occurs along the rays.
    pub count: u64,
}

impl BlockCount {
    /// The `k`-blocks `counts` holds, with how many times each occurs.
    pub(crate) fn table_of(counts: &BlockCounts, k: usize) -> Vec<Self> {
        counts
            .table(k)
            .unwrap_or_default()
            .into_iter()
            .map(|(symbols, count)| Self { symbols, count })
            .collect()
    }
}

/// Why an axis has the entropy rate it has: every count behind `h = H(X^L) - H(X^(L-1))`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AxisLesson {
    /// The canonical unit axis, physical space.
    pub axis: [f64; 3],
    /// The axis in world coordinates.
    #[serde(flatten)]
    pub world: WorldAxis,
    /// Block length L.
    pub block: usize,
    /// Quantization bins.
    pub bins: usize,
    /// Rays of the paper's lattice that met the volume.
    pub rays: u64,
    /// Samples counted (missing ones left out).
    pub samples: u64,
    /// `H(X^1) … H(X^L)`, bits: entry `k - 1` is `H(X^k)`.
    pub block_entropies: Vec<f64>,
    /// `h = H(X^L) - H(X^(L-1))`, bits per sample: the view's `entropy_rate`.
    pub entropy_rate: f64,
    /// Every L-block that occurs, most frequent first (ties by symbols).
    pub blocks: Vec<BlockCount>,
    /// Every (L-1)-block that occurs, most frequent first.
    pub short_blocks: Vec<BlockCount>,
}

impl AxisLesson {
    /// `H(X^L)`, bits.
    pub fn h_long(&self) -> f64 {
        self.block_entropies[self.block - 1]
    }

    /// `H(X^(L-1))`, bits.
    pub fn h_short(&self) -> f64 {
        self.block_entropies[self.block - 2]
    }
}

/// The run of quantized samples along one ray, as the entropy rate counts them.
#[derive(Clone, Debug, PartialEq)]
pub struct RaySamples {
    /// The ray's indices on the lattice.
    pub ray: (i64, i64),
    /// Its samples' bins, first to last (`None`: missing, which breaks the blocks).
    pub bins: Vec<Option<u8>>,
    /// The first and last sample's positions, voxel index coordinates.
    pub ends: ([f64; 3], [f64; 3]),
}

/// The plane of rays a lesson's ray lies in: the lattice's rays `(i, j)` for every `i` of the
/// ray's row `j`, each a row of quantized samples, aligned by sample index, so that the ray is
/// one row of a picture of the volume's bins.
#[derive(Clone, Debug, PartialEq)]
pub struct RayPlane {
    /// The row of rays, `j`.
    pub j: i64,
    /// The rays' `i`, in order.
    pub rays: Vec<i64>,
    /// The sample index `k` of the first column.
    pub first_k: i64,
    /// Per ray, its bins by column: `None` outside the volume or missing.
    pub bins: Vec<Vec<Option<u8>>>,
    /// The index in `rays` of the lesson's ray.
    pub selected: Option<usize>,
}

/// The plane of rays holding the ray `offset` rays from the central one (see [`ray_samples`]),
/// on the paper's lattice along `axis`.
pub fn ray_plane(
    volume: &Volume,
    axis: [f64; 3],
    params: &ViewParams,
    offset: (i64, i64),
) -> Result<Option<RayPlane>> {
    let (lattice, (si, j)) = offset_ray(volume, axis, params, offset)?;
    let Some((i0, i1)) = lattice.row_span(j) else {
        return Ok(None);
    };
    let q = volume.quantizer(params.sampling.bins)?;
    let rays: Vec<(i64, i64, Vec<Option<u8>>)> =
        crate::volume::with_voxels!(volume.data(), |data| {
            let sampler = no_map(data, volume, q);
            (i0..=i1)
                .filter_map(|i| {
                    let k0 = lattice.ray(i, j)?.k0;
                    Some((i, k0, ray_bins(&sampler, &lattice, i, j)?))
                })
                .collect()
        });
    let Some(first_k) = rays.iter().map(|r| r.1).min() else {
        return Ok(None);
    };
    let last_k = rays
        .iter()
        .map(|(_, k0, b)| k0 + b.len() as i64)
        .max()
        .unwrap_or(first_k);
    let width = (last_k - first_k) as usize;
    let bins = rays
        .iter()
        .map(|(_, k0, b)| {
            let mut row = vec![None; width];
            let at = (k0 - first_k) as usize;
            row[at..at + b.len()].copy_from_slice(b);
            row
        })
        .collect();
    Ok(Some(RayPlane {
        j,
        selected: rays.iter().position(|r| r.0 == si),
        rays: rays.iter().map(|r| r.0).collect(),
        first_k,
        bins,
    }))
}

/// A sampler of `volume` without a cell map, for a ray or a plane of rays: the same bins as the
/// walks' (a map only saves work), without building a map of every voxel for a few hundred
/// samples.
fn no_map<'a, T: crate::volume::Voxel>(
    data: &'a [T],
    volume: &Volume,
    q: crate::volume::Quantizer,
) -> BinSampler<'a, T> {
    BinSampler::window(data, volume, q, 0..0)
}

/// The paper's lattice along `axis` (phase 0, every ray) with `params`' spacings.
fn paper_lattice(volume: &Volume, axis: [f64; 3], params: &ViewParams) -> Result<Lattice> {
    let sampling = params.sampling.resolved(volume.dims(), volume.spacing())?;
    Ok(Lattice::new(
        volume.dims(),
        volume.spacing(),
        canonical_axis(axis)?,
        sampling.ray_spacing.unwrap_or(1.0),
        sampling.sample_spacing.unwrap_or(1.0),
        [0.0; 3],
    )?)
}

/// The paper's lattice along `axis` and the ray `offset` rays from its central one.
fn offset_ray(
    volume: &Volume,
    axis: [f64; 3],
    params: &ViewParams,
    offset: (i64, i64),
) -> Result<(Lattice, (i64, i64))> {
    let lattice = paper_lattice(volume, axis, params)?;
    let (ci, cj) = lattice.central_ray();
    Ok((lattice, (ci + offset.0, cj + offset.1)))
}

fn canonical_axis(axis: [f64; 3]) -> Result<[f64; 3]> {
    normalize(axis)
        .map(canonical)
        .ok_or_else(|| Error::invalid("axis", "[0, 0, 0]", "a direction with a length"))
}

/// The lesson of `axis` on `volume` by the view search's `params`: the same lattice, walk and
/// counts that gave the axis its entropy rate, so `entropy_rate` is the view's to the bit.
pub fn axis_lesson(
    volume: &Volume,
    axis: [f64; 3],
    params: &ViewParams,
    monitor: &Monitor,
) -> Result<AxisLesson> {
    axis_lesson_within(volume, axis, params, None, monitor)
}

/// [`axis_lesson`], its blocks counted slab by slab within `room` bytes when given (as the view
/// search streamed within them counts them: the same numbers, bit for bit), else with the
/// whole cell map in memory.
pub fn axis_lesson_within(
    volume: &Volume,
    axis: [f64; 3],
    params: &ViewParams,
    room: Option<u64>,
    monitor: &Monitor,
) -> Result<AxisLesson> {
    let lattice = paper_lattice(volume, axis, params)?;
    let block = params.block;
    let bins = params.sampling.bins;
    let q = volume.quantizer(bins)?;
    let walk = |block: usize| -> Result<(BlockCounts, u64)> {
        if let Some(room) = room {
            return block_counts_streamed(volume, &lattice, params, block, room, monitor);
        }
        crate::volume::with_voxels!(volume.data(), |data| {
            block_counts(&BinSampler::over(data, volume, q), &lattice, block, monitor)
        })
    };
    // L = 4 has a middle length its counts do not give: the walk with blocks of 2 does.
    let middle = 2..block.saturating_sub(1);
    let walk_units = match room {
        Some(room) => streamed_slabs(volume, room),
        None => work_units(&lattice),
    };
    monitor.start("counting blocks", walk_units * (1 + middle.len() as u64));
    let (counts, rays) = walk(block)?;
    let (h1, h_short, h_long) = counts.entropies();
    let mut block_entropies = vec![h1];
    for k in middle {
        block_entropies.push(walk(k)?.0.entropies().2);
    }
    block_entropies.extend([h_short, h_long]);
    let table = |k: usize| BlockCount::table_of(&counts, k);
    let d = lattice.d;
    Ok(AxisLesson {
        axis: d,
        world: volume.transform().describe(d, volume.spacing()),
        block,
        bins,
        rays,
        samples: counts.symbols(),
        entropy_rate: (h_long - h_short).max(0.0),
        block_entropies,
        blocks: table(block),
        short_blocks: table(block - 1),
    })
}

/// `H` of a block table, bits: what the lesson's entropies are, recomputed from its counts.
pub fn table_entropy(table: &[BlockCount]) -> f64 {
    entropy(table.iter().map(|b| b.count).collect::<Vec<_>>())
}

/// The samples of the ray `offset` rays from the one through the volume's centre (along the
/// lattice's two in-plane directions) on the paper's lattice along `axis`; `None` when that
/// ray misses the volume.
pub fn ray_samples(
    volume: &Volume,
    axis: [f64; 3],
    params: &ViewParams,
    offset: (i64, i64),
) -> Result<Option<RaySamples>> {
    let (lattice, (i, j)) = offset_ray(volume, axis, params, offset)?;
    let q = volume.quantizer(params.sampling.bins)?;
    let bins = crate::volume::with_voxels!(volume.data(), |data| {
        ray_bins(&no_map(data, volume, q), &lattice, i, j)
    });
    Ok(bins.map(|bins| {
        let ray = lattice.ray(i, j).expect("ray_bins found the ray");
        RaySamples {
            ray: (i, j),
            bins,
            ends: (ray.at(ray.k0), ray.at(ray.k1)),
        }
    }))
}

#[cfg(test)]
mod tests {
    use super::{offset_ray, ray_samples};
    use crate::view::{BinSampler, ViewParams, ray_bins};
    use crate::volume::phantom;

    /// A lesson's ray, sampled without a cell map, has the bins the walks count with one: for
    /// integer and f32 voxels, on the grid and off it.
    #[test]
    fn a_lessons_ray_without_a_map_has_the_walks_bins() {
        let i16s = phantom::body([40, 36, 52], 2).unwrap();
        let f32s = phantom::shepp_logan([33, 30, 28]).unwrap();
        let params = ViewParams::default();
        for v in [&i16s, &f32s] {
            let q = v.quantizer(params.sampling.bins).unwrap();
            for axis in [[0.0, 0.0, 1.0], [0.3, -0.5, 0.81], [1.0, 1.0, 0.0]] {
                for offset in [(0, 0), (3, -2), (-5, 4)] {
                    let (lattice, (i, j)) = offset_ray(v, axis, &params, offset).unwrap();
                    let shown = ray_samples(v, axis, &params, offset).unwrap().unwrap();
                    let walked = crate::volume::with_voxels!(v.data(), |data| {
                        ray_bins(&BinSampler::over(data, v, q), &lattice, i, j)
                    });
                    let walked = walked.unwrap();
                    assert!(walked.iter().filter(|b| b.is_some()).count() > 10);
                    assert_eq!(shown.bins, walked, "{axis:?} {offset:?}");
                }
            }
        }
    }
}
