//! The slices themselves: drawn as radiologists read them when the orientation is known, their
//! pixels mapped back to the volume, and the strip of slab faces.

use slabscope::geometry::WorldTransform;
use slabscope::render::slice::{SliceFrame, SliceParams, faces, slice};
use slabscope::render::{Colormap, Preset, Renderer, Stack, Transfer, TransferChoice};
use slabscope::{Volume, VoxelType};

const N: usize = 21;

/// A cube of tissue (100) with bright markers (1000) near the high end of x and of y, and low
/// z, in voxel space; world axes as `linear` says (RAS+ rows).
fn marked(linear: [[f64; 3]; 3]) -> Volume {
    let data = (0..N * N * N)
        .map(|i| {
            let (x, y, z) = (i % N, (i / N) % N, i / (N * N));
            let near = |c: usize, at: usize| c.abs_diff(at) <= 1;
            let centre = |c: usize| near(c, N / 2);
            if (near(x, 17) && centre(y) && centre(z))
                || (centre(x) && near(y, 17) && centre(z))
                || (centre(x) && centre(y) && near(z, 3))
            {
                1000.0
            } else {
                100.0
            }
        })
        .collect();
    Volume::new([N; 3], [1.0; 3], VoxelType::I16, data)
        .unwrap()
        .with_transform(WorldTransform::ras(linear, [0.0; 3]))
}

const RAS: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
const LPS: [[f64; 3]; 3] = [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]];

fn grey(v: &Volume) -> Transfer {
    let look = TransferChoice {
        preset: Preset::Auto,
        colormap: Colormap::Grey,
        window: Some((0.0, 1000.0)),
    };
    Renderer::new(v).unwrap().transfer(look, 1.0).unwrap()
}

/// Where the brightest pixels of a slice are, as fractions of its width and height.
fn bright_spots(v: &Volume, axis: [f64; 3], at: f64) -> Vec<(f64, f64)> {
    let params = SliceParams {
        fit: (105, 105),
        letters: false,
        ..SliceParams::default()
    };
    let image = slice(v, &grey(v), axis, at, &params).unwrap();
    let (w, h) = (image.pixmap.width(), image.pixmap.height());
    let d = image.pixmap.data();
    (0..w * h)
        .filter(|&i| d[4 * i as usize] > 240)
        .map(|i| {
            (
                f64::from(i % w) / f64::from(w),
                f64::from(i / w) / f64::from(h),
            )
        })
        .collect()
}

fn mean(spots: &[(f64, f64)]) -> (f64, f64) {
    let n = spots.len() as f64;
    assert!(n > 0.0, "no marker shows");
    (
        spots.iter().map(|s| s.0).sum::<f64>() / n,
        spots.iter().map(|s| s.1).sum::<f64>() / n,
    )
}

#[test]
fn axial_slices_show_the_patients_right_on_the_left_and_anterior_up() {
    let centre = (N / 2) as f64;
    // RAS: the +x marker is on the patient's right, the +y marker anterior.
    let ras = marked(RAS);
    let (x, y) = mean(&bright_spots(&ras, [0.0, 0.0, 1.0], centre));
    assert!(x < 0.5 && y < 0.5, "RAS: markers at ({x:.2}, {y:.2})");
    let spots = bright_spots(&ras, [0.0, 0.0, 1.0], centre);
    let right = mean(
        &spots
            .iter()
            .copied()
            .filter(|s| s.1 > 0.4)
            .collect::<Vec<_>>(),
    );
    assert!(right.0 < 0.3, "the right marker on the left: {right:?}");
    let front = mean(
        &spots
            .iter()
            .copied()
            .filter(|s| s.0 > 0.4)
            .collect::<Vec<_>>(),
    );
    assert!(front.1 < 0.3, "the anterior marker up: {front:?}");
    // LPS: the same voxels are on the patient's left and posterior.
    let lps = marked(LPS);
    let spots = bright_spots(&lps, [0.0, 0.0, 1.0], centre);
    let left = mean(
        &spots
            .iter()
            .copied()
            .filter(|s| s.1 < 0.6)
            .collect::<Vec<_>>(),
    );
    assert!(left.0 > 0.7, "the left marker on the right: {left:?}");
    let back = mean(
        &spots
            .iter()
            .copied()
            .filter(|s| s.0 < 0.6)
            .collect::<Vec<_>>(),
    );
    assert!(back.1 > 0.7, "the posterior marker down: {back:?}");
}

#[test]
fn coronal_and_sagittal_slices_have_superior_up_and_the_conventional_sides() {
    let v = marked(RAS);
    let centre = (N / 2) as f64;
    // Coronal (across y): the right marker on the left, the low-z (inferior) marker down.
    let spots = bright_spots(&v, [0.0, 1.0, 0.0], centre);
    let right = mean(
        &spots
            .iter()
            .copied()
            .filter(|s| s.1 < 0.7)
            .collect::<Vec<_>>(),
    );
    assert!(right.0 < 0.3, "coronal: right on the left: {right:?}");
    let low = mean(
        &spots
            .iter()
            .copied()
            .filter(|s| s.0 > 0.4)
            .collect::<Vec<_>>(),
    );
    assert!(low.1 > 0.7, "coronal: inferior down: {low:?}");
    // Sagittal (across x): anterior on the left, inferior down.
    let spots = bright_spots(&v, [1.0, 0.0, 0.0], centre);
    let front = mean(
        &spots
            .iter()
            .copied()
            .filter(|s| s.1 < 0.7)
            .collect::<Vec<_>>(),
    );
    assert!(front.0 < 0.3, "sagittal: anterior on the left: {front:?}");
    for (axis, letters) in [
        ([0.0, 0.0, 1.0], ['R', 'L', 'A', 'P']),
        ([0.0, 1.0, 0.0], ['R', 'L', 'S', 'I']),
        ([1.0, 0.0, 0.0], ['A', 'P', 'S', 'I']),
    ] {
        let frame = SliceFrame::new(&v, axis).unwrap();
        assert_eq!(frame.letters, Some(letters), "{axis:?}");
    }
    let lps = marked(LPS);
    let frame = SliceFrame::new(&lps, [0.0, 0.0, 1.0]).unwrap();
    assert_eq!(
        frame.letters,
        Some(['R', 'L', 'A', 'P']),
        "letters name the world"
    );
}

#[test]
fn without_an_orientation_slices_have_no_letters_and_x_to_the_right() {
    let data = (0..N * N * N).map(|i| (i % N) as f32).collect();
    let v = Volume::new([N; 3], [1.0; 3], VoxelType::F32, data).unwrap();
    let frame = SliceFrame::new(&v, [0.0, 0.0, 1.0]).unwrap();
    assert_eq!(frame.letters, None);
    assert_eq!(frame.right, [1.0, 0.0, 0.0]);
    assert_eq!(
        frame.up,
        [0.0, -1.0, 0.0],
        "y down, as image viewers show it"
    );
}

#[test]
fn slice_pixels_map_back_to_the_volume() {
    let v = marked(RAS);
    for axis in [[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [1.0, 1.0, 1.0]] {
        let image = slice(&v, &grey(&v), axis, 12.0, &SliceParams::default()).unwrap();
        for (x, y) in [(3.0, 7.0), (100.0, 40.5), (250.0, 260.0)] {
            let p = image.point(x, y);
            let (bx, by) = image.pixel_of(p);
            assert!((bx - x).abs() < 1e-9 && (by - y).abs() < 1e-9, "{axis:?}");
            let n: f64 = axis.iter().map(|c| c * c).sum::<f64>().sqrt();
            let along: f64 = (0..3).map(|m| p[m] * axis[m] / n).sum();
            assert!((along - 12.0).abs() < 1e-9, "{axis:?}: on the plane");
        }
        // The slice is fit into the size asked, keeping its shape.
        assert!(image.pixmap.width() <= 512 && image.pixmap.height() <= 512);
        assert!(image.pixmap.width() == 512 || image.pixmap.height() == 512);
    }
}

#[test]
fn the_faces_strip_has_a_column_per_slab_and_shows_each_face() {
    let v = marked(RAS);
    let stack = Stack {
        axis: [0.0, 0.0, 1.0],
        slices: N,
        thickness: 1.0,
        offset: 0.0,
    };
    // The z marker is in slices 2 to 4: slab 0's last slice (3) shows it, slab 1's do not.
    let strip = faces(&v, &grey(&v), &stack, &[(0, 4), (4, N)], (50, 50)).unwrap();
    assert_eq!((strip.width(), strip.height()), (2 * 54 + 4, 2 * 54 + 4));
    let bright = |x0: u32, y0: u32| {
        (y0..y0 + 50)
            .flat_map(|y| (x0..x0 + 50).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let i = 4 * (y * strip.width() + x) as usize;
                // White, not the letters' yellow.
                strip.data()[i..i + 3].iter().all(|&c| c > 240)
            })
            .count()
    };
    assert!(bright(4, 4) > 0, "slab 0's upper face shows the marker");
    assert_eq!(bright(58, 4), 0, "slab 1's upper face does not");
}
