//! What a TUI user waits for on large volumes: the binary in a tmux window of 160×45 (half-block
//! pictures, as over SSH without image passthrough), its screen read every 20 ms, from start to
//! the first picture (the preview pane's title names the encoded image) and to full resolution
//! (the slab table shown and no preview label or gauge left). Then, in this process, how long the
//! view search and the histories of the 512³ volume take to stop once cancelled, as Esc, `PgDn` or `q`
//! ask.
//!
//! `cargo build --release && cargo bench --bench tui_bench -- [--sizes 256x256x256,512x512x512,1024x1024x1024]
//! [--files PATH,...] [--runs 3] [--dir DIR] [--bin PATH ...]`
//!
//! Needs tmux. The volumes are those of `big_bench` (body phantoms, i16 NIfTI in `DIR`, default
//! `target/bench-volumes`), written once, then each of `--files` (`--sizes ''` for only those:
//! an OME-Zarr store's own levels, say). Each `--bin` is run in turns with the others.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use common::{median, parse_dims, volume};
use slabscope::partition::StackParams;
use slabscope::{Histories, LoadOptions, Monitor, Scope, ViewParams};

/// Seconds to the first picture and to full resolution of one run of `bin` on `file`.
fn open(bin: &Path, file: &Path, id: usize) -> Result<(f64, f64), Box<dyn std::error::Error>> {
    let socket = format!("slabscope-bench-{}-{id}", std::process::id());
    let tmux = |args: &[&str]| {
        Command::new("tmux")
            .arg("-L")
            .arg(&socket)
            .args(args)
            .output()
    };
    let command = format!(
        "{} {} --protocol blocks; sleep 600",
        bin.display(),
        file.display()
    );
    let start = Instant::now();
    tmux(&[
        "new-session",
        "-d",
        "-s",
        "b",
        "-x",
        "160",
        "-y",
        "45",
        &command,
    ])?;
    let mut first = None;
    let result = loop {
        let screen =
            String::from_utf8_lossy(&tmux(&["capture-pane", "-p", "-t", "b"])?.stdout).into_owned();
        let t = start.elapsed().as_secs_f64();
        if first.is_none() && screen.contains(" KB]") {
            first = Some(t);
        }
        // The status line's last row shows a gauge (`views: view search 34%`) while any job
        // runs.
        let status = screen.lines().rfind(|l| !l.trim().is_empty()).unwrap_or("");
        let settled = !screen.contains("preview:") && !status.contains('%');
        if let Some(f) = first
            && settled
            && screen.contains("Slabs: ")
        {
            break Ok((f, t));
        }
        if t > 1200.0 {
            break Err(format!("{}: no full resolution after 20 minutes", file.display()).into());
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let _ = tmux(&["kill-server"]);
    result
}

/// Milliseconds from cancelling to the return of the view search and of the histories on
/// `file`, each cancelled `after` its start (the histories along z: slicing, the background
/// fill, then the histories).
fn cancel_latency(file: &Path, after: Duration) -> Result<(f64, f64), Box<dyn std::error::Error>> {
    let volume = slabscope::load(file, &LoadOptions::default())?.volume;
    let stop = |work: &(dyn Fn(&Monitor) -> bool + Sync)| {
        let cancel = AtomicBool::new(false);
        std::thread::scope(|s| {
            let job = s.spawn(|| work(&Monitor::new(Some(&cancel), None)));
            std::thread::sleep(after);
            let t = Instant::now();
            cancel.store(true, Ordering::Relaxed);
            let cancelled = job.join().expect("the job runs");
            (cancelled, t.elapsed().as_secs_f64() * 1e3)
        })
    };
    let (views_cancelled, views) = stop(&|m| {
        slabscope::search(&volume, &ViewParams::default(), m)
            .is_err_and(|e| matches!(e, slabscope::Error::Cancelled))
    });
    let (histories_cancelled, histories) = stop(&|m| {
        Histories::new(
            &volume,
            [0.0, 0.0, 1.0],
            &StackParams::default(),
            Scope::ALL,
            m,
        )
        .is_err_and(|e| matches!(e, slabscope::Error::Cancelled))
    });
    if !(views_cancelled && histories_cancelled) {
        return Err("a job finished before it was cancelled: cancel sooner".into());
    }
    Ok((views, histories))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = common::Args::from_env();
    let sizes = args.value("--sizes").unwrap_or("256x256x256,512x512x512");
    let runs = args.runs()?;
    let dir = args.dir();
    let bins = args.bins();
    if Command::new("tmux").arg("-V").output().is_err() {
        return Err("tui_bench needs tmux (apt-get install tmux)".into());
    }
    std::fs::create_dir_all(&dir)?;
    println!("{runs} runs each, medians; tmux 160x45, half-block pictures");
    let mut id = 0;
    let mut cancel_on = None;
    let mut files = Vec::new();
    for text in sizes.split(',').filter(|t| !t.is_empty()) {
        let dims = parse_dims(text).ok_or_else(|| format!("--sizes: {text:?} is not NXxNYxNZ"))?;
        let path = volume(&dir, dims)?;
        if dims == [512; 3] {
            cancel_on = Some(path.clone());
        }
        files.push((text.to_string(), path));
    }
    for path in args.value("--files").into_iter().flat_map(|f| f.split(',')) {
        let name = Path::new(path)
            .file_name()
            .map_or(path.into(), |n| n.to_string_lossy());
        files.push((name.into_owned(), PathBuf::from(path)));
    }
    for (text, path) in files {
        let mut first = vec![Vec::new(); bins.len()];
        let mut full = vec![Vec::new(); bins.len()];
        for _ in 0..runs {
            for (b, bin) in bins.iter().enumerate() {
                id += 1;
                let (f, t) = open(bin, &path, id)?;
                first[b].push(f);
                full[b].push(t);
            }
        }
        for (b, bin) in bins.iter().enumerate() {
            println!(
                "{text:<16} first picture {:>7.2} s   full resolution {:>7.2} s  ({})",
                median(first[b].clone()),
                median(full[b].clone()),
                bin.display()
            );
        }
    }
    if let Some(path) = cancel_on {
        for ms in [300, 1000, 2000, 4000] {
            let (views, histories) = cancel_latency(&path, Duration::from_millis(ms))?;
            println!(
                "512x512x512 cancelled {ms} ms in: the view search stops in {views:.0} ms, the \
                 histories in {histories:.0} ms"
            );
        }
    }
    Ok(())
}
