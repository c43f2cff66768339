//! Integers wider than an f32 holds exactly: 64-bit ones (VTK's `Int64`/`UInt64` and `long`,
//! h5py's int64/uint64) and 32-bit ones (every format's u32/i32), held as f32, as every value
//! wider than 16 bits is, each one rounded to the nearest f32. An f32 holds every integer up to
//! 2^24 in magnitude exactly, and larger ones only when their low bits are zero; the values that
//! were rounded are counted by one test ([`Rounded::of`], [`Rounded::of_bytes`], [`Exact`]), and
//! said in a note ([`Rounded::note`]), never rounded silently.

use std::io::{ErrorKind, Read};

use super::{DataSpec, fill};
use crate::error::Result;
use crate::formats::scratch::Room;
use crate::volume::{Endian, VoxelType, Voxels};

/// A 64-bit integer type of a file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Wide {
    /// Signed (`Int64`, `long`, `vtktypeint64`, int64).
    I64,
    /// Unsigned (`UInt64`, `unsigned_long`, `vtktypeuint64`, uint64).
    U64,
}

impl Wide {
    /// The bytes of one value.
    pub(crate) const SIZE: usize = 8;

    /// Its name in notes and messages.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Self::I64 => "i64",
            Self::U64 => "u64",
        }
    }
}

/// What rounding 64-bit integers to f32 did: how many values changed, and the largest of them in
/// magnitude.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Rounded {
    /// Values an f32 does not hold exactly.
    pub count: u64,
    /// The largest such value in magnitude.
    pub largest: i128,
}

/// Integers of at most this magnitude are f32s exactly: 2^24.
const EXACT: u64 = 1 << 24;

impl Rounded {
    /// The integers of `values` an f32 does not hold exactly, counted: the test every reader
    /// that widens 32-bit integers to f32 applies (64-bit ones pass through [`WideReader`]).
    pub(crate) fn of(values: impl IntoIterator<Item = i64>) -> Self {
        let mut rounded = Self::default();
        for v in values {
            if v.unsigned_abs() > EXACT {
                rounded.take(i128::from(v));
            }
        }
        rounded
    }

    /// [`Rounded::of`] the voxels of `bytes` stored as `ty` in `endian` order: nothing for types
    /// other than u32 and i32 (smaller integers and floats are f32s exactly, and 64-bit
    /// integers are counted as they are read).
    pub(crate) fn of_bytes(bytes: &[u8], ty: VoxelType, endian: Endian) -> Self {
        let word = |c: &[u8]| {
            let mut w = [0u8; 4];
            w.copy_from_slice(c);
            if endian == Endian::Big {
                w.reverse();
            }
            w
        };
        let words = bytes.chunks_exact(4).map(word);
        match ty {
            VoxelType::U32 => Self::of(words.map(|w| i64::from(u32::from_le_bytes(w)))),
            VoxelType::I32 => Self::of(words.map(|w| i64::from(i32::from_le_bytes(w)))),
            _ => Self::default(),
        }
    }

    /// These counts and `other`'s.
    #[must_use]
    pub(crate) fn plus(mut self, other: Self) -> Self {
        self.add(other);
        self
    }

    /// `v` as the nearest f32, counted when that is not `v`.
    pub(crate) fn take(&mut self, v: i128) -> f32 {
        #[allow(clippy::cast_precision_loss)] // counted below
        let f = v as f32;
        #[allow(clippy::cast_possible_truncation)] // an f32 of a 64-bit value fits an i128
        if f as i128 != v {
            self.count += 1;
            if v.abs() > self.largest.abs() {
                self.largest = v;
            }
        }
        f
    }

    /// Both counts: `other`'s added to these.
    pub(crate) fn add(&mut self, other: Self) {
        self.count += other.count;
        if other.largest.abs() > self.largest.abs() {
            self.largest = other.largest;
        }
    }

    /// The note saying that `count` values of type `ty` (its name: `i64`, `u32`...) were
    /// rounded, when any was.
    pub(crate) fn note(&self, ty: &str) -> Option<String> {
        (self.count > 0).then(|| {
            format!(
                "{} {} value{} beyond what an f32 holds exactly rounded to the nearest f32 \
                 (the largest {})",
                self.count,
                ty,
                if self.count == 1 { "" } else { "s" },
                self.largest
            )
        })
    }
}

/// Element types a reader widens to f32 as they are: the integers an f32 does not hold exactly
/// counted ([`Rounded::of`]) for u32 and i32, nothing for the others.
pub(crate) trait Exact: Sized {
    /// The values of `values` an f32 does not hold exactly.
    fn rounded(_values: &[Self]) -> Rounded {
        Rounded::default()
    }
}

impl Exact for u8 {}
impl Exact for i8 {}
impl Exact for u16 {}
impl Exact for i16 {}
impl Exact for f32 {}
impl Exact for f64 {}

impl Exact for u32 {
    fn rounded(values: &[u32]) -> Rounded {
        Rounded::of(values.iter().map(|&v| i64::from(v)))
    }
}

impl Exact for i32 {
    fn rounded(values: &[i32]) -> Rounded {
        Rounded::of(values.iter().map(|&v| i64::from(v)))
    }
}

/// 64-bit integers of `input` (in `endian` order) read as f32 in this machine's byte order.
pub(crate) struct WideReader<R> {
    input: R,
    wide: Wide,
    endian: Endian,
    raw: Vec<u8>,
    /// One value's bytes not yet given, and how many of them were.
    held: [u8; 4],
    at_held: usize,
    /// The values rounded so far.
    pub rounded: Rounded,
}

impl<R: Read> WideReader<R> {
    pub(crate) fn new(input: R, wide: Wide, endian: Endian) -> Self {
        Self {
            input,
            wide,
            endian,
            raw: Vec::new(),
            held: [0; 4],
            at_held: 4,
            rounded: Rounded::default(),
        }
    }

    /// The value of the 8 bytes `b`.
    fn value(&mut self, b: &[u8]) -> f32 {
        let mut word = [0u8; 8];
        word.copy_from_slice(b);
        if self.endian == Endian::Big {
            word.reverse();
        }
        let v = match self.wide {
            Wide::I64 => i128::from(i64::from_le_bytes(word)),
            Wide::U64 => i128::from(u64::from_le_bytes(word)),
        };
        self.rounded.take(v)
    }
}

impl<R: Read> Read for WideReader<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if self.at_held < 4 {
            let n = (4 - self.at_held).min(buf.len());
            buf[..n].copy_from_slice(&self.held[self.at_held..self.at_held + n]);
            self.at_held += n;
            return Ok(n);
        }
        if buf.is_empty() {
            return Ok(0);
        }
        let want = (buf.len() / 4).clamp(1, 1 << 13);
        let mut raw = std::mem::take(&mut self.raw);
        raw.resize(want * Wide::SIZE, 0);
        let got = fill(&mut self.input, &mut raw);
        let got = match got {
            Ok(got) => got,
            Err(e) => {
                self.raw = raw;
                return Err(e);
            }
        };
        let whole = got / Wide::SIZE;
        let mut given = 0;
        for (i, b) in raw[..whole * Wide::SIZE]
            .chunks_exact(Wide::SIZE)
            .enumerate()
        {
            let f = self.value(b).to_ne_bytes();
            if buf.len() >= 4 * (i + 1) {
                buf[4 * i..4 * i + 4].copy_from_slice(&f);
                given += 4;
            } else {
                self.held = f;
                let n = buf.len() - given;
                buf[given..].copy_from_slice(&f[..n]);
                self.at_held = n;
                given += n;
            }
        }
        self.raw = raw;
        if whole == 0 && got > 0 {
            return Err(std::io::Error::new(
                ErrorKind::UnexpectedEof,
                "the data ends inside a 64-bit value",
            ));
        }
        Ok(given)
    }
}

/// The spec of the f32 values a [`WideReader`] gives for the voxels `spec` describes.
pub(crate) fn as_f32(spec: &DataSpec) -> DataSpec {
    DataSpec {
        voxel_type: VoxelType::F32,
        endian: Endian::NATIVE,
        scale: None,
        ..spec.clone()
    }
}

/// The 64-bit integers of `stream` (their bytes in `spec.endian`), as f32 voxels, and what
/// rounding them did; `what` names the stream in messages.
pub(crate) fn read_wide(
    spec: &DataSpec,
    wide: Wide,
    stream: impl Read,
    what: &'static str,
    room: Room,
) -> Result<(Voxels, Rounded)> {
    let mut reader = WideReader::new(stream, wide, spec.endian);
    let voxels = {
        let mut buffered = std::io::BufReader::new(&mut reader);
        // f32 values: nothing more rounded here.
        super::read_voxels_from(&as_f32(spec), &mut buffered, what, room)?.0
    };
    Ok((voxels, reader.rounded))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_all(bytes: &[u8], wide: Wide, endian: Endian, chunk: usize) -> (Vec<f32>, Rounded) {
        let mut r = WideReader::new(bytes, wide, endian);
        let mut out = Vec::new();
        let mut buf = vec![0u8; chunk];
        loop {
            let n = r.read(&mut buf).unwrap();
            if n == 0 {
                break;
            }
            out.extend_from_slice(&buf[..n]);
        }
        let values = out
            .chunks_exact(4)
            .map(|b| f32::from_ne_bytes(b.try_into().unwrap()))
            .collect();
        (values, r.rounded)
    }

    #[test]
    fn every_read_size_gives_the_same_values_and_counts_the_rounded_ones() {
        let values: [i64; 5] = [-1, 1 << 24, (1 << 24) + 1, i64::MIN, -((1 << 40) + 3)];
        let le: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let be: Vec<u8> = values.iter().flat_map(|v| v.to_be_bytes()).collect();
        let expected = [
            -1.0,
            16_777_216.0,
            16_777_216.0,
            -9.223_372e18,
            -1_099_511_627_776.0,
        ];
        for chunk in [1, 3, 4, 7, 64] {
            for (bytes, endian) in [(&le, Endian::Little), (&be, Endian::Big)] {
                let (got, rounded) = read_all(bytes, Wide::I64, endian, chunk);
                assert_eq!(got, expected, "chunk {chunk}");
                // 2^24 + 1 and -(2^40 + 3) are rounded; i64::MIN = -2^63 is held exactly.
                assert_eq!(
                    rounded,
                    Rounded {
                        count: 2,
                        largest: -((1 << 40) + 3)
                    }
                );
            }
        }
        let (got, rounded) = read_all(&u64::MAX.to_le_bytes(), Wide::U64, Endian::Little, 4);
        assert_eq!(got, [18_446_744_073_709_551_616.0]);
        assert_eq!(rounded.largest, i128::from(u64::MAX));
        assert_eq!(
            rounded.note(Wide::U64.name()).unwrap(),
            "1 u64 value beyond what an f32 holds exactly rounded to the nearest f32 (the \
             largest 18446744073709551615)"
        );
        assert_eq!(Rounded::default().note("i64"), None);
    }

    #[test]
    fn thirty_two_bit_integers_beyond_two_to_the_24_are_counted() {
        let u: [u32; 5] = [0, 1 << 24, (1 << 24) + 1, (1 << 25) + 4, u32::MAX];
        let le: Vec<u8> = u.iter().flat_map(|v| v.to_le_bytes()).collect();
        let be: Vec<u8> = u.iter().flat_map(|v| v.to_be_bytes()).collect();
        // 2^24 and 2^25 + 4 are f32s (a step of 4 between 2^25 and 2^26); 2^24 + 1 and 2^32 - 1
        // are not.
        let expected = Rounded {
            count: 2,
            largest: i128::from(u32::MAX),
        };
        assert_eq!(
            Rounded::of_bytes(&le, VoxelType::U32, Endian::Little),
            expected
        );
        assert_eq!(
            Rounded::of_bytes(&be, VoxelType::U32, Endian::Big),
            expected
        );
        assert_eq!(u32::rounded(&u), expected);
        let i: [i32; 4] = [-(1 << 24), -(1 << 24) - 1, i32::MIN, i32::MAX];
        let le: Vec<u8> = i.iter().flat_map(|v| v.to_le_bytes()).collect();
        // -2^24 and -2^31 are f32s; -2^24 - 1 and 2^31 - 1 are not.
        let expected = Rounded {
            count: 2,
            largest: i128::from(i32::MAX),
        };
        assert_eq!(
            Rounded::of_bytes(&le, VoxelType::I32, Endian::Little),
            expected
        );
        assert_eq!(i32::rounded(&i), expected);
        assert_eq!(
            expected.note("i32").unwrap(),
            "2 i32 values beyond what an f32 holds exactly rounded to the nearest f32 (the \
             largest 2147483647)"
        );
        // Other types are not counted here: 16-bit and float values are f32s (or f64s rounded
        // by design), 64-bit ones counted as they are read.
        assert_eq!(
            Rounded::of_bytes(&le, VoxelType::F32, Endian::Little),
            Rounded::default()
        );
        assert_eq!(f64::rounded(&[1e300]), Rounded::default());
    }

    #[test]
    fn a_value_cut_short_is_an_end_inside_it() {
        let mut r = WideReader::new(&[1u8, 0, 0][..], Wide::I64, Endian::Little);
        let e = r.read(&mut [0u8; 8]).unwrap_err();
        assert_eq!(e.kind(), ErrorKind::UnexpectedEof);
    }
}
