//! The arrays of a legacy VTK file after the one read, for `info`: each one's line, its values
//! skipped by their size (binary) or their count (ASCII), section by section (`POINT_DATA`,
//! `CELL_DATA`, a `FIELD`'s arrays, `METADATA` blocks).

use std::io::{BufRead, BufReader, Read, Seek, SeekFrom};

use super::{Header, VtkArray, scalar_type};
use crate::formats::Source;

/// A file read line by line for its arrays.
type Lines = BufReader<std::fs::File>;

/// The most arrays listed after the one read.
const MAX_LISTED: usize = 256;

/// The arrays after the one read, as far as the file can be followed: each one's line, its
/// values skipped by their size (binary) or their count (ASCII). The listing stops quietly at
/// the end of the file or at anything it does not know: it only tells, the volume is read.
pub(super) fn later_arrays(source: &Source, h: &Header) -> Vec<VtkArray> {
    let mut arrays = Vec::new();
    let Ok(file) = source.open() else {
        return arrays;
    };
    let mut file = BufReader::new(file);
    let tuples = if h.cells {
        h.points
            .iter()
            .map(|&n| n.saturating_sub(1).max(1))
            .product()
    } else {
        h.points.iter().product::<usize>()
    };
    let mut walk = Walk {
        binary: h.binary,
        data: if h.cells { "cell" } else { "point" },
        tuples: tuples as u64,
    };
    let first = if h.color {
        "unsigned_char"
    } else {
        h.array.1.as_str()
    };
    let skipped = file.seek(SeekFrom::Start(h.start)).is_ok() && walk.skip(&mut file, first, 1);
    while skipped && arrays.len() < MAX_LISTED {
        let Some(line) = next_line(&mut file) else {
            break;
        };
        if !walk.take(&mut file, &line, &mut arrays) {
            break;
        }
    }
    arrays
}

/// Where the listing of arrays stands: the encoding, and the section's data and tuple count.
struct Walk {
    binary: bool,
    data: &'static str,
    tuples: u64,
}

impl Walk {
    /// Takes one line after an array's values; false when the listing stops.
    fn take(&mut self, file: &mut Lines, line: &str, arrays: &mut Vec<VtkArray>) -> bool {
        let words: Vec<&str> = line.split_whitespace().collect();
        let word = |i: usize| words.get(i).copied().unwrap_or("");
        let number = |i: usize| word(i).parse::<u64>().ok();
        let mut array = |kind: &'static str, name: &str, ty: &str| {
            arrays.push(VtkArray {
                name: name.to_string(),
                kind,
                ty: ty.to_string(),
                data: self.data,
            });
        };
        let (ty, components) = match word(0).to_ascii_uppercase().as_str() {
            "" => return true,
            "POINT_DATA" | "CELL_DATA" => {
                self.data = if word(0).eq_ignore_ascii_case("CELL_DATA") {
                    "cell"
                } else {
                    "point"
                };
                return number(1).map(|n| self.tuples = n).is_some();
            }
            "METADATA" => return skip_block(file),
            "SCALARS" => {
                array("scalars", word(1), word(2));
                if !skip_lookup_line(file) {
                    return false;
                }
                (word(2), number(3).unwrap_or(1))
            }
            "COLOR_SCALARS" => {
                array("color_scalars", word(1), "unsigned_char");
                ("unsigned_char", number(2).unwrap_or(0))
            }
            key @ ("VECTORS" | "NORMALS" | "TENSORS") => {
                let kind = match key {
                    "VECTORS" => "vectors",
                    "NORMALS" => "normals",
                    _ => "tensors",
                };
                array(kind, word(1), word(2));
                (word(2), if kind == "tensors" { 9 } else { 3 })
            }
            "TEXTURE_COORDINATES" => {
                array("texture_coordinates", word(1), word(3));
                (word(3), number(2).unwrap_or(0))
            }
            "LOOKUP_TABLE" => {
                // A lookup table of its own (`LOOKUP_TABLE name size`): `size` colours of four
                // components.
                let ty = if self.binary {
                    "unsigned_char"
                } else {
                    "float"
                };
                return number(2).is_none_or(|size| self.skip_values(file, ty, size, 4));
            }
            "FIELD" => return self.field(file, number(2).unwrap_or(0), arrays),
            _ => return false,
        };
        self.skip(file, ty, components)
    }

    /// The `count` arrays of a `FIELD`, each a line `name components tuples type` and values.
    fn field(&self, file: &mut Lines, count: u64, arrays: &mut Vec<VtkArray>) -> bool {
        for _ in 0..count {
            if arrays.len() >= MAX_LISTED {
                return false;
            }
            // The line after binary values is empty.
            let Some(line) = next_line(file)
                .filter(|l| !l.is_empty())
                .or_else(|| next_line(file))
            else {
                return false;
            };
            let words: Vec<&str> = line.split_whitespace().collect();
            let [name, components, tuples, ty] = words[..] else {
                return false;
            };
            let (Ok(components), Ok(tuples)) = (components.parse(), tuples.parse()) else {
                return false;
            };
            arrays.push(VtkArray {
                name: name.to_string(),
                kind: "field",
                ty: ty.to_string(),
                data: self.data,
            });
            if !self.skip_values(file, ty, tuples, components) {
                return false;
            }
        }
        true
    }

    /// Skips the values of an array of the section's tuples, `components` each.
    fn skip(&self, file: &mut Lines, ty: &str, components: u64) -> bool {
        self.skip_values(file, ty, self.tuples, components)
    }

    /// Skips `tuples` × `components` values of the type `ty`; false when that cannot be done.
    fn skip_values(&self, file: &mut Lines, ty: &str, tuples: u64, components: u64) -> bool {
        let Some(count) = tuples.checked_mul(components) else {
            return false;
        };
        if !self.binary {
            return skip_words(file, count);
        }
        let size = match ty.to_ascii_lowercase().as_str() {
            "long" | "unsigned_long" | "vtkidtype" | "vtktypeint64" | "vtktypeuint64" => Some(8),
            other => scalar_type(other).map(|t| t.size() as u64),
        };
        size.and_then(|s| count.checked_mul(s))
            .and_then(|bytes| i64::try_from(bytes).ok())
            .is_some_and(|bytes| file.seek_relative(bytes).is_ok())
    }
}

/// The next line (without its end), at most 4096 bytes; `None` at the end of the file.
fn next_line(file: &mut Lines) -> Option<String> {
    let mut line = Vec::new();
    let read = (&mut *file).take(4096).read_until(b'\n', &mut line).ok()?;
    (read > 0).then(|| String::from_utf8_lossy(&line).trim().to_string())
}

/// Skips the `LOOKUP_TABLE` line after a `SCALARS` line, where there is one.
fn skip_lookup_line(file: &mut Lines) -> bool {
    let Ok(at) = file.stream_position() else {
        return false;
    };
    match next_line(file) {
        Some(line) if line.to_ascii_uppercase().starts_with("LOOKUP_TABLE") => true,
        Some(_) => file.seek(SeekFrom::Start(at)).is_ok(),
        None => false,
    }
}

/// Skips the lines of a `METADATA` block, up to the empty line that ends it.
fn skip_block(file: &mut Lines) -> bool {
    for _ in 0..1 << 16 {
        match next_line(file) {
            Some(line) if line.is_empty() => return true,
            Some(_) => {}
            None => return false,
        }
    }
    false
}

/// Skips `count` words (ASCII values), up to the end of the last.
fn skip_words(file: &mut Lines, count: u64) -> bool {
    let mut left = count;
    let mut in_word = false;
    while left > 0 {
        let Ok(buf) = file.fill_buf() else {
            return false;
        };
        if buf.is_empty() {
            // The end of the file ends the last word.
            return left == 1 && in_word;
        }
        let mut used = 0;
        for &b in buf {
            let space = b.is_ascii_whitespace();
            if in_word && space {
                left -= 1;
                if left == 0 {
                    break;
                }
            }
            in_word = !space;
            used += 1;
        }
        file.consume(used);
    }
    true
}
