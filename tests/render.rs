//! The exploded-view ray caster on scenes with known answers, and against reference images.
//!
//! `UPDATE_REFERENCES=1 cargo test --test render` rewrites the reference images; look at them
//! before committing.

#![allow(clippy::unwrap_used)] // tests fail loudly by design

use std::path::PathBuf;

use slabscope::partition::{Method, PartitionParams, Stop, partition};
use slabscope::progress::Monitor;
use slabscope::render::{CameraParams, Gap, Layout, Mode, Preset, RenderParams, Renderer};
use slabscope::volume::phantom;
use slabscope::{Volume, VoxelType};

fn plain(width: u32, height: u32) -> RenderParams {
    RenderParams {
        width,
        height,
        outlines: false,
        labels: false,
        ..RenderParams::default()
    }
}

#[test]
fn one_bright_voxel_appears_where_the_camera_puts_it() {
    let mut data = vec![0.0f32; 21 * 17 * 19];
    let (x, y, z) = (5usize, 12usize, 9usize);
    data[x + 21 * (y + 17 * z)] = 1000.0;
    let v = Volume::new([21, 17, 19], [1.0, 1.0, 1.5], VoxelType::F32, data).unwrap();
    let renderer = Renderer::new(&v).unwrap();
    for perspective in [false, true] {
        let params = RenderParams {
            mode: Mode::Mip,
            // A fixed window: the auto preset has no percentiles to go by on an empty volume.
            preset: Preset::CtBone,
            step: 0.25,
            camera: CameraParams {
                azimuth: 35.0,
                elevation: 25.0,
                zoom: 1.0,
                perspective,
            },
            ..plain(121, 101)
        };
        let image = renderer
            .render(&Layout::whole([0.0, 0.0, 1.0]), &params, &Monitor::none())
            .unwrap();
        let data = image.pixmap.data();
        let brightest = (0..121 * 101).max_by_key(|&i| data[4 * i]).unwrap();
        let (bx, by) = (
            (brightest % 121) as f64 + 0.5,
            (brightest / 121) as f64 + 0.5,
        );
        let (px, py) = image.camera.project([x as f64, y as f64, z as f64 * 1.5]);
        assert!(
            (bx - px).abs() <= 1.0 && (by - py).abs() <= 1.0,
            "{perspective}: at ({bx}, {by}), predicted ({px:.2}, {py:.2})"
        );
    }
}

/// A body phantom and the paper's partition of it (top-down, 4 slabs, every voxel) along z, as
/// the reference images were made.
fn body_in_slabs(dims: [usize; 3], seed: u64) -> (Volume, slabscope::partition::Partition) {
    let v = phantom::body(dims, seed).unwrap();
    let p = partition(
        &v,
        [0.0, 0.0, 1.0],
        &PartitionParams::paper(),
        &Monitor::none(),
    )
    .unwrap();
    (v, p)
}

/// A volume of two materials, below and above z = 20, and its 2-slab partition along z.
fn two_slabs() -> (Volume, slabscope::partition::Partition) {
    let v = phantom::layers([32, 32, 40], [0.0, 0.0, 1.0], 1).unwrap();
    let params = PartitionParams {
        method: Method::TopDown,
        stop: Stop::Slabs(2),
        ..PartitionParams::paper()
    };
    let p = partition(&v, [0.0, 0.0, 1.0], &params, &Monitor::none()).unwrap();
    (v, p)
}

/// Rows of the image's middle column that show the background, between rows that do not.
fn gap_rows(image: &slabscope::render::Image, background: [u8; 3]) -> usize {
    let (w, h) = (
        image.pixmap.width() as usize,
        image.pixmap.height() as usize,
    );
    let data = image.pixmap.data();
    let is_bg: Vec<bool> = (0..h)
        .map(|y| data[4 * (y * w + w / 2)..][..3] == background)
        .collect();
    let first = is_bg.iter().position(|b| !b).unwrap();
    let last = is_bg.iter().rposition(|b| !b).unwrap();
    is_bg[first..=last].iter().filter(|&&b| b).count()
}

#[test]
fn exploded_slabs_show_a_gap_that_widens_with_spread() {
    let (v, p) = two_slabs();
    let renderer = Renderer::new(&v).unwrap();
    let params = RenderParams {
        preset: Preset::Auto,
        camera: CameraParams {
            azimuth: 20.0,
            elevation: 10.0,
            ..CameraParams::default()
        },
        ..plain(80, 120)
    };
    let render = |spread: f64| {
        renderer
            .render(
                &Layout::exploded(&p, Gap::Uniform, spread),
                &params,
                &Monitor::none(),
            )
            .unwrap()
    };
    let (none, some, more) = (
        gap_rows(&render(0.0), params.background),
        gap_rows(&render(0.3), params.background),
        gap_rows(&render(0.6), params.background),
    );
    assert_eq!(none, 0, "no gap without spread");
    assert!(
        some >= 3,
        "a band of background rows between the slabs: {some}"
    );
    assert!(more > some, "wider with more spread: {more} vs {some}");
}

#[test]
fn zero_spread_equals_the_plain_render() {
    let (v, p) = two_slabs();
    let renderer = Renderer::new(&v).unwrap();
    for mode in [Mode::Dvr, Mode::Mip] {
        let params = RenderParams {
            mode,
            ..plain(64, 48)
        };
        let whole = renderer
            .render(&Layout::whole(p.axis), &params, &Monitor::none())
            .unwrap();
        let exploded = renderer
            .render(
                &Layout::exploded(&p, Gap::Similarity, 0.0),
                &params,
                &Monitor::none(),
            )
            .unwrap();
        assert!(whole.pixmap.data() == exploded.pixmap.data(), "{mode:?}");
    }
}

#[test]
fn images_do_not_depend_on_the_thread_count() {
    let (v, p) = body_in_slabs([40, 40, 64], 2);
    let layout = Layout::exploded(&p, Gap::Similarity, 0.3);
    let params = RenderParams {
        preset: Preset::CtSoft,
        highlight: Some(1),
        ..RenderParams {
            width: 90,
            height: 70,
            ..RenderParams::default()
        }
    };
    let png = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            Renderer::new(&v)
                .unwrap()
                .render(&layout, &params, &Monitor::none())
                .unwrap()
                .png()
                .unwrap()
        })
    };
    assert_eq!(png(1), png(3));
}

/// Compares a render with a committed reference image: mean absolute difference per channel
/// below 1.5 (of 255), for small numeric differences across machines.
fn check_reference(name: &str, image: &slabscope::render::Image) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/reference")
        .join(format!("{name}.png"));
    if std::env::var_os("UPDATE_REFERENCES").is_some() {
        std::fs::write(&path, image.png().unwrap()).unwrap();
        return;
    }
    let reference = tiny_skia::Pixmap::load_png(&path).unwrap();
    assert_eq!(
        (reference.width(), reference.height()),
        (image.pixmap.width(), image.pixmap.height())
    );
    let diff: u64 = reference
        .data()
        .iter()
        .zip(image.pixmap.data())
        .map(|(a, b)| u64::from(a.abs_diff(*b)))
        .sum();
    let mean = diff as f64 / reference.data().len() as f64;
    assert!(mean < 1.5, "{name}: mean difference {mean}");
}

#[test]
fn fixed_scenes_match_their_reference_images() {
    let (v, p) = body_in_slabs([48, 48, 78], 1);
    let renderer = Renderer::new(&v).unwrap();
    let scenes = [
        (
            "body-dvr-bone",
            Mode::Dvr,
            Preset::CtBone,
            Gap::Similarity,
            None,
        ),
        (
            "body-dvr-soft-highlight",
            Mode::Dvr,
            Preset::CtSoft,
            Gap::Uniform,
            Some(2),
        ),
        ("body-mip", Mode::Mip, Preset::CtBone, Gap::Uniform, None),
    ];
    for (name, mode, preset, gap, highlight) in scenes {
        let params = RenderParams {
            width: 120,
            height: 96,
            mode,
            preset,
            highlight,
            ..RenderParams::default()
        };
        let image = renderer
            .render(&Layout::exploded(&p, gap, 0.3), &params, &Monitor::none())
            .unwrap();
        check_reference(name, &image);
    }
    let sl = phantom::shepp_logan([40; 3]).unwrap();
    let params = RenderParams {
        width: 96,
        height: 96,
        preset: Preset::Mri,
        outlines: false,
        labels: false,
        ..RenderParams::default()
    };
    let image = Renderer::new(&sl)
        .unwrap()
        .render(&Layout::whole([0.0, 0.0, 1.0]), &params, &Monitor::none())
        .unwrap();
    check_reference("shepp-logan-mri", &image);
}

#[test]
fn absurd_image_sizes_are_refused() {
    let v = phantom::shepp_logan([8; 3]).unwrap();
    let renderer = Renderer::new(&v).unwrap();
    for (w, h) in [(0, 10), (10, 0), (100_000, 100_000)] {
        assert!(
            renderer
                .render(
                    &Layout::whole([0.0, 0.0, 1.0]),
                    &plain(w, h),
                    &Monitor::none()
                )
                .is_err()
        );
    }
}
