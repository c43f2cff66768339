//! The reports other programs read: the JSON object of `analyze --json` (docs/design.md §3), the slab
//! boundaries for renderers, what `info --json` says of a volume or a folder, and the curves as
//! CSV. Built from library results only, so that the
//! CLI, the TUI's export and triage print the same thing. Every JSON object carries
//! [`SCHEMA_VERSION`], raised whenever a field changes meaning or goes away.

use std::fmt::Write as _;

use serde::Serialize;

use crate::analysis::{Analysis, AxisBy, AxisGain, GainRanking, GainSampling};
use crate::error::{Error, Result};
use crate::explain::Explain;
use crate::geometry::{WorldAxis, dot};
use crate::partition::{BackgroundSummary, Partition};
use crate::view::{AxisEntropy, Contender, RankedBy, ViewParams};
use crate::volume::Volume;

mod info;
mod json;
mod labels;

pub use info::{FolderReport, InfoReport, ListedVolume};
pub use labels::{stage_labels, write_labels};

/// The version of the JSON contract.
pub const SCHEMA_VERSION: u32 = 2;

/// The object `analyze --json` prints.
#[derive(Clone, Debug, Serialize)]
pub struct AnalysisReport {
    /// [`SCHEMA_VERSION`].
    pub schema_version: u32,
    /// The file as the user named it.
    pub file: String,
    /// `[nx, ny, nz]`.
    pub dims: [usize; 3],
    /// `[sx, sy, sz]`, mm.
    pub spacing: [f64; 3],
    /// Smallest and largest finite voxel.
    pub range: [f32; 2],
    /// The voxel-to-world transform: `affine`, `orientation`, `orthogonal`, `world_bounds`.
    #[serde(flatten)]
    pub geometry: GeometryReport,
    /// The pyramid level the analysis was computed on (level 0: every voxel).
    pub resolution: ResolutionReport,
    /// The pyramid level the view search ran on, when it is not `resolution`'s (a full-resolution
    /// partition within a memory limit searches the views on a coarser level).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub views_resolution: Option<ResolutionReport>,
    /// The sampling and view-search parameters, spacings resolved to millimetres.
    pub params: ViewParams,
    /// Every axis of the view search, lowest entropy rate first (absent without a search).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub views: Option<Vec<AxisEntropy>>,
    /// The most structured axis (null without a search).
    pub best_axis: Option<[f64; 3]>,
    /// What the views are sorted by: `phase_mean` or `paper_lattice` (absent without a search).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ranked_by: Option<RankedBy>,
    /// Whether another axis is a contender: null on the paper's single lattice, absent without a
    /// search.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub uncertain: Option<Option<bool>>,
    /// The best axis and its contenders, each `{axis, mean, se}`: null on the paper's single
    /// lattice, absent without a search.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contenders: Option<Option<Vec<Contender>>>,
    /// With refinement: the best axis found near the best sphere axes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refined: Option<AxisEntropy>,
    /// With the gain ranking: which ranking picked the axis, `entropy` or `gain` (absent when
    /// the axis was given).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub axis_by: Option<AxisBy>,
    /// With the gain ranking: how it sampled, `{"slabs", "every", "phases"}`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gain_sampling: Option<GainSampling>,
    /// With the gain ranking: whether another axis keeps as much within two standard errors.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gain_uncertain: Option<bool>,
    /// With the gain ranking: the best axis by gain and its contenders, each `{axis, mean, se}`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gain_contenders: Option<Vec<Contender>>,
    /// With the gain ranking: the best axis by gain, refined between the sphere's axes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gain_refined: Option<AxisGain>,
    /// What was left out of the slab histograms as background: `{"mode", "value", "fraction"}`,
    /// null when nothing was (`--background none`).
    pub background: Option<BackgroundSummary>,
    /// What the user should know about this analysis.
    pub notes: Vec<String>,
    /// The partition along the axis.
    pub partition: Partition,
    /// With `--explain`: the numbers behind the axis and the steps (docs/json.md).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub explain: Option<Explain>,
}

impl AnalysisReport {
    /// The report of `analysis` of `volume`, read from the file `file`, run with `view` (whose
    /// spacings are resolved here when no view search ran).
    pub fn new(
        file: &str,
        volume: &Volume,
        view: &ViewParams,
        analysis: &Analysis,
    ) -> Result<Self> {
        let s = volume.stats();
        let views = analysis.views.as_ref();
        let gain = analysis.gain.as_ref();
        let params = match views {
            Some(v) => v.params.clone(),
            None => ViewParams {
                sampling: view.sampling.resolved(volume.dims(), volume.spacing())?,
                ..view.clone()
            },
        };
        // A level read without level 0 (a remote store's): the grid is level 0's, the range
        // the level's own.
        let (dims, spacing, geometry) = match volume.unread_finest() {
            Some(f) => (
                f.dims,
                f.spacing,
                GeometryReport::of_grid(&f.transform, f.dims),
            ),
            None => (volume.dims(), volume.spacing(), GeometryReport::of(volume)),
        };
        Ok(Self {
            schema_version: SCHEMA_VERSION,
            file: file.to_string(),
            dims,
            spacing,
            range: [s.min, s.max],
            geometry,
            resolution: ResolutionReport::of(volume),
            views_resolution: None,
            params,
            views: views.map(|v| match (gain, analysis.axis_by) {
                (Some(g), Some(AxisBy::Gain)) => g.sorted(&v.views).into_iter().cloned().collect(),
                _ => v.views.clone(),
            }),
            best_axis: match (&analysis.gain, analysis.axis_by) {
                (Some(g), Some(AxisBy::Gain)) => Some(g.refined.axis),
                _ => views.map(|v| v.best().axis),
            },
            ranked_by: views.map(|v| v.ranked_by),
            uncertain: views.map(|v| v.uncertain),
            contenders: views.map(|v| v.contenders.clone()),
            refined: views.and_then(|v| v.refined.clone()),
            axis_by: gain.and(analysis.axis_by),
            gain_sampling: gain.map(|g| g.sampling),
            gain_uncertain: gain.map(GainRanking::uncertain),
            gain_contenders: gain.map(|g| g.contenders.clone()),
            gain_refined: gain.map(|g| g.refined.clone()),
            background: Some(analysis.partition.background).filter(|b| b.mode != "none"),
            notes: analysis.notes.clone(),
            partition: analysis.partition.clone(),
            explain: analysis.explain.clone(),
        })
    }
}

impl AnalysisReport {
    /// This report of an analysis of `level`, a pyramid level of the volume it describes (whose
    /// dimensions, spacing, range and geometry it keeps): the slab indices are `level`'s slices.
    #[must_use]
    pub fn computed_on(mut self, level: &Volume) -> Self {
        self.resolution = ResolutionReport::of(level);
        self
    }

    /// This report of an analysis whose view search ran on `level`: `views_resolution` says so
    /// when it is not the level partitioned (and nothing is said without a view search).
    #[must_use]
    pub fn views_on(mut self, level: &Volume) -> Self {
        let views = ResolutionReport::of(level);
        if self.views.is_some() && views.pyramid_level != self.resolution.pyramid_level {
            self.views_resolution = Some(views);
        }
        self
    }
}

/// The pyramid level an analysis was computed on.
#[derive(Clone, Debug, Serialize)]
pub struct ResolutionReport {
    /// The pyramid level: 0 is every voxel; each level halves every axis.
    pub pyramid_level: usize,
    /// Per axis, how many voxels of the file one voxel of the level spans.
    pub factor: [usize; 3],
    /// The level's dimensions.
    pub dims: [usize; 3],
}

impl ResolutionReport {
    /// The level `volume` is.
    #[must_use]
    pub fn of(volume: &Volume) -> Self {
        let level = volume.level();
        Self {
            pyramid_level: level.index,
            factor: level.factor,
            dims: volume.dims(),
        }
    }
}

/// Where a volume lies in the world, as `info --json` and `analyze --json` give it.
#[derive(Clone, Debug, Serialize)]
pub struct GeometryReport {
    /// The 4×4 voxel-to-world matrix, rows, voxel index to RAS+ mm; spacing on the diagonal when
    /// the file states no orientation.
    pub affine: [[f64; 4]; 4],
    /// The orientation codes as nibabel's `aff2axcodes` gives them (`LPS`, `RAS`, `LSA`, ...),
    /// null when the file states no orientation.
    pub orientation: Option<String>,
    /// Whether the voxel axes are perpendicular in the world (false under shear, such as a
    /// tilted gantry's).
    pub orthogonal: bool,
    /// The smallest and largest world coordinates of the voxel centres, `[[x, y, z], [x, y, z]]`.
    pub world_bounds: [[f64; 3]; 2],
}

impl GeometryReport {
    /// The geometry of `volume`.
    pub fn of(volume: &Volume) -> Self {
        Self::of_grid(volume.transform(), volume.dims())
    }

    /// The geometry of a volume of `dims` voxels placed by `t`.
    #[must_use]
    pub fn of_grid(t: &crate::geometry::WorldTransform, dims: [usize; 3]) -> Self {
        Self {
            affine: t.matrix,
            orientation: t.axcodes(),
            orthogonal: t.is_orthogonal(),
            world_bounds: t.world_bounds(dims),
        }
    }
}

/// The slab boundaries in the form renderers take: slice indices, millimetres along the axis
/// and fractions of its length, and each boundary plane as a point and a normal in world mm.
#[derive(Clone, Debug, Serialize)]
pub struct SlabsReport {
    /// [`SCHEMA_VERSION`].
    pub schema_version: u32,
    /// The file as the user named it.
    pub file: String,
    /// The canonical axis, in physical voxel space.
    pub axis: [f64; 3],
    /// The axis in world coordinates: `world_axis` and `anatomy`.
    #[serde(flatten)]
    pub world: WorldAxis,
    /// The orientation codes of the volume (`LPS`, `RAS`, ...), null when the file states none.
    pub orientation: Option<String>,
    /// The method that found the slabs.
    pub method: crate::partition::Method,
    /// Number of slices.
    pub slices: usize,
    /// Distance between slices, mm.
    pub thickness_mm: f64,
    /// The slabs in slice order.
    pub slabs: Vec<SlabBounds>,
    /// The K + 1 boundary planes in order, from the start of slab 0 to the end of the last:
    /// slab i lies between planes i and i + 1.
    pub planes: Vec<Plane>,
}

/// One slab's bounds.
#[derive(Clone, Debug, Serialize)]
pub struct SlabBounds {
    /// Its number, from 0.
    pub index: usize,
    /// Slices `[start, end)`.
    pub slices: (usize, usize),
    /// Where it starts and ends along the axis, mm from voxel (0, 0, 0).
    pub mm: (f64, f64),
    /// Where it starts and ends along `world_axis`, world mm.
    pub world_mm: (f64, f64),
    /// Where it starts and ends as fractions of the stack.
    pub fraction: (f64, f64),
}

/// A plane in world millimetres: the points `x` with `normal · (x - point) = 0`.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Plane {
    /// The point of the plane nearest the volume's centre.
    pub point: [f64; 3],
    /// Its unit normal, `world_axis`.
    pub normal: [f64; 3],
    /// Its signed position along the normal, `normal · point`.
    pub world_mm: f64,
}

impl SlabsReport {
    /// The bounds of `p`'s slabs, a partition of `volume`.
    pub fn new(file: &str, volume: &Volume, p: &Partition) -> Self {
        let n = p.slices as f64;
        let t = volume.transform();
        let spacing = volume.spacing();
        let centre: [f64; 3] =
            std::array::from_fn(|k| (volume.dims()[k] as f64 - 1.0) / 2.0 * spacing[k]);
        let plane = |s: f64| {
            let along = s - dot(centre, p.axis);
            let point = t.physical_point(
                std::array::from_fn(|k| centre[k] + along * p.axis[k]),
                spacing,
            );
            let normal = p.world.world_axis;
            Plane {
                point,
                normal,
                world_mm: dot(normal, point),
            }
        };
        let mut planes: Vec<Plane> = p.info.iter().map(|s| plane(s.mm.0)).collect();
        planes.extend(p.info.last().map(|s| plane(s.mm.1)));
        Self {
            schema_version: SCHEMA_VERSION,
            file: file.to_string(),
            axis: p.axis,
            world: p.world.clone(),
            orientation: t.axcodes(),
            method: p.method,
            slices: p.slices,
            thickness_mm: p.thickness,
            slabs: p
                .info
                .iter()
                .enumerate()
                .map(|(index, s)| SlabBounds {
                    index,
                    slices: s.slices,
                    mm: s.mm,
                    world_mm: s.world_mm,
                    fraction: (s.slices.0 as f64 / n, s.slices.1 as f64 / n),
                })
                .collect(),
            planes,
        }
    }
}

/// `value` as pretty JSON, with every `-0.0` written as `0.0` (a direction component that is
/// zero has no sign worth printing), nothing in it raw: its control and bidirectional characters
/// written as `\uXXXX` escapes ([`names::json`](crate::error::names::json)).
pub fn to_json(value: &impl Serialize) -> Result<String> {
    let text = json::pretty(value).map_err(|e| Error::Encode(e.to_string()))?;
    Ok(crate::error::names::json(&text).into_owned())
}

/// `value` as one line of JSON (a row of JSON Lines), nothing in it raw: its control and
/// bidirectional characters written as `\uXXXX` escapes ([`names::json`](crate::error::names::json)).
pub fn to_json_line(value: &impl Serialize) -> Result<String> {
    let text = serde_json::to_string(value).map_err(|e| Error::Encode(e.to_string()))?;
    Ok(crate::error::names::json(&text).into_owned())
}

/// `cut,mm,world_mm,nmi,gain`: for each boundary between slice c-1 and c, its position along the
/// axis and along `world_axis`, the NMI of the two slices, and the ΔI of cutting the whole stack there.
pub fn curves_csv(p: &Partition) -> String {
    let mut out = String::from("cut,mm,world_mm,nmi,gain\n");
    for c in 1..p.slices {
        let mm = p.offset + (c as f64 - 0.5) * p.thickness;
        let _ = writeln!(
            out,
            "{c},{mm},{},{},{}",
            p.world_mm(mm),
            p.nmi_curve[c - 1],
            p.gain_curve[c - 1]
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::formats::Loaded;
    use crate::formats::dicom::DicomSeries;

    /// The key paths of a JSON value (`.dicom.patient`, `.volumes[].path`), as the contract
    /// snapshots list them.
    fn key_paths(v: &serde_json::Value, prefix: &str, out: &mut Vec<String>) {
        match v {
            serde_json::Value::Object(o) => {
                for (k, v) in o {
                    let path = format!("{prefix}.{k}");
                    out.push(path.clone());
                    key_paths(v, &path, out);
                }
            }
            serde_json::Value::Array(a) => {
                for v in a.iter().filter(|v| v.is_object()) {
                    key_paths(v, &format!("{prefix}[]"), out);
                }
            }
            _ => {}
        }
    }

    fn keys_of(value: &impl Serialize) -> Vec<String> {
        let text = to_json(value).unwrap();
        let mut keys = Vec::new();
        key_paths(&serde_json::from_str(&text).unwrap(), "", &mut keys);
        keys.sort();
        keys.dedup();
        keys
    }

    #[test]
    fn info_reports_every_key_of_the_contract() {
        let mut loaded = Loaded {
            volume: crate::volume::phantom::body([12, 10, 14], 1).unwrap(),
            format: crate::formats::Format::Nrrd,
            notes: vec!["a note".into()],
            sources: Vec::new(),
            details: None,
            format_version: None,
        };
        let plain = InfoReport::new("body.nrrd", &loaded, 32).unwrap();
        assert_eq!(plain.histogram.len(), 32);
        let keys = keys_of(&plain);
        assert_eq!(
            keys,
            [
                ".affine",
                ".dicom",
                ".dims",
                ".file",
                ".format",
                ".format_version",
                ".hdf5",
                ".held_type",
                ".histogram",
                ".mapped_bytes",
                ".mean",
                ".memory_bytes",
                ".missing",
                ".mrc",
                ".notes",
                ".ome_zarr",
                ".orientation",
                ".orthogonal",
                ".range",
                ".schema_version",
                ".scratch_bytes",
                ".spacing",
                ".statistics_from",
                ".stored_bytes",
                ".type",
                ".voxels",
                ".vti",
                ".vtk",
                ".world_bounds",
            ]
        );
        loaded.format = crate::formats::Format::Dicom;
        loaded.details = Some(std::sync::Arc::new(DicomSeries {
            key: "1.2.3".into(),
            number: Some(4),
            description: "Abdomen".into(),
            modality: "CT".into(),
            syntax: "explicit VR little endian".into(),
            patient: vec![("patient name".into(), "Doe^J".into())],
        }));
        let dicom = InfoReport::new("ct", &loaded, 32).unwrap();
        let keys = keys_of(&dicom);
        for key in [
            ".dicom.series",
            ".dicom.number",
            ".dicom.description",
            ".dicom.modality",
            ".dicom.transfer_syntax",
            ".dicom.patient",
            ".dicom.patient.patient name",
        ] {
            assert!(keys.iter().any(|k| k == key), "{key} missing from {keys:?}");
        }
        let v: serde_json::Value = serde_json::from_str(&to_json(&dicom).unwrap()).unwrap();
        assert_eq!(v["schema_version"], SCHEMA_VERSION);
        assert_eq!(v["type"], "i16");
        assert_eq!(v["format"], "dicom");
    }

    #[test]
    fn a_folder_report_lists_its_volumes() {
        let report = FolderReport::new(
            Path::new("scans"),
            vec![ListedVolume {
                path: "scans/ct".into(),
                series: Some("1.2.3".into()),
                label: Some("series 4 \"Abdomen\"".into()),
            }],
        );
        assert_eq!(
            keys_of(&report),
            [
                ".folder",
                ".schema_version",
                ".volumes",
                ".volumes[].label",
                ".volumes[].path",
                ".volumes[].series"
            ]
        );
    }

    #[test]
    fn no_negative_zero_is_written() {
        let text =
            to_json(&serde_json::json!({"axis": [1.0, -0.0, -0.0], "n": [-0.5, 0]})).unwrap();
        assert!(!text.contains("-0.0"), "{text}");
        assert!(text.contains("-0.5"));
    }
}
