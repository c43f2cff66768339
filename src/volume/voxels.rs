//! Voxels in their own type (docs/design.md §5): u8, i8, u16 and i16 as the file stores them,
//! every other type as f32; held in memory or memory-mapped from the file, and reached through
//! `with_voxels!` so that each algorithm is compiled once per type.

use std::sync::Arc;

use bytemuck::Pod;

use super::VoxelType;
use super::mapped::MappedFile;
use super::quantize::Quantizer;

/// A voxel value as stored: a type the algorithms read directly and widen to f32 where they
/// interpolate (exactly: every value of these types is an f32).
pub trait Voxel: Pod + PartialOrd + Send + Sync + std::fmt::Debug + 'static {
    /// The type as files and reports name it.
    const TYPE: VoxelType;

    /// The value as f32, exactly as the f32 path has always held it.
    fn to_f32(self) -> f32;

    /// Whether the value is missing (NaN): never, for integers.
    #[inline]
    fn is_missing(self) -> bool {
        false
    }

    /// The value's place in a lookup table over every value of the type (`value - MIN`), for
    /// types of at most 16 bits; `None` for f32.
    fn table_index(self) -> Option<usize>;

    /// The value as an integer, for the integer types (whose sums are exact in integers, so that
    /// loops over them need no floating-point chain); `None` for f32.
    fn integer(self) -> Option<i32>;

    /// Voxels of this type held in `store`.
    fn wrap(store: Store<Self>) -> Voxels;
}

macro_rules! integer_voxel {
    ($t:ty, $ty:ident) => {
        impl Voxel for $t {
            const TYPE: VoxelType = VoxelType::$ty;

            #[inline]
            fn to_f32(self) -> f32 {
                f32::from(self)
            }

            #[inline]
            fn table_index(self) -> Option<usize> {
                Some((i32::from(self) - i32::from(<$t>::MIN)) as usize)
            }

            #[inline]
            fn integer(self) -> Option<i32> {
                Some(i32::from(self))
            }

            fn wrap(store: Store<Self>) -> Voxels {
                Voxels::$ty(store)
            }
        }
    };
}

integer_voxel!(u8, U8);
integer_voxel!(i8, I8);
integer_voxel!(u16, U16);
integer_voxel!(i16, I16);

impl Voxel for f32 {
    const TYPE: VoxelType = VoxelType::F32;

    #[inline]
    fn to_f32(self) -> f32 {
        self
    }

    #[inline]
    fn is_missing(self) -> bool {
        self.is_nan()
    }

    #[inline]
    fn table_index(self) -> Option<usize> {
        None
    }

    #[inline]
    fn integer(self) -> Option<i32> {
        None
    }

    fn wrap(store: Store<Self>) -> Voxels {
        Voxels::F32(store)
    }
}

/// The type voxels of a file's type are held in: integers of at most 16 bits as they are, every
/// other type (and any scaled data) as f32.
#[must_use]
pub fn held_type(stored: VoxelType, scaled: bool) -> VoxelType {
    match stored {
        VoxelType::U8 | VoxelType::I8 | VoxelType::U16 | VoxelType::I16 if !scaled => stored,
        _ => VoxelType::F32,
    }
}

/// Makes the infinities of `values` missing (NaN), as every reader stores them.
pub(crate) fn infinities_missing(values: &mut [f32]) {
    for v in values.iter_mut().filter(|v| v.is_infinite()) {
        *v = f32::NAN;
    }
}

/// Memory a volume reads its voxels from in place without owning it: a buffer another program
/// lends (a NumPy array's, through the Python package), kept alive as long as any volume made
/// from it. The bytes must not change while a volume reads them (its statistics are taken once).
pub trait LentBytes: Send + Sync + std::fmt::Debug {
    /// The lent bytes.
    fn bytes(&self) -> &[u8];
}

/// Where a volume's voxels live: a vector of their own, a stretch of a mapped file, or memory
/// lent by its owner.
#[derive(Clone, Debug)]
pub enum Store<T> {
    /// Decoded into memory.
    Owned(Arc<Vec<T>>),
    /// Read in place from memory another program owns (counted as memory, not as a map).
    Lent(Arc<dyn LentBytes>),
    /// Read in place from a mapped file: `len` voxels from byte `offset`, aligned for `T`.
    Mapped {
        /// The file's map.
        file: Arc<MappedFile>,
        /// Byte offset of the first voxel.
        offset: usize,
        /// Number of voxels.
        len: usize,
    },
}

impl<T: Voxel> Store<T> {
    /// The voxels in memory order.
    #[inline]
    #[must_use]
    pub fn as_slice(&self) -> &[T] {
        match self {
            Self::Owned(v) => v,
            Self::Lent(bytes) => bytemuck::cast_slice(bytes.bytes()),
            Self::Mapped { file, offset, len } => bytemuck::cast_slice(
                &file.bytes()[*offset..*offset + *len * std::mem::size_of::<T>()],
            ),
        }
    }

    /// A mapped store, when the bytes from `offset` hold `len` voxels aligned for `T` (a map is
    /// page-aligned, so this asks that `offset` be a multiple of the voxel size).
    pub(crate) fn mapped(file: Arc<MappedFile>, offset: usize, len: usize) -> Option<Self> {
        let bytes = len.checked_mul(std::mem::size_of::<T>())?;
        let end = offset.checked_add(bytes)?;
        let slice = file.bytes().get(offset..end)?;
        bytemuck::try_cast_slice::<u8, T>(slice).ok()?;
        Some(Self::Mapped { file, offset, len })
    }

    /// Whether the voxels are read from a mapped file.
    #[must_use]
    pub fn is_mapped(&self) -> bool {
        matches!(self, Self::Mapped { .. })
    }

    /// Whether the voxels are read from a scratch file ([`MappedFile::is_scratch`]).
    #[must_use]
    pub fn is_scratch(&self) -> bool {
        matches!(self, Self::Mapped { file, .. } if file.is_scratch())
    }

    /// Fails, naming the file, when the voxels are read from a map whose file was cut short
    /// under it ([`MappedFile::check`]).
    pub fn check_intact(&self) -> crate::error::Result<()> {
        match self {
            Self::Mapped { file, .. } => file.check(),
            _ => Ok(()),
        }
    }
}

/// A volume's voxels, in the type they are held in.
#[derive(Clone, Debug)]
pub enum Voxels {
    /// Unsigned 8-bit.
    U8(Store<u8>),
    /// Signed 8-bit.
    I8(Store<i8>),
    /// Unsigned 16-bit.
    U16(Store<u16>),
    /// Signed 16-bit.
    I16(Store<i16>),
    /// Everything else, widened (and scaled) to f32.
    F32(Store<f32>),
}

/// Runs `$body` with `$data` bound to the voxels of `$voxels` as a slice of their own type, so
/// that the body is compiled once per held type.
macro_rules! with_voxels {
    ($voxels:expr, |$data:ident| $body:expr) => {
        match $voxels {
            $crate::volume::Voxels::U8(s) => {
                let $data = s.as_slice();
                $body
            }
            $crate::volume::Voxels::I8(s) => {
                let $data = s.as_slice();
                $body
            }
            $crate::volume::Voxels::U16(s) => {
                let $data = s.as_slice();
                $body
            }
            $crate::volume::Voxels::I16(s) => {
                let $data = s.as_slice();
                $body
            }
            $crate::volume::Voxels::F32(s) => {
                let $data = s.as_slice();
                $body
            }
        }
    };
}

pub(crate) use with_voxels;

impl Voxels {
    /// Voxels decoded into memory.
    #[must_use]
    pub fn owned<T: Voxel>(voxels: Vec<T>) -> Self {
        T::wrap(Store::Owned(Arc::new(voxels)))
    }

    /// f32 voxels decoded into memory, infinities made missing (NaN) as every reader makes them.
    #[must_use]
    pub fn from_f32(mut voxels: Vec<f32>) -> Self {
        use rayon::prelude::*;
        voxels.par_chunks_mut(1 << 16).for_each(infinities_missing);
        Self::owned(voxels)
    }

    /// f32 voxels that all hold values of `ty` (whole numbers in its range, as a reader that
    /// learns the type from the values has checked), held as `ty` when it is held as stored
    /// (see [`held_type`]), else as f32.
    #[must_use]
    pub fn narrowed(values: Vec<f32>, ty: VoxelType) -> Self {
        use rayon::prelude::*;
        fn to<T: Voxel>(values: &[f32], cast: fn(f32) -> T) -> Voxels {
            Voxels::owned(values.par_iter().map(|&v| cast(v)).collect())
        }
        match held_type(ty, false) {
            VoxelType::U8 => to(&values, |v| v as u8),
            VoxelType::I8 => to(&values, |v| v as i8),
            VoxelType::U16 => to(&values, |v| v as u16),
            VoxelType::I16 => to(&values, |v| v as i16),
            _ => Self::from_f32(values),
        }
    }

    /// Voxels of type `T` read in place from `bytes`, in this machine's byte order; `None` when
    /// the bytes are not a whole number of voxels aligned for `T`, or (for f32) hold an
    /// infinity, which a volume holds as missing (NaN) and lent memory cannot be changed to.
    #[must_use]
    pub fn lent<T: Voxel>(bytes: Arc<dyn LentBytes>) -> Option<Self> {
        use rayon::prelude::*;
        let voxels: &[T] = bytemuck::try_cast_slice(bytes.bytes()).ok()?;
        if T::TYPE == VoxelType::F32
            && voxels
                .par_iter()
                .any(|v| !v.is_missing() && !v.to_f32().is_finite())
        {
            return None;
        }
        Some(T::wrap(Store::Lent(bytes)))
    }

    /// Voxels read in place from `file`: `len` voxels of type `ty` (held as they are, see
    /// [`held_type`]) from byte `offset`, in this machine's byte order; `None` when the type is
    /// not held as stored or the bytes are not aligned for it.
    pub(crate) fn mapped(
        file: Arc<MappedFile>,
        ty: VoxelType,
        offset: usize,
        len: usize,
    ) -> Option<Self> {
        Some(match ty {
            VoxelType::U8 => Self::U8(Store::mapped(file, offset, len)?),
            VoxelType::I8 => Self::I8(Store::mapped(file, offset, len)?),
            VoxelType::U16 => Self::U16(Store::mapped(file, offset, len)?),
            VoxelType::I16 => Self::I16(Store::mapped(file, offset, len)?),
            VoxelType::F32 => Self::F32(Store::mapped(file, offset, len)?),
            _ => return None,
        })
    }

    /// The type the voxels are held in.
    #[must_use]
    pub fn held(&self) -> VoxelType {
        match self {
            Self::U8(_) => VoxelType::U8,
            Self::I8(_) => VoxelType::I8,
            Self::U16(_) => VoxelType::U16,
            Self::I16(_) => VoxelType::I16,
            Self::F32(_) => VoxelType::F32,
        }
    }

    /// Number of voxels.
    #[must_use]
    pub fn len(&self) -> usize {
        with_voxels!(self, |v| v.len())
    }

    /// Whether there are no voxels (never, for a volume).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether the voxels are read from a mapped file.
    #[must_use]
    pub fn is_mapped(&self) -> bool {
        match self {
            Self::U8(s) => s.is_mapped(),
            Self::I8(s) => s.is_mapped(),
            Self::U16(s) => s.is_mapped(),
            Self::I16(s) => s.is_mapped(),
            Self::F32(s) => s.is_mapped(),
        }
    }

    /// Whether the voxels are read from a scratch file decoded beyond the memory budget.
    #[must_use]
    pub fn is_scratch(&self) -> bool {
        match self {
            Self::U8(s) => s.is_scratch(),
            Self::I8(s) => s.is_scratch(),
            Self::U16(s) => s.is_scratch(),
            Self::I16(s) => s.is_scratch(),
            Self::F32(s) => s.is_scratch(),
        }
    }

    /// Fails, naming the file, when the voxels are read from a map whose file was cut short
    /// under it ([`MappedFile::check`]): what was computed from them is wrong.
    pub fn check_intact(&self) -> crate::error::Result<()> {
        match self {
            Self::U8(s) => s.check_intact(),
            Self::I8(s) => s.check_intact(),
            Self::U16(s) => s.check_intact(),
            Self::I16(s) => s.check_intact(),
            Self::F32(s) => s.check_intact(),
        }
    }

    /// Bytes the voxels take as held (in memory or in the map).
    #[must_use]
    pub fn bytes(&self) -> u64 {
        (self.len() * self.held().size()) as u64
    }

    /// The voxel at linear index `i`, as f32.
    #[inline]
    #[must_use]
    pub fn get(&self, i: usize) -> f32 {
        with_voxels!(self, |v| v[i].to_f32())
    }

    /// Every voxel as f32, in memory order (a copy: for writers and tests, not for algorithms).
    #[must_use]
    pub fn to_f32_vec(&self) -> Vec<f32> {
        with_voxels!(self, |v| v.iter().map(|x| x.to_f32()).collect())
    }
}

/// The bins of every value of a ≤ 16-bit integer type under a quantizer: `table[value - MIN]`
/// is exactly [`Quantizer::bin`] of the value, so quantizing by table changes no result.
#[derive(Clone, Debug)]
pub struct BinTable {
    bins: Vec<u8>,
}

impl BinTable {
    /// Whether values of `voxel_type` are binned by a table (integers of at most 16 bits).
    #[must_use]
    pub fn exists(voxel_type: VoxelType) -> bool {
        Self::size(voxel_type).is_some()
    }

    fn size(voxel_type: VoxelType) -> Option<u32> {
        match voxel_type {
            VoxelType::U8 | VoxelType::I8 => Some(1 << 8),
            VoxelType::U16 | VoxelType::I16 => Some(1 << 16),
            _ => None,
        }
    }

    /// The table of `T` under `q`, or `None` for f32 (no table: quantize by the formula).
    #[must_use]
    pub fn new<T: Voxel>(q: &Quantizer) -> Option<Self> {
        let size = Self::size(T::TYPE)?;
        let min = T::TYPE.range().0;
        let bins = (0..size)
            .map(|i| {
                let v = (min + f64::from(i)) as f32;
                q.bin(v).unwrap_or(0)
            })
            .collect();
        Some(Self { bins })
    }

    /// The bin of `v` (a value of the table's type).
    #[inline]
    #[must_use]
    pub fn bin<T: Voxel>(&self, v: T) -> u8 {
        v.table_index().map_or(0, |i| self.bins[i])
    }
}

/// Quantizes voxels of any held type: by table for integers, by the formula for f32; the same
/// bins either way.
#[derive(Clone, Debug)]
pub struct VoxelQuantizer {
    q: Quantizer,
    table: Option<BinTable>,
}

impl VoxelQuantizer {
    /// The quantizer `q` for voxels of type `T`.
    #[must_use]
    pub fn new<T: Voxel>(q: Quantizer) -> Self {
        Self {
            table: BinTable::new::<T>(&q),
            q,
        }
    }

    /// The bin of `v`, `None` when it is missing.
    #[inline]
    #[must_use]
    pub fn bin<T: Voxel>(&self, v: T) -> Option<u8> {
        match &self.table {
            Some(t) => Some(t.bin(v)),
            None => self.q.bin(v.to_f32()),
        }
    }

    /// The quantizer behind it.
    #[must_use]
    pub fn quantizer(&self) -> &Quantizer {
        &self.q
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn every<T: Voxel>(values: &[T], lo: f32, hi: f32) {
        for bins in [2, 7, 32, 255] {
            let q = Quantizer::new(lo, hi, bins).unwrap();
            let vq = VoxelQuantizer::new::<T>(q);
            assert!(vq.table.is_some(), "{:?} has a table", T::TYPE);
            for &v in values {
                assert_eq!(vq.bin(v), q.bin(v.to_f32()), "{v:?} with {bins} bins");
            }
        }
    }

    #[test]
    fn tables_give_the_formula_for_every_value() {
        every(&(0..=255u8).collect::<Vec<_>>(), 3.0, 200.0);
        every(&(-128..=127i8).collect::<Vec<_>>(), -100.0, 100.0);
        every(&(0..=u16::MAX).collect::<Vec<_>>(), 0.0, 4095.0);
        every(&(i16::MIN..=i16::MAX).collect::<Vec<_>>(), -1024.0, 3071.0);
        every(&(i16::MIN..=i16::MAX).collect::<Vec<_>>(), -3.5, 2.25);
        // A range inside the type's: values beyond it clamp as the formula clamps them.
        let q = Quantizer::new(10.0, 20.0, 4).unwrap();
        let vq = VoxelQuantizer::new::<u8>(q);
        assert_eq!((vq.bin(0u8), vq.bin(255u8)), (Some(0), Some(3)));
    }

    #[test]
    fn f32_quantizes_by_the_formula() {
        let q = Quantizer::new(0.0, 1.0, 4).unwrap();
        let vq = VoxelQuantizer::new::<f32>(q);
        assert!(vq.table.is_none());
        assert_eq!(vq.bin(0.5f32), Some(2));
        assert_eq!(vq.bin(f32::NAN), None);
    }

    #[test]
    fn held_types_keep_small_integers_only() {
        assert_eq!(held_type(VoxelType::I16, false), VoxelType::I16);
        assert_eq!(held_type(VoxelType::I16, true), VoxelType::F32);
        assert_eq!(held_type(VoxelType::U32, false), VoxelType::F32);
        assert_eq!(held_type(VoxelType::F64, false), VoxelType::F32);
    }

    #[test]
    fn voxels_dispatch_on_their_type() {
        let v = Voxels::owned(vec![1i16, -2, 3]);
        assert_eq!(v.held(), VoxelType::I16);
        assert_eq!((v.len(), v.bytes(), v.get(1)), (3, 6, -2.0));
        assert_eq!(v.to_f32_vec(), vec![1.0, -2.0, 3.0]);
        assert!(!v.is_mapped());
        let sum: f32 = with_voxels!(&v, |d| d.iter().map(|x| x.to_f32()).sum());
        assert_eq!(sum, 2.0);
    }

    #[test]
    fn narrowing_keeps_the_values() {
        let v = Voxels::narrowed(vec![-3.0, 0.0, 1000.0], VoxelType::I16);
        assert_eq!(v.held(), VoxelType::I16);
        assert_eq!(v.to_f32_vec(), vec![-3.0, 0.0, 1000.0]);
        let w = Voxels::narrowed(vec![1.0, f32::INFINITY], VoxelType::I32);
        assert_eq!(w.held(), VoxelType::F32);
        assert!(w.get(1).is_nan(), "infinities are missing");
    }

    #[test]
    fn mapped_stores_need_alignment_and_room() {
        let mut file = tempfile::tempfile().unwrap();
        std::io::Write::write_all(&mut file, &[0, 1, 0, 2, 0, 3, 0]).unwrap();
        let file = crate::volume::mapped::map(&file, std::path::Path::new("t")).unwrap();
        let v = Voxels::mapped(file.clone(), VoxelType::U16, 2, 2).unwrap();
        assert!(v.is_mapped());
        assert_eq!(
            v.to_f32_vec(),
            vec![f32::from(u16::from_le_bytes([0, 2])), 768.0]
        );
        assert!(
            Voxels::mapped(file.clone(), VoxelType::U16, 1, 2).is_none(),
            "odd offset"
        );
        assert!(
            Voxels::mapped(file.clone(), VoxelType::U16, 2, 3).is_none(),
            "past the end"
        );
        assert!(
            Voxels::mapped(file, VoxelType::F64, 0, 0).is_none(),
            "not held as stored"
        );
    }

    /// Memory lent as a byte vector: what the Python package does with a NumPy array's buffer.
    #[derive(Debug)]
    struct Buffer(Vec<u8>);

    impl LentBytes for Buffer {
        fn bytes(&self) -> &[u8] {
            &self.0
        }
    }

    #[test]
    fn lent_memory_is_read_in_place_and_counted_as_memory() {
        let values: Vec<i16> = vec![-3, 0, 7, 1200, -32768, 32767, 5, 5];
        let bytes: Vec<u8> = bytemuck::cast_slice(&values).to_vec();
        let lent = Voxels::lent::<i16>(Arc::new(Buffer(bytes))).unwrap();
        assert_eq!(lent.held(), VoxelType::I16);
        assert!(!lent.is_mapped(), "lent memory is memory, not a map");
        let owned = Voxels::owned(values);
        assert_eq!(lent.to_f32_vec(), owned.to_f32_vec());
        let a =
            crate::volume::Volume::from_voxels([2, 2, 2], [1.0; 3], VoxelType::I16, lent).unwrap();
        let b =
            crate::volume::Volume::from_voxels([2, 2, 2], [1.0; 3], VoxelType::I16, owned).unwrap();
        assert_eq!(a.stats(), b.stats());
        assert_eq!(a.histogram(32).unwrap(), b.histogram(32).unwrap());
        assert_eq!(a.memory_bytes(), 16);
    }

    #[test]
    fn lent_memory_that_is_not_whole_voxels_or_holds_an_infinity_is_refused() {
        let odd = Arc::new(Buffer(vec![0; 3]));
        assert!(
            Voxels::lent::<u16>(odd).is_none(),
            "3 bytes are not u16 voxels"
        );
        let with_inf: Vec<u8> = bytemuck::cast_slice(&[1.0f32, f32::INFINITY]).to_vec();
        assert!(Voxels::lent::<f32>(Arc::new(Buffer(with_inf))).is_none());
        let with_nan: Vec<u8> = bytemuck::cast_slice(&[1.0f32, f32::NAN]).to_vec();
        let v = Voxels::lent::<f32>(Arc::new(Buffer(with_nan))).unwrap();
        assert!(
            v.get(1).is_nan(),
            "NaN is missing, as every reader holds it"
        );
    }
}
