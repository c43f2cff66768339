//! Times exploded renders of a 256x256x415 body phantom with 4 slabs (the benchmark): the
//! default (cut faces, automatic transfer function) and plain DVR and MIP, and the slice strip of
//! `render --faces`; writes the last image of each to /tmp for looking at. Then large body
//! phantoms (512³ unless `--big N,...` says which sizes), 4 uniform slabs, at 640×480 and
//! 320×240: each render at the pyramid level the rule picks against the same render forced to
//! level 0 (the behaviour before renders read the pyramid), the first render (which makes the
//! level and its bricks) apart from the median of 5 after it.
//!
//! `cargo bench --bench render_bench [-- --big 512,1024]`

use std::time::Instant;

use slabscope::partition::{PartitionParams, partition};
use slabscope::progress::Monitor;
use slabscope::render::{
    DEFAULT_SPREAD, Gap, Layout, Mode, Preset, RenderParams, Renderer, Stack, TransferChoice, slice,
};
use slabscope::volume::Volume;
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
                "{name:<9} {w}x{h}: median {:6.1} ms (min {:.1}), pyramid level {}",
                times[2],
                times[0],
                image.as_ref().map_or(0, |i| i.pyramid_level)
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
    // On a fresh volume: the first strip makes the pyramid levels its tiles read.
    let fresh = fresh(&volume)?;
    let stack = Stack::of(&part);
    let strip = || slice::faces(&fresh, &transfer, &stack, &part.slabs, (150, 150));
    let t = Instant::now();
    let mut strip_image = strip()?;
    let first = t.elapsed().as_secs_f64() * 1e3;
    let mut times = Vec::new();
    for _ in 0..5 {
        let t = Instant::now();
        strip_image = strip()?;
        times.push(t.elapsed().as_secs_f64() * 1e3);
    }
    times.sort_by(f64::total_cmp);
    println!(
        "faces strip of 4 slabs, 150x150 tiles: median {:6.1} ms; first {first:.0} ms",
        times[2]
    );
    let strip = Some(strip_image);
    if let Some(strip) = strip {
        std::fs::write("/tmp/render-faces.png", strip.encode_png()?)?;
    }
    for n in big_sizes()? {
        big(n)?;
    }
    Ok(())
}

/// `volume` with no pyramid level made yet (its voxels shared).
fn fresh(volume: &Volume) -> Result<Volume, Box<dyn std::error::Error>> {
    Ok(Volume::from_voxels(
        volume.dims(),
        volume.spacing(),
        volume.voxel_type(),
        volume.data().clone(),
    )?
    .with_transform(*volume.transform()))
}

/// The sizes `--big N,...` asks for (default 512).
fn big_sizes() -> Result<Vec<usize>, Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    match args.iter().position(|a| a == "--big") {
        Some(i) => Ok(args
            .get(i + 1)
            .ok_or("--big N,...")?
            .split(',')
            .map(str::parse)
            .collect::<Result<_, _>>()?),
        None => Ok(vec![512]),
    }
}

/// A body phantom of `n`³ voxels in 4 uniform slabs at 640×480 and 320×240: the rule's pyramid
/// level against level 0, each with a fresh renderer and volume, so that the first render makes
/// the pyramid level and the bricks it reads.
fn big(n: usize) -> Result<(), Box<dyn std::error::Error>> {
    let t = Instant::now();
    let volume = phantom::body([n; 3], 1)?;
    println!("body {n}³: made in {:.1} s", t.elapsed().as_secs_f64());
    let pyramid = fresh(&volume)?;
    let t = Instant::now();
    let _ = pyramid.coarser(1);
    let one = t.elapsed().as_secs_f64() * 1e3;
    let _ = pyramid.coarser(3);
    println!(
        "body {n}³: pyramid level 1 made in {one:.0} ms, levels 2 and 3 after it in {:.0} ms",
        t.elapsed().as_secs_f64() * 1e3 - one
    );
    drop(pyramid);
    let stack = Stack {
        axis: [0.0, 0.0, 1.0],
        slices: n,
        thickness: 1.0,
        offset: 0.0,
    };
    let q = n / 4;
    let slabs = [(0, q), (q, 2 * q), (2 * q, 3 * q), (3 * q, n)];
    let layout = Layout::from_slabs(&stack, &slabs, None, Gap::Uniform, DEFAULT_SPREAD);
    for (w, h) in [(640, 480), (320, 240)] {
        let params = RenderParams {
            width: w,
            height: h,
            ..RenderParams::default()
        };
        for forced in [Some(0), None] {
            timed_renders(&fresh(&volume)?, &layout, &params, forced, n)?;
        }
    }
    Ok(())
}

/// Times a first render and 5 more of `volume` at pyramid level `forced` (None: the rule's),
/// and writes the last to /tmp.
fn timed_renders(
    volume: &Volume,
    layout: &Layout,
    params: &RenderParams,
    forced: Option<usize>,
    n: usize,
) -> Result<(), Box<dyn std::error::Error>> {
    let none = Monitor::none();
    let t = Instant::now();
    let renderer = Renderer::new(volume)?;
    let prepare = t.elapsed().as_secs_f64() * 1e3;
    let render = || match forced {
        Some(k) => renderer.render_at(layout, params, k, &none),
        None => renderer.render(layout, params, &none),
    };
    let t = Instant::now();
    let mut image = render()?;
    let first = t.elapsed().as_secs_f64() * 1e3;
    let mut times = Vec::new();
    for _ in 0..5 {
        let t = Instant::now();
        image = render()?;
        times.push(t.elapsed().as_secs_f64() * 1e3);
    }
    times.sort_by(f64::total_cmp);
    let (w, h) = (params.width, params.height);
    let how = if forced.is_some() {
        "level 0 (old)"
    } else {
        "rule (new)"
    };
    println!(
        "body {n}³ {w}x{h} {how:<13}: pyramid level {}, median {:7.1} ms (min {:.1}); \
         renderer {prepare:.0} ms, first render {first:.0} ms",
        image.pyramid_level, times[2], times[0]
    );
    let name = if forced.is_some() { "level0" } else { "rule" };
    std::fs::write(format!("/tmp/render-big-{n}-{w}-{name}.png"), image.png()?)?;
    Ok(())
}
