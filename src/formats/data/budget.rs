//! Voxels weighed against the memory budget before they are allocated.

use std::path::Path;

use crate::error::{Error, Result};
use crate::formats::limits::physical_memory;
use crate::volume::{Voxel, VoxelType, dims_string};

/// Checks `dims` against the memory limit for an f32 volume and returns the voxel count.
pub(crate) fn check_budget(path: &Path, dims: [usize; 3], max_memory: u64) -> Result<usize> {
    check_budget_of(path, dims, VoxelType::F32, max_memory)
}

/// Checks `dims` against the memory limit for a volume held as `held` and returns the voxel
/// count.
pub(crate) fn check_budget_of(
    path: &Path,
    dims: [usize; 3],
    held: VoxelType,
    max_memory: u64,
) -> Result<usize> {
    let count = voxel_count(path, dims)?;
    let bytes = count.and_then(|n| (n as u64).checked_mul(held.size() as u64));
    // A limit above this machine's memory is this machine's memory.
    let (limit, machine) = match physical_memory() {
        Some(m) if m < max_memory => (m, true),
        _ => (max_memory, false),
    };
    match (count, bytes) {
        (Some(n), Some(b)) if b <= limit => Ok(n),
        _ => Err(Error::TooLarge {
            path: path.to_path_buf(),
            what: format!(
                "a {} {held} volume{}",
                dims_string(dims),
                if machine {
                    " (more than this machine has)"
                } else {
                    ""
                }
            ),
            needed: bytes.unwrap_or(u64::MAX),
            limit,
            machine,
            disk: false,
        }),
    }
}

/// The voxel count of `dims` (`None` past `usize`); dimensions with a zero are an error.
pub(super) fn voxel_count(path: &Path, dims: [usize; 3]) -> Result<Option<usize>> {
    if dims.contains(&0) {
        return Err(Error::format(
            path,
            format!("dimensions {} contain a zero", dims_string(dims)),
        ));
    }
    Ok(dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d)))
}

/// A zeroed f32 voxel buffer of `dims`, after checking the budget; an allocation the machine
/// cannot make is an error, not an abort.
pub(crate) fn voxel_buffer(path: &Path, dims: [usize; 3], max_memory: u64) -> Result<Vec<f32>> {
    typed_buffer(path, dims, max_memory)
}

/// A zeroed buffer of `dims` voxels of type `T`, after checking the budget.
pub(crate) fn typed_buffer<T: Voxel>(
    path: &Path,
    dims: [usize; 3],
    max_memory: u64,
) -> Result<Vec<T>> {
    let n = check_budget_of(path, dims, T::TYPE, max_memory)?;
    // Asked of the system first, so that a refusal is an error; then made zeroed, whose pages
    // the system provides only as they are written.
    let mut probe: Vec<T> = Vec::new();
    probe.try_reserve_exact(n).map_err(|_| Error::TooLarge {
        path: path.to_path_buf(),
        what: format!(
            "a {} {} volume (the system refused it)",
            dims_string(dims),
            T::TYPE
        ),
        needed: (n * T::TYPE.size()) as u64,
        limit: max_memory,
        machine: true,
        disk: false,
    })?;
    drop(probe);
    Ok(bytemuck::zeroed_vec(n))
}
