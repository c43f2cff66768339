//! The parameters written in a syntax of their own, parsed: an axis, a background rule, a
//! window, raw dimensions and spacing, a voxel type, a byte order, a byte count, a resolution,
//! a shard. Each returns `None` for text it does not take; what it takes is said by the
//! parameter's entry.

use crate::formats::{parse_bytes, parse_dims};
use crate::geometry::AxisChoice;
use crate::volume::background::BackgroundRule;
use crate::volume::{Endian, Resolution, VoxelType};

/// Two values written `A` then a separator then `B` (spaces around each allowed).
#[must_use]
pub fn pair<T: std::str::FromStr>(s: &str, separators: &[char]) -> Option<(T, T)> {
    let (a, b) = s.split_once(separators)?;
    Some((a.trim().parse().ok()?, b.trim().parse().ok()?))
}

/// `best`, `x`, `y`, `z`, `axial`, `coronal`, `sagittal` or a direction `DX,DY,DZ`.
#[must_use]
pub fn axis(s: &str) -> Option<AxisChoice> {
    s.parse().ok()
}

/// `auto`, `none` or a finite value.
#[must_use]
pub fn background(s: &str) -> Option<BackgroundRule> {
    match s.trim() {
        "auto" => Some(BackgroundRule::Auto),
        "none" => Some(BackgroundRule::None),
        t => t
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .map(|v| BackgroundRule::Below(v as f32)),
    }
}

/// `LO,HI` with `LO` below `HI`, both finite.
#[must_use]
pub fn window(s: &str) -> Option<(f32, f32)> {
    pair::<f32>(s, &[',']).filter(|&(lo, hi)| lo.is_finite() && hi.is_finite() && lo < hi)
}

/// `NXxNYxNZ` (or `NX,NY,NZ`, as Python's tuples come).
#[must_use]
pub fn dims(s: &str) -> Option<[usize; 3]> {
    parse_dims(&s.replace(',', "x"))
}

/// Three positive spacings `SX,SY,SZ`.
#[must_use]
pub fn spacing(s: &str) -> Option<[f64; 3]> {
    crate::geometry::parse_triple(s).filter(|v| v.iter().all(|x| x.is_finite() && *x > 0.0))
}

/// A voxel type: `u8` ... `f64`, or NumPy's names (`uint8` ... `float64`).
#[must_use]
pub fn voxel_type(s: &str) -> Option<VoxelType> {
    VoxelType::parse(s.trim())
}

/// `little` or `big`.
#[must_use]
pub fn endian(s: &str) -> Option<Endian> {
    match s.trim() {
        "little" => Some(Endian::Little),
        "big" => Some(Endian::Big),
        _ => None,
    }
}

/// A byte count: `8G`, `512M`, `1048576`.
#[must_use]
pub fn bytes(s: &str) -> Option<u64> {
    parse_bytes(s)
}

/// `full`, `auto` or a pyramid level.
#[must_use]
pub fn resolution(s: &str) -> Option<Resolution> {
    s.trim().parse().ok()
}

/// A picture's size `WxH` (or `W,H`, as Python's tuples come), at least 1x1 and at most
/// [`MAX_PIXELS`](crate::render::MAX_PIXELS) pixels.
#[must_use]
pub fn size(s: &str) -> Option<(u32, u32)> {
    pair::<u32>(s, &['x', 'X', ',']).filter(|&(w, h)| {
        w > 0 && h > 0 && u64::from(w) * u64::from(h) <= crate::render::MAX_PIXELS
    })
}

/// A shard `K/N` (or `K,N`, as Python's tuples come): the K-th of N, K from 1 to N.
#[must_use]
pub fn shard(s: &str) -> Option<(u64, u64)> {
    pair::<u64>(s, &['/', ',']).filter(|&(k, n)| (1..=n).contains(&k))
}

/// Any text (a series' number or UID, a label image's name).
#[must_use]
pub fn any(s: &str) -> Option<String> {
    Some(s.to_string())
}
