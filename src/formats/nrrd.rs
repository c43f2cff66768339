//! NRRD (`.nrrd` with attached data, `.nhdr` with a detached data file): a small parser for the
//! fields a scalar volume needs, and a writer (raw or gzip) that never overwrites unasked.

mod write;

use std::io::Read;
use std::path::Path;

pub(crate) use self::write::stage;
pub use self::write::{NrrdEncoding, write_nrrd};

use super::data::{DataSpec, Encoding, Skip, pick_volume, read_voxels};
use super::reader::{Reader, Sniff};
use super::{Format, LoadOptions, Read0, Source};
use crate::error::{Error, Result};
use crate::geometry::WorldTransform;
use crate::volume::{Endian, VoxelType};

/// The NRRD reader.
pub(crate) struct Nrrd;

impl Reader for Nrrd {
    fn format(&self) -> Format {
        Format::Nrrd
    }

    fn title(&self) -> &'static str {
        "NRRD"
    }

    fn sniff(&self, head: &[u8]) -> Sniff {
        if head.starts_with(b"NRRD000") {
            Sniff::Mine
        } else {
            Sniff::No
        }
    }

    fn extensions(&self) -> &'static [&'static str] {
        &[".nrrd", ".nhdr"]
    }

    fn volumes(&self) -> bool {
        true
    }

    fn read(&self, source: &Source, opts: &LoadOptions) -> Result<Read0> {
        load(source, opts)
    }
}

/// The most bytes a header may take before we stop looking for its end.
const MAX_HEADER: usize = 1 << 20;

/// The fields of an NRRD header that slabscope uses.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Header {
    pub voxel_type: VoxelType,
    pub sizes: Vec<usize>,
    pub encoding: Encoding,
    pub endian: Option<Endian>,
    pub spacings: Option<Vec<f64>>,
    /// Each axis's space direction (a vector of the space's dimension); `None` for a `none`
    /// axis.
    pub directions: Option<Vec<Option<Vec<f64>>>>,
    /// `space`, lowercase (e.g. `left-posterior-superior`).
    pub space: Option<String>,
    /// `space origin`.
    pub origin: Option<Vec<f64>>,
    pub kinds: Option<Vec<String>>,
    pub data_file: Option<String>,
    pub line_skip: u64,
    pub byte_skip: Skip,
    /// Bytes up to and including the blank line that ends the header.
    pub len: usize,
}

fn voxel_type(name: &str) -> std::result::Result<VoxelType, String> {
    let t = name.trim().to_ascii_lowercase();
    Ok(match t.as_str() {
        "signed char" | "int8" | "int8_t" => VoxelType::I8,
        "uchar" | "unsigned char" | "uint8" | "uint8_t" => VoxelType::U8,
        "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => {
            VoxelType::I16
        }
        "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => {
            VoxelType::U16
        }
        "int" | "signed int" | "int32" | "int32_t" => VoxelType::I32,
        "uint" | "unsigned int" | "uint32" | "uint32_t" => VoxelType::U32,
        "float" => VoxelType::F32,
        "double" => VoxelType::F64,
        _ => return Err(format!("NRRD type {t:?}")),
    })
}

fn type_name(ty: VoxelType) -> &'static str {
    match ty {
        VoxelType::U8 => "uint8",
        VoxelType::I8 => "int8",
        VoxelType::U16 => "uint16",
        VoxelType::I16 => "int16",
        VoxelType::U32 => "uint32",
        VoxelType::I32 => "int32",
        VoxelType::F32 => "float",
        VoxelType::F64 => "double",
    }
}

/// Parses "(1,0,0) (0,1.5,0) none" into direction vectors.
fn parse_directions(value: &str) -> Option<Vec<Option<Vec<f64>>>> {
    let mut out = Vec::new();
    let mut rest = value.trim();
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix("none") {
            out.push(None);
            rest = r.trim_start();
        } else if let Some(r) = rest.strip_prefix('(') {
            let (vector, r) = parse_vector(r)?;
            out.push(Some(vector));
            rest = r.trim_start();
        } else {
            return None;
        }
    }
    Some(out)
}

/// The numbers of a vector "1,0.5,2)" (after its opening parenthesis), and what follows it.
fn parse_vector(after_paren: &str) -> Option<(Vec<f64>, &str)> {
    let end = after_paren.find(')')?;
    let comps = after_paren[..end]
        .split(',')
        .map(|c| c.trim().parse().ok())
        .collect::<Option<Vec<f64>>>()?;
    Some((comps, &after_paren[end + 1..]))
}

/// Per world axis, the sign that takes an NRRD `space` to RAS+; `None` for a space without
/// anatomical meaning (`scanner-xyz`, `3D-right-handed`, ...).
fn space_to_ras(space: &str) -> Option<[f64; 3]> {
    Some(match space {
        "right-anterior-superior" | "ras" => [1.0, 1.0, 1.0],
        "left-anterior-superior" | "las" => [-1.0, 1.0, 1.0],
        "left-posterior-superior" | "lps" => [-1.0, -1.0, 1.0],
        _ => return None,
    })
}

/// The voxel-to-world transform of the spatial axes `axes` of a header with an anatomical
/// `space` and `space directions`.
fn transform(h: &Header, axes: &[usize]) -> Option<WorldTransform> {
    let sign = space_to_ras(h.space.as_deref()?)?;
    let directions = h.directions.as_ref()?;
    let columns: Vec<&Vec<f64>> = axes
        .iter()
        .take(3)
        .map(|&a| directions.get(a)?.as_ref())
        .collect::<Option<_>>()?;
    if columns.len() != 3 || columns.iter().any(|c| c.len() != 3) {
        return None;
    }
    let origin = match &h.origin {
        Some(o) if o.len() == 3 => [o[0], o[1], o[2]],
        Some(_) => return None,
        None => [0.0; 3],
    };
    let linear = std::array::from_fn(|r| std::array::from_fn(|c| columns[c][r] * sign[r]));
    Some(WorldTransform::ras(
        linear,
        std::array::from_fn(|r| origin[r] * sign[r]),
    ))
}

/// Header fields as they are read, before the required ones are checked.
#[derive(Default)]
struct Fields {
    voxel_type: Option<VoxelType>,
    dimension: Option<usize>,
    sizes: Option<Vec<usize>>,
    encoding: Option<Encoding>,
    endian: Option<Endian>,
    spacings: Option<Vec<f64>>,
    directions: Option<Vec<Option<Vec<f64>>>>,
    space: Option<String>,
    origin: Option<Vec<f64>>,
    kinds: Option<Vec<String>>,
    data_file: Option<String>,
    line_skip: u64,
    byte_skip: Option<Skip>,
}

fn whole_numbers(value: &str) -> Option<Vec<usize>> {
    value.split_whitespace().map(|t| t.parse().ok()).collect()
}

/// The encoding an `encoding` field names.
fn encoding(path: &Path, value: &str) -> Result<Encoding> {
    Ok(match value.to_ascii_lowercase().as_str() {
        "raw" => Encoding::Raw,
        "gzip" | "gz" => Encoding::Gzip,
        "ascii" | "text" | "txt" => Encoding::Ascii,
        other => {
            return Err(Error::unsupported(path, format!("NRRD encoding {other:?}")));
        }
    })
}

/// The numbers of a `spacings` field (`nan` for an axis without one), or `None` when one is
/// not a number.
fn spacings(value: &str) -> Option<Vec<f64>> {
    let parse = |t: &str| {
        if t.eq_ignore_ascii_case("nan") {
            Some(f64::NAN)
        } else {
            t.parse().ok()
        }
    };
    value.split_whitespace().map(parse).collect()
}

/// Reads one `field: value` line into `f`.
fn read_field(path: &Path, f: &mut Fields, key: &str, value: &str) -> Result<()> {
    let bad = |m: String| Error::format(path, m);
    match key.trim().to_ascii_lowercase().as_str() {
        "type" => f.voxel_type = Some(voxel_type(value).map_err(|t| Error::unsupported(path, t))?),
        "dimension" => {
            f.dimension = Some(
                value
                    .parse()
                    .map_err(|_| bad(format!("dimension {value:?}")))?,
            );
        }
        "sizes" => {
            f.sizes = Some(
                whole_numbers(value)
                    .ok_or_else(|| bad(format!("sizes {value:?} are not whole numbers")))?,
            );
        }
        "encoding" => f.encoding = Some(encoding(path, value)?),
        "endian" => {
            f.endian = Some(match value.to_ascii_lowercase().as_str() {
                "little" => Endian::Little,
                "big" => Endian::Big,
                other => return Err(bad(format!("endian {other:?}"))),
            });
        }
        "spacings" => {
            f.spacings = Some(
                spacings(value)
                    .ok_or_else(|| bad(format!("spacings {value:?} are not numbers")))?,
            );
        }
        "space directions" => {
            f.directions = Some(
                parse_directions(value)
                    .ok_or_else(|| bad(format!("space directions {value:?}")))?,
            );
        }
        "space" => f.space = Some(value.trim().to_ascii_lowercase()),
        "space origin" => {
            let vector = value
                .trim()
                .strip_prefix('(')
                .and_then(parse_vector)
                .ok_or_else(|| bad(format!("space origin {value:?}")))?;
            f.origin = Some(vector.0);
        }
        "kinds" => {
            f.kinds = Some(
                value
                    .split_whitespace()
                    .map(str::to_ascii_lowercase)
                    .collect(),
            );
        }
        "data file" | "datafile" => f.data_file = Some(value.to_string()),
        "line skip" | "lineskip" => {
            f.line_skip = value
                .parse()
                .map_err(|_| bad(format!("line skip {value:?}")))?;
        }
        "byte skip" | "byteskip" => {
            f.byte_skip = Some(match value.parse::<i64>() {
                Ok(-1) => Skip::FromEnd,
                Ok(n) if n >= 0 => Skip::Bytes(n as u64),
                _ => return Err(bad(format!("byte skip {value:?}"))),
            });
        }
        _ => {}
    }
    Ok(())
}

/// Parses an NRRD header from the start of `bytes` (which may continue with attached data).
pub(crate) fn parse_header(path: &Path, bytes: &[u8]) -> Result<Header> {
    let bad = |m: String| Error::format(path, m);
    if !bytes.starts_with(b"NRRD000") {
        return Err(bad("not an NRRD file (no NRRD000X magic)".into()));
    }
    let mut pos = 0;
    let mut ended = false;
    let mut fields = Fields::default();
    let mut first = true;
    while pos < bytes.len() {
        let end = bytes[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |i| pos + i);
        let line = String::from_utf8_lossy(&bytes[pos..end]);
        let line = line.trim_end_matches('\r');
        pos = (end + 1).min(bytes.len());
        if line.is_empty() {
            ended = true;
            break;
        }
        if std::mem::take(&mut first) || line.starts_with('#') || line.contains(":=") {
            continue;
        }
        let Some((key, value)) = line.split_once(':') else {
            return Err(bad(format!("header line {line:?} is not \"field: value\"")));
        };
        read_field(path, &mut fields, key, value.trim())?;
    }
    let missing = |f: &str| bad(format!("header has no \"{f}\" field"));
    let h = Header {
        voxel_type: fields.voxel_type.ok_or_else(|| missing("type"))?,
        sizes: fields.sizes.ok_or_else(|| missing("sizes"))?,
        encoding: fields.encoding.ok_or_else(|| missing("encoding"))?,
        endian: fields.endian,
        spacings: fields.spacings,
        directions: fields.directions,
        space: fields.space,
        origin: fields.origin,
        kinds: fields.kinds,
        data_file: fields.data_file,
        line_skip: fields.line_skip,
        byte_skip: fields.byte_skip.unwrap_or(Skip::Bytes(0)),
        len: pos,
    };
    let dimension = fields.dimension.ok_or_else(|| missing("dimension"))?;
    if dimension != h.sizes.len() {
        return Err(bad(format!(
            "dimension is {dimension} but sizes lists {} numbers",
            h.sizes.len()
        )));
    }
    if !(1..=4).contains(&dimension) {
        return Err(Error::unsupported(
            path,
            format!("{dimension}-dimensional NRRD (1 to 4 are read)"),
        ));
    }
    if !ended && h.data_file.is_none() {
        return Err(bad(
            "header does not end with a blank line and names no data file".into(),
        ));
    }
    Ok(h)
}

/// Reads the header bytes: up to the first blank line, or the whole (detached) header file.
fn read_header_bytes(source: &Source) -> Result<Vec<u8>> {
    let path = source.path();
    let file = source.open()?;
    let mut bytes = Vec::new();
    let mut reader = file.take(MAX_HEADER as u64);
    let mut chunk = [0u8; 8192];
    loop {
        let n = reader.read(&mut chunk).map_err(|e| Error::io(path, e))?;
        if n == 0 {
            return Ok(bytes);
        }
        bytes.extend_from_slice(&chunk[..n]);
        if bytes.windows(2).any(|w| w == b"\n\n") || bytes.windows(4).any(|w| w == b"\r\n\r\n") {
            return Ok(bytes);
        }
    }
}

fn is_spatial(kind: &str) -> bool {
    matches!(kind, "domain" | "space" | "time" | "???" | "none")
}

/// The axes of the header that are the volume's (space, then any further ones): all of them,
/// but a leading non-spatial axis of size 1 (a "scalar" component) is dropped; larger ones are
/// multi-component voxels, which slabscope does not read.
fn volume_axes(path: &Path, h: &Header) -> Result<Vec<usize>> {
    let mut axes: Vec<usize> = (0..h.sizes.len()).collect();
    if let Some(kinds) = &h.kinds {
        if kinds.len() != h.sizes.len() {
            return Err(Error::format(
                path,
                format!("kinds lists {} axes, sizes {}", kinds.len(), h.sizes.len()),
            ));
        }
        if !is_spatial(&kinds[0]) && h.sizes.len() > 1 {
            if h.sizes[0] != 1 {
                return Err(Error::unsupported(
                    path,
                    format!(
                        "{} components per voxel (kind {:?}); slabscope reads scalar volumes",
                        h.sizes[0], kinds[0]
                    ),
                ));
            }
            axes.remove(0);
        }
    }
    Ok(axes)
}

fn load(source: &Source, opts: &LoadOptions) -> Result<Read0> {
    let path = source.path();
    let h = parse_header(path, &read_header_bytes(source)?)?;
    let mut notes = Vec::new();
    let axes = volume_axes(path, &h)?;
    let mut dims = [1usize; 3];
    let mut spacing = [1.0f64; 3];
    for (k, &axis) in axes.iter().take(3).enumerate() {
        dims[k] = h.sizes[axis];
        let s = h
            .spacings
            .as_ref()
            .and_then(|s| s.get(axis).copied())
            .or_else(|| {
                h.directions
                    .as_ref()
                    .and_then(|d| d.get(axis)?.as_ref())
                    .map(|v| v.iter().map(|c| c * c).sum::<f64>().sqrt())
            });
        match s {
            Some(s) if s.is_finite() && s > 0.0 => spacing[k] = s,
            Some(s) => notes.push(format!("axis {k} has spacing {s}: using 1 mm")),
            None => {}
        }
    }
    let extra: usize = axes.iter().skip(3).map(|&a| h.sizes[a]).product();
    if extra == 0 {
        return Err(Error::format(path, "the fourth size is zero"));
    }
    let volumes = pick_volume(path, extra, opts.part.volume, &mut notes)?;
    if h.endian.is_none() && h.voxel_type.size() > 1 && h.encoding != Encoding::Ascii {
        notes.push("no endian field: assuming little-endian".into());
    }
    let endian = h.endian.unwrap_or_default();
    let (file, start) = match &h.data_file {
        None => (source.clone(), h.len as u64),
        Some(name) => {
            if name.contains('%') || name.split_whitespace().count() > 1 || name.starts_with("LIST")
            {
                return Err(Error::unsupported(
                    path,
                    format!("multi-file data ({name:?})"),
                ));
            }
            (source.sibling(name)?, 0)
        }
    };
    let spec = DataSpec {
        file,
        start,
        skip_lines: h.line_skip,
        skip: h.byte_skip,
        encoding: h.encoding,
        dims,
        voxel_type: h.voxel_type,
        endian,
        scale: None,
        volumes,
        trailing: false,
    };
    let (voxels, rounded) = read_voxels(&spec, opts.room())?;
    notes.extend(rounded.note(h.voxel_type.name()));
    let transform = transform(&h, &axes);
    Ok(
        Read0::new(path, dims, spacing, h.voxel_type, voxels, notes)?
            .with_transform(transform)
            .with_source(spec.file.path()),
    )
}

#[cfg(test)]
mod tests;
