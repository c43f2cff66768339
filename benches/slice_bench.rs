//! Cutting a volume into its slice stack along oblique axes (the partition's first pass, which
//! resamples every voxel on the axis's lattice): the median seconds of each cut and a checksum
//! of the stack (its slice histograms and slab means), so that builds can be compared for speed
//! and sameness.
//!
//! `cargo bench --bench slice_bench -- [--file PATH | --size 256x256x415] [--runs 3] [--background none]`

use std::time::Instant;

use slabscope::formats::{LoadOptions, load};
use slabscope::partition::{SliceStack, StackParams};
use slabscope::progress::Monitor;
use slabscope::volume::background::BackgroundRule;
use slabscope::volume::{Volume, phantom};

mod common;
use common::arg;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let volume: Volume = if let Some(path) = arg("--file") {
        load(std::path::Path::new(&path), &LoadOptions::default())?.volume
    } else {
        let size = arg("--size").unwrap_or_else(|| "256x256x415".into());
        let d: Vec<usize> = size.split('x').map(str::parse).collect::<Result<_, _>>()?;
        phantom::body([d[0], d[1], d[2]], 1)?
    };
    let runs: usize = arg("--runs").map_or(Ok(3), |r| r.parse())?;
    let mut params = StackParams::default();
    if arg("--background").as_deref() == Some("none") {
        params.background = BackgroundRule::None;
    }
    let (a, b) = (0.525_731_112_119_133_6, 0.850_650_808_352_039_9);
    for axis in [[a, 0.0, b], [0.577, 0.577, 0.577]] {
        let mut times = Vec::new();
        let mut check = (0u64, 0.0f64);
        for _ in 0..runs {
            let t = Instant::now();
            let stack = SliceStack::new(&volume, axis, &params, &Monitor::none())?;
            times.push(t.elapsed().as_secs_f64());
            let h = stack.slice_histograms();
            let weighted: u64 = h
                .iter()
                .enumerate()
                .map(|(i, &c)| (i as u64 % 97 + 1) * c)
                .sum();
            let mean = stack.mean(0, stack.slices()).unwrap_or(f64::NAN);
            check = (weighted, mean);
        }
        times.sort_by(f64::total_cmp);
        println!(
            "axis [{:.3}, {:.3}, {:.3}]: median {:.3} s of {runs}; histograms {} mean {:.12}",
            axis[0],
            axis[1],
            axis[2],
            times[runs / 2],
            check.0,
            check.1
        );
    }
    Ok(())
}
