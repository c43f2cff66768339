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

/// Along each coordinate axis of volumes wider than a run of pixels (so that a task's pixels
/// are taken in several runs, some cut short by a row's end), every pixel's column holds its
/// voxels' symbols in order, background left out.
#[test]
fn a_coordinate_cut_is_every_pixels_voxel_column() {
    for dims in [[70, 67, 3], [3, 70, 67], [67, 3, 70]] {
        let len = dims.iter().product::<usize>();
        let data: Vec<f32> = (0..len).map(|i| ((i * 7919) % 1009) as f32).collect();
        let v = Volume::new(dims, [1.0; 3], VoxelType::F32, data).unwrap();
        let q = v.quantizer(32).unwrap();
        let below = 100.0;
        let stride = [1, dims[0], dims[0] * dims[1]];
        for m in 0..3 {
            let mut axis = [0.0; 3];
            axis[m] = 1.0;
            let params = StackParams {
                background: BackgroundRule::Below(below),
                ..StackParams::default()
            };
            let s = SliceStack::new(&v, axis, &params, &Monitor::none()).unwrap();
            let a = usize::from(m == 0);
            let b = 3 - m - a;
            assert_eq!(s.pixels(), dims[a] * dims[b]);
            for p in 0..s.pixels() {
                let base = (p % dims[a]) * stride[a] + (p / dims[a]) * stride[b];
                let expect: Vec<u8> = (0..dims[m])
                    .map(|k| {
                        let x = v.voxels()[base + k * stride[m]];
                        if x <= below {
                            MISSING
                        } else {
                            q.bin(x).unwrap()
                        }
                    })
                    .collect();
                assert_eq!(
                    s.column(p, 0, dims[m]),
                    (0, &expect[..]),
                    "{dims:?} axis {m} pixel {p}"
                );
            }
        }
    }
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

/// A noisy volume larger than a band of rows and a tile of columns, with a missing voxel.
fn noisy() -> Volume {
    let mut state = 7u64;
    let mut data: Vec<f32> = (0..41 * 37 * 29)
        .map(|i| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (i % 41) as f32 + (state >> 40) as f32 / 1e6
        })
        .collect();
    data[41 * 37 * 14 + 41 * 18 + 20] = f32::NAN;
    Volume::new([41, 37, 29], [1.0, 0.8, 1.3], VoxelType::F32, data).unwrap()
}

#[test]
fn an_oblique_cut_is_every_rays_samples_in_order_and_strips_add_to_the_whole() {
    use crate::volume::interpolate::Interpolator;
    let v = noisy();
    let it = Interpolator::new(&v);
    for background in [
        BackgroundRule::None,
        BackgroundRule::Below(12.5),
        BackgroundRule::Auto,
    ] {
        for (axis, spacing) in [
            ([0.3, 0.5, 0.8], None),
            ([-0.7, 0.1, 0.4], Some(0.7)),
            ([1.0, 1.0, 1.0], Some(1.6)),
        ] {
            let params = StackParams {
                sampling: SamplingParams {
                    ray_spacing: spacing,
                    sample_spacing: spacing,
                    ..SamplingParams::default()
                },
                background,
            };
            let cutter = Cutter::new(&v, axis, &params, &Monitor::none()).unwrap();
            let lattice = cutter.lattice.as_ref().unwrap();
            let stack = SliceStack::new(&v, axis, &params, &Monitor::none()).unwrap();
            // The definition: ray after ray, each sample's symbol in order.
            let ((_, _), (j0, j1)) = lattice.ray_ranges();
            let (k_first, _) = lattice.sample_range();
            let (mut symbols, mut columns) = (Vec::new(), Vec::new());
            let mut sums = vec![0.0f64; stack.slices()];
            let mut counts = vec![0u64; stack.slices()];
            let mut positions = vec![0u64; stack.slices()];
            for j in j0..=j1 {
                for ray in lattice.row(j) {
                    columns.push(Column {
                        offset: symbols.len(),
                        first: (ray.k0 - k_first) as u32,
                        len: ray.len() as u32,
                    });
                    for k in ray.k0..=ray.k1 {
                        let p = ray.at(k);
                        let (value, index) = (it.sample(p), it.nearest(p));
                        let s = (k - k_first) as usize;
                        symbols.push(cutter.symbol_in(cutter.background.test(), index, value));
                        positions[s] += 1;
                        if value.is_finite() && !cutter.background.contains(index, value) {
                            sums[s] += f64::from(value);
                            counts[s] += 1;
                        }
                    }
                }
            }
            let case = format!("{background:?} {axis:?} {spacing:?}");
            assert!(columns.len() > 16 * 16, "{case}: more rays than a tile");
            assert_eq!(stack.columns, columns, "{case}");
            assert_eq!(stack.symbols, symbols, "{case}");
            assert_eq!(stack.positions, positions, "{case}");
            assert_eq!(stack.counts, counts, "{case}");
            for (a, b) in stack.sums.iter().zip(&sums) {
                assert!((a - b).abs() <= 1e-9 * b.abs().max(1.0), "{case}: {a} {b}");
            }
            // Cut in strips of 5, 1 and the rest of the rows, the sums the same bit for bit.
            let rows = cutter.rows();
            let mut strip_sums = SliceSums::new(cutter.slices());
            let mut strip_symbols = Vec::new();
            for part in [0..5, 5..6, 6..rows] {
                let mut add = |row: &SliceSums| strip_sums.add_onto(row);
                let strip = cutter.cut(part, Some(&mut add), &Monitor::none()).unwrap();
                strip_symbols.extend(strip.symbols);
            }
            assert_eq!(strip_symbols, symbols, "{case}");
            assert_eq!(strip_sums.counts, stack.counts, "{case}");
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&strip_sums.sums), bits(&stack.sums), "{case}");
        }
    }
}
