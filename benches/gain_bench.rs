//! Times the ranking of every axis by partition gain (`--gain`) beside the default view search on
//! the same volume: the body phantom of the paper's Table 1 (256×256×415) and ch2-sized volumes
//! (181×217×181: the Shepp-Logan head and layers normal to the cube diagonal), each the median of
//! `--runs` runs. The gain ranking includes its refinement between the sphere's axes.
//!
//! `cargo bench --bench gain_bench [-- --runs 3]`

use std::time::Instant;

use slabscope::analysis::{AnalysisParams, rank_by_gain};
use slabscope::progress::Monitor;
use slabscope::view::{axis_angle, search};
use slabscope::volume::{Volume, phantom};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let runs: usize = args
        .iter()
        .position(|a| a == "--runs")
        .and_then(|i| args.get(i + 1))
        .map_or(Ok(3), |r| r.parse())?;
    let ch2 = [181, 217, 181];
    let volumes: Vec<(&str, Volume)> = vec![
        ("body 256x256x415", phantom::body([256, 256, 415], 1)?),
        ("head 181x217x181", phantom::shepp_logan(ch2)?),
        (
            "layers 181x217x181",
            phantom::layers(ch2, [1.0, 1.0, 1.0], 1)?,
        ),
    ];
    println!(
        "threads: {}; {runs} runs each, medians",
        rayon::current_num_threads()
    );
    println!(
        "{:<20} {:>14} {:>14} {:>6}  best by gain, its angle to the entropy rate's best",
        "volume", "views (s)", "gain (s)", "every"
    );
    let params = AnalysisParams::default();
    for (name, volume) in &volumes {
        let time = |f: &dyn Fn() -> slabscope::Result<()>| -> slabscope::Result<f64> {
            let mut secs = Vec::with_capacity(runs);
            for _ in 0..runs {
                let t = Instant::now();
                f()?;
                secs.push(t.elapsed().as_secs_f64());
            }
            secs.sort_by(f64::total_cmp);
            Ok(secs[secs.len() / 2])
        };
        let views = search(volume, &params.view, &Monitor::none())?;
        let gain = rank_by_gain(volume, &params, &Monitor::none())?;
        let t_views = time(&|| search(volume, &params.view, &Monitor::none()).map(drop))?;
        let t_gain = time(&|| rank_by_gain(volume, &params, &Monitor::none()).map(drop))?;
        let a = gain.refined.axis;
        println!(
            "{name:<20} {t_views:>14.3} {t_gain:>14.3} {:>6}  [{:.3}, {:.3}, {:.3}] {:.4} bits, {:.1}°",
            gain.sampling.every,
            a[0],
            a[1],
            a[2],
            gain.refined.partition_gain,
            axis_angle(a, views.best().axis)
        );
    }
    Ok(())
}
