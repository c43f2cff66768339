//! Headerless raw voxels, described by options or by the file name (`bonsai_256x256x256_uint8.raw`,
//! `head.256x256x113.u16.raw`); read through a memory map.

use super::data::{DataSpec, Encoding, Skip, read_voxels};
use super::reader::Reader;
use super::{Format, LoadOptions, Read0, Source};
use crate::error::{Error, Result};
use crate::volume::{Endian, VoxelType, dims_string};

/// The raw reader.
pub(crate) struct Raw;

impl Reader for Raw {
    fn format(&self) -> Format {
        Format::Raw
    }

    fn title(&self) -> &'static str {
        "raw"
    }

    fn reads(&self) -> Option<&'static str> {
        Some("headerless raw data given its dimensions and voxel type")
    }

    fn fallback(&self) -> bool {
        true
    }

    /// Dimensions given make any file raw data.
    fn forced(&self, opts: &LoadOptions) -> bool {
        opts.raw.dims.is_some()
    }

    fn claims_name(&self, name: &str) -> bool {
        [".raw", ".bin", ".vol", ".img"]
            .iter()
            .any(|e| name.ends_with(e))
            || parse_raw_name(name).is_some()
    }

    /// Only a name that carries its dimensions, with a raw data extension.
    fn volume_name(&self, name: &str) -> bool {
        [".raw", ".bin", ".vol"].iter().any(|e| name.ends_with(e)) && parse_raw_name(name).is_some()
    }

    fn read(&self, source: &Source, opts: &LoadOptions) -> Result<Read0> {
        load(source, opts)
    }
}

/// How to read a headerless raw file; unset fields come from the file name or defaults.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RawOptions {
    /// Dimensions `[nx, ny, nz]`; setting them makes any file load as raw.
    pub dims: Option<[usize; 3]>,
    /// Voxel type.
    pub voxel_type: Option<VoxelType>,
    /// Spacing in mm (default 1).
    pub spacing: Option<[f64; 3]>,
    /// Byte order (default little).
    pub endian: Option<Endian>,
    /// Bytes to skip at the start of the file (default 0).
    pub offset: Option<u64>,
}

/// Parses `NXxNYxNZ` (e.g. `256x256x113`).
#[must_use]
pub fn parse_dims(text: &str) -> Option<[usize; 3]> {
    let parts: Vec<usize> = text
        .split(['x', 'X'])
        .map(|p| p.trim().parse().ok())
        .collect::<Option<_>>()?;
    <[usize; 3]>::try_from(parts).ok()
}

/// Dimensions and voxel type found in a raw file's name, e.g. `bonsai_256x256x256_uint8.raw`.
#[must_use]
pub fn parse_raw_name(name: &str) -> Option<([usize; 3], Option<VoxelType>)> {
    let tokens: Vec<&str> = name.split(['_', '.', '-', ' ']).collect();
    let dims = tokens.iter().find_map(|t| parse_dims(t))?;
    let ty = tokens.iter().find_map(|t| VoxelType::parse(t));
    Some((dims, ty))
}

fn load(source: &Source, opts: &LoadOptions) -> Result<Read0> {
    let path = source.path();
    let from_name = parse_raw_name(&source.name());
    let raw = &opts.raw;
    let dims = raw
        .dims
        .or(from_name.map(|n| n.0))
        .ok_or_else(|| Error::RawUndescribed {
            path: path.to_path_buf(),
            missing: &["dims", "type"],
            detail: "headerless raw data (or a name like NAME_256x256x113_uint16.raw)".into(),
        })?;
    let offset = raw.offset.unwrap_or(0);
    let Some(voxel_type) = raw.voxel_type.or(from_name.and_then(|n| n.1)) else {
        return Err(Error::RawUndescribed {
            path: path.to_path_buf(),
            missing: &["type"],
            detail: missing_type_detail(source, dims, offset),
        });
    };
    let spec = DataSpec {
        file: source.clone(),
        start: offset,
        skip_lines: 0,
        skip: Skip::Bytes(0),
        encoding: Encoding::Raw,
        dims,
        voxel_type,
        endian: raw.endian.unwrap_or_default(),
        scale: None,
        volumes: (0, 1),
        trailing: false,
    };
    let (voxels, rounded) = read_voxels(&spec, opts.room())?;
    let spacing = raw.spacing.unwrap_or([1.0; 3]);
    let mut notes: Vec<String> = rounded.note(voxel_type.name()).into_iter().collect();
    if raw.spacing.is_none() {
        notes.push("raw data carries no spacing: using 1 mm per voxel".into());
    }
    Read0::new(path, dims, spacing, voxel_type, voxels, notes)
}

/// What is known of raw data without a voxel type, with the bytes per voxel its size suggests.
fn missing_type_detail(source: &Source, dims: [usize; 3], offset: u64) -> String {
    let voxels = dims.iter().map(|&d| d as u64).product::<u64>();
    let len = source.len().unwrap_or(0);
    let data = len.saturating_sub(offset);
    let hint = if voxels > 0 && data.is_multiple_of(voxels) && data > 0 {
        format!(" (its size suggests {} bytes per voxel)", data / voxels)
    } else {
        String::new()
    };
    format!("headerless raw data of {}{hint}", dims_string(dims))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_dims_and_types_from_names() {
        assert_eq!(
            parse_raw_name("bonsai_256x256x256_uint8.raw"),
            Some(([256, 256, 256], Some(VoxelType::U8)))
        );
        assert_eq!(
            parse_raw_name("head.256x256x113.u16.raw"),
            Some(([256, 256, 113], Some(VoxelType::U16)))
        );
        assert_eq!(
            parse_raw_name("ct-512X512X45.raw"),
            Some(([512, 512, 45], None))
        );
        assert_eq!(parse_raw_name("scan.raw"), None);
        assert_eq!(parse_dims("1x2"), None);
        assert_eq!(parse_dims("1x2x3x4"), None);
    }
}
