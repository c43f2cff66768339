//! A store's coarser datasets read without its level 0: the first picture's preview
//! ([`read_preview`]) and, for a store local or at a URL, the level an analysis asks for
//! ([`read_serving`]), each as its pyramid level of the image, quantized with its own range
//! (level 0's is not known until level 0 is read).

use std::path::Path;

use super::{LoadOptions, Opened, Read0, levels};
use crate::error::Result;
use crate::volume::{Resolution, pyramid};

/// The finest of the store's coarser datasets on the pyramid's grid with at most `max_voxels`
/// voxels (with `max_voxels` 0, the coarsest), read as that pyramid level of the image without
/// reading level 0 (so quantized with its own range); `None` when level 0 itself has at most
/// `max_voxels` voxels or no such dataset exists.
pub(super) fn read_preview(
    dir: &Path,
    opts: &LoadOptions,
    max_voxels: usize,
) -> Result<Option<Read0>> {
    let opened = Opened::new(dir, opts)?;
    let (finest, pyramid, chain) = chained(&opened);
    let wanted = match max_voxels {
        0 => 1,
        _ => pyramid::level_within(&chain, max_voxels),
    };
    let within = pyramid.levels.iter().copied().filter(|&(k, _)| k >= wanted);
    let best = if max_voxels == 0 {
        within.max()
    } else {
        within.min()
    };
    let (Some((k, i)), 1..) = (best, wanted) else {
        return Ok(None);
    };
    let mut read0 = opened.read(dir, i, opts)?;
    read0.volume = read0.volume.into_pyramid_level(k, finest, &pyramid.steps);
    Ok(Some(read0))
}

/// The coarsest of the store's coarser datasets on the pyramid's grid no coarser than the
/// pyramid level `resolution` picks for level 0 (from the metadata: no voxel of level 0 is
/// read), read as its pyramid level of the image, quantized with its own range, with a note
/// saying so; the level asked is computed from it ([`Volume::coarser`](crate::Volume::coarser)).
/// `None` when `resolution` picks level 0 or the store holds no such dataset. An error when
/// `resolution` names a level past the last.
pub(crate) fn read_serving(
    dir: &Path,
    opts: &LoadOptions,
    resolution: Resolution,
) -> Result<Option<Read0>> {
    let opened = Opened::new(dir, opts)?;
    let (finest, pyramid, chain) = chained(&opened);
    let wanted = resolution.level(&chain)?;
    let best = (pyramid.levels.iter().copied())
        .filter(|&(k, _)| k <= wanted)
        .max();
    let Some((k, i)) = best else {
        return Ok(None);
    };
    let mut read0 = opened.read(dir, i, opts)?;
    read0.volume = read0.volume.into_pyramid_level(k, finest, &pyramid.steps);
    read0.notes.push(format!(
        "pyramid level {wanted} from the store's dataset {:?} (pyramid level {k}), level 0 not \
         read: quantized with that dataset's own value range, level 0's not being known",
        opened.image.datasets[i].path
    ));
    Ok(Some(read0))
}

/// Level 0's grid, the store's pyramid, and the dimensions of every pyramid level (level 0's
/// first).
fn chained(opened: &Opened) -> (pyramid::Finest, levels::StorePyramid, Vec<[usize; 3]>) {
    let finest = opened.grid(0, &mut Vec::new());
    let dims0 = finest.dims;
    let pyramid = levels::StorePyramid::of(&opened.image, &opened.arrays, &opened.layout);
    let chain = pyramid::chain_dims(dims0, &pyramid::steps_after(dims0, &pyramid.steps));
    (finest, pyramid, chain)
}
