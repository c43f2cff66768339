//! A series' voxels: its frames read from their files, file by file in parallel (native pixels
//! straight from the file, deflated and compressed ones through a second walk and
//! dicom-pixeldata), into the planes of a volume; a Siemens mosaic frame decoded once and its
//! tiles cut from it.

use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

use dicom_core::value::PixelFragmentSequence;
use dicom_core::{DataElement, VR};
use dicom_dictionary_std::tags;
use dicom_object::meta::FileMetaTableBuilder;
use dicom_pixeldata::PixelDecoder;
use rayon::prelude::*;

use super::assemble::{Layout, Series};
use super::header::Image;
use super::pixels::{self, Decode};
use super::read::{self, Pixels, Syntax};
use super::scan::{Scan, Scanned};
use super::{parse, quoted};
use crate::error::{Error, Result};
use crate::formats::data::wide::Rounded;
use crate::formats::data::{check_budget, voxel_buffer};
use crate::formats::scratch::{Room, VoxelOut};
use crate::volume::Voxels;

/// The voxels of slices `order` of `series` as they lie: a volume of `dims` columns, rows and
/// slices, within the budget of `room` or in its scratch folder; with the values an f32 does
/// not hold exactly, counted.
pub(super) fn as_they_lie(
    path: &Path,
    scan: &Scan,
    series: &Series,
    order: &[usize],
    dims: [usize; 3],
    room: Room,
) -> Result<(Voxels, Rounded)> {
    let mut out = room.f32_voxels(path, dims)?;
    let planes: Vec<&mut [f32]> = out.all().chunks_mut(dims[0] * dims[1]).collect();
    let rounded = fill(scan, series, order, planes, room.max_memory)?;
    Ok((out.finish()?, rounded))
}

/// The voxels of slices `order` of `series` resampled to `slices` evenly spaced along the
/// normal of `layout` (the tilt undone): the source slices within the budget of `room`, the
/// volume made from them beside them or in its scratch folder; with the source values an f32
/// does not hold exactly, counted.
pub(super) fn resampled(
    path: &Path,
    scan: &Scan,
    series: &Series,
    layout: &Layout,
    order: &[usize],
    slices: usize,
    room: Room,
) -> Result<(Voxels, Rounded)> {
    let [cols, rows] = layout.plane;
    let budget = room.max_memory;
    check_budget(path, [cols, rows, layout.slices], budget)?;
    // The source slices and the resampled volume held at once, or the volume on disk.
    let dims = [cols, rows, slices];
    let mut out = VoxelOut::new(path, dims, room.scratch, || {
        check_budget(path, [cols, rows, layout.slices + slices], budget)?;
        voxel_buffer(path, dims, budget)
    })?;
    let (planes, rounded) = read_slices(scan, series, order, layout.plane, budget)?;
    let step = layout.spacing[2];
    out.all()
        .par_chunks_mut(cols * rows)
        .enumerate()
        .for_each(|(k, plane)| {
            let depth = k as f64 * step;
            pixels::resample_slice(
                &planes,
                &layout.depths,
                &layout.shifts,
                layout.plane,
                depth,
                plane,
            );
        });
    Ok((out.finish()?, rounded))
}

/// Reads the slices `order` names into planes of their own (for resampling).
fn read_slices(
    scan: &Scan,
    series: &Series,
    order: &[usize],
    plane: [usize; 2],
    budget: u64,
) -> Result<(Vec<Vec<f32>>, Rounded)> {
    let mut planes: Vec<Vec<f32>> = vec![vec![0.0; plane[0] * plane[1]]; order.len()];
    let refs: Vec<&mut [f32]> = planes.iter_mut().map(Vec::as_mut_slice).collect();
    let rounded = fill(scan, series, order, refs, budget)?;
    Ok((planes, rounded))
}

/// Decodes slice `k` of `order` into `planes[k]`, file by file in parallel, stopped between
/// files when the load is cancelled; the values an f32 does not hold exactly, counted.
fn fill(
    scan: &Scan,
    series: &Series,
    order: &[usize],
    planes: Vec<&mut [f32]>,
    budget: u64,
) -> Result<Rounded> {
    let mut by_file: std::collections::BTreeMap<usize, Vec<(&Image, &mut [f32])>> =
        std::collections::BTreeMap::new();
    for (&i, plane) in order.iter().zip(planes) {
        let im = &series.images[i];
        by_file.entry(im.file).or_default().push((im, plane));
    }
    by_file
        .into_iter()
        .collect::<Vec<_>>()
        .into_par_iter()
        .map(|(file, frames)| {
            scan.cancel.check()?;
            read_frames(&scan.files[file], frames, budget)
        })
        .try_reduce(Rounded::default, |a, b| Ok(a.plus(b)))
}

/// Decodes `frames` of one file.
fn read_frames(file: &Scanned, frames: Vec<(&Image, &mut [f32])>, budget: u64) -> Result<Rounded> {
    let path = file.path.as_path();
    let big = file.syntax.big;
    match &file.pixels {
        Pixels::None => Err(Error::format(path, "no pixel data")),
        Pixels::Native { offset, len } => {
            let mut f = crate::formats::Source::new(path).open()?;
            let size = f.metadata().map_err(|e| Error::io(path, e))?.len();
            let (mut buf, mut mosaic) = (Vec::new(), MosaicFrame::new(path, budget));
            for (im, plane) in frames {
                mosaic.put(im, plane, |out, counted| {
                    let bytes = im.format.frame_bytes();
                    let start = u64::from(im.frame) * bytes;
                    let available = (*len).min(size.saturating_sub(*offset));
                    if start + bytes > available {
                        return Err(Error::Truncated {
                            path: path.to_path_buf(),
                            expected: start + bytes,
                            found: available,
                        });
                    }
                    buf.resize(bytes as usize, 0);
                    f.seek(SeekFrom::Start(offset + start))
                        .and_then(|_| f.read_exact(&mut buf))
                        .map_err(|e| Error::io(path, e))?;
                    let d = Decode::new(&im.format, big, im.rescale);
                    Ok(d.frame(&buf, out, counted))
                })?;
            }
            Ok(mosaic.rounded)
        }
        Pixels::Deflated | Pixels::Inflated(_) | Pixels::Encapsulated | Pixels::Fragments(..) => {
            let part = read::read(path, budget, true)?;
            match part.pixels {
                Pixels::Inflated(data) => {
                    let mut mosaic = MosaicFrame::new(path, budget);
                    for (im, plane) in frames {
                        mosaic.put(im, plane, |out, counted| {
                            let bytes = im.format.frame_bytes();
                            let start = u64::from(im.frame) * bytes;
                            let src = data
                                .get(start as usize..(start + bytes) as usize)
                                .ok_or_else(|| Error::Truncated {
                                    path: path.to_path_buf(),
                                    expected: start + bytes,
                                    found: data.len() as u64,
                                })?;
                            let d = Decode::new(&im.format, false, im.rescale);
                            Ok(d.frame(src, out, counted))
                        })?;
                    }
                    Ok(mosaic.rounded)
                }
                Pixels::Fragments(table, fragments) => {
                    let mosaic = MosaicFrame::new(path, budget);
                    let (dataset, syntax) = (&part.dataset, &file.syntax);
                    decode_fragments(path, dataset, syntax, table, fragments, frames, mosaic)
                }
                _ => Err(Error::format(path, "no pixel data")),
            }
        }
    }
}

/// Decodes `frames` of encapsulated pixel data through dicom-pixeldata.
fn decode_fragments(
    path: &Path,
    dataset: &[u8],
    syntax: &Syntax,
    table: Vec<u32>,
    fragments: Vec<Vec<u8>>,
    frames: Vec<(&Image, &mut [f32])>,
    mut mosaic: MosaicFrame,
) -> Result<Rounded> {
    let format = &frames[0].0.format;
    super::codestream::check(path, syntax, format, &fragments)?;
    let mut obj = parse(path, dataset, syntax)?;
    obj.put(DataElement::new(
        tags::PIXEL_DATA,
        VR::OB,
        PixelFragmentSequence::new(table, fragments),
    ));
    let meta = FileMetaTableBuilder::new()
        .transfer_syntax(syntax.uid.as_str())
        .media_storage_sop_class_uid("1.2.840.10008.5.1.4.1.1.7")
        .media_storage_sop_instance_uid("2.25.0");
    let obj = obj
        .with_meta(meta)
        .map_err(|e| Error::format(path, format!("DICOM header: {}", quoted(&e))))?;
    for (im, plane) in frames {
        mosaic.put(im, plane, |out, counted| {
            let decoded = obj.decode_pixel_data_frame(im.frame).map_err(|e| {
                Error::format(
                    path,
                    format!(
                        "{} pixel data: {}",
                        read::syntax_name(&syntax.uid),
                        quoted(&e)
                    ),
                )
            })?;
            let src = decoded.frame_data(0).map_err(|e| {
                Error::format(path, format!("decoded frame {}: {}", im.frame, quoted(&e)))
            })?;
            // The decoders give interleaved RGB for colour.
            let mut f = im.format.clone();
            f.planar = false;
            if f.colour() {
                f.photometric = "RGB".into();
            }
            Ok(Decode::new(&f, false, im.rescale).frame(src, out, counted))
        })?;
    }
    Ok(mosaic.rounded)
}

/// The frame of a Siemens mosaic last decoded, kept while its tiles are cut from it (each frame
/// is decoded once, however many slices it holds); and the values an f32 does not hold exactly
/// counted over the file's frames (each frame's used tiles once).
struct MosaicFrame<'p> {
    path: &'p Path,
    budget: u64,
    frame: Option<u32>,
    values: Vec<f32>,
    /// The mosaic frames already counted.
    counted: std::collections::BTreeSet<u32>,
    /// The count so far.
    rounded: Rounded,
}

impl<'p> MosaicFrame<'p> {
    fn new(path: &'p Path, budget: u64) -> Self {
        Self {
            path,
            budget,
            frame: None,
            values: Vec::new(),
            counted: std::collections::BTreeSet::new(),
            rounded: Rounded::default(),
        }
    }

    /// Puts the pixels of `im` into `plane`: a whole frame `decode`d into it, or a tile cut
    /// from its mosaic frame, `decode`d once into a buffer of its own (charged to the budget),
    /// its tiles' values counted once (the trailing empty tiles are no slices).
    fn put(
        &mut self,
        im: &Image,
        plane: &mut [f32],
        decode: impl FnOnce(&mut [f32], &dyn Fn(usize) -> bool) -> Result<Rounded>,
    ) -> Result<()> {
        let Some(tile) = &im.tile else {
            let r = decode(plane, &|_| true)?;
            self.rounded.add(r);
            return Ok(());
        };
        let cols = usize::from(im.format.cols);
        if self.frame != Some(im.frame) {
            self.frame = None;
            let dims = [cols, usize::from(im.format.rows), 1];
            if self.values.len() != dims[0] * dims[1] {
                self.values = voxel_buffer(self.path, dims, self.budget)?;
            }
            let first = self.counted.insert(im.frame);
            let used = |i: usize| first && tile.holds(i % cols, i / cols);
            let r = decode(&mut self.values, &used)?;
            self.rounded.add(r);
            self.frame = Some(im.frame);
        }
        tile.cut(&self.values, cols, plane);
        Ok(())
    }
}
