//! VTK XML image data (`.vti`), as `ParaView`, `PyVista` and VTK's `vtkXMLImageDataWriter` save
//! simulation grids: an XML header (`<VTKFile type="ImageData">`, `<ImageData WholeExtent
//! Origin Spacing Direction>`, one `<Piece Extent>` (or several, assembled: `pieces.rs`), its `<PointData>` and `<CellData>`
//! `<DataArray>`s), the values inline as ascii or base64 (`format="binary"`), or appended after
//! the header in an `<AppendedData>` section, raw or base64, found by their `offset`. Binary values
//! start with a header of their size (`UInt32` or `UInt64` words), or, compressed (zlib or LZ4),
//! of the blocks' sizes. x runs fastest. 64-bit integers are held as f32, a note counting the
//! values rounded (`data::wide`).
//!
//! The array read is the one a data section's `Scalars` names (point data first), else the first
//! one-component array; an array of several components (a vector field) named so is refused, as
//! the legacy reader refuses one. Cell data is a volume of one voxel fewer along each axis, its
//! voxels at the cells' centres. The file's units are taken as mm; `Direction` (VTK 9) turns the
//! axes, placing the volume without naming anatomy (VTK's world has none). The XML is parsed up to
//! `<AppendedData>`; appended raw values are read from the file by their offset, in place where
//! they can be. `info` lists the file's arrays (`vti`).

mod arrays;
mod payload;
mod pieces;
mod read;

use std::path::Path;

use roxmltree::{Document, Node, NodeId, ParsingOptions};

use self::payload::{Compressor, Words};
use super::data::wide::Wide;
use super::data::{DataSpec, Encoding, Skip};
use super::reader::{Reader, Sniff};
use super::{Format, LoadOptions, Read0, Source};
use crate::error::{Error, Result};
use crate::geometry::WorldTransform;
use crate::volume::{Endian, VoxelType};

/// The VTK XML image data reader.
pub(crate) struct Vti;

/// The most XML nodes a header may hold.
const MAX_NODES: u32 = 1 << 16;

impl Reader for Vti {
    fn format(&self) -> Format {
        Format::Vti
    }

    fn title(&self) -> &'static str {
        "VTK XML image data"
    }

    /// Its point data arrays.
    fn arrays(&self) -> bool {
        true
    }

    fn reads(&self) -> Option<&'static str> {
        Some("VTK XML image data (.vti)")
    }

    fn sniff(&self, head: &[u8]) -> Sniff {
        if starts_vtk_file(head) {
            Sniff::Mine
        } else {
            Sniff::No
        }
    }

    fn extensions(&self) -> &'static [&'static str] {
        &[".vti"]
    }

    fn details_key(&self) -> Option<&'static str> {
        Some("vti")
    }

    fn read(&self, source: &Source, opts: &LoadOptions) -> Result<Read0> {
        load(source, opts)
    }
}

/// Whether `head` starts like a VTK XML file: `<VTKFile` after an XML declaration, comments and
/// whitespace.
fn starts_vtk_file(head: &[u8]) -> bool {
    let mut rest = head.strip_prefix(b"\xef\xbb\xbf").unwrap_or(head);
    loop {
        rest = rest.trim_ascii_start();
        let close: &[u8] = if rest.starts_with(b"<?") {
            b"?>"
        } else if rest.starts_with(b"<!--") {
            b"-->"
        } else {
            return rest.starts_with(b"<VTKFile");
        };
        match rest.windows(close.len()).position(|w| w == close) {
            Some(end) => rest = &rest[end + close.len()..],
            None => return false,
        }
    }
}

/// Where the appended data is: its encoding and where its bytes start (after the `_`).
#[derive(Clone, Copy, Debug)]
struct Appended {
    base64: bool,
    start: usize,
}

/// What the file's header says of the file as a whole.
#[derive(Clone, Copy, Debug)]
struct Layout {
    words: Words,
    compressor: Option<Compressor>,
    appended: Option<Appended>,
}

/// The array read: its section, name, type, format and offset.
struct Array<'a> {
    id: NodeId,
    cells: bool,
    name: String,
    /// The type its voxels are held in (f32 for 64-bit integers).
    ty: VoxelType,
    /// Its type when it holds 64-bit integers.
    wide: Option<Wide>,
    format: &'a str,
    offset: Option<u64>,
    text: &'a str,
}

fn load(source: &Source, opts: &LoadOptions) -> Result<Read0> {
    let path = source.path();
    let bad = |what: String| Error::format(path, what);
    let map = source.map()?;
    let bytes = map.bytes();
    // The XML ends where the appended data starts: that part is no XML.
    let tag = find(bytes, b"<AppendedData");
    let xml_end = tag.unwrap_or(bytes.len());
    let text = std::str::from_utf8(&bytes[..xml_end])
        .map_err(|e| bad(format!("its XML header is not UTF-8 text: {e}")))?;
    let owned;
    let text = if tag.is_some() {
        owned = format!("{text}</VTKFile>");
        owned.as_str()
    } else {
        text
    };
    let options = ParsingOptions {
        nodes_limit: MAX_NODES,
        ..ParsingOptions::default()
    };
    let doc = Document::parse_with_options(text, options).map_err(|e| {
        bad(format!(
            "its XML header: {}",
            crate::error::names::controls(&e.to_string())
        ))
    })?;
    let root = doc.root_element();
    let appended = tag
        .map(|at| appended_section(path, bytes, at))
        .transpose()?;
    let layout = layout(path, root, appended)?;
    let image = child(path, root, "ImageData")?;
    // VTK gives no units: spacing and origin are taken as mm, as the legacy reader takes them.
    let mut notes = Vec::new();
    let pieces: Vec<Node> = image
        .children()
        .filter(|n| n.has_tag_name("Piece"))
        .collect();
    let (piece, extent) = match pieces[..] {
        [] => return Err(bad("holds no <Piece>".into())),
        [piece] => (piece, integers::<6>(path, piece, "Extent")?),
        [first, ..] => (first, integers::<6>(path, image, "WholeExtent")?),
    };
    let points: [usize; 3] = std::array::from_fn(|m| extent_points(extent, m));
    if points.contains(&0) {
        return Err(bad(format!("its Extent {extent:?} is empty or too large")));
    }
    let array = pick_array(path, piece, opts.part.array.as_deref())?;
    let spec = DataSpec {
        file: source.clone(),
        start: 0,
        skip_lines: 0,
        skip: Skip::Bytes(0),
        encoding: Encoding::Raw,
        dims: voxel_dims(points, array.cells),
        voxel_type: array.ty,
        endian: layout.words.endian,
        scale: None,
        volumes: (0, 1),
        trailing: true,
    };
    let (voxels, rounded) = match pieces.len() {
        1 => read::read_array(&spec, &array, layout, bytes, opts.room())?,
        n => {
            let read = pieces::assemble(&spec, &pieces, extent, &array, (layout, bytes), opts)?;
            notes.push(format!("{n} pieces assembled into its WholeExtent"));
            read
        }
    };
    notes.extend(rounded.note(array.wide.map_or(array.ty.name(), Wide::name)));
    if array.cells {
        notes.push("cell data: a voxel a cell, at its centre".into());
    }
    let (spacing, transform) = placement(path, image, extent, array.cells, &mut notes)?;
    let mut read = Read0::new(path, spec.dims, spacing, array.ty, voxels, notes)?;
    read.details = Some(std::sync::Arc::new(arrays::arrays(piece, array.id)));
    Ok(read.with_transform(Some(transform)))
}

/// The first place of `needle` in `bytes`.
fn find(bytes: &[u8], needle: &[u8]) -> Option<usize> {
    bytes.windows(needle.len()).position(|w| w == needle)
}

/// The `<AppendedData encoding>` tag at `at`, and where its data starts, after its `_`.
fn appended_section(path: &Path, bytes: &[u8], at: usize) -> Result<Appended> {
    let bad = |what: &str| Error::format(path, format!("its AppendedData {what}"));
    let end = bytes[at..]
        .iter()
        .take(4096)
        .position(|&b| b == b'>')
        .ok_or_else(|| bad("tag does not end"))?;
    let tag = std::str::from_utf8(&bytes[at..=at + end]).map_err(|_| bad("tag is no text"))?;
    let tag = format!("{}/>", tag.trim_end_matches('>').trim_end_matches('/'));
    let doc = Document::parse(&tag).map_err(|e| {
        bad(&format!(
            "tag: {}",
            crate::error::names::controls(&e.to_string())
        ))
    })?;
    let base64 = match doc.root_element().attribute("encoding").unwrap_or("raw") {
        "raw" => false,
        "base64" => true,
        other => return Err(bad(&format!("encoding {other:?}: expected raw or base64"))),
    };
    let after = at + end + 1;
    let skip = bytes[after..]
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .filter(|&i| bytes[after + i] == b'_')
        .ok_or_else(|| bad("does not start with an underscore"))?;
    Ok(Appended {
        base64,
        start: after + skip + 1,
    })
}

/// The `<VTKFile>` element's byte order, header type and compressor.
fn layout(path: &Path, root: Node, appended: Option<Appended>) -> Result<Layout> {
    let bad = |what: String| Error::unsupported(path, what);
    if !root.has_tag_name("VTKFile") {
        return Err(Error::format(path, "its XML is not a VTKFile"));
    }
    match root.attribute("type") {
        Some("ImageData") => {}
        other => {
            return Err(bad(format!(
                "a VTK XML {} file: slabscope reads image data (ImageData)",
                other.unwrap_or("untyped")
            )));
        }
    }
    let endian = match root.attribute("byte_order").unwrap_or("LittleEndian") {
        "LittleEndian" => Endian::Little,
        "BigEndian" => Endian::Big,
        other => return Err(bad(format!("byte_order {other:?}"))),
    };
    let size = match root.attribute("header_type").unwrap_or("UInt32") {
        "UInt32" => 4,
        "UInt64" => 8,
        other => {
            return Err(bad(format!(
                "header_type {other:?}: expected UInt32 or UInt64"
            )));
        }
    };
    let compressor = match root.attribute("compressor").unwrap_or("") {
        "" => None,
        "vtkZLibDataCompressor" => Some(Compressor::Zlib),
        "vtkLZ4DataCompressor" => Some(Compressor::Lz4),
        other => {
            return Err(bad(format!(
                "compressor {other:?}: slabscope reads zlib- and LZ4-compressed and uncompressed \
                 data"
            )));
        }
    };
    Ok(Layout {
        words: Words { size, endian },
        compressor,
        appended,
    })
}

/// The child element of `node` named `name`.
fn child<'a, 'i>(path: &Path, node: Node<'a, 'i>, name: &str) -> Result<Node<'a, 'i>> {
    node.children()
        .find(|n| n.has_tag_name(name))
        .ok_or_else(|| {
            Error::format(
                path,
                format!("no <{name}> in its <{}>", node.tag_name().name()),
            )
        })
}

/// `N` numbers of the attribute `name` of `node`, `None` when it has none.
fn numbers<const N: usize>(path: &Path, node: Node, name: &str) -> Result<Option<[f64; N]>> {
    let Some(text) = node.attribute(name) else {
        return Ok(None);
    };
    let values: Vec<f64> = text
        .split_ascii_whitespace()
        .map(|w| w.parse().ok().filter(|v: &f64| v.is_finite()))
        .collect::<Option<_>>()
        .unwrap_or_default();
    let values: [f64; N] = values.try_into().map_err(|_| {
        Error::format(
            path,
            format!(
                "{name}={:?}: expected {N} numbers",
                crate::error::names::text(text)
            ),
        )
    })?;
    Ok(Some(values))
}

/// `N` whole numbers of the attribute `name` of `node`, which must have it.
fn integers<const N: usize>(path: &Path, node: Node, name: &str) -> Result<[i64; N]> {
    let values = numbers::<N>(path, node, name)?.ok_or_else(|| {
        Error::format(
            path,
            format!("its <{}> has no {name}", node.tag_name().name()),
        )
    })?;
    if values.iter().any(|v| v.fract() != 0.0 || v.abs() > 1e15) {
        return Err(Error::format(
            path,
            format!("{name} {values:?}: expected whole numbers"),
        ));
    }
    Ok(values.map(|v| v as i64))
}

/// The voxels along each axis of the `points` of an extent: a cell fewer for cell data (one
/// where the extent is flat).
fn voxel_dims(points: [usize; 3], cells: bool) -> [usize; 3] {
    if cells {
        points.map(|n| n.saturating_sub(1).max(1))
    } else {
        points
    }
}

/// The points of `extent` along axis `m`; 0 when it is empty or beyond a billion.
fn extent_points(extent: [i64; 6], m: usize) -> usize {
    let n = extent[2 * m + 1] - extent[2 * m] + 1;
    usize::try_from(n)
        .ok()
        .filter(|&n| n <= 1 << 30)
        .unwrap_or(0)
}

/// The array read: the one `chosen` names (`--array`), else the one `Scalars` names (point data
/// first), else the first one of one component.
fn pick_array<'a>(path: &Path, piece: Node<'a, '_>, chosen: Option<&str>) -> Result<Array<'a>> {
    let sections = ["PointData", "CellData"].map(|s| piece.children().find(|n| n.has_tag_name(s)));
    let arrays = |section: Option<Node<'a, '_>>| {
        section
            .into_iter()
            .flat_map(|s| s.children().filter(|n| n.has_tag_name("DataArray")))
    };
    if let Some(chosen) = chosen {
        let all = || (0..2).flat_map(|k| arrays(sections[k]).map(move |a| (k, a)));
        let Some((k, node)) = all().find(|(_, a)| a.attribute("Name") == Some(chosen)) else {
            let names: Vec<String> = all()
                .map(|(_, a)| {
                    format!(
                        "{:?}",
                        crate::error::names::text(a.attribute("Name").unwrap_or(""))
                    )
                })
                .collect();
            return Err(Error::format(
                path,
                format!(
                    "holds no array {:?}: its arrays are {}",
                    crate::error::names::text(chosen),
                    names.join(", ")
                ),
            ));
        };
        return array(path, node, k == 1);
    }
    let named = sections.iter().enumerate().find_map(|(k, s)| {
        let scalars = s.and_then(|s| s.attribute("Scalars"))?;
        Some((k, arrays(*s).find(|a| a.attribute("Name") == Some(scalars))))
    });
    let (k, node) = match named {
        Some((k, Some(node))) => (k, node),
        Some((k, None)) => {
            let scalars = sections[k]
                .and_then(|s| s.attribute("Scalars"))
                .unwrap_or("");
            return Err(Error::format(
                path,
                format!(
                    "its Scalars {:?} names no array",
                    crate::error::names::text(scalars)
                ),
            ));
        }
        None => (0..2)
            .find_map(|k| {
                arrays(sections[k])
                    .find(|a| a.attribute("NumberOfComponents").unwrap_or("1") == "1")
                    .map(|a| (k, a))
            })
            .ok_or_else(|| Error::format(path, "holds no array of one component to read"))?,
    };
    array(path, node, k == 1)
}

/// What the `<DataArray>` `node` says.
fn array<'a>(path: &Path, node: Node<'a, '_>, cells: bool) -> Result<Array<'a>> {
    let name = node.attribute("Name").unwrap_or("").to_string();
    let shown = crate::error::names::text(&name);
    let components = node.attribute("NumberOfComponents").unwrap_or("1");
    if components != "1" {
        return Err(Error::unsupported(
            path,
            format!(
                "its array {shown:?} has {} components a voxel (a vector field): slabscope reads scalars",
                crate::error::names::text(components)
            ),
        ));
    }
    let ty_name = node.attribute("type").unwrap_or("");
    let (ty, wide) = scalar_type(ty_name).ok_or_else(|| {
        Error::unsupported(
            path,
            format!(
                "its array {shown:?} is of type {:?}: slabscope reads Int8 to UInt64, Float32 \
                 and Float64",
                crate::error::names::text(ty_name)
            ),
        )
    })?;
    let offset = node
        .attribute("offset")
        .map(|o| {
            o.trim()
                .parse::<u64>()
                .map_err(|_| Error::format(path, format!("its array {shown:?} has a bad offset")))
        })
        .transpose()?;
    Ok(Array {
        id: node.id(),
        cells,
        name,
        ty,
        wide,
        format: node.attribute("format").unwrap_or("ascii"),
        offset,
        text: node.text().unwrap_or(""),
    })
}

impl Array<'_> {
    /// The bytes of one of its values in the file.
    fn size(&self) -> usize {
        self.wide.map_or(self.ty.size(), |_| Wide::SIZE)
    }
}

/// The voxel type of a VTK XML type's name, and its 64-bit integer type (held as f32).
fn scalar_type(name: &str) -> Option<(VoxelType, Option<Wide>)> {
    let ty = match name {
        "Int8" | "Char" => VoxelType::I8,
        "UInt8" => VoxelType::U8,
        "Int16" => VoxelType::I16,
        "UInt16" => VoxelType::U16,
        "Int32" => VoxelType::I32,
        "UInt32" => VoxelType::U32,
        "Float32" => VoxelType::F32,
        "Float64" => VoxelType::F64,
        "Int64" => return Some((VoxelType::F32, Some(Wide::I64))),
        "UInt64" => return Some((VoxelType::F32, Some(Wide::U64))),
        _ => return None,
    };
    Some((ty, None))
}

/// The spacing and the voxel-to-world transform of the `<ImageData>` `image` whose piece spans
/// `extent`: `Origin + Direction · (index · Spacing)`, a cell's voxel at the cell's centre.
fn placement(
    path: &Path,
    image: Node,
    extent: [i64; 6],
    cells: bool,
    notes: &mut Vec<String>,
) -> Result<([f64; 3], WorldTransform)> {
    let spacing = numbers::<3>(path, image, "Spacing")?.unwrap_or_else(|| {
        notes.push("no Spacing: using 1 mm".into());
        [1.0; 3]
    });
    if spacing.iter().any(|&s| s <= 0.0) {
        return Err(Error::format(
            path,
            format!("Spacing {spacing:?}: expected three positive numbers"),
        ));
    }
    let origin = numbers::<3>(path, image, "Origin")?.unwrap_or([0.0; 3]);
    let direction = numbers::<9>(path, image, "Direction")?
        .unwrap_or([1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
    // The first voxel's index in the image's grid.
    let first: [f64; 3] =
        std::array::from_fn(|m| extent[2 * m] as f64 + if cells { 0.5 } else { 0.0 });
    let mut transform = WorldTransform::unknown(spacing);
    for r in 0..3 {
        for c in 0..3 {
            transform.matrix[r][c] = direction[3 * r + c] * spacing[c];
        }
        transform.matrix[r][3] = origin[r]
            + (0..3)
                .map(|c| transform.matrix[r][c] * first[c])
                .sum::<f64>();
    }
    Ok((spacing, transform))
}
