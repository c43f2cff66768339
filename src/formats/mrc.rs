//! MRC/CCP4 (`.mrc`, `.rec`, `.map`, `.st`, `.ali`, `.mrcs`): the maps and tomograms of
//! electron microscopy, as MRC2014 describes them. A 1024-byte header of 4-byte words (`NX`, `NY`,
//! `NZ`, `MODE`, the sampling `MX`, `MY`, `MZ`, the cell in ångström, which map axes the
//! columns, rows and sections run along, `ISPG`, the extended header's size `NSYMBT`, `"MAP "` at
//! byte 208 and the machine stamp), an extended header skipped by its declared size, then the
//! voxels, columns fastest.
//!
//! Modes read: 0 (signed bytes; unsigned in IMOD's files that say so), 1 (i16), 2 (f32), 6 (u16)
//! and 12 (f16, widened to f32). The voxel size is the cell over the sampling along each map axis;
//! a map whose columns, rows and sections do not run along X, Y and Z is reordered so that the
//! volume's x, y, z are the map's X, Y, Z. A stack of images (`ISPG` 0 in a tilt series' or
//! particle stack's file) is refused: it is no volume.

use std::io::Read;
use std::path::Path;

use serde::Serialize;

use super::data::{DataSpec, Encoding, Skip, read_voxels, typed_buffer};
use super::details::{Details, json_of};
use super::reader::{Reader, Sniff};
use super::scratch::{Room, VoxelOut};
use super::{Format, LoadOptions, Read0, Source};
use crate::error::{Error, Result};
use crate::volume::{Endian, VoxelType, Voxels};

/// The MRC reader.
pub(crate) struct Mrc;

/// Names whose files are stacks of images when the header says `ISPG` 0: tilt series, aligned
/// stacks, particle stacks.
const STACKS: [&str; 3] = [".st", ".ali", ".mrcs"];

impl Reader for Mrc {
    fn format(&self) -> Format {
        Format::Mrc
    }

    fn title(&self) -> &'static str {
        "MRC"
    }

    fn sniff(&self, head: &[u8]) -> Sniff {
        if head.len() >= 1024 && &head[208..212] == b"MAP " {
            Sniff::Mine
        } else {
            Sniff::No
        }
    }

    /// Files written before MRC2014 may lack `"MAP "`: their names say what they are.
    #[allow(clippy::case_sensitive_file_extension_comparisons)] // the name is lowercased
    fn claims_name(&self, name: &str) -> bool {
        [".mrc", ".rec", ".st", ".ali", ".mrcs"]
            .iter()
            .any(|e| name.ends_with(e))
    }

    #[allow(clippy::case_sensitive_file_extension_comparisons)] // the name is lowercased
    fn volume_name(&self, name: &str) -> bool {
        self.claims_name(name) || name.ends_with(".map") || name.ends_with(".ccp4")
    }

    fn details_key(&self) -> Option<&'static str> {
        Some("mrc")
    }

    fn read(&self, source: &Source, opts: &LoadOptions) -> Result<Read0> {
        load(source, opts)
    }
}

/// What `info` shows of an MRC map: its mode, and what the mode's values are.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub(crate) struct MrcDetails {
    /// `MODE` as the header gives it.
    pub mode: i32,
    /// What its values are: `32-bit reals`, `8-bit unsigned integers (IMOD)`, ...
    pub values: &'static str,
}

impl Details for MrcDetails {
    fn lines(&self) -> Vec<(String, String)> {
        vec![("mode".into(), format!("{} ({})", self.mode, self.values))]
    }

    fn json(&self) -> serde_json::Value {
        json_of(self)
    }
}

/// What the header says.
#[derive(Debug)]
struct Header {
    /// Columns, rows, sections.
    n: [usize; 3],
    mode: i32,
    /// Voxels along the cell's X, Y, Z.
    sampling: [i32; 3],
    /// The cell's size along X, Y, Z, ångström.
    cell: [f32; 3],
    /// Which map axis (1, 2, 3: X, Y, Z) the columns, rows and sections run along.
    axes: [i32; 3],
    ispg: i32,
    extended: i32,
    endian: Endian,
    /// IMOD's stamp with its flag for bytes read as unsigned.
    unsigned_bytes: bool,
}

/// IMOD's stamp (`"IMOD"` as a word), and its flag for signed bytes.
const IMOD_STAMP: i32 = 1_146_047_817;

fn header(path: &Path, head: &[u8; 1024]) -> Result<Header> {
    // The machine stamp: 0x44 0x44 or 0x44 0x41 little-endian, 0x11 0x11 big-endian; without
    // one (older files), the order in which the dimensions and mode make sense.
    let endian = match head[212..214] {
        [0x44, 0x44 | 0x41] => Endian::Little,
        [0x11, 0x11] => Endian::Big,
        _ => {
            let n = i32::from_le_bytes([head[0], head[1], head[2], head[3]]);
            if (1..1 << 24).contains(&n) {
                Endian::Little
            } else {
                Endian::Big
            }
        }
    };
    let word = |i: usize| {
        let b = [
            head[4 * i],
            head[4 * i + 1],
            head[4 * i + 2],
            head[4 * i + 3],
        ];
        match endian {
            Endian::Little => i32::from_le_bytes(b),
            Endian::Big => i32::from_be_bytes(b),
        }
    };
    let real = |i: usize| f32::from_bits(word(i) as u32);
    let n = [word(0), word(1), word(2)];
    if n.iter().any(|&d| d < 1) {
        return Err(Error::format(
            path,
            format!(
                "not an MRC file: its header says {} x {} x {} voxels",
                n[0], n[1], n[2]
            ),
        ));
    }
    Ok(Header {
        n: n.map(|d| d as usize),
        mode: word(3),
        sampling: [word(7), word(8), word(9)],
        cell: [real(10), real(11), real(12)],
        axes: [word(16), word(17), word(18)],
        ispg: word(22),
        extended: word(23),
        endian,
        unsigned_bytes: word(38) == IMOD_STAMP && head[156] & 1 == 0,
    })
}

impl Header {
    /// The type the voxels are stored as (f16 as its bits, u16).
    fn stored(&self, path: &Path) -> Result<VoxelType> {
        Ok(match self.mode {
            0 if self.unsigned_bytes => VoxelType::U8,
            0 => VoxelType::I8,
            1 => VoxelType::I16,
            2 => VoxelType::F32,
            6 | 12 => VoxelType::U16,
            3 | 4 => {
                return Err(Error::unsupported(
                    path,
                    format!(
                        "MRC mode {}: complex values (a Fourier transform); slabscope reads real volumes",
                        self.mode
                    ),
                ));
            }
            mode => {
                return Err(Error::unsupported(
                    path,
                    format!("MRC mode {mode}: slabscope reads modes 0, 1, 2, 6 and 12"),
                ));
            }
        })
    }

    /// What the values of a mode read are.
    fn values(&self) -> &'static str {
        match self.mode {
            0 if self.unsigned_bytes => "8-bit unsigned integers (IMOD)",
            0 => "8-bit signed integers",
            1 => "16-bit signed integers",
            2 => "32-bit reals",
            6 => "16-bit unsigned integers",
            _ => "16-bit reals",
        }
    }

    /// Where each stored axis (columns, rows, sections) goes among x, y, z.
    fn order(&self, path: &Path) -> Result<[usize; 3]> {
        let a = self.axes;
        if a == [0, 0, 0] {
            return Ok([0, 1, 2]);
        }
        let mut seen = [false; 3];
        for &m in &a {
            match usize::try_from(m - 1).ok().filter(|&m| m < 3) {
                Some(m) if !seen[m] => seen[m] = true,
                _ => {
                    return Err(Error::format(
                        path,
                        format!(
                            "MAPC, MAPR, MAPS are {}, {}, {}: expected 1, 2 and 3 in some order",
                            a[0], a[1], a[2]
                        ),
                    ));
                }
            }
        }
        Ok(a.map(|m| (m - 1) as usize))
    }

    /// The voxel size along x, y, z in mm: the cell over the sampling (ångström), or `None`
    /// when the header gives none.
    fn spacing(&self) -> Option<[f64; 3]> {
        let size: [f64; 3] =
            std::array::from_fn(|m| f64::from(self.cell[m]) / f64::from(self.sampling[m]));
        size.iter()
            .all(|s| s.is_finite() && *s > 0.0)
            .then(|| size.map(|s| s * 1e-7))
    }
}

fn load(source: &Source, opts: &LoadOptions) -> Result<Read0> {
    let path = source.path();
    let mut head = [0u8; 1024];
    let mut file = source.open()?;
    file.read_exact(&mut head)
        .map_err(|_| Error::format(path, "not an MRC file: shorter than its 1024-byte header"))?;
    let h = header(path, &head)?;
    let stored = h.stored(path)?;
    let order = h.order(path)?;
    let name = source.name().to_ascii_lowercase();
    if h.ispg == 0 && h.n[2] > 1 && STACKS.iter().any(|e| name.ends_with(e)) {
        return Err(Error::format(
            path,
            format!(
                "a stack of {} images (ISPG 0: a tilt series or particle stack), not a volume: \
                 reconstruct it first",
                h.n[2]
            ),
        ));
    }
    if h.ispg >= 400 {
        return Err(Error::unsupported(
            path,
            format!("a stack of volumes (ISPG {}) is not read", h.ispg),
        ));
    }
    let extended = u64::try_from(h.extended).map_err(|_| {
        Error::format(
            path,
            format!("its extended header is {} bytes long", h.extended),
        )
    })?;
    let spec = DataSpec {
        file: source.clone(),
        start: 1024 + extended,
        skip_lines: 0,
        skip: Skip::Bytes(0),
        encoding: Encoding::Raw,
        dims: h.n,
        voxel_type: stored,
        endian: h.endian,
        scale: None,
        volumes: (0, 1),
        trailing: false,
    };
    let mut notes = Vec::new();
    let (ty, mut voxels) = if h.mode == 12 {
        // Widened to f32, within the budget as an f32 volume or in the scratch folder.
        opts.room().check(path, h.n)?;
        // f16 and MRC's other integers are f32s exactly.
        let (bits, _) = read_voxels(&spec, opts.room())?;
        (VoxelType::F32, widen_f16(path, &bits, h.n, opts.room())?)
    } else {
        (stored, read_voxels(&spec, opts.room())?.0)
    };
    let mut dims = h.n;
    if order != [0, 1, 2] {
        // A copy in the new order, within the budget or in the scratch folder.
        dims = reorder_dims(h.n, order);
        voxels = reorder(path, &voxels, h.n, order, opts.room())?;
        notes.push(format!(
            "its columns, rows and sections run along the map's {}: reordered to x, y, z",
            order.map(|m| ["X", "Y", "Z"][m]).join(", ")
        ));
    }
    let spacing = h.spacing().unwrap_or_else(|| {
        notes.push("the header gives no voxel size (cell and sampling): using 1 mm".into());
        [1.0; 3]
    });
    if h.ispg == 0 && h.n[2] > 1 {
        notes.push("the header calls it a stack of images (ISPG 0): read as a volume".into());
    }
    let mut read = Read0::new(path, dims, spacing, ty, voxels, notes)?;
    read.details = Some(std::sync::Arc::new(MrcDetails {
        mode: h.mode,
        values: h.values(),
    }));
    Ok(read)
}

/// The `dims` f16 voxels of `path`, held as their bits, as f32 in `room`.
fn widen_f16(path: &Path, bits: &Voxels, dims: [usize; 3], room: Room) -> Result<Voxels> {
    let Voxels::U16(s) = bits else {
        unreachable!("f16 is read as u16")
    };
    let mut out = room.f32_voxels(path, dims)?;
    for (v, &b) in out.all().iter_mut().zip(s.as_slice()) {
        *v = half::f16::from_bits(b).to_f32();
    }
    out.finish()
}

/// The dimensions along x, y, z of a map stored `n` (columns, rows, sections) along `order`.
fn reorder_dims(n: [usize; 3], order: [usize; 3]) -> [usize; 3] {
    let mut dims = [0; 3];
    for s in 0..3 {
        dims[order[s]] = n[s];
    }
    dims
}

/// The voxels of `path` stored columns, rows, sections (`n`), along the map axes `order`, put
/// in x, y, z order in `room`.
fn reorder(
    path: &Path,
    voxels: &Voxels,
    n: [usize; 3],
    order: [usize; 3],
    room: Room,
) -> Result<Voxels> {
    let dims = reorder_dims(n, order);
    let stride = [1, dims[0], dims[0] * dims[1]];
    crate::volume::with_voxels!(voxels, |v| {
        let mut held = VoxelOut::new(path, dims, room.scratch, || {
            typed_buffer(path, dims, room.max_memory)
        })?;
        let out = held.all();
        let mut i = 0;
        for s in 0..n[2] {
            for r in 0..n[1] {
                for c in 0..n[0] {
                    let at = [c, r, s];
                    let to: usize = (0..3).map(|k| at[k] * stride[order[k]]).sum();
                    out[to] = v[i];
                    i += 1;
                }
            }
        }
        held.finish()
    })
}
