//! Reproduces the paper's Table 1 on `body` phantoms of its sizes: the best view, top-down P(K)
//! and bottom-up G(K), in seconds beside the paper's (a 2008 quad-core), and the peak memory.
//!
//! `cargo bench --bench table1 [-- --quick]` (`--quick`: the first volume only)

use std::time::Instant;

use slabscope::partition::{MergeHistory, SliceStack, SplitHistory, StackParams};
use slabscope::progress::Monitor;
use slabscope::view::{ViewParams, search};
use slabscope::volume::background::BackgroundRule;
use slabscope::volume::phantom;

/// The paper's rows: name, size, and seconds for best view, P(2), P(4), P(8), G(8), G(4), G(2).
const PAPER: [(&str, [usize; 3], [f64; 7]); 3] = [
    (
        "Human body",
        [256, 256, 415],
        [111.0, 0.4, 0.9, 2.0, 28.9, 36.2, 70.5],
    ),
    (
        "Hemorrhage",
        [512, 512, 45],
        [55.5, 0.2, 0.6, 1.2, 6.3, 10.8, 14.4],
    ),
    (
        "Histological",
        [587, 342, 499],
        [722.6, 2.3, 5.8, 12.6, 214.0, 324.7, 525.0],
    ),
];

fn time<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let t = Instant::now();
    let out = f();
    (out, t.elapsed().as_secs_f64())
}

/// Peak resident memory of this process, from /proc (Linux), in bytes.
fn peak_memory() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    Some(line.split_whitespace().nth(1)?.parse::<u64>().ok()? * 1024)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let quick = std::env::args().any(|a| a == "--quick");
    let rows = if quick { &PAPER[..1] } else { &PAPER[..] };
    println!(
        "threads: {}; times in seconds, ours / paper's",
        rayon::current_num_threads()
    );
    println!(
        "{:<13} {:<12} {:>15} {:>7} {:>13} {:>13} {:>13} {:>15} {:>15} {:>15} {:>8}",
        "volume",
        "size",
        "best view",
        "slice",
        "P(2)",
        "P(4)",
        "P(8)",
        "G(8)",
        "G(4)",
        "G(2)",
        "G(all)"
    );
    for &(name, dims, paper) in rows {
        // Restart the peak-memory mark (Linux: "5" resets VmHWM) so each row reports its own.
        let _ = std::fs::write("/proc/self/clear_refs", "5");
        let volume = phantom::body(dims, 1)?;
        let none = Monitor::none();
        // The paper's method: one lattice per axis, every voxel counted.
        let paper_stack = StackParams {
            background: BackgroundRule::None,
            ..StackParams::default()
        };
        let (views, t_view) = time(|| search(&volume, &ViewParams::paper(), &none));
        let axis = views?.best().axis;
        let (stack, t_slice) = time(|| SliceStack::new(&volume, axis, &paper_stack, &none));
        let stack = stack?;
        let n = stack.slices();
        let (h, t_hist) = time(|| stack.slice_histograms());
        let p = [2usize, 4, 8].map(|k| time(|| SplitHistory::with_limit(&h, 32, k - 1)).1 + t_hist);
        let g = [8usize, 4, 2].map(|k| time(|| MergeHistory::with_limit(&stack, &none, n - k)).1);
        let (_, g_all) = time(|| MergeHistory::new(&stack, &none));
        let cell = |ours: f64, theirs: f64| format!("{ours:.3}/{theirs}");
        println!(
            "{name:<13} {:<12} {:>15} {:>7.3} {:>13} {:>13} {:>13} {:>15} {:>15} {:>15} {:>8.3}",
            format!("{}x{}x{}", dims[0], dims[1], dims[2]),
            cell(t_view, paper[0]),
            t_slice,
            cell(p[0], paper[1]),
            cell(p[1], paper[2]),
            cell(p[2], paper[3]),
            cell(g[0], paper[4]),
            cell(g[1], paper[5]),
            cell(g[2], paper[6]),
            g_all
        );
        if let Some(peak) = peak_memory() {
            println!(
                "{:<13} peak memory {:.0} MiB = {:.2}x the volume's f32 size ({} slices along [{:.3}, {:.3}, {:.3}])",
                "",
                peak as f64 / (1 << 20) as f64,
                peak as f64 / volume.memory_bytes() as f64,
                n,
                axis[0],
                axis[1],
                axis[2]
            );
        }
    }
    Ok(())
}
