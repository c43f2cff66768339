//! Long thin volumes (#47): `slabscope analyze LINE --axis A --json` as a whole process on a line
//! of pseudo-random u8 one voxel across and N along each axis in turn (an NRRD), and the
//! default `analyze` (view search first) on the same lines: the time from start to exit and the
//! peak anonymous memory (`RssAnon`, sampled every 2 ms).
//!
//! `cargo build --release && cargo bench --bench long_thin -- [--length 200000] [--runs 3]
//! [--dir DIR] [--bin PATH ...]`
//!
//! The lines are written into `DIR` (default `target/bench-volumes`). Each `--bin` is timed in
//! turns with the others (old and new builds side by side); by default
//! `target/release/slabscope`.

mod common;

use std::path::{Path, PathBuf};

use common::{median, run};

/// A line of `dims` voxels of pseudo-random u8 as an NRRD in `dir`, written once.
fn line(dir: &Path, dims: [usize; 3]) -> std::io::Result<PathBuf> {
    let path = dir.join(format!("line_{}x{}x{}.nrrd", dims[0], dims[1], dims[2]));
    if path.exists() {
        return Ok(path);
    }
    let mut state = 7u64;
    let mut bytes = format!(
        "NRRD0004\ntype: uint8\ndimension: 3\nsizes: {} {} {}\nencoding: raw\n\n",
        dims[0], dims[1], dims[2]
    )
    .into_bytes();
    bytes.extend((0..dims.iter().product::<usize>()).map(|_| {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 56) as u8
    }));
    std::fs::write(&path, bytes)?;
    Ok(path)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = common::Args::from_env();
    let n: usize = args.value("--length").map_or(Ok(200_000), str::parse)?;
    let runs = args.runs()?;
    let dir = args.dir();
    let bins = args.bins();
    std::fs::create_dir_all(&dir)?;
    println!(
        "threads: {}; {runs} runs each, medians",
        rayon::current_num_threads()
    );
    let lines = [([1, 1, n], "z"), ([n, 1, 1], "x"), ([1, n, 1], "y")];
    for (dims, axis) in lines {
        let file = line(&dir, dims)?.to_string_lossy().into_owned();
        let along: [&str; 5] = ["analyze", &file, "--axis", axis, "--json"];
        let search: [&str; 3] = ["analyze", &file, "--json"];
        for (name, argv) in [
            (format!("--axis {axis}"), &along[..]),
            ("search".into(), &search),
        ] {
            let mut times = vec![Vec::new(); bins.len()];
            let mut peaks = vec![Vec::new(); bins.len()];
            for _ in 0..runs {
                for (b, bin) in bins.iter().enumerate() {
                    let (t, m) = run(bin, argv)?;
                    times[b].push(t);
                    peaks[b].push(m);
                }
            }
            let size = format!("{}x{}x{}", dims[0], dims[1], dims[2]);
            for (b, bin) in bins.iter().enumerate() {
                println!(
                    "{size:<14} {name:<10} {:>7.2} s {:>7.0} MiB anonymous  ({})",
                    median(times[b].clone()),
                    median(peaks[b].clone()),
                    bin.display()
                );
            }
        }
    }
    Ok(())
}
