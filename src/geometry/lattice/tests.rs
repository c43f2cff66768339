//! Tests of the ray lattice: its rays against the definition's divisions, its index
//! coordinates, its bounds, and the sample budget of its spacings.

use super::*;
use crate::testing::Lcg;

#[test]
fn axis_aligned_rays_are_the_voxel_columns() {
    let l = Lattice::new([4, 3, 5], [1.0; 3], [0.0, 0.0, 1.0], 1.0, 1.0, [0.0; 3]).unwrap();
    assert_eq!(l.ray_ranges(), ((0, 3), (0, 2)));
    let r = l.ray(2, 1).unwrap();
    assert_eq!((r.k0, r.k1), (0, 4));
    assert_eq!(r.at(3), [2.0, 1.0, 3.0]);
    assert!(l.ray(4, 0).is_none());
    assert!(l.ray(-1, 0).is_none());
}

/// `Lattice::ray`'s sample range as the definition computes it: a division per bound.
fn rays_by_division(l: &Lattice, i: i64, j: i64) -> Option<(i64, i64)> {
    let base = l.point(i, j, 0);
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for m in 0..3 {
        let eps = 1e-9 * (1.0 + l.extent[m]);
        let dm = l.sample_spacing * l.d[m];
        if dm.abs() < 1e-12 {
            if base[m] < -eps || base[m] > l.extent[m] + eps {
                return None;
            }
            continue;
        }
        let t1 = (-eps - base[m]) / dm;
        let t2 = (l.extent[m] + eps - base[m]) / dm;
        lo = lo.max(t1.min(t2));
        hi = hi.min(t1.max(t2));
    }
    let (k0, k1) = (lo.ceil() as i64, hi.floor() as i64);
    (k0 <= k1).then_some((k0, k1))
}

#[test]
fn rays_are_the_ones_division_gives() {
    // Random axes, spacings and phases, and lattices whose samples fall on the box's faces
    // (whole steps from a whole phase), where a bound is a whole number.
    let mut lcg = Lcg::new(11);
    let mut unit = move || (lcg.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
    let mut cases = vec![
        ([7, 5, 9], [1.0; 3], [1.0, 0.0, 0.0], 1.0, 1.0, [0.0; 3]),
        (
            [7, 5, 9],
            [0.5, 1.0, 2.0],
            [1.0, 1.0, 0.0],
            0.5,
            0.5,
            [0.0; 3],
        ),
        ([7, 5, 9], [1.0; 3], [1.0, 2.0, 2.0], 1.0, 1.0, [0.0; 3]),
        (
            [6, 6, 6],
            [1.0; 3],
            [0.0, 3.0, 4.0],
            1.0,
            1.0,
            [1.0, 0.0, 2.0],
        ),
    ];
    for _ in 0..40 {
        let axis = [unit() - 0.5, unit() - 0.5, unit() - 0.5];
        let spacing = [0.3 + unit(), 0.3 + unit(), 0.3 + unit()];
        let phase = [unit(), unit(), unit()];
        cases.push(([9, 8, 11], spacing, axis, 0.2 + unit(), 0.2 + unit(), phase));
    }
    let mut rays = 0;
    for (dims, spacing, axis, x, y, phase) in cases {
        let l = Lattice::new(dims, spacing, axis, x, y, phase).unwrap();
        let ((i0, i1), (j0, j1)) = l.ray_ranges();
        for j in j0 - 1..=j1 + 1 {
            for i in i0 - 1..=i1 + 1 {
                let got = l.ray(i, j).map(|r| (r.k0, r.k1));
                assert_eq!(got, rays_by_division(&l, i, j), "{axis:?} ray {i}, {j}");
                rays += usize::from(got.is_some());
            }
        }
    }
    assert!(rays > 1000, "{rays} rays");
}

#[test]
fn index_coordinates_are_divisions_by_the_spacing() {
    let p = [0.1, -7.3, 1e-310];
    for spacing in [[1.0, 2.0, 0.25], [0.7, 3.0, 1.5], [1.0, 1.0, 0.125]] {
        let l = Lattice::new([4, 4, 4], spacing, [1.0, 2.0, 3.0], 1.0, 1.0, [0.0; 3]).unwrap();
        let exact: [f64; 3] = std::array::from_fn(|m| p[m] / spacing[m]);
        assert_eq!(l.to_index(p).map(f64::to_bits), exact.map(f64::to_bits));
    }
}

#[test]
fn oblique_rays_stay_inside_the_box() {
    let l = Lattice::new(
        [10, 12, 9],
        [1.0, 0.5, 2.0],
        [1.0, 2.0, 3.0],
        0.5,
        0.5,
        [0.3, 0.7, 0.1],
    )
    .unwrap();
    let ((i0, i1), (j0, j1)) = l.ray_ranges();
    let mut samples = 0;
    for i in i0..=i1 {
        for j in j0..=j1 {
            if let Some(r) = l.ray(i, j) {
                for k in [r.k0, r.k1] {
                    let p = r.at(k);
                    assert!(p[0] > -1e-6 && p[0] < 9.0 + 1e-6, "{p:?}");
                    assert!(p[1] > -1e-6 && p[1] < 11.0 + 1e-6, "{p:?}");
                    assert!(p[2] > -1e-6 && p[2] < 8.0 + 1e-6, "{p:?}");
                }
                assert!(!l.inside(l.point(i, j, r.k0 - 1)) && !l.inside(l.point(i, j, r.k1 + 1)));
                samples += r.len();
            }
        }
    }
    // The box is 9 x 5.5 x 16 mm = 792 mm³; each sample stands for 0.5³ mm³.
    let expected = 792.0 / 0.125;
    assert!(
        (samples as f64 / expected - 1.0).abs() < 0.1,
        "{samples} samples, about {expected} expected"
    );
}

#[test]
fn floor_and_ceil_match_the_library() {
    for x in [
        0.0,
        -0.0,
        0.5,
        -0.5,
        1.0,
        -1.0,
        2.999_999,
        -2.000_001,
        1e15 + 0.5,
        -7.25,
    ] {
        assert_eq!(floor_i64(x), x.floor() as i64, "{x}");
        assert_eq!(ceil_i64(x), x.ceil() as i64, "{x}");
    }
}

#[test]
fn rounding_halves_away_from_zero_like_the_library() {
    for x in [
        0.0,
        0.5,
        -0.5,
        1.5,
        -1.5,
        2.5,
        0.499_999_999_999_999_94,
        -2.4,
        7.0,
        1e15 + 0.5,
        -3.75,
        4_294_967_295.5,
    ] {
        assert_eq!(round_half_away(x), x.round() as i64, "{x}");
    }
    let mut lcg = Lcg::with_increment(3, 1);
    for _ in 0..10_000 {
        let state = lcg.next_u64();
        let x = ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 1e12;
        assert_eq!(round_half_away(x), x.round() as i64, "{x}");
    }
}

#[test]
fn a_lattice_finer_than_the_budget_is_coarsened_finest_first() {
    let sampling = |x: Option<f64>, y: Option<f64>| SamplingParams {
        bins: 32,
        ray_spacing: x,
        sample_spacing: y,
    };
    let dims = [200, 200, 200];
    // The defaults take one sample a voxel: untouched.
    let (x, y, f) = sampling(None, None).spacings(dims, [1.0; 3]).unwrap();
    assert_eq!((x, y, f), (1.0, 1.0, 1.0));
    // Rays 100 times finer: the rays alone are coarsened, to 16 samples a voxel.
    let (x, y, _) = sampling(Some(0.01), None).spacings(dims, [1.0; 3]).unwrap();
    assert_eq!(y, 1.0);
    assert!((1.0 / (x * x * y) - 16.0).abs() < 1e-6, "{x}");
    // A header's tiny spacing makes both fine: both coarsened alike.
    let (x, y, f) = sampling(None, None)
        .spacings(dims, [1e-4, 1.0, 1.0])
        .unwrap();
    assert!((x - y).abs() < 1e-12 && f > 1.0);
    let samples = 200.0 * 1e-4 * 200.0 * 200.0 / (x * x * y);
    assert!((samples / (16.0 * 8e6) - 1.0).abs() < 1e-6, "{samples}");
    assert!(
        sampling(None, None)
            .budget_note(dims, [1e-4, 1.0, 1.0])
            .is_some()
    );
    assert!(sampling(None, None).budget_note(dims, [1.0; 3]).is_none());
}

/// `could_hold` is false only where no ray of any phase holds `block` samples: checked against
/// every ray of shifted lattices over thin and flat boxes, and false across a one-voxel-thick
/// volume along every axis that crosses it.
#[test]
fn a_lattice_too_thin_for_a_block_holds_none_in_any_phase() {
    let flat = Lattice::new([8, 8, 1], [1.0; 3], [0.6, 0.0, 0.8], 1.0, 1.0, [0.0; 3]).unwrap();
    assert!(!flat.could_hold(3) && flat.could_hold(1));
    let along = Lattice::new([8, 8, 1], [1.0; 3], [0.6, 0.8, 0.0], 1.0, 1.0, [0.0; 3]).unwrap();
    assert!(along.could_hold(3));
    let mut rng = Lcg::new(7);
    for case in 0..300 {
        let dims = [1 + (case % 3), 2 + (case % 5), 1 + (case % 2) * 3];
        let mut unit = || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        let axis = crate::geometry::normalize(std::array::from_fn(|_| unit() * 2.0 - 1.0)).unwrap();
        let phase = std::array::from_fn(|_| unit());
        let Ok(l) = Lattice::new(dims, [0.7, 1.0, 1.3], axis, 0.5, 0.6, phase) else {
            continue;
        };
        let ((i0, i1), (j0, j1)) = l.ray_ranges();
        let longest = (i0..=i1)
            .flat_map(|i| (j0..=j1).map(move |j| (i, j)))
            .filter_map(|(i, j)| l.ray(i, j))
            .map(|r| (r.k1 - r.k0 + 1) as usize)
            .max()
            .unwrap_or(0);
        for block in 1..6 {
            assert!(
                l.could_hold(block) || longest < block,
                "{dims:?} {axis:?}: a ray of {longest} samples, block {block}"
            );
        }
    }
}
