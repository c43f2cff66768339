//! VolumeShop / TU Wien `.dat`: three little-endian u16 dimensions, then u16 voxels, recognised by
//! the file size being exactly 6 + 2·nx·ny·nz.

use std::io::Read;
use std::path::Path;

use super::data::{DataSpec, Encoding, Skip, read_voxels};
use super::reader::Reader;
use super::{Format, LoadOptions, Read0, Source};
use crate::error::{Error, Result};
use crate::volume::{Endian, VoxelType, dims_string};

/// The VolumeShop reader.
pub(crate) struct VolumeShop;

impl Reader for VolumeShop {
    fn format(&self) -> Format {
        Format::VolumeShop
    }

    fn title(&self) -> &'static str {
        "VolumeShop"
    }

    fn reads(&self) -> Option<&'static str> {
        Some("VolumeShop .dat")
    }

    #[allow(clippy::case_sensitive_file_extension_comparisons)] // the name is lowercased
    fn claims_name(&self, name: &str) -> bool {
        name.ends_with(".dat")
    }

    fn volume_name(&self, name: &str) -> bool {
        self.claims_name(name)
    }

    fn read(&self, source: &Source, opts: &LoadOptions) -> Result<Read0> {
        load(source, opts)
    }
}

/// The dimensions a `.dat` header of `head` claims, when the file size `len` agrees with them.
pub(crate) fn check_header(path: &Path, head: &[u8], len: u64) -> Result<[usize; 3]> {
    if head.len() < 6 {
        return Err(Error::format(
            path,
            format!("not a VolumeShop .dat file: {len} bytes is shorter than its 6-byte header"),
        ));
    }
    let d = |i: usize| usize::from(u16::from_le_bytes([head[2 * i], head[2 * i + 1]]));
    let dims = [d(0), d(1), d(2)];
    let expected = 6 + 2 * dims.iter().map(|&v| v as u64).product::<u64>();
    if dims.contains(&0) || expected != len {
        return Err(Error::format(
            path,
            format!(
                "not a VolumeShop .dat file: its header says {} u16 voxels ({expected} bytes with the header) \
                 but the file holds {len} bytes; other raw data needs its dimensions and voxel type",
                dims_string(dims)
            ),
        ));
    }
    Ok(dims)
}

fn load(source: &Source, opts: &LoadOptions) -> Result<Read0> {
    let path = source.path();
    let mut file = source.open()?;
    let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
    let mut head = [0u8; 6];
    let n = file.read(&mut head).map_err(|e| Error::io(path, e))?;
    let dims = check_header(path, &head[..n], len)?;
    let spec = DataSpec {
        file: source.clone(),
        start: 6,
        skip_lines: 0,
        skip: Skip::Bytes(0),
        encoding: Encoding::Raw,
        dims,
        voxel_type: VoxelType::U16,
        endian: Endian::Little,
        scale: None,
        volumes: (0, 1),
        trailing: false,
    };
    let (voxels, _) = read_voxels(&spec, opts.room())?; // u16: f32s exactly
    let notes = vec!["VolumeShop .dat files carry no spacing: using 1 mm".into()];
    Read0::new(path, dims, [1.0; 3], VoxelType::U16, voxels, notes)
}
