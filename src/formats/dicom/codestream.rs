//! What a compressed frame's own header states (its size, and for JPEG and JPEG 2000 its
//! precision and components), read
//! before a decoder sizes its buffers by it: a fragment claiming more than the image it belongs
//! to is an error, not an allocation.

use std::path::Path;

use super::format::PixelFormat;
use super::read;
use super::read::Syntax;
use crate::error::{Error, Result};

/// What a frame's codestream states.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Frame {
    width: u32,
    height: u32,
    /// Bits a sample (0: not read, as for JPEG XL, whose decoder checks it against its own
    /// limits).
    precision: u8,
    /// Components (0: not read).
    components: u16,
    /// JPEG 2000 tiles (1 for JPEG and JPEG XL).
    tiles: u64,
}

/// JPEG 2000's limit on tiles: tile indices are 16-bit, 65535 excluded.
const MAX_TILES: u64 = 65_535;

/// Checks the frame each JPEG, JPEG 2000 or JPEG XL fragment starts states against the image `format`
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
        let frame = jpeg_frame(fragment)
            .or_else(|| j2k_frame(fragment))
            .or_else(|| jxl_frame(fragment));
        let Some(f) = frame else {
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
            let detail = if f.precision > 0 {
                format!(
                    ", {} components of {} bits in {} tiles,",
                    f.components, f.precision, f.tiles
                )
            } else {
                String::new()
            };
            return Err(Error::format(
                path,
                format!(
                    "a compressed frame of {}x{} pixels{detail} in an image of {}x{} with {} \
                     samples a pixel",
                    f.width, f.height, format.cols, format.rows, format.samples
                ),
            ));
        }
        // Tiles a codestream states and holds no tile-part of would decode as zeros, silently.
        if let Some(code) = j2k_code(fragment)
            && let Some(held) = j2k_tiles_held(code, f.tiles, fragments.len() == 1)
            && held < f.tiles
        {
            return Err(Error::format(
                path,
                format!(
                    "a JPEG 2000 frame states {} tiles and holds data for {held}: the others \
                     would decode as zeros",
                    f.tiles
                ),
            ));
        }
    }
    Ok(())
}

/// A JPEG 2000 codestream from its SOC marker: `data` bare, as DICOM stores it, or inside a
/// JP2 file's `jp2c` box.
fn j2k_code(data: &[u8]) -> Option<&[u8]> {
    let code = if data.starts_with(&[0xFF, 0x4F, 0xFF, 0x51]) {
        data
    } else {
        jp2_codestream(data)?
    };
    code.starts_with(&[0xFF, 0x4F, 0xFF, 0x51]).then_some(code)
}

/// How many of the `tiles` a JPEG 2000 codestream states have a tile-part in it, walking its
/// main header's marker segments and then its tile-parts (SOT: `Isot`, the tile, and `Psot`,
/// the length to the next). Known only when the walk ends in `code`, at the EOC marker, a
/// last tile-part running to the end, or `code`'s own end when it is the `whole` codestream;
/// `None` when the codestream goes on past `code` (a frame in several fragments) or cannot be
/// walked.
fn j2k_tiles_held(code: &[u8], tiles: u64, whole: bool) -> Option<u64> {
    let be16 = |at: usize| Some(u16::from_be_bytes(code.get(at..at + 2)?.try_into().ok()?));
    let ended = |at: usize| match code.get(at..at + 2) {
        Some([0xFF, 0xD9]) => Some(true),
        Some([0xFF, 0x90]) => Some(false),
        None if whole && at == code.len() => Some(true),
        _ => None,
    };
    let mut held = vec![false; usize::try_from(tiles).ok()?];
    let mut at = 2;
    while code.get(at..at + 2) != Some(&[0xFF, 0x90]) {
        if ended(at) == Some(true) {
            return Some(0);
        }
        if code.get(at) != Some(&0xFF) {
            return None;
        }
        at = at.checked_add(2 + usize::from(be16(at + 2)?))?;
    }
    loop {
        if let Some(h) = held.get_mut(usize::from(be16(at + 4)?)) {
            *h = true;
        }
        let psot = u32::from_be_bytes(code.get(at + 6..at + 10)?.try_into().ok()?);
        if psot == 0 {
            break;
        }
        at = at.checked_add(usize::try_from(psot).ok()?)?;
        if ended(at)? {
            break;
        }
    }
    Some(held.iter().filter(|&&h| h).count() as u64)
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
    let code = j2k_code(data)?;
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
    boxed(data, *b"jp2c")
}

/// The contents of the first top-level box of type `kind` of an ISO base media file (JP2 and
/// JPEG XL containers alike).
fn boxed(data: &[u8], kind: [u8; 4]) -> Option<&[u8]> {
    let mut at = 0usize;
    while at + 8 <= data.len() {
        let len = u32::from_be_bytes(data[at..at + 4].try_into().ok()?) as usize;
        let this = &data[at + 4..at + 8];
        let (header, len) = match len {
            0 => (8, data.len() - at),
            1 => {
                let long = u64::from_be_bytes(data.get(at + 8..at + 16)?.try_into().ok()?);
                (16, usize::try_from(long).ok()?)
            }
            n => (8, n),
        };
        if this == kind.as_slice() {
            return data.get(at + header..);
        }
        if len < header {
            return None;
        }
        at = at.checked_add(len)?;
    }
    None
}

/// The image size a JPEG XL codestream's `SizeHeader` states (the codestream bare, or inside a
/// container's `jxlc` box).
fn jxl_frame(data: &[u8]) -> Option<Frame> {
    const CONTAINER: [u8; 12] = [0, 0, 0, 12, b'J', b'X', b'L', b' ', 0x0D, 0x0A, 0x87, 0x0A];
    let code = if data.starts_with(&CONTAINER) {
        boxed(data, *b"jxlc")?
    } else {
        data
    };
    if !code.starts_with(&[0xFF, 0x0A]) {
        return None;
    }
    let mut bits = Bits {
        data: &code[2..],
        at: 0,
    };
    // One of the four widths a U32 field's two-bit selector names, plus one.
    let size = |bits: &mut Bits| -> Option<u64> {
        let width = [9, 13, 18, 30][bits.read(2)? as usize];
        Some(bits.read(width)? + 1)
    };
    let small = bits.read(1)? == 1;
    let height = if small {
        (bits.read(5)? + 1) * 8
    } else {
        size(&mut bits)?
    };
    let ratio = bits.read(3)?;
    let width = match ratio {
        0 if small => (bits.read(5)? + 1) * 8,
        0 => size(&mut bits)?,
        r => {
            let (num, den) =
                [(1, 1), (12, 10), (4, 3), (3, 2), (16, 9), (5, 4), (2, 1)][r as usize - 1];
            height * num / den
        }
    };
    Some(Frame {
        width: u32::try_from(width).unwrap_or(u32::MAX),
        height: u32::try_from(height).unwrap_or(u32::MAX),
        precision: 0,
        components: 0,
        tiles: 1,
    })
}

/// A reader of bits, least significant first in each byte, as JPEG XL packs them.
struct Bits<'a> {
    data: &'a [u8],
    at: usize,
}

impl Bits<'_> {
    fn read(&mut self, n: usize) -> Option<u64> {
        let mut v = 0u64;
        for k in 0..n {
            let byte = *self.data.get(self.at / 8)?;
            v |= u64::from((byte >> (self.at % 8)) & 1) << k;
            self.at += 1;
        }
        Some(v)
    }
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

    /// A tile-part of tile `tile`: SOT (`Lsot` 10, `Isot`, `Psot`, `TPsot` 0, `TNsot` 1), SOD and `data`
    /// bytes, `last` with Psot 0 (running to the end).
    fn tile_part(tile: u16, data: usize, last: bool) -> Vec<u8> {
        let psot = if last { 0 } else { (14 + data) as u32 };
        let mut b = vec![0xFF, 0x90, 0, 10];
        b.extend_from_slice(&tile.to_be_bytes());
        b.extend_from_slice(&psot.to_be_bytes());
        b.extend_from_slice(&[0, 1, 0xFF, 0x93]);
        b.extend(std::iter::repeat_n(0x5A, data));
        b
    }

    #[test]
    fn j2k_tiles_without_a_tile_part_are_counted() {
        // 4 tiles stated (64x48 in 32x32), with a COD-like segment before the first SOT.
        let mut head = siz(64, 48, 32, 16);
        head.extend_from_slice(&[0xFF, 0x52, 0, 4, 1, 2]);
        let with = |parts: &[Vec<u8>], eoc: bool| {
            let mut b = head.clone();
            for p in parts {
                b.extend_from_slice(p);
            }
            if eoc {
                b.extend_from_slice(&[0xFF, 0xD9]);
            }
            b
        };
        let all: Vec<_> = (0..4).map(|t| tile_part(t, 7, false)).collect();
        assert_eq!(j2k_tiles_held(&with(&all, true), 4, false), Some(4));
        assert_eq!(j2k_tiles_held(&with(&all, false), 4, true), Some(4));
        // The header alone, or one tile of the four: the rest would be zeros.
        assert_eq!(j2k_tiles_held(&with(&[], true), 4, false), Some(0));
        assert_eq!(j2k_tiles_held(&with(&[], false), 4, true), Some(0));
        let one = [tile_part(2, 7, false), tile_part(2, 3, false)];
        assert_eq!(j2k_tiles_held(&with(&one, true), 4, false), Some(1));
        // A last tile-part running to the end.
        let last = [tile_part(0, 5, false), tile_part(1, 9, true)];
        assert_eq!(j2k_tiles_held(&with(&last, false), 4, false), Some(2));
        // Going on in a later fragment, or not walkable: not known.
        assert_eq!(j2k_tiles_held(&with(&all[..2], false), 4, false), None);
        let mut cut = with(&all, true);
        cut.truncate(cut.len() - 20);
        assert_eq!(j2k_tiles_held(&cut, 4, false), None);
        assert_eq!(
            j2k_code(&with(&all, true)).map(<[u8]>::len),
            Some(with(&all, true).len())
        );
    }

    #[test]
    fn jxl_size_header_is_read() {
        let frame = |w, h| Frame {
            width: w,
            height: h,
            precision: 0,
            components: 0,
            tiles: 1,
        };
        // Small: height (3 + 1) * 8 = 32; ratio 0; width (7 + 1) * 8 = 64. Bits, low first:
        // 1, then 3, 0 and 7 in 5, 3 and 5 bits.
        let small = [0xFF, 0x0A, 0b0000_0111, 0b0000_1110];
        assert_eq!(jxl_frame(&small), Some(frame(64, 32)));
        // Not small: height by the 13-bit width (selector 1), 4999 + 1; ratio 7: twice as wide.
        let mut v: u64 = 0;
        let mut at = 0;
        for (value, width) in [(0, 1), (1, 2), (4999, 13), (7, 3)] {
            v |= value << at;
            at += width;
        }
        let mut large = vec![0xFF, 0x0A];
        large.extend_from_slice(&v.to_le_bytes()[..3]);
        assert_eq!(jxl_frame(&large), Some(frame(10_000, 5_000)));
        assert_eq!(jxl_frame(&large[..3]), None, "cut short");
    }
}
