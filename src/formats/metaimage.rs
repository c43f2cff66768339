//! MetaImage (`.mha` with local data, `.mhd` with a data file): `Key = Value` lines ending with
//! `ElementDataFile`.

use std::io::Read;
use std::path::Path;

use super::data::{DataSpec, Encoding, Skip, pick_volume, read_voxels};
use super::reader::{Reader, Sniff};
use super::{Format, LoadOptions, Read0, Source};
use crate::error::{Error, Result};
use crate::geometry::WorldTransform;
use crate::volume::{Endian, VoxelType};

const MAX_HEADER: u64 = 1 << 20;

/// Keys that may open a MetaImage header.
const OPENING_KEYS: [&str; 6] = [
    "ObjectType",
    "NDims",
    "Comment",
    "ObjectSubType",
    "TransformType",
    "DimSize",
];

/// The MetaImage reader.
pub(crate) struct MetaImage;

impl Reader for MetaImage {
    fn format(&self) -> Format {
        Format::MetaImage
    }

    fn title(&self) -> &'static str {
        "MetaImage"
    }

    fn sniff(&self, head: &[u8]) -> Sniff {
        if looks_like(head) {
            Sniff::Mine
        } else {
            Sniff::No
        }
    }

    fn extensions(&self) -> &'static [&'static str] {
        &[".mha", ".mhd"]
    }

    fn volumes(&self) -> bool {
        true
    }

    fn read(&self, source: &Source, opts: &LoadOptions) -> Result<Read0> {
        load(source, opts)
    }
}

/// Whether `head` starts like a MetaImage header.
fn looks_like(head: &[u8]) -> bool {
    let first = head.split(|&b| b == b'\n').next().unwrap_or_default();
    let first = String::from_utf8_lossy(first);
    first.split_once('=').is_some_and(|(k, _)| {
        OPENING_KEYS
            .iter()
            .any(|o| k.trim().eq_ignore_ascii_case(o))
    })
}

/// The fields of a MetaImage header that slabscope uses.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Header {
    pub dims: Vec<usize>,
    pub voxel_type: VoxelType,
    pub spacing: Option<Vec<f64>>,
    pub big_endian: bool,
    pub compressed: bool,
    pub skip: Skip,
    pub channels: usize,
    pub data_file: String,
    /// `TransformMatrix`: each axis's direction in LPS, one after the other.
    pub directions: Option<Vec<f64>>,
    /// `Offset`: the world position of voxel (0, 0, 0), LPS mm.
    pub offset: Option<Vec<f64>>,
    /// Bytes up to and including the `ElementDataFile` line.
    pub len: usize,
}

fn element_type(path: &Path, name: &str) -> Result<VoxelType> {
    Ok(match name {
        "MET_UCHAR" => VoxelType::U8,
        "MET_CHAR" => VoxelType::I8,
        "MET_USHORT" => VoxelType::U16,
        "MET_SHORT" => VoxelType::I16,
        "MET_UINT" => VoxelType::U32,
        "MET_INT" => VoxelType::I32,
        "MET_FLOAT" => VoxelType::F32,
        "MET_DOUBLE" => VoxelType::F64,
        other => return Err(Error::unsupported(path, format!("ElementType {other}"))),
    })
}

fn boolean(value: &str) -> bool {
    matches!(value.to_ascii_lowercase().as_str(), "true" | "1" | "yes")
}

/// Header fields as they are read, before the required ones are checked.
#[derive(Default)]
struct Fields {
    ndims: Option<usize>,
    dims: Option<Vec<usize>>,
    voxel_type: Option<VoxelType>,
    spacing: Option<Vec<f64>>,
    big_endian: bool,
    compressed: bool,
    skip: Option<Skip>,
    channels: Option<usize>,
    data_file: Option<String>,
    directions: Option<Vec<f64>>,
    offset: Option<Vec<f64>>,
}

/// Reads one `Key = Value` line into `f`.
fn read_field(path: &Path, f: &mut Fields, key: &str, value: &str) -> Result<()> {
    let bad = |m: String| Error::format(path, m);
    let numbers = |what: &str| -> Result<Vec<f64>> {
        value
            .split_whitespace()
            .map(|t| t.parse().ok())
            .collect::<Option<_>>()
            .ok_or_else(|| bad(format!("{what} {value:?} are not numbers")))
    };
    match key {
        "NDims" => f.ndims = Some(value.parse().map_err(|_| bad(format!("NDims {value:?}")))?),
        "DimSize" => {
            f.dims = Some(
                value
                    .split_whitespace()
                    .map(|t| t.parse().ok())
                    .collect::<Option<_>>()
                    .ok_or_else(|| bad(format!("DimSize {value:?} are not whole numbers")))?,
            );
        }
        "ElementType" => f.voxel_type = Some(element_type(path, value)?),
        "ElementSpacing" => f.spacing = Some(numbers("ElementSpacing")?),
        "ElementSize" if f.spacing.is_none() => f.spacing = Some(numbers("ElementSize")?),
        "ElementByteOrderMSB" | "BinaryDataByteOrderMSB" => f.big_endian = boolean(value),
        "CompressedData" => f.compressed = boolean(value),
        "ElementNumberOfChannels" => {
            f.channels = Some(
                value
                    .parse()
                    .map_err(|_| bad(format!("ElementNumberOfChannels {value:?}")))?,
            );
        }
        "HeaderSize" => {
            f.skip = Some(match value.parse::<i64>() {
                Ok(-1) => Skip::FromEnd,
                Ok(n) if n >= 0 => Skip::Bytes(n as u64),
                _ => return Err(bad(format!("HeaderSize {value:?}"))),
            });
        }
        "ElementDataFile" => f.data_file = Some(value.to_string()),
        "TransformMatrix" | "Rotation" | "Orientation" => {
            f.directions = Some(numbers("TransformMatrix")?);
        }
        "Offset" | "Position" | "Origin" => f.offset = Some(numbers("Offset")?),
        _ => {}
    }
    Ok(())
}

/// Parses a MetaImage header from the start of `bytes`.
pub(crate) fn parse_header(path: &Path, bytes: &[u8]) -> Result<Header> {
    let bad = |m: String| Error::format(path, m);
    let mut f = Fields::default();
    let mut pos = 0;
    while pos < bytes.len() && f.data_file.is_none() {
        let end = bytes[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |i| pos + i);
        let line = String::from_utf8_lossy(&bytes[pos..end]);
        let line = line.trim();
        pos = (end + 1).min(bytes.len());
        if line.is_empty() {
            continue;
        }
        let Some((key, value)) = line.split_once('=') else {
            return Err(bad(format!("header line {line:?} is not \"Key = Value\"")));
        };
        read_field(path, &mut f, key.trim(), value.trim())?;
    }
    let missing = |field: &str| bad(format!("header has no {field} field"));
    let h = Header {
        dims: f.dims.ok_or_else(|| missing("DimSize"))?,
        voxel_type: f.voxel_type.ok_or_else(|| missing("ElementType"))?,
        spacing: f.spacing,
        big_endian: f.big_endian,
        compressed: f.compressed,
        skip: f.skip.unwrap_or(Skip::Bytes(0)),
        channels: f.channels.unwrap_or(1),
        directions: f.directions,
        offset: f.offset,
        data_file: f
            .data_file
            .ok_or_else(|| missing("ElementDataFile (it must be the last field)"))?,
        len: pos,
    };
    if let Some(n) = f.ndims
        && n != h.dims.len()
    {
        return Err(bad(format!(
            "NDims is {n} but DimSize lists {} numbers",
            h.dims.len()
        )));
    }
    if !(1..=4).contains(&h.dims.len()) {
        return Err(Error::unsupported(
            path,
            format!("{}-dimensional MetaImage", h.dims.len()),
        ));
    }
    if h.channels != 1 {
        return Err(Error::unsupported(
            path,
            format!(
                "{} channels per voxel; slabscope reads scalar volumes",
                h.channels
            ),
        ));
    }
    Ok(h)
}

fn load(source: &Source, opts: &LoadOptions) -> Result<Read0> {
    let path = source.path();
    let mut bytes = Vec::new();
    source
        .open()?
        .take(MAX_HEADER)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    let h = parse_header(path, &bytes)?;
    let mut notes = Vec::new();
    let mut dims = [1usize; 3];
    let mut spacing = [1.0f64; 3];
    for k in 0..h.dims.len().min(3) {
        dims[k] = h.dims[k];
        if let Some(s) = h.spacing.as_ref().and_then(|s| s.get(k)) {
            if s.is_finite() && *s > 0.0 {
                spacing[k] = *s;
            } else {
                notes.push(format!("ElementSpacing[{k}] is {s}: using 1 mm"));
            }
        }
    }
    let extra = h.dims.get(3).copied().unwrap_or(1);
    if extra == 0 {
        return Err(Error::format(path, "the fourth DimSize is zero"));
    }
    let volumes = pick_volume(path, extra, opts.part.volume, &mut notes)?;
    let (file, start, skip) = match h.data_file.as_str() {
        "LOCAL" => (source.clone(), h.len as u64, Skip::Bytes(0)),
        name if name.starts_with("LIST")
            || name.contains('%')
            || name.split_whitespace().count() > 1 =>
        {
            return Err(Error::unsupported(
                path,
                format!("multi-file data ({name:?})"),
            ));
        }
        name => (source.sibling(name)?, 0, h.skip),
    };
    let spec = DataSpec {
        file,
        start,
        skip_lines: 0,
        skip,
        encoding: if h.compressed {
            Encoding::Zlib
        } else {
            Encoding::Raw
        },
        dims,
        voxel_type: h.voxel_type,
        endian: if h.big_endian {
            Endian::Big
        } else {
            Endian::Little
        },
        scale: None,
        volumes,
        trailing: false,
    };
    let (voxels, rounded) = read_voxels(&spec, opts.room())?;
    notes.extend(rounded.note(h.voxel_type.name()));
    let transform = transform(&h, spacing);
    Ok(
        Read0::new(path, dims, spacing, h.voxel_type, voxels, notes)?
            .with_transform(transform)
            .with_source(spec.file.path()),
    )
}

/// The voxel-to-world transform of a 3D header with `TransformMatrix` or `Offset`: ITK's world
/// is LPS, and the matrix lists each axis's direction in turn.
fn transform(h: &Header, spacing: [f64; 3]) -> Option<WorldTransform> {
    if h.dims.len() < 3 || (h.directions.is_none() && h.offset.is_none()) {
        return None;
    }
    let identity = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    let m = h.directions.as_deref().unwrap_or(&identity);
    let o = h.offset.as_deref().unwrap_or(&[0.0; 3]);
    if m.len() != 9 || o.len() != 3 {
        return None;
    }
    let linear = std::array::from_fn(|r| std::array::from_fn(|c| m[3 * c + r] * spacing[c]));
    Some(WorldTransform::lps(linear, [o[0], o[1], o[2]]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Header> {
        parse_header(Path::new("t.mha"), text.as_bytes())
    }

    #[test]
    fn parses_the_fields() {
        let text = "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = True\n\
                    CompressedData = False\nElementSpacing = 1 2 3.5\nDimSize = 181 217 3\n\
                    ElementType = MET_SHORT\nElementDataFile = LOCAL\nDATA";
        let h = parse(text).unwrap();
        assert_eq!(h.dims, vec![181, 217, 3]);
        assert_eq!(h.voxel_type, VoxelType::I16);
        assert_eq!(h.spacing, Some(vec![1.0, 2.0, 3.5]));
        assert!(h.big_endian && !h.compressed);
        assert_eq!(h.len, text.len() - 4);
    }

    #[test]
    fn rejects_with_reasons() {
        let err = |t: &str| parse(t).unwrap_err().to_string();
        assert!(
            err("NDims = 3\nDimSize = 2 2\nElementType = MET_UCHAR\nElementDataFile = x\n")
                .contains("NDims is 3")
        );
        assert!(err("DimSize = 2 2 2\nElementType = MET_LONG\n").contains("MET_LONG"));
        assert!(err("DimSize = 2 2 2\nElementType = MET_UCHAR\n").contains("ElementDataFile"));
        assert!(err("DimSize = 2 2 2\nElementType = MET_UCHAR\nElementNumberOfChannels = 3\nElementDataFile = x\n")
            .contains("3 channels"));
    }

    #[test]
    fn recognises_headers() {
        assert!(looks_like(b"ObjectType = Image\n"));
        assert!(looks_like(b"NDims=3\n"));
        assert!(!looks_like(b"Hello = World\n"));
    }
}
