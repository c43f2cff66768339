//! Voxel types as stored in files, and their decoding into f32.

use serde::Serialize;

use super::voxels::{Voxel, Voxels};

/// The voxel type a file stores, kept so that `info` can report it and writers can restore it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum VoxelType {
    /// Unsigned 8-bit integer.
    U8,
    /// Signed 8-bit integer.
    I8,
    /// Unsigned 16-bit integer.
    U16,
    /// Signed 16-bit integer.
    I16,
    /// Unsigned 32-bit integer.
    U32,
    /// Signed 32-bit integer.
    I32,
    /// IEEE 754 single precision.
    F32,
    /// IEEE 754 double precision.
    F64,
}

/// Byte order of multi-byte voxels in a file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Endian {
    /// Least significant byte first (x86, most files).
    #[default]
    Little,
    /// Most significant byte first.
    Big,
}

impl Endian {
    /// This machine's byte order.
    pub const NATIVE: Endian = if cfg!(target_endian = "big") {
        Endian::Big
    } else {
        Endian::Little
    };
}

impl VoxelType {
    /// Every type, in the order of `name`'s table.
    pub const ALL: [VoxelType; 8] = [
        Self::U8,
        Self::I8,
        Self::U16,
        Self::I16,
        Self::U32,
        Self::I32,
        Self::F32,
        Self::F64,
    ];

    /// Bytes per voxel.
    #[must_use]
    pub fn size(self) -> usize {
        match self {
            Self::U8 | Self::I8 => 1,
            Self::U16 | Self::I16 => 2,
            Self::U32 | Self::I32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    /// The short name used on the command line and in JSON: `u8`, `i16`, `f32`, ...
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::U8 => "u8",
            Self::I8 => "i8",
            Self::U16 => "u16",
            Self::I16 => "i16",
            Self::U32 => "u32",
            Self::I32 => "i32",
            Self::F32 => "f32",
            Self::F64 => "f64",
        }
    }

    /// Parses a short name (`u16`) or a common long one (`uint16`, `float`, `double`, `uchar`).
    #[must_use]
    pub fn parse(name: &str) -> Option<Self> {
        Some(match name.to_ascii_lowercase().as_str() {
            "u8" | "uint8" | "uchar" | "ubyte" => Self::U8,
            "i8" | "int8" | "char" | "byte" => Self::I8,
            "u16" | "uint16" | "ushort" => Self::U16,
            "i16" | "int16" | "short" => Self::I16,
            "u32" | "uint32" | "uint" => Self::U32,
            "i32" | "int32" | "int" => Self::I32,
            "f32" | "float32" | "float" | "single" => Self::F32,
            "f64" | "float64" | "double" => Self::F64,
            _ => return None,
        })
    }

    /// Whether the type holds integers, so that a writer rounds to it.
    #[must_use]
    pub fn is_integer(self) -> bool {
        !matches!(self, Self::F32 | Self::F64)
    }

    /// The smallest and largest value the type holds, as f64.
    #[must_use]
    pub fn range(self) -> (f64, f64) {
        match self {
            Self::U8 => (0.0, f64::from(u8::MAX)),
            Self::I8 => (f64::from(i8::MIN), f64::from(i8::MAX)),
            Self::U16 => (0.0, f64::from(u16::MAX)),
            Self::I16 => (f64::from(i16::MIN), f64::from(i16::MAX)),
            Self::U32 => (0.0, f64::from(u32::MAX)),
            Self::I32 => (f64::from(i32::MIN), f64::from(i32::MAX)),
            Self::F32 => (f64::from(f32::MIN), f64::from(f32::MAX)),
            Self::F64 => (f64::MIN, f64::MAX),
        }
    }
}

impl std::fmt::Display for VoxelType {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Decodes `out.len()` voxels from `bytes` (exactly that many voxels' bytes), applying
/// `value * slope + intercept` when a scale is given.
pub(crate) fn decode_to(
    bytes: &[u8],
    ty: VoxelType,
    endian: Endian,
    scale: Option<(f64, f64)>,
    out: &mut [f32],
) {
    debug_assert_eq!(bytes.len(), out.len() * ty.size());
    macro_rules! decode {
        ($t:ty, $n:literal) => {{
            let it = bytes.chunks_exact($n).map(|c| {
                let a: [u8; $n] = c.try_into().expect("chunks_exact yields whole voxels");
                match endian {
                    Endian::Little => <$t>::from_le_bytes(a),
                    Endian::Big => <$t>::from_be_bytes(a),
                }
            });
            match scale {
                None => out.iter_mut().zip(it).for_each(|(o, v)| *o = v as f32),
                Some((m, b)) => out
                    .iter_mut()
                    .zip(it)
                    .for_each(|(o, v)| *o = (v as f64 * m + b) as f32),
            }
        }};
    }
    match ty {
        VoxelType::U8 => decode!(u8, 1),
        VoxelType::I8 => decode!(i8, 1),
        VoxelType::U16 => decode!(u16, 2),
        VoxelType::I16 => decode!(i16, 2),
        VoxelType::U32 => decode!(u32, 4),
        VoxelType::I32 => decode!(i32, 4),
        VoxelType::F32 => decode!(f32, 4),
        VoxelType::F64 => decode!(f64, 8),
    }
}

/// Writes every voxel of `voxels` to `sink` as `ty` in little-endian order (see [`encode_le`]),
/// a chunk at a time.
pub(crate) fn write_le(
    voxels: &Voxels,
    ty: VoxelType,
    sink: &mut impl std::io::Write,
) -> std::io::Result<()> {
    let mut bytes = Vec::new();
    crate::volume::with_voxels!(voxels, |v| {
        for chunk in v.chunks(1 << 16) {
            bytes.clear();
            encode_le(chunk, ty, &mut bytes);
            sink.write_all(&bytes)?;
        }
    });
    Ok(())
}

/// Encodes voxels as `ty` in little-endian order, rounding and clamping to integer types
/// (missing voxels become 0 there).
pub(crate) fn encode_le<T: Voxel>(values: &[T], ty: VoxelType, out: &mut Vec<u8>) {
    let (lo, hi) = ty.range();
    let int = |v: f32| -> f64 {
        if v.is_finite() {
            f64::from(v).round().clamp(lo, hi)
        } else {
            0.0
        }
    };
    out.reserve(values.len() * ty.size());
    for v in values {
        let v = v.to_f32();
        match ty {
            VoxelType::U8 => out.push(int(v) as u8),
            VoxelType::I8 => out.extend((int(v) as i8).to_le_bytes()),
            VoxelType::U16 => out.extend((int(v) as u16).to_le_bytes()),
            VoxelType::I16 => out.extend((int(v) as i16).to_le_bytes()),
            VoxelType::U32 => out.extend((int(v) as u32).to_le_bytes()),
            VoxelType::I32 => out.extend((int(v) as i32).to_le_bytes()),
            VoxelType::F32 => out.extend(v.to_le_bytes()),
            VoxelType::F64 => out.extend(f64::from(v).to_le_bytes()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for ty in VoxelType::ALL {
            assert_eq!(VoxelType::parse(ty.name()), Some(ty));
        }
        assert_eq!(VoxelType::parse("uint16"), Some(VoxelType::U16));
        assert_eq!(VoxelType::parse("complex64"), None);
    }

    #[test]
    fn decodes_both_byte_orders_and_scales() {
        let mut out = [0.0; 3];
        decode_to(
            &[0x01, 0x02],
            VoxelType::U16,
            Endian::Little,
            None,
            &mut out[..1],
        );
        decode_to(
            &[0x01, 0x02],
            VoxelType::U16,
            Endian::Big,
            None,
            &mut out[1..2],
        );
        decode_to(
            &[0xff],
            VoxelType::I8,
            Endian::Big,
            Some((2.0, 10.0)),
            &mut out[2..],
        );
        assert_eq!(out, [513.0, 258.0, 8.0]);
    }

    #[test]
    fn encode_round_trips_every_type() {
        let values = [0.0f32, 1.0, 100.0, 7.0];
        for ty in VoxelType::ALL {
            let mut bytes = Vec::new();
            encode_le(&values, ty, &mut bytes);
            assert_eq!(bytes.len(), values.len() * ty.size());
            let mut back = [0.0; 4];
            decode_to(&bytes, ty, Endian::Little, None, &mut back);
            assert_eq!(back, values, "{ty}");
        }
    }

    #[test]
    fn encode_clamps_and_zeroes_missing() {
        let mut bytes = Vec::new();
        encode_le(&[300.0, -5.0, f32::NAN, 2.5], VoxelType::U8, &mut bytes);
        assert_eq!(bytes, vec![255, 0, 0, 3]);
    }
}
