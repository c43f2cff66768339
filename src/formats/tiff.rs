//! TIFF: a multi-page grayscale stack (8/16/32-bit integers or 32/64-bit floats), or a folder of
//! single-page slices sorted by the number in their names. Spacing comes from an OME-TIFF's
//! OME-XML (which also orders its pages over z, channel and time), else from ImageJ's description
//! (`spacing=`) and the resolution tags when present.

use std::io::Cursor;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use tiff::decoder::{Decoder, DecodingResult, Limits};
use tiff::tags::{ResolutionUnit, Tag};

use super::data;
use super::data::wide::{Exact, Rounded};
use super::reader::{Reader, Sniff};
use super::{Folder, Format, LoadOptions, Read0, Source, ome, tiff_ifd};
use crate::error::{Error, Result};
use crate::volume::VoxelType;
use crate::volume::mapped::MappedFile;

/// A TIFF's bytes as the decoder reads them: the source's map.
struct Bytes(Arc<MappedFile>);

impl AsRef<[u8]> for Bytes {
    fn as_ref(&self) -> &[u8] {
        self.0.bytes()
    }
}

type Tiff = Decoder<Cursor<Bytes>>;

/// The reader of a multi-page TIFF stack (an OME-TIFF's pages over z, channel and time).
pub(crate) struct TiffStack;

impl Reader for TiffStack {
    fn format(&self) -> Format {
        Format::Tiff
    }

    fn title(&self) -> &'static str {
        "TIFF"
    }

    fn reads(&self) -> Option<&'static str> {
        Some("TIFF stacks")
    }

    fn volume_name(&self, name: &str) -> bool {
        [".tif", ".tiff"].iter().any(|e| name.ends_with(e))
    }

    fn sniff(&self, head: &[u8]) -> Sniff {
        if [b"II*\0", b"MM\0*", b"II+\0", b"MM\0+"]
            .iter()
            .any(|m| head.starts_with(*m))
        {
            Sniff::Mine
        } else {
            Sniff::No
        }
    }

    fn volumes(&self) -> bool {
        true
    }

    fn channels(&self) -> bool {
        true
    }

    /// Reads the source's map (the `tiff` decoder takes any `Read + Seek`).
    fn read(&self, source: &Source, opts: &LoadOptions) -> Result<Read0> {
        load_stack(source, opts)
    }
}

/// The reader of a folder of single-page TIFF slices.
pub(crate) struct TiffSlices;

impl Reader for TiffSlices {
    fn format(&self) -> Format {
        Format::TiffFolder
    }

    fn title(&self) -> &'static str {
        "TIFF slices"
    }

    /// Named with the stacks ("TIFF stacks"): a folder of slices is one.
    fn reads(&self) -> Option<&'static str> {
        None
    }

    fn slice_name(&self, path: &Path) -> bool {
        is_tiff(path)
    }

    fn reads_folder(&self, kind: Folder, _opts: &LoadOptions) -> bool {
        kind == Folder::Slices
    }

    /// Reads the folder's slices, each from its own [`Source`]'s map (the folder is walked by
    /// its path: a folder of files has no bytes of its own).
    fn read(&self, source: &Source, opts: &LoadOptions) -> Result<Read0> {
        load_folder(source.path(), opts)
    }
}

/// Opens the TIFF `source`, mapped, once [`tiff_ifd::check`] found its directories sound;
/// returns its decoder and its length in bytes. What is decoded from it is checked against the
/// file being cut short under the map ([`intact`]).
fn open(source: &Source) -> Result<(Tiff, u64)> {
    let path = source.path();
    let map = source.map()?;
    tiff_ifd::check(path, map.bytes())?;
    let len = map.bytes().len() as u64;
    let dec = Decoder::new(Cursor::new(Bytes(map)))
        .map_err(|e| Error::format(path, format!("not a readable TIFF: {e}")))?;
    Ok((dec, len))
}

/// Fails, naming the file, when it was cut short under the decoder's map while it was read (a
/// host that recovers from the fault, as Python does, read zeros in place of the pages gone).
fn intact(dec: &mut Tiff) -> Result<()> {
    dec.inner().get_ref().0.check()
}

/// A page as its directory describes it, read without decoding anything.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Page {
    width: u32,
    height: u32,
    ty: VoxelType,
}

impl Page {
    /// Its decoded size in bytes, and in f32 voxels.
    fn bytes(self) -> usize {
        self.width as usize * self.height as usize * self.ty.size()
    }

    fn voxels(self) -> usize {
        self.width as usize * self.height as usize
    }
}

/// The current page's size and sample type, from its tags alone: one grayscale sample a pixel
/// of a type slabscope reads, or an error that names what it is instead.
fn describe(path: &Path, dec: &mut Tiff, page: usize) -> Result<Page> {
    let fail = |e: tiff::TiffError| Error::format(path, format!("page {page}: {e}"));
    let unsupported = |what: String| {
        Err(Error::unsupported(
            path,
            format!("page {page} has {what}; slabscope reads grayscale TIFF"),
        ))
    };
    let (width, height) = dec.dimensions().map_err(fail)?;
    let tag = |dec: &mut Tiff, tag: Tag, default: u16| -> Result<u16> {
        match dec.find_tag_unsigned_vec::<u16>(tag).map_err(fail)? {
            None => Ok(default),
            Some(v) => Ok(v.first().copied().unwrap_or(default)),
        }
    };
    let samples = tag(dec, Tag::SamplesPerPixel, 1)?;
    let bits = tag(dec, Tag::BitsPerSample, 1)?;
    let format = tag(dec, Tag::SampleFormat, 1)?;
    let photometric = tag(dec, Tag::PhotometricInterpretation, 1)?;
    if samples != 1 || photometric > 1 {
        let kind = match dec.colortype() {
            Ok(c) => format!("{c:?} pixels"),
            Err(_) => format!("{samples} samples a pixel"),
        };
        return unsupported(kind);
    }
    let ty = match (format, bits) {
        (1, 8) => VoxelType::U8,
        (2, 8) => VoxelType::I8,
        (1, 16) => VoxelType::U16,
        (2, 16) => VoxelType::I16,
        (1, 32) => VoxelType::U32,
        (2, 32) => VoxelType::I32,
        (3, 32) => VoxelType::F32,
        (3, 64) => VoxelType::F64,
        (3, b) => return unsupported(format!("{b}-bit float samples")),
        (1 | 2, 64) => return unsupported("64-bit integer samples".into()),
        (_, 1) => return unsupported("1-bit (black and white) samples".into()),
        (_, b) => return unsupported(format!("{b}-bit samples of format {format}")),
    };
    Ok(Page { width, height, ty })
}

fn pages_agree(path: &Path, page: usize, first: Page, this: Page) -> Result<()> {
    if first == this {
        return Ok(());
    }
    Err(Error::format(
        path,
        format!(
            "page {page} is {}x{} {} but the first page is {}x{} {}",
            this.width, this.height, this.ty, first.width, first.height, first.ty
        ),
    ))
}

/// Decodes the current page, described by `page`, into `out` (its voxels), with the decoder
/// allowed no more memory than the page needs; the 32-bit integers an f32 does not hold
/// exactly, counted.
fn decode(
    path: &Path,
    (dec, len): (Tiff, u64),
    index: usize,
    page: Page,
    buffer: &mut DecodingResult,
    out: &mut [f32],
) -> Result<(Tiff, Rounded)> {
    let mut limits = Limits::default();
    // The page, and any tag value (the crate charges those to the same limit; the directory
    // walk found each within the file).
    limits.decoding_buffer_size = page.bytes().max(usize::try_from(len).unwrap_or(usize::MAX));
    // Compressed strips are read whole: no bigger than the page, with room for data that did
    // not compress.
    limits.intermediate_buffer_size = page.bytes().saturating_mul(2).saturating_add(1 << 16);
    let mut dec = dec.with_limits(limits);
    dec.read_image_to_buffer(buffer)
        .map_err(|e| Error::format(path, format!("page {index}: {e}")))?;
    let (n, rounded) = fill(buffer, out);
    if n != page.voxels() {
        return Err(Error::format(
            path,
            format!("page {index} decoded to {n} samples, not {}", page.voxels()),
        ));
    }
    Ok((dec, rounded))
}

/// Widens the decoded samples into `out`: the number of samples decoded, and the integers an
/// f32 does not hold exactly, counted.
fn fill(buffer: &DecodingResult, out: &mut [f32]) -> (usize, Rounded) {
    fn widen<T: Copy + Into<f64> + Exact>(values: &[T], out: &mut [f32]) -> (usize, Rounded) {
        for (o, &v) in out.iter_mut().zip(values) {
            *o = v.into() as f32;
        }
        (values.len(), T::rounded(values))
    }
    match buffer {
        DecodingResult::U8(v) => widen(v, out),
        DecodingResult::I8(v) => widen(v, out),
        DecodingResult::U16(v) => widen(v, out),
        DecodingResult::I16(v) => widen(v, out),
        DecodingResult::U32(v) => widen(v, out),
        DecodingResult::I32(v) => widen(v, out),
        DecodingResult::F32(v) => widen(v, out),
        DecodingResult::F64(v) => widen(v, out),
        _ => (0, Rounded::default()),
    }
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

fn load_stack(source: &Source, opts: &LoadOptions) -> Result<Read0> {
    let path = source.path();
    let (mut dec, len) = open(source)?;
    let description = dec
        .get_tag_ascii_string(Tag::ImageDescription)
        .unwrap_or_default();
    let ome = ome::parse(&description).map_err(|m| Error::format(path, m))?;
    let mut notes = Vec::new();
    let spacing = match &ome {
        Some(o) => ome_spacing(o, &mut notes),
        None => spacing(&mut dec),
    };
    // Every page is described and checked against the first, and what is read against the
    // budget, before a single one is decoded.
    let first = describe(path, &mut dec, 0)?;
    let wanted = |pages: usize| ome.as_ref().map_or(pages, |o| o.size_zct[0]);
    let mut pages = 1usize;
    let plane = |pages: usize| [first.width as usize, first.height as usize, pages];
    opts.room().check(path, plane(wanted(pages)))?;
    while dec.more_images() {
        opts.cancel.check()?;
        dec.next_image()
            .map_err(|e| Error::format(path, format!("page {pages}: {e}")))?;
        pages_agree(path, pages, first, describe(path, &mut dec, pages)?)?;
        pages += 1;
        opts.room().check(path, plane(wanted(pages)))?;
    }
    let indices: Vec<usize> = match &ome {
        Some(o) => ome_pages(path, o, first, pages, opts, &mut notes)?,
        None if opts.part.volume > 0 => return Err(data::one_volume(path, 1, opts.part.volume)),
        None if opts.part.channel > 0 => return Err(data::one_channel(path, 1, opts.part.channel)),
        None => (0..pages).collect(),
    };
    let dims = plane(indices.len());
    let mut voxels = opts.room().f32_voxels(path, dims)?;
    let mut buffer = DecodingResult::U8(Vec::new());
    let mut rounded = Rounded::default();
    for (&index, out) in indices.iter().zip(voxels.all().chunks_mut(first.voxels())) {
        opts.cancel.check()?;
        dec.seek_to_image(index)
            .map_err(|e| Error::format(path, format!("page {index}: {e}")))?;
        let r;
        (dec, r) = decode(path, (dec, len), index, first, &mut buffer, out)?;
        rounded.add(r);
    }
    intact(&mut dec)?;
    notes.extend(rounded.note(first.ty.name()));
    Read0::new(path, dims, spacing, first.ty, voxels.finish()?, notes)
}

/// An OME-TIFF's voxel sizes in mm; an axis without one is 1, and a note says so.
fn ome_spacing(o: &ome::OmePixels, notes: &mut Vec<String>) -> [f64; 3] {
    let missing: Vec<&str> = ["x", "y", "z"]
        .into_iter()
        .zip(o.spacing)
        .filter_map(|(a, s)| s.is_none().then_some(a))
        .collect();
    if !missing.is_empty() {
        notes.push(format!(
            "the OME-XML gives no physical size along {}: taken as 1 mm",
            missing.join(", ")
        ));
    }
    o.spacing.map(|s| s.unwrap_or(1.0))
}

/// The pages of an OME-TIFF that hold channel `opts.part.channel` at time point `opts.part.volume`, in z
/// order, after checking the OME-XML against the pages the file holds; notes say which were read.
fn ome_pages(
    path: &Path,
    o: &ome::OmePixels,
    first: Page,
    pages: usize,
    opts: &LoadOptions,
    notes: &mut Vec<String>,
) -> Result<Vec<usize>> {
    let [z, c, t] = o.size_zct;
    if o.size_xy != [first.width as usize, first.height as usize] {
        return Err(Error::format(
            path,
            format!(
                "the OME-XML says {}x{} planes but the pages are {}x{}",
                o.size_xy[0], o.size_xy[1], first.width, first.height
            ),
        ));
    }
    if o.pages() > pages {
        return Err(Error::format(
            path,
            format!(
                "the OME-XML says {z} planes x {c} channels x {t} time points ({} pages) but the \
                 file holds {pages}",
                o.pages()
            ),
        ));
    }
    if opts.part.channel >= c {
        return Err(data::one_channel(path, c, opts.part.channel));
    }
    if opts.part.volume >= t {
        return Err(data::one_volume(path, t, opts.part.volume));
    }
    if c > 1 || t > 1 {
        notes.push(format!(
            "OME-TIFF of {c} channel{} and {t} time point{}: read channel {} at time point {}",
            if c == 1 { "" } else { "s" },
            if t == 1 { "" } else { "s" },
            opts.part.channel,
            opts.part.volume
        ));
    }
    if o.images > 1 {
        notes.push(format!("OME-TIFF of {} images: read the first", o.images));
    }
    Ok((0..z)
        .map(|k| o.page([k, opts.part.channel, opts.part.volume]))
        .collect())
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

/// Whether the file at `path` is named like a TIFF (`.tif`, `.tiff`, any case): in a folder, a
/// slice.
pub(crate) fn is_tiff(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("tif") || e.eq_ignore_ascii_case("tiff"))
}

/// The TIFF files of a folder in slice order. Anything named like a slice that is not a
/// readable regular file (a folder, a FIFO, a broken or looping link) is an error that names it,
/// not a slice silently left out.
pub(crate) fn slice_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let entries = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
    let mut files = Vec::new();
    for entry in entries {
        let path = entry.map_err(|e| Error::io(dir, e))?.path();
        if !is_tiff(&path) {
            continue;
        }
        let meta = std::fs::metadata(&path).map_err(|e| Error::io(&path, e))?;
        if !meta.is_file() {
            return Err(Error::format(
                &path,
                "named like a slice, but not a regular file",
            ));
        }
        files.push(path);
    }
    if files.is_empty() {
        return Err(Error::format(dir, "folder holds no .tif or .tiff slices"));
    }
    files.sort_by(|a, b| (slice_number(a), a.file_name()).cmp(&(slice_number(b), b.file_name())));
    Ok(files)
}

fn load_folder(dir: &Path, opts: &LoadOptions) -> Result<Read0> {
    let files = slice_files(dir)?;
    let (mut dec, _) = open(&Source::new(&files[0]))?;
    let spacing = spacing(&mut dec);
    let first = describe(&files[0], &mut dec, 0)?;
    let dims = [first.width as usize, first.height as usize, files.len()];
    opts.room().check(dir, dims)?;
    // Every slice is described and checked before any is decoded.
    for (i, file) in files.iter().enumerate().skip(1) {
        opts.cancel.check()?;
        let mut dec = open(&Source::new(file))?.0;
        pages_agree(file, i, first, describe(file, &mut dec, 0)?)?;
    }
    let mut voxels = opts.room().f32_voxels(dir, dims)?;
    let mut buffer = DecodingResult::U8(Vec::new());
    let mut rounded = Rounded::default();
    for (file, out) in files.iter().zip(voxels.all().chunks_mut(first.voxels())) {
        opts.cancel.check()?;
        let (mut dec, len) = open(&Source::new(file))?;
        // The file may have changed since it was described.
        pages_agree(file, 0, first, describe(file, &mut dec, 0)?)?;
        let (mut dec, r) = decode(file, (dec, len), 0, first, &mut buffer, out)?;
        intact(&mut dec)?;
        rounded.add(r);
    }
    let name = |p: &PathBuf| crate::error::shown(Path::new(p.file_name().unwrap_or_default()));
    let mut notes = vec![format!(
        "{} slices from {} to {}",
        files.len(),
        name(&files[0]),
        name(&files[files.len() - 1])
    )];
    notes.extend(rounded.note(first.ty.name()));
    Read0::new(dir, dims, spacing, first.ty, voxels.finish()?, notes)
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
