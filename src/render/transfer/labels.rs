//! Label volumes: telling one from an image (integers in regions, few distinct values) and the
//! categorical transfer function that gives each label a colour of its own.

use super::{Colormap, Transfer, check_step};
use crate::error::Result;
use crate::volume::Volume;

/// The most distinct values a volume of integers may have to be drawn as labels (an atlas of
/// 116 regions has 117).
pub const MAX_LABELS: usize = 256;

/// The least share of voxels equal to their neighbour along x for a volume to be drawn as labels:
/// labels come in regions, while a ramp or a quantized image with few levels changes from voxel
/// to voxel.
const LABEL_RUNS: f64 = 0.8;

/// Opacity of a label per reference millimetre: solid after a few voxels.
const LABEL_OPACITY: f32 = 0.5;

/// Distinct colours for labels (Glasbey's first, without black and white), in order.
const PALETTE: [[u8; 3]; 20] = [
    [230, 25, 75],
    [60, 180, 75],
    [255, 225, 25],
    [0, 130, 200],
    [245, 130, 48],
    [145, 30, 180],
    [70, 240, 240],
    [240, 50, 230],
    [210, 245, 60],
    [250, 190, 212],
    [0, 128, 128],
    [220, 190, 255],
    [170, 110, 40],
    [255, 250, 200],
    [128, 0, 0],
    [170, 255, 195],
    [128, 128, 0],
    [255, 215, 180],
    [0, 0, 128],
    [128, 128, 128],
];

impl Transfer {
    /// A categorical transfer function for a label volume of `labels` (value, voxel count): the
    /// most common label (the background) clear, every other a distinct colour of the palette,
    /// in ascending order of value.
    pub fn for_labels(labels: &[(f32, u64)], step: f64, reference: f64) -> Result<Self> {
        check_step(step, reference)?;
        let mut labels = labels.to_vec();
        labels.sort_by(|a, b| a.0.total_cmp(&b.0));
        let background = labels
            .iter()
            .enumerate()
            .max_by_key(|(_, l)| l.1)
            .map_or(0, |(i, _)| i);
        let a = 1.0 - (1.0 - LABEL_OPACITY).powf((step / reference) as f32);
        let (mut table, mut face, mut opacity) = (Vec::new(), Vec::new(), Vec::new());
        let mut colour = PALETTE.iter().cycle();
        for i in 0..labels.len() {
            if i == background {
                table.push([0.0; 4]);
                face.push([0.0; 4]);
                opacity.push(0.0);
                continue;
            }
            let c = colour
                .next()
                .expect("the palette cycles")
                .map(|c| f32::from(c) / 255.0);
            table.push([c[0] * a, c[1] * a, c[2] * a, a]);
            face.push([c[0], c[1], c[2], 1.0]);
            opacity.push(a);
        }
        let values: Vec<f32> = labels.iter().map(|l| l.0).collect();
        let window = (values[0], values[values.len() - 1]);
        Ok(Self {
            min: window.0,
            scale: 0.0,
            table,
            face,
            window,
            mip: window,
            colormap: Colormap::Grey,
            opacity,
            labels: Some(values),
        })
    }
}

/// Distinct values with their counts, and how many voxels equal the one before them.
type Seen = (Vec<(f32, u64)>, u64);

/// The distinct values of `volume` with their voxel counts, when it looks like a label volume:
/// integer voxels with between 2 and [`MAX_LABELS`] distinct values, in regions (most voxels
/// equal to their neighbour).
pub fn label_values(volume: &Volume) -> Option<Vec<(f32, u64)>> {
    use rayon::prelude::*;
    if !volume.voxel_type().is_integer() {
        return None;
    }
    let merge = |(mut a, ra): Seen, (b, rb): Seen| -> Option<Seen> {
        for (v, n) in b {
            match a.iter_mut().find(|e| e.0 == v) {
                Some(e) => e.1 += n,
                None => a.push((v, n)),
            }
        }
        (a.len() <= MAX_LABELS).then_some((a, ra + rb))
    };
    let values = volume
        .voxels()
        .par_chunks(1 << 16)
        .map(|chunk| {
            let mut seen: Vec<(f32, u64)> = Vec::new();
            let (mut last, mut runs) = (0, 0u64);
            for &v in chunk {
                if v.is_nan() {
                    continue;
                }
                if seen.get(last).is_some_and(|e| e.0 == v) {
                    seen[last].1 += 1;
                    runs += 1;
                    continue;
                }
                match seen.iter().position(|e| e.0 == v) {
                    Some(i) => {
                        seen[i].1 += 1;
                        last = i;
                    }
                    None if seen.len() == MAX_LABELS => return None,
                    None => {
                        last = seen.len();
                        seen.push((v, 1));
                    }
                }
            }
            Some((seen, runs))
        })
        .try_reduce(|| (Vec::new(), 0), merge)?;
    let (values, runs) = values;
    let total: u64 = values.iter().map(|v| v.1).sum();
    (values.len() >= 2 && runs as f64 >= LABEL_RUNS * total as f64).then_some(values)
}
