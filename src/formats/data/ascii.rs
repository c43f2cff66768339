//! NRRD's ascii encoding: whitespace- or comma-separated numbers, read a token at a time so that
//! no garbage is held in memory, each checked against the voxel type.

use std::io::{BufRead, Read};

use super::wide::{Rounded, Wide};
use super::{DataSpec, Skip, buffered};
use crate::error::{Error, Result};
use crate::formats::scratch::Room;
use crate::volume::{VoxelType, Voxels};

/// The longest token of ascii data: longer ones are not numbers slabscope reads.
const MAX_TOKEN: usize = 64;

/// Characters of a bad token an error quotes.
const QUOTED: usize = 40;

/// `token` quoted for a one-line message: at most [`QUOTED`] characters, escaped.
pub(super) fn quote(token: &[u8]) -> String {
    let text = crate::error::names::bytes(&token[..token.len().min(QUOTED)]);
    let more = if token.len() > QUOTED { "…" } else { "" };
    format!("\"{text}\"{more}")
}

/// The next whitespace- or comma-separated token of `reader` in `token`: `false` at the end. A
/// token longer than [`MAX_TOKEN`] stops the reading, so that no garbage is held in memory.
pub(super) fn next_token(reader: &mut impl BufRead, token: &mut Vec<u8>) -> std::io::Result<bool> {
    token.clear();
    loop {
        let buf = buffered(reader)?;
        if buf.is_empty() {
            return Ok(!token.is_empty());
        }
        let separator = |b: &u8| b.is_ascii_whitespace() || *b == b',';
        let mut used = 0;
        for b in buf {
            used += 1;
            if separator(b) {
                if !token.is_empty() {
                    reader.consume(used);
                    return Ok(true);
                }
            } else {
                token.push(*b);
                if token.len() > MAX_TOKEN {
                    reader.consume(used);
                    return Ok(true);
                }
            }
        }
        reader.consume(used);
    }
}

pub(super) fn read_ascii(
    spec: &DataSpec,
    mut reader: impl BufRead,
    out: &mut [f32],
) -> Result<Rounded> {
    let count = out.len();
    let mut n = 0;
    let path = spec.file.path();
    let io = |e: std::io::Error| Error::format(path, format!("ascii data: {e}"));
    let skip = match spec.skip {
        Skip::Bytes(n) => n,
        Skip::FromEnd => return Err(Error::unsupported(path, "byte skip -1 with ascii data")),
    };
    std::io::copy(&mut (&mut reader).take(skip), &mut std::io::sink()).map_err(io)?;
    let ty = spec.voxel_type;
    let integer = !matches!(ty, VoxelType::F32 | VoxelType::F64);
    let (lo, hi) = ty.range();
    let mut token = Vec::with_capacity(MAX_TOKEN + 1);
    let mut rounded = Rounded::default();
    // The volumes before the one read.
    let before = spec.volumes.0 * count;
    for read in 0..before {
        if !next_token(&mut reader, &mut token).map_err(io)? {
            return Err(Error::format(
                path,
                format!(
                    "truncated ascii data: {read} values before volume {} of {before}",
                    spec.volumes.0
                ),
            ));
        }
    }
    while next_token(&mut reader, &mut token).map_err(io)? {
        if n == count {
            if spec.allow_trailing() {
                break;
            }
            return Err(Error::format(
                path,
                format!("ascii data holds more than the {count} values the header describes"),
            ));
        }
        let bad = |why: &str| {
            Error::format(
                path,
                format!("ascii data, value {n}: {} {why}", quote(&token)),
            )
        };
        let v: f64 = std::str::from_utf8(&token)
            .ok()
            .filter(|_| token.len() <= MAX_TOKEN)
            .and_then(|t| t.parse().ok())
            .ok_or_else(|| bad("is not a number"))?;
        if integer && !(v.fract() == 0.0 && (lo..=hi).contains(&v)) {
            return Err(bad(&format!("is not a {ty} value ({lo} to {hi})")));
        }
        out[n] = if let Some((m, b)) = spec.scale {
            (v * m + b) as f32
        } else {
            if integer {
                // A whole number within a 32-bit type's range, so exact as an i64.
                #[allow(clippy::cast_possible_truncation)]
                rounded.add(Rounded::of([v as i64]));
            }
            v as f32
        };
        n += 1;
    }
    if n < count {
        return Err(Error::format(
            path,
            format!("truncated ascii data: expected {count} values, found {n}"),
        ));
    }
    Ok(rounded)
}

/// The ascii 64-bit integers of `reader` as f32 voxels (each a whole number of the type's
/// range), and what rounding them did.
pub(crate) fn read_wide_ascii(
    spec: &DataSpec,
    wide: Wide,
    mut reader: impl BufRead,
    room: Room,
) -> Result<(Voxels, Rounded)> {
    let path = spec.file.path();
    let mut out = room.f32_voxels(path, spec.dims)?;
    let values = out.all();
    let io = |e: std::io::Error| Error::format(path, format!("ascii data: {e}"));
    let mut token = Vec::new();
    let mut rounded = Rounded::default();
    let mut n = 0;
    while next_token(&mut reader, &mut token).map_err(io)? {
        if n == values.len() {
            if spec.allow_trailing() {
                break;
            }
            return Err(Error::format(
                path,
                format!(
                    "ascii data holds more than the {} values the header describes",
                    values.len()
                ),
            ));
        }
        let text = std::str::from_utf8(&token).unwrap_or("");
        let v = match wide {
            Wide::I64 => text.parse::<i64>().ok().map(i128::from),
            Wide::U64 => text.parse::<u64>().ok().map(i128::from),
        };
        let v = v.ok_or_else(|| {
            Error::format(
                path,
                format!(
                    "ascii data, value {n}: {} is not an integer of type {}",
                    quote(&token),
                    wide.name()
                ),
            )
        })?;
        values[n] = rounded.take(v);
        n += 1;
    }
    if n < values.len() {
        return Err(Error::format(
            path,
            format!(
                "truncated ascii data: expected {} values, found {n}",
                values.len()
            ),
        ));
    }
    Ok((out.finish()?, rounded))
}
