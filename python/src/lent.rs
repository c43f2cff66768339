//! A NumPy array's memory lent to a volume, read in place.

use std::sync::Arc;

use numpy::{Element, PyArray3, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use slabscope::volume::{LentBytes, Voxel, VoxelType, Voxels};

/// A NumPy array's memory lent to a volume: the array is kept alive as long as the volume.
struct ArrayBytes {
    _array: Py<PyAny>,
    data: *const u8,
    len: usize,
}

// SAFETY: the bytes are read only, and the array they belong to is kept alive (its reference
// is released through PyO3's pool when dropped without the GIL).
unsafe impl Send for ArrayBytes {}
// SAFETY: as above: shared reads of memory nobody frees while the volume lives.
unsafe impl Sync for ArrayBytes {}

impl std::fmt::Debug for ArrayBytes {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ArrayBytes({} bytes)", self.len)
    }
}

impl LentBytes for ArrayBytes {
    fn bytes(&self) -> &[u8] {
        // SAFETY: `data` points at `len` bytes of the array's buffer, which `_array` keeps
        // alive; the volume only reads them.
        unsafe { std::slice::from_raw_parts(self.data, self.len) }
    }
}

/// The voxels of `array` read in place, when it is a Fortran-ordered, aligned array of `T`
/// in native byte order (and, for f32, without infinities).
fn lend<T: Voxel + Element>(array: &Bound<'_, PyAny>) -> Option<Voxels> {
    let typed = array.cast::<PyArray3<T>>().ok()?;
    if !typed.is_fortran_contiguous() || !typed.is_aligned() {
        return None;
    }
    let bytes = ArrayBytes {
        _array: array.clone().unbind(),
        data: typed.data().cast::<u8>().cast_const(),
        len: typed.len() * std::mem::size_of::<T>(),
    };
    Voxels::lent::<T>(Arc::new(bytes))
}

/// The voxels of `array` in place, where its type is held as stored.
pub fn lend_any(array: &Bound<'_, PyAny>, ty: VoxelType) -> Option<Voxels> {
    match ty {
        VoxelType::U8 => lend::<u8>(array),
        VoxelType::I8 => lend::<i8>(array),
        VoxelType::U16 => lend::<u16>(array),
        VoxelType::I16 => lend::<i16>(array),
        VoxelType::F32 => lend::<f32>(array),
        _ => None,
    }
}
