//! The reports other programs read: the JSON object of `analyze --json` (DESIGN.md §3), the slab
//! boundaries for renderers, and the curves as CSV. Built from library results only, so that the
//! CLI, the TUI's export and triage print the same thing. Every JSON object carries
//! [`SCHEMA_VERSION`], raised whenever a field changes meaning or goes away.

use std::fmt::Write as _;

use serde::Serialize;

use crate::analysis::Analysis;
use crate::error::{Error, Result};
use crate::partition::{BackgroundSummary, Partition};
use crate::view::{AxisEntropy, Contender, RankedBy, ViewParams};
use crate::volume::Volume;

/// The version of the JSON contract.
pub const SCHEMA_VERSION: u32 = 1;

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
    /// What was left out of the slab histograms as background: `{"mode", "value", "fraction"}`,
    /// null when nothing was (`--background none`).
    pub background: Option<BackgroundSummary>,
    /// What the user should know about this analysis.
    pub notes: Vec<String>,
    /// The partition along the axis.
    pub partition: Partition,
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
        let params = match views {
            Some(v) => v.params.clone(),
            None => ViewParams {
                sampling: view.sampling.resolved(volume.dims(), volume.spacing())?,
                ..view.clone()
            },
        };
        Ok(Self {
            schema_version: SCHEMA_VERSION,
            file: file.to_string(),
            dims: volume.dims(),
            spacing: volume.spacing(),
            range: [s.min, s.max],
            params,
            views: views.map(|v| v.views.clone()),
            best_axis: views.map(|v| v.best().axis),
            ranked_by: views.map(|v| v.ranked_by),
            uncertain: views.map(|v| v.uncertain),
            contenders: views.map(|v| v.contenders.clone()),
            refined: views.and_then(|v| v.refined.clone()),
            background: Some(analysis.partition.background).filter(|b| b.mode != "none"),
            notes: analysis.notes.clone(),
            partition: analysis.partition.clone(),
        })
    }
}

/// The slab boundaries in the form renderers take: slice indices, millimetres along the axis
/// and fractions of its length.
#[derive(Clone, Debug, Serialize)]
pub struct SlabsReport {
    /// [`SCHEMA_VERSION`].
    pub schema_version: u32,
    /// The file as the user named it.
    pub file: String,
    /// The canonical axis.
    pub axis: [f64; 3],
    /// The method that found the slabs.
    pub method: crate::partition::Method,
    /// Number of slices.
    pub slices: usize,
    /// Distance between slices, mm.
    pub thickness_mm: f64,
    /// The slabs in slice order.
    pub slabs: Vec<SlabBounds>,
}

/// One slab's bounds.
#[derive(Clone, Debug, Serialize)]
pub struct SlabBounds {
    /// Its number, from 0.
    pub index: usize,
    /// Slices `[start, end)`.
    pub slices: (usize, usize),
    /// Where it starts and ends along the axis, mm.
    pub mm: (f64, f64),
    /// Where it starts and ends as fractions of the stack.
    pub fraction: (f64, f64),
}

impl SlabsReport {
    /// The bounds of `p`'s slabs.
    pub fn new(file: &str, p: &Partition) -> Self {
        let n = p.slices as f64;
        Self {
            schema_version: SCHEMA_VERSION,
            file: file.to_string(),
            axis: p.axis,
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
                    fraction: (s.slices.0 as f64 / n, s.slices.1 as f64 / n),
                })
                .collect(),
        }
    }
}

/// `value` as pretty JSON, with every `-0.0` written as `0.0` (a direction component that is
/// zero has no sign worth printing).
pub fn to_json(value: &impl Serialize) -> Result<String> {
    fn unsign(v: &mut serde_json::Value) {
        match v {
            serde_json::Value::Number(n) if n.as_f64() == Some(0.0) && n.is_f64() => {
                *v = serde_json::json!(0.0);
            }
            serde_json::Value::Array(a) => a.iter_mut().for_each(unsign),
            serde_json::Value::Object(o) => o.values_mut().for_each(unsign),
            _ => {}
        }
    }
    let mut v = serde_json::to_value(value).map_err(|e| Error::Encode(e.to_string()))?;
    unsign(&mut v);
    serde_json::to_string_pretty(&v).map_err(|e| Error::Encode(e.to_string()))
}

/// `cut,mm,nmi,gain`: for each boundary between slice c-1 and c, its position, the NMI of the
/// two slices, and the ΔI of cutting the whole stack there.
pub fn curves_csv(p: &Partition) -> String {
    let mut out = String::from("cut,mm,nmi,gain\n");
    for c in 1..p.slices {
        let mm = p.offset + (c as f64 - 0.5) * p.thickness;
        let _ = writeln!(
            out,
            "{c},{mm},{},{}",
            p.nmi_curve[c - 1],
            p.gain_curve[c - 1]
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_negative_zero_is_written() {
        let text =
            to_json(&serde_json::json!({"axis": [1.0, -0.0, -0.0], "n": [-0.5, 0]})).unwrap();
        assert!(!text.contains("-0.0"), "{text}");
        assert!(text.contains("-0.5"));
    }
}
