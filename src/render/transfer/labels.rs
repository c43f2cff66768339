//! Label volumes: telling one from an image (integers in regions, few distinct values) and the
//! categorical transfer function that gives each label a colour of its own.

use super::{Colormap, Transfer, check_step};
use crate::error::Result;
pub use crate::volume::labels::{MAX_LABELS, label_values};

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
