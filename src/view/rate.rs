//! The entropy rate of one axis (paper §4): parallel rays on the lattice, trilinear samples,
//! quantized, with L-block and (L-1)-block counts pooled over all rays.

use rayon::prelude::*;
use serde::Serialize;

use crate::error::Result;
use crate::measure::{BlockCounts, Run};
use crate::progress::Monitor;
use crate::volume::sampling::{BinSampler, Lattice, Ray, to_fixed};

/// Spread of an axis's entropy rate over shifted lattices (`--phases`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PhaseSpread {
    /// Mean over the paper's lattice and the shifted ones.
    pub mean: f64,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
    /// Standard deviation.
    pub std: f64,
}

impl PhaseSpread {
    /// The statistics of `values` (not empty).
    pub fn of(values: &[f64]) -> Self {
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
        Self {
            mean,
            min: values.iter().copied().fold(f64::INFINITY, f64::min),
            max: values.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            std: var.sqrt(),
        }
    }

    /// `max - min`.
    pub fn range(&self) -> f64 {
        self.max - self.min
    }
}

/// The entropy rate of one axis, with the block entropies behind it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AxisEntropy {
    /// Canonical unit direction in physical space.
    pub axis: [f64; 3],
    /// Angle of the axis's projection on the x-y plane from +x, degrees.
    pub azimuth: f64,
    /// Angle of the axis above the x-y plane, degrees.
    pub elevation: f64,
    /// `h = H(X^L) - H(X^(L-1))`, bits per sample (paper eq. 4): lower is more structured.
    pub entropy_rate: f64,
    /// `H(X^1)`, bits.
    pub h1: f64,
    /// `H(X^(L-1))`, bits.
    pub h_short: f64,
    /// `H(X^L)`, bits.
    pub h_long: f64,
    /// The paper's other estimate, `H(X^L) / L` (eq. 3).
    pub per_symbol: f64,
    /// Rays that met the volume.
    pub rays: u64,
    /// Samples counted (missing ones left out).
    pub samples: u64,
    /// The spread over shifted lattices, when asked for.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub phases: Option<PhaseSpread>,
}

impl AxisEntropy {
    fn new(axis: [f64; 3], counts: &BlockCounts, rays: u64) -> Self {
        let (h1, h_short, h_long) = counts.entropies();
        Self {
            axis,
            // `+ 0.0` turns -0 into 0 for display.
            azimuth: axis[1].atan2(axis[0]).to_degrees() + 0.0,
            elevation: axis[2].clamp(-1.0, 1.0).asin().to_degrees() + 0.0,
            entropy_rate: (h_long - h_short).max(0.0),
            h1,
            h_short,
            h_long,
            per_symbol: h_long / counts.block() as f64,
            rays,
            samples: counts.symbols(),
            phases: None,
        }
    }
}

/// Rays are walked in square tiles of this many rays a side, all rays of a tile advancing
/// together sample by sample, so that the voxels in use stay a small neighbourhood in memory.
const TILE: i64 = 16;

/// Whether every sample of `ray` falls exactly on a voxel centre, so no interpolation is needed.
fn on_grid(ray: &Ray) -> bool {
    let whole = |x: f64| (x - x.round()).abs() < 1e-9;
    ray.origin.iter().chain(&ray.step).all(|&c| whole(c))
}

/// A ray of a tile being walked: where it is and its block state.
struct Walker {
    k0: i64,
    k1: i64,
    run: Run,
    path: Path,
}

/// How a walker finds its next sample.
enum Path {
    /// On the voxel grid: the linear index of the current sample and the step between samples.
    Grid(i64, i64),
    /// Anywhere else: the current position and the step, in fixed point.
    Fixed([i64; 3], [i64; 3]),
}

/// Feeds the quantized samples of the rays `(i, j)` of one tile into `counts`, advancing all rays
/// together; a missing sample breaks its ray's sequence. Returns the number of rays.
fn walk_tile(
    lattice: &Lattice,
    (is, js): ((i64, i64), (i64, i64)),
    sampler: &BinSampler,
    counts: &mut BlockCounts,
    walkers: &mut Vec<Walker>,
) -> u64 {
    walkers.clear();
    for j in js.0..=js.1 {
        for i in is.0..=is.1 {
            if let Some(ray) = lattice.ray(i, j) {
                let path = if on_grid(&ray) {
                    let it = sampler.interpolator();
                    let start = it.linear(ray.at(ray.k0).map(|c| c.round() as i64));
                    Path::Grid(start, it.linear(ray.step.map(|c| c.round() as i64)))
                } else {
                    Path::Fixed(to_fixed(ray.at(ray.k0)), to_fixed(ray.step))
                };
                walkers.push(Walker {
                    k0: ray.k0,
                    k1: ray.k1,
                    run: Run::default(),
                    path,
                });
            }
        }
    }
    let k0 = walkers.iter().map(|w| w.k0).min().unwrap_or(0);
    let k1 = walkers.iter().map(|w| w.k1).max().unwrap_or(-1);
    for k in k0..=k1 {
        for w in walkers.iter_mut() {
            if k < w.k0 || k > w.k1 {
                continue;
            }
            let bin = match &mut w.path {
                Path::Grid(index, step) => {
                    let b = sampler.bin_at_linear(*index as usize);
                    *index += *step;
                    b
                }
                Path::Fixed(p, step) => {
                    let b = sampler.bin_fixed(*p);
                    for m in 0..3 {
                        p[m] += step[m];
                    }
                    b
                }
            };
            match bin {
                Some(b) => counts.push_to(&mut w.run, b),
                None => w.run = Run::default(),
            }
        }
    }
    walkers.len() as u64
}

/// The inclusive ranges of the tile rows of `lattice`'s rays.
fn tile_rows(lattice: &Lattice) -> impl Iterator<Item = (i64, i64)> {
    let (_, (j0, j1)) = lattice.ray_ranges();
    (j0..=j1)
        .step_by(TILE as usize)
        .map(move |j| (j, (j + TILE - 1).min(j1)))
}

/// Number of progress units [`entropy_rate`] reports for `lattice`: its rows of tiles.
pub fn work_units(lattice: &Lattice) -> u64 {
    tile_rows(lattice).count() as u64
}

/// The entropy rate along `lattice`'s axis with blocks of length `block`, reporting one unit per
/// row of tiles to `monitor` (so it can be cancelled within a row's time).
pub fn entropy_rate(
    sampler: &BinSampler,
    lattice: &Lattice,
    block: usize,
    monitor: &Monitor,
) -> Result<AxisEntropy> {
    let ((i0, i1), _) = lattice.ray_ranges();
    let rows: Vec<(i64, i64)> = tile_rows(lattice).collect();
    let empty = || (BlockCounts::new(sampler.bins(), block), 0u64, Vec::new());
    let (counts, rays, _) = rows
        .into_par_iter()
        .try_fold(empty, |(mut counts, mut rays, mut walkers), js| {
            for i in (i0..=i1).step_by(TILE as usize) {
                let is = (i, (i + TILE - 1).min(i1));
                rays += walk_tile(lattice, (is, js), sampler, &mut counts, &mut walkers);
            }
            monitor.advance(1)?;
            Ok((counts, rays, walkers))
        })
        .try_reduce(empty, |(mut a, ra, w), (b, rb, _)| {
            a.merge(&b);
            Ok((a, ra + rb, w))
        })?;
    Ok(AxisEntropy::new(lattice.d, &counts, rays))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::block_entropies;
    use crate::volume::Volume;
    use crate::volume::VoxelType;

    fn random_volume(dims: [usize; 3], levels: u32, seed: u64) -> Volume {
        let mut state = seed;
        let data = (0..dims.iter().product::<usize>())
            .map(|_| {
                state = state
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                ((state >> 33) % u64::from(levels)) as f32
            })
            .collect();
        Volume::new(dims, [1.0; 3], VoxelType::U8, data).unwrap()
    }

    #[test]
    fn axis_aligned_rate_equals_a_brute_force_count_over_columns() {
        let v = random_volume([7, 6, 9], 5, 3);
        let q = v.quantizer(4).unwrap();
        let bins: Vec<u8> = v.voxels().iter().map(|&x| q.bin(x).unwrap()).collect();
        let [nx, ny, nz] = v.dims();
        let idx = |x: usize, y: usize, z: usize| x + nx * (y + ny * z);
        let columns = |axis: usize| -> Vec<Vec<u8>> {
            match axis {
                0 => (0..ny * nz)
                    .map(|r| (0..nx).map(|x| bins[idx(x, r % ny, r / ny)]).collect())
                    .collect(),
                1 => (0..nx * nz)
                    .map(|r| (0..ny).map(|y| bins[idx(r % nx, y, r / nx)]).collect())
                    .collect(),
                _ => (0..nx * ny)
                    .map(|r| (0..nz).map(|z| bins[idx(r % nx, r / nx, z)]).collect())
                    .collect(),
            }
        };
        for (axis, d) in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
            .into_iter()
            .enumerate()
        {
            for block in 2..=4 {
                let lattice = Lattice::for_volume(&v, d).unwrap();
                let sampler = BinSampler::new(&v, q);
                let got = entropy_rate(&sampler, &lattice, block, &Monitor::none()).unwrap();
                let cols = columns(axis);
                let (h1, hs, hl) = block_entropies(cols.iter().map(Vec::as_slice), 4, block);
                assert!(
                    (got.entropy_rate - (hl - hs)).abs() < 1e-12,
                    "axis {axis} L {block}"
                );
                assert!((got.h1 - h1).abs() < 1e-12);
                assert_eq!(got.samples, v.len() as u64);
                assert_eq!(got.rays, cols.len() as u64);
            }
        }
    }

    #[test]
    fn missing_voxels_break_sequences() {
        let mut data = vec![1.0f32; 27];
        data[13] = f32::NAN; // the centre
        data[0] = 0.0;
        let v = Volume::new([3, 3, 3], [1.0; 3], VoxelType::F32, data).unwrap();
        let q = v.quantizer(2).unwrap();
        let lattice = Lattice::for_volume(&v, [0.0, 0.0, 1.0]).unwrap();
        let r = entropy_rate(&BinSampler::new(&v, q), &lattice, 2, &Monitor::none()).unwrap();
        assert_eq!(r.samples, 26);
    }
}
