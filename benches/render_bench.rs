//! Times exploded renders of a 256x256x415 body phantom with 4 slabs (the benchmark): the
//! default (cut faces, automatic transfer function) and plain DVR and MIP, and the slice strip of
//! `render --faces`; writes the last image of each to /tmp for looking at.
//!
//! `cargo bench --bench render_bench`

use std::time::Instant;

use slabscope::partition::{PartitionParams, partition};
use slabscope::progress::Monitor;
use slabscope::render::{
    DEFAULT_SPREAD, Gap, Layout, Mode, Preset, RenderParams, Renderer, Stack, TransferChoice, slice,
};
use slabscope::volume::phantom;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let volume = phantom::body([256, 256, 415], 1)?;
    let none = Monitor::none();
    let part = partition(&volume, [0.0, 0.0, 1.0], &PartitionParams::paper(), &none)?;
    let layout = Layout::exploded(&part, Gap::Similarity, DEFAULT_SPREAD);
    let t = Instant::now();
    let renderer = Renderer::new(&volume)?;
    println!(
        "threads: {}; prepare (bricks, histogram): {:.1} ms",
        rayon::current_num_threads(),
        t.elapsed().as_secs_f64() * 1e3
    );
    for (mode, preset, name) in [
        (Mode::Cut, Preset::Auto, "cut-auto"),
        (Mode::Dvr, Preset::Auto, "dvr-auto"),
        (Mode::Dvr, Preset::CtBone, "dvr-bone"),
        (Mode::Dvr, Preset::CtSoft, "dvr-soft"),
        (Mode::Mip, Preset::CtBone, "mip"),
    ] {
        for (w, h) in [(640, 480), (320, 240)] {
            let params = RenderParams {
                width: w,
                height: h,
                mode,
                preset,
                ..RenderParams::default()
            };
            let mut times = Vec::new();
            let mut image = None;
            for _ in 0..5 {
                let t = Instant::now();
                image = Some(renderer.render(&layout, &params, &none)?);
                times.push(t.elapsed().as_secs_f64() * 1e3);
            }
            times.sort_by(f64::total_cmp);
            println!(
                "{name:<9} {w}x{h}: median {:6.1} ms (min {:.1})",
                times[2], times[0]
            );
            if let Some(image) = image {
                std::fs::write(format!("/tmp/render-{name}-{w}.png"), image.png()?)?;
            }
        }
    }
    let look = TransferChoice {
        preset: Preset::Auto,
        colormap: slabscope::render::Colormap::Grey,
        window: None,
    };
    let transfer = renderer.transfer(look, 1.0)?;
    let mut times = Vec::new();
    let mut strip = None;
    for _ in 0..5 {
        let t = Instant::now();
        strip = Some(slice::faces(
            &volume,
            &transfer,
            &Stack::of(&part),
            &part.slabs,
            (150, 150),
        )?);
        times.push(t.elapsed().as_secs_f64() * 1e3);
    }
    times.sort_by(f64::total_cmp);
    println!(
        "faces strip of 4 slabs, 150x150 tiles: median {:6.1} ms",
        times[2]
    );
    if let Some(strip) = strip {
        std::fs::write("/tmp/render-faces.png", strip.encode_png()?)?;
    }
    Ok(())
}
