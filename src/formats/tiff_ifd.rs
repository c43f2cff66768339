//! A walk over a TIFF's directories before the `tiff` crate reads them: every directory and every
//! tag value must lie within the file, and the chain must not loop. The crate then never sizes a
//! buffer from a count no file could hold (its 0.11 reader allocates an ASCII value of any count
//! up to its decoding limit, and prints a debugging line above it).

use std::io::{Cursor, Read, Seek, SeekFrom};
use std::path::Path;

use crate::error::{Error, Result};

/// Bytes per value of each TIFF field type (0 for types this walk does not know, whose values it
/// leaves to the decoder).
fn type_size(ty: u16) -> u64 {
    match ty {
        1 | 2 | 6 | 7 => 1,
        3 | 8 => 2,
        4 | 9 | 11 | 13 => 4,
        5 | 10 | 12 | 16..=18 => 8,
        _ => 0,
    }
}

/// Reads the little- or big-endian integer of `n` bytes at the reader's position.
fn uint(r: &mut impl Read, n: usize, big: bool) -> std::io::Result<u64> {
    let mut b = [0u8; 8];
    r.read_exact(&mut b[..n])?;
    let bytes = &b[..n];
    Ok(if big {
        bytes.iter().fold(0u64, |v, &x| v << 8 | u64::from(x))
    } else {
        bytes.iter().rev().fold(0u64, |v, &x| v << 8 | u64::from(x))
    })
}

/// Checks the directories of the TIFF whose bytes are `bytes` (named `path` in messages); returns
/// how many pages it has.
pub(crate) fn check(path: &Path, bytes: &[u8]) -> Result<usize> {
    let len = bytes.len() as u64;
    let mut r = Cursor::new(bytes);
    let bad = |m: String| Error::format(path, format!("not a readable TIFF: {m}"));
    let io = |e: std::io::Error| Error::format(path, format!("not a readable TIFF: {e}"));
    let mut magic = [0u8; 4];
    r.read_exact(&mut magic).map_err(io)?;
    let (big, bigtiff) = match &magic {
        b"II*\0" => (false, false),
        b"MM\0*" => (true, false),
        b"II+\0" => (false, true),
        b"MM\0+" => (true, true),
        _ => return Err(bad("no TIFF signature".into())),
    };
    // Offsets, counts and entries are 4, 2 and 12 bytes in TIFF, 8, 8 and 20 in BigTIFF.
    let (word, count_size, entry) = if bigtiff { (8, 8, 20) } else { (4, 2, 12) };
    if bigtiff {
        uint(&mut r, 4, big).map_err(io)?;
    }
    let mut next = uint(&mut r, word, big).map_err(io)?;
    let mut seen = std::collections::HashSet::new();
    let mut pages = 0usize;
    while next != 0 {
        if !seen.insert(next) {
            return Err(bad(format!(
                "page {pages}: its directory loops back to an earlier one"
            )));
        }
        if next >= len {
            return Err(bad(format!(
                "page {pages}: its directory lies at byte {next}, beyond the {len}-byte file"
            )));
        }
        r.seek(SeekFrom::Start(next)).map_err(io)?;
        let entries = uint(&mut r, count_size, big).map_err(io)?;
        let end = entries
            .checked_mul(entry)
            .and_then(|n| n.checked_add(next + count_size as u64 + word as u64));
        if end.is_none_or(|e| e > len) {
            return Err(bad(format!(
                "page {pages}: its directory of {entries} entries runs past the end of the file"
            )));
        }
        for _ in 0..entries {
            let tag = uint(&mut r, 2, big).map_err(io)?;
            let ty = uint(&mut r, 2, big).map_err(io)? as u16;
            let count = uint(&mut r, word, big).map_err(io)?;
            let value = uint(&mut r, word, big).map_err(io)?;
            let bytes = count.checked_mul(type_size(ty));
            let inline = bytes.is_some_and(|b| b <= word as u64);
            let within = bytes
                .and_then(|b| value.checked_add(b))
                .is_some_and(|e| e <= len);
            if !inline && !within {
                return Err(bad(format!(
                    "page {pages}: tag {tag} claims {count} values, more than the file holds"
                )));
            }
        }
        next = uint(&mut r, word, big).map_err(io)?;
        pages += 1;
    }
    if pages == 0 {
        return Err(bad("it has no pages".into()));
    }
    Ok(pages)
}
