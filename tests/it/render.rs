//! The exploded-view ray caster on scenes with known answers, and against reference images.
//!
//! `UPDATE_REFERENCES=1 cargo test --test it render::` rewrites the reference images; look at them
//! before committing.

use slabscope::partition::{Method, PartitionParams, Stop, partition};
use slabscope::progress::Monitor;
use slabscope::render::slice::{self, SliceParams};
use slabscope::render::{
    CameraParams, Colormap, Gap, Layout, Mode, Preset, RenderParams, Renderer, Stack,
    TransferChoice,
};
use slabscope::volume::phantom;
use slabscope::{Volume, VoxelType};

use crate::common::data;

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
    for mode in [Mode::Cut, Mode::Dvr, Mode::Mip] {
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
        fade: true,
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
fn check_reference(name: &str, pixmap: &tiny_skia::Pixmap) {
    let path = data("reference").join(format!("{name}.png"));
    if std::env::var_os("UPDATE_REFERENCES").is_some() {
        std::fs::write(&path, pixmap.encode_png().unwrap()).unwrap();
        return;
    }
    let reference = tiny_skia::Pixmap::load_png(&path).unwrap();
    assert_eq!(
        (reference.width(), reference.height()),
        (pixmap.width(), pixmap.height())
    );
    let diff: u64 = reference
        .data()
        .iter()
        .zip(pixmap.data())
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
        ("body-cut", Mode::Cut, Preset::Auto, Gap::Similarity, None),
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
            fade: highlight.is_some(),
            ..RenderParams::default()
        };
        let image = renderer
            .render(&Layout::exploded(&p, gap, 0.3), &params, &Monitor::none())
            .unwrap();
        check_reference(name, &image.pixmap);
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
    check_reference("shepp-logan-mri", &image.pixmap);
    let labels = label_blocks();
    let image = Renderer::new(&labels)
        .unwrap()
        .render(
            &Layout::whole([0.0, 0.0, 1.0]),
            &plain(120, 72),
            &Monitor::none(),
        )
        .unwrap();
    check_reference("labels-cut", &image.pixmap);
    let transfer = renderer
        .transfer(
            TransferChoice {
                preset: Preset::Auto,
                colormap: Colormap::Grey,
                window: None,
            },
            1.0,
        )
        .unwrap();
    let stack = Stack::of(&p);
    let params = SliceParams {
        fit: (96, 96),
        ..SliceParams::default()
    };
    let axial = slice::slice(&v, &transfer, stack.axis, 50.0, &params).unwrap();
    check_reference("body-slice-axial", &axial.pixmap);
    let strip = slice::faces(&v, &transfer, &stack, &p.slabs, (48, 48)).unwrap();
    check_reference("body-faces", &strip);
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

/// A cube of tissue (100) in air (0), 40 voxels a side, with a bright square (200) in the two
/// slices on either side of the cut at 19.5 (so the face, between them, carries it exactly).
fn patterned_cube() -> Volume {
    let n = 40;
    let data = (0..n * n * n)
        .map(|i| {
            let (x, y, z) = (i % n, (i / n) % n, i / (n * n));
            let inside = |c: usize| (6..34).contains(&c);
            if !(inside(x) && inside(y) && inside(z)) {
                0.0
            } else if (19..=20).contains(&z) && (10..20).contains(&x) && (12..30).contains(&y) {
                200.0
            } else {
                100.0
            }
        })
        .collect();
    Volume::new([n; 3], [1.0; 3], VoxelType::U16, data).unwrap()
}

/// The RGB of the pixel where world point `p` projects.
fn pixel_at(image: &slabscope::render::Image, p: [f64; 3]) -> [u8; 3] {
    let (x, y) = image.camera.project(p);
    let w = image.pixmap.width() as usize;
    let i = 4 * (y as usize * w + x as usize);
    let d = image.pixmap.data();
    [d[i], d[i + 1], d[i + 2]]
}

#[test]
fn a_cut_face_shows_the_slice_at_the_pixels_where_it_projects() {
    let v = patterned_cube();
    let stack = Stack {
        axis: [0.0, 0.0, 1.0],
        slices: 40,
        thickness: 1.0,
        offset: 0.0,
    };
    let layout = Layout::from_slabs(&stack, &[(0, 20), (20, 40)], None, Gap::Uniform, 0.5);
    let params = RenderParams {
        // The lower slab alone: its cut, at 19.5, faces the camera whole.
        highlight: Some(0),
        solo: true,
        window: Some((0.0, 200.0)),
        camera: CameraParams {
            azimuth: 30.0,
            elevation: 60.0,
            ..CameraParams::default()
        },
        ..plain(200, 200)
    };
    let image = Renderer::new(&v)
        .unwrap()
        .render(&layout, &params, &Monitor::none())
        .unwrap();
    let offset = layout.slabs[0].offset;
    let face = |x: f64, y: f64| pixel_at(&image, [x, y, 19.5 + offset]);
    // Lit as a surface at 60 degrees: 0.75 + 0.25 sin 60 of the window's grey.
    let light = 0.75 + 0.25 * 60f64.to_radians().sin();
    for (x, y, grey) in [
        (12.0, 15.0, 1.0),
        (17.0, 27.0, 1.0),
        (14.5, 20.5, 1.0),
        (25.0, 20.0, 0.5),
        (9.0, 9.0, 0.5),
        (30.0, 31.0, 0.5),
        (14.0, 32.0, 0.5),
    ] {
        let expected = (grey * light * 255.0) as i32;
        let c = face(x, y);
        assert!(
            c.iter().all(|&k| (i32::from(k) - expected).abs() <= 6),
            "face at ({x}, {y}): {c:?}, expected about {expected}"
        );
    }
    // Without the cut faces (plain DVR) the same pixels show the volume, not the slice.
    let dvr = Renderer::new(&v)
        .unwrap()
        .render(
            &layout,
            &RenderParams {
                mode: Mode::Dvr,
                ..params.clone()
            },
            &Monitor::none(),
        )
        .unwrap();
    assert_ne!(
        pixel_at(&dvr, [12.0, 15.0, 19.5 + offset]),
        face(12.0, 15.0)
    );
}

#[test]
fn the_exploded_stack_fills_the_image_whatever_the_axis_and_spread() {
    // Layers that fill their box, all made opaque: the picture is the stack's projection.
    let v = phantom::layers([36, 40, 44], [1.0, 1.0, 1.0], 1).unwrap();
    let renderer = Renderer::new(&v).unwrap();
    for axis in [
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.6, 0.0, 0.8],
    ] {
        let p = partition(&v, axis, &PartitionParams::paper(), &Monitor::none()).unwrap();
        for spread in [0.0, 0.5, 2.0] {
            for (w, h) in [(160, 90), (90, 160)] {
                let params = RenderParams {
                    window: Some((-2.0, -1.0)),
                    ..plain(w, h)
                };
                let image = renderer
                    .render(
                        &Layout::exploded(&p, Gap::Similarity, spread),
                        &params,
                        &Monitor::none(),
                    )
                    .unwrap();
                let d = image.pixmap.data();
                let bg = params.background;
                let (mut x0, mut x1, mut y0, mut y1) = (u32::MAX, 0, u32::MAX, 0);
                for y in 0..h {
                    for x in 0..w {
                        let i = 4 * (y * w + x) as usize;
                        if d[i..i + 3] != bg {
                            (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
                        }
                    }
                }
                let what = format!("axis {axis:?}, spread {spread}, {w}x{h}");
                assert!(
                    x0 > 0 && y0 > 0 && x1 < w - 1 && y1 < h - 1,
                    "{what}: touches"
                );
                let cover = f64::from(x1 - x0 + 1) / f64::from(w);
                let cover = cover.max(f64::from(y1 - y0 + 1) / f64::from(h));
                assert!(cover >= 0.6, "{what}: covers {cover:.2}");
            }
        }
    }
}

#[test]
fn an_edge_behind_an_opaque_volume_is_not_drawn() {
    // An opaque block filling its box: the bottom outline's back edge lies behind it.
    let v = Volume::new([20, 20, 20], [1.0; 3], VoxelType::F32, vec![100.0; 8000]).unwrap();
    let renderer = Renderer::new(&v).unwrap();
    let params = RenderParams {
        window: Some((0.0, 1.0)),
        outlines: true,
        ..plain(160, 160)
    };
    let layout = Layout::whole([0.0, 0.0, 1.0]);
    let with = renderer.render(&layout, &params, &Monitor::none()).unwrap();
    let without = renderer
        .render(
            &layout,
            &RenderParams {
                outlines: false,
                ..params.clone()
            },
            &Monitor::none(),
        )
        .unwrap();
    // The edges of the bottom and the top outline, at their middles.
    let mids = |z: f64| [[9.5, 0.0, z], [9.5, 19.0, z], [0.0, 9.5, z], [19.0, 9.5, z]];
    let back = mids(0.0)
        .into_iter()
        .max_by(|a, b| with.camera.depth(*a).total_cmp(&with.camera.depth(*b)))
        .unwrap();
    assert_eq!(
        pixel_at(&with, back),
        pixel_at(&without, back),
        "back edge drawn"
    );
    let front = mids(19.0)
        .into_iter()
        .min_by(|a, b| with.camera.depth(*a).total_cmp(&with.camera.depth(*b)))
        .unwrap();
    assert_ne!(
        pixel_at(&with, front),
        pixel_at(&without, front),
        "front edge missing"
    );
}

/// A label volume: background 0 with blocks of labels 3, 7 and 9 side by side.
fn label_blocks() -> Volume {
    let (nx, ny, nz) = (36, 12, 12);
    let data = (0..nx * ny * nz)
        .map(|i| {
            let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
            if !(2..10).contains(&y) || !(2..10).contains(&z) {
                0.0
            } else {
                match x {
                    2..10 => 3.0,
                    14..22 => 7.0,
                    26..34 => 9.0,
                    _ => 0.0,
                }
            }
        })
        .collect();
    Volume::new([nx, ny, nz], [1.0; 3], VoxelType::U8, data).unwrap()
}

#[test]
fn label_volumes_are_drawn_in_distinct_colours() {
    let v = label_blocks();
    let renderer = Renderer::new(&v).unwrap();
    let labels: Vec<f32> = renderer.labels().unwrap().iter().map(|l| l.0).collect();
    assert_eq!(labels.len(), 4);
    for l in [0.0, 3.0, 7.0, 9.0] {
        assert!(labels.contains(&l), "{labels:?}");
    }
    // From straight above, each block's top shows on its own.
    let params = RenderParams {
        camera: CameraParams {
            elevation: 89.0,
            ..CameraParams::default()
        },
        ..plain(240, 120)
    };
    let image = renderer
        .render(&Layout::whole([0.0, 0.0, 1.0]), &params, &Monitor::none())
        .unwrap();
    let colours: Vec<[u8; 3]> = [6.0, 18.0, 30.0]
        .iter()
        .map(|&x| pixel_at(&image, [x, 6.0, 11.0]))
        .collect();
    for (i, a) in colours.iter().enumerate() {
        assert!(a[0] != a[1] || a[1] != a[2], "label {i} is grey: {a:?}");
        for b in &colours[i + 1..] {
            let distance: i32 = (0..3)
                .map(|k| (i32::from(a[k]) - i32::from(b[k])).abs())
                .sum();
            assert!(distance > 60, "{a:?} and {b:?} are alike");
        }
    }
    // The background label is clear: the gap between blocks shows the background colour.
    assert_eq!(pixel_at(&image, [12.0, 6.0, 11.0]), [12, 12, 18]);
    // Integers with many values, and floats, are not labels.
    let ramp: Vec<f32> = (0..4096).map(|i| (i % 100) as f32).collect();
    let many = Volume::new([16, 16, 16], [1.0; 3], VoxelType::U8, ramp.clone()).unwrap();
    assert!(Renderer::new(&many).unwrap().labels().is_none());
    let few: Vec<f32> = ramp.iter().map(|v| (v % 3.0).floor()).collect();
    let floats = Volume::new([16, 16, 16], [1.0; 3], VoxelType::F32, few).unwrap();
    assert!(Renderer::new(&floats).unwrap().labels().is_none());
}
