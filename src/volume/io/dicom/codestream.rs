//! What a compressed frame's own header states (its size, precision and components), read
//! before a decoder sizes its buffers by it: a fragment claiming more than the image it belongs
//! to is an error, not an allocation.

use std::path::Path;

use super::header::PixelFormat;
use super::read;
use super::read::Syntax;
use crate::error::{Error, Result};

/// What a frame's codestream states.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Frame {
    width: u32,
    height: u32,
    /// Bits a sample.
    precision: u8,
    components: u16,
    /// JPEG 2000 tiles (1 for JPEG).
    tiles: u64,
}

/// JPEG 2000's limit on tiles: tile indices are 16-bit, 65535 excluded.
const MAX_TILES: u64 = 65_535;

/// Checks the frame each JPEG or JPEG 2000 fragment starts states against the image `format`
/// describes: not larger, at most 16 bits and the image's samples, and for JPEG 2000 a tile
/// count within the standard's. 12-bit extended JPEG, which the decoder does not read, is named
/// as unsupported.
pub(super) fn check(
    path: &Path,
    syntax: &Syntax,
    format: &PixelFormat,
    fragments: &[Vec<u8>],
) -> Result<()> {
    if !syntax.uid.starts_with("1.2.840.10008.1.2.4.") {
        return Ok(());
    }
    for fragment in fragments {
        let Some(f) = jpeg_frame(fragment).or_else(|| j2k_frame(fragment)) else {
            continue;
        };
        if syntax.uid == "1.2.840.10008.1.2.4.51" && f.precision > 8 {
            return Err(Error::unsupported(
                path,
                format!(
                    "transfer syntax {}: {}-bit extended JPEG, which the pure-Rust JPEG \
                     decoder does not read",
                    read::syntax_name(&syntax.uid),
                    f.precision
                ),
            ));
        }
        if f.height > u32::from(format.rows)
            || f.width > u32::from(format.cols)
            || f.precision > 16
            || f.components > format.samples.max(3)
            || f.tiles > MAX_TILES
        {
            return Err(Error::format(
                path,
                format!(
                    "a compressed frame of {}x{} pixels, {} components of {} bits in {} tiles, \
                     in an image of {}x{} with {} samples a pixel",
                    f.width,
                    f.height,
                    f.components,
                    f.precision,
                    f.tiles,
                    format.cols,
                    format.rows,
                    format.samples
                ),
            ));
        }
    }
    Ok(())
}

/// The frame a JPEG stream's start-of-frame marker states.
fn jpeg_frame(data: &[u8]) -> Option<Frame> {
    let mut i = 2;
    if !data.starts_with(&[0xFF, 0xD8]) {
        return None;
    }
    while i + 4 <= data.len() {
        if data[i] != 0xFF {
            return None;
        }
        let marker = data[i + 1];
        let len = usize::from(u16::from_be_bytes([data[i + 2], data[i + 3]]));
        if (0xC0..=0xCF).contains(&marker) && !matches!(marker, 0xC4 | 0xC8 | 0xCC) {
            let f = data.get(i + 4..i + 10)?;
            return Some(Frame {
                precision: f[0],
                height: u32::from(u16::from_be_bytes([f[1], f[2]])),
                width: u32::from(u16::from_be_bytes([f[3], f[4]])),
                components: u16::from(f[5]),
                tiles: 1,
            });
        }
        i += 2 + len;
    }
    None
}

/// The frame a JPEG 2000 codestream's SIZ marker segment states (the codestream bare, as DICOM
/// stores it, or inside a JP2 file's `jp2c` box).
fn j2k_frame(data: &[u8]) -> Option<Frame> {
    let code = if data.starts_with(&[0xFF, 0x4F, 0xFF, 0x51]) {
        data
    } else {
        jp2_codestream(data)?
    };
    if !code.starts_with(&[0xFF, 0x4F, 0xFF, 0x51]) {
        return None;
    }
    let be32 = |at: usize| -> Option<u32> {
        Some(u32::from_be_bytes(code.get(at..at + 4)?.try_into().ok()?))
    };
    // After SOC and the SIZ marker: Lsiz, Rsiz, then Xsiz, Ysiz, XOsiz, YOsiz, XTsiz, YTsiz,
    // XTOsiz, YTOsiz (32-bit), Csiz (16-bit), and per component Ssiz, XRsiz, YRsiz.
    let [x, y, xo, yo, xt, yt, xto, yto] = std::array::from_fn(|k| be32(8 + 4 * k));
    let (x, y, xo, yo) = (x?, y?, xo?, yo?);
    let (xt, yt, xto, yto) = (xt?, yt?, xto?, yto?);
    let components = u16::from_be_bytes(code.get(40..42)?.try_into().ok()?);
    let precision = (0..usize::from(components))
        .map(|c| code.get(42 + 3 * c).map(|s| (s & 0x7F) + 1))
        .try_fold(0u8, |p, s| Some(p.max(s?)))?;
    let tiles_along = |size: u32, tile_origin: u32, tile: u32| {
        u64::from(size.saturating_sub(tile_origin)).div_ceil(u64::from(tile.max(1)))
    };
    Some(Frame {
        width: x.saturating_sub(xo),
        height: y.saturating_sub(yo),
        precision,
        components,
        tiles: tiles_along(x, xto, xt) * tiles_along(y, yto, yt),
    })
}

/// The contents of a JP2 file's contiguous codestream box (`jp2c`), walking its top-level
/// boxes.
fn jp2_codestream(data: &[u8]) -> Option<&[u8]> {
    const SIGNATURE: [u8; 12] = [0, 0, 0, 12, b'j', b'P', b' ', b' ', 0x0D, 0x0A, 0x87, 0x0A];
    if !data.starts_with(&SIGNATURE) {
        return None;
    }
    let mut at = 0usize;
    while at + 8 <= data.len() {
        let len = u32::from_be_bytes(data[at..at + 4].try_into().ok()?) as usize;
        let kind = &data[at + 4..at + 8];
        let (header, len) = match len {
            0 => (8, data.len() - at),
            1 => {
                let long = u64::from_be_bytes(data.get(at + 8..at + 16)?.try_into().ok()?);
                (16, usize::try_from(long).ok()?)
            }
            n => (8, n),
        };
        if kind == b"jp2c" {
            return data.get(at + header..);
        }
        if len < header {
            return None;
        }
        at = at.checked_add(len)?;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A JPEG 2000 codestream's start: SOC and a SIZ segment for a `w`×`h` image of one
    /// component of `bits` bits in tiles of `tile`×`tile`.
    fn siz(w: u32, h: u32, tile: u32, bits: u8) -> Vec<u8> {
        let mut b = vec![0xFF, 0x4F, 0xFF, 0x51, 0, 41, 0, 0];
        for v in [w, h, 0, 0, tile, tile, 0, 0] {
            b.extend_from_slice(&v.to_be_bytes());
        }
        b.extend_from_slice(&[0, 1, bits - 1, 1, 1]);
        b
    }

    #[test]
    fn j2k_siz_is_read_bare_and_in_a_jp2_box() {
        let code = siz(64, 48, 32, 16);
        let frame = Frame {
            width: 64,
            height: 48,
            precision: 16,
            components: 1,
            tiles: 4,
        };
        assert_eq!(j2k_frame(&code), Some(frame));
        let mut jp2 = vec![0, 0, 0, 12, b'j', b'P', b' ', b' ', 0x0D, 0x0A, 0x87, 0x0A];
        jp2.extend_from_slice(&[0, 0, 0, 20, b'f', b't', b'y', b'p']);
        jp2.extend_from_slice(&[0; 12]);
        jp2.extend_from_slice(&((8 + code.len()) as u32).to_be_bytes());
        jp2.extend_from_slice(b"jp2c");
        jp2.extend_from_slice(&code);
        assert_eq!(j2k_frame(&jp2), Some(frame));
        // Tiles of one pixel: 2^32 of them claimed.
        assert_eq!(
            j2k_frame(&siz(65_536, 65_536, 1, 8)).unwrap().tiles,
            1 << 32
        );
        // Cut short, or not a codestream.
        assert_eq!(j2k_frame(&code[..30]), None);
        assert_eq!(j2k_frame(b"\xff\xd8\xff\xe0"), None);
    }
}
