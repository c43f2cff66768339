//! Times the view search (42 viewpoints, 32 bins, L = 3) on `body` phantoms of the paper's
//! Table 1 sizes, beside the paper's figures: on the paper's single lattice, and at the defaults
//! (ranked by the mean over 8 lattice phases).
//!
//! `cargo bench --bench view_bench [-- --quick]`

use std::time::Instant;

use slabscope::progress::Monitor;
use slabscope::view::{ViewParams, search};
use slabscope::volume::phantom;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let quick = std::env::args().any(|a| a == "--quick");
    let sizes: &[([usize; 3], f64)] = if quick {
        &[([256, 256, 415], 111.0)]
    } else {
        &[
            ([256, 256, 415], 111.0),
            ([512, 512, 45], 55.5),
            ([587, 342, 499], 722.6),
        ]
    };
    println!("threads: {}", rayon::current_num_threads());
    println!(
        "{:<14} {:<14} {:>10} {:>10} {:>9}  best axis",
        "volume", "ranking", "paper (s)", "ours (s)", "speed-up"
    );
    for &(dims, paper) in sizes {
        let volume = phantom::body(dims, 1)?;
        for (name, params) in [
            ("paper lattice", ViewParams::paper()),
            ("8 phases", ViewParams::default()),
        ] {
            let t = Instant::now();
            let result = search(&volume, &params, &Monitor::none())?;
            let secs = t.elapsed().as_secs_f64();
            let best = result.best();
            println!(
                "{:<14} {name:<14} {paper:>10.1} {secs:>10.3} {:>8.0}x  [{:.3}, {:.3}, {:.3}] h = {:.4}",
                format!("{}x{}x{}", dims[0], dims[1], dims[2]),
                paper / secs,
                best.axis[0],
                best.axis[1],
                best.axis[2],
                best.entropy_rate
            );
        }
    }
    Ok(())
}
