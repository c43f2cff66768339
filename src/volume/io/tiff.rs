//! TIFF: a multi-page grayscale stack (8/16/32-bit integers or 32/64-bit floats), or a folder of
//! single-page slices sorted by the number in their names. Spacing comes from ImageJ's description
//! (`spacing=`) and the resolution tags when present.

use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};

use tiff::decoder::{Decoder, DecodingResult, Limits};
use tiff::tags::{ResolutionUnit, Tag};

use super::data::check_budget;
use super::{LoadOptions, Read0};
use crate::error::{Error, Result};
use crate::volume::VoxelType;

type Tiff = Decoder<BufReader<File>>;

fn open(path: &Path, max_memory: u64) -> Result<Tiff> {
    let file = File::open(path).map_err(|e| Error::io(path, e))?;
    let mut limits = Limits::default();
    limits.decoding_buffer_size = usize::try_from(max_memory).unwrap_or(usize::MAX);
    Decoder::new(BufReader::new(file))
        .map(|d| d.with_limits(limits))
        .map_err(|e| Error::format(path, format!("not a readable TIFF: {e}")))
}

/// Decodes the current page, checking it is grayscale, and appends it to `out`.
fn read_page(
    path: &Path,
    dec: &mut Tiff,
    page: usize,
    out: &mut Vec<f32>,
) -> Result<(u32, u32, VoxelType)> {
    let fail = |e: tiff::TiffError| Error::format(path, format!("page {page}: {e}"));
    let (w, h) = dec.dimensions().map_err(fail)?;
    match dec.colortype().map_err(fail)? {
        tiff::ColorType::Gray(_) => {}
        other => {
            return Err(Error::unsupported(
                path,
                format!("page {page} is {other:?}; slabscope reads grayscale TIFF"),
            ));
        }
    }
    let image = dec.read_image().map_err(fail)?;
    let ty = match image {
        DecodingResult::U8(v) => extend(out, v, VoxelType::U8),
        DecodingResult::I8(v) => extend(out, v, VoxelType::I8),
        DecodingResult::U16(v) => extend(out, v, VoxelType::U16),
        DecodingResult::I16(v) => extend(out, v, VoxelType::I16),
        DecodingResult::U32(v) => extend(out, v, VoxelType::U32),
        DecodingResult::I32(v) => extend(out, v, VoxelType::I32),
        DecodingResult::F32(v) => extend(out, v, VoxelType::F32),
        DecodingResult::F64(v) => extend(out, v, VoxelType::F64),
        _ => {
            return Err(Error::unsupported(
                path,
                format!("page {page}: 64-bit integer or 16-bit float samples"),
            ));
        }
    };
    Ok((w, h, ty))
}

fn extend<T: Copy + Into<f64>>(out: &mut Vec<f32>, values: Vec<T>, ty: VoxelType) -> VoxelType {
    out.extend(values.into_iter().map(|v| v.into() as f32));
    ty
}

/// x, y spacing from the resolution tags (pixels per unit), and z from ImageJ's `spacing=`.
fn spacing(dec: &mut Tiff) -> [f64; 3] {
    let mm_per_unit = match dec
        .find_tag_unsigned::<u16>(Tag::ResolutionUnit)
        .ok()
        .flatten()
    {
        Some(u) if u == ResolutionUnit::Centimeter.to_u16() => Some(10.0),
        Some(u) if u == ResolutionUnit::Inch.to_u16() => Some(25.4),
        _ => None,
    };
    let description = dec
        .get_tag_ascii_string(Tag::ImageDescription)
        .unwrap_or_default();
    let imagej = description.starts_with("ImageJ");
    let field = |key: &str| -> Option<f64> {
        description
            .lines()
            .find_map(|l| l.strip_prefix(key))
            .and_then(|v| v.trim().parse().ok())
    };
    // ImageJ stores the unit in its description and leaves ResolutionUnit unset; assume its
    // unit is mm unless it says micron.
    let unit = if imagej {
        match description.lines().find_map(|l| l.strip_prefix("unit=")) {
            Some("micron" | "um" | "\\u00B5m") => Some(0.001),
            Some("cm") => Some(10.0),
            _ => Some(1.0),
        }
    } else {
        mm_per_unit
    };
    let mut resolution = |tag: Tag| -> Option<f64> {
        let v = dec.get_tag_u32_vec(tag).ok()?;
        (v.len() == 2 && v[0] > 0).then(|| f64::from(v[1]) / f64::from(v[0]))
    };
    let sx = unit.and_then(|u| resolution(Tag::XResolution).map(|r| r * u));
    let sy = unit.and_then(|u| resolution(Tag::YResolution).map(|r| r * u));
    let sz = if imagej {
        field("spacing=").zip(unit).map(|(s, u)| s * u)
    } else {
        None
    };
    let ok = |s: Option<f64>| s.filter(|s| s.is_finite() && *s > 0.0).unwrap_or(1.0);
    [ok(sx), ok(sy), ok(sz)]
}

fn pages_agree(
    path: &Path,
    page: usize,
    first: (u32, u32, VoxelType),
    this: (u32, u32, VoxelType),
) -> Result<()> {
    if first == this {
        return Ok(());
    }
    Err(Error::format(
        path,
        format!(
            "page {page} is {}x{} {} but the first page is {}x{} {}",
            this.0, this.1, this.2, first.0, first.1, first.2
        ),
    ))
}

pub(crate) fn load_stack(path: &Path, opts: &LoadOptions) -> Result<Read0> {
    let mut dec = open(path, opts.max_memory)?;
    let spacing = spacing(&mut dec);
    let mut voxels = Vec::new();
    let mut first = None;
    let mut pages = 0usize;
    loop {
        if let Some((w, h, _)) = first {
            check_budget(path, [w as usize, h as usize, pages + 1], opts.max_memory)?;
        } else {
            let (w, h) = dec
                .dimensions()
                .map_err(|e| Error::format(path, e.to_string()))?;
            check_budget(path, [w as usize, h as usize, 1], opts.max_memory)?;
        }
        let this = read_page(path, &mut dec, pages, &mut voxels)?;
        pages_agree(path, pages, *first.get_or_insert(this), this)?;
        pages += 1;
        if !dec.more_images() {
            break;
        }
        dec.next_image()
            .map_err(|e| Error::format(path, format!("page {pages}: {e}")))?;
    }
    let (w, h, ty) = first.expect("a TIFF has a first page");
    let dims = [w as usize, h as usize, pages];
    Read0::new(path, dims, spacing, ty, voxels, Vec::new())
}

/// The last run of digits in a file name, for ordering slices.
fn slice_number(path: &Path) -> Option<u64> {
    let stem = path.file_stem()?.to_string_lossy();
    let digits: String = stem
        .chars()
        .rev()
        .skip_while(|c| !c.is_ascii_digit())
        .take_while(char::is_ascii_digit)
        .collect();
    digits.chars().rev().collect::<String>().parse().ok()
}

/// The TIFF files of a folder in slice order.
pub(crate) fn slice_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let entries = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.is_file()
                && p.extension().is_some_and(|e| {
                    e.eq_ignore_ascii_case("tif") || e.eq_ignore_ascii_case("tiff")
                })
        })
        .collect();
    if files.is_empty() {
        return Err(Error::format(dir, "folder holds no .tif or .tiff slices"));
    }
    files.sort_by(|a, b| (slice_number(a), a.file_name()).cmp(&(slice_number(b), b.file_name())));
    Ok(files)
}

pub(crate) fn load_folder(dir: &Path, opts: &LoadOptions) -> Result<Read0> {
    let files = slice_files(dir)?;
    let mut first_dec = open(&files[0], opts.max_memory)?;
    let (w, h) = first_dec
        .dimensions()
        .map_err(|e| Error::format(&files[0], e.to_string()))?;
    check_budget(dir, [w as usize, h as usize, files.len()], opts.max_memory)?;
    let spacing = spacing(&mut first_dec);
    drop(first_dec);
    let mut voxels = Vec::with_capacity(w as usize * h as usize * files.len());
    let mut first = None;
    for (i, file) in files.iter().enumerate() {
        let mut dec = open(file, opts.max_memory)?;
        let this = read_page(file, &mut dec, 0, &mut voxels)?;
        pages_agree(file, i, *first.get_or_insert(this), this)?;
    }
    let (w, h, ty) = first.expect("the folder has a first slice");
    let dims = [w as usize, h as usize, files.len()];
    let notes = vec![format!(
        "{} slices from {} to {}",
        files.len(),
        files[0].file_name().unwrap_or_default().to_string_lossy(),
        files[files.len() - 1]
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
    )];
    Read0::new(dir, dims, spacing, ty, voxels, notes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slices_sort_by_their_last_number() {
        let n = |s: &str| slice_number(Path::new(s));
        assert_eq!(n("img_0012.tif"), Some(12));
        assert_eq!(n("s2_slice10.tiff"), Some(10));
        assert_eq!(n("plain.tif"), None);
    }
}
