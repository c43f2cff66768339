//! Legacy VTK (`.vtk`) image data, `DATASET STRUCTURED_POINTS`, as VTK's own writers and
//! `ParaView` save simulation grids: a text header (`DIMENSIONS`, `SPACING` or the older
//! `ASPECT_RATIO`, `ORIGIN`, then `POINT_DATA` or `CELL_DATA` and the first array's `SCALARS` or
//! one-component `COLOR_SCALARS` line and `LOOKUP_TABLE`), then the values, big-endian binary or
//! ASCII, x fastest. Cell data is a volume of one voxel fewer along each axis, its voxels at the
//! cells' centres. Other datasets (polygons, unstructured and curvilinear grids) are no image and
//! are refused naming what they are. `info` lists the file's arrays (`arrays`).

mod arrays;

use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;

use serde::Serialize;

use self::arrays::later_arrays;

use super::data::wide::{Rounded, Wide, read_wide};
use super::data::{DataSpec, Encoding, Skip, read_voxels};
use super::details::{Details, json_of};
use super::reader::{Reader, Sniff};
use super::{Format, LoadOptions, Read0, Source};
use crate::error::{Error, Result};
use crate::formats::data::ascii::read_wide_ascii;
use crate::geometry::WorldTransform;
use crate::volume::{Endian, VoxelType, Voxels};

/// The legacy VTK reader.
pub(crate) struct Vtk;

/// The most bytes read looking for the end of the header.
const HEADER_BYTES: u64 = 64 << 10;

impl Reader for Vtk {
    fn format(&self) -> Format {
        Format::Vtk
    }

    fn title(&self) -> &'static str {
        "VTK"
    }

    fn reads(&self) -> Option<&'static str> {
        Some("legacy VTK image data")
    }

    fn sniff(&self, head: &[u8]) -> Sniff {
        if head.starts_with(b"# vtk DataFile Version") {
            Sniff::Mine
        } else {
            Sniff::No
        }
    }

    fn extensions(&self) -> &'static [&'static str] {
        &[".vtk"]
    }

    fn details_key(&self) -> Option<&'static str> {
        Some("vtk")
    }

    fn read(&self, source: &Source, opts: &LoadOptions) -> Result<Read0> {
        load(source, opts)
    }
}

/// What `info` shows of a legacy VTK file: its arrays, the one read first.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub(crate) struct VtkDetails {
    /// The arrays, in the file's order.
    pub arrays: Vec<VtkArray>,
}

/// One array of a legacy VTK file.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub(crate) struct VtkArray {
    /// Its name as written.
    pub name: String,
    /// What it is: `scalars`, `color_scalars`, `vectors`, `normals`, `tensors`,
    /// `texture_coordinates` or `field` (an array of a `FIELD`).
    pub kind: &'static str,
    /// Its type as written (`float`, `unsigned_char`; `unsigned_char` for colours).
    #[serde(rename = "type")]
    pub ty: String,
    /// `point` or `cell` data.
    pub data: &'static str,
}

impl Details for VtkDetails {
    fn lines(&self) -> Vec<(String, String)> {
        let arrays: Vec<String> = self
            .arrays
            .iter()
            .map(|a| {
                let kind = a.kind.replace('_', " ");
                let name = crate::error::names::text(&a.name);
                let ty = crate::error::names::text(&a.ty);
                format!("{name} ({ty} {kind}, {} data)", a.data)
            })
            .collect();
        vec![("arrays".into(), arrays.join(", "))]
    }

    fn json(&self) -> serde_json::Value {
        json_of(self)
    }
}

/// What the header says.
#[derive(Debug, Default)]
struct Header {
    binary: bool,
    points: [usize; 3],
    spacing: Option<[f64; 3]>,
    origin: [f64; 3],
    cells: bool,
    ty: Option<VoxelType>,
    /// Its type when it holds 64-bit integers (held as f32).
    wide: Option<Wide>,
    color: bool,
    /// The array's name and type as written.
    array: (String, String),
    /// Where the values start.
    start: u64,
}

fn header(path: &Path, text: &[u8]) -> Result<Header> {
    let mut h = Header::default();
    let mut at = 0usize;
    let mut lines = 0;
    loop {
        let end = text[at..]
            .iter()
            .position(|&b| b == b'\n')
            .ok_or_else(|| Error::format(path, "its header ends before its values start"))?;
        let line = String::from_utf8_lossy(&text[at..at + end])
            .trim()
            .to_string();
        at += end + 1;
        lines += 1;
        // The version line, the title and the encoding come first, in that order.
        match lines {
            1 | 2 => {}
            3 => {
                h.binary = match line.to_ascii_uppercase().as_str() {
                    "BINARY" => true,
                    "ASCII" => false,
                    other => {
                        return Err(Error::format(
                            path,
                            format!("its third line is {other:?}: expected BINARY or ASCII"),
                        ));
                    }
                }
            }
            _ if h.take(path, &line)? => {
                h.start = at as u64;
                return Ok(h);
            }
            _ => {}
        }
    }
}

impl Header {
    /// Takes one line of the header after the encoding; true when the values follow it.
    fn take(&mut self, path: &Path, line: &str) -> Result<bool> {
        let bad = |what: String| Error::format(path, what);
        let words: Vec<&str> = line.split_whitespace().collect();
        let Some(&key) = words.first() else {
            return Ok(false);
        };
        let numbers = |n: usize| -> Result<Vec<f64>> {
            let v: Option<Vec<f64>> = words[1..].iter().map(|w| w.parse().ok()).collect();
            v.filter(|v| v.len() == n && v.iter().all(|x| x.is_finite()))
                .ok_or_else(|| bad(format!("{line:?}: expected {n} numbers")))
        };
        match key.to_ascii_uppercase().as_str() {
            "DATASET" => {
                let kind = words.get(1).copied().unwrap_or("");
                if !kind.eq_ignore_ascii_case("STRUCTURED_POINTS") {
                    return Err(Error::unsupported(
                        path,
                        format!(
                            "a VTK {kind} dataset: slabscope reads image data (STRUCTURED_POINTS)"
                        ),
                    ));
                }
            }
            "DIMENSIONS" => {
                let n = numbers(3)?;
                if n.iter().any(|&d| d < 1.0 || d.fract() != 0.0 || d > 1e9) {
                    return Err(bad(format!(
                        "{line:?}: expected three whole numbers from 1"
                    )));
                }
                self.points = [n[0] as usize, n[1] as usize, n[2] as usize];
            }
            "SPACING" | "ASPECT_RATIO" => {
                let s = numbers(3)?;
                self.spacing = Some([s[0], s[1], s[2]]);
            }
            "ORIGIN" => {
                let o = numbers(3)?;
                self.origin = [o[0], o[1], o[2]];
            }
            "POINT_DATA" => self.cells = false,
            "CELL_DATA" => self.cells = true,
            "SCALARS" => self.scalars(path, line, &words)?,
            "COLOR_SCALARS" => {
                if words.get(2) != Some(&"1") {
                    return Err(Error::unsupported(
                        path,
                        format!("{line:?}: colours of more than one component"),
                    ));
                }
                self.ty = Some(VoxelType::U8);
                self.color = true;
                let name = words.get(1).copied().unwrap_or("");
                self.array = (name.to_string(), "unsigned_char".to_string());
                return Ok(true);
            }
            "LOOKUP_TABLE" => return Ok(self.ty.is_some()),
            "VECTORS" | "NORMALS" | "TENSORS" | "TEXTURE_COORDINATES" | "FIELD" => {
                return Err(Error::unsupported(
                    path,
                    format!("its first array is {key}: slabscope reads scalars"),
                ));
            }
            _ => {}
        }
        Ok(false)
    }

    /// A `SCALARS name type [components]` line.
    fn scalars(&mut self, path: &Path, line: &str, words: &[&str]) -> Result<()> {
        let name = words.get(2).copied().unwrap_or("");
        self.array = (
            words.get(1).copied().unwrap_or("").to_string(),
            name.to_string(),
        );
        self.wide = wide_type(name);
        self.ty = Some(
            scalar_type(name)
                .or(self.wide.map(|_| VoxelType::F32))
                .ok_or_else(|| Error::unsupported(path, format!("VTK scalars of type {name:?}")))?,
        );
        if words.get(3).map_or(Ok(1), |c| c.parse::<usize>()) != Ok(1) {
            return Err(Error::unsupported(
                path,
                format!("{line:?}: more than one component a voxel (a vector field)"),
            ));
        }
        Ok(())
    }
}

/// The voxel type of a VTK scalar type's name.
fn scalar_type(name: &str) -> Option<VoxelType> {
    Some(match name.to_ascii_lowercase().as_str() {
        "unsigned_char" | "vtktypeuint8" => VoxelType::U8,
        "char" | "signed_char" | "vtktypeint8" => VoxelType::I8,
        "unsigned_short" | "vtktypeuint16" => VoxelType::U16,
        "short" | "vtktypeint16" => VoxelType::I16,
        "unsigned_int" | "vtktypeuint32" => VoxelType::U32,
        "int" | "vtktypeint32" => VoxelType::I32,
        "float" | "vtktypefloat32" => VoxelType::F32,
        "double" | "vtktypefloat64" => VoxelType::F64,
        _ => return None,
    })
}

/// The 64-bit integer type of a VTK scalar type's name (`long` as VTK writes it on Linux and
/// macOS: 8 bytes).
fn wide_type(name: &str) -> Option<Wide> {
    match name.to_ascii_lowercase().as_str() {
        "long" | "vtkidtype" | "vtktypeint64" => Some(Wide::I64),
        "unsigned_long" | "vtktypeuint64" => Some(Wide::U64),
        _ => None,
    }
}

fn load(source: &Source, opts: &LoadOptions) -> Result<Read0> {
    let path = source.path();
    let mut text = Vec::new();
    source
        .open()?
        .take(HEADER_BYTES)
        .read_to_end(&mut text)
        .map_err(|e| Error::io(path, e))?;
    let h = header(path, &text)?;
    let Some(ty) = h.ty else {
        return Err(Error::format(path, "no SCALARS before its values"));
    };
    if h.points.contains(&0) {
        return Err(Error::format(path, "no DIMENSIONS line"));
    }
    let dims = if h.cells {
        h.points.map(|n| n.saturating_sub(1).max(1))
    } else {
        h.points
    };
    let spec = DataSpec {
        file: source.clone(),
        start: h.start,
        skip_lines: 0,
        skip: Skip::Bytes(0),
        encoding: if h.binary {
            Encoding::Raw
        } else {
            Encoding::Ascii
        },
        dims,
        // ASCII colours are fractions of 255.
        voxel_type: if h.color && !h.binary {
            VoxelType::F32
        } else {
            ty
        },
        endian: Endian::Big,
        scale: (h.color && !h.binary).then_some((255.0, 0.0)),
        volumes: (0, 1),
        // VTK's writer ends binary values with a newline.
        trailing: true,
    };
    let mut notes = Vec::new();
    let (mut voxels, rounded, stored) = if let Some(wide) = h.wide {
        let (voxels, rounded) = read_wide_values(&spec, wide, opts)?;
        (voxels, rounded, wide.name())
    } else {
        let (voxels, rounded) = read_voxels(&spec, opts.room())?;
        (voxels, rounded, ty.name())
    };
    notes.extend(rounded.note(stored));
    let mut held = ty;
    if h.color && !h.binary {
        // ASCII colours are written as fractions of 255: the bytes again.
        voxels = match voxels {
            Voxels::F32(s) => Voxels::narrowed(
                s.as_slice().iter().map(|v| v.round()).collect(),
                VoxelType::U8,
            ),
            other => other,
        };
        held = VoxelType::U8;
    }
    let (spacing, transform) = placement(path, &h, &mut notes)?;
    let mut read = Read0::new(path, dims, spacing, held, voxels, notes)?;
    let mut details = h.details();
    details.arrays.extend(later_arrays(source, &h));
    read.details = Some(std::sync::Arc::new(details));
    Ok(read.with_transform(Some(transform)))
}

/// The spacing of the file `h` heads, and its voxels' place: at its origin (the first cell's
/// centre half a step past it), its orientation unknown.
fn placement(
    path: &Path,
    h: &Header,
    notes: &mut Vec<String>,
) -> Result<([f64; 3], WorldTransform)> {
    let spacing = h.spacing.unwrap_or_else(|| {
        notes.push("no SPACING: using 1 mm".into());
        [1.0; 3]
    });
    if spacing.iter().any(|&s| s <= 0.0) {
        return Err(Error::format(
            path,
            format!("SPACING {spacing:?}: expected three positive numbers"),
        ));
    }
    // The first cell's centre lies half a step past the first point.
    let origin: [f64; 3] =
        std::array::from_fn(|m| h.origin[m] + if h.cells { spacing[m] / 2.0 } else { 0.0 });
    if h.cells {
        notes.push("cell data: a voxel a cell, at its centre".into());
    }
    // VTK's world has no anatomical axes: placed at its origin, orientation unknown.
    let mut transform = WorldTransform::unknown(spacing);
    for (row, o) in transform.matrix.iter_mut().zip(origin) {
        row[3] = o;
    }
    Ok((spacing, transform))
}

/// The 64-bit integers of the values `spec` describes, binary (big-endian) or ascii, as f32
/// voxels, and what rounding them did.
fn read_wide_values(spec: &DataSpec, wide: Wide, opts: &LoadOptions) -> Result<(Voxels, Rounded)> {
    let path = spec.file.path();
    let mut file = spec.file.open()?;
    let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
    file.seek(SeekFrom::Start(spec.start))
        .map_err(|e| Error::io(path, e))?;
    let file = BufReader::new(file);
    if spec.encoding == Encoding::Ascii {
        return read_wide_ascii(spec, wide, file, opts.room());
    }
    let expected = spec
        .dims
        .iter()
        .try_fold(Wide::SIZE as u64, |a, &d| a.checked_mul(d as u64))
        .unwrap_or(u64::MAX);
    let found = len.saturating_sub(spec.start);
    if found < expected {
        return Err(Error::Truncated {
            path: path.to_path_buf(),
            expected,
            found,
        });
    }
    read_wide(spec, wide, file.take(expected), "binary", opts.room())
}

impl Header {
    /// What `info` shows of the file.
    fn details(&self) -> VtkDetails {
        let (name, ty) = self.array.clone();
        VtkDetails {
            arrays: vec![VtkArray {
                name,
                kind: if self.color {
                    "color_scalars"
                } else {
                    "scalars"
                },
                ty,
                data: if self.cells { "cell" } else { "point" },
            }],
        }
    }
}
