//! Which dataset of an HDF5 file is read, what `info` lists of the file's datasets, and the voxel
//! size from the dataset's attributes.

use std::path::Path;

use rust_hdf5::{DatatypeMessage, H5Dataset, H5File};
use serde::Serialize;

use crate::error::{Error, Result};
use crate::formats::details::{Details, json_of};

/// The most datasets looked at in one file (an Imaris file holds two a channel, time point and
/// resolution level).
const MAX_DATASETS: usize = 65_536;

/// The most datasets `info --json` lists, and its text line.
const MAX_LISTED: usize = 256;
const MAX_LINE: usize = 16;

/// What `DXchange` names a reconstruction (and a beamline's projections).
const DXCHANGE: &str = "exchange/data";

/// What lies beside a beamline's projections, and says they are not a reconstruction.
const RAW_BESIDE: [&str; 3] = ["theta", "data_white", "data_dark"];

/// One dataset of the file.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub(crate) struct Hdf5Dataset {
    /// Its path from the root, with a leading `/`.
    pub path: String,
    /// Its shape, slowest index first, as h5py gives it.
    pub shape: Vec<usize>,
    /// Its element type (`u16`, `f32 big-endian`, `string`...).
    #[serde(rename = "type")]
    pub ty: String,
}

/// What `info` shows of an HDF5 file: its datasets, the one read first.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub(crate) struct Hdf5Details {
    /// The datasets: the one read, then the others by path (at most 256).
    pub datasets: Vec<Hdf5Dataset>,
    /// How many datasets the file holds.
    pub count: usize,
}

impl Details for Hdf5Details {
    fn lines(&self) -> Vec<(String, String)> {
        let mut listed: Vec<String> = self
            .datasets
            .iter()
            .take(MAX_LINE)
            .map(|d| {
                let shape: Vec<String> = d.shape.iter().map(usize::to_string).collect();
                format!(
                    "{} ({} {})",
                    crate::error::names::text(&d.path),
                    shape.join("x"),
                    d.ty
                )
            })
            .collect();
        if self.count > MAX_LINE {
            listed.push(format!("and {} more", self.count - MAX_LINE));
        }
        vec![("datasets".into(), listed.join(", "))]
    }

    fn json(&self) -> serde_json::Value {
        json_of(self)
    }
}

/// A dataset found in the file: its path (without the leading `/`, as `rust-hdf5` names it) and
/// its shape.
#[derive(Clone, Debug)]
pub(super) struct Found {
    pub path: String,
    pub shape: Vec<usize>,
    pub ty: String,
}

impl Found {
    /// Its path as shown, with a leading `/`.
    pub(super) fn shown(&self) -> String {
        format!("/{}", crate::error::names::text(&self.path))
    }
}

/// Every dataset of `file` (at most [`MAX_DATASETS`]), by path.
pub(super) fn list(path: &Path, file: &H5File) -> Result<Vec<Found>> {
    let mut names = file.dataset_names();
    names.sort_unstable();
    if names.len() > MAX_DATASETS {
        return Err(Error::unsupported(
            path,
            format!(
                "holds {} datasets: slabscope looks at most {MAX_DATASETS}",
                names.len()
            ),
        ));
    }
    let mut found = Vec::with_capacity(names.len());
    for name in names {
        let Ok(ds) = file.dataset(&name) else {
            continue;
        };
        let ty = ds
            .datatype()
            .map_or_else(|_| "unreadable type".into(), |t| type_name(&t));
        found.push(Found {
            shape: ds.shape(),
            path: name,
            ty,
        });
    }
    Ok(found)
}

/// The dataset read: the one `named` (a path, with or without its leading `/`), else `DXchange`'s
/// `/exchange/data`, else the only one of three or four dimensions. A beamline's projections
/// are refused unless named; a dataset of another rank always.
pub(super) fn choose<'a>(
    path: &Path,
    found: &'a [Found],
    named: Option<&str>,
    notes: &mut Vec<String>,
) -> Result<&'a Found> {
    let volumes: Vec<&Found> = found
        .iter()
        .filter(|f| matches!(f.shape.len(), 3 | 4))
        .collect();
    let chosen = if let Some(named) = named {
        let want = named.trim_start_matches('/');
        found.iter().find(|f| f.path == want).ok_or_else(|| {
            Error::format(
                path,
                format!(
                    "holds no dataset {}: its datasets are {}",
                    crate::error::names::text(named),
                    listed(found)
                ),
            )
        })?
    } else if let Some(dx) = found.iter().find(|f| f.path == DXCHANGE) {
        refuse_projections(path, found, dx)?;
        dx
    } else {
        match volumes.as_slice() {
            [one] => one,
            [] => {
                return Err(Error::format(
                    path,
                    format!(
                        "holds no dataset of three dimensions: its datasets are {}",
                        listed(found)
                    ),
                ));
            }
            several => {
                return Err(Error::format(
                    path,
                    format!(
                        "holds {} datasets of three or four dimensions ({}): name one with --array",
                        several.len(),
                        several
                            .iter()
                            .map(|f| f.shown())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                ));
            }
        }
    };
    if !matches!(chosen.shape.len(), 3 | 4) {
        return Err(rank_error(path, chosen));
    }
    if found.len() > 1 {
        notes.push(format!(
            "read dataset {} of the file's {}",
            chosen.shown(),
            found.len()
        ));
    }
    Ok(chosen)
}

/// The error for a dataset of another rank than three or four (or four where three are asked).
pub(super) fn rank_error(path: &Path, chosen: &Found) -> Error {
    Error::format(
        path,
        format!(
            "dataset {} has {} dimensions ({}): slabscope reads datasets of three (z, y, x) or \
             four (t, z, y, x)",
            chosen.shown(),
            chosen.shape.len(),
            chosen.ty
        ),
    )
}

/// Refuses `dx` when a beamline's raw data lies beside it: it is projections.
fn refuse_projections(path: &Path, found: &[Found], dx: &Found) -> Result<()> {
    let parent = dx.path.rsplit_once('/').map_or("", |(p, _)| p);
    let beside: Vec<&str> = RAW_BESIDE
        .into_iter()
        .filter(|raw| {
            let sibling = if parent.is_empty() {
                (*raw).to_string()
            } else {
                format!("{parent}/{raw}")
            };
            found.iter().any(|f| f.path == sibling)
        })
        .collect();
    if beside.is_empty() {
        return Ok(());
    }
    Err(Error::format(
        path,
        format!(
            "holds projections, not a reconstruction ({} beside {}): reconstruct it first, \
             or name the dataset with --array to look at the projections",
            beside.join(", "),
            dx.shown()
        ),
    ))
}

/// The datasets of `found`, listed for a message (the first 8).
fn listed(found: &[Found]) -> String {
    if found.is_empty() {
        return "none".into();
    }
    let mut text: Vec<String> = found
        .iter()
        .take(8)
        .map(|f| {
            let shape: Vec<String> = f.shape.iter().map(usize::to_string).collect();
            format!("{} ({})", f.shown(), shape.join("x"))
        })
        .collect();
    if found.len() > 8 {
        text.push(format!("and {} more", found.len() - 8));
    }
    text.join(", ")
}

/// What `info` lists: the dataset read first, then the others by path.
pub(super) fn details(found: &[Found], read: &str) -> Hdf5Details {
    let entry = |f: &Found| Hdf5Dataset {
        path: format!("/{}", f.path),
        shape: f.shape.clone(),
        ty: f.ty.clone(),
    };
    let first = found.iter().filter(|f| f.path == read).map(entry);
    let rest = found.iter().filter(|f| f.path != read).map(entry);
    Hdf5Details {
        datasets: first.chain(rest).take(MAX_LISTED).collect(),
        count: found.len(),
    }
}

/// The voxel size along x, y, z in mm from the dataset's `element_size_um` attribute (three
/// values, z, y, x, in µm, as ilastik and Fiji write it); `None` when it has none usable.
pub(super) fn spacing(ds: &H5Dataset) -> Option<[f64; 3]> {
    let attr = ds.attr("element_size_um").ok()?;
    let values: Vec<f64> = attr.read_numeric_as::<f64>().ok().or_else(|| {
        attr.read_numeric_as::<i64>()
            .ok()
            .map(|v| v.into_iter().map(|x| x as f64).collect())
    })?;
    let [z, y, x] = values.as_slice() else {
        return None;
    };
    let mm = [*x, *y, *z].map(|um| um * 1e-3);
    mm.iter().all(|s| s.is_finite() && *s > 0.0).then_some(mm)
}

/// A dataset's element type as `info` shows it.
pub(super) fn type_name(dt: &DatatypeMessage) -> String {
    let order = |o: &rust_hdf5::ByteOrder| match o {
        rust_hdf5::ByteOrder::LittleEndian => "",
        rust_hdf5::ByteOrder::BigEndian => " big-endian",
    };
    match dt {
        DatatypeMessage::FixedPoint {
            size,
            byte_order,
            signed,
            ..
        } => format!(
            "{}{}{}",
            if *signed { "i" } else { "u" },
            u64::from(*size) * 8,
            order(byte_order)
        ),
        DatatypeMessage::FloatingPoint {
            size, byte_order, ..
        } => format!("f{}{}", u64::from(*size) * 8, order(byte_order)),
        DatatypeMessage::Compound { .. } => "compound".into(),
        DatatypeMessage::FixedString { .. } | DatatypeMessage::VarLenString { .. } => {
            "string".into()
        }
        _ => "other".into(),
    }
}
