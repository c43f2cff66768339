//! A `.vti` file of several `<Piece>`s, as `vtkXMLImageDataWriter` streams a large image: each
//! piece its own `Extent` within the image's `WholeExtent`, its own arrays. Each piece's array is
//! read as a file of one piece is, then placed in the whole volume. The pieces must cover the
//! whole extent; where they overlap (VTK's pieces of point data share their boundary points)
//! their values must agree. The whole volume and the largest piece are weighed together against
//! the budget before anything is read.

use roxmltree::Node;

use super::read::read_array;
use super::{Array, Layout, integers, pick_array, voxel_dims};
use crate::error::{Error, Result};
use crate::formats::LoadOptions;
use crate::formats::data::DataSpec;
use crate::formats::data::wide::Rounded;
use crate::formats::scratch::Room;
use crate::volume::voxels::{held_type, with_voxels};
use crate::volume::{Voxel, VoxelType, Voxels, dims_string};

/// One piece: its array, where its first voxel lies in the whole volume, and its dims.
struct Piece<'a> {
    array: Array<'a>,
    at: [usize; 3],
    dims: [usize; 3],
}

/// The volume `spec` describes (the whole extent `whole`), assembled from the arrays of
/// `pieces` that `first` (the first piece's) names; with the 64-bit values rounded to f32.
pub(super) fn assemble(
    spec: &DataSpec,
    pieces: &[Node],
    whole: [i64; 6],
    first: &Array,
    (layout, bytes): (Layout, &[u8]),
    opts: &LoadOptions,
) -> Result<(Voxels, Rounded)> {
    let found = pieces
        .iter()
        .enumerate()
        .map(|(i, &node)| piece(spec, node, i, whole, first, opts))
        .collect::<Result<Vec<Piece>>>()?;
    let held: Vec<VoxelType> = found.iter().map(|p| held_of(&p.array)).collect();
    let out_type = if held.iter().all(|&h| h == held[0]) {
        held[0]
    } else {
        VoxelType::F32
    };
    check_budget(spec, &found, out_type, opts.max_memory)?;
    // The pieces are read into memory: the whole volume is.
    let room = Room {
        scratch: None,
        ..opts.room()
    };
    let mut rounded = Rounded::default();
    let mut read = |i: usize| -> Result<Voxels> {
        let p = &found[i];
        let spec = DataSpec {
            dims: p.dims,
            voxel_type: p.array.ty,
            ..spec.clone()
        };
        let (voxels, r) = read_array(&spec, &p.array, layout, bytes, room)?;
        rounded.add(r);
        Ok(voxels)
    };
    let voxels = match out_type {
        VoxelType::U8 => place_all::<u8>(spec, &found, &mut read)?,
        VoxelType::I8 => place_all::<i8>(spec, &found, &mut read)?,
        VoxelType::U16 => place_all::<u16>(spec, &found, &mut read)?,
        VoxelType::I16 => place_all::<i16>(spec, &found, &mut read)?,
        _ => place_all::<f32>(spec, &found, &mut read)?,
    };
    Ok((voxels, rounded))
}

/// The type the voxels of `array` are held in when read.
fn held_of(array: &Array) -> VoxelType {
    if array.format == "ascii" {
        VoxelType::F32
    } else {
        held_type(array.ty, false)
    }
}

/// Piece `i`, `node`, of the image of whole extent `whole`: its array, checked to be the first
/// piece's, and its place, checked to lie within the whole extent.
fn piece<'a>(
    spec: &DataSpec,
    node: Node<'a, '_>,
    i: usize,
    whole: [i64; 6],
    first: &Array,
    opts: &LoadOptions,
) -> Result<Piece<'a>> {
    let path = spec.file.path();
    let extent = integers::<6>(path, node, "Extent")?;
    let inside = (0..3).all(|m| {
        whole[2 * m] <= extent[2 * m]
            && extent[2 * m] <= extent[2 * m + 1]
            && extent[2 * m + 1] <= whole[2 * m + 1]
    });
    if !inside {
        return Err(Error::format(
            path,
            format!("its piece {i}'s Extent {extent:?} is not within its WholeExtent {whole:?}"),
        ));
    }
    let chosen = opts.part.array.as_deref().or(Some(first.name.as_str()));
    let array = pick_array(path, node, chosen)?;
    if array.cells != first.cells || array.ty != first.ty || array.wide != first.wide {
        return Err(Error::format(
            path,
            format!(
                "its piece {i}'s array {:?} is not of the first piece's type or data",
                crate::error::names::text(&array.name)
            ),
        ));
    }
    // Within the whole extent, the piece's extent is no larger.
    let points: [usize; 3] =
        std::array::from_fn(|m| (extent[2 * m + 1] - extent[2 * m]) as usize + 1);
    let at = std::array::from_fn(|m| (extent[2 * m] - whole[2 * m]) as usize);
    let dims = voxel_dims(points, array.cells);
    if (0..3).any(|m| at[m] + dims[m] > spec.dims[m]) {
        return Err(Error::format(
            path,
            format!("its piece {i}'s cells of Extent {extent:?} lie beyond its WholeExtent"),
        ));
    }
    Ok(Piece { array, at, dims })
}

/// Checks that the whole volume (held as `held`), the largest piece as read (and, held in
/// another type, its copy as f32), and a bit a voxel fit in `max_memory` together.
fn check_budget(spec: &DataSpec, pieces: &[Piece], held: VoxelType, max_memory: u64) -> Result<()> {
    let count = |dims: [usize; 3]| dims.iter().try_fold(1u64, |a, &d| a.checked_mul(d as u64));
    let largest = pieces
        .iter()
        .map(|p| {
            let own = held_of(&p.array);
            let copy = if own == held { 0 } else { 4 };
            count(p.dims).and_then(|n| n.checked_mul(own.size() as u64 + copy))
        })
        .try_fold(0u64, |a, b| b.map(|b| a.max(b)));
    let whole = count(spec.dims);
    let needed = whole
        .and_then(|n| n.checked_mul(held.size() as u64))
        .zip(whole.map(|n| n.div_ceil(8)))
        .and_then(|(a, b)| a.checked_add(b))
        .zip(largest)
        .and_then(|(a, b)| a.checked_add(b));
    match needed {
        Some(n) if n <= max_memory => Ok(()),
        _ => Err(Error::TooLarge {
            path: spec.file.path().to_path_buf(),
            what: format!(
                "a {} {held} volume assembled from {} pieces",
                dims_string(spec.dims),
                pieces.len()
            ),
            needed: needed.unwrap_or(u64::MAX),
            limit: max_memory,
            machine: false,
            disk: false,
        }),
    }
}

/// The whole volume of voxels of type `T`: each piece read (by `read`) and placed, then checked
/// to leave no voxel uncovered.
fn place_all<T: Voxel>(
    spec: &DataSpec,
    pieces: &[Piece],
    read: &mut dyn FnMut(usize) -> Result<Voxels>,
) -> Result<Voxels> {
    let path = spec.file.path();
    let [nx, ny, nz] = spec.dims;
    let mut out: Vec<T> = crate::formats::data::typed_buffer(path, spec.dims, u64::MAX)?;
    let mut covered = vec![0u64; (nx * ny * nz).div_ceil(64)];
    for (i, p) in pieces.iter().enumerate() {
        let voxels = read(i)?;
        let same = voxels.held() == T::TYPE;
        let values: Vec<T>;
        let data: &[T] = if same {
            with_voxels!(&voxels, |d| bytemuck::cast_slice(d))
        } else if T::TYPE == VoxelType::F32 {
            // Held in another type than the whole (pieces of different encodings): as f32.
            values = bytemuck::cast_vec(voxels.to_f32_vec());
            &values
        } else {
            return Err(Error::format(
                path,
                format!(
                    "its piece {i} is held as {}, not {}",
                    voxels.held(),
                    T::TYPE
                ),
            ));
        };
        let [px, py, pz] = p.dims;
        for z in 0..pz {
            for y in 0..py {
                let from = &data[(z * py + y) * px..][..px];
                let start = ((p.at[2] + z) * ny + p.at[1] + y) * nx + p.at[0];
                for (x, &v) in from.iter().enumerate() {
                    let k = start + x;
                    let (word, bit) = (k / 64, 1u64 << (k % 64));
                    if covered[word] & bit != 0 && !agree(out[k], v) {
                        return Err(disagree(spec, i, [k % nx, k / nx % ny, k / (nx * ny)]));
                    }
                    covered[word] |= bit;
                    out[k] = v;
                }
            }
        }
    }
    if let Some(k) = (0..nx * ny * nz).find(|&k| covered[k / 64] & (1 << (k % 64)) == 0) {
        return Err(Error::format(
            path,
            format!(
                "its pieces leave voxel ({}, {}, {}) of its WholeExtent uncovered",
                k % nx,
                k / nx % ny,
                k / (nx * ny)
            ),
        ));
    }
    Ok(Voxels::owned(out))
}

/// Whether two values of a voxel that two pieces hold are the same (both missing, or equal).
fn agree<T: Voxel>(a: T, b: T) -> bool {
    a.to_f32() == b.to_f32() || (a.is_missing() && b.is_missing())
}

/// The error of piece `i` giving voxel `at` another value than an earlier piece gave it.
fn disagree(spec: &DataSpec, i: usize, at: [usize; 3]) -> Error {
    Error::format(
        spec.file.path(),
        format!(
            "its piece {i} gives voxel ({}, {}, {}) another value than an earlier piece",
            at[0], at[1], at[2]
        ),
    )
}
