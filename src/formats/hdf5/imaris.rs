//! Imaris files (`.ims`, Imaris 5.5's layout in HDF5): the volume of a time point and channel
//! at the finest resolution level, `DataSet/ResolutionLevel 0/TimePoint T/Channel C/Data`,
//! cut to the image's size (`ImageSizeX`, `Y`, `Z` of its channel's group: the data is padded
//! to whole chunks), its voxel size the extents of `DataSetInfo/Image` (`ExtMin0` … `ExtMax2`,
//! in its `Unit`, µm when none) over its size. Imaris writes every attribute as text. A coarser
//! resolution level on the pyramid's grid is the first picture (`load_preview`).

use crate::volume::pyramid;
use std::path::Path;

use rust_hdf5::H5File;

use super::pick::Found;
use crate::error::Result;
use crate::formats::LoadOptions;
use crate::formats::data::{one_channel, pick_volume};

/// The group of the finest resolution level.
const LEVEL0: &str = "DataSet/ResolutionLevel 0";

/// The most resolution levels looked at.
const MAX_LEVELS: usize = 32;

/// The most time points or channels counted.
const MAX_COUNT: usize = 1 << 16;

/// What of an Imaris file is read.
#[derive(Debug)]
pub(super) struct Imaris {
    /// The dataset's path (without the leading `/`).
    pub path: String,
    /// The image's size along x, y, z, where the channel's group says it.
    pub size: Option<[usize; 3]>,
    /// The voxel size along x, y, z in mm, where `DataSetInfo/Image` gives it.
    pub spacing: Option<[f64; 3]>,
}

/// The group of time point `t`, channel `c` at resolution level `level`.
fn group(level: usize, t: usize, c: usize) -> String {
    format!("DataSet/ResolutionLevel {level}/TimePoint {t}/Channel {c}")
}

/// The dataset of time point `t`, channel `c` at the finest level.
fn data(t: usize, c: usize) -> String {
    format!("{LEVEL0}/TimePoint {t}/Channel {c}/Data")
}

/// What to read of `file` when it is laid out as Imaris writes (its first time point's first
/// channel at `DataSet/ResolutionLevel 0`): the time point `--volume` names and the channel
/// `--channel` does, checked against how many there are, at resolution level `level`; `None`
/// for any other file.
pub(super) fn pick(
    path: &Path,
    file: &H5File,
    found: &[Found],
    opts: &LoadOptions,
    level: usize,
    notes: &mut Vec<String>,
) -> Result<Option<Imaris>> {
    let has = |p: &str| found.iter().any(|f| f.path == p);
    if !has(&data(0, 0)) {
        return Ok(None);
    }
    let times = (0..MAX_COUNT).take_while(|&t| has(&data(t, 0))).count();
    let channels = (0..MAX_COUNT).take_while(|&c| has(&data(0, c))).count();
    let (t, _) = pick_volume(path, times, opts.part.volume, notes)?;
    if opts.part.channel >= channels {
        return Err(one_channel(path, channels, opts.part.channel));
    }
    if channels > 1 {
        notes.push(format!(
            "Imaris file with {channels} channels: loaded channel {}",
            opts.part.channel
        ));
    }
    let c = opts.part.channel;
    let root = file.root_group();
    let number = |group: &str, key: &str| -> Option<f64> {
        let text = root.group(group).ok()?.attr_string(key).ok()?;
        text.trim().parse::<f64>().ok().filter(|v| v.is_finite())
    };
    let channel = group(level, t, c);
    let size = ["ImageSizeX", "ImageSizeY", "ImageSizeZ"]
        .map(|k| number(&channel, k).filter(|&v| v >= 1.0 && v.fract() == 0.0));
    let size = match size {
        [Some(x), Some(y), Some(z)] => Some([x as usize, y as usize, z as usize]),
        _ => None,
    };
    let spacing = image_spacing(&|k| number("DataSetInfo/Image", k), file, size);
    Ok(Some(Imaris {
        path: format!("{channel}/Data"),
        size,
        spacing,
    }))
}

/// The voxel size along x, y, z in mm: each extent (`ExtMax` − `ExtMin`) over the image's size
/// in voxels, in the `Unit` of `DataSetInfo/Image` (µm when none is given).
fn image_spacing(
    number: &dyn Fn(&str) -> Option<f64>,
    file: &H5File,
    size: Option<[usize; 3]>,
) -> Option<[f64; 3]> {
    let size = size?;
    let unit = file
        .root_group()
        .group("DataSetInfo/Image")
        .ok()
        .and_then(|g| g.attr_string("Unit").ok())
        .unwrap_or_else(|| "um".into());
    let to_mm = match unit.trim() {
        "um" | "µm" | "micron" => 1e-3,
        "nm" => 1e-6,
        "mm" => 1.0,
        _ => return None,
    };
    let mut spacing = [0.0; 3];
    for (m, s) in spacing.iter_mut().enumerate() {
        let extent = number(&format!("ExtMax{m}"))? - number(&format!("ExtMin{m}"))?;
        *s = extent / size[m] as f64 * to_mm;
    }
    spacing
        .iter()
        .all(|s| s.is_finite() && *s > 0.0)
        .then_some(spacing)
}

/// The coarser resolution level to preview of an Imaris file, with the pyramid level it is and
/// the finest level's size: the finest level on the pyramid's grid (each level's size the
/// last's halved, rounding up) with at most `max_voxels` voxels; `None` when the finest level
/// has no more, or none is on the grid.
pub(super) fn preview_level(
    path: &Path,
    file: &H5File,
    found: &[Found],
    opts: &LoadOptions,
    max_voxels: usize,
) -> Result<Option<(usize, usize, [usize; 3])>> {
    let mut notes = Vec::new();
    let mut size_at = |level: usize| {
        pick(path, file, found, opts, level, &mut notes).map(|i| i.and_then(|i| i.size))
    };
    let Some(dims0) = size_at(0)? else {
        return Ok(None);
    };
    let chain = pyramid::chain_dims(dims0, &pyramid::steps_after(dims0, &[]));
    let wanted = pyramid::level_within(&chain, max_voxels);
    if wanted == 0 {
        return Ok(None);
    }
    let (t, c) = (opts.part.volume, opts.part.channel);
    let has = |p: &str| found.iter().any(|f| f.path == p);
    let mut best: Option<(usize, usize)> = None;
    for level in (1..MAX_LEVELS).take_while(|&l| has(&format!("{}/Data", group(l, t, c)))) {
        let Some(size) = size_at(level)? else {
            continue;
        };
        let mut d = dims0;
        let k = (1..=64).find(|_| {
            d = crate::volume::pyramid::coarser_dims(d);
            d == size
        });
        if let Some(k) = k.filter(|&k| k >= wanted) {
            best = Some(best.map_or((k, level), |b| b.min((k, level))));
        }
    }
    Ok(best.map(|(k, level)| (level, k, dims0)))
}

/// Cuts the voxel bytes `bytes` of a volume of `dims` (x fastest, `elem` bytes a voxel) to its
/// first `size` voxels along each axis, in place; an error naming the dataset `name` when
/// `size` is larger.
pub(super) fn crop(
    path: &Path,
    name: &str,
    bytes: &mut Vec<u8>,
    dims: [usize; 3],
    size: [usize; 3],
    elem: usize,
) -> Result<()> {
    if (0..3).any(|m| size[m] > dims[m]) {
        return Err(crate::error::Error::format(
            path,
            format!("Imaris says the image is {size:?} voxels, more than dataset {name} holds"),
        ));
    }
    cut(bytes, dims, size, elem);
    Ok(())
}

/// [`crop`], its size checked.
fn cut(bytes: &mut Vec<u8>, dims: [usize; 3], size: [usize; 3], elem: usize) {
    let row = size[0] * elem;
    let mut to = 0;
    for z in 0..size[2] {
        for y in 0..size[1] {
            let from = ((z * dims[1] + y) * dims[0]) * elem;
            bytes.copy_within(from..from + row, to);
            to += row;
        }
    }
    bytes.truncate(to);
}

/// The grid of level 0 (of `dims0`) of the file `coarse` was read from as a coarser level: the
/// same extent (an Imaris image's `ExtMin` to `ExtMax`) cut into `dims0` voxels, so each axis's
/// spacing scaled by its voxel counts' ratio and the first voxel's centre moved to half a fine
/// voxel from the extent's corner.
pub(super) fn finest(coarse: &crate::volume::Volume, dims0: [usize; 3]) -> pyramid::Finest {
    let (dims, spacing) = (coarse.dims(), coarse.spacing());
    let mut transform = *coarse.transform();
    let mut spacing0 = spacing;
    for a in 0..3 {
        let ratio = dims[a] as f64 / dims0[a] as f64;
        spacing0[a] = spacing[a] * ratio;
        for row in 0..3 {
            let column = transform.matrix[row][a];
            transform.matrix[row][3] += 0.5 * column * (ratio - 1.0);
            transform.matrix[row][a] = column * ratio;
        }
    }
    pyramid::Finest {
        dims: dims0,
        spacing: spacing0,
        transform,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crop_keeps_the_first_voxels_of_each_row_and_slice() {
        // 3x2x2 of u16, voxel value x + 10y + 100z, cut to 2x1x2.
        let mut bytes = Vec::new();
        for z in 0..2u16 {
            for y in 0..2u16 {
                for x in 0..3u16 {
                    bytes.extend_from_slice(&(x + 10 * y + 100 * z).to_le_bytes());
                }
            }
        }
        cut(&mut bytes, [3, 2, 2], [2, 1, 2], 2);
        let values: Vec<u16> = bytes
            .chunks(2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]))
            .collect();
        assert_eq!(values, [0, 1, 100, 101]);
    }
}
