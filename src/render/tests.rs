//! Which pyramid level renders and slices read, and that reading a coarse one changes neither
//! the framing nor, for a volume that is the same at both levels, the picture.

use super::slice::{SliceParams, slice};
use super::*;
use crate::partition::{PartitionParams, partition};
use crate::volume::{VoxelType, phantom};

const Z: [f64; 3] = [0.0, 0.0, 1.0];

/// A volume of `dims` voxels `spacing` apart, constant within blocks of `block` voxels a side
/// (values 100.25 to 200.25, not integers, so not a label volume).
fn blocky(dims: [usize; 3], block: usize, spacing: [f64; 3]) -> Volume {
    let mut data = Vec::with_capacity(dims.iter().product());
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let (a, b, c) = (x / block, y / block, z / block);
                data.push(100.25 + ((7 * a + 13 * b + 29 * c) % 11) as f32 * 10.0);
            }
        }
    }
    Volume::new(dims, spacing, VoxelType::F32, data).unwrap()
}

/// `width × height`, every value of [`blocky`] visible (so the whole box is drawn).
fn seen(width: u32, height: u32, mode: Mode) -> RenderParams {
    RenderParams {
        width,
        height,
        mode,
        window: Some((50.0, 250.0)),
        ..RenderParams::default()
    }
}

/// Mean absolute difference per channel, and the fraction of pixels with a channel more than
/// `far` apart.
fn difference(a: &Image, b: &Image, far: u8) -> (f64, f64) {
    let (a, b) = (a.pixmap.data(), b.pixmap.data());
    let sum: u64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| u64::from(x.abs_diff(*y)))
        .sum();
    let apart = a
        .chunks(4)
        .zip(b.chunks(4))
        .filter(|(p, q)| p.iter().zip(*q).any(|(x, y)| x.abs_diff(*y) > far))
        .count();
    (
        sum as f64 / a.len() as f64,
        apart as f64 / (a.len() / 4) as f64,
    )
}

#[test]
fn todays_pictures_read_pyramid_level_0_unchanged() {
    let none = Monitor::none();
    // A 64³ volume at 640×480, whole and exploded.
    let v = phantom::layers([64; 3], [1.0, 1.0, 1.0], 1).unwrap();
    let part = partition(&v, Z, &PartitionParams::paper(), &none).unwrap();
    let renderer = Renderer::new(&v).unwrap();
    for layout in [
        Layout::whole(Z),
        Layout::exploded(&part, Gap::Similarity, DEFAULT_SPREAD),
    ] {
        let params = RenderParams::default();
        let image = renderer.render(&layout, &params, &none).unwrap();
        assert_eq!(image.pyramid_level, 0);
        let level0 = renderer.render_at(&layout, &params, 0, &none).unwrap();
        assert_eq!(image.pixmap.data(), level0.pixmap.data());
    }
    // The built-in dataset as the TUI first shows it in a picture of 1000×600.
    let v = phantom::body([128, 128, 208], 1).unwrap(); // crate::builtin_dataset's
    let part = partition(&v, Z, &PartitionParams::default(), &none).unwrap();
    let layout = Layout::exploded(&part, Gap::Similarity, DEFAULT_SPREAD);
    let params = RenderParams {
        width: 1000,
        height: 600,
        ..RenderParams::default()
    };
    let renderer = Renderer::new(&v).unwrap();
    let image = renderer.render(&layout, &params, &none).unwrap();
    assert_eq!(image.pyramid_level, 0);
    let level0 = renderer.render_at(&layout, &params, 0, &none).unwrap();
    assert_eq!(image.pixmap.data(), level0.pixmap.data());
    assert!(renderer.levels[1].get().is_none(), "no coarse level made");
}

#[test]
fn a_small_picture_of_a_large_volume_reads_a_coarse_level() {
    // 2048³ voxels of 1 mm, whole, at 640×480 from the default camera: the box (2047 mm a
    // side) seen obliquely fills 92% of the picture's height; its pixels are over 4 mm, so level
    // 0 gives over 4 voxels a pixel, level 1 over 2 and level 2 under 2: pyramid level 2.
    let params = RenderParams::default();
    let extent = [2047.0; 3];
    let (camera, level) = framed(
        (&halving_grids([2048; 3], [1.0; 3]), None),
        &Layout::whole(Z),
        &params,
        &Aabb::of(extent),
    )
    .unwrap();
    let pixel = camera.pixel_size(&[]);
    assert!((4.0..8.0).contains(&pixel), "{pixel} mm");
    assert_eq!(level, 2);
    // Exploded by half its length, the scene is taller: level 3.
    let stack = Stack {
        axis: Z,
        slices: 2048,
        thickness: 1.0,
        offset: 0.0,
    };
    let layout = Layout::from_slabs(&stack, &[(0, 1024), (1024, 2048)], None, Gap::Uniform, 0.5);
    let (camera, level) = framed(
        (&halving_grids([2048; 3], [1.0; 3]), None),
        &layout,
        &params,
        &Aabb::of(extent),
    )
    .unwrap();
    let pixel = camera.pixel_size(&[]);
    assert!((8.0..16.0).contains(&pixel), "{pixel} mm");
    assert_eq!(level, 3);
    // The same at 0.5 mm along z (a twice as thin box): only one level less along up.
    let (_, level) = framed(
        (&halving_grids([2048; 3], [1.0, 1.0, 0.5]), None),
        &Layout::whole(Z),
        &params,
        &Aabb::of([2047.0, 2047.0, 1023.5]),
    )
    .unwrap();
    assert_eq!(level, 2);
}

#[test]
fn a_render_reads_the_level_its_pixels_allow_and_makes_only_that_levels_bricks() {
    let none = Monitor::none();
    let v = blocky([64; 3], 8, [1.0; 3]);
    let renderer = Renderer::new(&v).unwrap();
    let params = seen(32, 24, Mode::Cut);
    let layout = Layout::whole(Z);
    let image = renderer.render(&layout, &params, &none).unwrap();
    let (camera, _) = renderer
        .camera(&layout, &params, &Aabb::of([63.0; 3]))
        .unwrap();
    let expect = pyramid_level(camera.pixel_size(&[]), camera.axes(), [64; 3], [1.0; 3]);
    assert!(expect > 0);
    assert_eq!(image.pyramid_level, expect);
    assert!(
        renderer.levels[0].get().is_none(),
        "level 0's bricks not made"
    );
    assert!(renderer.levels[expect].get().is_some());
    let forced = renderer.render_at(&layout, &params, expect, &none).unwrap();
    assert_eq!(image.pixmap.data(), forced.pixmap.data());
    assert_eq!(image.camera, camera);
    // Perspective: the pixel at the nearest depth, smaller than at the centre.
    let near = RenderParams {
        camera: CameraParams {
            perspective: true,
            ..CameraParams::default()
        },
        ..params
    };
    let image = renderer.render(&layout, &near, &none).unwrap();
    let points = overlay::scene_points(&layout, &Aabb::of([63.0; 3]), &near);
    let nearest = image.camera.pixel_size(&points);
    assert!(nearest < image.camera.pixel_size(&[]));
    let expect = pyramid_level(nearest, image.camera.axes(), [64; 3], [1.0; 3]);
    assert_eq!(image.pyramid_level, expect);
}

#[test]
fn a_coarse_render_of_a_blocky_volume_matches_level_0_and_frames_it_the_same() {
    // Blocks of 8 voxels: pyramid levels 1 and 2 hold the blocks' values exactly (in blocks of
    // 4 and 2 voxels), centred where level 0's are. What differs is only where values change:
    // interpolation ramps across a block boundary over one voxel of the level read (1, 2 or 4
    // voxels of level 0), so pixels that see a boundary within a voxel or two differ, and
    // samples lie 2 or 4 times as far apart along rays (the opacity corrected for it). Hence
    // the bounds: a mean difference under 1.5·k of 255 per channel, and under 4·k % of the
    // pixels more than 24 apart, for pyramid level k (measured: 0.6 and 0.2% at level 1, 1.5
    // and 1.7% at level 2 for cut faces and DVR; 1.0 and 1.1%, 2.7 and 5.0% for MIP, whose
    // maximum along a ray grazing a block's corner is the first to miss it). Shading is off:
    // the gradients at block boundaries spread over 2^k voxels, so what it lights differs by
    // design.
    let none = Monitor::none();
    let v = blocky([64, 64, 64], 8, [1.0, 0.8, 1.25]);
    let renderer = Renderer::new(&v).unwrap();
    let stack = Stack {
        axis: Z,
        slices: 64,
        thickness: 1.25,
        offset: 0.0,
    };
    let layout = Layout::from_slabs(&stack, &[(0, 28), (28, 64)], None, Gap::Uniform, 0.5);
    for mode in [Mode::Cut, Mode::Dvr, Mode::Mip] {
        let params = RenderParams {
            shading: false,
            ..seen(160, 120, mode)
        };
        let level0 = renderer.render_at(&layout, &params, 0, &none).unwrap();
        for k in [1, 2] {
            let coarse = renderer.render_at(&layout, &params, k, &none).unwrap();
            assert_eq!(coarse.pyramid_level, k);
            // The camera, and so the outlines and labels, are level 0's.
            assert_eq!(coarse.camera, level0.camera, "{mode:?} at level {k}");
            let (mean, apart) = difference(&level0, &coarse, 24);
            assert!(mean < 1.5 * k as f64, "{mode:?} level {k}: mean {mean}");
            assert!(apart < 0.04 * k as f64, "{mode:?} level {k}: {apart}");
        }
    }
}

#[test]
fn slices_read_the_level_their_pixels_allow() {
    let v = blocky([64, 64, 64], 8, [1.0; 3]);
    let renderer = Renderer::new(&v).unwrap();
    let transfer = renderer
        .transfer(
            TransferChoice {
                preset: Preset::Auto,
                colormap: Colormap::Grey,
                window: Some((50.0, 250.0)),
            },
            1.0,
        )
        .unwrap();
    let draw = |fit: (u32, u32)| {
        let params = SliceParams {
            fit,
            ..SliceParams::default()
        };
        slice(&v, &transfer, Z, 30.0, &params).unwrap()
    };
    // 63 mm across 64 pixels: under a voxel a pixel. Across 16: 3.9 (level 1 gives 1.97).
    // Across 8: 7.9, level 2.
    assert_eq!(draw((64, 64)).pyramid_level, 0);
    let (small, smaller) = (draw((16, 16)), draw((8, 8)));
    assert_eq!((small.pyramid_level, smaller.pyramid_level), (1, 2));
    // Pixels map to the same mm, and every block of 2 pixels is a block of 8 voxels: each
    // pixel at a block's inside is its value's grey.
    assert_eq!(small.pixel, 63.0 / 16.0);
    assert_eq!(
        small.point(0.0, 0.0),
        [0.5 * small.pixel, 0.5 * small.pixel, 30.0]
    );
    let level0 = draw((64, 64));
    for (x, y) in [(1.0, 1.0), (5.0, 9.0), (14.0, 6.0)] {
        let p = small.point(x, y);
        let (px, py) = level0.pixel_of(p);
        let grey = |image: &slice::SliceImage, (x, y): (f64, f64)| {
            let at = 4 * (y as usize * image.pixmap.width() as usize + x as usize);
            image.pixmap.data()[at]
        };
        assert_eq!(
            grey(&small, (x, y)),
            grey(&level0, (px.round(), py.round())),
            "{p:?}"
        );
    }
}

/// The value of [`ramp_volume`] at `p`, mm.
fn ramp(p: [f64; 3]) -> f64 {
    0.5 + p[0] + 0.5 * p[1] + 0.25 * p[2]
}

/// A linear ramp, 48×40×32 voxels 1, 1.5 and 2 mm apart (not integers: not a label volume).
fn ramp_volume() -> Volume {
    let dims = [48, 40, 32];
    let spacing = [1.0, 1.5, 2.0];
    let mut data = Vec::new();
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let p = [
                    x as f64 * spacing[0],
                    y as f64 * spacing[1],
                    z as f64 * spacing[2],
                ];
                data.push(ramp(p) as f32);
            }
        }
    }
    Volume::new(dims, spacing, VoxelType::F32, data).unwrap()
}

#[test]
fn a_coarse_slice_of_a_ramp_reads_the_values_where_level_0_has_them() {
    // A linear ramp is its own block mean at every pyramid level, and trilinear interpolation
    // gives it back exactly: a slice at level 1 reads the ramp's value at every pixel's point,
    // but within half a coarse voxel of the box's low edges, where the coarse grid (its voxel 0
    // at level 0's 0.5) stops and the value is its edge's. Greys exact to rounding.
    let v = ramp_volume();
    let renderer = Renderer::new(&v).unwrap();
    let (lo, hi) = (0.5, ramp([47.0, 58.5, 62.0]) as f32);
    let transfer = renderer
        .transfer(
            TransferChoice {
                preset: Preset::Auto,
                colormap: Colormap::Grey,
                window: Some((lo, hi)),
            },
            1.0,
        )
        .unwrap();
    let params = SliceParams {
        fit: (12, 12),
        letters: false,
        ..SliceParams::default()
    };
    let image = slice(&v, &transfer, Z, 31.0, &params).unwrap();
    assert_eq!(image.pyramid_level, 1, "{} mm a pixel", image.pixel);
    let mut checked = 0;
    for y in 0..image.pixmap.height() {
        for x in 0..image.pixmap.width() {
            let p = image.point(f64::from(x), f64::from(y));
            if p[0] < 0.5 || p[1] < 0.75 {
                continue;
            }
            let grey = (ramp(p) as f32 - lo) / (hi - lo);
            let expect = (grey.clamp(0.0, 1.0) * 255.0).round();
            let got = image.pixmap.data()[4 * (y * image.pixmap.width() + x) as usize];
            assert!(
                (f32::from(got) - expect).abs() <= 1.0,
                "{p:?}: {got} vs {expect}"
            );
            checked += 1;
        }
    }
    assert!(checked > 60, "{checked}");
}

#[test]
fn a_cut_face_of_a_ramp_reads_the_same_values_at_every_level() {
    // The lower slab alone, seen from above: its top is a cut face, the ramp's section there,
    // which every pyramid level holds exactly (a linear ramp is its own block mean, and
    // trilinear interpolation gives it back). The faces of levels 1 and 2 match level 0's to
    // two grey levels (face colours are a table of bins) but for a rim of pixels at the box's
    // edges, where a coarse grid stops short: measured 0.05% of the pixels further apart at
    // level 1, 2.1% at level 2, bound 5% (a grid off by half a voxel of level 0 puts 41% apart
    // at level 1).
    let none = Monitor::none();
    let v = ramp_volume();
    let renderer = Renderer::new(&v).unwrap();
    let stack = Stack {
        axis: Z,
        slices: 32,
        thickness: 2.0,
        offset: 0.0,
    };
    let layout = Layout::from_slabs(&stack, &[(0, 16), (16, 32)], None, Gap::Uniform, 0.5);
    let params = RenderParams {
        width: 64,
        height: 64,
        window: Some((0.5, ramp([47.0, 58.5, 62.0]) as f32)),
        camera: CameraParams {
            elevation: 89.0,
            ..CameraParams::default()
        },
        highlight: Some(0),
        solo: true,
        outlines: false,
        labels: false,
        shading: false,
        ..RenderParams::default()
    };
    let level0 = renderer.render_at(&layout, &params, 0, &none).unwrap();
    for k in [1, 2] {
        let coarse = renderer.render_at(&layout, &params, k, &none).unwrap();
        assert_eq!(coarse.camera, level0.camera);
        let (_, apart) = difference(&level0, &coarse, 2);
        assert!(apart < 0.05, "level {k}: {:.1}% apart", 100.0 * apart);
    }
}
