//! Times the analysis of a long axis: a line volume of 200,000 voxels (piecewise constant with
//! noise), the default `analyze` (view search, then top-down to 4 slabs along the best axis), and
//! every history along it as the TUI computes them.
//!
//! `cargo run --release --example long_axis [-- SLICES]`

use std::time::Instant;

use slabscope::partition::StackParams;
use slabscope::{AnalysisParams, Histories, Monitor, Scope, Volume, VoxelType, analyze};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n: usize = std::env::args().nth(1).map_or(Ok(200_000), |a| a.parse())?;
    let mut state = 7u64;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        state >> 33
    };
    let mut level = 0.0;
    let data: Vec<f32> = (0..n)
        .map(|i| {
            if i % 5000 == 0 {
                level = (next() % 250) as f32;
            }
            level + (next() % 7) as f32
        })
        .collect();
    let volume = Volume::new([n, 1, 1], [1.0; 3], VoxelType::U8, data)?;
    let t = Instant::now();
    let a = analyze(&volume, &AnalysisParams::default(), &Monitor::none())?;
    println!(
        "{n}x1x1: default analyze {:.2} s (best axis {:?}, {} slabs of {} slices)",
        t.elapsed().as_secs_f64(),
        a.axis(),
        a.partition.slabs.len(),
        a.partition.slices
    );
    let t = Instant::now();
    let h = Histories::new(
        &volume,
        [1.0, 0.0, 0.0],
        &StackParams::default(),
        Scope::ALL,
        &Monitor::none(),
    )?;
    println!(
        "{n}x1x1: every history along x (the TUI's) {:.2} s; notes: {:?}",
        t.elapsed().as_secs_f64(),
        h.notes()
    );
    Ok(())
}
