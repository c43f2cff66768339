//! Label volumes (segmentations, atlases): telling one from an image, since a label volume is
//! drawn with a colour per label and its pyramid levels take the most frequent label, not a mean.

use rayon::prelude::*;

use crate::volume::{Volume, Voxel};

/// The most distinct values a volume of integers may have to be drawn as labels (an atlas of
/// 116 regions has 117).
pub const MAX_LABELS: usize = 256;

/// The least share of voxels equal to their neighbour along x for a volume to be drawn as labels:
/// labels come in regions, while a ramp or a quantized image with few levels changes from voxel
/// to voxel.
const LABEL_RUNS: f64 = 0.8;

/// Distinct values with their counts, and how many voxels equal the one before them.
type Seen = (Vec<(f32, u64)>, u64);

/// The distinct values of `volume` with their voxel counts, when it looks like a label volume:
/// integer voxels with between 2 and [`MAX_LABELS`] distinct values, in regions (most voxels
/// equal to their neighbour).
pub fn label_values(volume: &Volume) -> Option<Vec<(f32, u64)>> {
    let (values, runs) = counted(volume)?;
    let total: u64 = values.iter().map(|v| v.1).sum();
    (values.len() >= 2 && runs as f64 >= LABEL_RUNS * total as f64).then_some(values)
}

/// The distinct values of `volume` with their voxel counts, for a volume its file declares a
/// label image (an OME-Zarr `labels/` image): integer voxels with at most [`MAX_LABELS`]
/// distinct values, however they lie.
pub fn declared_label_values(volume: &Volume) -> Option<Vec<(f32, u64)>> {
    counted(volume).map(|(values, _)| values)
}

/// The distinct values of an integer volume with their counts (sorted by first appearance),
/// and how many voxels equal the one before them; `None` past [`MAX_LABELS`] values.
fn counted(volume: &Volume) -> Option<Seen> {
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
    crate::volume::with_voxels!(volume.data(), |data| {
        data.par_chunks(1 << 16)
            .map(seen_in)
            .try_reduce(|| (Vec::new(), 0), merge)
    })
}

/// The distinct values of `chunk` with their counts, and how many equal the one before them;
/// `None` past [`MAX_LABELS`] values.
fn seen_in<T: Voxel>(chunk: &[T]) -> Option<Seen> {
    let mut seen: Vec<(f32, u64)> = Vec::new();
    let (mut last, mut runs) = (0, 0u64);
    for v in chunk {
        let v = v.to_f32();
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
}
