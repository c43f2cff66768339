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

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use slabscope::volume::io::write_volume;
use slabscope::volume::phantom;

/// One timed run: seconds from start to exit, and the peak anonymous memory in MiB.
fn run(bin: &Path, args: &[&str]) -> Result<(f64, f64), Box<dyn std::error::Error>> {
    let start = Instant::now();
    let mut child = Command::new(bin)
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()?;
    let status = format!("/proc/{}/status", child.id());
    let mut peak_kib = 0u64;
    loop {
        if let Some(exit) = child.try_wait()? {
            if !exit.success() {
                return Err(format!("{} {args:?} failed: {exit}", bin.display()).into());
            }
            break;
        }
        if let Ok(text) = std::fs::read_to_string(&status)
            && let Some(kib) = text
                .lines()
                .find(|l| l.starts_with("RssAnon:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok())
        {
            peak_kib = peak_kib.max(kib);
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    Ok((start.elapsed().as_secs_f64(), peak_kib as f64 / 1024.0))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Free bytes on the file system holding `dir`.
fn free_bytes(dir: &Path) -> Option<u64> {
    let out = Command::new("df")
        .args(["--output=avail", "-B1"])
        .arg(dir)
        .output()
        .ok()?;
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .nth(1)?
        .trim()
        .parse()
        .ok()
}

/// The phantom of `dims` as i16 NIfTI in `dir`, written unless it is there.
fn volume(dir: &Path, dims: [usize; 3]) -> Result<PathBuf, Box<dyn std::error::Error>> {
    let path = dir.join(format!("body_{}x{}x{}.nii", dims[0], dims[1], dims[2]));
    if path.exists() {
        return Ok(path);
    }
    let bytes = dims.iter().product::<usize>() as u64 * 2 + 352;
    if free_bytes(dir).is_some_and(|free| free < bytes + (1 << 30)) {
        return Err(format!("{}: not enough free disk for {bytes} bytes", dir.display()).into());
    }
    let t = Instant::now();
    let v = phantom::body(dims, 1)?;
    write_volume(&path, &v, false)?;
    println!(
        "wrote {} in {:.1} s",
        path.display(),
        t.elapsed().as_secs_f64()
    );
    Ok(path)
}

fn parse_dims(text: &str) -> Option<[usize; 3]> {
    let mut it = text.split('x').map(|n| n.parse().ok());
    let dims = [it.next()??, it.next()??, it.next()??];
    it.next().is_none().then_some(dims)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
    };
    let sizes = value("--sizes").map_or("256x256x415,512x512x512", String::as_str);
    let runs: usize = value("--runs").map_or(Ok(3), |r| r.parse())?;
    let dir = PathBuf::from(value("--dir").map_or("target/bench-volumes", String::as_str));
    let mut bins: Vec<PathBuf> = args
        .windows(2)
        .filter(|w| w[0] == "--bin")
        .map(|w| PathBuf::from(&w[1]))
        .collect();
    if bins.is_empty() {
        bins.push(PathBuf::from("target/release/slabscope"));
    }
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
