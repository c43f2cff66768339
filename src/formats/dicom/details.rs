//! What `info` and `triage` show of a DICOM series: its number, description, modality and
//! transfer syntax, and the patient-identifying fields only when they were asked for.

use std::collections::BTreeMap;

use serde::Serialize;
use serde_json::Value;
use serde_json::value::RawValue;

use super::DicomSeries;
use crate::error::names::controls;
use crate::formats::details::{Details, json_of, raw_of};

/// The DICOM series as `info --json` gives it.
#[derive(Clone, Debug, Serialize)]
pub struct DicomReport {
    /// The series' key: its `SeriesInstanceUID` (with `#2`, ... on the parts of a split series).
    pub series: String,
    /// `SeriesNumber`.
    pub number: Option<i64>,
    /// `SeriesDescription`.
    pub description: String,
    /// Modality.
    pub modality: String,
    /// The transfer syntax, named.
    pub transfer_syntax: String,
    /// Patient-identifying fields by name, only when they were asked for (empty otherwise).
    pub patient: BTreeMap<String, String>,
}

impl DicomReport {
    /// The report of the series `d`.
    #[must_use]
    pub fn of(d: &DicomSeries) -> Self {
        Self {
            series: d.key.clone(),
            number: d.number,
            description: d.description.clone(),
            modality: d.modality.clone(),
            transfer_syntax: d.syntax.clone(),
            patient: d.patient.iter().cloned().collect(),
        }
    }
}

impl Details for DicomSeries {
    /// Its fields escaped as they were read (`controls` leaves them so and keeps anything else
    /// out).
    fn lines(&self) -> Vec<(String, String)> {
        let number = self.number.map_or_else(String::new, |n| format!("{n} "));
        let mut lines = vec![
            (
                "series".to_string(),
                format!(
                    "{number}\"{}\" ({})",
                    controls(&self.description),
                    controls(&self.modality)
                ),
            ),
            ("series uid".to_string(), controls(&self.key).into_owned()),
            ("syntax".to_string(), controls(&self.syntax).into_owned()),
        ];
        for (field, value) in &self.patient {
            lines.push((field.clone(), controls(value).into_owned()));
        }
        lines
    }

    fn json(&self) -> Value {
        json_of(&DicomReport::of(self))
    }

    fn row_json(&self) -> Option<Box<RawValue>> {
        raw_of(self)
    }

    fn label(&self) -> Option<String> {
        Some(match (self.number, self.description.is_empty()) {
            (Some(n), false) => format!(" [series {n} \"{}\"]", self.description),
            (Some(n), true) => format!(" [series {n}]"),
            (None, _) => format!(" [series {}]", self.key),
        })
    }
}
