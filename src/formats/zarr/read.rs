//! Reading one dataset (one resolution level) of a store: the voxels of one time point and
//! channel, chunk by chunk, into the volume's buffer.

use std::path::Path;

use rayon::prelude::*;
use zarrs::array::{Array, ArraySubset, ElementOwned};
use zarrs::storage::ReadableStorageTraits;

use super::Layout;
use super::failure::{self, Failure};
use super::guard::Guard;
use super::meta::ArrayMeta;
use super::root::Root;
use crate::error::{Error, Result};
use crate::formats::data::typed_buffer;
use crate::formats::data::wide::{Exact, Rounded};
use crate::formats::scratch::VoxelOut;
use crate::progress::Cancel;
use crate::volume::voxels::held_type;
use crate::volume::{Voxel, VoxelType, Voxels};

/// One dataset of an image, and which time point and channel of it to read.
#[derive(Clone, Copy, Debug)]
pub struct Dataset<'a> {
    /// Where the store lives.
    pub root: &'a Root,
    /// The image's node in the store.
    pub node: &'a str,
    /// The image as messages name it.
    pub image: &'a Path,
    /// The dataset's path in the image.
    pub path: &'a str,
    /// Its array's metadata.
    pub meta: &'a ArrayMeta,
    /// Where its axes are.
    pub layout: &'a Layout,
    /// The time point and channel read.
    pub at: [u64; 2],
    /// The memory budget.
    pub max_memory: u64,
    /// The folder for voxels beyond the budget (`LoadOptions::scratch`).
    pub scratch: Option<&'a Path>,
    /// Looked at before each chunk: raised, the read stops.
    pub cancel: &'a Cancel,
}

impl Dataset<'_> {
    /// The voxels of the dataset, of dimensions `dims` (x fastest): integers of at most 16 bits
    /// in their type, everything else as f32.
    pub fn voxels(&self, dims: [usize; 3]) -> Result<Voxels> {
        Ok(self.voxels_counted(dims)?.0)
    }

    /// [`Dataset::voxels`], with the 32-bit integers an f32 does not hold exactly counted.
    pub fn voxels_counted(&self, dims: [usize; 3]) -> Result<(Voxels, Rounded)> {
        let fail = |m: String| Error::format(self.image, m);
        let stored = self.meta.voxel_type().map_err(fail)?;
        check_chunks(self.image, self.meta, stored, self.max_memory)?;
        let step = self.meta.inner.as_ref().unwrap_or(&self.meta.chunks);
        check_reads(
            self.image,
            self.path,
            self.layout,
            step,
            (dims, self.root.is_remote()),
        )?;
        let guard = Guard::new(self.path, self.meta, stored.size() as u64)
            .map_err(|e| fail(format!("dataset {:?}: {e}", self.path)))?;
        let store = self.root.storage(self.node, self.max_memory, guard);
        let array = Array::open(store, &format!("/{}", self.path))
            .map_err(|e| fail(format!("dataset {:?}: {e}", self.path)))?;
        Reader {
            path: self.image,
            array: &array,
            layout: self.layout,
            at: self.at,
            step,
            chunks: &self.meta.chunks,
            dims,
            max_memory: self.root.room(self.max_memory),
            scratch: self.scratch,
            cancel: self.cancel,
        }
        .voxels(stored)
    }
}

/// Fails when one chunk, decoded, would claim more than a quarter of the budget (a hostile
/// chunk shape claims memory a small array never needs).
fn check_chunks(path: &Path, array: &ArrayMeta, ty: VoxelType, max_memory: u64) -> Result<()> {
    for (what, shape) in [
        ("chunk", Some(&array.chunks)),
        ("inner chunk", array.inner.as_ref()),
    ] {
        let Some(shape) = shape else { continue };
        let bytes = shape
            .iter()
            .try_fold(ty.size() as u64, |a, &n| a.checked_mul(n.max(1)));
        let limit = max_memory / 4;
        match bytes {
            Some(b) if b <= limit => {}
            _ => {
                let dims: Vec<String> = shape.iter().map(u64::to_string).collect();
                return Err(Error::TooLarge {
                    path: path.to_path_buf(),
                    what: format!("one {what} of {} {ty} voxels", dims.join("x")),
                    needed: bytes.unwrap_or(u64::MAX),
                    limit,
                    machine: false,
                    disk: false,
                });
            }
        }
    }
    Ok(())
}

/// The most requests one read of a dataset over HTTP makes (a chunk, or an inner chunk of a
/// shard, is one): a store of tiny chunks is refused, not fetched a million times over. Also the
/// most chunks of fewer than [`SMALL_CHUNK`] voxels one read of a local store takes.
pub const MAX_REQUESTS: u64 = 65_536;

/// Voxels a chunk holds below which its own cost (a file opened, or a shard's index entry read,
/// a codec run) outweighs its voxels': a local store of more than [`MAX_REQUESTS`] chunks this
/// small is refused before any is read (a 512³ store of one-voxel chunks is 134 million of them,
/// hours of work even when no chunk file exists).
pub const SMALL_CHUNK: u64 = 4096;

/// Fails when reading the dataset `path` of dimensions `dims` (x fastest), a chunk for each
/// `step` of it (in the axes' order), would read more than [`MAX_REQUESTS`] chunks: over HTTP
/// (`remote`) whatever their size, locally when they are smaller than [`SMALL_CHUNK`] voxels.
fn check_reads(
    image: &Path,
    path: &str,
    layout: &Layout,
    step: &[u64],
    (dims, remote): ([usize; 3], bool),
) -> Result<()> {
    let [nx, ny, nz] = dims.map(|n| n as u64);
    let [z, y, x] = layout.spatial;
    let per = |axis: Option<usize>, n: u64| axis.map_or(1, |a| n.div_ceil(step[a].max(1)));
    let side = |axis: Option<usize>, n: u64| axis.map_or(1, |a| step[a].clamp(1, n.max(1)));
    let reads = per(z, nz)
        .saturating_mul(per(y, ny))
        .saturating_mul(per(x, nx));
    let voxels = side(z, nz) * side(y, ny) * side(x, nx);
    if reads <= MAX_REQUESTS || (!remote && voxels >= SMALL_CHUNK) {
        return Ok(());
    }
    let shape: Vec<String> = step.iter().map(u64::to_string).collect();
    let (what, advice) = if remote {
        ("requests over HTTP", "download the store")
    } else {
        ("chunks of fewer than 4096 voxels", "rechunk the store")
    };
    Err(Error::format(
        image,
        format!(
            "dataset {path:?} is read in chunks of {} voxels: {reads} {what}, more than the \
             {MAX_REQUESTS} slabscope reads at once ({advice}, or read a coarser level with \
             --resolution)",
            shape.join("x")
        ),
    ))
}

/// `v`, or NaN (missing) for an infinity.
fn finite_or_nan(v: f32) -> f32 {
    if v.is_infinite() { f32::NAN } else { v }
}

/// How the voxels of one time point and channel are read, chunk by chunk, into the volume.
struct Reader<'a> {
    path: &'a Path,
    array: &'a Array<dyn ReadableStorageTraits>,
    layout: &'a Layout,
    /// The time point and channel read.
    at: [u64; 2],
    /// The chunk shape reads step by, in the axes' order (the inner chunk's when sharded).
    step: &'a [u64],
    /// The chunk (or shard) shape, in the axes' order.
    chunks: &'a [u64],
    dims: [usize; 3],
    max_memory: u64,
    scratch: Option<&'a Path>,
    cancel: &'a Cancel,
}

impl Reader<'_> {
    /// The voxels, held as integers of at most 16 bits are, everything else as f32; with the
    /// 32-bit integers an f32 does not hold exactly counted.
    fn voxels(&self, stored: VoxelType) -> Result<(Voxels, Rounded)> {
        fn done<T: Voxel>((out, rounded): (VoxelOut<T>, Rounded)) -> Result<(Voxels, Rounded)> {
            Ok((out.finish()?, rounded))
        }
        match held_type(stored, false) {
            VoxelType::U8 => done(self.read::<u8, u8>(|v| v)?),
            VoxelType::I8 => done(self.read::<i8, i8>(|v| v)?),
            VoxelType::U16 => done(self.read::<u16, u16>(|v| v)?),
            VoxelType::I16 => done(self.read::<i16, i16>(|v| v)?),
            // Infinities made missing as each value is stored, as every reader stores them.
            _ => match stored {
                VoxelType::U32 => done(self.read::<u32, f32>(|v| v as f32)?),
                VoxelType::I32 => done(self.read::<i32, f32>(|v| v as f32)?),
                VoxelType::F64 => done(self.read::<f64, f32>(|v| finite_or_nan(v as f32))?),
                _ => done(self.read::<f32, f32>(finite_or_nan)?),
            },
        }
    }

    /// Reads elements of type `E` into a volume of `T`, converting each with `to`: slabs of one
    /// chunk's depth along z in parallel, each chunk of a slab in turn, stopped between chunks
    /// when the load is cancelled.
    fn read<E: ElementOwned + Copy + Send + Sync + Exact, T: Voxel>(
        &self,
        to: fn(E) -> T,
    ) -> Result<(VoxelOut<T>, Rounded)> {
        let (path, dims) = (self.path, self.dims);
        let mut all = VoxelOut::new(path, dims, self.scratch, || {
            typed_buffer::<T>(path, dims, self.max_memory)
        })?;
        let out = all.all();
        let [nx, ny, nz] = self.dims;
        let step = |axis: Option<usize>| axis.map_or(1, |a| self.step[a].max(1) as usize);
        let [sz, sy, sx] = self.layout.spatial.map(step);
        let slab = nx * ny * sz.min(nz);
        let rounded = out
            .par_chunks_mut(slab)
            .enumerate()
            .map(|(k, out)| {
                let z0 = k * sz;
                let z1 = (z0 + sz).min(nz);
                let mut rounded = Rounded::default();
                for y0 in (0..ny).step_by(sy) {
                    for x0 in (0..nx).step_by(sx) {
                        self.cancel.check()?;
                        let box3 = [z0..z1, y0..(y0 + sy).min(ny), x0..(x0 + sx).min(nx)];
                        rounded.add(self.chunk(&box3, z0, out, to)?);
                    }
                }
                Ok::<Rounded, Error>(rounded)
            })
            .try_reduce(Rounded::default, |a, b| Ok(a.plus(b)))?;
        Ok((all, rounded))
    }

    /// Reads the box `[z, y, x]` of the volume into `out`, the slab that starts at slice `z0`;
    /// the values an f32 does not hold exactly, counted.
    fn chunk<E: ElementOwned + Copy + Exact, T: Voxel>(
        &self,
        [z, y, x]: &[std::ops::Range<usize>; 3],
        z0: usize,
        out: &mut [T],
        to: fn(E) -> T,
    ) -> Result<Rounded> {
        let [nx, ny, _] = self.dims;
        let ranges: Vec<std::ops::Range<u64>> = (0..self.array.dimensionality())
            .map(|a| {
                let span = |r: &std::ops::Range<usize>| r.start as u64..r.end as u64;
                if Some(a) == self.layout.time {
                    self.at[0]..self.at[0] + 1
                } else if Some(a) == self.layout.channel {
                    self.at[1]..self.at[1] + 1
                } else if Some(a) == self.layout.spatial[0] {
                    span(z)
                } else if Some(a) == self.layout.spatial[1] {
                    span(y)
                } else if Some(a) == self.layout.spatial[2] {
                    span(x)
                } else {
                    0..1
                }
            })
            .collect();
        let values: Vec<E> = self
            .array
            .retrieve_array_subset(&ArraySubset::new_with_ranges(&ranges))
            .map_err(|e| {
                // The chunk (or shard) that holds the box, by its key.
                let chunk: Vec<u64> = ranges
                    .iter()
                    .zip(self.chunks)
                    .map(|(r, &c)| r.start / c.max(1))
                    .collect();
                let key = self.array.chunk_key(&chunk);
                match failure::find(&e) {
                    // The guard's refusal names the chunk already.
                    Some(Failure::Refused(message)) => Error::format(self.path, message.clone()),
                    // The store's, naming the file from where the store is (a label image's
                    // `labels/NAME/` before the key over HTTP): said once, as the array's key.
                    Some(Failure::Unread { problem, .. }) => {
                        Error::format(self.path, format!("chunk {key}: {problem}"))
                    }
                    None => Error::format(self.path, format!("chunk {key}: {e}")),
                }
            })?;
        let width = x.len();
        for (i, row) in values.chunks_exact(width).enumerate() {
            let (dz, dy) = (i / y.len(), i % y.len());
            let at = ((z.start - z0 + dz) * ny + y.start + dy) * nx + x.start;
            for (o, &v) in out[at..at + width].iter_mut().zip(row) {
                *o = to(v);
            }
        }
        Ok(E::rounded(&values))
    }
}
