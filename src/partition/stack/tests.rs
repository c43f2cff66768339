//! Tests of slice stacks: coordinate slices are voxel planes, background is left out, oblique
//! stacks count only samples inside, and the geometry alone matches the stack.

use super::*;
use crate::progress::Monitor;
use crate::volume::Volume;
use crate::volume::VoxelType;

fn ramp() -> Volume {
    let data = (0..4 * 3 * 5).map(|i| i as f32).collect();
    Volume::new([4, 3, 5], [1.0, 1.0, 2.5], VoxelType::F32, data).unwrap()
}

#[test]
fn coordinate_slices_are_voxel_planes() {
    let v = ramp();
    let q = v.quantizer(60).unwrap();
    for (m, n) in [(0, 4), (1, 3), (2, 5)] {
        let mut axis = [0.0; 3];
        axis[m] = -1.0;
        let s = SliceStack::new(
            &v,
            axis,
            &StackParams {
                sampling: SamplingParams {
                    bins: 60,
                    ..SamplingParams::default()
                },
                ..StackParams::default()
            },
            &Monitor::none(),
        )
        .unwrap();
        assert_eq!(s.axis()[m], 1.0, "canonical");
        assert_eq!(s.slices(), n);
        assert_eq!(s.pixels(), 60 / n);
        let h = s.slice_histograms();
        // Every slice holds exactly the voxels of its plane.
        for slice in 0..n {
            let mut expect = vec![0u64; 60];
            for (i, &x) in v.voxels().iter().enumerate() {
                let coord = [i % 4, (i / 4) % 3, i / 12][m];
                if coord == slice {
                    expect[usize::from(q.bin(x).unwrap())] += 1;
                }
            }
            assert_eq!(
                &h[slice * 60..(slice + 1) * 60],
                &expect[..],
                "axis {m} slice {slice}"
            );
        }
    }
    let s = SliceStack::new(
        &v,
        [0.0, 0.0, 1.0],
        &StackParams::default(),
        &Monitor::none(),
    )
    .unwrap();
    assert_eq!(s.thickness(), 2.5);
    assert_eq!(s.mean(0, 1), Some((0..12).sum::<i32>() as f64 / 12.0));
}

#[test]
fn background_is_left_out() {
    let v = ramp();
    let params = StackParams {
        background: BackgroundRule::Below(29.0),
        ..StackParams::default()
    };
    let s = SliceStack::new(&v, [0.0, 0.0, 1.0], &params, &Monitor::none()).unwrap();
    let h = s.slice_histograms();
    let per_slice: Vec<u64> = h.chunks(32).map(|c| c.iter().sum()).collect();
    assert_eq!(per_slice, vec![0, 0, 6, 12, 12]);
    assert_eq!(s.mean(0, 2), None);
}

#[test]
fn oblique_stacks_count_only_samples_inside() {
    let v = ramp();
    let s = SliceStack::new(
        &v,
        [1.0, 1.0, 1.0],
        &StackParams::default(),
        &Monitor::none(),
    )
    .unwrap();
    let total: u64 = s.slice_histograms().iter().sum();
    // The box is 3 x 2 x 10 mm: about 60 samples at 1 mm.
    assert!((40..=90).contains(&total), "{total} samples");
    for p in 0..s.pixels() {
        assert!(s.column(p, 0, s.slices()).1.iter().all(|&c| c != MISSING));
    }
}

#[test]
fn the_geometry_alone_matches_the_stack() {
    let v = ramp();
    let params = StackParams::default();
    for axis in [
        [0.0, 0.0, 1.0],
        [0.0, -1.0, 0.0],
        [1.0, 2.0, 3.0],
        [-0.3, 0.1, 0.9],
    ] {
        let stack = SliceStack::new(&v, axis, &params, &Monitor::none()).unwrap();
        let (d, slices, thickness, offset) = slice_geometry(&v, axis, &params).unwrap();
        assert_eq!(d, stack.axis(), "{axis:?}");
        assert_eq!(slices, stack.slices(), "{axis:?}");
        assert_eq!(thickness.to_bits(), stack.thickness().to_bits(), "{axis:?}");
        assert_eq!(offset.to_bits(), stack.offset().to_bits(), "{axis:?}");
    }
}
