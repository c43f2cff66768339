//! Times triage of 100 volumes of 128³ (the benchmark): body phantoms with different
//! seeds written as NRRD to a temporary folder, then walked, loaded and analysed one after the
//! other as `slabscope triage` does (view search and a 4-slab partition each).
//!
//! `cargo bench --bench triage_bench` (as `slabscope triage` does: two volumes at a
//! time; also one at a time, and the full search)

use std::time::{Duration, Instant};

use slabscope::AnalysisParams;
use slabscope::formats::{NrrdEncoding, write_nrrd};
use slabscope::triage::{TriagePlan, discover, look_all};
use slabscope::volume::phantom;
use slabscope::{Error, LoadOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let count = 100;
    let dir = tempfile::tempdir()?;
    let t = Instant::now();
    for i in 0..count {
        let v = phantom::body([128, 128, 128], i as u64 + 1)?;
        write_nrrd(
            &dir.path().join(format!("v{i:03}.nrrd")),
            &v,
            NrrdEncoding::Raw,
            false,
        )?;
    }
    println!(
        "wrote {count} volumes of 128³ in {:.1} s",
        t.elapsed().as_secs_f64()
    );
    let volumes = discover(&[dir.path().to_path_buf()], &LoadOptions::default())?;
    let describe = |_: &std::path::Path, e: Error| e.to_string();
    for (fast, workers) in [(true, 2), (true, 1), (false, 2)] {
        let how = TriagePlan {
            load: LoadOptions::default(),
            params: AnalysisParams::default(),
            timeout: Duration::from_secs(60),
            fast,
            tile: None,
        };
        let t = Instant::now();
        let mut failed = 0;
        look_all(&volumes, &how, workers, None, &describe, |_, looked| {
            failed += usize::from(looked.row.error.is_some());
            true
        });
        let took = t.elapsed().as_secs_f64();
        println!(
            "triage of {} volumes ({}, {workers} at a time): {took:.1} s ({:.0} ms a volume), \
             {failed} failed, {} threads",
            volumes.len(),
            if fast { "fast path" } else { "--full" },
            took * 1e3 / volumes.len() as f64,
            rayon::current_num_threads()
        );
    }
    Ok(())
}
