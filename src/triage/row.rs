//! One volume's row.

use serde::Serialize;

use crate::analysis::Analysis;
use crate::formats::Loaded;
use crate::formats::RowDetails;
use crate::report::SCHEMA_VERSION;

/// One volume's row: what it is, what is wrong with it, and its most structured axis and slabs.
/// Rows carry no timings, so that the rows of shards concatenate to those of one run.
#[derive(Clone, Debug, Serialize)]
pub struct TriageRow {
    /// [`SCHEMA_VERSION`].
    pub schema_version: u32,
    /// The file or folder as found, escaped by the one rule of [`crate::error::names`].
    pub path: String,
    /// The DICOM series' key (its `SeriesInstanceUID`) in a folder of DICOM files.
    pub series: Option<String>,
    /// What the reader tells of the volume, under the key of each reader whose rows carry it
    /// (`dicom`: the series' number, description, modality, transfer syntax; patient fields
    /// only when they were asked for), null but for the reader that read it.
    #[serde(flatten)]
    pub details: RowDetails,
    /// The format read (null when loading failed).
    pub format: Option<String>,
    /// `[nx, ny, nz]`.
    pub dims: Option<[usize; 3]>,
    /// `[sx, sy, sz]`, mm.
    pub spacing: Option<[f64; 3]>,
    /// Orientation codes (`RAS`, `LPS`, ...), null when the file states none.
    pub orientation: Option<String>,
    /// The voxel type in the file.
    #[serde(rename = "type")]
    pub voxel_type: Option<String>,
    /// Smallest and largest finite voxel.
    pub range: Option<[f32; 2]>,
    /// Voxels that were NaN or infinite.
    pub missing: Option<usize>,
    /// What the loader and the analysis noticed (a 4D file, a coarsened lattice, ...).
    pub problems: Vec<String>,
    /// Why the volume could not be looked at, on one line; null when it could.
    pub error: Option<String>,
    /// The most structured axis (null when no view search ran or it failed).
    pub best_axis: Option<[f64; 3]>,
    /// Its anatomical name, when the orientation names it.
    pub anatomy: Option<String>,
    /// Its entropy rate, bits (the mean over lattice phases where the ranking used it).
    pub entropy_rate: Option<f64>,
    /// Whether another axis is a contender (null on the paper's single lattice).
    pub uncertain: Option<bool>,
    /// With the gain ranking (`--gain`, `--axis-by gain`): the axis whose top-down slabs keep
    /// the most.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gain_axis: Option<[f64; 3]>,
    /// With the gain ranking: the information its slabs keep, bits.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub partition_gain: Option<f64>,
    /// With the gain ranking: whether another axis keeps as much within two standard errors.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gain_uncertain: Option<bool>,
    /// The axis partitioned along.
    pub axis: Option<[f64; 3]>,
    /// The slabs along it, `[start, end)` slice indices.
    pub slabs: Option<Vec<[usize; 2]>>,
}

impl TriageRow {
    /// The row of a volume that could not be looked at.
    pub fn failed(path: &str, error: String) -> Self {
        Self {
            schema_version: SCHEMA_VERSION,
            path: path.to_string(),
            series: None,
            details: RowDetails::none(),
            format: None,
            dims: None,
            spacing: None,
            orientation: None,
            voxel_type: None,
            range: None,
            missing: None,
            problems: Vec::new(),
            error: Some(error),
            best_axis: None,
            anatomy: None,
            entropy_rate: None,
            uncertain: None,
            gain_axis: None,
            partition_gain: None,
            gain_uncertain: None,
            axis: None,
            slabs: None,
        }
    }

    /// The row of `loaded`, found at `path`, without its analysis (yet).
    pub fn loaded(path: &str, loaded: &Loaded) -> Self {
        let v = &loaded.volume;
        let s = v.stats();
        Self {
            format: Some(loaded.format.name().to_string()),
            dims: Some(v.dims()),
            spacing: Some(v.spacing()),
            orientation: v.transform().axcodes(),
            voxel_type: Some(v.voxel_type().to_string()),
            range: (s.finite > 0).then_some([s.min, s.max]),
            missing: Some(s.missing),
            problems: loaded.notes.clone(),
            details: loaded.row_details(),
            error: None,
            ..Self::failed(path, String::new())
        }
    }

    /// The volume's name: its path, with the reader's label after it (the DICOM series), or
    /// the series' key when it was not read.
    pub fn name(&self) -> String {
        let series = match (self.details.label(), &self.series) {
            (Some(label), _) => label.to_string(),
            (None, Some(key)) => format!(" [series {key}]"),
            (None, None) => String::new(),
        };
        format!("{}{series}", self.path)
    }

    /// Adds what the analysis found.
    #[must_use]
    pub fn analysed(mut self, analysis: &Analysis) -> Self {
        if let Some(views) = &analysis.views {
            let best = views.best();
            self.best_axis = Some(best.axis);
            self.anatomy.clone_from(&best.world.anatomy);
            self.entropy_rate = Some(crate::view::score(best));
            self.uncertain = views.uncertain;
        }
        if let Some(g) = &analysis.gain {
            self.gain_axis = Some(g.refined.axis);
            self.partition_gain = Some(g.refined.partition_gain);
            self.gain_uncertain = Some(g.uncertain());
        }
        let p = &analysis.partition;
        if self.anatomy.is_none() {
            self.anatomy.clone_from(&p.world.anatomy);
        }
        self.axis = Some(p.axis);
        self.slabs = Some(p.slabs.iter().map(|&(a, b)| [a, b]).collect());
        self.problems.extend(analysis.notes.iter().cloned());
        self
    }

    /// The best axis in few characters: its anatomical plane (`I→S`), else `x`, `y` or `z`, else
    /// its components; none without a view search.
    pub fn axis_name(&self) -> Option<String> {
        if let Some(name) = &self.anatomy {
            return name.split(',').next().map(str::to_string);
        }
        let a = self.best_axis?;
        Some(match crate::geometry::coordinate_axis(a) {
            Some(m) => ["x", "y", "z"][m].to_string(),
            None => format!("[{:.2},{:.2},{:.2}]", a[0] + 0.0, a[1] + 0.0, a[2] + 0.0),
        })
    }

    /// The row with `error` (the analysis failed after the volume loaded).
    #[must_use]
    pub fn with_error(mut self, error: String) -> Self {
        self.error = Some(error);
        self
    }
}
