//! Times each axis of the view search separately (a profiling aid).
//!
//! `cargo run --release --example axis_probe`

use std::time::Instant;

use slabscope::geometry::lattice::Lattice;
use slabscope::progress::Monitor;
use slabscope::view::BinSampler;
use slabscope::view::{entropy_rate, icosphere};
use slabscope::volume::phantom;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let volume = phantom::body([256, 256, 415], 1)?;
    let sampler = BinSampler::new(&volume, volume.quantizer(32)?);
    for axis in icosphere::axes(1) {
        let lattice = Lattice::at_voxel_spacing(volume.dims(), volume.spacing(), axis)?;
        let t = Instant::now();
        let r = entropy_rate(&sampler, &lattice, 3, &Monitor::none())?;
        let secs = t.elapsed().as_secs_f64();
        println!(
            "[{:6.3} {:6.3} {:6.3}] {:7.3} s  {:5.1} ns/sample  h = {:.4}",
            axis[0],
            axis[1],
            axis[2],
            secs,
            secs * 2e9 / r.samples as f64,
            r.entropy_rate
        );
    }
    Ok(())
}
