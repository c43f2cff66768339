//! HDF5 (`.h5`, `.hdf5`, `.hdf`, `.nxs`, `.ims`): the files of synchrotron micro-CT (`DXchange`'s
//! `/exchange/data`, `NeXus`), ilastik, Fiji and Imaris. One dataset of three dimensions (or four,
//! a series of volumes, chosen with `--volume`) is read: the one `--array` names by its path, else
//! `DXchange`'s `/exchange/data`, else the file's only one. It is stored in C order as h5py writes
//! it, the last index fastest, so its indices are z, y, x (t, z, y, x), as OME-Zarr's are.
//!
//! The file's structure, its chunk indexes and its filters (deflate, shuffle, Fletcher-32 and
//! what `rust-hdf5` decodes besides) are `rust-hdf5`'s, a pure-Rust reader (docs/design.md,
//! "HDF5"); what is checked here is what slabscope asks of every reader: the dataset's size
//! and its chunks' weighed against the budget before anything is read, datasets whose data is
//! in other files refused, one line for every error. The voxel size is the `element_size_um`
//! attribute's (z, y, x in µm, as ilastik and Fiji write it) where there is one; otherwise a
//! note says 1 mm was used. An Imaris file is read as `imaris.rs` says. A beamline's raw file (projections, with `theta`, `data_white` or
//! `data_dark` beside them) is refused unless `--array` names the dataset.

mod dxchange;
mod imaris;
mod nexus;
mod pick;

use std::path::Path;

use rust_hdf5::{ByteOrder, DatatypeMessage, FileLocking, H5Dataset, H5File, StorageLayout};

use super::data::wide::{Wide, read_wide};
use super::data::{DataSpec, Encoding, Skip, one_channel, pick_volume, read_voxels_from};
use super::reader::{Reader, Sniff};
use super::{Format, LoadOptions, Read0, Source};
use crate::error::{Error, Result};
use crate::volume::voxels::held_type;
use crate::volume::{Endian, VoxelType};

/// The HDF5 reader.
pub(crate) struct Hdf5;

/// The signature every HDF5 superblock starts with.
const SIGNATURE: &[u8; 8] = b"\x89HDF\r\n\x1a\n";

impl Reader for Hdf5 {
    fn format(&self) -> Format {
        Format::Hdf5
    }

    fn title(&self) -> &'static str {
        "HDF5"
    }

    fn reads(&self) -> Option<&'static str> {
        Some("HDF5 datasets")
    }

    /// The signature at the start, or after a user block (512 bytes, or a larger power of two).
    fn sniff(&self, head: &[u8]) -> Sniff {
        let at = |o: usize| head.get(o..o + 8) == Some(SIGNATURE);
        if at(0) || [512, 1024, 2048].into_iter().any(at) {
            Sniff::Mine
        } else {
            Sniff::No
        }
    }

    fn extensions(&self) -> &'static [&'static str] {
        &[".h5", ".hdf5", ".hdf", ".he5", ".nxs", ".ims"]
    }

    fn volumes(&self) -> bool {
        true
    }

    /// An Imaris file's channels.
    fn channels(&self) -> bool {
        true
    }

    /// Its datasets.
    fn arrays(&self) -> bool {
        true
    }

    fn details_key(&self) -> Option<&'static str> {
        Some("hdf5")
    }

    fn read(&self, source: &Source, opts: &LoadOptions) -> Result<Read0> {
        load(source, opts)
    }

    /// An Imaris file's coarser resolution level on the pyramid's grid.
    fn preview(
        &self,
        source: &Source,
        opts: &LoadOptions,
        max_voxels: usize,
    ) -> Result<Option<Read0>> {
        let path = source.path();
        let named = source.name().to_ascii_lowercase();
        #[allow(clippy::case_sensitive_file_extension_comparisons)] // lowercased
        let ims = named.ends_with(".ims");
        if !ims || opts.part.array.is_some() || !path.is_file() {
            return Ok(None);
        }
        if self.sniff(&source.head(4096)?) != Sniff::Mine {
            return Ok(None);
        }
        let (file, listing) = open(path)?;
        let Some((level, k, dims0)) =
            imaris::preview_level(path, &file, &listing, opts, max_voxels)?
        else {
            return Ok(None);
        };
        let mut read = load_level(source, opts, level)?;
        let finest = imaris::finest(&read.volume, dims0);
        read.volume = read.volume.into_pyramid_level(k, finest, &[]);
        Ok(Some(read))
    }
}

/// The first line of an error of `rust-hdf5`, at most 200 characters.
fn message(e: &rust_hdf5::Hdf5Error) -> String {
    let text = e.to_string();
    let line = text.lines().next().unwrap_or_default();
    crate::error::names::text(&line.chars().take(200).collect::<String>())
}

/// The voxel type and byte order of a dataset's elements, and their 64-bit integer type (held as
/// f32); an error naming the dataset for a type slabscope does not read.
fn voxel_type(
    path: &Path,
    name: &str,
    dt: &DatatypeMessage,
) -> Result<(VoxelType, Endian, Option<Wide>)> {
    let endian = |order: &ByteOrder| match order {
        ByteOrder::LittleEndian => Endian::Little,
        ByteOrder::BigEndian => Endian::Big,
    };
    let ty = match dt {
        DatatypeMessage::FixedPoint {
            size,
            byte_order,
            signed,
            ..
        } => {
            let ty = match (size, signed) {
                (1, false) => Some((VoxelType::U8, None)),
                (1, true) => Some((VoxelType::I8, None)),
                (2, false) => Some((VoxelType::U16, None)),
                (2, true) => Some((VoxelType::I16, None)),
                (4, false) => Some((VoxelType::U32, None)),
                (4, true) => Some((VoxelType::I32, None)),
                (8, false) => Some((VoxelType::F32, Some(Wide::U64))),
                (8, true) => Some((VoxelType::F32, Some(Wide::I64))),
                _ => None,
            };
            ty.map(|(t, wide)| (t, endian(byte_order), wide))
        }
        DatatypeMessage::FloatingPoint {
            size, byte_order, ..
        } => match size {
            4 => Some((VoxelType::F32, endian(byte_order), None)),
            8 => Some((VoxelType::F64, endian(byte_order), None)),
            _ => None,
        },
        _ => None,
    };
    ty.ok_or_else(|| {
        Error::unsupported(
            path,
            format!(
                "dataset {name} holds {}: slabscope reads 8- to 64-bit integers and 32- and \
                 64-bit reals",
                pick::type_name(dt)
            ),
        )
    })
}

/// Opens the HDF5 file `path` for reading, and lists its datasets.
fn open(path: &Path) -> Result<(H5File, Vec<pick::Found>)> {
    let file = H5File::options()
        .locking(FileLocking::Disabled)
        .open(path)
        .map_err(|e| Error::format(path, format!("not a readable HDF5 file: {}", message(&e))))?;
    let listing = pick::list(path, &file)?;
    Ok((file, listing))
}

fn load(source: &Source, opts: &LoadOptions) -> Result<Read0> {
    load_level(source, opts, 0)
}

/// Reads the volume `opts` pick of `source`, at resolution level `level` of an Imaris file
/// (level 0 of any other).
fn load_level(source: &Source, opts: &LoadOptions, level: usize) -> Result<Read0> {
    let path = source.path();
    let (file, listing) = open(path)?;
    let mut notes = Vec::new();
    let imaris = match opts.part.array {
        None => imaris::pick(path, &file, &listing, opts, level, &mut notes)?,
        Some(_) => None,
    };
    let chosen = match &imaris {
        Some(i) => listing
            .iter()
            .find(|f| f.path == i.path)
            .ok_or_else(|| Error::format(path, format!("holds no dataset /{}", i.path)))?,
        None if opts.part.channel > 0 => return Err(one_channel(path, 1, opts.part.channel)),
        None => pick::choose(path, &listing, opts.part.array.as_deref(), &mut notes)?,
    };
    let name = chosen.shown();
    let ds = file
        .dataset(&chosen.path)
        .map_err(|e| Error::format(path, format!("dataset {name}: {}", message(&e))))?;
    let (ty, endian, wide) = voxel_type(
        path,
        &name,
        &ds.datatype().map_err(|e| bad(path, &name, &e))?,
    )?;
    // The bytes of one stored value.
    let size = wide.map_or(ty.size(), |_| Wide::SIZE);
    check_storage(path, &name, &ds, size as u64, opts.max_memory)?;
    let shape = &chosen.shape;
    let rank = shape.len();
    let mut dims = [shape[rank - 1], shape[rank - 2], shape[rank - 3]];
    let count = if rank == 4 { shape[0] } else { 1 };
    let volume = match imaris {
        Some(_) if rank == 4 => return Err(pick::rank_error(path, chosen)),
        Some(_) => 0,
        None => pick_volume(path, count, opts.part.volume, &mut notes)?.0,
    };
    check_budget(path, &name, shape, (ty, size), opts.max_memory)?;
    let mut bytes = read_volume(path, &name, &ds, dims, size, (volume, count))?;
    if let Some(cut) = imaris.as_ref().and_then(|i| i.size) {
        imaris::crop(path, &name, &mut bytes, dims, cut, size)?;
        dims = cut;
    }
    let spec = DataSpec {
        file: source.clone(),
        start: 0,
        skip_lines: 0,
        skip: Skip::Bytes(0),
        encoding: Encoding::Raw,
        dims,
        voxel_type: ty,
        endian,
        scale: None,
        volumes: (0, 1),
        trailing: false,
    };
    let mut stream = bytes.as_slice();
    let (voxels, rounded, stored) = if let Some(wide) = wide {
        let (voxels, rounded) = read_wide(&spec, wide, stream, "HDF5 dataset", opts.room())?;
        (voxels, rounded, wide.name())
    } else {
        let (voxels, rounded) = read_voxels_from(&spec, &mut stream, "HDF5 dataset", opts.room())?;
        (voxels, rounded, ty.name())
    };
    notes.extend(rounded.note(stored));
    drop(bytes);
    let imaris_spacing = imaris.and_then(|i| i.spacing);
    let spacing = voxel_size(
        &file,
        &ds,
        (&chosen.path, &name),
        imaris_spacing,
        &mut notes,
    );
    let mut read = Read0::new(path, dims, spacing, ty, voxels, notes)?;
    read.details = Some(std::sync::Arc::new(pick::details(&listing, &chosen.path)));
    Ok(read)
}

/// The voxel size of the dataset `ds` (at `path`, shown as `name`) in mm: its `element_size_um`,
/// an Imaris file's (`imaris`), or `DXchange`'s, else 1 mm with a note.
fn voxel_size(
    file: &H5File,
    ds: &H5Dataset,
    (path, name): (&str, &str),
    imaris: Option<[f64; 3]>,
    notes: &mut Vec<String>,
) -> [f64; 3] {
    let given = imaris.or_else(|| pick::spacing(ds)).or_else(|| {
        let shape = ds.shape();
        let zyx = match shape.as_slice() {
            [.., z, y, x] => [*z, *y, *x],
            _ => return None,
        };
        let (spacing, note) =
            dxchange::spacing(file, path).or_else(|| nexus::spacing(file, path, zyx))?;
        notes.push(note);
        Some(spacing)
    });
    given.unwrap_or_else(|| {
        notes.push(format!(
            "dataset {name} gives no voxel size (no element_size_um attribute, no DXchange \
             pixel size, no NeXus axes): using 1 mm"
        ));
        [1.0; 3]
    })
}

/// The stored bytes of volume `volume.0` of the `volume.1` the dataset `ds` holds, each of
/// `dims` voxels of `size` bytes; the dataset is read whole.
fn read_volume(
    path: &Path,
    name: &str,
    ds: &H5Dataset,
    dims: [usize; 3],
    size: usize,
    (volume, count): (usize, usize),
) -> Result<Vec<u8>> {
    let mut bytes = ds.read_raw_bytes().map_err(|e| bad(path, name, &e))?;
    let one = dims.iter().product::<usize>() * size;
    if bytes.len() != one * count {
        return Err(Error::format(
            path,
            format!(
                "dataset {name} read as {} bytes, not the {} its shape says",
                bytes.len(),
                one * count
            ),
        ));
    }
    if volume > 0 {
        bytes.drain(..one * volume);
    }
    bytes.truncate(one);
    Ok(bytes)
}

/// The error of `rust-hdf5` reading the dataset `name`, in one line.
fn bad(path: &Path, name: &str, e: &rust_hdf5::Hdf5Error) -> Error {
    Error::format(path, format!("dataset {name}: {}", message(e)))
}

/// Refuses a dataset whose data is not in the file (a virtual dataset, external storage), and
/// chunks of no voxel or of more than `max_memory` bytes (of `size`-byte elements).
fn check_storage(
    path: &Path,
    name: &str,
    ds: &H5Dataset,
    size: u64,
    max_memory: u64,
) -> Result<()> {
    let layout = ds.storage_layout().map_err(|e| bad(path, name, &e))?;
    let external = !ds
        .external_files()
        .map_err(|e| bad(path, name, &e))?
        .is_empty();
    if matches!(layout, StorageLayout::Virtual) || external {
        return Err(Error::unsupported(
            path,
            format!(
                "dataset {name} keeps its data in other files (a virtual dataset or external \
                 storage): slabscope reads data stored in the file"
            ),
        ));
    }
    if let Some(chunk) = ds.chunk_dims() {
        let shape = ds.shape();
        if chunk.len() != shape.len() || chunk.contains(&0) {
            return Err(Error::format(
                path,
                format!(
                    "dataset {name} has chunks of {chunk:?} for a shape of {shape:?}: a chunk \
                     needs one size a dimension, none zero"
                ),
            ));
        }
        let bytes = chunk.iter().try_fold(size, |a, &d| a.checked_mul(d as u64));
        if bytes.is_none_or(|b| b > max_memory) {
            return Err(Error::TooLarge {
                path: path.to_path_buf(),
                what: format!("a chunk of {chunk:?} of dataset {name}"),
                needed: bytes.unwrap_or(u64::MAX),
                limit: max_memory,
                machine: false,
                disk: false,
            });
        }
    }
    Ok(())
}

/// Checks that the dataset's stored bytes (every volume of it, read at once, each value of
/// `size` bytes) and the volume they are decoded into (as `ty` is held) fit in `max_memory`
/// together, and that each chunk of it does.
fn check_budget(
    path: &Path,
    name: &str,
    shape: &[usize],
    (ty, size): (VoxelType, usize),
    max_memory: u64,
) -> Result<()> {
    let rank = shape.len();
    let voxels = shape[rank - 3..]
        .iter()
        .try_fold(1u64, |a, &d| a.checked_mul(d as u64));
    let stored = shape
        .iter()
        .try_fold(size as u64, |a, &d| a.checked_mul(d as u64));
    let held = voxels.and_then(|n| n.checked_mul(held_type(ty, false).size() as u64));
    let needed = stored.zip(held).and_then(|(s, h)| s.checked_add(h));
    match needed {
        Some(n) if n <= max_memory => Ok(()),
        _ => Err(Error::TooLarge {
            path: path.to_path_buf(),
            what: format!(
                "dataset {name}, {} {} voxels, read whole and then decoded",
                shape
                    .iter()
                    .map(usize::to_string)
                    .collect::<Vec<_>>()
                    .join("x"),
                if size == ty.size() {
                    ty.to_string()
                } else {
                    "64-bit integer".into()
                }
            ),
            needed: needed.unwrap_or(u64::MAX),
            limit: max_memory,
            machine: false,
            disk: false,
        }),
    }
}

#[cfg(test)]
mod tests;
