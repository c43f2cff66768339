//! The view search's walks side by side, and the floor they are held to: for each volume (body
//! phantoms held as f32), the 21 axes of the paper's 42 viewpoints on the paper's lattice, walked
//! by the tile walk and by the bricked walk (bricks of each size asked for; `sN` for about N³ cells shaped for the
//! axis), in turns, and 21
//! passes over the cell map in memory order counting 3-blocks of its rows as the walks count
//! them (no interpolation, no mixed cells): the cost of reading the map 21 times. With `--slabs`,
//! the same lattices counted a slab of planes at a time as a cluster's tasks and the search beyond
//! the budget count them (`ViewRounds::count_slab`, each slab of the given thickness in cell
//! planes walked apart, its parts added). Prints the median seconds of each and its nanoseconds
//! per voxel.
//!
//! `cargo bench --bench walk_bench -- [--sizes 256x256x415,512x512x512] [--bricks 64,s64 or "" for none]
//! [--slabs 64,511] [--runs 3] [--no-tiles]`

use std::time::Instant;

use rayon::prelude::*;
use slabscope::geometry::lattice::Lattice;
use slabscope::measure::BlockCounts;
use slabscope::progress::Monitor;
use slabscope::view::{
    BinSampler, Vector, ViewParams, ViewRound, ViewRounds, Walk, block_counts_by, icosphere,
};
use slabscope::volume::Volume;
use slabscope::volume::phantom;

mod common;
use common::{arg, median, parse_dims};

/// 21 passes over `cells` in memory order, rows of `nx` cells, counting 3-blocks into a table
/// per thread; the blocks counted, so that the work is not optimized away.
fn floor(cells: &[u8], nx: usize) -> u64 {
    (0..21)
        .map(|_| {
            cells
                .par_chunks(nx * 64)
                .fold(
                    || BlockCounts::new(32, 3),
                    |mut counts, rows| {
                        for row in rows.chunks(nx) {
                            for &c in row {
                                counts.push(c & 31);
                            }
                            counts.end_sequence();
                        }
                        counts
                    },
                )
                .map(|counts| counts.blocks())
                .sum::<u64>()
        })
        .sum()
}

/// The paper's lattices of the 21 axes counted in slabs of `thick` cell planes, each walked
/// apart and the parts added; the blocks counted.
fn slabs(volume: &Volume, thick: usize) -> Result<u64, Box<dyn std::error::Error>> {
    let rounds = ViewRounds::new(volume, &ViewParams::paper())?;
    let cells = volume.dims()[2].saturating_sub(1).max(1);
    let mut sum = rounds.zero(volume, &ViewRound::Paper)?;
    for z in (0..cells).step_by(thick.max(1)) {
        let part = rounds.count_slab(volume, &ViewRound::Paper, z..(z + thick).min(cells))?;
        for (s, p) in sum.iter_mut().zip(part) {
            s.add(p);
        }
    }
    Ok(sum.iter().map(|s| s.counts.blocks()).sum())
}

/// The brick sizes `--bricks` asks for, each `(size, shaped)`: a size `sN` is bricks of about
/// N³ cells shaped for each axis.
fn bricks_arg() -> Result<Vec<(usize, bool)>, std::num::ParseIntError> {
    arg("--bricks")
        .unwrap_or_else(|| "64,s64".into())
        .split(',')
        .filter(|b| !b.is_empty())
        .map(|b| {
            Ok::<_, std::num::ParseIntError>((
                b.trim_start_matches('s').parse()?,
                b.starts_with('s'),
            ))
        })
        .collect()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let sizes = arg("--sizes").unwrap_or_else(|| "256x256x415,512x512x512".into());
    let bricks = bricks_arg()?;
    let thick: Vec<usize> = arg("--slabs")
        .unwrap_or_default()
        .split(',')
        .filter(|t| !t.is_empty())
        .map(str::parse)
        .collect::<Result<_, _>>()?;
    let runs: usize = arg("--runs").map_or(Ok(3), |r| r.parse())?;
    let axes = icosphere::axes(1);
    println!(
        "threads: {}, {} axes, {runs} runs in turns, medians",
        rayon::current_num_threads(),
        axes.len()
    );
    println!(
        "{:<14} {:<12} {:>9} {:>12}",
        "volume", "walk", "s", "ns/voxel"
    );
    for text in sizes.split(',') {
        let dims = parse_dims(text).ok_or_else(|| format!("--sizes: {text:?} is not NXxNYxNZ"))?;
        let volume = phantom::body(dims, 1)?;
        let sampler = BinSampler::new(&volume, volume.quantizer(32)?);
        let mut walks = Vec::new();
        if !std::env::args().any(|a| a == "--no-tiles") {
            walks.push((
                "tiles".to_string(),
                Walk::Tiles {
                    vector: Vector::Widest,
                },
            ));
        }
        for &(size, shaped) in &bricks {
            let name = format!("bricks {}{size}", if shaped { "s" } else { "" });
            walks.push((name, Walk::Bricks { size, shaped }));
        }
        let lattices: Vec<Lattice> = axes
            .iter()
            .map(|&a| Lattice::at_voxel_spacing(dims, volume.spacing(), a))
            .collect::<Result<_, _>>()?;
        let mut times = vec![Vec::new(); walks.len() + thick.len() + 1];
        let mut check = vec![0u64; walks.len() + thick.len()];
        for _ in 0..runs {
            for (k, (_, walk)) in walks.iter().enumerate() {
                let t = Instant::now();
                let mut blocks = 0;
                for lattice in &lattices {
                    let (counts, _) =
                        block_counts_by(&sampler, lattice, 3, *walk, &Monitor::none())?;
                    blocks += counts.blocks();
                }
                times[k].push(t.elapsed().as_secs_f64());
                check[k] = blocks;
            }
            for (k, &t) in thick.iter().enumerate() {
                let k = walks.len() + k;
                let start = Instant::now();
                check[k] = slabs(&volume, t)?;
                times[k].push(start.elapsed().as_secs_f64());
            }
            let t = Instant::now();
            std::hint::black_box(floor(sampler.cells(), dims[0]));
            times[walks.len() + thick.len()].push(t.elapsed().as_secs_f64());
        }
        assert!(
            check.iter().all(|&c| c == check[0]),
            "every walk counts the same blocks"
        );
        let voxels = volume.len() as f64;
        let slab_names: Vec<String> = thick.iter().map(|t| format!("slabs {t}")).collect();
        let names = (walks.iter().map(|(n, _)| n.as_str()))
            .chain(slab_names.iter().map(String::as_str))
            .chain(["floor"]);
        for (name, t) in names.zip(times) {
            let s = median(t);
            println!("{text:<14} {name:<12} {s:>9.3} {:>12.2}", s * 1e9 / voxels);
        }
    }
    Ok(())
}
