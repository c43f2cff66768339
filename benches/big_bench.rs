//! What a user waits for, and the memory it takes, on large volumes: `slabscope info` and
//! `analyze` (the defaults, and the paper's view search) as whole processes on body phantoms
//! stored as uncompressed i16 NIfTI, the time from start to exit and the peak anonymous memory
//! (`RssAnon` of `/proc/PID/status`, sampled every 2 ms: mapped file pages the kernel can drop
//! are not in it).
//!
//! `cargo build --release && cargo bench --bench big_bench -- [--sizes 256x256x415,512x512x512,1024x1024x1024]
//! [--runs 3] [--dir DIR] [--bin PATH ...]`
//!
//! The volumes are written once into `DIR` (default `target/bench-volumes`) after checking the
//! free disk space, and kept for later runs. Each `--bin` is timed in turns with the others (old
//! and new builds side by side); by default `target/release/slabscope`.

mod common;

use common::{median, parse_dims, run, volume};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = common::Args::from_env();
    let sizes = args.value("--sizes").unwrap_or("256x256x415,512x512x512");
    let runs = args.runs()?;
    let dir = args.dir();
    let bins = args.bins();
    std::fs::create_dir_all(&dir)?;
    let commands: [(&str, &[&str]); 3] = [
        ("info", &["info"]),
        ("analyze", &["analyze"]),
        (
            "analyze, paper's view search",
            &[
                "analyze",
                "--phases",
                "0",
                "--background",
                "none",
                "--slabs",
                "1",
            ],
        ),
    ];
    println!(
        "threads: {}; {runs} runs each, medians",
        rayon::current_num_threads()
    );
    for text in sizes.split(',') {
        let dims = parse_dims(text).ok_or_else(|| format!("--sizes: {text:?} is not NXxNYxNZ"))?;
        let path = volume(&dir, dims)?;
        let file = path.to_string_lossy().into_owned();
        for (name, command) in commands {
            let mut argv: Vec<&str> = command.to_vec();
            argv.push(&file);
            let mut times = vec![Vec::new(); bins.len()];
            let mut peaks = vec![Vec::new(); bins.len()];
            for _ in 0..runs {
                for (b, bin) in bins.iter().enumerate() {
                    let (t, m) = run(bin, &argv)?;
                    times[b].push(t);
                    peaks[b].push(m);
                }
            }
            for (b, bin) in bins.iter().enumerate() {
                println!(
                    "{text:<16} {name:<30} {:>8.2} s {:>8.0} MiB anonymous  ({})",
                    median(times[b].clone()),
                    median(peaks[b].clone()),
                    bin.display()
                );
            }
        }
    }
    Ok(())
}
